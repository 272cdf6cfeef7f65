//! CPU reference of `wgsl/pyramid.wgsl`: the rotated-grid depth MIP chain.

use crate::frame::PyramidLayout;

/// All levels of the pyramid of `depth` (`layout.levels[0]` is `depth` itself), packed at the
/// layout's offsets.
pub fn pyramid(depth: &[f32], layout: &PyramidLayout) -> Vec<f32> {
    let mut out = vec![0.0; layout.total as usize];
    let base = &layout.levels[0];
    out[..depth.len()].copy_from_slice(depth);
    let _ = base;
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
