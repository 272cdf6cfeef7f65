//! CPU reference of `wgsl/pyramid.wgsl`: the rotated-grid and the nearest-depth MIP chains.

use glam::Vec2;

use crate::frame::PyramidLayout;
pub use crate::frame::mip_size;

/// All levels of the pyramid of `depth` (`layout.levels[0]` is `depth` itself), packed at the
/// layout's offsets.
pub fn pyramid(depth: &[f32], layout: &PyramidLayout) -> Vec<f32> {
    rotated_grid(depth, layout)
}

/// The rotated-grid MIP chain of `base` (`wgsl/shared/level.wgsl`; `layout.levels[0]` is
/// `base` itself), packed at the layout's offsets: each texel one texel of the level below.
pub fn rotated_grid<T: Copy + Default>(base: &[T], layout: &PyramidLayout) -> Vec<T> {
    let mut out = vec![T::default(); layout.total as usize];
    out[..base.len()].copy_from_slice(base);
    for pair in layout.levels.windows(2) {
        let (src, dst) = (&pair[0], &pair[1]);
        for y in 0..dst.height {
            for x in 0..dst.width {
                let sx = (2 * x + ((y & 1) ^ 1)).min(src.width - 1);
                let sy = (2 * y + ((x & 1) ^ 1)).min(src.height - 1);
                out[(dst.offset + y * dst.width + x) as usize] =
                    out[(src.offset + sy * src.width + sx) as usize];
            }
        }
    }
    out
}

/// As `mip_origin`: the level-0 pixel texel `t` of `level` of a `width` x `height` image's chain
/// was taken from.
pub fn mip_origin(width: u32, height: u32, level: usize, t: (u32, u32)) -> (u32, u32) {
    let mut p = t;
    for l in (1..=level).rev() {
        let below = mip_size(width, height, l - 1);
        p = (
            (2 * p.0 + ((p.1 & 1) ^ 1)).min(below.0 - 1),
            (2 * p.1 + ((p.0 & 1) ^ 1)).min(below.1 - 1),
        );
    }
    p
}

/// As `mip_texel`: the index of the texel of `level` under pixel `(tx, ty)` and the centre of
/// the pixel it came from.
pub fn mip_texel(layout: &PyramidLayout, (tx, ty): (u32, u32), level: usize) -> (usize, Vec2) {
    let l = layout.levels[level];
    let texel = (tx >> level, ty >> level);
    let origin = mip_origin(layout.levels[0].width, layout.levels[0].height, level, texel);
    let q = (l.offset + texel.1 * l.width + texel.0) as usize;
    (q, Vec2::new(origin.0 as f32, origin.1 as f32) + 0.5)
}

/// As `floor_log2`: floor(log2 x) for x >= 1 (0 below), from the exponent bits.
fn floor_log2(x: f32) -> i32 {
    ((x.max(1.0).to_bits() >> 23) & 0xff) as i32 - 127
}

/// As `mip_level`: the level a tap `h` pixels away reads, within [0, coarsest].
pub fn mip_level(h: f32, mip_offset: u32, coarsest: usize) -> usize {
    (floor_log2(h) - mip_offset as i32).clamp(0, coarsest as i32) as usize
}

/// As `mip_coarsest`: the coarsest level a march of steps `spacing` pixels apart reads.
pub fn mip_coarsest(spacing: f32, layout: &PyramidLayout) -> usize {
    let levels = layout.levels.len().min(8) as i32;
    floor_log2(spacing).clamp(0, levels - 1) as usize
}

/// The nearer of two depths, 0 (no surface) counting as infinitely far.
fn nearer(a: f32, b: f32) -> f32 {
    if a > 0.0 && (b <= 0.0 || a < b) { a } else { b }
}

/// All levels of the nearest-depth pyramid of `depth` (`pyramid_nearest`): each texel the
/// nearest depth of its 2x2 block below, packed at the layout's offsets.
pub fn nearest(depth: &[f32], layout: &PyramidLayout) -> Vec<f32> {
    let mut out = vec![0.0; layout.total as usize];
    out[..depth.len()].copy_from_slice(depth);
    for pair in layout.levels.windows(2) {
        let (src, dst) = (&pair[0], &pair[1]);
        let at = |out: &[f32], x: u32, y: u32| out[(src.offset + y * src.width + x) as usize];
        for y in 0..dst.height {
            for x in 0..dst.width {
                let (x0, y0) = (2 * x, 2 * y);
                let (x1, y1) = ((x0 + 1).min(src.width - 1), (y0 + 1).min(src.height - 1));
                let top = nearer(at(&out, x0, y0), at(&out, x1, y0));
                let bottom = nearer(at(&out, x0, y1), at(&out, x1, y1));
                out[(dst.offset + y * dst.width + x) as usize] = nearer(top, bottom);
            }
        }
    }
    out
}
