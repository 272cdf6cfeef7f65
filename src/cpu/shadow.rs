//! CPU reference of the shadow maps (the CPU rasterizer from each face) and of the lookup in
//! `wgsl/shared/shadow.wgsl` / `wgsl/direct.wgsl`.

use glam::{Vec2, Vec3};

use crate::cpu::frame::{clip_to_pixel, mat_mul};
use crate::cpu::raster::{RasterInput, double_sided_triangles, raster_layer0};
use crate::frame::{ShadowFace, light_faces};
use crate::scene::{GpuLight, Scene, SceneInfo};

/// Every shadow-casting light's maps at `resolution`, drawn by the CPU rasterizer.
pub fn maps(scene: &Scene, resolution: u32) -> (Vec<ShadowFace>, Vec<[u32; 2]>, Vec<u64>) {
    let info = SceneInfo::of(scene);
    let counts =
        (scene.triangles.len() as u32, scene.materials.len() as u32, scene.positions.len() as u32);
    let ds = double_sided_triangles(scene);
    let input = RasterInput::new(scene, &ds);
    let (mut faces, mut atlas) = (Vec::new(), Vec::new());
    let mut per_light = vec![[0u32; 2]; info.lights.len().max(2)];
    for group in light_faces(&info, resolution, counts) {
        per_light[group.light] = [group.first as u32, group.faces.len() as u32];
        for (uniform, face) in group.faces {
            atlas.extend(raster_layer0(&uniform, &input));
            faces.push(face);
        }
    }
    (faces, per_light, atlas)
}

/// Shadow maps as the direct kernel reads them.
pub struct Shadows<'a> {
    /// Every face, in atlas order.
    pub faces: &'a [ShadowFace],
    /// Per light: (first face, face count).
    pub light_faces: &'a [[u32; 2]],
    /// The faces' visibility words back to back.
    pub atlas: &'a [u64],
    /// Percentage-closer filtering radius.
    pub pcf: u32,
}

impl Shadows<'_> {
    /// As `shadow_face_at`: the face of light i (`light`) whose view holds world point `world`;
    /// `None` for a light without a shadow map.
    pub(crate) fn face_at(&self, i: usize, light: &GpuLight, world: Vec3) -> Option<&ShadowFace> {
        let [first, count] = self.light_faces.get(i).copied().unwrap_or([0, 0]);
        let d = world - Vec3::from(light.position);
        (count > 0).then(|| &self.faces[(first + shadow_face_index(count, d)) as usize])
    }
}

const SHADOW_BIAS_TEXELS: f32 = 1.0;
const SHADOW_SLOPE_TEXELS: f32 = 2.0;
const SHADOW_NORMAL_OFFSET_TEXELS: f32 = 1.0;

fn shadow_face_index(count: u32, d: Vec3) -> u32 {
    if count < 6 {
        return 0;
    }
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        return if d.x > 0.0 { 0 } else { 1 };
    }
    if a.y >= a.z {
        return if d.y > 0.0 { 2 } else { 3 };
    }
    if d.z > 0.0 { 4 } else { 5 }
}

/// As `shadow` in `wgsl/direct.wgsl`: the lit fraction of the PCF taps.
pub fn shadow(sh: &Shadows, i: usize, light: &GpuLight, world: Vec3, n: Vec3, l: Vec3) -> f32 {
    let Some(f) = sh.face_at(i, light, world) else { return 1.0 };
    let texel = if f.ortho != 0 {
        f.texel
    } else {
        f.texel * (-mat_mul(&f.view, world.extend(1.0).to_array()).z).max(0.0)
    };
    let p = world + n * (texel * SHADOW_NORMAL_OFFSET_TEXELS);
    let vp = mat_mul(&f.view, p.extend(1.0).to_array());
    let c = mat_mul(&f.proj, vp.to_array());
    if c.w.is_nan() || c.w <= 0.0 {
        return 1.0;
    }
    let res = f.resolution as f32;
    let uv = clip_to_pixel(c, Vec2::splat(res));
    let depth = -vp.z;
    let cos_theta = n.dot(l).clamp(0.05, 1.0);
    let tan_theta = (1.0 - cos_theta * cos_theta).sqrt() / cos_theta;
    let bias = texel * (SHADOW_BIAS_TEXELS + SHADOW_SLOPE_TEXELS * tan_theta.min(10.0));
    let center = uv.floor();
    let k = sh.pcf as i32;
    let mut lit = 0.0;
    for dy in -k..=k {
        for dx in -k..=k {
            let tx = (center.x as i32 + dx).clamp(0, f.resolution as i32 - 1) as u32;
            let ty = (center.y as i32 + dy).clamp(0, f.resolution as i32 - 1) as u32;
            let word = sh.atlas[(f.offset + ty * f.resolution + tx) as usize];
            let stored = (word >> 32) as u32;
            if stored == u32::MAX || depth <= f32::from_bits(stored) + bias {
                lit += 1.0;
            }
        }
    }
    let side = (2 * k + 1) as f32;
    lit / (side * side)
}
