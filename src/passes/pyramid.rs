//! `wgsl/pyramid.wgsl`: the depth pyramid of each G-buffer layer.

use bytemuck::{Pod, Zeroable};

use crate::gpu;
use crate::settings::Precision;

/// Most levels built (level 0 is full resolution).
pub const MAX_LEVELS: u32 = 6;

/// One level's place in the packed buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Level {
    /// First texel.
    pub offset: u32,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
}

/// Where each level lies in the packed f32 buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PyramidLayout {
    /// Level 0 (full resolution) first.
    pub levels: Vec<Level>,
    /// Texels in all levels.
    pub total: u32,
}

impl PyramidLayout {
    /// The levels of a `width` x `height` image: halving (rounding up) until 1x1 or
    /// [`MAX_LEVELS`].
    pub fn new(width: u32, height: u32) -> Self {
        let mut levels = Vec::new();
        let (mut w, mut h, mut offset) = (width, height, 0);
        loop {
            levels.push(Level { offset, width: w, height: h });
            offset += w * h;
            if levels.len() as u32 == MAX_LEVELS || (w == 1 && h == 1) {
                break;
            }
            w = w.div_ceil(2);
            h = h.div_ceil(2);
        }
        PyramidLayout { levels, total: offset }
    }
}

/// Mirrors `struct PyramidLevel` in `wgsl/pyramid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LevelUniform {
    src_offset: u32,
    src_width: u32,
    src_height: u32,
    dst_offset: u32,
    dst_width: u32,
    dst_height: u32,
    _pad: [u32; 2],
}

/// The pyramid kernels and the per-level constants of one image size.
pub struct PyramidPass {
    base: wgpu::ComputePipeline,
    level: wgpu::ComputePipeline,
    uniforms: Vec<wgpu::Buffer>,
    layout: PyramidLayout,
}

impl PyramidPass {
    /// Builds the pipelines for `precision` G-buffers of `width` x `height`.
    pub fn new(device: &wgpu::Device, precision: Precision, width: u32, height: u32) -> Self {
        let defines = &precision.defines()[..];
        let layout = PyramidLayout::new(width, height);
        let uniforms = (0..layout.levels.len())
            .map(|i| {
                let dst = layout.levels[i];
                let src = layout.levels[i.saturating_sub(1)];
                let u = LevelUniform {
                    src_offset: src.offset,
                    src_width: src.width,
                    src_height: src.height,
                    dst_offset: dst.offset,
                    dst_width: dst.width,
                    dst_height: dst.height,
                    _pad: [0; 2],
                };
                gpu::uniform_buffer(device, "deep-gbuffer.pyramid.level", bytemuck::bytes_of(&u))
            })
            .collect();
        PyramidPass {
            base: gpu::compute_pipeline(device, "pyramid", "pyramid_base", defines),
            level: gpu::compute_pipeline(device, "pyramid", "pyramid_level", defines),
            uniforms,
            layout,
        }
    }

    /// The level layout.
    pub fn layout(&self) -> &PyramidLayout {
        &self.layout
    }

    /// Bytes of one layer's pyramid buffer.
    pub fn buffer_size(&self) -> u64 {
        u64::from(self.layout.total) * 4
    }

    /// Records the pyramid of `gbuffer` into `pyramid`.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        gbuffer: &wgpu::Buffer,
        pyramid: &wgpu::Buffer,
    ) {
        for (i, level) in self.layout.levels.iter().enumerate() {
            let pipeline = if i == 0 { &self.base } else { &self.level };
            let entries: Vec<(u32, &wgpu::Buffer)> = if i == 0 {
                vec![(0, &self.uniforms[i]), (1, gbuffer), (2, pyramid)]
            } else {
                vec![(0, &self.uniforms[i]), (2, pyramid)]
            };
            gpu::dispatch_pixels(
                device,
                pass,
                "deep-gbuffer.pyramid",
                pipeline,
                &entries,
                (level.width, level.height),
            );
        }
    }
}
