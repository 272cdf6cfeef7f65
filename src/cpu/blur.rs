//! CPU reference of `wgsl/blur.wgsl`: one direction of the bilateral blur.

use glam::Vec3;

use crate::cpu::mean::Mean;
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

/// Blurs `source` along x (`vertical` false) or y, guided by the G-buffer `samples`.
pub fn blur(
    width: u32,
    height: u32,
    radius: u32,
    vertical: bool,
    samples: &[GSample],
    source: &[f32],
) -> Vec<f32> {
    let mut target = source.to_vec();
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
                let w = gauss * bilateral_weight(s.depth, s.normal, center.depth, center.normal);
                mean.add(source[q], w);
            }
            if let Some(v) = mean.value() {
                target[p] = v;
            }
        }
    }
    target
}
