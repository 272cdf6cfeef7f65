//! CPU reference of `wgsl/pyramid.wgsl`: the rotated-grid and the nearest-depth MIP chains.

use crate::frame::PyramidLayout;

/// All levels of the pyramid of `depth` (`layout.levels[0]` is `depth` itself), packed at the
/// layout's offsets.
pub fn pyramid(depth: &[f32], layout: &PyramidLayout) -> Vec<f32> {
    let mut out = vec![0.0; layout.total as usize];
    out[..depth.len()].copy_from_slice(depth);
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
