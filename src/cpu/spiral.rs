//! CPU mirror of `wgsl/shared/spiral.wgsl`: the tap pattern of the screen-space gathers.

use std::f32::consts::TAU;

use glam::Vec2;

use crate::cpu::frame::pixels_per_unit;
use crate::frame::FrameUniform;

pub(crate) const GOLDEN_TURNS: f32 = 0.381_966_01;

/// As `pixel_hash`.
pub fn pixel_hash(x: u32, y: u32) -> u32 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    h
}

/// As `depth_slope_span`: how far the view depth of a surface (view-space point `v`, normal `n`)
/// runs over `pixels` of the screen.
pub fn depth_slope_span(f: &FrameUniform, v: glam::Vec3, n: glam::Vec3, pixels: f32) -> f32 {
    let ray = if f.ortho == 0 { v.normalize() } else { glam::Vec3::NEG_Z };
    let cos_v = n.normalize().dot(ray).abs().clamp(0.0995, 1.0);
    let slope = (1.0 - cos_v * cos_v).sqrt() / cos_v;
    pixels * slope / pixels_per_unit(f, (-v.z).max(1e-6))
}

/// As `spiral_distance`.
pub fn spiral_distance(i: u32, n: u32, r_px: f32) -> f32 {
    r_px * (i as f32 + 0.5) / n as f32
}

/// As `spiral_tap`.
pub fn spiral_tap(x: u32, y: u32, i: u32, n: u32, r_px: f32) -> (i32, i32) {
    spiral_tap_turned(x, y, i, n, r_px, 0)
}

/// As `spiral_tap_turned`.
pub fn spiral_tap_turned(x: u32, y: u32, i: u32, n: u32, r_px: f32, turn: u32) -> (i32, i32) {
    let rotation = (((pixel_hash(x, y) >> 20) + (turn % 4096) * 1565) % 4096) as f32 / 4096.0;
    let angle = (i as f32 * GOLDEN_TURNS + rotation).fract() * TAU;
    let h = spiral_distance(i, n, r_px);
    let tap =
        (Vec2::new(x as f32, y as f32) + 0.5 + h * Vec2::new(angle.cos(), angle.sin())).floor();
    (tap.x as i32, tap.y as i32)
}
