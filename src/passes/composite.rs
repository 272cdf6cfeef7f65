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

/// The composite kernel, with and without AV and radiosity inputs.
pub struct CompositePass {
    /// Indexed by `ao + 2 radiosity + 4 reflections`.
    pipelines: [wgpu::ComputePipeline; 8],
}

impl CompositePass {
    /// Builds the pipelines.
    pub fn new(device: &wgpu::Device, precision: Precision) -> Self {
        let pipelines = [0usize, 1, 2, 3, 4, 5, 6, 7].map(|variant| {
            let mut defines = precision.defines();
            if variant & 1 != 0 {
                defines.push("AO");
            }
            if variant & 2 != 0 {
                defines.push("RADIOSITY");
            }
            if variant & 4 != 0 {
                defines.push("REFLECTIONS");
            }
            gpu::compute_pipeline(device, "composite", "composite_main", &defines)
        });
        CompositePass { pipelines }
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
        radiosity: Option<&wgpu::Buffer>,
        reflections: Option<&wgpu::Buffer>,
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
        if let Some(av) = av {
            entries.push((4, av));
        }
        if let Some(radiosity) = radiosity {
            entries.push((6, radiosity));
        }
        if let Some(reflections) = reflections {
            entries.push((7, reflections));
        }
        let pipeline = &self.pipelines[usize::from(av.is_some())
            + 2 * usize::from(radiosity.is_some())
            + 4 * usize::from(reflections.is_some())];
        gpu::dispatch_pixels(device, pass, "deep-gbuffer.composite", pipeline, &entries, size);
    }
}
