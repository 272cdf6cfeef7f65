//! CPU reference of `wgsl/radiosity.wgsl` for a frame without history: the feedback (B = direct
//! + emission on both layers) and the gather.

use std::f32::consts::PI;

use glam::{Vec2, Vec3, Vec4, Vec4Swizzles};

use crate::cpu::frame::pixels_per_unit;
use crate::cpu::frame::{mat_mul, view_position};
use crate::cpu::pyramid::{mip_coarsest, mip_level, mip_origin, mip_size, mip_texel, rotated_grid};
use crate::cpu::slices::{SECTORS, Slice, slice_noise, solid_backs, step_distance};
use crate::cpu::spiral::{spiral_distance, spiral_tap_turned};
use crate::frame::{FrameUniform, PyramidLayout, RadiosityUniform, SourceTexel};
use crate::gbuffer::GSample;
use crate::settings::Boost;

/// boost(rho) of `wgsl/radiosity.wgsl`.
pub fn boost(u: &RadiosityUniform, rho: Vec3) -> f32 {
    Boost { unsaturated: u.boost_unsaturated, saturated: u.boost_saturated }.of(rho.to_array())
}

/// As `reflected`: the indirect light `s` reflects every way alike from irradiance `e`, damped
/// and boosted (`b`, its boost) for the next bounce, plus its emission (what its far side sends).
pub fn reflected(u: &RadiosityUniform, s: &GSample, b: f32, e: Vec3) -> Vec3 {
    b * u.damping * (1.0 - s.metallic) * s.occlusion * s.base_color / PI * e + s.emissive
}

/// As `spread`: what a gather's irradiance and coverage `g` stand for over the whole
/// hemisphere, E / c (0 where it covered nothing).
pub fn spread(g: Vec4) -> Vec3 {
    if g.w > 0.0 { g.truncate() / g.w.max(1e-6) } else { Vec3::ZERO }
}

/// B of one layer without history: the boosted Lambertian part of the direct radiance
/// (`diffuse`, [`direct_and_diffuse`](crate::cpu::direct::direct_and_diffuse)) plus emission
/// where there is a surface.
pub fn feedback_without_history(
    u: &RadiosityUniform,
    layer: &[GSample],
    diffuse: &[Vec3],
) -> Vec<Vec3> {
    layer
        .iter()
        .zip(diffuse)
        .map(|(s, d)| {
            if s.depth > 0.0 {
                let b = boost(u, s.base_color);
                b * *d + reflected(u, s, b, Vec3::ZERO)
            } else {
                Vec3::ZERO
            }
        })
        .collect()
}

/// The gather source of `radiosity_feedback` and `radiosity_source_level` for a frame without
/// history: both layers' view depths, view-space normals (of `f`'s view) and B (`b`) at every
/// pixel (H, what a surface's far side sends, is its emission and the indirect light it
/// reflects: none yet), and the rotated-grid levels of `layout` above them.
pub fn source(
    f: &FrameUniform,
    layers: [&[GSample]; 2],
    b: [&[Vec3]; 2],
    layout: &PyramidLayout,
) -> Vec<SourceTexel> {
    let base: Vec<SourceTexel> = (0..layers[0].len())
        .map(|p| {
            let [s0, s1] = [&layers[0][p], &layers[1][p]];
            let normal = |s: &GSample| {
                let n = mat_mul(&f.view, s.normal.extend(0.0).to_array()).xyz();
                if s.depth > 0.0 { n } else { Vec3::ZERO }
            };
            SourceTexel::new(
                [s0.depth, s1.depth],
                [normal(s0), normal(s1)],
                [b[0][p], b[1][p]],
                [s0, s1].map(|s| if s.depth > 0.0 { s.emissive } else { Vec3::ZERO }),
            )
        })
        .collect();
    rotated_grid(&base, layout)
}

/// The gathered irradiance (rgb) and confidence (w), by the estimator `u.estimator` names, at
/// the points of layer `receiver` (0: `radiosity`; 1: `radiosity.layer1`, with
/// `u.layer1_samples` taps) in every texel of the rotated grid's `level` (0: every pixel; above,
/// each texel at the pixel it stands for, before the upsample), from the gather `source` (levels
/// of `layout`); `layers` give the centre points and the spiral's normals.
pub fn gather(
    f: &FrameUniform,
    u: &RadiosityUniform,
    layers: [&[GSample]; 2],
    source: &[SourceTexel],
    layout: &PyramidLayout,
    (level, receiver): (usize, usize),
) -> Vec<Vec4> {
    let taps = if receiver == 1 { u.layer1_samples } else { u.samples };
    let g = Gather { f, u, layers, source, layout, receiver, taps };
    let size = mip_size(f.width, f.height, level);
    let mut out = vec![Vec4::ZERO; (size.0 * size.1) as usize];
    for ty in 0..size.1 {
        for tx in 0..size.0 {
            let (x, y) = mip_origin(f.width, f.height, level, (tx, ty));
            let p = (y * f.width + x) as usize;
            let texel = (ty * size.0 + tx) as usize;
            let s = &layers[receiver][p];
            if s.depth.is_nan() || s.depth <= 0.0 || taps == 0 {
                continue;
            }
            if u.estimator == 1 {
                out[texel] = g.slices((x, y), (tx, ty));
                continue;
            }
            let c = view_position(f, Vec2::new(x as f32, y as f32) + 0.5, s.depth);
            let n = mat_mul(&f.view, s.normal.extend(0.0).to_array()).xyz().normalize();
            let r_px = u.radius * pixels_per_unit(f, s.depth);
            let mut sum = Vec3::ZERO;
            let mut weight = 0.0f32;
            let mut m = 0u32;
            for i in 0..taps {
                let (tx, ty) = spiral_tap_turned(x, y, i, taps, r_px, u.turn);
                if tx < 0 || ty < 0 || tx >= f.width as i32 || ty >= f.height as i32 {
                    continue;
                }
                let h = spiral_distance(i, taps, r_px);
                let level = mip_level(h, u.mip_offset, u.levels as usize - 1);
                let (q, at) = mip_texel(layout, (tx as u32, ty as u32), level);
                let t = &source[q];
                let o = (at.y as u32 * f.width + at.x as u32) as usize;
                for (layer, samples) in layers.iter().enumerate() {
                    let depth = t.depth(layer);
                    if depth.is_nan() || depth <= 0.0 {
                        continue;
                    }
                    let v = view_position(f, at, depth) - c;
                    let len = v.length();
                    if len.is_nan() || len <= 1e-6 {
                        continue;
                    }
                    let w = v / len;
                    let wn_x = w.dot(n);
                    let normal = samples[o].normal;
                    let wn_y =
                        w.dot(mat_mul(&f.view, normal.extend(0.0).to_array()).xyz().normalize());
                    if wn_x > 0.0 && (u.normal_test == 0 || wn_y < 0.0) {
                        sum += t.radiance(layer) * wn_x;
                        weight += wn_x;
                        m += 1;
                        break;
                    }
                }
            }
            let e = match (m, u.normalization) {
                (0, _) => Vec3::ZERO,
                (_, 0) => PI * sum / weight,
                _ => 2.0 * PI / m as f32 * sum,
            };
            let confidence = m as f32 / taps as f32;
            out[texel] = (e * confidence).extend(confidence);
        }
    }
    out
}

/// `FACING_SLACK` of `wgsl/radiosity.wgsl`.
const FACING_SLACK: f32 = 1e-3;

/// `BEND_COS`, `GRAZING` and `BEND_REACH` of `wgsl/radiosity.wgsl` (curved surfaces).
const BEND_COS: f32 = 0.95;
const GRAZING: f32 = 0.3;
const BEND_REACH: f32 = 0.5;

/// As `Sender`: the last layer-0 point that hid sectors on a side of a slice, what it sent,
/// where it lies, its normal and the cosine at which it faces the receiver.
struct Sender {
    light: Vec3,
    y: Vec3,
    n: Vec3,
    facing: f32,
}

/// As `Grazing`: a layer-0 point that starts a surface and faces the receiver at a grazing
/// angle, whose light waits for the next step's point.
struct Grazing {
    b: Vec3,
    h: Vec3,
    facing: f32,
    count: u32,
    count_half: u32,
    y: Vec3,
    n: Vec3,
}

impl Grazing {
    /// As `grazing_light`: what it sends towards the receiver `c`, the next step finding the
    /// layer-0 point and normal `next` (`None`: no point).
    fn light(&self, c: Vec3, next: Option<(Vec3, Vec3)>) -> Vec3 {
        let Some((y2, n2)) = next else {
            return self.b;
        };
        let away = n2.dot(c - y2) / (c - y2).length().max(1e-30) < self.facing;
        let turn = (n2 - self.n).length();
        if away && turn * (c - self.y).length() > BEND_REACH * (y2 - self.y).length().max(1e-6) {
            let s = self.facing.max(0.0) / GRAZING;
            return self.h * (1.0 - s) + self.b * s;
        }
        self.b
    }
}

/// As `Gathered`: the sectors a slice's steps have hidden and the light they sent, every
/// step's or every other step's (the extrapolation's half).
#[derive(Default)]
struct Gathered {
    occupied: u32,
    sum: Vec3,
}

impl Gathered {
    /// As `first_hidden`: how many of `bits` nothing hid before.
    fn first(&self, bits: u32) -> u32 {
        (bits & !self.occupied).count_ones()
    }
}

/// As `send`: `light` into the sectors a point hid first, `first` of every step's and
/// `first_half` of every other step's.
fn send(every: &mut Gathered, half: &mut Gathered, light: Vec3, first: u32, first_half: u32) {
    every.sum += light * first as f32;
    half.sum += light * first_half as f32;
}

/// As `occupy`: `bits` hidden among every step's sectors, and every other step's on an `even`
/// step.
fn occupy(every: &mut Gathered, half: &mut Gathered, bits: u32, even: bool) {
    every.occupied |= bits;
    if even {
        half.occupied |= bits;
    }
}

/// What the gather reads.
struct Gather<'a> {
    f: &'a FrameUniform,
    u: &'a RadiosityUniform,
    layers: [&'a [GSample]; 2],
    source: &'a [SourceTexel],
    layout: &'a PyramidLayout,
    /// The layer whose points gather.
    receiver: usize,
    /// Taps per point.
    taps: u32,
}

impl Gather<'_> {
    /// As `sent`: what the surface of `layer` in texel `t` (pixel centre `at`, view depth `z`)
    /// sends towards the view-space point `c`, B where it faces `c` (or without the normal
    /// test), else H.
    fn sent(&self, t: &SourceTexel, layer: usize, c: Vec3, at: Vec2, z: f32) -> Vec3 {
        if self.u.normal_test == 0 {
            return t.radiance(layer);
        }
        let d = c - view_position(self.f, at, z);
        self.sent_towards(t, layer, t.normal(layer), d, d.length())
    }

    /// As `sent_towards`: `sent` with the surface's normal and d = c - its point (|d| =
    /// `reach`) at hand.
    fn sent_towards(
        &self,
        t: &SourceTexel,
        layer: usize,
        normal: Vec3,
        d: Vec3,
        reach: f32,
    ) -> Vec3 {
        if d.dot(normal) > -FACING_SLACK * reach { t.radiance(layer) } else { t.hidden(layer) }
    }

    /// As `slices_gather`: the irradiance and confidence at pixel `(x, y)`.
    fn slices(&self, (x, y_px): (u32, u32), noise_at: (u32, u32)) -> Vec4 {
        let (f, u) = (self.f, self.u);
        let s = &self.layers[self.receiver][(y_px * f.width + x) as usize];
        let c = view_position(f, Vec2::new(x as f32, y_px as f32) + 0.5, s.depth);
        let n = mat_mul(&f.view, s.normal.extend(0.0).to_array()).xyz().normalize();
        let r_px = u.radius * pixels_per_unit(f, s.depth);
        let slices = u.slices.max(1);
        let steps = (self.taps / (2 * slices)).max(1);
        let noise = slice_noise(noise_at.0, noise_at.1, u.turn);
        let (mut seen, mut covered) = (Vec3::ZERO, 0.0f32);
        for k in 0..slices {
            let sl = Slice::at(f, k, slices, noise, c, n);
            if sl.weight.is_nan() || sl.weight <= 0.0 {
                continue;
            }
            let (mut every, mut half) = (Gathered::default(), Gathered::default());
            for side in [1.0, -1.0] {
                let spacing = sl.spacing(f, (x, y_px), side, r_px, steps);
                let coarsest = mip_coarsest(spacing, self.layout);
                let mut last: Option<Sender> = None;
                let mut grazing: Option<Grazing> = None;
                for j in 0..steps {
                    let h = step_distance(spacing, j, steps, noise.1);
                    let even = j % 2 == 0;
                    let level = mip_level(h, u.mip_offset, coarsest);
                    let found = sl
                        .tap(f, (x, y_px), h, side)
                        .map(|tap| mip_texel(self.layout, tap, level))
                        .map(|(q, at)| (&self.source[q], at))
                        .filter(|(t, _)| t.depth(0) > 0.0);
                    let point = found
                        .filter(|_| u.normal_test != 0)
                        .map(|(t, at)| (view_position(f, at, t.depth(0)), t.normal(0)));
                    if let Some(g) = grazing.take() {
                        let light = g.light(c, point);
                        send(&mut every, &mut half, light, g.count, g.count_half);
                        if let Some(l) = last.as_mut() {
                            l.light = light;
                        }
                    }
                    let Some((t, at)) = found else {
                        continue;
                    };
                    let (z0, z1) = (t.depth(0), t.depth(1));
                    let (back0, back1) = solid_backs(z0, z1, u.thickness);
                    let (bits, _) = sl.solid_sectors(f, c, n, at, side, z0, back0, 0.0, u.radius);
                    let first = every.first(bits);
                    let first_half = if even { half.first(bits) } else { 0 };
                    match point {
                        _ if bits == 0 => {}
                        None => send(&mut every, &mut half, t.radiance(0), first, first_half),
                        Some((y, ny)) => {
                            // The rules for curved surfaces.
                            let d = c - y;
                            let reach = d.length();
                            let mut light = self.sent_towards(t, 0, ny, d, reach);
                            let mut facing = ny.dot(d) / reach.max(1e-30);
                            let joined = last
                                .as_ref()
                                .filter(|l| (y - l.y).length_squared() < reach * reach);
                            match joined {
                                Some(l) if ny.dot(l.n) < BEND_COS && l.facing > facing => {
                                    (light, facing) = (l.light, l.facing);
                                }
                                None if facing < GRAZING => {
                                    let (b, h) = (light, t.hidden(0));
                                    grazing = Some(Grazing {
                                        b,
                                        h,
                                        facing,
                                        count: first,
                                        count_half: first_half,
                                        y,
                                        n: ny,
                                    });
                                }
                                _ => {}
                            }
                            last = Some(Sender { light, y, n: ny, facing });
                            if grazing.is_none() {
                                send(&mut every, &mut half, light, first, first_half);
                            }
                        }
                    }
                    occupy(&mut every, &mut half, bits, even);
                    if z1 > z0 {
                        let (bits, _) =
                            sl.solid_sectors(f, c, n, at, side, z1, back1, 0.0, u.radius);
                        let first = every.first(bits);
                        let first_half = if even { half.first(bits) } else { 0 };
                        let light = self.sent(t, 1, c, at, z1);
                        send(&mut every, &mut half, light, first, first_half);
                        occupy(&mut every, &mut half, bits, even);
                    }
                }
                // A grazing point with no step after it: nothing tells that its surface bends.
                if let Some(g) = grazing {
                    send(&mut every, &mut half, g.b, g.count, g.count_half);
                }
            }
            // Richardson's extrapolation in the steps a side.
            let k = u.extrapolation;
            let (hidden, hidden_half) =
                (every.occupied.count_ones() as f32, half.occupied.count_ones() as f32);
            seen += sl.weight * (every.sum + k * (every.sum - half.sum)).max(Vec3::ZERO)
                / SECTORS as f32;
            covered += sl.weight * (hidden + k * (hidden - hidden_half)).max(0.0) / SECTORS as f32;
        }
        (PI * seen / slices as f32).extend((covered / slices as f32).min(1.0))
    }
}

/// As `layer1_record`: what the layer-1 gather keeps of its irradiance and confidence `g` at a
/// point of view depth `z`: E / c (0 where it found nothing) and z (0 where there is no point).
pub fn layer1_record(g: Vec4, z: f32) -> Vec4 {
    // NaN depths fail the test too.
    if z.is_nan() || z <= 0.0 {
        return Vec4::ZERO;
    }
    let e = if g.truncate().is_finite() { spread(g) } else { Vec3::ZERO };
    e.extend(z)
}
