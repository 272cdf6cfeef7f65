//! `wgsl/blur.wgsl`: the separable bilateral blur (horizontal, then vertical).

use crate::gpu;
use crate::settings::Precision;

/// Both directions of the blur with one radius.
pub struct BlurPass {
    pipelines: [wgpu::ComputePipeline; 2],
}

impl BlurPass {
    /// Builds the pipelines for `precision` G-buffers and a blur `radius` in pixels, for f32
    /// images or (`vec4`) `vec4<f32>` images.
    pub fn new(device: &wgpu::Device, precision: Precision, radius: u32, vec4: bool) -> Self {
        let mut packed = precision.defines();
        if vec4 {
            packed.push("VEC4");
        }
        let packed = &packed[..];
        let mut vertical = packed.to_vec();
        vertical.push("VERTICAL");
        let radius = [("RADIUS", f64::from(radius))];
        BlurPass {
            pipelines: [
                gpu::compute_pipeline_with(device, "blur", "blur_main", packed, &radius),
                gpu::compute_pipeline_with(device, "blur", "blur_main", &vertical, &radius),
            ],
        }
    }

    /// Records `source` -> `scratch` (horizontal) -> `target` (vertical).
    #[expect(clippy::too_many_arguments, reason = "the kernel's bindings, named")]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        frame: &wgpu::Buffer,
        gbuffer0: &wgpu::Buffer,
        source: &wgpu::Buffer,
        scratch: &wgpu::Buffer,
        target: &wgpu::Buffer,
        size: (u32, u32),
    ) {
        for (pipeline, (from, to)) in
            self.pipelines.iter().zip([(source, scratch), (scratch, target)])
        {
            let entries = [(0, frame), (2, gbuffer0), (3, from), (4, to)];
            gpu::dispatch_pixels(device, pass, "deep-gbuffer.blur", pipeline, &entries, size);
        }
    }
}
