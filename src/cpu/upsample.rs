//! CPU reference of `wgsl/upsample.wgsl`: the depth- and normal-aware upsample of an effect
//! computed at a level of the rotated grid.

use std::ops::{Add, Div, Mul, Sub};

use crate::cpu::blur::bilateral_weight;
use crate::cpu::mean::Mean;
use crate::cpu::pyramid::{mip_origin, mip_size};
use crate::gbuffer::GSample;

/// As `candidate`: whether texel `t` of `low` (`size` texels wide) stands for a surface, and
/// then its value, its depth gap to `s` and the blur's depth and normal weight against `s`.
fn candidate<T: Copy>(
    (width, height, level): (u32, u32, usize),
    t: (u32, u32),
    size: (u32, u32),
    s: &GSample,
    samples: &[GSample],
    low: &[T],
) -> Option<(T, f32, f32)> {
    let o = mip_origin(width, height, level, t);
    let so = &samples[(o.1 * width + o.0) as usize];
    if so.depth.is_nan() || so.depth <= 0.0 {
        return None;
    }
    let gap = (so.depth - s.depth).abs();
    let weight = bilateral_weight(so.depth, so.normal, s.depth, s.normal);
    Some((low[(t.1 * size.0 + t.0) as usize], gap, weight))
}

/// Every pixel of a `width` x `height` image from `low`, the effect computed at `level` (texel t
/// at the pixel `mip_origin(level, t)`), guided by the layer-0 `samples`; pixels without a
/// surface, or whose 4x4 texels have none, take `empty`. The weighted means are `Mean`s, as the
/// kernel's are.
pub fn upsample<T>(
    width: u32,
    height: u32,
    level: usize,
    empty: T,
    samples: &[GSample],
    low: &[T],
) -> Vec<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<f32, Output = T> + Div<f32, Output = T>,
{
    let size = mip_size(width, height, level);
    let scale = (1u32 << level) as f32;
    let last = ((size.0 - 1) as f32, (size.1 - 1) as f32);
    let texel = |x: f32, y: f32| (x.clamp(0.0, last.0) as u32, y.clamp(0.0, last.1) as u32);
    let image = (width, height, level);
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let s = &samples[(y * width + x) as usize];
            if s.depth.is_nan() || s.depth <= 0.0 {
                out.push(empty);
                continue;
            }
            let at = ((x as f32 + 0.5) / scale - 0.5, (y as f32 + 0.5) / scale - 0.5);
            let base = (at.0.floor(), at.1.floor());
            let f = (at.0 - base.0, at.1 - base.1);
            let mut mean = Mean::new(empty * 0.0);
            for j in 0..4u32 {
                let corner = ((j & 1) as f32, (j >> 1) as f32);
                let t = texel(base.0 + corner.0, base.1 + corner.1);
                if let Some((value, _, weight)) = candidate(image, t, size, s, samples, low) {
                    let bx = if corner.0 > 0.5 { f.0 } else { 1.0 - f.0 };
                    let by = if corner.1 > 0.5 { f.1 } else { 1.0 - f.1 };
                    mean.add(value, bx * by * weight);
                }
            }
            if let Some(v) = mean.value() {
                out.push(v);
                continue;
            }
            let (mut nearest, mut nearest_gap) = (empty, 3.0e38f32);
            for j in 0..16u32 {
                let t = texel(base.0 + (j & 3) as f32 - 1.0, base.1 + (j >> 2) as f32 - 1.0);
                if let Some((value, gap, weight)) = candidate(image, t, size, s, samples, low) {
                    mean.add(value, weight);
                    if gap < nearest_gap {
                        nearest_gap = gap;
                        nearest = value;
                    }
                }
            }
            out.push(mean.value().unwrap_or(nearest));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A `w` x `h` layer 0: a near plane (depth 1) left of column `edge`, a far one (depth 3) from
    /// it on, both facing the camera, and no surface in row `hole` (if any).
    fn two_planes(w: u32, h: u32, edge: u32, hole: Option<u32>) -> Vec<GSample> {
        let mut samples = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let depth = if Some(y) == hole {
                    0.0
                } else if x < edge {
                    1.0
                } else {
                    3.0
                };
                samples.push(GSample { depth, normal: Vec3::Z, ..Default::default() });
            }
        }
        samples
    }

    /// The value each texel of `level` holds: the depth of the pixel it stands for.
    fn low_of(w: u32, h: u32, level: usize, samples: &[GSample]) -> Vec<f32> {
        let size = mip_size(w, h, level);
        let mut low = Vec::new();
        for ty in 0..size.1 {
            for tx in 0..size.0 {
                let (x, y) = mip_origin(w, h, level, (tx, ty));
                low.push(samples[(y * w + x) as usize].depth);
            }
        }
        low
    }

    #[test]
    fn nothing_bleeds_across_a_depth_edge_and_holes_take_the_empty_value() {
        for (w, h) in [(16, 12), (17, 9), (5, 3)] {
            for level in [1, 2] {
                for edge in [0, 3, 6, 7] {
                    for hole in [None, Some(1)] {
                        let samples = two_planes(w, h, edge, hole);
                        let low = low_of(w, h, level, &samples);
                        let up = upsample(w, h, level, -1.0, &samples, &low);
                        for (p, (v, s)) in up.iter().zip(&samples).enumerate() {
                            // A pixel without a surface takes the empty value; one with a surface
                            // takes only texels of its own plane (their value is their depth),
                            // unless none of its four texels stands for a pixel of its own plane
                            // (next to the hole, where the rotated grid picked hole pixels).
                            let y = p as u32 / w;
                            let near_hole = hole.is_some_and(|r| y.abs_diff(r) <= 1 << level);
                            let what = format!("{w}x{h} level {level} edge {edge} pixel {p}");
                            if s.depth <= 0.0 {
                                assert_eq!(*v, -1.0, "{what}");
                            } else if !near_hole {
                                assert_eq!(*v, s.depth, "{what}");
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_linear_ramp_on_one_plane_is_interpolated_within_its_range() {
        let (w, h) = (32u32, 16u32);
        let samples = two_planes(w, h, w, None);
        let size = mip_size(w, h, 1);
        // Each texel holds the x of the pixel it stands for: the upsample stays between the
        // nearest texels' values, so within 2 pixels of the pixel's own x.
        let low: Vec<f32> = (0..size.0 * size.1)
            .map(|t| mip_origin(w, h, 1, (t % size.0, t / size.0)).0 as f32)
            .collect();
        let up = upsample(w, h, 1, 0.0, &samples, &low);
        for (p, v) in up.iter().enumerate() {
            let x = (p as u32 % w) as f32;
            assert!((v - x).abs() <= 2.0, "pixel {p}: {v} against x = {x}");
        }
    }
}
