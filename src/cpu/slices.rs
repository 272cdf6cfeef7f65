//! CPU mirror of `wgsl/shared/slices.wgsl`: the slices of the hemisphere that the obscurance's
//! `horizon` and `bitmask` estimators and the radiosity's `slices` gather integrate over.

use glam::{Vec2, Vec3};

use crate::cpu::frame::{screen_exit, view_position};
use crate::cpu::spiral::pixel_hash;
use crate::frame::FrameUniform;

/// Sectors per slice (one bit each).
pub const SECTORS: u32 = 32;
const PI: f32 = std::f32::consts::PI;

/// The 4x4 Bayer matrix, row by row.
const BAYER: [[u32; 4]; 4] = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];

/// As `slice_noise`: the pixel's turn of the slices (a 4x4 Bayer pattern plus a little of its
/// hash), jitter of the steps and offset of the sectors; the turn and the jitter moved on by
/// `frame_turn` steps of the golden ratio and of 0.5698.
pub fn slice_noise(x: u32, y: u32, frame_turn: u32) -> (f32, f32, f32) {
    let hash = pixel_hash(x, y);
    let bayer = BAYER[(y & 3) as usize][(x & 3) as usize];
    let within = (hash >> 24) as f32 / 256.0;
    let turn = ((bayer as f32 + within) / 16.0 + (frame_turn % 4096) as f32 * 0.618_034).fract();
    let jitter =
        (((hash >> 8) & 0xfff) as f32 / 4096.0 + (frame_turn % 4096) as f32 * 0.569_840_3).fract();
    let offset = (hash & 0xff) as f32 / 256.0 + 0.5 / 256.0;
    (turn, jitter, offset)
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

/// As `step_distance`: step j of `steps` along a side whose even spacing is `spacing`, at
/// t^1.5 of the side's reach (t = (j + jitter) / steps), crowded towards the point.
pub fn step_distance(spacing: f32, j: u32, steps: u32, jitter: f32) -> f32 {
    let t = (j as f32 + jitter) / steps as f32;
    spacing * steps as f32 * t * t.sqrt()
}

/// As `solid_backs`: where the solids of a step's two layers end (0: without end).
pub fn solid_backs(z0: f32, z1: f32, thickness: f32) -> (f32, f32) {
    if thickness > 0.0 {
        let back0 = if z1 > z0 { (z0 + thickness).min(z1) } else { z0 + thickness };
        (back0, z1 + thickness.min((z1 - z0).max(0.0)))
    } else {
        (if z1 > z0 { z1 } else { 0.0 }, 0.0)
    }
}

/// As `struct Slice`.
pub struct Slice {
    /// Screen direction of the slice.
    pub dir: Vec2,
    v: Vec3,
    gamma: f32,
    total: f32,
    /// |n_p| W_total: the slice's share of the integral (0 when degenerate).
    pub weight: f32,
    offset: f32,
    sin_gamma: f32,
    cos_gamma: f32,
    /// W(theta) = w_neg - F(theta) for theta <= 0, w_pos + F(theta) above (F: the antiderivative
    /// of cos(t - gamma) sin t, -cos(2t - gamma) / 4 + t sin(gamma) / 2).
    w_neg: f32,
    w_pos: f32,
}

impl Slice {
    /// As `slice_at`: slice `k` of `count` at view-space point `c` (normal `n`).
    pub fn at(
        f: &FrameUniform,
        k: u32,
        count: u32,
        noise: (f32, f32, f32),
        c: Vec3,
        n: Vec3,
    ) -> Self {
        let phi = PI * (k as f32 + noise.0) / count as f32;
        let dir = Vec2::new(phi.cos(), phi.sin());
        let v = if f.ortho != 0 { Vec3::Z } else { (-c).normalize() };
        let s_view = Vec3::new(dir.x, -dir.y, 0.0);
        let axis = (s_view - v * s_view.dot(v)).normalize();
        let plane = v.cross(axis);
        let np = n - plane * n.dot(plane);
        let np_len = np.length();
        let gamma = np.dot(axis).atan2(np.dot(v)).clamp(-0.5 * PI, 0.5 * PI);
        let (sin_gamma, cos_gamma) = (gamma.sin(), gamma.cos());
        let w_neg = 0.25 * cos_gamma + 0.5 * (gamma - 0.5 * PI) * sin_gamma;
        let w_pos = w_neg + 0.5 * cos_gamma;
        let total = cos_gamma + gamma * sin_gamma;
        let weight = if np_len > 1e-6 { np_len * total } else { 0.0 };
        Slice { dir, v, gamma, total, weight, offset: noise.2, sin_gamma, cos_gamma, w_neg, w_pos }
    }

    /// As `slice_spacing`: the spacing (pixels) of `steps` steps on `side` (+-1) of the slice
    /// through pixel `(x, y)`, spread over the radius `r_px` or the part of it on screen.
    pub fn spacing(
        &self,
        f: &FrameUniform,
        (x, y): (u32, u32),
        side: f32,
        r_px: f32,
        steps: u32,
    ) -> f32 {
        let p = Vec2::new(x as f32, y as f32) + 0.5;
        r_px.min(screen_exit(f, p, self.dir * side)) / steps as f32
    }

    /// As `slice_tap`: the pixel of the step at `h` pixels on `side` (+-1) of the slice through
    /// pixel `(x, y)`, if it lies on screen and is not that pixel.
    pub fn tap(
        &self,
        f: &FrameUniform,
        (x, y): (u32, u32),
        h: f32,
        side: f32,
    ) -> Option<(u32, u32)> {
        let t = (Vec2::new(x as f32, y as f32) + 0.5 + side * h * self.dir).floor();
        let (tx, ty) = (t.x as i32, t.y as i32);
        let inside = tx >= 0 && ty >= 0 && tx < f.width as i32 && ty < f.height as i32;
        (inside && (tx as u32, ty as u32) != (x, y)).then_some((tx as u32, ty as u32))
    }

    /// As `weight_in`: the weight W of direction `d` from a tap on `side` (+-1), 0 before the
    /// arc and W_total past it.
    fn weight(&self, d: Vec3, side: f32) -> f32 {
        let c = (d.dot(self.v) / d.length().max(1e-30)).clamp(-1.0, 1.0);
        let theta = side * c.acos();
        if theta <= self.gamma - 0.5 * PI {
            return 0.0;
        }
        if theta >= self.gamma + 0.5 * PI {
            return self.total;
        }
        let s = side * (1.0 - c * c).max(0.0).sqrt();
        let f = -0.25 * ((2.0 * c * c - 1.0) * self.cos_gamma + 2.0 * s * c * self.sin_gamma)
            + 0.5 * theta * self.sin_gamma;
        if theta <= 0.0 { self.w_neg - f } else { self.w_pos + f }
    }

    /// As `sector_bits`: the sectors whose centres lie between the weights `w0` and `w1`.
    fn bits(&self, w0: f32, w1: f32) -> u32 {
        let scale = SECTORS as f32 / self.total;
        let first = (w0.min(w1) * scale - self.offset).ceil() as i32;
        let last = ((w0.max(w1) * scale - self.offset).floor() as i32).min(SECTORS as i32 - 1);
        let first = first.max(0);
        if last < first {
            return 0;
        }
        let count = (last - first + 1) as u32;
        let ones = if count >= 32 { u32::MAX } else { (1 << count) - 1 };
        ones << first as u32
    }

    /// As `solid_sectors`: the sectors the solid of a point hides, and the squared distance
    /// from `c` to the point (not lowered).
    #[allow(clippy::too_many_arguments, reason = "the WGSL function's arguments, in its order")]
    pub fn solid_sectors(
        &self,
        f: &FrameUniform,
        c: Vec3,
        n: Vec3,
        at: Vec2,
        side: f32,
        z: f32,
        back: f32,
        lower: f32,
        radius: f32,
    ) -> (u32, f32) {
        let down = n * lower;
        let point = view_position(f, at, z);
        let y = point - down;
        let endless = back.is_nan() || back <= z;
        let far = view_position(f, at, if endless { 2.0 * z } else { back }) - down;
        let nearest = segment_distance(c, y, far, endless);
        let front2 = (point - c).length_squared();
        let height = (y - c).dot(n);
        if nearest.is_nan() || nearest >= radius || height.is_nan() || height <= 0.0 {
            return (0, front2);
        }
        let w0 = self.weight(y - c, side);
        // Without end: towards theta = +-pi, past the arc's end on the tap's side.
        let w1 = match (endless, side > 0.0) {
            (false, _) => self.weight(far - c, side),
            (true, true) => self.total,
            (true, false) => 0.0,
        };
        (self.bits(w0, w1), front2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::CameraMatrices;
    use crate::scene::Camera;

    /// Lowering a point (the obscurance's bias) decides which directions its solid hides, not
    /// how far away the surface is: the distance its falloff takes is the point's own, so that
    /// a larger bias never brings an occluder nearer.
    #[test]
    fn a_lowered_point_keeps_its_own_distance() {
        let camera = Camera::perspective(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 60.0, 0.1);
        let (w, h) = (64, 48);
        let m = CameraMatrices::new(&camera, w, h);
        let f = FrameUniform::new(&camera, m, m, w, h, 0.0, (0, 0, 0));
        // A wall facing the camera at depth 3 and, four pixels to the right, a point 0.4 in
        // front of it.
        let c = view_position(&f, Vec2::new(32.5, 24.5), 3.0);
        let n = Vec3::Z;
        let sl = Slice::at(&f, 0, 1, (0.0, 0.5, 0.5), c, n);
        let at = Vec2::new(36.5, 24.5);
        let point = view_position(&f, at, 2.6);
        let own = (point - c).length_squared();
        for lower in [0.0, 0.05, 0.2] {
            let (bits, front2) = sl.solid_sectors(&f, c, n, at, 1.0, 2.6, 2.9, lower, 1.0);
            assert_ne!(bits, 0, "lowered by {lower} the point still stands above the wall");
            assert_eq!(front2, own, "lowered by {lower}");
        }
    }

    /// The steps stay in order within the side's reach, crowd towards the point (each gap at
    /// least the one before it) and reach it as the jitter approaches 1; an even spread would
    /// put step j at (j + jitter) spacings.
    #[test]
    fn steps_crowd_towards_the_point_within_the_reach() {
        let (spacing, steps) = (3.0f32, 8u32);
        for jitter in [0.0f32, 0.25, 0.5, 0.999] {
            let h: Vec<f32> =
                (0..steps).map(|j| step_distance(spacing, j, steps, jitter)).collect();
            assert!(h[0] >= 0.0 && h[steps as usize - 1] <= spacing * steps as f32);
            for w in h.windows(3) {
                assert!(w[1] - w[0] <= w[2] - w[1] + 1e-5, "{h:?}");
            }
            // The first step lies nearer than an even spread puts it (past the very start).
            if jitter > 0.0 {
                assert!(h[0] < spacing * jitter, "{h:?}");
            }
        }
        let last = step_distance(spacing, steps - 1, steps, 0.999_999);
        assert!((last - spacing * steps as f32).abs() < 1e-3, "{last}");
    }

    /// Layer 0's solid ends at layer 1's surface or `thickness` behind itself, whichever is
    /// nearer; layer 1's is `thickness` deep but no deeper than the gap in front of it; a
    /// thickness of 0 makes layer 0 solid down to layer 1 and layer 1 without end (0).
    #[test]
    fn the_second_layer_is_no_deeper_than_the_gap_in_front_of_it() {
        assert_eq!(solid_backs(1.0, 1.25, 0.5), (1.25, 1.5));
        assert_eq!(solid_backs(1.0, 3.0, 0.5), (1.5, 3.5));
        assert_eq!(solid_backs(1.0, 0.0, 0.5).0, 1.5);
        assert_eq!(solid_backs(1.0, 1.25, 0.0), (1.25, 0.0));
        assert_eq!(solid_backs(1.0, 0.0, 0.0), (0.0, 0.0));
    }
}
