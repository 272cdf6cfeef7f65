//! `wgsl/dof.wgsl`: depth of field through the camera's thin lens.

use super::{FrameContext, Recorder, Stage};
use crate::frame::DofUniform;
use crate::gpu::{self, slots::dof as slot};
use crate::plan::PassId;
use crate::scene::{Camera, SceneInfo};
use crate::settings::Settings;

/// The depth of field: its constants and the sharp image the composite writes for it.
pub(crate) struct DofStage {
    uniform: wgpu::Buffer,
    sharp: wgpu::Buffer,
}

impl DofStage {
    /// The stage for a `pixels`-pixel frame.
    pub(crate) fn new(device: &wgpu::Device, pixels: u64) -> Self {
        DofStage {
            uniform: gpu::uniform_buffer_for::<DofUniform>(device, "deep-gbuffer.dof"),
            sharp: gpu::storage_buffer(
                device,
                "deep-gbuffer.dof.sharp",
                pixels * 16,
                wgpu::BufferUsages::empty(),
            ),
        }
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

    /// The image through a pinhole, as the composite writes it (`vec4<f32>` per pixel).
    pub(crate) fn sharp(&self) -> &wgpu::Buffer {
        &self.sharp
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
        let entries = [
            (slot::FRAME, ctx.frame),
            (slot::DOF, &self.uniform),
            (slot::GBUFFER0, ctx.gbuffer[0]),
            (slot::GBUFFER1, ctx.gbuffer[1]),
            (slot::DIRECT1, ctx.direct[1]),
            (slot::SHARP, &self.sharp),
            (slot::HDR, ctx.hdr),
        ];
        pipeline.dispatch_pixels(ctx.device, &mut pass, &entries, ctx.size());
    }
}
