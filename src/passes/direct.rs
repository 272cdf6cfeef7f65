//! `wgsl/direct.wgsl`: deferred direct lighting of layer 0.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::SceneBuffers;
use crate::gpu;
use crate::settings::Precision;

/// Mirrors `struct Direct` in `wgsl/direct.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct DirectUniform {
    light_count: u32,
    _pad: [u32; 3],
}

/// The direct-light kernel.
pub struct DirectPass {
    pipeline: wgpu::ComputePipeline,
}

impl DirectPass {
    /// Builds the pipeline for `precision` G-buffers.
    pub fn new(device: &wgpu::Device, precision: Precision) -> Self {
        let defines: &[&str] = if precision == Precision::Packed { &["PACKED"] } else { &[] };
        DirectPass { pipeline: gpu::compute_pipeline(device, "direct", "direct_main", defines) }
    }

    /// Records the direct radiance of `gbuffer` into `radiance` (`vec4<f32>` per pixel).
    #[expect(clippy::too_many_arguments, reason = "the kernel's bindings, named")]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        frame: &wgpu::Buffer,
        scene: &SceneBuffers,
        gbuffer: &wgpu::Buffer,
        radiance: &wgpu::Buffer,
        size: (u32, u32),
    ) {
        let light_count = scene.info().lights.len() as u32;
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("deep-gbuffer.direct"),
            contents: bytemuck::bytes_of(&DirectUniform { light_count, _pad: [0; 3] }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let entries =
            [(0, frame), (1, &uniform), (2, gbuffer), (3, scene.light_buffer()), (4, radiance)];
        let group = gpu::bind_group(device, "deep-gbuffer.direct", &self.pipeline, &entries);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
    }
}
