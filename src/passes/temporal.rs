//! `wgsl/temporal.wgsl`: the temporal filter the obscurance and the radiosity share.

use super::FrameContext;
use crate::frame::TemporalUniform;
use crate::gpu::{self, slots::temporal as slot};

/// One estimate's temporal filter: its constants (written every frame) and whether it filters
/// `vec4<f32>` values (the radiosity's irradiance and coverage) or f32 ones (the obscurance's AV).
pub(crate) struct Temporal {
    uniform: wgpu::Buffer,
    vec4: bool,
}

impl Temporal {
    /// A filter of `vec4<f32>` values (`vec4`) or f32 ones, its constants labelled `label`.
    pub(crate) fn new(device: &wgpu::Device, label: &str, vec4: bool) -> Self {
        Temporal { uniform: gpu::uniform_buffer_for::<TemporalUniform>(device, label), vec4 }
    }

    /// This frame's constants: the history's weight `alpha`, the `tolerance` of its depth test,
    /// and whether there is a `history` to take.
    pub(crate) fn prepare(&self, queue: &wgpu::Queue, alpha: f32, tolerance: f32, history: bool) {
        let uniform = TemporalUniform { alpha, tolerance, history: u32::from(history), _pad: 0 };
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }

    /// Records `current` blended with `history_in` (the last frame's filtered values) into
    /// `history_out`, reprojected by layer 0's motion.
    pub(crate) fn record(
        &self,
        ctx: &FrameContext<'_>,
        pass: &mut wgpu::ComputePass<'_>,
        [current, history_in, history_out]: [&wgpu::Buffer; 3],
    ) {
        let mut defines = ctx.settings.precision.defines();
        if self.vec4 {
            defines.push("VEC4");
        }
        let pipeline = ctx.pipelines.get(ctx.device, "temporal", "temporal_main", &defines, &[]);
        let entries = [
            (slot::FRAME, ctx.frame),
            (slot::PARAMS, &self.uniform),
            (slot::GBUFFER, ctx.gbuffer[0]),
            (slot::PREV_VIS0, ctx.raster.previous_vis0()),
            (slot::CURRENT, current),
            (slot::HISTORY_IN, history_in),
            (slot::HISTORY_OUT, history_out),
        ];
        pipeline.dispatch_pixels(ctx.device, pass, &entries, ctx.size());
    }
}
