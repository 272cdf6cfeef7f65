//! `wgsl/composite.wgsl`: the terms summed into the HDR image.

use super::{FrameContext, Recorder, Stage};
use crate::SceneBuffers;
use crate::frame::CompositeUniform;
use crate::gpu::{self, slots::composite as slot};
use crate::plan::PassId;

/// The HDR image (`vec4<f32>` per pixel) and the composite's constants.
pub(crate) struct CompositeStage {
    uniform: wgpu::Buffer,
    hdr: wgpu::Buffer,
}

impl CompositeStage {
    /// The image of a `pixels`-pixel frame.
    pub(crate) fn new(device: &wgpu::Device, pixels: u64) -> Self {
        CompositeStage {
            uniform: gpu::uniform_buffer_for::<CompositeUniform>(device, "deep-gbuffer.composite"),
            hdr: gpu::storage_buffer(
                device,
                "deep-gbuffer.composite.hdr",
                pixels * 16,
                wgpu::BufferUsages::empty(),
            ),
        }
    }

    /// Writes the frame's constants.
    pub(crate) fn prepare(&self, queue: &wgpu::Queue, scene: &SceneBuffers) {
        let uniform = CompositeUniform { ambient: scene.info().ambient.to_array(), _pad: 0 };
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }

    /// The HDR image.
    pub(crate) fn hdr(&self) -> &wgpu::Buffer {
        &self.hdr
    }
}

impl Stage for CompositeStage {
    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        debug_assert_eq!(*id, PassId::Composite);
        let mut pass = rec.pass(id);
        let mut defines = ctx.settings.precision.defines();
        let mut entries = vec![
            (slot::FRAME, ctx.frame),
            (slot::COMPOSITE, &self.uniform),
            (slot::GBUFFER, ctx.gbuffer[0]),
            (slot::DIRECT, ctx.direct[0]),
            (slot::HDR, ctx.sharp.unwrap_or(&self.hdr)),
        ];
        let terms = [
            ("AO", slot::AV, ctx.av),
            ("RADIOSITY", slot::RADIOSITY, ctx.irradiance),
            ("REFLECTIONS", slot::REFLECTIONS, ctx.reflections),
        ];
        for (define, s, buffer) in terms {
            if let Some(buffer) = buffer {
                defines.push(define);
                entries.push((s, buffer));
            }
        }
        let pipeline = ctx.pipelines.get(ctx.device, "composite", "composite_main", &defines, &[]);
        pipeline.dispatch_pixels(ctx.device, &mut pass, &entries, ctx.size());
    }
}
