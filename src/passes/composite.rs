//! `wgsl/composite.wgsl`: the terms summed into the HDR image.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::gpu;
use crate::settings::Precision;

/// Mirrors `struct Composite` in `wgsl/composite.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct CompositeUniform {
    ambient: [f32; 3],
    _pad: u32,
}

/// The composite kernel, with or without an AV input.
pub struct CompositePass {
    pipeline: wgpu::ComputePipeline,
    ao: bool,
}

impl CompositePass {
    /// Builds the pipeline; `ao` reads an AV buffer.
    pub fn new(device: &wgpu::Device, precision: Precision, ao: bool) -> Self {
        let mut defines = Vec::new();
        if precision == Precision::Packed {
            defines.push("PACKED");
        }
        if ao {
            defines.push("AO");
        }
        CompositePass {
            pipeline: gpu::compute_pipeline(device, "composite", "composite_main", &defines),
            ao,
        }
    }

    /// Records the composite into `hdr` (`vec4<f32>` per pixel).
    #[expect(clippy::too_many_arguments, reason = "the kernel's bindings, named")]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        frame: &wgpu::Buffer,
        ambient: glam::Vec3,
        gbuffer: &wgpu::Buffer,
        direct: &wgpu::Buffer,
        av: Option<&wgpu::Buffer>,
        hdr: &wgpu::Buffer,
        size: (u32, u32),
    ) {
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("deep-gbuffer.composite"),
            contents: bytemuck::bytes_of(&CompositeUniform {
                ambient: ambient.to_array(),
                _pad: 0,
            }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let mut entries = vec![(0, frame), (1, &uniform), (2, gbuffer), (3, direct), (5, hdr)];
        if self.ao {
            entries.push((4, av.expect("an AV buffer for the AO variant")));
        }
        let group = gpu::bind_group(device, "deep-gbuffer.composite", &self.pipeline, &entries);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
    }
}
