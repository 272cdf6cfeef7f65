//! CPU reference of `wgsl/ao.wgsl`: two-layer ambient obscurance.

use glam::{Vec2, Vec3, Vec4Swizzles};

use crate::cpu::frame::mat_mul;
use crate::cpu::frame::pixels_per_unit;
pub use crate::cpu::frame::view_position;
use crate::cpu::pyramid::{mip_coarsest, mip_level, mip_origin, mip_size, mip_texel};
use crate::cpu::slices::{SECTORS, Slice, slice_noise, solid_backs, step_distance};
use crate::cpu::spiral::{spiral_distance, spiral_tap};
use crate::frame::FrameUniform;
use crate::frame::PyramidLayout;
use crate::gbuffer::GSample;
use crate::settings::{AoEstimator, AoSettings, downsample_level};

fn obscurance(s: &AoSettings, c: Vec3, n: Vec3, y: Vec3) -> f32 {
    let v = y - c;
    let vv = v.dot(v);
    let r2 = s.radius * s.radius;
    (1.0 - vv / r2).max(0.0) * ((v.dot(n) - s.bias) / (vv + 1e-4 * r2).sqrt()).max(0.0)
}

/// AV by `s.estimator` of every texel of the level `s.downsample` computes (every pixel at 1;
/// at 2 and 4 each texel of the rotated grid's level 1 or 2 at the pixel it stands for, before
/// the upsample). `pyramid1` is `None` for one-layer obscurance.
pub fn ao(
    f: &FrameUniform,
    s: &AoSettings,
    layer0: &[GSample],
    layout: &PyramidLayout,
    pyramid0: &[f32],
    pyramid1: Option<&[f32]>,
) -> Vec<f32> {
    ao_at_turn(f, s, 0, layer0, layout, pyramid0, pyramid1)
}

/// [`ao`] of a frame `turn` frames into the temporal filter's history (0: without one): the
/// slices turned by `turn`, with the slices and taps that frame takes
/// ([`AoSettings::frame_taps`]).
pub fn ao_at_turn(
    f: &FrameUniform,
    s: &AoSettings,
    turn: u32,
    layer0: &[GSample],
    layout: &PyramidLayout,
    pyramid0: &[f32],
    pyramid1: Option<&[f32]>,
) -> Vec<f32> {
    let (slices, samples) = s.frame_taps(turn > 0);
    let s = &AoSettings { slices, samples, ..s.clone() };
    let kernel = Kernel { f, s, turn, layout, pyramid0, pyramid1 };
    let level = downsample_level(s.downsample) as usize;
    let size = mip_size(f.width, f.height, level);
    let mut out = vec![1.0; (size.0 * size.1) as usize];
    for ty in 0..size.1 {
        for tx in 0..size.0 {
            let (x, y) = mip_origin(f.width, f.height, level, (tx, ty));
            let p = (y * f.width + x) as usize;
            let Some((c, n, r_px)) = kernel.centre(x, y, layer0[p].normal) else { continue };
            out[(ty * size.0 + tx) as usize] = match s.estimator {
                AoEstimator::Sao => kernel.sao((x, y), c, n, r_px),
                AoEstimator::Horizon | AoEstimator::Bitmask => {
                    kernel.slices((x, y), (tx, ty), c, n, r_px)
                }
            };
        }
    }
    out
}

/// As `step_falloff`: the falloff the sectors a layer-0 point hides first take, the mean of its
/// own and that of the side's last point where that point lies nearer it than the receiving
/// point does (the surface between two steps taken as straight), else its own.
fn step_falloff(own: f32, last: Option<f32>) -> f32 {
    last.map_or(own, |last| 0.5 * (own + last))
}

/// As `Hidden`: the sectors a slice's steps have hidden (all of them, or every other one for
/// the extrapolation), their falloff-weighted count, and the side's last layer-0 point with its
/// falloff.
#[derive(Default)]
struct Hidden {
    occupied: u32,
    sum: f32,
    last: Option<(f32, Vec3)>,
}

impl Hidden {
    /// As `hide_front`: the sectors `bits` of layer-0 point `y` that nothing hid before, at
    /// `step_falloff`, joined to the side's last point where `y` lies nearer it than `c` does.
    fn front(&mut self, bits: u32, falloff: f32, y: Vec3, c: Vec3) {
        let joined =
            self.last.filter(|(_, p)| (y - *p).length() < (y - c).length()).map(|(f, _)| f);
        self.sum += step_falloff(falloff, joined) * (bits & !self.occupied).count_ones() as f32;
        self.occupied |= bits;
        self.last = Some((falloff, y));
    }

    /// As `hide_behind`: the sectors `bits` of a layer-1 point that nothing hid before, at its
    /// own falloff.
    fn behind(&mut self, bits: u32, falloff: f32) {
        self.sum += falloff * (bits & !self.occupied).count_ones() as f32;
        self.occupied |= bits;
    }
}

/// What `wgsl/ao.wgsl` reads: the frame, the settings and the depth pyramids.
struct Kernel<'a> {
    f: &'a FrameUniform,
    s: &'a AoSettings,
    turn: u32,
    layout: &'a PyramidLayout,
    pyramid0: &'a [f32],
    pyramid1: Option<&'a [f32]>,
}

impl Kernel<'_> {
    /// As `centre`: the view-space point and normal of pixel `(x, y)` and the radius in pixels,
    /// `None` where there is nothing to obscure.
    fn centre(&self, x: u32, y: u32, normal: Vec3) -> Option<(Vec3, Vec3, f32)> {
        let (f, s) = (self.f, self.s);
        let z = self.pyramid0[(y * f.width + x) as usize];
        if z.is_nan() || z <= 0.0 || s.samples == 0 || s.radius.is_nan() || s.radius <= 0.0 {
            return None;
        }
        let c = view_position(f, Vec2::new(x as f32, y as f32) + 0.5, z);
        let n = mat_mul(&f.view, normal.extend(0.0).to_array()).xyz().normalize();
        Some((c, n, s.radius * pixels_per_unit(f, z)))
    }

    /// As `pyramid_texel`: the index of the texel of `level` under pixel `(tx, ty)` and the
    /// centre of the pixel it came from.
    fn pyramid_texel(&self, tap: (u32, u32), level: usize) -> (usize, Vec2) {
        mip_texel(self.layout, tap, level)
    }

    /// As `tap_level`: the pyramid level a tap `h` pixels away reads.
    fn tap_level(&self, h: f32, coarsest: usize) -> usize {
        mip_level(h, self.s.mip_offset, coarsest)
    }

    /// As `visibility`: Scalable Ambient Obscurance's sum.
    fn sao(&self, (x, y): (u32, u32), c: Vec3, n: Vec3, r_px: f32) -> f32 {
        let (f, s) = (self.f, self.s);
        let mut sum = 0.0;
        for i in 0..s.samples {
            let h = spiral_distance(i, s.samples, r_px);
            let (tx, ty) = spiral_tap(x, y, i, s.samples, r_px);
            if tx < 0 || ty < 0 || tx >= f.width as i32 || ty >= f.height as i32 {
                continue;
            }
            let level = self.tap_level(h, self.layout.levels.len() - 1);
            let (q, at) = self.pyramid_texel((tx as u32, ty as u32), level);
            let mut o = 0.0f32;
            if self.pyramid0[q] > 0.0 {
                o = obscurance(s, c, n, view_position(f, at, self.pyramid0[q]));
            }
            if let Some(p1) = self.pyramid1
                && p1[q] > 0.0
            {
                o = o.max(obscurance(s, c, n, view_position(f, at, p1[q])));
            }
            sum += o;
        }
        (1.0 - s.intensity * 2.0 / s.samples as f32 * sum).clamp(0.0, 1.0)
    }

    /// As `slice_visibility`: the `horizon` and `bitmask` estimators.
    fn slices(&self, (x, y): (u32, u32), noise_at: (u32, u32), c: Vec3, n: Vec3, r_px: f32) -> f32 {
        let (f, s) = (self.f, self.s);
        let slices = s.slices.max(1);
        let steps = (s.samples / (2 * slices)).max(1);
        let noise = slice_noise(noise_at.0, noise_at.1, self.turn);
        let thickness = s.solid_depth();
        let r2 = s.radius * s.radius;
        let falloff = |front2: f32| (1.0 - front2 / r2).max(0.0);
        let mut total = 0.0;
        for k in 0..slices {
            let sl = Slice::at(f, k, slices, noise, c, n);
            if sl.weight.is_nan() || sl.weight <= 0.0 {
                continue;
            }
            // Every step's sectors, and every other step's (j even) for the extrapolation.
            let (mut every, mut half) = (Hidden::default(), Hidden::default());
            // The two sides hold opposite halves of the arc; each spreads its steps over the
            // radius or the part of it on screen.
            for side in [1.0, -1.0] {
                let spacing = sl.spacing(f, (x, y), side, r_px, steps);
                let level = mip_coarsest(spacing, self.layout);
                every.last = None;
                half.last = None;
                for j in 0..steps {
                    let h = step_distance(spacing, j, steps, noise.1);
                    // Finer levels for the near steps, as `sao` reads them, never coarser than
                    // the step spacing.
                    let step_level = self.tap_level(h, level);
                    let Some(tap) = sl.tap(f, (x, y), h, side) else { continue };
                    let (q, at) = self.pyramid_texel(tap, step_level);
                    let z0 = self.pyramid0[q];
                    if z0.is_nan() || z0 <= 0.0 {
                        continue;
                    }
                    let z1 = self.pyramid1.map_or(0.0, |p1| p1[q]);
                    let (back0, back1) = solid_backs(z0, z1, thickness);
                    let even = j % 2 == 0;
                    let (bits, front2) =
                        sl.solid_sectors(f, c, n, at, side, z0, back0, s.bias, s.radius);
                    let point = view_position(f, at, z0);
                    every.front(bits, falloff(front2), point, c);
                    if even {
                        half.front(bits, falloff(front2), point, c);
                    }
                    if z1 > z0 {
                        let (bits, front2) =
                            sl.solid_sectors(f, c, n, at, side, z1, back1, s.bias, s.radius);
                        every.behind(bits, falloff(front2));
                        if even {
                            half.behind(bits, falloff(front2));
                        }
                    }
                }
            }
            let extrapolated = every.sum + s.extrapolation * (every.sum - half.sum);
            total += sl.weight * extrapolated / SECTORS as f32;
        }
        (1.0 - s.intensity * total / slices as f32).clamp(0.0, 1.0)
    }
}
