//! `wgsl/motion_blur.wgsl`: motion blur of the camera's motion.

use super::{FrameContext, Recorder, Stage};
use crate::frame::MotionBlurUniform;
use crate::gpu::{self, slots::motion_blur as slot};
use crate::plan::PassId;
use crate::scene::SceneInfo;
use crate::settings::Settings;

/// The motion blur: its constants.
pub(crate) struct MotionBlurStage {
    uniform: wgpu::Buffer,
}

impl MotionBlurStage {
    /// The stage.
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        MotionBlurStage {
            uniform: gpu::uniform_buffer_for::<MotionBlurUniform>(
                device,
                "deep-gbuffer.motion_blur",
            ),
        }
    }

    /// Writes the frame's constants for `scene`.
    pub(crate) fn prepare(&self, queue: &wgpu::Queue, s: &Settings, scene: &SceneInfo) {
        let uniform = MotionBlurUniform::new(&s.motion_blur, scene.ambient.to_array());
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }
}

impl Stage for MotionBlurStage {
    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        debug_assert_eq!(*id, PassId::MotionBlur);
        let mut pass = rec.pass(id);
        let mut defines = ctx.settings.precision.defines();
        if ctx.settings.motion_blur.two_layers && ctx.plan.layers == 2 {
            defines.push("TWO_LAYERS");
        }
        let pipeline =
            ctx.pipelines.get(ctx.device, "motion_blur", "motion_blur_main", &defines, &[]);
        let (Some(image), hdr) = ctx.image_io(id) else {
            unreachable!("a post pass reads an image");
        };
        let entries = [
            (slot::FRAME, ctx.frame),
            (slot::MOTION, &self.uniform),
            (slot::GBUFFER0, ctx.gbuffer[0]),
            (slot::GBUFFER1, ctx.gbuffer[1]),
            (slot::DIRECT1, ctx.direct[1]),
            (slot::IMAGE, image),
            (slot::HDR, hdr),
        ];
        pipeline.dispatch_pixels(ctx.device, &mut pass, &entries, ctx.size());
    }
}
