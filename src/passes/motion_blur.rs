//! `wgsl/motion_blur.wgsl`: motion blur of the camera's motion.

use super::{FrameContext, Recorder, Stage};
use crate::frame::MotionBlurUniform;
use crate::gpu::{self, slots::motion_blur as slot};
use crate::plan::PassId;
use crate::scene::SceneInfo;
use crate::settings::Settings;

/// The motion blur: its constants and the largest motion `motion_max` finds.
pub(crate) struct MotionBlurStage {
    uniform: wgpu::Buffer,
    largest: wgpu::Buffer,
}

impl MotionBlurStage {
    /// The stage.
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        MotionBlurStage {
            uniform: gpu::uniform_buffer_for::<MotionBlurUniform>(
                device,
                "deep-gbuffer.motion_blur",
            ),
            largest: gpu::storage_buffer(
                device,
                "deep-gbuffer.motion_blur.largest",
                4,
                wgpu::BufferUsages::empty(),
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
    fn begin(&self, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        if ctx.plan.contains(&PassId::MotionBlur) {
            rec.encoder().clear_buffer(&self.largest, 0, None);
        }
    }

    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        debug_assert_eq!(*id, PassId::MotionBlur);
        let mut pass = rec.pass(id);
        let mut defines = ctx.settings.precision.defines();
        if ctx.settings.motion_blur.two_layers && ctx.plan.layers == 2 {
            defines.push("TWO_LAYERS");
        }
        let get = |entry| ctx.pipelines.get(ctx.device, "motion_blur", entry, &defines, &[]);
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
            (slot::LARGEST, &self.largest),
        ];
        get("motion_max").dispatch_pixels(ctx.device, &mut pass, &entries, ctx.size());
        get("motion_blur_main").dispatch_pixels(ctx.device, &mut pass, &entries, ctx.size());
    }
}
