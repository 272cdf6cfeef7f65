//! `wgsl/ao.wgsl`: two-layer ambient obscurance.

use bytemuck::{Pod, Zeroable};

use crate::gpu;
use crate::passes::pyramid::PyramidLayout;
use crate::settings::{AoSettings, Precision};

/// Mirrors `struct Ao` in `wgsl/ao.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct AoUniform {
    /// World-space radius.
    pub radius: f32,
    /// Bias β.
    pub bias: f32,
    /// Intensity.
    pub intensity: f32,
    /// Taps per pixel.
    pub samples: u32,
    /// Pyramid levels.
    pub levels: u32,
    /// [`AoSettings::mip_offset`].
    pub mip_offset: u32,
    /// Padding.
    pub _pad: [u32; 2],
    /// Level offsets in the packed pyramid (up to 8).
    pub offsets: [[u32; 4]; 2],
}

const _: () = assert!(std::mem::size_of::<AoUniform>() == 64);

impl AoUniform {
    /// The constants for `settings` over a pyramid of `layout`.
    pub fn new(settings: &AoSettings, layout: &PyramidLayout) -> Self {
        let mut offsets = [[0; 4]; 2];
        for (i, l) in layout.levels.iter().enumerate().take(8) {
            offsets[i / 4][i % 4] = l.offset;
        }
        AoUniform {
            radius: settings.radius,
            bias: settings.bias,
            intensity: settings.intensity,
            samples: settings.samples,
            levels: layout.levels.len().min(8) as u32,
            mip_offset: settings.mip_offset,
            _pad: [0; 2],
            offsets,
        }
    }
}

/// The obscurance kernel for one precision and layer count.
pub struct AoPass {
    pipeline: wgpu::ComputePipeline,
    two_layers: bool,
}

impl AoPass {
    /// Builds the pipeline; `two_layers` reads both pyramids.
    pub fn new(device: &wgpu::Device, precision: Precision, two_layers: bool) -> Self {
        let mut defines = precision.defines();
        if two_layers {
            defines.push("TWO_LAYERS");
        }
        AoPass { pipeline: gpu::compute_pipeline(device, "ao", "ao_main", &defines), two_layers }
    }

    /// Records the obscurance of a `width` x `height` frame into `av`.
    #[expect(clippy::too_many_arguments, reason = "the kernel's bindings, named")]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        frame: &wgpu::Buffer,
        uniform: &wgpu::Buffer,
        gbuffer0: &wgpu::Buffer,
        pyramids: [&wgpu::Buffer; 2],
        av: &wgpu::Buffer,
        size: (u32, u32),
    ) {
        let mut entries = vec![(0, frame), (1, uniform), (2, gbuffer0), (3, pyramids[0]), (5, av)];
        if self.two_layers {
            entries.push((4, pyramids[1]));
        }
        gpu::dispatch_pixels(device, pass, "deep-gbuffer.ao", &self.pipeline, &entries, size);
    }
}
