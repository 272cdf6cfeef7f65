//! CPU reference of `wgsl/blur.wgsl`: one direction of the bilateral blur.

use glam::{Vec2, Vec3};

use crate::cpu::frame::{mat_mul, pixels_per_unit, view_position};
use crate::cpu::mean::Mean;
use crate::frame::FrameUniform;
use crate::gbuffer::GSample;

const DEPTH_TOLERANCE: f32 = 0.05;

/// As `bilateral_weight` (`wgsl/shared/bilateral.wgsl`): the depth and normal weight of a sample
/// at view depth `z` with normal `n` against the centre's `zc`, `nc`.
pub fn bilateral_weight(z: f32, n: Vec3, zc: f32, nc: Vec3) -> f32 {
    let depth_weight = (1.0 - (z - zc).abs() / (DEPTH_TOLERANCE * zc)).max(0.0);
    let c = n.dot(nc).max(0.0);
    let c2 = c * c;
    let c4 = c2 * c2;
    depth_weight * c4 * c4
}

/// As `plane_weight`: the weight of view-space point `q` by its distance from the tangent plane
/// of the centre's point `c` (view-space normal `nc`), in `footprint`s.
pub fn plane_weight(q: Vec3, c: Vec3, nc: Vec3, footprint: f32) -> f32 {
    (1.0 - nc.dot(q - c).abs() / footprint).max(0.0)
}

/// Blurs `source` along x (`vertical` false) or y, guided by the G-buffer `samples`; with
/// `plane`, the frame the samples were drawn from, each tap is weighed by its distance from the
/// centre's tangent plane too (the obscurance's blur, `PLANE` in `wgsl/blur.wgsl`).
pub fn blur(
    (width, height): (u32, u32),
    radius: u32,
    vertical: bool,
    plane: Option<&FrameUniform>,
    samples: &[GSample],
    source: &[f32],
) -> Vec<f32> {
    let mut target = source.to_vec();
    let point = |f: &FrameUniform, x: i32, y: i32, d: f32| {
        view_position(f, Vec2::new(x as f32 + 0.5, y as f32 + 0.5), d)
    };
    let step = if vertical { (0, 1) } else { (1, 0) };
    let r = radius as i32;
    let sigma = (r as f32).max(1.0) * 0.5;
    for y in 0..height as i32 {
        for x in 0..width as i32 {
            let p = (y as u32 * width + x as u32) as usize;
            let center = &samples[p];
            if center.depth.is_nan() || center.depth <= 0.0 || radius == 0 {
                continue;
            }
            let tangent = plane.map(|f| {
                let nc = mat_mul(&f.view, center.normal.extend(0.0).to_array()).truncate();
                (f, point(f, x, y, center.depth), nc, 1.0 / pixels_per_unit(f, center.depth))
            });
            let mut mean = Mean::new(0.0f32);
            for k in -r..=r {
                let (tx, ty) = (x + step.0 * k, y + step.1 * k);
                if tx < 0 || ty < 0 || tx >= width as i32 || ty >= height as i32 {
                    continue;
                }
                let q = (ty as u32 * width + tx as u32) as usize;
                let s = &samples[q];
                if s.depth.is_nan() || s.depth <= 0.0 {
                    continue;
                }
                let fk = k as f32;
                let gauss = (-fk * fk / (2.0 * sigma * sigma)).exp();
                let mut w =
                    gauss * bilateral_weight(s.depth, s.normal, center.depth, center.normal);
                if let Some((f, c, nc, footprint)) = tangent {
                    w *= plane_weight(point(f, tx, ty, s.depth), c, nc, footprint);
                }
                mean.add(source[q], w);
            }
            if let Some(v) = mean.value() {
                target[p] = v;
            }
        }
    }
    target
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::CameraMatrices;
    use crate::scene::Camera;

    /// A slanted plane seen from the camera at z = 3 (its depths run from about 1.9 to 7 across
    /// the image), every row alike; in `grooves` its odd columns lie 1.5 pixels' footprints
    /// behind it.
    fn plane(f: &FrameUniform, grooves: bool) -> Vec<GSample> {
        // The plane through the origin facing (0.6, 0, 0.8); the camera looks down -z, so a view
        // point v is the world point v + (0, 0, 3).
        let n = Vec3::new(0.6, 0.0, 0.8);
        let eye = Vec3::new(0.0, 0.0, 3.0);
        let mut samples = Vec::new();
        for y in 0..f.height {
            for x in 0..f.width {
                let unit = view_position(f, Vec2::new(x as f32 + 0.5, y as f32 + 0.5), 1.0);
                let mut depth = -n.dot(eye) / n.dot(unit);
                if grooves && x % 2 == 1 {
                    depth -= 1.5 / pixels_per_unit(f, depth) / n.dot(unit);
                }
                samples.push(GSample { depth, normal: n, ..GSample::default() });
            }
        }
        samples
    }

    /// The plane weight keeps a slanted plane whole (its pixels are one surface however their
    /// depths differ) and keeps a groove's floor apart from its rim, which the depth and
    /// normal weight alone mix (their depths differ by less than its tolerance).
    #[test]
    fn the_plane_weight_blurs_a_slanted_plane_and_keeps_grooves_apart() {
        let camera = Camera::perspective(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 60.0, 0.1);
        let (w, h) = (256, 192);
        let m = CameraMatrices::new(&camera, w, h);
        let f = FrameUniform::new(&camera, m, m, w, h, 0.0, (0, 0, 0));
        let source: Vec<f32> = (0..w * h).map(|p| (p % w % 2) as f32).collect();
        let middle = (96 * w + 120) as usize..(96 * w + 136) as usize;

        let flat = plane(&f, false);
        let (first, last) = (flat[(96 * w) as usize].depth, flat[(97 * w - 1) as usize].depth);
        assert!(last / first > 3.0, "depths {first} .. {last}");
        let blurred = blur((w, h), 4, false, Some(&f), &flat, &source);
        for p in middle.clone() {
            assert!((blurred[p] - 0.5).abs() < 0.1, "plane, pixel {p}: {}", blurred[p]);
        }

        let grooved = plane(&f, true);
        let with = blur((w, h), 4, false, Some(&f), &grooved, &source);
        let without = blur((w, h), 4, false, None, &grooved, &source);
        for p in middle {
            assert_eq!(with[p], source[p], "grooves, pixel {p}");
            assert!((without[p] - source[p]).abs() > 0.2, "no plane weight, pixel {p}");
        }
    }
}
