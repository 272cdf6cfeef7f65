//! `wgsl/resolve.wgsl`: visibility buffer to G-buffer layer.

use super::{FrameContext, Recorder, Stage};
use crate::gpu::{self, slots::resolve as slot};
use crate::plan::PassId;

/// The G-buffer layers and the kernel that fills them from the visibility buffers.
pub(crate) struct ResolveStage {
    gbuffer: [wgpu::Buffer; 2],
}

impl ResolveStage {
    /// Two layers of `bytes` bytes each.
    pub(crate) fn new(device: &wgpu::Device, bytes: u64) -> Self {
        let g = |label| gpu::storage_buffer(device, label, bytes, wgpu::BufferUsages::empty());
        ResolveStage {
            gbuffer: [g("deep-gbuffer.resolve.layer0"), g("deep-gbuffer.resolve.layer1")],
        }
    }

    /// The G-buffer of `layer` (0 or 1).
    pub(crate) fn gbuffer(&self, layer: usize) -> &wgpu::Buffer {
        &self.gbuffer[layer.min(1)]
    }
}

impl Stage for ResolveStage {
    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        debug_assert_eq!(*id, PassId::Resolve);
        let mut pass = rec.pass(id);
        let vis = [ctx.raster.vis0(), ctx.raster.vis1()];
        for (vis, gbuffer) in vis.into_iter().zip(&self.gbuffer).take(ctx.plan.layers as usize) {
            resolve_layer(ctx, &mut pass, vis, gbuffer, None);
        }
    }
}

/// Records the resolve of visibility buffer `vis` into the G-buffer layer `gbuffer`, over the
/// whole image or with the workgroups `args` holds (8x8 pixels each).
pub(crate) fn resolve_layer(
    ctx: &FrameContext<'_>,
    pass: &mut wgpu::ComputePass<'_>,
    vis: &wgpu::Buffer,
    gbuffer: &wgpu::Buffer,
    args: Option<&wgpu::Buffer>,
) {
    let defines = ctx.settings.precision.defines();
    let pipeline = ctx.pipelines.get(ctx.device, "resolve", "resolve", &defines, &[]);
    let b = ctx.scene.buffers();
    let entries = [
        (slot::FRAME, ctx.frame),
        (slot::POSITIONS, &b.positions),
        (slot::NORMALS, &b.normals),
        (slot::UVS, &b.uvs),
        (slot::INDICES, &b.indices),
        (slot::TRI_MATERIALS, &b.triangle_materials),
        (slot::MATERIALS, &b.materials),
        (slot::TEXELS, &b.texels),
        (slot::VIS, vis),
        (slot::GBUFFER, gbuffer),
        (slot::UVS1, &ctx.scene.uvs1),
        (slot::TANGENTS, &ctx.scene.tangents),
    ];
    match args {
        Some(args) => pipeline.dispatch_indirect(ctx.device, pass, &entries, args, 0),
        None => pipeline.dispatch_pixels(ctx.device, pass, &entries, ctx.size()),
    }
}
