//! CPU reference of `wgsl/resolve.wgsl`: visibility words to G-buffer samples.

use glam::{Vec2, Vec3, Vec4Swizzles};

use crate::cpu::frame::{mat_mul, view_position};
use crate::frame::FrameUniform;
use crate::gbuffer::{GSample, VIS_EMPTY};
use crate::scene::{Material, Scene, Texture};

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

fn texel(t: &Texture, x: u32, y: u32, srgb: bool) -> Vec3 {
    let i = ((y * t.width + x) * 4) as usize;
    Vec3::from_array(std::array::from_fn(|k| {
        let c = f32::from(t.rgba8[i + k]) / 255.0;
        if srgb { srgb_to_linear(c) } else { c }
    }))
}

/// As `sample_texture`: bilinear, repeating; sRGB texels decoded before they are filtered.
pub(crate) fn sample_texture(t: &Texture, uv: Vec2, srgb: bool) -> Vec3 {
    let size = Vec2::new(t.width as f32, t.height as f32);
    let p = uv.fract_gl() * size - 0.5;
    let f = p.fract_gl();
    let (w, h) = (t.width as i32, t.height as i32);
    let i0 = p.floor();
    let x0 = ((i0.x as i32 % w + w) % w) as u32;
    let y0 = ((i0.y as i32 % h + h) % h) as u32;
    let x1 = (x0 + 1) % t.width;
    let y1 = (y0 + 1) % t.height;
    let top = texel(t, x0, y0, srgb).lerp(texel(t, x1, y0, srgb), f.x);
    let bottom = texel(t, x0, y1, srgb).lerp(texel(t, x1, y1, srgb), f.x);
    top.lerp(bottom, f.y)
}

/// What a material gives a surface point at texture coordinate `uv`: its factors times its
/// textures, bounded (as the resolve does), the reflectivity taken per texel as
/// metallic x (1 - roughness) where a metallic-roughness texture is given.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MaterialSample {
    pub base_color: Vec3,
    pub emissive: Vec3,
    pub roughness: f32,
    pub metallic: f32,
    pub reflectivity: f32,
}

pub(crate) fn material_at(scene: &Scene, m: &Material, uv: Vec2) -> MaterialSample {
    let texture = |t: Option<u32>| {
        t.and_then(|t| scene.textures.get(t as usize))
            .filter(|_| uv.abs().cmplt(Vec2::splat(1e6)).all())
    };
    let mut base = m.base_color.xyz();
    if let Some(t) = texture(m.base_color_texture) {
        base *= sample_texture(t, uv, true);
    }
    let mut emissive = m.emissive;
    if let Some(t) = texture(m.emissive_texture) {
        emissive *= sample_texture(t, uv, true);
    }
    let mut roughness = m.roughness.clamp(0.0, 1.0);
    let mut metallic = m.metallic.clamp(0.0, 1.0);
    let mut reflectivity = m.reflectivity.clamp(0.0, 1.0);
    if let Some(t) = texture(m.metallic_roughness_texture) {
        let mr = sample_texture(t, uv, false);
        roughness = (roughness * mr.y).clamp(0.0, 1.0);
        metallic = (metallic * mr.z).clamp(0.0, 1.0);
        reflectivity = metallic * (1.0 - roughness);
    }
    MaterialSample {
        base_color: base.clamp(Vec3::ZERO, Vec3::ONE),
        emissive: emissive.max(Vec3::ZERO),
        roughness,
        metallic,
        reflectivity,
    }
}

/// The G-buffer sample of visibility word `word` at pixel (x, y).
pub fn resolve_pixel(f: &FrameUniform, scene: &Scene, word: u64, x: u32, y: u32) -> GSample {
    let id = word as u32;
    if word == VIS_EMPTY || id as usize >= scene.triangles.len() {
        return GSample::default();
    }
    let d = f32::from_bits((word >> 32) as u32);
    let [i0, i1, i2] = scene.triangles[id as usize].map(|i| i as usize);
    let (w0, w1, w2) = (scene.positions[i0], scene.positions[i1], scene.positions[i2]);
    let a = mat_mul(&f.view, w0.extend(1.0).to_array()).xyz();
    let b = mat_mul(&f.view, w1.extend(1.0).to_array()).xyz();
    let c = mat_mul(&f.view, w2.extend(1.0).to_array()).xyz();
    let target = view_position(f, Vec2::new(x as f32 + 0.5, y as f32 + 0.5), d);
    let (origin, dir) = if f.ortho != 0 {
        (Vec3::new(target.x, target.y, 0.0), Vec3::NEG_Z)
    } else {
        (Vec3::ZERO, target)
    };
    let (e1, e2) = (b - a, c - a);
    let pv = dir.cross(e2);
    let det = e1.dot(pv);
    let mut bary = Vec3::splat(1.0 / 3.0);
    if det.abs() > 1e-30 {
        let tv = origin - a;
        let u = tv.dot(pv) / det;
        let v = dir.dot(tv.cross(e1)) / det;
        let raw = Vec3::new(1.0 - u - v, u, v).clamp(Vec3::ZERO, Vec3::ONE);
        let sum = raw.x + raw.y + raw.z;
        if sum > 0.0 {
            bary = raw / sum;
        }
    }
    let world = w0 * bary.x + w1 * bary.y + w2 * bary.z;
    let mut geo = (w1 - w0).cross(w2 - w0);
    let gl = geo.length();
    let eye = mat_mul(&f.inv_view, origin.extend(1.0).to_array()).xyz();
    let to_eye = if f.ortho != 0 {
        mat_mul(&f.inv_view, [0.0, 0.0, 1.0, 0.0]).xyz().normalize()
    } else {
        (eye - world).normalize()
    };
    geo = if gl > 0.0 && gl <= 3e38 { geo / gl } else { to_eye };
    let n_interp =
        scene.normals[i0] * bary.x + scene.normals[i1] * bary.y + scene.normals[i2] * bary.z;
    let nl = n_interp.length();
    let mut n = if nl > 1e-12 && nl <= 3e38 { n_interp / nl } else { geo };
    if geo.dot(to_eye) < 0.0 {
        geo = -geo;
        n = -n;
    }
    if n.dot(to_eye) < 0.0 {
        n = (n - to_eye * (n.dot(to_eye) - 1e-3)).normalize();
    }
    if n.dot(n).is_nan() || n.dot(n) <= 0.5 {
        n = geo;
    }
    let mid = scene.triangle_materials[id as usize];
    let mut s = GSample { depth: d, normal: n, material: mid, ..GSample::default() };
    if let Some(m) = scene.materials.get(mid as usize) {
        let uv = scene.uvs[i0] * bary.x + scene.uvs[i1] * bary.y + scene.uvs[i2] * bary.z;
        let at = material_at(scene, m, uv);
        s.base_color = at.base_color;
        s.roughness = at.roughness;
        s.metallic = at.metallic;
        s.reflectivity = at.reflectivity;
        s.emissive = at.emissive;
    }
    let pc = mat_mul(&f.prev_view_proj, world.extend(1.0).to_array());
    if pc.w > 1e-20 {
        let prev = Vec2::new(
            (pc.x / pc.w * 0.5 + 0.5) * f.width as f32,
            (0.5 - pc.y / pc.w * 0.5) * f.height as f32,
        );
        let motion = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - prev;
        if motion.abs().cmplt(Vec2::splat(1e30)).all() {
            s.motion = motion;
        }
    }
    s
}

/// Resolves a whole visibility buffer.
pub fn resolve(f: &FrameUniform, scene: &Scene, vis: &[u64]) -> Vec<GSample> {
    (0..f.height)
        .flat_map(|y| (0..f.width).map(move |x| (x, y)))
        .map(|(x, y)| resolve_pixel(f, scene, vis[(y * f.width + x) as usize], x, y))
        .collect()
}
