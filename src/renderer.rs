//! [`Renderer`]: the deep G-buffer stage, recorded into a caller's command encoder.

use crate::SceneBuffers;
use crate::environment::Environment;
use crate::gbuffer::{self, GBufferLayer};
use crate::gpu::frame::CameraMatrices;
use crate::gpu::{self, FrameUniform, PassTiming, Timestamps};
use crate::passes::ao::{AoPass, AoUniform};
use crate::passes::blur::BlurPass;
use crate::passes::composite::CompositePass;
use crate::passes::direct::{DirectPass, ShadowInputs};
use crate::passes::fill::FillPass;
use crate::passes::present::PresentPass;
use crate::passes::pyramid::PyramidPass;
use crate::passes::radiosity::{RadiosityPass, RadiosityTargets, RadiosityUniform};
use crate::passes::raster::{self, RasterMode, RasterPass, RasterTargets};
use crate::passes::reflections::{ReflectionTargets, ReflectionsPass, ReflectionsUniform};
use crate::passes::resolve::ResolvePass;
use crate::passes::shadow::{self, ShadowFace};
use crate::plan::{Plan, Reason};
use crate::scene::Camera;
use crate::settings::{AtomicPath, Layer1Variant, Settings};
use crate::{Error, Result};

/// Counters the GPU keeps while rasterizing, read with [`Renderer::diagnostics`].
///
/// The `rejected_*` and `untextured_triangles` counters check what the CPU cannot: the contents
/// of a host's [imported](crate::SceneBuffers::import) buffers. A rejected triangle is not drawn
/// (it never reaches a kernel that would read through its bad index); each is counted once a
/// frame, by the camera's layer-0 raster. Scenes uploaded from a [`Scene`](crate::Scene) are
/// validated on the CPU and always count 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Diagnostics {
    /// Triangles (after clipping) rasterized by the large-triangle tiles in the last frame,
    /// summed over every raster of the frame (both layers and the shadow maps).
    pub large_triangles: u32,
    /// Large triangles dropped because the bin was full (0 unless the bin is undersized).
    pub dropped_triangles: u32,
    /// Triangles rejected because a vertex index is not below the vertex count.
    pub rejected_indices: u32,
    /// Triangles rejected because their material id is not below the material count.
    pub rejected_materials: u32,
    /// Triangles rejected because a vertex position is NaN or infinite.
    pub rejected_positions: u32,
    /// Triangles drawn with their base colour alone because their material's texture does not
    /// lie inside the texel buffer (or has a zero size).
    pub untextured_triangles: u32,
}

impl Diagnostics {
    /// Triangles not drawn because of bad input.
    pub fn rejected_triangles(&self) -> u32 {
        self.rejected_indices + self.rejected_materials + self.rejected_positions
    }

    /// Whether any input was rejected or drawn without its texture.
    pub fn has_bad_input(&self) -> bool {
        self.rejected_triangles() + self.untextured_triangles > 0
    }

    /// One line per non-zero counter of lost or degraded geometry, for a log.
    pub fn warnings(&self) -> Vec<String> {
        [
            (
                self.dropped_triangles,
                "large triangles did not fit the raster bin and were not drawn",
            ),
            (
                self.rejected_indices,
                "triangles have a vertex index past the vertex count (not drawn)",
            ),
            (
                self.rejected_materials,
                "triangles have a material id past the material count (not drawn)",
            ),
            (
                self.rejected_positions,
                "triangles have a NaN or infinite vertex position (not drawn)",
            ),
            (
                self.untextured_triangles,
                "triangles' textures lie outside the texel buffer (drawn untextured)",
            ),
        ]
        .into_iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{n} {what}"))
        .collect()
    }
}

/// Passes one frame can time (the capacity of the timestamp query set).
const MAX_TIMED_PASSES: u32 = 32;

/// Renders deep G-buffers on a device it borrows.
///
/// Create it once per device; call [`encode`](Renderer::encode) once per frame and
/// [`resize`](Renderer::resize) when the image size changes.
/// It owns only its targets and the history that the one-pass layer-1 variants need.
pub struct Renderer {
    settings: Settings,
    fill: FillPass,
    raster: RasterPass,
    resolve: ResolvePass,
    frame: wgpu::Buffer,
    bins: wgpu::Buffer,
    args: wgpu::Buffer,
    large: Option<wgpu::Buffer>,
    vis0: [wgpu::Buffer; 2],
    vis1: wgpu::Buffer,
    gbuffer: [wgpu::Buffer; 2],
    /// Which `vis0` holds the last frame's layer 0.
    last: usize,
    history: Option<CameraMatrices>,
    timestamps: Option<Timestamps>,
    passes: Vec<String>,
    last_frame: Option<FrameUniform>,
    ao: Option<AoStage>,
    shading: Option<ShadingStage>,
    shadows: Option<ShadowStage>,
    radiosity: Option<RadiosityStage>,
    reflections: Option<ReflectionsStage>,
    present: Option<PresentPass>,
    plan: Option<Plan>,
    /// The environment map (texels, width, height) missed reflection rays see.
    environment: Option<(wgpu::Buffer, u32, u32)>,
    /// The last frame [`render`](Renderer::render) submitted, still perhaps on the GPU.
    in_flight: Option<wgpu::SubmissionIndex>,
}

/// Reflections: the kernels, the tile list, its indirect arguments and the reflected radiance.
struct ReflectionsStage {
    pass: ReflectionsPass,
    tiles: wgpu::Buffer,
    args: wgpu::Buffer,
    output: wgpu::Buffer,
    /// Bound in place of an environment map when there is none.
    no_environment: wgpu::Buffer,
    tiles_x: u32,
    tiles_y: u32,
}

impl ReflectionsStage {
    fn new(device: &wgpu::Device, s: &Settings) -> ReflectionsStage {
        let (tiles_x, tiles_y) = (s.width.div_ceil(8), s.height.div_ceil(8));
        let pixels = u64::from(s.width) * u64::from(s.height);
        ReflectionsStage {
            pass: ReflectionsPass::new(device, s.precision),
            tiles: gpu::storage_buffer(
                device,
                "deep-gbuffer.reflections.tiles",
                (u64::from(tiles_x * tiles_y) + 1) * 4,
                wgpu::BufferUsages::empty(),
            ),
            args: gpu::storage_buffer(
                device,
                "deep-gbuffer.reflections.args",
                16,
                wgpu::BufferUsages::INDIRECT,
            ),
            output: gpu::storage_buffer(
                device,
                "deep-gbuffer.reflections.output",
                pixels * 16,
                wgpu::BufferUsages::empty(),
            ),
            no_environment: gpu::storage_buffer(
                device,
                "deep-gbuffer.reflections.no_environment",
                16,
                wgpu::BufferUsages::empty(),
            ),
            tiles_x,
            tiles_y,
        }
    }
}

/// Radiosity: the kernels, the outgoing radiance of both layers, the gathered irradiance, the
/// filtered irradiance of the last and this frame, and last frame's layer 1.
struct RadiosityStage {
    pass: RadiosityPass,
    uniform: wgpu::Buffer,
    b: [wgpu::Buffer; 2],
    raw: wgpu::Buffer,
    history: [wgpu::Buffer; 2],
    /// Which `history` holds the last frame's filtered irradiance.
    last: usize,
    /// Frames since the history began.
    turn: u32,
    blur: BlurPass,
    /// The blur's intermediate and result.
    blurred: [wgpu::Buffer; 2],
}

impl RadiosityStage {
    /// The last encoded frame's irradiance as the composite read it, after `last` flipped.
    fn output_after_frame(&self, blur_radius: u32) -> &wgpu::Buffer {
        if blur_radius > 0 { &self.blurred[1] } else { &self.history[self.last] }
    }

    /// This frame's irradiance as the composite reads it (blurred unless the radius is 0).
    fn output(&self, blur_radius: u32) -> &wgpu::Buffer {
        if blur_radius > 0 { &self.blurred[1] } else { &self.history[1 - self.last] }
    }

    fn new(device: &wgpu::Device, s: &Settings) -> RadiosityStage {
        let pixels = u64::from(s.width) * u64::from(s.height);
        let buffer = |label: &str, bytes: u64| {
            gpu::storage_buffer(device, label, bytes, wgpu::BufferUsages::empty())
        };
        RadiosityStage {
            pass: RadiosityPass::new(device, s.precision),
            uniform: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("deep-gbuffer.radiosity"),
                size: std::mem::size_of::<RadiosityUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            b: [
                buffer("deep-gbuffer.radiosity.b0", pixels * 16),
                buffer("deep-gbuffer.radiosity.b1", pixels * 16),
            ],
            raw: buffer("deep-gbuffer.radiosity.raw", pixels * 16),
            history: [
                buffer("deep-gbuffer.radiosity.history.a", pixels * 16),
                buffer("deep-gbuffer.radiosity.history.b", pixels * 16),
            ],
            last: 0,
            turn: 0,
            blur: BlurPass::new(device, s.precision, s.radiosity.blur_radius, true),
            blurred: [
                buffer("deep-gbuffer.radiosity.blur", pixels * 16),
                buffer("deep-gbuffer.radiosity.blurred", pixels * 16),
            ],
        }
    }
}

/// Shadow maps of the shadow-casting lights: one visibility buffer per face (drawn by the
/// rasterizer), copied into one atlas the direct kernel reads.
struct ShadowStage {
    /// The shadow lights' names, in the plan's order (the stage is rebuilt when they change).
    key: Vec<String>,
    /// Per shadow light: name, light index, first face, face count.
    groups: Vec<(String, usize, usize, usize)>,
    face_uniforms: Vec<wgpu::Buffer>,
    face_vis: Vec<wgpu::Buffer>,
    faces: wgpu::Buffer,
    light_faces: wgpu::Buffer,
    atlas: wgpu::Buffer,
}

impl ShadowStage {
    fn new(device: &wgpu::Device, s: &Settings, scene: &SceneBuffers) -> Result<ShadowStage> {
        let res = s.shadows.resolution;
        let face_bytes = u64::from(res) * u64::from(res) * 8;
        let info = scene.info();
        let layout = shadow::light_faces(info, res, (0, 0, 0));
        let groups: Vec<(String, usize, usize, usize)> = layout
            .iter()
            .map(|g| (info.lights[g.light].name.clone(), g.light, g.first, g.faces.len()))
            .collect();
        let total: usize = groups.iter().map(|g| g.3).sum();
        let limit =
            device.limits().max_storage_buffer_binding_size.min(device.limits().max_buffer_size);
        if face_bytes * total as u64 > limit {
            return Err(Error::ExceedsLimit {
                what: format!("{total} shadow-map faces of {res}x{res}"),
                needed: face_bytes * total as u64,
                limit,
            });
        }
        let uniform = || {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("deep-gbuffer.shadow.frame"),
                size: std::mem::size_of::<FrameUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let storage = |label: &str, size: u64| {
            gpu::storage_buffer(device, label, size, wgpu::BufferUsages::empty())
        };
        Ok(ShadowStage {
            key: groups.iter().map(|g| g.0.clone()).collect(),
            groups,
            face_uniforms: (0..total).map(|_| uniform()).collect(),
            face_vis: (0..total).map(|_| storage("deep-gbuffer.shadow.face", face_bytes)).collect(),
            faces: storage(
                "deep-gbuffer.shadow.faces",
                (total.max(1) * std::mem::size_of::<ShadowFace>()) as u64,
            ),
            light_faces: storage(
                "deep-gbuffer.shadow.lights",
                (info.lights.len().max(2) * 8) as u64,
            ),
            atlas: storage("deep-gbuffer.shadow.atlas", face_bytes * total.max(1) as u64),
        })
    }

    /// Writes every face's camera (lights or bounds may have changed).
    fn update(&self, queue: &wgpu::Queue, scene: &SceneBuffers, res: u32) {
        let info = scene.info();
        let b = scene.buffers();
        let mut faces = Vec::new();
        let mut light_faces = vec![[0u32; 2]; info.lights.len().max(2)];
        for group in
            shadow::light_faces(info, res, (b.triangle_count, b.material_count, b.vertex_count))
        {
            light_faces[group.light] = [group.first as u32, group.faces.len() as u32];
            for (k, (uniform, face)) in group.faces.into_iter().enumerate() {
                queue.write_buffer(
                    &self.face_uniforms[group.first + k],
                    0,
                    bytemuck::bytes_of(&uniform),
                );
                faces.push(face);
            }
        }
        if !faces.is_empty() {
            queue.write_buffer(&self.faces, 0, bytemuck::cast_slice(&faces));
        }
        queue.write_buffer(&self.light_faces, 0, bytemuck::cast_slice(&light_faces));
    }
}

/// Direct light and the composite, and their images.
struct ShadingStage {
    direct: DirectPass,
    composite: CompositePass,
    /// Direct radiance (layers 0 and 1) and the HDR composite, `vec4<f32>` per pixel.
    radiance: wgpu::Buffer,
    radiance1: wgpu::Buffer,
    hdr: wgpu::Buffer,
}

impl ShadingStage {
    fn new(device: &wgpu::Device, s: &Settings) -> ShadingStage {
        let bytes = u64::from(s.width) * u64::from(s.height) * 16;
        let buffer =
            |label: &str| gpu::storage_buffer(device, label, bytes, wgpu::BufferUsages::empty());
        ShadingStage {
            direct: DirectPass::new(device, s.precision),
            composite: CompositePass::new(device, s.precision),
            radiance1: buffer("deep-gbuffer.direct.radiance1"),
            radiance: buffer("deep-gbuffer.direct.radiance"),
            hdr: buffer("deep-gbuffer.composite.hdr"),
        }
    }
}

/// The obscurance passes and their buffers (present when obscurance is enabled).
struct AoStage {
    pyramid: PyramidPass,
    pyramids: [wgpu::Buffer; 2],
    ao: AoPass,
    uniform: wgpu::Buffer,
    blur: BlurPass,
    /// Raw AV, the blur's intermediate, blurred AV.
    av: [wgpu::Buffer; 3],
    two_layers: bool,
}

impl AoStage {
    fn new(device: &wgpu::Device, s: &Settings, two_layers: bool) -> AoStage {
        let pyramid = PyramidPass::new(device, s.precision, s.width, s.height);
        let size = pyramid.buffer_size();
        let buffer = |label: &str, size: u64| {
            gpu::storage_buffer(device, label, size, wgpu::BufferUsages::empty())
        };
        let pixels = u64::from(s.width) * u64::from(s.height) * 4;
        AoStage {
            pyramids: [
                buffer("deep-gbuffer.pyramid.layer0", size),
                buffer("deep-gbuffer.pyramid.layer1", size),
            ],
            ao: AoPass::new(device, s.precision, two_layers),
            uniform: gpu::uniform_buffer(
                device,
                "deep-gbuffer.ao",
                bytemuck::bytes_of(&AoUniform::new(&s.ao, pyramid.layout())),
            ),
            blur: BlurPass::new(device, s.precision, s.ao.blur_radius, false),
            av: [
                buffer("deep-gbuffer.ao.raw", pixels),
                buffer("deep-gbuffer.ao.blur", pixels),
                buffer("deep-gbuffer.ao.av", pixels),
            ],
            pyramid,
            two_layers,
        }
    }
}

impl Renderer {
    /// Features deep-gbuffer cannot run without (none: every path has a fallback).
    pub fn required_features() -> wgpu::Features {
        wgpu::Features::empty()
    }

    /// The features of the 64-bit atomic raster path.
    pub fn int64_features() -> wgpu::Features {
        wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX
    }

    /// Features used when present: 64-bit atomics (one raster pass instead of two) and
    /// timestamp queries (per-pass GPU timings).
    pub fn optional_features() -> wgpu::Features {
        Self::int64_features() | wgpu::Features::TIMESTAMP_QUERY
    }

    /// Limits deep-gbuffer needs beyond the WebGPU defaults: 12 storage buffers per stage. Raise
    /// `max_storage_buffer_binding_size` to the adapter's for large images (a layer at 1920x1080
    /// in full precision is 133 MB).
    pub fn required_limits() -> wgpu::Limits {
        wgpu::Limits { max_storage_buffers_per_shader_stage: 12, ..wgpu::Limits::default() }
    }

    /// Creates the renderer's pipelines and targets on `device`.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, settings: Settings) -> Result<Renderer> {
        gpu::scoped(device, "deep-gbuffer.renderer", || Self::create(device, queue, settings))
    }

    fn create(device: &wgpu::Device, queue: &wgpu::Queue, settings: Settings) -> Result<Renderer> {
        settings.validate()?;
        let features = device.features();
        let int64 = match settings.atomics {
            AtomicPath::Auto => features.contains(Self::int64_features()),
            AtomicPath::Int64 => {
                if !features.contains(wgpu::Features::SHADER_INT64) {
                    return Err(Error::MissingFeature("SHADER_INT64"));
                }
                if !features.contains(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX) {
                    return Err(Error::MissingFeature("SHADER_INT64_ATOMIC_MIN_MAX"));
                }
                true
            }
            AtomicPath::Int32 => false,
        };
        let limits = device.limits();
        if limits.max_storage_buffers_per_shader_stage
            < Self::required_limits().max_storage_buffers_per_shader_stage
        {
            return Err(Error::ExceedsLimit {
                what: "storage buffers per shader stage".into(),
                needed: u64::from(Self::required_limits().max_storage_buffers_per_shader_stage),
                limit: u64::from(limits.max_storage_buffers_per_shader_stage),
            });
        }
        let pixels = u64::from(settings.width) * u64::from(settings.height);
        let binding_limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let gbuffer_bytes = pixels * gbuffer::bytes_per_pixel(settings.precision);
        if gbuffer_bytes > binding_limit {
            return Err(Error::ExceedsLimit {
                what: format!(
                    "a {}x{} G-buffer layer ({:?})",
                    settings.width, settings.height, settings.precision
                ),
                needed: gbuffer_bytes,
                limit: binding_limit,
            });
        }
        let vis = |label: &str| {
            gpu::storage_buffer(device, label, pixels * 8, wgpu::BufferUsages::empty())
        };
        let g = |label: &str| {
            gpu::storage_buffer(device, label, gbuffer_bytes, wgpu::BufferUsages::empty())
        };
        Ok(Renderer {
            fill: FillPass::new(device),
            raster: RasterPass::new(int64),
            resolve: ResolvePass::new(device, settings.precision),
            frame: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("deep-gbuffer.frame"),
                size: std::mem::size_of::<FrameUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            bins: gpu::storage_buffer(
                device,
                "deep-gbuffer.raster.bins",
                raster::BINS_BYTES,
                wgpu::BufferUsages::empty(),
            ),
            args: gpu::storage_buffer(
                device,
                "deep-gbuffer.raster.args",
                raster::ARGS_BYTES,
                wgpu::BufferUsages::INDIRECT,
            ),
            large: None,
            vis0: [vis("deep-gbuffer.raster.vis0.a"), vis("deep-gbuffer.raster.vis0.b")],
            vis1: vis("deep-gbuffer.raster.vis1"),
            gbuffer: [g("deep-gbuffer.resolve.layer0"), g("deep-gbuffer.resolve.layer1")],
            last: 0,
            history: None,
            timestamps: if settings.timings {
                Timestamps::new(device, queue, MAX_TIMED_PASSES)
            } else {
                None
            },
            passes: Vec::new(),
            last_frame: None,
            ao: None,
            shading: None,
            shadows: None,
            radiosity: None,
            reflections: None,
            present: None,
            plan: None,
            environment: None,
            in_flight: None,
            settings,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Changes the image size between frames. Every per-pixel target is reallocated and the
    /// temporal history restarts (the next frame is a first frame, as after
    /// [`reset_history`](Renderer::reset_history)); compiled raster and resolve pipelines and
    /// the environment map are kept. A size the device cannot hold is an error that leaves the
    /// renderer as it was.
    pub fn resize(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        width: u32,
        height: u32,
    ) -> Result<()> {
        if (width, height) == (self.settings.width, self.settings.height) {
            return Ok(());
        }
        let settings = Settings { width, height, ..self.settings.clone() };
        let mut next = Renderer::new(device, queue, settings)?;
        std::mem::swap(&mut next.raster, &mut self.raster);
        std::mem::swap(&mut next.fill, &mut self.fill);
        std::mem::swap(&mut next.resolve, &mut self.resolve);
        next.environment = self.environment.take();
        next.in_flight = self.in_flight.take();
        *self = next;
        Ok(())
    }

    /// Sets the equirectangular environment that reflection rays see when they leave the screen
    /// (`None`: the scene's constant ambient sky, the default). The map is uploaded once and
    /// kept until the next call.
    pub fn set_environment(
        &mut self,
        device: &wgpu::Device,
        environment: Option<&Environment>,
    ) -> Result<()> {
        self.environment = match environment {
            None => None,
            Some(env) => {
                let bytes: &[u8] = bytemuck::cast_slice(env.texels());
                let limit = device.limits().max_storage_buffer_binding_size;
                if bytes.len() as u64 > limit {
                    return Err(Error::ExceedsLimit {
                        what: format!("a {}x{} environment map", env.width(), env.height()),
                        needed: bytes.len() as u64,
                        limit,
                    });
                }
                let buffer =
                    gpu::storage_buffer_init(device, "deep-gbuffer.reflections.environment", bytes);
                Some((buffer, env.width(), env.height()))
            }
        };
        Ok(())
    }

    /// `"int64"` (one 64-bit atomicMin per fragment) or `"int32"` (depth pass, then id pass).
    pub fn raster_path(&self) -> &'static str {
        if self.raster.int64() { "int64" } else { "int32" }
    }

    /// Forgets the previous frame (a camera cut): the next frame rasterizes layer 1 exactly.
    pub fn reset_history(&mut self) {
        self.history = None;
    }

    /// The plan for `scene` under this renderer's settings (what [`encode`](Renderer::encode)
    /// will run). The first frame of a one-pass layer-1 variant rasterizes the layers in two
    /// passes (`raster.layer0`, `raster.layer1`) instead of `raster.layers`.
    pub fn plan(&self, scene: &SceneBuffers) -> Plan {
        let mut plan = Plan::new(scene.info(), &self.settings);
        if plan.layers == 2
            && self.history.is_none()
            && let Some(i) = plan.passes.iter().position(|p| p == "raster.layers")
        {
            {
                plan.passes
                    .splice(i..=i, ["raster.layer0".to_string(), "raster.layer1".to_string()]);
            }
        }
        plan
    }

    /// The plan of the last [`encode`](Renderer::encode).
    pub fn last_plan(&self) -> Option<&Plan> {
        self.plan.as_ref()
    }

    /// The shadow maps of the last frame, every face's visibility words back to back (in the
    /// order of [`light_faces`](crate::passes::shadow::light_faces)), or `None` without shadows.
    pub fn shadow_atlas_buffer(&self) -> Option<&wgpu::Buffer> {
        self.plan.as_ref().filter(|p| !p.shadows.is_empty())?;
        self.shadows.as_ref().map(|s| &s.atlas)
    }

    /// Radiosity buffers of the last frame: [outgoing radiance B of layer 0, of layer 1, the
    /// gathered irradiance and confidence, the temporally filtered irradiance, the blurred
    /// irradiance the composite read], all `vec4<f32>` per pixel; `None` when radiosity is off.
    pub fn radiosity_buffers(&self) -> Option<[&wgpu::Buffer; 5]> {
        self.plan.as_ref().filter(|p| p.radiosity == Reason::Runs)?;
        let r = self.radiosity.as_ref()?;
        // `last` has flipped at the end of the frame: this frame's history is `history[last]`.
        Some([
            &r.b[0],
            &r.b[1],
            &r.raw,
            &r.history[r.last],
            r.output_after_frame(self.settings.radiosity.blur_radius),
        ])
    }

    /// The reflected radiance (rgb, scaled by the reflectivity) and its confidence (a) of the
    /// last frame, `vec4<f32>` per pixel; `None` when no reflection pass ran.
    pub fn reflections_buffer(&self) -> Option<&wgpu::Buffer> {
        self.plan.as_ref().filter(|p| p.reflections == Reason::Runs)?;
        self.reflections.as_ref().map(|r| &r.output)
    }

    /// The HDR image of the last frame: `vec4<f32>` per pixel, linear radiance (a = 1 on
    /// surfaces, 0 on the sky).
    pub fn hdr_buffer(&self) -> Option<&wgpu::Buffer> {
        self.shading.as_ref().map(|s| &s.hdr)
    }

    /// The direct radiance of the last frame (`vec4<f32>` per pixel; zero when no light runs).
    pub fn direct_buffer(&self) -> Option<&wgpu::Buffer> {
        self.shading.as_ref().map(|s| &s.radiance)
    }

    /// The direct radiance of layer 1 (computed when radiosity or reflections read it).
    pub fn direct1_buffer(&self) -> Option<&wgpu::Buffer> {
        self.shading.as_ref().map(|s| &s.radiance1)
    }

    /// Reads a `vec4<f32>` per-pixel image (HDR, direct radiance) back as rgb.
    pub fn read_rgb(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<glam::Vec3>> {
        let values = self.read_f32(device, queue, buffer)?;
        let n = (self.settings.width * self.settings.height) as usize;
        Ok(values.chunks_exact(4).take(n).map(|c| glam::Vec3::new(c[0], c[1], c[2])).collect())
    }

    /// The frame constants of the last [`encode`](Renderer::encode): what the CPU references
    /// need to reproduce the frame.
    pub fn frame_uniform(&self) -> Option<&FrameUniform> {
        self.last_frame.as_ref()
    }

    /// The uniform buffer holding the last frame's [`FrameUniform`] (camera and image size),
    /// for passes of the caller's that follow this stage.
    pub fn frame_buffer(&self) -> &wgpu::Buffer {
        &self.frame
    }

    /// The names of the passes the last [`encode`](Renderer::encode) recorded, in order.
    pub fn passes(&self) -> &[String] {
        &self.passes
    }

    /// Records one frame, every pass of its [`plan`](Renderer::plan), into `encoder`. Submit it, then read the
    /// results with [`read_gbuffer`](Renderer::read_gbuffer) or use
    /// [`gbuffer_buffer`](Renderer::gbuffer_buffer) in your own passes.
    pub fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        camera: &Camera,
    ) -> Result<()> {
        self.encode_frame(device, queue, encoder, scene, camera, false)
    }

    /// Records a frame; `provided`: the G-buffer layers and visibility depths were written by
    /// [`render_gbuffer`](Renderer::render_gbuffer), so no raster or resolve pass runs.
    fn encode_frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        camera: &Camera,
        provided: bool,
    ) -> Result<()> {
        camera.validate()?;
        let mut plan = self.plan(scene);
        if provided {
            plan.passes.retain(|p| !(p.starts_with("raster.") || p == "resolve"));
        }
        if !plan.shadows.is_empty() {
            let rebuild = self.shadows.as_ref().is_none_or(|st| st.key != plan.shadows);
            if rebuild {
                self.shadows = Some(ShadowStage::new(device, &self.settings, scene)?);
            }
            self.shadows.as_ref().expect("built above").update(
                queue,
                scene,
                self.settings.shadows.resolution,
            );
        }
        let ao_two_layers = plan.ao_two_layers;
        if plan.ao == Reason::Runs && self.ao.as_ref().is_none_or(|a| a.two_layers != ao_two_layers)
        {
            self.ao = Some(AoStage::new(device, &self.settings, ao_two_layers));
        }
        if self.shading.is_none() {
            self.shading = Some(ShadingStage::new(device, &self.settings));
        }
        if plan.reflections == Reason::Runs && self.reflections.is_none() {
            self.reflections = Some(ReflectionsStage::new(device, &self.settings));
        }
        let radiosity_history = self.history.is_some() && self.radiosity.is_some();
        if plan.radiosity == Reason::Runs {
            let stage =
                self.radiosity.get_or_insert_with(|| RadiosityStage::new(device, &self.settings));
            let jitter = self.settings.radiosity.jitter;
            stage.turn = if radiosity_history && jitter { stage.turn.wrapping_add(1) } else { 0 };
            let uniform =
                RadiosityUniform::new(&self.settings.radiosity, radiosity_history, stage.turn);
            queue.write_buffer(&stage.uniform, 0, bytemuck::bytes_of(&uniform));
        }
        let layers = plan.layers as usize;
        let s = &self.settings;
        let current = CameraMatrices::new(camera, s.width, s.height);
        let previous = self.history.unwrap_or(current);
        let b = scene.buffers();
        let uniform = FrameUniform {
            flags: gpu::FRAME_DIAGNOSTICS,
            ..FrameUniform::new(
                camera,
                current,
                previous,
                s.width,
                s.height,
                s.dz,
                (b.triangle_count, b.material_count, b.vertex_count),
            )
        };
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(&uniform));
        self.last_frame = Some(uniform);
        let needed =
            raster::bin_bytes(b.triangle_count, device.limits().max_storage_buffer_binding_size);
        if self.large.as_ref().is_none_or(|l| l.size() < needed) {
            let usage = wgpu::BufferUsages::empty();
            self.large =
                Some(gpu::storage_buffer(device, "deep-gbuffer.raster.large", needed, usage));
        }
        encoder.clear_buffer(&self.bins, 0, None);

        let one_pass = layers == 2 && s.layer1 != Layer1Variant::TwoPass && self.history.is_some();
        let write = 1 - self.last;
        let (vis0, prev_vis0) = (&self.vis0[write], &self.vis0[self.last]);
        let large = self.large.as_ref().expect("allocated above");
        let (frame, bins, args) = (&self.frame, &self.bins, &self.args);
        let targets = |vis0, vis1, zref| RasterTargets {
            frame,
            bins,
            large,
            args,
            vis0,
            vis1,
            zref,
            counts: None,
        };
        let mut timestamps = self.timestamps.as_mut();
        if let Some(t) = timestamps.as_deref_mut() {
            t.reset();
        }
        let mut passes: Vec<String> = Vec::new();
        let mut begin = |encoder: &mut wgpu::CommandEncoder, name: &str| {
            passes.push(name.to_string());
            let label = format!("deep-gbuffer.{name}");
            let timestamp_writes = timestamps.as_deref_mut().and_then(|t| t.pass(name));
            encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(&label),
                    timestamp_writes,
                })
                .forget_lifetime()
        };

        if !provided {
            let mut pass = begin(encoder, "raster.clear");
            self.fill.encode(device, &mut pass, vis0, u32::MAX);
            if layers == 2 {
                self.fill.encode(device, &mut pass, &self.vis1, u32::MAX);
            }
        }
        if provided {
            // The caller's layers are in place (render_gbuffer wrote them).
        } else if one_pass {
            let reproject = s.layer1 == Layer1Variant::Reproject;
            let mut pass = begin(encoder, "raster.layers");
            let t = targets(Some(vis0), Some(&self.vis1), Some(prev_vis0));
            self.raster.encode(device, &mut pass, scene, RasterMode::Both { reproject }, &t);
        } else {
            {
                let mut pass = begin(encoder, "raster.layer0");
                self.raster.encode(
                    device,
                    &mut pass,
                    scene,
                    RasterMode::Layer0,
                    &targets(Some(vis0), None, None),
                );
            }
            if layers == 2 {
                let mut pass = begin(encoder, "raster.layer1");
                let t = targets(None, Some(&self.vis1), Some(vis0));
                self.raster.encode(device, &mut pass, scene, RasterMode::Layer1, &t);
            }
        }
        if !provided {
            let mut pass = begin(encoder, "resolve");
            for (layer, vis) in [vis0, &self.vis1].iter().enumerate().take(layers) {
                self.resolve.encode(
                    device,
                    &mut pass,
                    scene,
                    &self.frame,
                    vis,
                    &self.gbuffer[layer],
                    s.width,
                    s.height,
                );
            }
        }
        let size = (s.width, s.height);
        let ao_stage = self.ao.as_ref().filter(|_| plan.ao == Reason::Runs);
        if let Some(ao) = ao_stage {
            {
                let mut pass = begin(encoder, "pyramid");
                let layers = if ao.two_layers { 2 } else { 1 };
                for layer in 0..layers {
                    ao.pyramid.encode(device, &mut pass, &self.gbuffer[layer], &ao.pyramids[layer]);
                }
            }
            {
                let mut pass = begin(encoder, "ao");
                let pyramids = [&ao.pyramids[0], &ao.pyramids[1]];
                ao.ao.encode(
                    device,
                    &mut pass,
                    &self.frame,
                    &ao.uniform,
                    &self.gbuffer[0],
                    pyramids,
                    &ao.av[0],
                    size,
                );
            }
            if s.ao.blur_radius > 0 {
                let mut pass = begin(encoder, "ao.blur");
                ao.blur.encode(
                    device,
                    &mut pass,
                    &self.frame,
                    &self.gbuffer[0],
                    &ao.av[0],
                    &ao.av[1],
                    &ao.av[2],
                    size,
                );
            }
        }
        let shading = self.shading.as_ref().expect("created above");
        let shadow_stage = self.shadows.as_ref().filter(|_| !plan.shadows.is_empty());
        if let Some(stage) = shadow_stage {
            for (name, _, first, count) in &stage.groups {
                {
                    let mut pass = begin(encoder, &format!("shadow.{name}"));
                    for face in *first..first + count {
                        self.fill.encode(device, &mut pass, &stage.face_vis[face], u32::MAX);
                        let t = RasterTargets {
                            frame: &stage.face_uniforms[face],
                            bins,
                            large,
                            args,
                            vis0: Some(&stage.face_vis[face]),
                            vis1: None,
                            zref: None,
                            counts: None,
                        };
                        self.raster.encode(device, &mut pass, scene, RasterMode::Layer0, &t);
                    }
                }
                for face in *first..first + count {
                    let bytes = stage.face_vis[face].size();
                    encoder.copy_buffer_to_buffer(
                        &stage.face_vis[face],
                        0,
                        &stage.atlas,
                        face as u64 * bytes,
                        bytes,
                    );
                }
            }
        }
        if plan.direct == Reason::Runs {
            let mut pass = begin(encoder, "direct");
            let layer1 = plan.radiosity == Reason::Runs || plan.reflections == Reason::Runs;
            let targets =
                [(&self.gbuffer[0], &shading.radiance), (&self.gbuffer[1], &shading.radiance1)];
            for (gbuffer, radiance) in targets.into_iter().take(1 + usize::from(layer1)) {
                let shadows = shadow_stage.map(|stage| ShadowInputs {
                    faces: &stage.faces,
                    light_faces: &stage.light_faces,
                    atlas: &stage.atlas,
                    pcf: s.shadows.pcf,
                });
                shading.direct.encode(
                    device,
                    &mut pass,
                    &self.frame,
                    scene,
                    gbuffer,
                    radiance,
                    shadows,
                    size,
                );
            }
        } else {
            encoder.clear_buffer(&shading.radiance, 0, None);
            encoder.clear_buffer(&shading.radiance1, 0, None);
        }
        let radiosity_stage = self.radiosity.as_ref().filter(|_| plan.radiosity == Reason::Runs);
        if let Some(r) = radiosity_stage {
            let targets = RadiosityTargets {
                frame: &self.frame,
                uniform: &r.uniform,
                gbuffer: [&self.gbuffer[0], &self.gbuffer[1]],
                direct: [&shading.radiance, &shading.radiance1],
                b: [&r.b[0], &r.b[1]],
                raw: &r.raw,
                history: [&r.history[r.last], &r.history[1 - r.last]],
                prev_vis0,
            };
            {
                let mut pass = begin(encoder, "radiosity");
                r.pass.encode_gather(device, &mut pass, &targets, size);
            }
            {
                let mut pass = begin(encoder, "radiosity.temporal");
                r.pass.encode_temporal(device, &mut pass, &targets, size);
            }
            if s.radiosity.blur_radius > 0 {
                let mut pass = begin(encoder, "radiosity.blur");
                let filtered = &r.history[1 - r.last];
                r.blur.encode(
                    device,
                    &mut pass,
                    &self.frame,
                    &self.gbuffer[0],
                    filtered,
                    &r.blurred[0],
                    &r.blurred[1],
                    size,
                );
            }
        }
        let reflections_stage =
            self.reflections.as_ref().filter(|_| plan.reflections == Reason::Runs);
        if let Some(r) = reflections_stage {
            encoder.clear_buffer(&r.tiles, 0, None);
            encoder.clear_buffer(&r.output, 0, None);
            let mut pass = begin(encoder, "reflections");
            let (environment, env_width, env_height) = match &self.environment {
                Some((buffer, w, h)) => (buffer, *w, *h),
                None => (&r.no_environment, 0, 0),
            };
            // The radiosity pass's B is the fuller outgoing radiance (it adds the previous
            // frame's indirect light to direct and emission).
            let radiance = match radiosity_stage {
                Some(rad) => [&rad.b[0], &rad.b[1]],
                None => [&shading.radiance, &shading.radiance1],
            };
            let uniform = ReflectionsUniform {
                sky: scene.info().ambient.to_array(),
                max_distance: s.reflections.max_distance,
                thickness: s.reflections.thickness,
                tiles_x: r.tiles_x,
                tiles_y: r.tiles_y,
                env_width,
                env_height,
                with_emission: u32::from(radiosity_stage.is_some()),
                _pad: [0; 2],
            };
            let targets = ReflectionTargets {
                frame: &self.frame,
                gbuffer0: &self.gbuffer[0],
                vis1: &self.vis1,
                radiance,
                environment,
                tiles: &r.tiles,
                args: &r.args,
                output: &r.output,
            };
            r.pass.encode(device, &mut pass, &uniform, &targets);
        }
        {
            let mut pass = begin(encoder, "composite");
            let av = ao_stage.map(|ao| if s.ao.blur_radius > 0 { &ao.av[2] } else { &ao.av[0] });
            let radiosity = radiosity_stage.map(|r| r.output(s.radiosity.blur_radius));
            let composite = &shading.composite;
            let ambient = scene.info().ambient;
            composite.encode(
                device,
                &mut pass,
                &self.frame,
                ambient,
                &self.gbuffer[0],
                &shading.radiance,
                av,
                radiosity,
                reflections_stage.map(|r| &r.output),
                &shading.hdr,
                size,
            );
        }
        if let Some(t) = &self.timestamps {
            t.resolve(encoder);
        }
        if let Some(r) = self.radiosity.as_mut().filter(|_| plan.radiosity == Reason::Runs) {
            r.last = 1 - r.last;
        }
        debug_assert_eq!(passes, plan.passes, "the recorded passes are the plan's");
        self.plan = Some(plan);
        self.passes = passes;
        self.last = write;
        self.history = Some(current);
        Ok(())
    }

    /// [`encode`](Renderer::encode), then copies the HDR composite (`vec4<f32>` per pixel, row
    /// major) into the caller's `target` buffer (COPY_DST, at least `width * height * 16` bytes).
    pub fn encode_to(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        camera: &Camera,
        target: &wgpu::Buffer,
    ) -> Result<()> {
        let bytes = u64::from(self.settings.width) * u64::from(self.settings.height) * 16;
        if target.size() < bytes || !target.usage().contains(wgpu::BufferUsages::COPY_DST) {
            return Err(Error::ImportedBuffer {
                name: "target",
                message: format!(
                    "needs COPY_DST usage and {bytes} bytes (has {} bytes, {:?})",
                    target.size(),
                    target.usage()
                ),
            });
        }
        self.encode(device, queue, encoder, scene, camera)?;
        let hdr = self.hdr_buffer().expect("encode creates it");
        encoder.copy_buffer_to_buffer(hdr, 0, target, 0, bytes);
        Ok(())
    }

    /// [`encode`](Renderer::encode), then writes the HDR composite into the caller's storage
    /// texture: `Rgba32Float` or `Rgba16Float`, the renderer's size, with STORAGE_BINDING usage.
    pub fn encode_to_texture(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        camera: &Camera,
        texture: &wgpu::Texture,
    ) -> Result<()> {
        let f16 = match texture.format() {
            wgpu::TextureFormat::Rgba32Float => false,
            wgpu::TextureFormat::Rgba16Float => true,
            other => {
                return Err(Error::ImportedBuffer {
                    name: "texture",
                    message: format!("format {other:?}; expected Rgba32Float or Rgba16Float"),
                });
            }
        };
        let (w, h) = (self.settings.width, self.settings.height);
        let size = texture.size();
        if (size.width, size.height) != (w, h)
            || !texture.usage().contains(wgpu::TextureUsages::STORAGE_BINDING)
        {
            return Err(Error::ImportedBuffer {
                name: "texture",
                message: format!(
                    "{}x{} with {:?}; needs {w}x{h} and STORAGE_BINDING",
                    size.width,
                    size.height,
                    texture.usage()
                ),
            });
        }
        self.encode(device, queue, encoder, scene, camera)?;
        let present = self.present.get_or_insert_with(|| PresentPass::new(device));
        let hdr = &self.shading.as_ref().expect("encode creates it").hdr;
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("deep-gbuffer.present"),
            timestamp_writes: None,
        });
        present.encode(device, &mut pass, &self.frame, hdr, &view, f16, (w, h));
        Ok(())
    }

    /// Encodes and submits one frame on `queue`.
    pub fn render(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        camera: &Camera,
    ) -> Result<()> {
        self.submit_frame(device, queue, scene, camera, false)
    }

    /// Shades a deep G-buffer that the caller provides instead of rasterizing one: the layers
    /// (one, or two when the plan reads layer 1; of the renderer's size) are uploaded in the full
    /// encoding and every pass after `resolve` runs on them, with the scene's lights, materials
    /// and shadow casters and `camera`'s matrices. This is how the kernels are tested on stored
    /// G-buffers (fixtures/gbuffer/), and how a host that draws its own G-buffer uses the
    /// lighting alone. Needs [`Precision::Full`](crate::Precision::Full).
    pub fn render_gbuffer(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        camera: &Camera,
        layers: &[GBufferLayer],
    ) -> Result<()> {
        let s = &self.settings;
        if s.precision != crate::Precision::Full {
            return Err(Error::setting(
                "precision",
                "a provided G-buffer is uploaded in the full encoding (set precision to full)",
            ));
        }
        let needed = self.plan(scene).layers as usize;
        if layers.len() < needed || layers.len() > 2 {
            return Err(Error::setting(
                "gbuffer",
                format!("{} layers given, the plan reads {needed} (give 1 or 2)", layers.len()),
            ));
        }
        for (i, l) in layers.iter().enumerate() {
            if (l.width, l.height) != (s.width, s.height)
                || l.samples.len() != (s.width * s.height) as usize
            {
                return Err(Error::setting(
                    "gbuffer",
                    format!(
                        "layer {i} is {}x{} with {} samples, the renderer is {}x{}",
                        l.width,
                        l.height,
                        l.samples.len(),
                        s.width,
                        s.height
                    ),
                ));
            }
        }
        let write = 1 - self.last;
        let empty = GBufferLayer {
            width: s.width,
            height: s.height,
            samples: vec![Default::default(); (s.width * s.height) as usize],
        };
        let layer1 = layers.get(1).unwrap_or(&empty);
        for (l, (gbuffer, vis)) in [&layers[0], layer1]
            .into_iter()
            .zip([(&self.gbuffer[0], &self.vis0[write]), (&self.gbuffer[1], &self.vis1)])
        {
            queue.write_buffer(gbuffer, 0, bytemuck::cast_slice(&l.encode_full()));
            let words: Vec<u64> =
                l.samples
                    .iter()
                    .map(|s| {
                        if s.depth > 0.0 {
                            gbuffer::vis_pack(s.depth, 0)
                        } else {
                            gbuffer::VIS_EMPTY
                        }
                    })
                    .collect();
            queue.write_buffer(vis, 0, bytemuck::cast_slice(&words));
        }
        self.submit_frame(device, queue, scene, camera, true)
    }

    /// Records a frame into an encoder of its own and submits it, GPU errors caught.
    fn submit_frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        camera: &Camera,
        provided: bool,
    ) -> Result<()> {
        gpu::scoped(device, "deep-gbuffer.frame", || {
            let label = Some("deep-gbuffer.frame");
            let mut encoder =
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label });
            self.encode_frame(device, queue, &mut encoder, scene, camera, provided)?;
            let index = queue.submit([encoder.finish()]);
            // At most two frames in flight: wait for the one before. This also lets the device
            // free what finished frames used; without it a loop of renders that never polls
            // keeps every frame's transient objects alive.
            if let Some(previous) = self.in_flight.replace(index) {
                device
                    .poll(wgpu::PollType::Wait { submission_index: Some(previous), timeout: None })
                    .map_err(|e| Error::Gpu {
                        label: "deep-gbuffer.frame".into(),
                        message: e.to_string(),
                    })?;
            }
            Ok(())
        })
    }

    /// Per-pass GPU times of the last submitted frame (empty without `TIMESTAMP_QUERY`).
    pub fn timings(&self, device: &wgpu::Device) -> Result<Vec<PassTiming>> {
        match &self.timestamps {
            Some(t) => t.read(device),
            None => Ok(Vec::new()),
        }
    }

    /// The visibility buffer of `layer` (0 or 1): `u64` words `(depth bits << 32) | triangle id`.
    pub fn visibility_buffer(&self, layer: usize) -> &wgpu::Buffer {
        if layer == 0 { &self.vis0[self.last] } else { &self.vis1 }
    }

    /// The G-buffer of `layer` (layout in `wgsl/shared/gbuffer.wgsl`).
    pub fn gbuffer_buffer(&self, layer: usize) -> &wgpu::Buffer {
        &self.gbuffer[layer.min(1)]
    }

    /// Reads a visibility buffer back (waits for the GPU).
    pub fn read_visibility(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        layer: usize,
    ) -> Result<Vec<u64>> {
        let bytes = gpu::read_buffer(device, queue, self.visibility_buffer(layer))?;
        let n = (self.settings.width * self.settings.height) as usize;
        Ok(bytemuck::pod_collect_to_vec::<u8, u64>(&bytes[..n * 8]))
    }

    /// Reads and decodes a G-buffer layer (waits for the GPU).
    pub fn read_gbuffer(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        layer: usize,
    ) -> Result<GBufferLayer> {
        let bytes = gpu::read_buffer(device, queue, self.gbuffer_buffer(layer))?;
        Ok(GBufferLayer::decode(
            &bytes,
            self.settings.width,
            self.settings.height,
            self.settings.precision,
        ))
    }

    /// The ambient visibility AV in [0, 1] per pixel (f32, row-major; blurred unless the blur
    /// radius is 0), or `None` when obscurance is off.
    pub fn ao_buffer(&self) -> Option<&wgpu::Buffer> {
        self.plan.as_ref().filter(|p| p.ao == Reason::Runs)?;
        let ao = self.ao.as_ref()?;
        Some(if self.settings.ao.blur_radius > 0 { &ao.av[2] } else { &ao.av[0] })
    }

    /// The obscurance before the blur, or `None` when obscurance is off.
    pub fn ao_raw_buffer(&self) -> Option<&wgpu::Buffer> {
        self.ao.as_ref().map(|ao| &ao.av[0])
    }

    /// The depth pyramid of `layer` (levels packed as in
    /// [`PyramidLayout`](crate::passes::pyramid::PyramidLayout)), or `None` when obscurance is off.
    pub fn pyramid_buffer(&self, layer: usize) -> Option<&wgpu::Buffer> {
        self.ao.as_ref().map(|ao| &ao.pyramids[layer.min(1)])
    }

    /// Reads an f32 per-pixel buffer such as [`ao_buffer`](Renderer::ao_buffer) back.
    pub fn read_f32(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<f32>> {
        let bytes = gpu::read_buffer(device, queue, buffer)?;
        Ok(bytemuck::pod_collect_to_vec::<u8, f32>(&bytes[..bytes.len() / 4 * 4]))
    }

    /// Reads the raster counters and the bad-input counts of the last frame (waits for the GPU).
    pub fn diagnostics(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Diagnostics> {
        let bytes = gpu::read_buffer(device, queue, &self.bins)?;
        let w: &[u32] = bytemuck::cast_slice(&bytes[..raster::BINS_BYTES as usize]);
        Ok(Diagnostics {
            large_triangles: w[3],
            dropped_triangles: w[1],
            rejected_indices: w[8],
            rejected_materials: w[9],
            rejected_positions: w[10],
            untextured_triangles: w[11],
        })
    }
}
