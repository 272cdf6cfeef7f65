//! Shadow maps: each shadow-casting light's faces drawn by the compute rasterizer
//! (`wgsl/raster.wgsl`, layer 0) from the light ([`crate::frame::light_faces`]), copied into one
//! atlas that `wgsl/direct.wgsl` reads.
//!
//! A light's faces are kept from frame to frame while what they were drawn from holds: the
//! faces' cameras and counts (the light, the scene's bounds, the shadow resolution), the scene's
//! geometry buffers and the renderer's geometry generation, which
//! [`Renderer::geometry_changed`](crate::Renderer::geometry_changed) advances. A static scene's
//! later frames then draw no shadow map.
//!
//! Where the plan adds the off-screen light (`radiosity.offscreen`), each face is also drawn at
//! [`RSM_RESOLUTION`] texels a side and resolved into G-buffer records: the light's reflective
//! shadow map, what `wgsl/offscreen.wgsl` gathers the light of the surfaces no layer holds from.
//! It is kept and redrawn with the shadow maps.

use super::fill::Fill;
use super::raster::{Draw, RasterMode};
use super::resolve::resolve_view;
use super::{FrameContext, Recorder, RsmInputs, ShadowInputs, Stage};
use crate::frame::{FrameUniform, LightFaces, RSM_RESOLUTION, ShadowFace, light_faces};
use crate::gpu;
use crate::plan::{PassId, Plan};
use crate::settings::{Settings, ShadowSettings};
use crate::{Error, Result, SceneBuffers};

/// One shadow-casting light's faces in the atlas.
struct Group {
    light: usize,
    first: usize,
    count: usize,
    /// What the faces in the atlas were drawn from (`None`: not drawn yet).
    drawn: Option<Drawn>,
}

/// What a light's faces were drawn from: while it is unchanged, they are kept.
#[derive(PartialEq)]
struct Drawn {
    /// The scene's buffers ([`SceneBuffers::identity`]: a re-uploaded scene has new ones).
    geometry: [wgpu::Buffer; 6],
    /// The faces' frame uniforms: cameras, resolution and the scene's counts.
    faces: Vec<u8>,
    /// [`Renderer::geometry_changed`](crate::Renderer::geometry_changed)'s count.
    generation: u64,
    /// Whether the reflective shadow map was drawn too.
    rsm: bool,
}

impl Drawn {
    fn new(
        scene: &SceneBuffers,
        faces: &[(FrameUniform, ShadowFace)],
        generation: u64,
        plan: &Plan,
    ) -> Drawn {
        Drawn {
            geometry: scene.identity(),
            faces: faces.iter().flat_map(|(u, _)| bytemuck::bytes_of(u).to_vec()).collect(),
            generation,
            rsm: wants_rsm(plan),
        }
    }
}

/// Whether `plan` reads the reflective shadow maps.
fn wants_rsm(plan: &Plan) -> bool {
    plan.contains(&PassId::RadiosityOffscreen)
}

/// Faces drawn from the lights by the rasterizer at one resolution, in atlas order: a frame
/// uniform and a visibility buffer per face, the faces' lookup constants (`ShadowFace`, offsets
/// in texels) and their visibility words back to back (the atlas). The shadow maps are one
/// set, the reflective shadow maps another.
struct Faces {
    resolution: u32,
    uniforms: Vec<wgpu::Buffer>,
    vis: Vec<wgpu::Buffer>,
    fill: Fill,
    lookup: wgpu::Buffer,
    atlas: wgpu::Buffer,
}

impl Faces {
    /// `total` faces of `resolution` texels a side, labelled `deep-gbuffer.<what>.*`.
    fn new(device: &wgpu::Device, what: &str, resolution: u32, total: usize) -> Faces {
        let bytes = ShadowSettings::atlas_bytes(resolution, 1);
        let label = |part: &str| format!("deep-gbuffer.{what}.{part}");
        let storage = |part: &str, size| {
            gpu::storage_buffer(device, &label(part), size, wgpu::BufferUsages::empty())
        };
        Faces {
            resolution,
            uniforms: (0..total)
                .map(|_| gpu::uniform_buffer_for::<FrameUniform>(device, &label("frame")))
                .collect(),
            vis: (0..total).map(|_| storage("face", bytes)).collect(),
            fill: Fill::new(device, bytes, u32::MAX),
            lookup: storage("faces", (total.max(1) * std::mem::size_of::<ShadowFace>()) as u64),
            atlas: storage("atlas", bytes * total.max(1) as u64),
        }
    }

    /// Every shadow-casting light's faces of `scene` at this set's resolution.
    fn of(&self, scene: &SceneBuffers) -> Vec<LightFaces> {
        light_faces(scene.info(), self.resolution, scene.counts())
    }

    /// Writes every face's camera and lookup constants (lights or bounds may have changed);
    /// returns the faces of each light.
    fn prepare(&self, queue: &wgpu::Queue, scene: &SceneBuffers) -> Vec<LightFaces> {
        let groups = self.of(scene);
        let mut lookup = Vec::new();
        for group in &groups {
            for (k, (uniform, face)) in group.faces.iter().enumerate() {
                let buffer = &self.uniforms[group.first + k];
                queue.write_buffer(buffer, 0, bytemuck::bytes_of(uniform));
                lookup.push(*face);
            }
        }
        if !lookup.is_empty() {
            queue.write_buffer(&self.lookup, 0, bytemuck::cast_slice(&lookup));
        }
        groups
    }

    /// Records the depth of face `face` into its visibility buffer.
    fn draw(&self, ctx: &FrameContext<'_>, pass: &mut wgpu::ComputePass<'_>, face: usize) {
        let vis = &self.vis[face];
        self.fill.record(ctx.device, ctx.pipelines, pass, vis);
        let step = Draw { vis0: Some(vis), ..Draw::new(&self.uniforms[face], RasterMode::Layer0) };
        ctx.raster.rasterizer.draw(ctx.device, ctx.pipelines, pass, ctx.scene, step);
    }

    /// Copies face `face`'s visibility words into the atlas.
    fn copy(&self, encoder: &mut wgpu::CommandEncoder, face: usize) {
        let vis = &self.vis[face];
        let bytes = vis.size();
        encoder.copy_buffer_to_buffer(vis, 0, &self.atlas, face as u64 * bytes, bytes);
    }
}

/// The lights' reflective shadow maps: every face drawn again at [`RSM_RESOLUTION`] and
/// resolved into G-buffer records, the records back to back, and each face's light.
struct Rsm {
    faces: Faces,
    records: Vec<wgpu::Buffer>,
    atlas: wgpu::Buffer,
    face_lights: wgpu::Buffer,
}

impl Rsm {
    fn new(device: &wgpu::Device, s: &Settings, total: usize) -> Rsm {
        let texels = u64::from(RSM_RESOLUTION * RSM_RESOLUTION);
        let bytes = texels * crate::gbuffer::bytes_per_pixel(s.precision);
        let storage =
            |label, size| gpu::storage_buffer(device, label, size, wgpu::BufferUsages::empty());
        Rsm {
            faces: Faces::new(device, "rsm", RSM_RESOLUTION, total),
            records: (0..total).map(|_| storage("deep-gbuffer.rsm.records", bytes)).collect(),
            atlas: storage("deep-gbuffer.rsm.gbuffer", bytes * total.max(1) as u64),
            face_lights: storage("deep-gbuffer.rsm.lights", total.max(1) as u64 * 4),
        }
    }
}

/// The lights whose shadow maps `plan` draws or reuses, in light order.
fn key(plan: &Plan) -> Vec<(usize, String)> {
    plan.shadow_lights().into_iter().map(|(light, name)| (light, name.to_owned())).collect()
}

/// The faces of every shadow-casting light (and, with the off-screen light, their reflective
/// shadow maps) and the lights' places among them.
pub(crate) struct ShadowStage {
    /// The plan's shadow lights this stage was made for (it is remade when they change).
    key: Vec<(usize, String)>,
    groups: Vec<Group>,
    faces: Faces,
    light_faces: wgpu::Buffer,
    /// The reflective shadow maps, made by the first plan that reads them.
    rsm: Option<Rsm>,
}

impl ShadowStage {
    /// The stage for the shadow lights of `plan`, or the one kept if it was made for them.
    pub(crate) fn for_plan(
        kept: Option<ShadowStage>,
        device: &wgpu::Device,
        s: &Settings,
        scene: &SceneBuffers,
        plan: &Plan,
    ) -> Result<ShadowStage> {
        let key = key(plan);
        let mut stage = match kept {
            Some(stage) if stage.key == key && stage.faces.resolution == s.shadows.resolution => {
                stage
            }
            _ => Self::new(device, s, scene, key)?,
        };
        if wants_rsm(plan) && stage.rsm.is_none() {
            let total = stage.groups.iter().map(|g| g.count).sum();
            stage.rsm = Some(Rsm::new(device, s, total));
        }
        Ok(stage)
    }

    fn new(
        device: &wgpu::Device,
        s: &Settings,
        scene: &SceneBuffers,
        key: Vec<(usize, String)>,
    ) -> Result<ShadowStage> {
        let res = s.shadows.resolution;
        let face_bytes = ShadowSettings::atlas_bytes(res, 1);
        let info = scene.info();
        let groups: Vec<Group> = light_faces(info, res, (0, 0, 0))
            .iter()
            .map(|g| Group { light: g.light, first: g.first, count: g.faces.len(), drawn: None })
            .collect();
        let total: usize = groups.iter().map(|g| g.count).sum();
        let limits = device.limits();
        let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        if face_bytes * total as u64 > limit {
            return Err(Error::ExceedsLimit {
                what: format!("{total} shadow-map faces of {res}x{res}"),
                needed: face_bytes * total as u64,
                limit,
                unit: "bytes",
            });
        }
        Ok(ShadowStage {
            key,
            groups,
            faces: Faces::new(device, "shadow", res, total),
            light_faces: gpu::storage_buffer(
                device,
                "deep-gbuffer.shadow.lights",
                (info.lights.len().max(2) * 8) as u64,
                wgpu::BufferUsages::empty(),
            ),
            rsm: None,
        })
    }

    /// Writes every face's camera (lights or bounds may have changed).
    pub(crate) fn prepare(&self, queue: &wgpu::Queue, scene: &SceneBuffers) {
        let mut light_faces_words = vec![[0u32; 2]; scene.info().lights.len().max(2)];
        for group in self.faces.prepare(queue, scene) {
            light_faces_words[group.light] = [group.first as u32, group.faces.len() as u32];
        }
        queue.write_buffer(&self.light_faces, 0, bytemuck::cast_slice(&light_faces_words));
        if let Some(rsm) = &self.rsm {
            let lights: Vec<u32> = rsm
                .faces
                .prepare(queue, scene)
                .iter()
                .flat_map(|g| std::iter::repeat_n(g.light as u32, g.faces.len()))
                .collect();
            if !lights.is_empty() {
                queue.write_buffer(&rsm.face_lights, 0, bytemuck::cast_slice(&lights));
            }
        }
    }

    /// What the off-screen light reads, where `plan` adds it.
    pub(crate) fn rsm_inputs(&self, plan: &Plan) -> Option<RsmInputs<'_>> {
        self.rsm.as_ref().filter(|_| wants_rsm(plan)).map(|r| RsmInputs {
            faces: &r.faces.lookup,
            face_lights: &r.face_lights,
            vis: &r.faces.atlas,
            gbuffer: &r.atlas,
            count: r.records.len() as u32,
        })
    }

    /// The lights of `plan` whose faces, drawn by an earlier frame, still hold for `scene` under
    /// `s` and the geometry `generation`.
    pub(crate) fn kept(
        &self,
        scene: &SceneBuffers,
        plan: &Plan,
        s: &Settings,
        generation: u64,
    ) -> Vec<usize> {
        if self.key != key(plan) || self.faces.resolution != s.shadows.resolution {
            return Vec::new();
        }
        self.faces
            .of(scene)
            .iter()
            .filter(|faces| {
                self.groups.iter().find(|g| g.light == faces.light).is_some_and(|g| {
                    g.drawn.as_ref() == Some(&Drawn::new(scene, &faces.faces, generation, plan))
                })
            })
            .map(|faces| faces.light)
            .collect()
    }

    /// Notes that the frame just recorded drew the faces of `plan`'s shadow passes.
    pub(crate) fn drew(&mut self, scene: &SceneBuffers, plan: &Plan, generation: u64) {
        for faces in self.faces.of(scene) {
            let drawn = plan
                .passes
                .iter()
                .any(|p| matches!(p, PassId::Shadow { light, .. } if *light == faces.light));
            if let Some(group) = self.groups.iter_mut().find(|g| g.light == faces.light)
                && drawn
            {
                group.drawn = Some(Drawn::new(scene, &faces.faces, generation, plan));
            }
        }
    }

    /// What the direct kernel reads.
    pub(crate) fn inputs(&self) -> ShadowInputs<'_> {
        ShadowInputs {
            faces: &self.faces.lookup,
            light_faces: &self.light_faces,
            atlas: &self.faces.atlas,
        }
    }

    /// The atlas: every face's visibility words back to back.
    pub(crate) fn atlas(&self) -> &wgpu::Buffer {
        &self.faces.atlas
    }
}

impl Stage for ShadowStage {
    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        let PassId::Shadow { light, .. } = id else { unreachable!("{id} is not a shadow pass") };
        let Some(group) = self.groups.iter().find(|g| g.light == *light) else {
            unreachable!("the stage was made for the plan's shadow lights")
        };
        let faces = group.first..group.first + group.count;
        let rsm = self.rsm.as_ref().filter(|_| wants_rsm(ctx.plan));
        {
            let mut pass = rec.pass(id);
            for face in faces.clone() {
                self.faces.draw(ctx, &mut pass, face);
            }
            for (rsm, face) in rsm.into_iter().flat_map(|r| faces.clone().map(move |f| (r, f))) {
                rsm.faces.draw(ctx, &mut pass, face);
                let view = (&rsm.faces.uniforms[face], (RSM_RESOLUTION, RSM_RESOLUTION));
                resolve_view(ctx, &mut pass, view, &rsm.faces.vis[face], &rsm.records[face], None);
            }
        }
        let encoder = rec.encoder();
        for face in faces {
            self.faces.copy(encoder, face);
            if let Some(rsm) = rsm {
                rsm.faces.copy(encoder, face);
                let bytes = rsm.records[face].size();
                let at = face as u64 * bytes;
                encoder.copy_buffer_to_buffer(&rsm.records[face], 0, &rsm.atlas, at, bytes);
            }
        }
    }
}
