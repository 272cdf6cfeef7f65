//! CPU reference of `wgsl/reflections.wgsl`: the two-layer hierarchical screen-space march, and
//! the rays it cannot place followed through the lights' shadow maps.

use glam::{UVec2, Vec2, Vec3, Vec4, Vec4Swizzles};

use crate::cpu::composite::shaded;
use crate::cpu::direct::lit;
use crate::cpu::frame::{
    clip_to_pixel, image_size, mat_mul, screen_exit, toward_camera, view_position,
};
use crate::cpu::pyramid::nearest;
use crate::cpu::resolve::{ray_triangle, surface_sample};
use crate::cpu::shadow::Shadows;
use crate::environment::Environment;
use crate::frame::{FrameUniform, PyramidLayout, ReflectionsUniform, ShadowFace};
use crate::gbuffer::GSample;
use crate::scene::{GpuLight, Scene};

/// Most cells one ray visits.
const ITERATIONS: u32 = 64;
const EDGE_FADE: f32 = 0.1;
/// An unbounded ray is followed this many times the depth of its origin.
const UNBOUNDED: f32 = 1000.0;
/// The ray stops this much in front of the near plane (relative).
const NEAR_MARGIN: f32 = 1.001;
/// `TO_SCENE_EDGE`: a followed ray's reach where the march found nothing.
const TO_SCENE_EDGE: f32 = 3.4e38;
/// `HIDDEN_SIDE`: the march ran into the side of a solid the camera does not see.
const HIDDEN_SIDE: u32 = 3;
/// Steps and bisections of a ray through the shadow maps, and the slack of its exact hit.
const HIDDEN_STEPS: u32 = 16;
const HIDDEN_REFINE: u32 = 6;
const HIDDEN_SLACK: f32 = 1e-4;

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

/// As `Mirror`: a reflecting sample's view-space point, unit normal, unit direction from the eye
/// (the camera's axis for an orthographic camera) and that direction mirrored.
struct Mirror {
    p: Vec3,
    n: Vec3,
    v: Vec3,
    r: Vec3,
}

impl Mirror {
    /// As `mirror_at`.
    fn at(f: &FrameUniform, pixel: UVec2, s: &GSample) -> Self {
        let p = view_position(f, pixel.as_vec2() + 0.5, s.depth);
        let n = view_normal(f, s).normalize();
        let v = if f.ortho != 0 { Vec3::NEG_Z } else { p.normalize() };
        Mirror { p, n, v, r: v - 2.0 * n.dot(v) * n }
    }
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
    /// from the front, or [`HIDDEN_SIDE`] where it meets layer 0's shell from behind.
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
            if g_in.max(g_out) >= 0.0 && g_in.min(g_out) <= thickness {
                return Some(if n.dot(r) < 0.0 { 0 } else { HIDDEN_SIDE });
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

    /// As `silhouette`: whether layer 0 at pixel q borders a pixel more than the thickness
    /// nearer or farther, or an empty one.
    fn silhouette(&self, q: usize) -> bool {
        let f = self.f;
        let (x, y) = ((q as u32 % f.width) as i32, (q as u32 / f.width) as i32);
        let depth = |s: &GSample| if s.depth > 0.0 { s.depth } else { 0.0 };
        let z = depth(&self.layer0[q]);
        [(1, 0), (-1, 0), (0, 1), (0, -1)].into_iter().any(|(dx, dy)| {
            let (tx, ty) = (x + dx, y + dy);
            if tx < 0 || ty < 0 || tx >= f.width as i32 || ty >= f.height as i32 {
                return false;
            }
            let zt = depth(&self.layer0[(ty as u32 * f.width + tx as u32) as usize]);
            zt.is_nan() || zt <= 0.0 || (zt - z).abs() > self.u.thickness
        })
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
    /// The scene, when the rays the screen cannot place are followed through `shadows`
    /// ([`ReflectionSettings::shadow_maps`](crate::ReflectionSettings::shadow_maps)).
    pub follow: Option<&'a Scene>,
}

impl HitShading<'_> {
    /// As `seen_at`: what a ray along view-space direction `d` that hits `layer` at pixel q
    /// sees, its direct light re-evaluated towards the ray's origin `t` away, widened by the
    /// lobe's spread `blur` (`relit`).
    fn seen(
        &self,
        f: &FrameUniform,
        layers: [&[GSample]; 2],
        (q, layer): (usize, u32),
        d: Vec3,
        (blur, t): (f32, f32),
        ambient: Vec3,
    ) -> Vec3 {
        let visibility = self.av.map_or(1.0, |a| a[q]);
        let mut s = layers[layer as usize][q];
        if blur > 0.0 {
            let curvature = layer_curvature(f, layers[layer as usize], q);
            s.roughness = widened_roughness(s.roughness, blur, t, curvature);
        }
        let centre = Vec2::new((q as u32 % f.width) as f32, (q as u32 / f.width) as f32) + 0.5;
        let world = mat_mul(&f.inv_view, view_position(f, centre, s.depth).extend(1.0).to_array());
        let v = -mat_mul(&f.inv_view, d.extend(0.0).to_array()).xyz().normalize();
        let direct = lit(&s, world.xyz(), v, self.lights, self.shadows).0;
        let e = if layer == 1 { Vec4::ZERO } else { self.irradiance.map_or(Vec4::ZERO, |e| e[q]) };
        shaded(&s, direct, visibility, e, ambient)
    }
}

/// As `reflectance`: what a surface reflects of the radiance arriving along its mirror
/// direction, its reflectivity tinted by its base colour as far as it is a metal (the F0 of its
/// specular BRDF). The ground truth's mirror term takes the same.
pub fn reflectance(reflectivity: f32, base_color: Vec3, metallic: f32) -> Vec3 {
    reflectivity * Vec3::ONE.lerp(base_color, metallic)
}

/// As `widened_roughness`: a GGX roughness widened by `blur` (the spread, as a GGX alpha, of the
/// directions a reflecting pixel gathers through the ray that met the surface) and by the turn
/// of a curved surface's normal over the patch those directions cover `t` away.
fn widened_roughness(roughness: f32, blur: f32, t: f32, curvature: f32) -> f32 {
    let widened = blur * (1.0 + t * curvature.min(1e6));
    let a = roughness * roughness;
    (a * a + widened * widened).sqrt().sqrt()
}

/// As `normal_change`: the change of a layer's normal across pixel q along `axis` (0: x, 1: y),
/// its length and the distance between the two neighbours' points, where both neighbours lie
/// on screen and hold a surface within a tenth of q's depth; (0, 0) elsewhere.
fn normal_change(f: &FrameUniform, layer: &[GSample], q: usize, axis: u32) -> (f32, f32) {
    let d = layer[q].depth;
    let (x, y) = ((q as u32 % f.width) as i32, (q as u32 / f.width) as i32);
    let (sx, sy) = if axis == 0 { (1, 0) } else { (0, 1) };
    let (x0, y0, x1, y1) = (x - sx, y - sy, x + sx, y + sy);
    if x0 < 0 || y0 < 0 || x1 >= f.width as i32 || y1 >= f.height as i32 {
        return (0.0, 0.0);
    }
    let s0 = &layer[(y0 as u32 * f.width + x0 as u32) as usize];
    let s1 = &layer[(y1 as u32 * f.width + x1 as u32) as usize];
    let same = |s: &GSample| s.depth > 0.0 && (s.depth - d).abs() < 0.1 * d;
    let dn = (s1.normal - s0.normal).length();
    if !(same(s0) && same(s1) && dn < 1e30) {
        return (0.0, 0.0);
    }
    let p0 = view_position(f, Vec2::new(x0 as f32, y0 as f32) + 0.5, s0.depth);
    let p1 = view_position(f, Vec2::new(x1 as f32, y1 as f32) + 0.5, s1.depth);
    (dn, (p1 - p0).length())
}

/// As `layer_curvature`: the curvature (radians of normal per unit) of a layer's surface at
/// pixel q, the larger of the two axes' normal change over its distance.
fn layer_curvature(f: &FrameUniform, layer: &[GSample], q: usize) -> f32 {
    (0..2).fold(0.0f32, |curvature, axis| {
        let (dn, len) = normal_change(f, layer, q, axis);
        let c = dn / len;
        if len > 0.0 && c < 1e30 { curvature.max(c) } else { curvature }
    })
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
    let mut followed = Vec::new();
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
            let Mirror { p, n, v, r } = Mirror::at(f, UVec2::new(x, y), s);
            let hit = march.trace(UVec2::new(x, y), s, r);
            let (mut mirror, mut mirror_trust) = (sky(r), 0.0);
            // As the kernel's `went` and `follow`.
            let went = hit.map_or(0.0, |(q, layer, _)| {
                let centre = Vec2::new((q as u32 % f.width) as f32, (q as u32 / f.width) as f32);
                (view_position(f, centre + 0.5, layer_depth(q, layer.min(1))) - p).length()
            });
            let follow = match hit {
                None => TO_SCENE_EDGE,
                Some((_, HIDDEN_SIDE, _)) => went,
                Some((q, 0, _)) if march.silhouette(q) => -went,
                Some(_) => 0.0,
            };
            if follow != 0.0 {
                followed.push((pi, follow));
            }
            let hit = hit.filter(|&(_, layer, _)| layer < 2);
            // As the kernel: k lobe directions (1: the mirror ray alone), each widening what it
            // hits by its share's spread.
            let alpha = s.roughness * s.roughness;
            let k = if alpha > 0.0 && u.lobe_samples > 1 {
                let share = (2.0 * s.roughness).min(1.0);
                ((u.lobe_samples as f32 * share).ceil() as u32).clamp(2, u.lobe_samples)
            } else {
                1
            };
            let blur = if alpha > 0.0 { alpha / (k as f32).sqrt() } else { 0.0 };
            let tint = reflectance(s.reflectivity, s.base_color, s.metallic);
            if let Some((q, layer, xy)) = hit {
                mirror_trust = edge_confidence(xy);
                let seen = shading.seen(f, layers, (q, layer), r, (blur, went), ambient);
                mirror = mirror.lerp(seen, mirror_trust);
            }
            if k == 1 {
                out[pi] = (tint * mirror).extend(mirror_trust);
                continue;
            }
            // As the kernel: lobe directions travel as far as the mirror ray did.
            let reach = hit.map(|_| went);
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
                            let seen =
                                shading.seen(f, layers, (q, layer), l, (blur, reach), ambient);
                            colour = sky(l).lerp(seen, confidence);
                        }
                    }
                }
                sum += colour;
                trust += confidence;
            }
            out[pi] = (tint * sum / k as f32).extend(trust / k as f32);
        }
    }
    if let (Some(scene), Some(shadows)) = (shading.follow, shading.shadows) {
        let hidden = Hidden { f, u, scene, lights: shading.lights, shadows };
        for (pi, follow) in followed {
            if let Some(v) = hidden.reflected(layer0, pi, follow) {
                out[pi] = v;
            }
        }
    }
    out
}

/// As `RayInMap`: a one-face light's clip positions and view depths at a ray's two ends.
struct RayInMap<'a> {
    face: &'a ShadowFace,
    c: [Vec4; 2],
    z: [f32; 2],
}

/// As `reflections_hidden`: what the lights' shadow maps hold, for the rays the march could not
/// place.
struct Hidden<'a> {
    f: &'a FrameUniform,
    u: &'a ReflectionsUniform,
    scene: &'a Scene,
    lights: &'a [GpuLight],
    shadows: &'a Shadows<'a>,
}

impl Hidden<'_> {
    /// As `map_point`: how far the surface light i's map holds at p's texel lies behind p, and
    /// its triangle.
    fn map_point(&self, i: usize, p: Vec3) -> Option<(f32, u32)> {
        let face = self.shadows.face_at(i, &self.lights[i], p)?;
        let v = mat_mul(&face.view, p.extend(1.0).to_array());
        self.map_at(face, mat_mul(&face.proj, v.to_array()), v.z)
    }

    /// As `map_at`: the same at face `face`'s clip position `c` and view z `vz`.
    fn map_at(&self, face: &ShadowFace, c: Vec4, vz: f32) -> Option<(f32, u32)> {
        if c.w.is_nan() || c.w <= 0.0 {
            return None;
        }
        let res = face.resolution as f32;
        let uv = clip_to_pixel(c, Vec2::splat(res));
        if !(uv.x >= 0.0 && uv.y >= 0.0 && uv.x < res && uv.y < res) {
            return None;
        }
        let t = uv.as_uvec2();
        let word = self.shadows.atlas[(face.offset + t.y * face.resolution + t.x) as usize];
        let depth = (word >> 32) as u32;
        (depth != u32::MAX).then(|| (f32::from_bits(depth) + vz, word as u32))
    }

    /// As `ray_in_map`: a one-face light's (sun, spot) clip positions and view depths of the
    /// ray's ends `o` and `o + d t_end` (both affine in the point); `None` for a point light.
    fn ray_in_map(&self, i: usize, (o, d): (Vec3, Vec3), t_end: f32) -> Option<RayInMap<'_>> {
        let [first, count] = self.shadows.light_faces.get(i).copied().unwrap_or([0, 0]);
        if count != 1 {
            return None;
        }
        let face = &self.shadows.faces[first as usize];
        let v0 = mat_mul(&face.view, o.extend(1.0).to_array());
        let v1 = mat_mul(&face.view, (o + d * t_end).extend(1.0).to_array());
        let (c0, c1) = (mat_mul(&face.proj, v0.to_array()), mat_mul(&face.proj, v1.to_array()));
        Some(RayInMap { face, c: [c0, c1], z: [v0.z, v1.z] })
    }

    /// As `map_along`: light i's map at `o + d t`, t in [0, t_end], interpolated along `ray`
    /// for a one-face light.
    fn map_along(
        &self,
        i: usize,
        ray: &Option<RayInMap<'_>>,
        (o, d): (Vec3, Vec3),
        (t, t_end): (f32, f32),
    ) -> Option<(f32, u32)> {
        let Some(r) = ray else { return self.map_point(i, o + d * t) };
        let s = t / t_end;
        self.map_at(r.face, r.c[0] + (r.c[1] - r.c[0]) * s, r.z[0] + (r.z[1] - r.z[0]) * s)
    }

    fn corners(&self, id: u32) -> [usize; 3] {
        self.scene.triangles[id as usize].map(|i| i as usize)
    }

    /// As `triangle_hit`: where the ray o + t d meets triangle `id` for t in (t_min, t_max].
    fn triangle_hit(
        &self,
        id: u32,
        o: Vec3,
        d: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, u32, Vec3)> {
        if id as usize >= self.scene.triangles.len() {
            return None;
        }
        let w = self.corners(id).map(|i| self.scene.positions[i]);
        let (t, bary) = ray_triangle(o, d, w, HIDDEN_SLACK)?;
        (t > t_min && t <= t_max).then_some((t, id, bary))
    }

    /// As `scene_exit`.
    fn scene_exit(&self, o: Vec3, d: Vec3) -> f32 {
        let [cx, cy, cz, r] = self.u.bounds;
        if r.is_nan() || r <= 0.0 {
            return 0.0;
        }
        let m = o - Vec3::new(cx, cy, cz);
        let b = m.dot(d);
        let c = m.dot(m) - r * r;
        (-b + (b * b - c).max(0.0).sqrt()).clamp(0.0, self.u.max_distance)
    }

    /// As `hidden_hit`: the first surface a light's shadow map holds that the ray from o along
    /// unit d meets within t_end.
    fn hidden_hit(&self, o: Vec3, d: Vec3, t_end: f32) -> Option<(f32, u32, Vec3)> {
        let mut best = None;
        if t_end.is_nan() || t_end <= 0.0 {
            return None;
        }
        let mut reach = t_end;
        let t_min = 1e-4 * self.u.bounds[3];
        for i in 0..self.lights.len() {
            if self.shadows.light_faces.get(i).is_none_or(|lf| lf[1] == 0) {
                continue;
            }
            let ray = self.ray_in_map(i, (o, d), t_end);
            let (mut t0, mut front) = (0.0f32, true);
            for k in 1..=HIDDEN_STEPS {
                let t1 = t_end * k as f32 / HIDDEN_STEPS as f32;
                if t0 >= reach {
                    break;
                }
                let m = self.map_along(i, &ray, (o, d), (t1, t_end));
                let behind = m.is_some_and(|(gap, _)| gap < 0.0);
                if behind && front {
                    let (mut lo, mut hi) = (t0, t1);
                    let id = m.map_or(0, |(_, id)| id);
                    let (mut id_hi, mut id_lo) = (id, id);
                    for _ in 0..HIDDEN_REFINE {
                        let mid = 0.5 * (lo + hi);
                        match self.map_along(i, &ray, (o, d), (mid, t_end)) {
                            Some((gap, id)) if gap < 0.0 => {
                                hi = mid;
                                id_hi = id;
                            }
                            other => {
                                lo = mid;
                                if let Some((_, id)) = other {
                                    id_lo = id;
                                }
                            }
                        }
                    }
                    let mut h = self.triangle_hit(id_hi, o, d, t_min, reach);
                    if h.is_none() && id_lo != id_hi {
                        h = self.triangle_hit(id_lo, o, d, t_min, reach);
                    }
                    if let Some(found) = h {
                        best = Some(found);
                        reach = found.0;
                        break;
                    }
                }
                front = !behind;
                t0 = t1;
            }
        }
        best
    }

    /// As `faces_camera`.
    fn faces_camera(&self, id: u32, x: Vec3, o: Vec3) -> bool {
        let f = self.f;
        let [w0, w1, w2] = self.corners(id).map(|i| self.scene.positions[i]);
        let geo = (w1 - w0).cross(w2 - w0);
        geo.dot(toward_camera(f, x)) * geo.dot(o - x) > 0.0
    }

    /// As `hidden_seen`: the hit surface lit towards o, its roughness widened by `blur`.
    fn seen(&self, (t, id, bary): (f32, u32, Vec3), d: Vec3, blur: f32) -> Vec3 {
        let scene = self.scene;
        let tri = self.corners(id);
        let w = tri.map(|i| scene.positions[i]);
        let mut s = surface_sample(scene, id, tri, bary, -d);
        let mut curvature = 0.0f32;
        for e in 0..3 {
            let (i, j) = (tri[e], tri[(e + 1) % 3]);
            let len = (w[(e + 1) % 3] - w[e]).length();
            let (ni, nj) = (scene.normals[i], scene.normals[j]);
            if len > 0.0 && ni.dot(ni) > 0.0 && nj.dot(nj) > 0.0 {
                let c = (nj.normalize() - ni.normalize()).length() / len;
                if c < 1e30 {
                    curvature = curvature.max(c);
                }
            }
        }
        s.roughness = widened_roughness(s.roughness, blur, t, curvature);
        let world = w[0] * bary.x + w[1] * bary.y + w[2] * bary.z;
        let direct = lit(&s, world, -d, self.lights, Some(self.shadows)).0;
        shaded(&s, direct, 1.0, Vec4::ZERO, Vec3::from(self.u.ambient))
    }

    /// What pixel `pi`'s ray, followed `follow` far, reflects, if it finds something.
    fn reflected(&self, layer0: &[GSample], pi: usize, follow: f32) -> Option<Vec4> {
        let f = self.f;
        let s = &layer0[pi];
        let (x, y) = (pi as u32 % f.width, pi as u32 / f.width);
        let m = Mirror::at(f, UVec2::new(x, y), s);
        let o = mat_mul(&f.inv_view, m.p.extend(1.0).to_array()).xyz();
        let r = mat_mul(&f.inv_view, m.r.extend(0.0).to_array()).xyz().normalize();
        let reach = self.scene_exit(o, r).min(1.25 * follow.abs() + self.u.thickness);
        let hit = self.hidden_hit(o, r, reach)?;
        if follow < 0.0 && self.faces_camera(hit.1, o + r * hit.0, o) {
            return None;
        }
        // The pixel's own spread of normals: a quarter of their change across it, per axis.
        let spread: f32 =
            (0..2).map(|axis| (0.25 * normal_change(f, layer0, pi, axis).0).powi(2)).sum();
        let alpha = s.roughness * s.roughness;
        let blur = (alpha * alpha + 2.0 * spread).sqrt();
        let tint = reflectance(s.reflectivity, s.base_color, s.metallic);
        Some((tint * self.seen(hit, r, blur)).extend(1.0))
    }
}
