//! `wgsl/fill.wgsl`: fills u32 buffers with a value (empties visibility buffers).

use bytemuck::{Pod, Zeroable};

use crate::gpu;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FillParams {
    value: u32,
    count: u32,
    _pad: [u32; 2],
}

/// The fill kernel.
pub struct FillPass {
    pipeline: wgpu::ComputePipeline,
}

impl FillPass {
    /// Builds the pipeline.
    pub fn new(device: &wgpu::Device) -> Self {
        FillPass { pipeline: gpu::compute_pipeline(device, "fill", "fill", &[]) }
    }

    /// Records a fill of all of `buffer` with `value`.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        buffer: &wgpu::Buffer,
        value: u32,
    ) {
        let count = (buffer.size() / 4) as u32;
        let params = gpu::uniform_buffer(
            device,
            "deep-gbuffer.fill.params",
            bytemuck::bytes_of(&FillParams { value, count, _pad: [0; 2] }),
        );
        let group = gpu::bind_group(
            device,
            "deep-gbuffer.fill",
            &self.pipeline,
            &[(0, &params), (1, buffer)],
        );
        let (x, y) = gpu::dispatch_size(count.div_ceil(256));
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
}
