//! CPU reference of `wgsl/motion_blur.wgsl`: motion blur of the camera's motion and of moving
//! geometry, from both layers. It walks each instant's full reach; the kernel stops where the
//! neighbourhood's largest motion says nothing more can be found, which gives the same image.

use glam::{Vec2, Vec3, Vec4};

use crate::cpu::composite::layer1_radiance;
use crate::cpu::frame::{clip_to_pixel, image_size};
use crate::cpu::spiral::pixel_hash;
use crate::frame::{FrameUniform, MOTION_TILE, MotionBlurUniform};
use crate::gbuffer::GSample;

/// What `motion_blur_main` reads: the constants, both layers, layer 1's direct radiance and the
/// image before the pass.
pub struct MotionBlurInputs<'a> {
    /// The constants.
    pub u: &'a MotionBlurUniform,
    /// The frame's constants (its cameras: the motion the camera alone gives a surface).
    pub frame: &'a FrameUniform,
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

/// What a tile of the kernel holds: the motion of the surface moving most by itself, the
/// largest component of that own motion, and the largest motion component of any surface.
#[derive(Clone, Copy, Default)]
struct Fastest {
    motion: Vec2,
    own: f32,
    any: f32,
}

/// As `camera_motion`.
fn camera_motion(f: &FrameUniform, centre: Vec2, d: f32) -> Vec2 {
    let (pc, _) = f.reproject(centre, d);
    if pc.w.is_nan() || pc.w <= 1e-20 {
        return Vec2::ZERO;
    }
    centre - clip_to_pixel(pc, image_size(f))
}

impl Fastest {
    /// As `faster`.
    fn faster(self, f: &FrameUniform, s: &GSample, centre: Vec2) -> Fastest {
        let key = s.motion.x.abs().max(s.motion.y.abs());
        if s.depth.is_nan() || s.depth <= 0.0 || key.is_nan() || key > 3.0e38 {
            return self;
        }
        let mut out = Fastest { any: self.any.max(key), ..self };
        let own = (s.motion - camera_motion(f, centre, s.depth)).abs();
        let own_key = own.x.max(own.y);
        if own_key <= 3.0e38 && own_key > self.own {
            out = Fastest { motion: s.motion, own: own_key, ..out };
        }
        out
    }
}

impl MotionBlurInputs<'_> {
    /// As `motion_tiles` then `motion_neighbours`: the fastest motion within `tile_reach` tiles
    /// of each tile, row by row.
    fn neighbourhoods(&self) -> (Vec<Fastest>, u32) {
        let (w, h) = self.size;
        let (tx, ty) = (w.div_ceil(MOTION_TILE), h.div_ceil(MOTION_TILE));
        let mut tiles = vec![Fastest::default(); (tx * ty) as usize];
        for y in 0..h {
            for x in 0..w {
                let t = &mut tiles[((y / MOTION_TILE) * tx + x / MOTION_TILE) as usize];
                let p = (y * w + x) as usize;
                let centre = Vec2::new(x as f32, y as f32) + 0.5;
                *t = t.faster(self.frame, &self.layers[0][p], centre);
                if self.two_layers {
                    *t = t.faster(self.frame, &self.layers[1][p], centre);
                }
            }
        }
        let r = self.u.tile_reach;
        let mut near = Vec::with_capacity(tiles.len());
        for y in 0..ty {
            for x in 0..tx {
                let mut best = Fastest::default();
                for ny in y.saturating_sub(r)..=(y + r).min(ty - 1) {
                    for nx in x.saturating_sub(r)..=(x + r).min(tx - 1) {
                        let t = tiles[(ny * tx + nx) as usize];
                        if t.own > best.own {
                            best = Fastest { any: best.any, ..t };
                        }
                        best.any = best.any.max(t.any);
                    }
                }
                near.push(best);
            }
        }
        (near, tx)
    }

    /// As `motion_blur_main`: every pixel over the shutter.
    pub fn image(&self) -> Vec<Vec4> {
        let (w, h) = self.size;
        let (near, tx) = self.neighbourhoods();
        let mut out = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let n = near[((y / MOTION_TILE) * tx + x / MOTION_TILE) as usize];
                out.push(self.pixel(x, y, n));
            }
        }
        out
    }

    fn pixel(&self, x: u32, y: u32, near: Fastest) -> Vec4 {
        let u = self.u;
        let p = (y * self.size.0 + x) as usize;
        let own = &self.layers[0][p];
        let speed = own.motion.length();
        let walk_own = own.depth > 0.0 && speed * u.shutter >= 0.5 && speed <= 3.0e38;
        let own_dir = own.motion / speed;
        let near_dir = near.motion / near.motion.length();
        let across = (own_dir.x * near.motion.y - own_dir.y * near.motion.x).abs() * u.shutter;
        let covered = walk_own && own_dir.dot(near.motion) > 0.0 && across <= 0.5;
        let near_moves = near.motion.x.abs().max(near.motion.y.abs()) * u.shutter >= 0.5;
        let walk_near = near.own * u.shutter >= 0.5 && near_moves && !covered;
        if !walk_own && !walk_near {
            return self.image[p];
        }
        let centre = Vec2::new(x as f32, y as f32) + 0.5;
        let jitter = (pixel_hash(x, y) >> 20) as f32 / 4096.0;
        let mut sum = Vec4::ZERO;
        for i in 0..u.samples {
            let s = u.shutter * (i as f32 + jitter) / u.samples as f32;
            let reach = (u.max_blur * s / u.shutter) as u32;
            let mut found = (self.image[p], 3.0e38f32);
            if walk_own {
                self.walk(&mut found, centre, own_dir, s, reach);
            }
            if walk_near {
                self.walk(&mut found, centre, near_dir, s, reach);
            }
            sum += found.0;
        }
        sum / u.samples as f32
    }

    /// As `walk`: `found` (radiance, nearest depth) with what stood at `centre` at instant `s`
    /// along `dir`.
    fn walk(&self, found: &mut (Vec4, f32), centre: Vec2, dir: Vec2, s: f32, reach: u32) {
        let (w, h) = self.size;
        let ambient = Vec3::from_array(self.u.ambient);
        for k in 0..=reach {
            let at = (centre + k as f32 * dir).floor();
            if at.x < 0.0 || at.y < 0.0 || at.x >= w as f32 || at.y >= h as f32 {
                break;
            }
            let q = (at.y as u32 * w + at.x as u32) as usize;
            let s0 = &self.layers[0][q];
            if s0.depth > 0.0 && s0.depth < found.1 && stood_at(at, s0.motion, s, centre) {
                *found = (self.image[q], s0.depth);
            }
            if self.two_layers {
                let s1 = &self.layers[1][q];
                if s1.depth > 0.0 && s1.depth < found.1 && stood_at(at, s1.motion, s, centre) {
                    *found = (layer1_radiance(s1, self.direct1[q], ambient), s1.depth);
                }
            }
        }
    }
}
