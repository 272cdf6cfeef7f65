//! `wgsl/composite.wgsl`: the terms summed into the HDR image.

use super::{FrameContext, Recorder, Stage};
use crate::SceneBuffers;
use crate::frame::CompositeUniform;
use crate::gpu::{self, slots::composite as slot};
use crate::plan::PassId;

/// The HDR image (`vec4<f32>` per pixel), the composite's constants, and two more images for
/// the passes after it (made when a plan first runs one).
pub(crate) struct CompositeStage {
    uniform: wgpu::Buffer,
    hdr: wgpu::Buffer,
    post: Option<[wgpu::Buffer; 2]>,
    pixels: u64,
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
            post: None,
            pixels,
        }
    }

    /// Makes the images of the passes after the composite, if not made yet.
    pub(crate) fn make_post(&mut self, device: &wgpu::Device) {
        let pixels = self.pixels;
        self.post.get_or_insert_with(|| {
            ["deep-gbuffer.post.a", "deep-gbuffer.post.b"].map(|label| {
                gpu::storage_buffer(device, label, pixels * 16, wgpu::BufferUsages::empty())
            })
        });
    }

    /// The images of the passes after the composite, once made.
    pub(crate) fn post(&self) -> Option<[&wgpu::Buffer; 2]> {
        self.post.as_ref().map(|[a, b]| [a, b])
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
            (slot::HDR, ctx.image_io(id).1),
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
