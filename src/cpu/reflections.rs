//! CPU reference of `wgsl/reflections.wgsl`: the two-layer hierarchical screen-space march.

use glam::{UVec2, Vec2, Vec3, Vec4, Vec4Swizzles};

use crate::cpu::composite::shaded;
use crate::cpu::direct::lit;
use crate::cpu::frame::{clip_to_pixel, image_size, mat_mul, screen_exit, view_position};
use crate::cpu::pyramid::nearest;
use crate::cpu::shadow::Shadows;
use crate::environment::Environment;
use crate::frame::{FrameUniform, PyramidLayout, ReflectionsUniform};
use crate::gbuffer::GSample;
use crate::scene::GpuLight;

/// Most cells one ray visits.
const ITERATIONS: u32 = 64;
const EDGE_FADE: f32 = 0.1;
/// An unbounded ray is followed this many times the depth of its origin.
const UNBOUNDED: f32 = 1000.0;
/// The ray stops this much in front of the near plane (relative).
const NEAR_MARGIN: f32 = 1.001;

/// The screen position (pixels) of view-space point q in front of the camera.
fn project(f: &FrameUniform, q: Vec3) -> Vec2 {
    let c = mat_mul(&f.proj, q.extend(1.0).to_array());
    clip_to_pixel(c, image_size(f))
}

/// 1/z of view depth z (z for an orthographic camera): linear along a screen-space segment.
fn linear_of(f: &FrameUniform, z: f32) -> f32 {
    if f.ortho != 0 { z } else { 1.0 / z }
}

fn depth_of(f: &FrameUniform, k: f32) -> f32 {
    if f.ortho != 0 { k } else { 1.0 / k }
}

/// As `plane_depth`: the depth of the plane of pixel q's sample s (view-space normal n) along
/// the view ray through `xy`.
fn plane_depth(f: &FrameUniform, s: &GSample, n: Vec3, q: usize, xy: Vec2) -> f32 {
    let centre = Vec2::new((q as u32 % f.width) as f32, (q as u32 / f.width) as f32) + 0.5;
    let c = view_position(f, centre, s.depth);
    let a = view_position(f, xy, 0.0);
    let b = view_position(f, xy, 1.0) - a;
    let facing = n.dot(b);
    if facing.abs() < 1e-4 * n.length() * b.length() {
        return s.depth;
    }
    n.dot(c - a) / facing
}

fn view_normal(f: &FrameUniform, s: &GSample) -> Vec3 {
    mat_mul(&f.view, s.normal.extend(0.0).to_array()).xyz()
}

/// Where a ray from `a` along `d` leaves cell `cell` of `size` pixels.
fn cell_exit(a: Vec2, d: Vec2, cell: UVec2, size: f32) -> f32 {
    let side = |c: u32, d: f32| (c as f32 + if d > 0.0 { 1.0 } else { 0.0 }) * size;
    let tx = if d.x != 0.0 { (side(cell.x, d.x) - a.x) / d.x } else { 3.4e38 };
    let ty = if d.y != 0.0 { (side(cell.y, d.y) - a.y) / d.y } else { 3.4e38 };
    tx.min(ty)
}

/// The march's inputs that stay the same for every pixel.
struct March<'a> {
    f: &'a FrameUniform,
    u: &'a ReflectionsUniform,
    layer0: &'a [GSample],
    layer1: Option<&'a [GSample]>,
    nearest: Vec<f32>,
    layout: PyramidLayout,
}

impl March<'_> {
    /// As `layer_hit`: the layer pixel q shows where the ray r's segment across it meets it
    /// from the front.
    #[allow(clippy::too_many_arguments)]
    fn layer_hit(
        &self,
        q: usize,
        r: Vec3,
        xy_in: Vec2,
        z_in: f32,
        xy_out: Vec2,
        z_out: f32,
    ) -> Option<u32> {
        let (f, thickness) = (self.f, self.u.thickness);
        let s = &self.layer0[q];
        if s.depth > 0.0 {
            let n = view_normal(f, s);
            let g_in = z_in - plane_depth(f, s, n, q, xy_in);
            let g_out = z_out - plane_depth(f, s, n, q, xy_out);
            if g_in.max(g_out) >= 0.0 && g_in.min(g_out) <= thickness && n.dot(r) < 0.0 {
                return Some(0);
            }
        }
        let s1 = &self.layer1?[q];
        let n1 = view_normal(f, s1);
        (s1.depth > 0.0
            && z_in.max(z_out) >= s1.depth
            && z_in.min(z_out) - s1.depth <= thickness
            && n1.dot(r) < 0.0)
            .then_some(1)
    }

    /// As `trace`: the pixel where pixel (x, y)'s mirrored ray hits, its layer and the
    /// screen position it entered; `None` for the environment.
    fn trace(&self, pixel: UVec2, s: &GSample, r: Vec3) -> Option<(usize, u32, Vec2)> {
        let f = self.f;
        let a = pixel.as_vec2() + 0.5;
        let p = view_position(f, a, s.depth);
        let mut reach_3d = self.u.max_distance.min(UNBOUNDED * s.depth);
        if r.z > 0.0 {
            reach_3d = reach_3d.min((-f.near * NEAR_MARGIN - p.z) / r.z);
        }
        if reach_3d.is_nan() || reach_3d <= 0.0 {
            return None;
        }
        let e = p + r * reach_3d;
        let d = project(f, e) - a;
        let (k0, k1) = (linear_of(f, s.depth), linear_of(f, -e.z));
        // Where the segment leaves the screen, if before its end.
        let t_end = 1f32.min(screen_exit(f, a, d));
        let reach = d.x.abs().max(d.y.abs());
        if reach.is_nan() || reach <= 0.5 {
            return None;
        }
        let nudge = 1e-3 / reach;
        let top = self.u.levels - 1;
        let inside = Vec2::new(f.width as f32, f.height as f32) - 1e-3;
        let mut level = 0u32;
        let mut t = cell_exit(a, d, pixel, 1.0) + nudge;
        let mut i = 0;
        while i < ITERATIONS && t < t_end {
            i += 1;
            let xy = (a + d * t).clamp(Vec2::ZERO, inside);
            let size = (1u32 << level) as f32;
            let cell = (xy / size).as_uvec2();
            let t_out = cell_exit(a, d, cell, size).min(t_end);
            let z_in = depth_of(f, k0 + (k1 - k0) * t);
            let z_out = depth_of(f, k0 + (k1 - k0) * t_out);
            if level > 0 {
                let l = self.layout.levels[level as usize];
                let front = self.nearest[(l.offset + cell.y * l.width + cell.x) as usize];
                if front > 0.0 && z_in.max(z_out) >= front {
                    level -= 1;
                } else {
                    t = t_out + nudge;
                    level = (level + 1).min(top);
                }
                continue;
            }
            let q = (cell.y * f.width + cell.x) as usize;
            if let Some(layer) = self.layer_hit(q, r, xy, z_in, a + d * t_out, z_out) {
                return Some((q, layer, xy));
            }
            t = t_out + nudge;
            level = 1.min(top);
        }
        None
    }
}

/// The frame's terms a hit surface is shaded with (`seen_at`).
pub struct HitShading<'a> {
    /// The lights, which re-light a hit surface towards the point its ray left.
    pub lights: &'a [GpuLight],
    /// Their shadow maps, when the frame draws them.
    pub shadows: Option<&'a Shadows<'a>>,
    /// The ambient visibility, when obscurance runs.
    pub av: Option<&'a [f32]>,
    /// The gathered irradiance and coverage, when radiosity runs.
    pub irradiance: Option<&'a [Vec4]>,
}

impl HitShading<'_> {
    /// As `seen_at`: what a ray along view-space direction `d` that hits `layer` at pixel q
    /// sees, its direct light re-evaluated towards the ray's origin (`relit`).
    fn seen(
        &self,
        f: &FrameUniform,
        layers: [&[GSample]; 2],
        (q, layer): (usize, u32),
        d: Vec3,
        ambient: Vec3,
    ) -> Vec3 {
        let visibility = self.av.map_or(1.0, |a| a[q]);
        let s = &layers[layer as usize][q];
        let centre = Vec2::new((q as u32 % f.width) as f32, (q as u32 / f.width) as f32) + 0.5;
        let world = mat_mul(&f.inv_view, view_position(f, centre, s.depth).extend(1.0).to_array());
        let v = -mat_mul(&f.inv_view, d.extend(0.0).to_array()).xyz().normalize();
        let direct = lit(s, world.xyz(), v, self.lights, self.shadows).0;
        let e = if layer == 1 { Vec4::ZERO } else { self.irradiance.map_or(Vec4::ZERO, |e| e[q]) };
        shaded(s, direct, visibility, e, ambient)
    }
}

/// A unit vector's orthonormal tangents (Duff et al. 2017), as `tangents`.
fn tangents(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The direction that a GGX microfacet of roughness `alpha` (the square of the material's
/// roughness) reflects `wo` (unit, towards the viewer) into about the unit normal `n`, for the
/// visible normal that `u` in [0, 1)^2 picks (Heitz 2018, "Sampling the GGX distribution of
/// visible normals"); a direction below the surface is mirrored above it. With `u` uniform this
/// samples the glossy lobe the reflections average over (the ground truth does); `alpha` 0 gives
/// the mirror direction. As `lobe_direction` in `wgsl/reflections.wgsl`.
pub fn lobe_direction(n: Vec3, wo: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let (t, b) = tangents(n);
    let ve = Vec3::new(wo.dot(t), wo.dot(b), wo.dot(n).max(1e-4)).normalize();
    let vh = Vec3::new(alpha * ve.x, alpha * ve.y, ve.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt() } else { Vec3::X };
    let t2 = vh.cross(t1);
    let radius = u.x.sqrt();
    let phi = std::f32::consts::TAU * u.y;
    let p1 = radius * phi.cos();
    let blend = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - blend) * (1.0 - p1 * p1).max(0.0).sqrt() + blend * radius * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    let m = Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize();
    let mut l = 2.0 * ve.dot(m) * m - ve;
    l.z = l.z.abs();
    (l.x * t + l.y * b + l.z * n).normalize()
}

/// The fractional golden ratio: the lobe samples' second coordinates.
const GOLDEN: f32 = 0.618034;

/// Reflected radiance (rgb, scaled by reflectivity) and confidence (w) of every pixel, marching
/// layer 0 and, when the uniform's `two_layers` is set, layer 1, and shading what the rays hit
/// with `shading`; rough surfaces average their glossy lobe (`lobe_samples` directions).
/// `environment` is the map the uniform's `env_width` refers to (`None`: the constant ambient).
pub fn reflections(
    f: &FrameUniform,
    u: &ReflectionsUniform,
    layers: [&[GSample]; 2],
    shading: &HitShading<'_>,
    environment: Option<&Environment>,
) -> Vec<Vec4> {
    let [layer0, layer1] = layers;
    let layout = PyramidLayout::new(f.width, f.height);
    let depth: Vec<f32> =
        layer0.iter().map(|s| if s.depth > 0.0 { s.depth } else { 0.0 }).collect();
    let layer1 = (u.two_layers != 0).then_some(layer1);
    let march = March { f, u, layer0, layer1, nearest: nearest(&depth, &layout), layout };
    let ambient = Vec3::from(u.ambient);
    let (w, h) = (f.width as f32, f.height as f32);
    let sky = |d: Vec3| match environment {
        Some(env) if u.env_width != 0 => {
            env.sample(mat_mul(&f.inv_view, d.extend(0.0).to_array()).xyz().normalize())
        }
        _ => ambient,
    };
    let edge_confidence = |xy: Vec2| {
        let uv = xy / Vec2::new(w, h);
        (uv.x.min(1.0 - uv.x).min(uv.y.min(1.0 - uv.y)) / EDGE_FADE).clamp(0.0, 1.0)
    };
    let layer_depth = |q: usize, layer: u32| {
        let s = &layers[layer as usize][q];
        if s.depth > 0.0 { s.depth } else { 0.0 }
    };
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
            let hit = march.trace(UVec2::new(x, y), s, r);
            let (mut mirror, mut mirror_trust) = (sky(r), 0.0);
            if let Some((q, layer, xy)) = hit {
                mirror_trust = edge_confidence(xy);
                mirror = mirror.lerp(shading.seen(f, layers, (q, layer), r, ambient), mirror_trust);
            }
            let alpha = s.roughness * s.roughness;
            if alpha.is_nan() || alpha <= 0.0 || u.lobe_samples <= 1 {
                out[pi] = (s.reflectivity * mirror).extend(mirror_trust);
                continue;
            }
            // As the kernel: lobe directions travel as far as the mirror ray did.
            let reach = hit.map(|(q, layer, _)| {
                let centre = Vec2::new((q as u32 % f.width) as f32, (q as u32 / f.width) as f32);
                (view_position(f, centre + 0.5, layer_depth(q, layer)) - p).length()
            });
            let share = (2.0 * s.roughness).min(1.0);
            let k = ((u.lobe_samples as f32 * share).ceil() as u32).clamp(2, u.lobe_samples);
            let (mut sum, mut trust) = (Vec3::ZERO, 0.0);
            for i in 0..k {
                let uv = Vec2::new((i as f32 + 0.5) / k as f32, (i as f32 * GOLDEN).fract());
                let l = lobe_direction(n, -v, alpha, uv);
                let Some(reach) = reach else {
                    sum += sky(l);
                    continue;
                };
                let (mut colour, mut confidence) = (mirror, mirror_trust);
                let e = p + l * reach;
                let tolerance = u.thickness + 0.25 * reach;
                if e.z < -f.near * NEAR_MARGIN {
                    let xy = project(f, e);
                    if xy.x >= 0.0 && xy.y >= 0.0 && xy.x < w && xy.y < h {
                        let q = (xy.y as u32 * f.width + xy.x as u32) as usize;
                        let d0 = layer_depth(q, 0);
                        let layer = if d0 > 0.0 && (d0 + e.z).abs() <= tolerance {
                            Some(0)
                        } else if u.two_layers != 0 {
                            let d1 = layer_depth(q, 1);
                            (d1 > 0.0 && (d1 + e.z).abs() <= tolerance).then_some(1)
                        } else {
                            None
                        };
                        if let Some(layer) = layer {
                            confidence = edge_confidence(xy);
                            let seen = shading.seen(f, layers, (q, layer), l, ambient);
                            colour = sky(l).lerp(seen, confidence);
                        }
                    }
                }
                sum += colour;
                trust += confidence;
            }
            out[pi] = (s.reflectivity * sum / k as f32).extend(trust / k as f32);
        }
    }
    out
}
