//! CPU reference of `wgsl/dof.wgsl`: depth of field through a thin lens, from both layers.

use std::f32::consts::TAU;

use glam::{Vec2, Vec3, Vec4};

use crate::cpu::composite::layer1_radiance;
use crate::cpu::spiral::{GOLDEN_TURNS, pixel_hash};
use crate::frame::DofUniform;
use crate::gbuffer::GSample;

/// What `dof_main` reads: the constants, both layers, layer 1's direct radiance and the sharp
/// image (the composite).
pub struct DofInputs<'a> {
    /// The constants.
    pub u: &'a DofUniform,
    /// Image width and height.
    pub size: (u32, u32),
    /// Layer 0 and layer 1.
    pub layers: [&'a [GSample]; 2],
    /// Whether rays find layer 1 (`TWO_LAYERS`).
    pub two_layers: bool,
    /// Layer 1's direct radiance.
    pub direct1: &'a [Vec3],
    /// The composite.
    pub sharp: &'a [Vec4],
}

impl DofInputs<'_> {
    /// As `reached`.
    fn reached(&self, inv_prev: f32, inv_z: f32, z: f32) -> bool {
        z > 0.0
            && inv_z <= 1.0 / z
            && (inv_prev > 1.0 / z || inv_z >= 1.0 / (z * (1.0 + self.u.thickness)))
    }

    /// As `lens_ray`: what the ray through lens point `u` finds for pixel `(x, y)`.
    fn lens_ray(&self, (x, y): (u32, u32), u: Vec2) -> Vec4 {
        let (w, h) = self.size;
        let d = self.u;
        let p = (y * w + x) as usize;
        let travel = u.length();
        let reach = travel * (-d.coc_range[0]).max(d.coc_range[1]);
        if reach.is_nan() || reach < 0.5 {
            return self.sharp[p];
        }
        let dc = 1.0 / travel;
        let k_lo = (d.coc_range[0] / dc).ceil() as i32;
        let k_hi = (d.coc_range[1] / dc).floor() as i32;
        let mut last = p;
        let mut inv_prev = d.inv_focus - (k_lo - 1) as f32 * dc / d.lens_px;
        for k in k_lo..=k_hi {
            let c = k as f32 * dc;
            let inv_z = d.inv_focus - c / d.lens_px;
            if inv_z.is_nan() || inv_z <= 0.0 {
                break;
            }
            let at = (Vec2::new(x as f32, y as f32) + 0.5 - c * u).floor();
            if at.x < 0.0 || at.y < 0.0 || at.x >= w as f32 || at.y >= h as f32 {
                return self.sharp[p];
            }
            let q = (at.y as u32 * w + at.x as u32) as usize;
            last = q;
            let z0 = self.layers[0][q].depth;
            if self.reached(inv_prev, inv_z, z0) {
                return self.sharp[q];
            }
            if self.two_layers && z0 > 0.0 && inv_z < 1.0 / (z0 * (1.0 + d.thickness)) {
                let s1 = &self.layers[1][q];
                if self.reached(inv_prev, inv_z, s1.depth) {
                    return layer1_radiance(s1, self.direct1[q], Vec3::from_array(d.ambient));
                }
            }
            inv_prev = inv_z;
        }
        let sky = self.layers[0][last].depth;
        if sky.is_nan() || sky <= 0.0 {
            return self.sharp[last];
        }
        self.sharp[p]
    }

    /// As `dof_main`: every pixel through the lens.
    pub fn image(&self) -> Vec<Vec4> {
        let (w, h) = self.size;
        let n = self.u.samples;
        let mut out = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let rotation = (pixel_hash(x, y) >> 20) as f32 / 4096.0;
                let mut sum = Vec4::ZERO;
                for i in 0..n {
                    let r = ((i as f32 + 0.5) / n as f32).sqrt();
                    let angle = (i as f32 * GOLDEN_TURNS + rotation).fract() * TAU;
                    sum += self.lens_ray((x, y), r * Vec2::new(angle.cos(), angle.sin()));
                }
                out.push(sum / n as f32);
            }
        }
        out
    }
}
