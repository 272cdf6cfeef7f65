//! CPU reference of `wgsl/transparency.wgsl` and the peels that feed it: the rasterizer's
//! `PEEL` step ([`raster_peel`]), the resolve and the direct light of each peel, `accumulate`
//! and `composite`.

use glam::{Vec3, Vec4};

use crate::cpu::composite::shaded;
use crate::cpu::direct::direct;
use crate::cpu::raster::{RasterInput, double_sided_triangles, raster_peel};
use crate::cpu::resolve::{resolve, triangle_opacity};
use crate::cpu::shadow::Shadows;
use crate::frame::FrameUniform;
use crate::gbuffer::{GSample, VIS_EMPTY, vis_depth, vis_id};
use crate::scene::{GpuLight, Scene};

/// What the transparency passes read: the frame, the scene, the opaque layer 0, the number of
/// peels, the shadow maps and the image the blended surfaces are laid over.
pub struct TransparencyInputs<'a> {
    /// The camera's frame constants.
    pub frame: &'a FrameUniform,
    /// The scene (its blended materials are peeled).
    pub scene: &'a Scene,
    /// This frame's opaque layer-0 visibility words.
    pub opaque: &'a [u64],
    /// Peels (k).
    pub layers: u32,
    /// The shadow maps the direct light reads, if shadows run.
    pub shadows: Option<&'a Shadows<'a>>,
    /// The image before (the composite).
    pub behind: &'a [Vec4],
}

/// As `accumulate`: adds the peeled surface `s` (visibility word `word`, direct radiance
/// `direct`) at pixel (x, y) behind those accumulated in `acc`.
#[expect(clippy::too_many_arguments, reason = "the kernel's inputs, spelled out")]
pub fn accumulate(
    f: &FrameUniform,
    scene: &Scene,
    word: u64,
    (x, y): (u32, u32),
    s: &GSample,
    direct: Vec3,
    ambient: Vec3,
    acc: Vec4,
) -> Vec4 {
    let (Some(id), Some(d)) = (vis_id(word), vis_depth(word)) else { return acc };
    if id as usize >= scene.triangles.len()
        || scene.triangle_materials[id as usize] as usize >= scene.materials.len()
    {
        return acc;
    }
    let colour = shaded(s, direct, 1.0, Vec4::ZERO, ambient);
    let a = triangle_opacity(f, scene, id as usize, x, y, d);
    let w = (1.0 - acc.w) * a;
    (acc.truncate() + w * colour).extend(acc.w + w)
}

/// As `composite`: the accumulated blend over the pixel `behind`.
pub fn composite(acc: Vec4, behind: Vec4) -> Vec4 {
    (acc.truncate() + (1.0 - acc.w) * behind.truncate()).extend(behind.w + (1.0 - behind.w) * acc.w)
}

impl TransparencyInputs<'_> {
    /// The k peels' visibility words, nearest first.
    pub fn peels(&self) -> Vec<Vec<u64>> {
        let ds = double_sided_triangles(self.scene);
        let input = RasterInput::new(self.scene, &ds);
        let mut peels: Vec<Vec<u64>> = Vec::new();
        for _ in 0..self.layers {
            let previous = peels.last().map(Vec::as_slice);
            let next = raster_peel(self.frame, &input, previous, self.opaque);
            peels.push(next);
        }
        peels
    }

    /// The image with the blended surfaces laid over [`behind`](TransparencyInputs::behind).
    pub fn image(&self) -> Vec<Vec4> {
        let f = self.frame;
        let lights: Vec<GpuLight> = self.scene.lights.iter().map(GpuLight::new).collect();
        let ambient = self.scene.ambient;
        let mut accum = vec![Vec4::ZERO; (f.width * f.height) as usize];
        for peel in self.peels() {
            if peel.iter().all(|&w| w == VIS_EMPTY) {
                break;
            }
            let layer = resolve(f, self.scene, &peel);
            let radiance = direct(f, &layer, &lights, self.shadows);
            for (p, acc) in accum.iter_mut().enumerate() {
                let (x, y) = (p as u32 % f.width, p as u32 / f.width);
                *acc = accumulate(
                    f,
                    self.scene,
                    peel[p],
                    (x, y),
                    &layer[p],
                    radiance[p],
                    ambient,
                    *acc,
                );
            }
        }
        accum.iter().zip(self.behind).map(|(a, b)| composite(*a, *b)).collect()
    }
}
