//! `wgsl/offscreen.wgsl`: the light of the surfaces neither layer holds, from the lights'
//! reflective shadow maps (drawn by the shadow stage), added to the radiosity's gather. The
//! radiosity stage owns it and records it as `radiosity.offscreen`.

use super::FrameContext;
use crate::frame::{
    Cluster, OffscreenUniform, RSM_CLUSTER_SIDE, RSM_CLUSTERS_PER_FACE, RSM_CLUSTERS_PER_PIXEL,
    RSM_HELD_MARGIN, RSM_RESOLUTION,
};
use crate::gpu::{self, slots::offscreen as slot};

/// The off-screen light's constants, the clusters of the reflective shadow maps' texels that no
/// layer holds, and those that hold a texel listed in order with their count.
pub(crate) struct Offscreen {
    uniform: wgpu::Buffer,
    clusters: wgpu::Buffer,
    lit: wgpu::Buffer,
    lit_count: wgpu::Buffer,
    faces: u32,
}

/// The off-screen light's buffers, as
/// [`Renderer::offscreen_buffers`](crate::Renderer::offscreen_buffers) names them: the lights'
/// reflective shadow maps and the clusters of their texels that no layer holds.
#[derive(Clone, Copy, Debug)]
pub struct OffscreenBuffers<'a> {
    /// A [`ShadowFace`](crate::frame::ShadowFace) per face, at
    /// [`RSM_RESOLUTION`] texels a side (offsets in texels).
    pub faces: &'a wgpu::Buffer,
    /// The light of each face (`u32`).
    pub face_lights: &'a wgpu::Buffer,
    /// The faces' visibility words, back to back (two `u32` a texel: id, depth).
    pub vis: &'a wgpu::Buffer,
    /// The faces' G-buffer records, back to back: a G-buffer layer [`RSM_RESOLUTION`] wide and
    /// `RSM_RESOLUTION * face_count` high.
    pub records: &'a wgpu::Buffer,
    /// How many faces.
    pub face_count: u32,
    /// [`RSM_CLUSTERS_PER_FACE`] [`Cluster`]s per face.
    pub clusters: &'a wgpu::Buffer,
}

impl Offscreen {
    /// The buffers for `faces` reflective shadow map faces: `kept` when it was made for as
    /// many, else new ones.
    pub(crate) fn for_faces(kept: Option<Offscreen>, device: &wgpu::Device, faces: u32) -> Self {
        if let Some(o) = kept.filter(|o| o.faces == faces) {
            return o;
        }
        let bytes =
            u64::from(faces.max(1) * RSM_CLUSTERS_PER_FACE) * std::mem::size_of::<Cluster>() as u64;
        let storage =
            |label, size| gpu::storage_buffer(device, label, size, wgpu::BufferUsages::empty());
        Offscreen {
            uniform: gpu::uniform_buffer_for::<OffscreenUniform>(device, "deep-gbuffer.offscreen"),
            clusters: storage("deep-gbuffer.offscreen.clusters", bytes),
            lit: storage("deep-gbuffer.offscreen.lit", bytes),
            lit_count: storage("deep-gbuffer.offscreen.count", 16),
            faces,
        }
    }

    /// Writes the frame's constants: the radiosity's `turn` and the frame's `layers`.
    pub(crate) fn prepare(&self, queue: &wgpu::Queue, turn: u32, layers: u32) {
        let uniform = OffscreenUniform::new(self.faces, turn, layers);
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }

    /// The clusters (a [`Cluster`] each).
    pub(crate) fn clusters(&self) -> &wgpu::Buffer {
        &self.clusters
    }

    /// Records the clusters, their list, and their light added to `gathered` (the gather's
    /// irradiance and coverage, at full resolution).
    pub(crate) fn record(
        &self,
        ctx: &FrameContext<'_>,
        pass: &mut wgpu::ComputePass<'_>,
        gathered: &wgpu::Buffer,
    ) {
        let Some(rsm) = &ctx.rsm else {
            unreachable!("the off-screen light runs with the reflective shadow maps")
        };
        let vis1 = if ctx.plan.layers == 2 { ctx.raster.vis1() } else { ctx.raster.vis0() };
        let entries = [
            (slot::FRAME, ctx.frame),
            (slot::PARAMS, &self.uniform),
            (slot::LIGHTS, ctx.scene.light_buffer()),
            (slot::FACES, rsm.faces),
            (slot::FACE_LIGHTS, rsm.face_lights),
            (slot::RSM_VIS, rsm.vis),
            (slot::RSM, rsm.gbuffer),
            (slot::VIS0, ctx.raster.vis0()),
            (slot::VIS1, vis1),
            (slot::CLUSTERS, &self.clusters),
            (slot::GBUFFER, ctx.gbuffer[0]),
            (slot::RAW, gathered),
            (slot::LIT, &self.lit),
            (slot::LIT_COUNT, &self.lit_count),
        ];
        let defines = ctx.settings.precision.defines();
        // The kernel's constants come from the crate's, which the CPU reference reads too.
        let constants = [
            ("RSM_RESOLUTION", f64::from(RSM_RESOLUTION)),
            ("CLUSTERS_PER_PIXEL", f64::from(RSM_CLUSTERS_PER_PIXEL)),
            ("HELD_MARGIN", f64::from(RSM_HELD_MARGIN)),
        ];
        let kernel =
            |entry| ctx.pipelines.get(ctx.device, "offscreen", entry, &defines, &constants);
        let cells = RSM_RESOLUTION / RSM_CLUSTER_SIDE;
        let (device, groups) = (ctx.device, (self.faces * cells, cells));
        kernel("offscreen_clusters").dispatch(device, pass, &entries, groups);
        kernel("offscreen_compact").dispatch(device, pass, &entries, (1, 1));
        kernel("offscreen_add").dispatch_pixels(device, pass, &entries, ctx.size());
    }
}
