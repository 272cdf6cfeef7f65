//! `wgsl/pyramid.wgsl`: the depth pyramid of each G-buffer layer.

use super::FrameContext;
use crate::frame::{LevelUniform, PyramidLayout};
use crate::gpu::{self, slots::pyramid as slot};

/// Which chain a pyramid holds (`wgsl/pyramid.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PyramidKind {
    /// One depth of each 2x2 block in a rotated grid (the obscurance's taps).
    RotatedGrid,
    /// The nearest depth of each 2x2 block (the reflections' hierarchical march).
    Nearest,
}

/// The per-level constants of one image size's pyramid.
pub(crate) struct Pyramid {
    layout: PyramidLayout,
    levels: Vec<wgpu::Buffer>,
}

impl Pyramid {
    /// The constants of a `width` x `height` pyramid.
    pub(crate) fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let layout = PyramidLayout::new(width, height);
        let levels = (0..layout.levels.len())
            .map(|i| {
                let u = LevelUniform::new(&layout, i);
                gpu::uniform_buffer(device, "deep-gbuffer.pyramid.level", bytemuck::bytes_of(&u))
            })
            .collect();
        Pyramid { layout, levels }
    }

    /// The level layout.
    pub(crate) fn layout(&self) -> &PyramidLayout {
        &self.layout
    }

    /// The constants (`PyramidLevel`) that build level `i`.
    pub(crate) fn level(&self, i: usize) -> &wgpu::Buffer {
        &self.levels[i]
    }

    /// Records the `kind` pyramid of `gbuffer` into `target`.
    pub(crate) fn record(
        &self,
        ctx: &FrameContext<'_>,
        pass: &mut wgpu::ComputePass<'_>,
        kind: PyramidKind,
        gbuffer: &wgpu::Buffer,
        target: &wgpu::Buffer,
    ) {
        let defines = ctx.settings.precision.defines();
        let above = match kind {
            PyramidKind::RotatedGrid => "pyramid_level",
            PyramidKind::Nearest => "pyramid_nearest",
        };
        for (i, level) in self.layout.levels.iter().enumerate() {
            let entry = if i == 0 { "pyramid_base" } else { above };
            let pipeline = ctx.pipelines.get(ctx.device, "pyramid", entry, &defines, &[]);
            let entries =
                [(slot::LEVEL, self.level(i)), (slot::GBUFFER, gbuffer), (slot::PYRAMID, target)];
            pipeline.dispatch_pixels(ctx.device, pass, &entries, (level.width, level.height));
        }
    }
}
