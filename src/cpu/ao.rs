//! CPU reference of `wgsl/ao.wgsl`: two-layer ambient obscurance.

use glam::{Vec2, Vec3, Vec4Swizzles};

use crate::cpu::frame::mat_mul;
pub use crate::cpu::frame::view_position;
use crate::cpu::spiral::{pixels_per_unit, spiral_distance, spiral_tap};
use crate::frame::FrameUniform;
use crate::frame::PyramidLayout;
use crate::gbuffer::GSample;
use crate::settings::AoSettings;

/// As `texel_origin` in the WGSL: the level-0 pixel a pyramid texel was taken from.
fn texel_origin(layout: &PyramidLayout, level: usize, t: (u32, u32)) -> (u32, u32) {
    let mut p = t;
    for l in (1..=level).rev() {
        let below = layout.levels[l - 1];
        p = (
            (2 * p.0 + ((p.1 & 1) ^ 1)).min(below.width - 1),
            (2 * p.1 + ((p.0 & 1) ^ 1)).min(below.height - 1),
        );
    }
    p
}

fn obscurance(s: &AoSettings, c: Vec3, n: Vec3, y: Vec3) -> f32 {
    let v = y - c;
    let vv = v.dot(v);
    let r2 = s.radius * s.radius;
    (1.0 - vv / r2).max(0.0) * ((v.dot(n) - s.bias) / (vv + 1e-4 * r2).sqrt()).max(0.0)
}

/// AV of every pixel. `pyramid1` is `None` for one-layer obscurance.
pub fn ao(
    f: &FrameUniform,
    s: &AoSettings,
    layer0: &[GSample],
    layout: &PyramidLayout,
    pyramid0: &[f32],
    pyramid1: Option<&[f32]>,
) -> Vec<f32> {
    let mut out = vec![1.0; (f.width * f.height) as usize];
    for y in 0..f.height {
        for x in 0..f.width {
            let p = (y * f.width + x) as usize;
            let z = pyramid0[p];
            if z.is_nan() || z <= 0.0 || s.samples == 0 || s.radius.is_nan() || s.radius <= 0.0 {
                continue;
            }
            let c = view_position(f, Vec2::new(x as f32, y as f32) + 0.5, z);
            let n = mat_mul(&f.view, layer0[p].normal.extend(0.0).to_array()).xyz().normalize();
            let r_px = s.radius * pixels_per_unit(f, z);
            let mut sum = 0.0;
            for i in 0..s.samples {
                let h = spiral_distance(i, s.samples, r_px);
                let (tx, ty) = spiral_tap(x, y, i, s.samples, r_px);
                if tx < 0 || ty < 0 || tx >= f.width as i32 || ty >= f.height as i32 {
                    continue;
                }
                let level = ((h.max(1.0).log2().floor() as i32) - s.mip_offset as i32)
                    .clamp(0, layout.levels.len() as i32 - 1) as usize;
                let l = layout.levels[level];
                let q =
                    (l.offset + ((ty as u32) >> level) * l.width + ((tx as u32) >> level)) as usize;
                let origin =
                    texel_origin(layout, level, ((tx as u32) >> level, (ty as u32) >> level));
                let at = Vec2::new(origin.0 as f32, origin.1 as f32) + 0.5;
                let mut o = 0.0f32;
                if pyramid0[q] > 0.0 {
                    o = obscurance(s, c, n, view_position(f, at, pyramid0[q]));
                }
                if let Some(p1) = pyramid1
                    && p1[q] > 0.0
                {
                    o = o.max(obscurance(s, c, n, view_position(f, at, p1[q])));
                }
                sum += o;
            }
            out[p] = (1.0 - s.intensity * 2.0 / s.samples as f32 * sum).clamp(0.0, 1.0);
        }
    }
    out
}
