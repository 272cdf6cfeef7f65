//! CPU reference of `wgsl/motion_blur.wgsl`: motion blur of the camera's motion, from both
//! layers. It walks each instant's full reach; the kernel stops where the largest motion says
//! nothing more can be found (`motion_max`), which gives the same image.

use glam::{Vec2, Vec3, Vec4};

use crate::cpu::composite::layer1_radiance;
use crate::cpu::spiral::pixel_hash;
use crate::frame::MotionBlurUniform;
use crate::gbuffer::GSample;

/// What `motion_blur_main` reads: the constants, both layers, layer 1's direct radiance and the
/// image before the pass.
pub struct MotionBlurInputs<'a> {
    /// The constants.
    pub u: &'a MotionBlurUniform,
    /// Image width and height.
    pub size: (u32, u32),
    /// Layer 0 and layer 1.
    pub layers: [&'a [GSample]; 2],
    /// Whether pixels see layer 1 (`TWO_LAYERS`).
    pub two_layers: bool,
    /// Layer 1's direct radiance.
    pub direct1: &'a [Vec3],
    /// The image before the pass.
    pub image: &'a [Vec4],
}

/// As `stood_at`.
fn stood_at(q: Vec2, m: Vec2, s: f32, centre: Vec2) -> bool {
    let d = (q + 0.5 - s * m - centre).abs();
    d.x.max(d.y) <= 0.75
}

impl MotionBlurInputs<'_> {
    /// As `motion_blur_main`: every pixel over the shutter.
    pub fn image(&self) -> Vec<Vec4> {
        let (w, h) = self.size;
        let mut out = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                out.push(self.pixel(x, y));
            }
        }
        out
    }

    fn pixel(&self, x: u32, y: u32) -> Vec4 {
        let (w, h) = self.size;
        let u = self.u;
        let p = (y * w + x) as usize;
        let own = &self.layers[0][p];
        let speed = own.motion.length();
        let moving = speed * u.shutter;
        if own.depth.is_nan() || own.depth <= 0.0 || moving.is_nan() || moving < 0.5 {
            return self.image[p];
        }
        let dir = own.motion / speed;
        let centre = Vec2::new(x as f32, y as f32) + 0.5;
        let jitter = (pixel_hash(x, y) >> 20) as f32 / 4096.0;
        let ambient = Vec3::from_array(u.ambient);
        let mut sum = Vec4::ZERO;
        for i in 0..u.samples {
            let s = u.shutter * (i as f32 + jitter) / u.samples as f32;
            let reach = (u.max_blur * s / u.shutter) as u32;
            let (mut best, mut nearest) = (self.image[p], 3.0e38f32);
            for k in 0..=reach {
                let at = (centre + k as f32 * dir).floor();
                if at.x < 0.0 || at.y < 0.0 || at.x >= w as f32 || at.y >= h as f32 {
                    break;
                }
                let q = (at.y as u32 * w + at.x as u32) as usize;
                let s0 = &self.layers[0][q];
                if s0.depth > 0.0 && s0.depth < nearest && stood_at(at, s0.motion, s, centre) {
                    nearest = s0.depth;
                    best = self.image[q];
                }
                if self.two_layers {
                    let s1 = &self.layers[1][q];
                    if s1.depth > 0.0 && s1.depth < nearest && stood_at(at, s1.motion, s, centre) {
                        nearest = s1.depth;
                        best = layer1_radiance(s1, self.direct1[q], ambient);
                    }
                }
            }
            sum += best;
        }
        sum / u.samples as f32
    }
}
