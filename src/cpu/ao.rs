//! CPU reference of `wgsl/ao.wgsl`: two-layer ambient obscurance.

use glam::{Vec2, Vec3, Vec4Swizzles};

use crate::cpu::frame::mat_mul;
pub use crate::cpu::frame::view_position;
use crate::cpu::spiral::{pixel_hash, pixels_per_unit, spiral_distance, spiral_tap};
use crate::frame::FrameUniform;
use crate::frame::PyramidLayout;
use crate::gbuffer::GSample;
use crate::settings::{AoEstimator, AoSettings};

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

/// AV of every pixel by `s.estimator`. `pyramid1` is `None` for one-layer obscurance.
pub fn ao(
    f: &FrameUniform,
    s: &AoSettings,
    layer0: &[GSample],
    layout: &PyramidLayout,
    pyramid0: &[f32],
    pyramid1: Option<&[f32]>,
) -> Vec<f32> {
    match s.estimator {
        AoEstimator::Sao => sao(f, s, layer0, layout, pyramid0, pyramid1),
        AoEstimator::Horizon | AoEstimator::Bitmask => {
            let slices = Slices { f, s, layout, pyramid0, pyramid1 };
            let mut out = vec![1.0; (f.width * f.height) as usize];
            for y in 0..f.height {
                for x in 0..f.width {
                    let p = (y * f.width + x) as usize;
                    out[p] = slices.visibility(x, y, layer0[p].normal);
                }
            }
            out
        }
    }
}

/// AV of every pixel by Scalable Ambient Obscurance's sum.
fn sao(
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

const SECTORS: u32 = 32;
const PI: f32 = std::f32::consts::PI;

/// Antiderivative of cos(t - gamma) sin(t) (`arc_f`).
fn arc_f(t: f32, gamma: f32) -> f32 {
    -0.25 * (2.0 * t - gamma).cos() + 0.5 * t * gamma.sin()
}

/// As `arc_weight`: the weight of the arc from gamma - pi/2 to theta.
fn arc_weight(theta: f32, gamma: f32) -> f32 {
    let start = arc_f(gamma - 0.5 * PI, gamma);
    if theta <= 0.0 {
        start - arc_f(theta, gamma)
    } else {
        start + arc_f(theta, gamma) - 2.0 * arc_f(0.0, gamma)
    }
}

/// As `struct Slice`.
struct Slice {
    v: Vec3,
    gamma: f32,
    total: f32,
    offset: f32,
}

impl Slice {
    /// As `angle_in`.
    fn angle(&self, d: Vec3, side: f32) -> f32 {
        side * (d.dot(self.v) / d.length().max(1e-30)).clamp(-1.0, 1.0).acos()
    }

    /// As `sector_bits`.
    fn bits(&self, theta0: f32, theta1: f32) -> u32 {
        let (a, b) = (self.gamma - 0.5 * PI, self.gamma + 0.5 * PI);
        let lo = theta0.min(theta1).clamp(a, b);
        let hi = theta0.max(theta1).clamp(a, b);
        let scale = SECTORS as f32 / self.total;
        let first = (arc_weight(lo, self.gamma) * scale - self.offset).ceil() as i32;
        let last = ((arc_weight(hi, self.gamma) * scale - self.offset).floor() as i32)
            .min(SECTORS as i32 - 1);
        let first = first.max(0);
        if last < first {
            return 0;
        }
        let count = (last - first + 1) as u32;
        let ones = if count >= 32 { u32::MAX } else { (1 << count) - 1 };
        ones << first as u32
    }
}

/// As `segment_distance`.
fn segment_distance(c: Vec3, y: Vec3, back: Vec3, endless: bool) -> f32 {
    let d = back - y;
    let dd = d.dot(d);
    let mut t = 0.0;
    if dd > 0.0 {
        t = ((c - y).dot(d) / dd).max(0.0);
        if !endless {
            t = t.min(1.0);
        }
    }
    (y + d * t - c).length()
}

/// The `horizon` and `bitmask` estimators (`slice_visibility`).
struct Slices<'a> {
    f: &'a FrameUniform,
    s: &'a AoSettings,
    layout: &'a PyramidLayout,
    pyramid0: &'a [f32],
    pyramid1: Option<&'a [f32]>,
}

impl Slices<'_> {
    fn thickness(&self) -> f32 {
        match self.s.estimator {
            AoEstimator::Bitmask => self.s.thickness * self.s.radius,
            _ => 0.0,
        }
    }

    /// As `hidden`: the sectors a point hides and their falloff.
    #[allow(clippy::too_many_arguments, reason = "the WGSL function's arguments, in its order")]
    fn hidden(
        &self,
        sl: &Slice,
        c: Vec3,
        n: Vec3,
        at: Vec2,
        side: f32,
        z: f32,
        back: f32,
    ) -> (u32, f32) {
        let lower = n * self.s.bias;
        let y = view_position(self.f, at, z) - lower;
        let endless = back.is_nan() || back <= z;
        let far = view_position(self.f, at, if endless { 2.0 * z } else { back }) - lower;
        let nearest = segment_distance(c, y, far, endless);
        let r2 = self.s.radius * self.s.radius;
        let height = (y - c).dot(n);
        if nearest.is_nan() || nearest * nearest >= r2 || height.is_nan() || height <= 0.0 {
            return (0, 0.0);
        }
        let theta0 = sl.angle(y - c, side);
        let theta1 = if endless { PI * side } else { sl.angle(far - c, side) };
        (sl.bits(theta0, theta1), (1.0 - (y - c).length_squared() / r2).max(0.0))
    }

    fn visibility(&self, x: u32, y: u32, normal: Vec3) -> f32 {
        let (f, s) = (self.f, self.s);
        let p = (y * f.width + x) as usize;
        let z = self.pyramid0[p];
        if z.is_nan() || z <= 0.0 || s.samples == 0 || s.radius.is_nan() || s.radius <= 0.0 {
            return 1.0;
        }
        let c = view_position(f, Vec2::new(x as f32, y as f32) + 0.5, z);
        let n = mat_mul(&f.view, normal.extend(0.0).to_array()).xyz().normalize();
        let v = if f.ortho != 0 { Vec3::Z } else { (-c).normalize() };
        let r_px = s.radius * pixels_per_unit(f, z);
        let slices = s.slices.max(1);
        let steps = (s.samples / (2 * slices)).max(1);
        let spacing = r_px / steps as f32;
        let levels = self.layout.levels.len().min(8) as i32;
        let level = (spacing.max(1.0).log2().floor() as i32).clamp(0, levels - 1) as usize;
        let hash = pixel_hash(x, y);
        let turn = (hash >> 20) as f32 / 4096.0;
        let jitter = ((hash >> 8) & 0xfff) as f32 / 4096.0;
        let offset = (hash & 0xff) as f32 / 256.0 + 0.5 / 256.0;
        let thickness = self.thickness();
        let mut total = 0.0;
        for k in 0..slices {
            let phi = PI * (k as f32 + turn) / slices as f32;
            let dir = Vec2::new(phi.cos(), phi.sin());
            let s_view = Vec3::new(dir.x, -dir.y, 0.0);
            let axis = (s_view - v * s_view.dot(v)).normalize();
            let plane = v.cross(axis);
            let np = n - plane * n.dot(plane);
            let np_len = np.length();
            if np_len.is_nan() || np_len <= 1e-6 {
                continue;
            }
            let gamma = np.dot(axis).atan2(np.dot(v)).clamp(-0.5 * PI, 0.5 * PI);
            let total_weight = arc_weight(gamma + 0.5 * PI, gamma);
            let sl = Slice { v, gamma, total: total_weight, offset };
            let mut occupied = 0u32;
            let mut hidden_weight = 0.0;
            for j in 0..steps {
                let h = spacing * (j as f32 + jitter);
                for sign in [1.0, -1.0] {
                    let t = (Vec2::new(x as f32, y as f32) + 0.5 + sign * h * dir).floor();
                    let (tx, ty) = (t.x as i32, t.y as i32);
                    if tx < 0
                        || ty < 0
                        || tx >= f.width as i32
                        || ty >= f.height as i32
                        || (tx as u32, ty as u32) == (x, y)
                    {
                        continue;
                    }
                    let l = self.layout.levels[level];
                    let texel = ((tx as u32) >> level, (ty as u32) >> level);
                    let q = (l.offset + texel.1 * l.width + texel.0) as usize;
                    let origin = texel_origin(self.layout, level, texel);
                    let at = Vec2::new(origin.0 as f32, origin.1 as f32) + 0.5;
                    let z0 = self.pyramid0[q];
                    if z0.is_nan() || z0 <= 0.0 {
                        continue;
                    }
                    let z1 = self.pyramid1.map_or(0.0, |p1| p1[q]);
                    let back0 = if thickness > 0.0 {
                        let b = z0 + thickness;
                        if z1 > z0 { b.min(z1) } else { b }
                    } else if z1 > z0 {
                        z1
                    } else {
                        0.0
                    };
                    let (bits, f0) = self.hidden(&sl, c, n, at, sign, z0, back0);
                    hidden_weight += f0 * (bits & !occupied).count_ones() as f32;
                    occupied |= bits;
                    if z1 > z0 {
                        let back1 = if thickness > 0.0 { z1 + thickness } else { 0.0 };
                        let (bits, f1) = self.hidden(&sl, c, n, at, sign, z1, back1);
                        hidden_weight += f1 * (bits & !occupied).count_ones() as f32;
                        occupied |= bits;
                    }
                }
            }
            total += np_len * total_weight * hidden_weight / SECTORS as f32;
        }
        (1.0 - s.intensity * total / slices as f32).clamp(0.0, 1.0)
    }
}
