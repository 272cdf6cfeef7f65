//! `wgsl/resolve.wgsl`: visibility buffer to G-buffer layer.

use crate::SceneBuffers;
use crate::gpu;
use crate::settings::Precision;

/// The resolve kernel for one G-buffer precision.
pub struct ResolvePass {
    pipeline: wgpu::ComputePipeline,
}

impl ResolvePass {
    /// Builds the pipeline.
    pub fn new(device: &wgpu::Device, precision: Precision) -> Self {
        ResolvePass {
            pipeline: gpu::compute_pipeline(device, "resolve", "resolve", &precision.defines()),
        }
    }

    /// Records the resolve of `vis` into `gbuffer` for a `width` x `height` image.
    #[expect(clippy::too_many_arguments, reason = "the kernel's bindings, named")]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        scene: &SceneBuffers,
        frame: &wgpu::Buffer,
        vis: &wgpu::Buffer,
        gbuffer: &wgpu::Buffer,
        width: u32,
        height: u32,
    ) {
        let b = scene.buffers();
        gpu::dispatch_pixels(
            device,
            pass,
            "deep-gbuffer.resolve",
            &self.pipeline,
            &[
                (0, frame),
                (1, &b.positions),
                (2, &b.normals),
                (3, &b.uvs),
                (4, &b.indices),
                (5, &b.triangle_materials),
                (6, &b.materials),
                (7, &b.texels),
                (8, vis),
                (9, gbuffer),
            ],
            (width, height),
        );
    }
}
