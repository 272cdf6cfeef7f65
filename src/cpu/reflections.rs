//! CPU reference of `wgsl/reflections.wgsl`: the two-layer screen-space march.

use glam::{Vec2, Vec3, Vec4, Vec4Swizzles};

use crate::cpu::frame::{mat_mul, view_position};
use crate::environment::Environment;
use crate::frame::FrameUniform;
use crate::frame::ReflectionsUniform;
use crate::gbuffer::{GSample, VIS_EMPTY};

const STEPS: u32 = 48;
const EDGE_FADE: f32 = 0.1;

fn project(f: &FrameUniform, q: Vec3) -> Option<(Vec2, f32)> {
    let c = mat_mul(&f.proj, q.extend(1.0).to_array());
    if c.w.is_nan() || c.w <= 0.0 {
        return None;
    }
    let px = Vec2::new(
        (c.x / c.w * 0.5 + 0.5) * f.width as f32,
        (0.5 - c.y / c.w * 0.5) * f.height as f32,
    );
    if !(px.x >= 0.0 && px.y >= 0.0 && px.x < f.width as f32 && px.y < f.height as f32) {
        return None;
    }
    Some((px, -q.z))
}

/// As `surface_depth`: pixel q's layer-0 plane depth along the view ray through `xy`.
fn surface_depth(f: &FrameUniform, layer0: &[GSample], q: usize, xy: Vec2) -> f32 {
    let s = &layer0[q];
    if s.depth.is_nan() || s.depth <= 0.0 {
        return 0.0;
    }
    let centre = Vec2::new((q as u32 % f.width) as f32, (q as u32 / f.width) as f32) + 0.5;
    let c = view_position(f, centre, s.depth);
    let n = mat_mul(&f.view, s.normal.extend(0.0).to_array()).xyz();
    let a = view_position(f, xy, 0.0);
    let b = view_position(f, xy, 1.0) - a;
    let facing = n.dot(b);
    if facing.abs() < 1e-4 * n.length() * b.length() {
        return s.depth;
    }
    n.dot(c - a) / facing
}

/// Reflected radiance (rgb, scaled by reflectivity) and confidence (w) of every pixel.
/// `environment` is the map the uniform's `env_width` refers to (`None`: the constant sky).
pub fn reflections(
    f: &FrameUniform,
    u: &ReflectionsUniform,
    layer0: &[GSample],
    vis1: &[u64],
    radiance: [&[Vec3]; 2],
    environment: Option<&Environment>,
) -> Vec<Vec4> {
    let mut out = vec![Vec4::ZERO; (f.width * f.height) as usize];
    for y in 0..f.height {
        for x in 0..f.width {
            let pi = (y * f.width + x) as usize;
            let s = &layer0[pi];
            if s.depth.is_nan()
                || s.depth <= 0.0
                || s.reflectivity.is_nan()
                || s.reflectivity <= 0.0
            {
                continue;
            }
            let p = view_position(f, Vec2::new(x as f32, y as f32) + 0.5, s.depth);
            let n = mat_mul(&f.view, s.normal.extend(0.0).to_array()).xyz().normalize();
            let v = if f.ortho != 0 { Vec3::NEG_Z } else { p.normalize() };
            let r = v - 2.0 * n.dot(v) * n;
            let step = u.max_distance / STEPS as f32;
            let sky = match environment {
                Some(env) if u.env_width != 0 => {
                    env.sample(mat_mul(&f.inv_view, r.extend(0.0).to_array()).xyz().normalize())
                }
                _ => Vec3::from(u.sky),
            };
            let (mut colour, mut confidence) = (sky, 0.0);
            for i in 1..=STEPS {
                let Some((px, z)) = project(f, p + r * (step * i as f32)) else { break };
                let q = (px.y as u32 * f.width + px.x as u32) as usize;
                let d0 = surface_depth(f, layer0, q, px);
                let layer = if d0 > 0.0 && z >= d0 && z - d0 <= u.thickness {
                    Some(0)
                } else {
                    let w1 = vis1[q];
                    let d1 = f32::from_bits((w1 >> 32) as u32);
                    (w1 != VIS_EMPTY && z >= d1 && z - d1 <= u.thickness).then_some(1)
                };
                if let Some(layer) = layer {
                    let seen = if layer == 0 {
                        let emission =
                            if u.with_emission == 0 { layer0[q].emissive } else { Vec3::ZERO };
                        radiance[0][q] + emission
                    } else {
                        radiance[1][q]
                    };
                    let uv = px / Vec2::new(f.width as f32, f.height as f32);
                    let edge = uv.x.min(1.0 - uv.x).min(uv.y.min(1.0 - uv.y));
                    confidence = (edge / EDGE_FADE).clamp(0.0, 1.0);
                    colour = sky.lerp(seen, confidence);
                    break;
                }
            }
            out[pi] = (s.reflectivity * colour).extend(confidence);
        }
    }
    out
}
