//! `wgsl/direct.wgsl`: deferred direct lighting of layer 0, with or without shadow maps.

use bytemuck::{Pod, Zeroable};

use crate::SceneBuffers;
use crate::gpu;
use crate::settings::Precision;

/// Mirrors `struct Direct` in `wgsl/direct.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct DirectUniform {
    light_count: u32,
    pcf: u32,
    _pad: [u32; 2],
}

/// The shadow inputs of the direct kernel.
pub struct ShadowInputs<'a> {
    /// `ShadowFace` per face.
    pub faces: &'a wgpu::Buffer,
    /// `(first face, face count)` per light.
    pub light_faces: &'a wgpu::Buffer,
    /// Every face's visibility words.
    pub atlas: &'a wgpu::Buffer,
    /// Percentage-closer filtering radius.
    pub pcf: u32,
}

/// The direct-light kernel, without and with shadows.
pub struct DirectPass {
    pipelines: [wgpu::ComputePipeline; 2],
}

impl DirectPass {
    /// Builds the pipelines for `precision` G-buffers.
    pub fn new(device: &wgpu::Device, precision: Precision) -> Self {
        let packed = &precision.defines()[..];
        let mut shadows = packed.to_vec();
        shadows.push("SHADOWS");
        DirectPass {
            pipelines: [
                gpu::compute_pipeline(device, "direct", "direct_main", packed),
                gpu::compute_pipeline(device, "direct", "direct_main", &shadows),
            ],
        }
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
        shadows: Option<ShadowInputs<'_>>,
        size: (u32, u32),
    ) {
        let light_count = scene.info().lights.len() as u32;
        let pcf = shadows.as_ref().map_or(0, |s| s.pcf);
        let uniform = gpu::uniform_buffer(
            device,
            "deep-gbuffer.direct",
            bytemuck::bytes_of(&DirectUniform { light_count, pcf, _pad: [0; 2] }),
        );
        let pipeline = &self.pipelines[usize::from(shadows.is_some())];
        let mut entries =
            vec![(0, frame), (1, &uniform), (2, gbuffer), (3, scene.light_buffer()), (4, radiance)];
        if let Some(s) = &shadows {
            entries.extend([(5, s.faces), (6, s.light_faces), (7, s.atlas)]);
        }
        gpu::dispatch_pixels(device, pass, "deep-gbuffer.direct", pipeline, &entries, size);
    }
}
