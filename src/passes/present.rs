//! `wgsl/present.wgsl`: the HDR composite into a caller's storage texture.

use crate::gpu;

/// The present kernel for rgba32float and rgba16float targets.
pub struct PresentPass {
    pipelines: [wgpu::ComputePipeline; 2],
}

impl PresentPass {
    /// Builds both pipelines.
    pub fn new(device: &wgpu::Device) -> Self {
        PresentPass {
            pipelines: [
                gpu::compute_pipeline(device, "present", "present_main", &[]),
                gpu::compute_pipeline(device, "present", "present_main", &["F16"]),
            ],
        }
    }

    /// Records the copy of `hdr` into `view` (of an rgba16float texture when `f16`).
    #[expect(clippy::too_many_arguments, reason = "the kernel's bindings, named")]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        frame: &wgpu::Buffer,
        hdr: &wgpu::Buffer,
        view: &wgpu::TextureView,
        f16: bool,
        size: (u32, u32),
    ) {
        let pipeline = &self.pipelines[usize::from(f16)];
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("deep-gbuffer.present"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: frame.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: hdr.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(view),
                },
            ],
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
    }
}
