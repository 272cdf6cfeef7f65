//! `wgsl/upsample.wgsl`: the depth- and normal-aware upsample of an effect computed at a lower
//! resolution.

use super::FrameContext;
use crate::gpu::slots::upsample as slot;

/// One upsample: the level the effect was computed at (1: half, 2: quarter resolution), whether
/// it holds `vec4<f32>` (radiosity) or f32 (obscurance) values, and the value of pixels without
/// a surface.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Upsample {
    pub level: u32,
    pub vec4: bool,
    pub empty: f32,
}

impl Upsample {
    /// Records `low` -> `full`, guided by layer 0.
    pub(crate) fn record(
        &self,
        ctx: &FrameContext<'_>,
        pass: &mut wgpu::ComputePass<'_>,
        [low, full]: [&wgpu::Buffer; 2],
    ) {
        let mut defines = ctx.settings.precision.defines();
        if self.vec4 {
            defines.push("VEC4");
        }
        let constants = [("LEVEL", f64::from(self.level)), ("EMPTY", f64::from(self.empty))];
        let pipeline =
            ctx.pipelines.get(ctx.device, "upsample", "upsample_main", &defines, &constants);
        let entries = [
            (slot::FRAME, ctx.frame),
            (slot::GBUFFER, ctx.gbuffer[0]),
            (slot::LOW, low),
            (slot::FULL, full),
        ];
        pipeline.dispatch_pixels(ctx.device, pass, &entries, ctx.size());
    }
}
