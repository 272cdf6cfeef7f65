//! `wgsl/dof.wgsl`: depth of field through the camera's thin lens.

use super::{FrameContext, Recorder, Stage};
use crate::frame::DofUniform;
use crate::gpu::{self, slots::dof as slot};
use crate::plan::PassId;
use crate::scene::{Camera, SceneInfo};
use crate::settings::Settings;

/// The depth of field: its constants.
pub(crate) struct DofStage {
    uniform: wgpu::Buffer,
}

impl DofStage {
    /// The stage.
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        DofStage { uniform: gpu::uniform_buffer_for::<DofUniform>(device, "deep-gbuffer.dof") }
    }

    /// Writes the frame's constants for `camera` and `scene`.
    pub(crate) fn prepare(
        &self,
        queue: &wgpu::Queue,
        s: &Settings,
        camera: &Camera,
        scene: &SceneInfo,
    ) {
        let ambient = scene.ambient.to_array();
        let uniform = DofUniform::new(&s.dof, camera, s.height, scene.bounds, ambient);
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }
}

impl Stage for DofStage {
    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        debug_assert_eq!(*id, PassId::Dof);
        let mut pass = rec.pass(id);
        let mut defines = ctx.settings.precision.defines();
        if ctx.settings.dof.two_layers && ctx.plan.layers == 2 {
            defines.push("TWO_LAYERS");
        }
        let pipeline = ctx.pipelines.get(ctx.device, "dof", "dof_main", &defines, &[]);
        let (Some(sharp), hdr) = ctx.image_io(id) else {
            unreachable!("a post pass reads an image");
        };
        let entries = [
            (slot::FRAME, ctx.frame),
            (slot::DOF, &self.uniform),
            (slot::GBUFFER0, ctx.gbuffer[0]),
            (slot::GBUFFER1, ctx.gbuffer[1]),
            (slot::DIRECT1, ctx.direct[1]),
            (slot::SHARP, sharp),
            (slot::HDR, hdr),
        ];
        pipeline.dispatch_pixels(ctx.device, &mut pass, &entries, ctx.size());
    }
}
