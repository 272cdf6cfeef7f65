//! CPU reference of `wgsl/resolve.wgsl`: visibility words to G-buffer samples.

use glam::{Vec2, Vec3, Vec4, Vec4Swizzles};

use crate::cpu::frame::{clip_to_pixel, image_size, mat_mul, toward_camera, view_position};
use crate::frame::FrameUniform;
use crate::gbuffer::{GSample, VIS_EMPTY};
use crate::scene::{Filter, Material, Scene, Texture, TextureRef, Wrap};

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// As `texel`: rgb decoded from sRGB when `srgb` is set, alpha always linear.
fn texel(t: &Texture, x: u32, y: u32, srgb: bool) -> Vec4 {
    let i = ((y * t.width + x) * 4) as usize;
    Vec4::from_array(std::array::from_fn(|k| {
        let c = f32::from(t.rgba8[i + k]) / 255.0;
        if srgb && k < 3 { srgb_to_linear(c) } else { c }
    }))
}

/// As `wrap_reduce`: a coordinate brought into one period of its wrap mode.
fn wrap_reduce(u: f32, mode: Wrap) -> f32 {
    match mode {
        Wrap::ClampToEdge => u.clamp(0.0, 1.0),
        Wrap::MirroredRepeat => u - 2.0 * (u * 0.5).floor(),
        Wrap::Repeat => u - u.floor(),
    }
}

/// As `wrap_index`: texel index `i` (in [-1, 2n]) as the wrap mode reads it.
fn wrap_index(i: i32, n: i32, mode: Wrap) -> u32 {
    match mode {
        Wrap::ClampToEdge => i.clamp(0, n - 1) as u32,
        Wrap::MirroredRepeat if i < 0 => 0,
        Wrap::MirroredRepeat if i < n => i as u32,
        Wrap::MirroredRepeat if i - n < n => (n - 1 - (i - n)) as u32,
        Wrap::MirroredRepeat => 0,
        Wrap::Repeat => ((i % n + n) % n) as u32,
    }
}

/// As `sample_texture`: texture `t` at `uv` (already transformed), wrapped and filtered as
/// `slot` says; sRGB texels decoded before they are filtered.
pub(crate) fn sample_texture(t: &Texture, slot: &TextureRef, uv: Vec2, srgb: bool) -> Vec3 {
    sample_texture_rgba(t, slot, uv, srgb).xyz()
}

/// [`sample_texture`] with the alpha channel (linear).
pub(crate) fn sample_texture_rgba(t: &Texture, slot: &TextureRef, uv: Vec2, srgb: bool) -> Vec4 {
    let size = Vec2::new(t.width as f32, t.height as f32);
    let r = Vec2::new(wrap_reduce(uv.x, slot.wrap_s), wrap_reduce(uv.y, slot.wrap_t));
    let (w, h) = (t.width as i32, t.height as i32);
    if slot.filter == Filter::Nearest {
        let i = (r * size).floor();
        let (x, y) =
            (wrap_index(i.x as i32, w, slot.wrap_s), wrap_index(i.y as i32, h, slot.wrap_t));
        return texel(t, x, y, srgb);
    }
    let p = r * size - 0.5;
    let f = p - p.floor();
    let i0 = p.floor();
    let (ix, iy) = (i0.x as i32, i0.y as i32);
    let x0 = wrap_index(ix, w, slot.wrap_s);
    let y0 = wrap_index(iy, h, slot.wrap_t);
    let x1 = wrap_index(ix + 1, w, slot.wrap_s);
    let y1 = wrap_index(iy + 1, h, slot.wrap_t);
    let top = texel(t, x0, y0, srgb).lerp(texel(t, x1, y0, srgb), f.x);
    let bottom = texel(t, x0, y1, srgb).lerp(texel(t, x1, y1, srgb), f.x);
    top.lerp(bottom, f.y)
}

/// A point inside a triangle: the scene, the triangle's vertex indices and the point's
/// barycentrics.
#[derive(Clone, Copy)]
pub(crate) struct Corners<'a> {
    pub scene: &'a Scene,
    pub tri: [usize; 3],
    pub bary: Vec3,
}

impl Corners<'_> {
    /// As `vertex_uv`: vertex `i`'s coordinates in set 0 or 1 (zero where there are none).
    fn vertex_uv(&self, i: usize, set: u32) -> Vec2 {
        let uvs = if set == 0 { &self.scene.uvs } else { &self.scene.uvs1 };
        uvs.get(i).copied().filter(|t| t.is_finite()).unwrap_or(Vec2::ZERO)
    }

    fn interpolate<T>(&self, f: impl Fn(usize) -> T) -> T
    where
        T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        let [a, b, c] = self.tri;
        f(a) * self.bary.x + f(b) * self.bary.y + f(c) * self.bary.z
    }

    /// As `slot_uv`: the point's coordinates as `slot` reads them.
    fn slot_uv(&self, slot: &TextureRef) -> Vec2 {
        let uv = self.interpolate(|i| self.vertex_uv(i, slot.tex_coord));
        let m = slot.transform;
        // Summed as the kernel sums (dot of the rows, then the translation).
        Vec2::new(
            m.matrix2.x_axis.x * uv.x + m.matrix2.y_axis.x * uv.y + m.translation.x,
            m.matrix2.x_axis.y * uv.x + m.matrix2.y_axis.y * uv.y + m.translation.y,
        )
    }

    /// As `read_slot`: the texture and coordinates `slot` reads at this point, when it reads one
    /// (the texture exists and the coordinates are finite and moderate).
    fn read_slot(&self, slot: Option<TextureRef>) -> Option<(&Texture, TextureRef, Vec2)> {
        let slot = slot?;
        let t = self.scene.textures.get(slot.texture as usize)?;
        let uv = self.slot_uv(&slot);
        uv.abs().cmplt(Vec2::splat(1e6)).all().then_some((t, slot, uv))
    }
}

/// What a material gives a surface point: its factors times its textures, bounded (as the
/// resolve does), the reflectivity taken per texel as metallic x (1 - roughness) where a
/// metallic-roughness texture is given.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MaterialSample {
    pub base_color: Vec3,
    pub emissive: Vec3,
    pub roughness: f32,
    pub metallic: f32,
    pub reflectivity: f32,
    pub occlusion: f32,
}

pub(crate) fn material_at(m: &Material, at: &Corners<'_>) -> MaterialSample {
    let mut base = m.base_color.xyz();
    if let Some((t, slot, uv)) = at.read_slot(m.base_color_texture) {
        base *= sample_texture(t, &slot, uv, true);
    }
    let mut emissive = m.emissive;
    if let Some((t, slot, uv)) = at.read_slot(m.emissive_texture) {
        emissive *= sample_texture(t, &slot, uv, true);
    }
    let mut roughness = m.roughness.clamp(0.0, 1.0);
    let mut metallic = m.metallic.clamp(0.0, 1.0);
    let mut reflectivity = m.reflectivity.clamp(0.0, 1.0);
    if let Some((t, slot, uv)) = at.read_slot(m.metallic_roughness_texture) {
        let mr = sample_texture(t, &slot, uv, false);
        roughness = (roughness * mr.y).clamp(0.0, 1.0);
        metallic = (metallic * mr.z).clamp(0.0, 1.0);
        reflectivity = metallic * (1.0 - roughness);
    }
    let mut occlusion = 1.0;
    if let Some((t, slot, uv)) = at.read_slot(m.occlusion_texture) {
        let strength = m.occlusion_strength.clamp(0.0, 1.0);
        occlusion =
            (1.0 + strength * (sample_texture(t, &slot, uv, false).x - 1.0)).clamp(0.0, 1.0);
    }
    MaterialSample {
        base_color: base.clamp(Vec3::ZERO, Vec3::ONE),
        emissive: emissive.max(Vec3::ZERO),
        roughness,
        metallic,
        reflectivity,
        occlusion,
    }
}

/// As `normal_mapped`: the unit normal `n` turned by material `m`'s normal texture at the
/// point (the frame of the interpolated vertex tangents, or where they are missing the
/// triangle's own texture-space frame); `n` where `m` has no normal texture or no frame exists.
pub(crate) fn normal_mapped(m: &Material, at: &Corners<'_>, n: Vec3) -> Vec3 {
    let Some((texture, slot, uv)) = at.read_slot(m.normal_texture) else { return n };
    let c = sample_texture(texture, &slot, uv, false);
    let scene = at.scene;
    let tangent = |i: usize| scene.tangents.get(i).copied().filter(|t| t.is_finite());
    let t0 = tangent(at.tri[0]).unwrap_or(Vec4::ZERO);
    let mut t = at.interpolate(|i| tangent(i).unwrap_or(Vec4::ZERO).xyz());
    let mut sign = if t0.w < 0.0 { -1.0 } else { 1.0 };
    if !(t.dot(t) > 1e-12 && t.dot(t) <= 3e38) {
        let [i0, i1, i2] = at.tri;
        let a = at.vertex_uv(i0, slot.tex_coord);
        let (d1, d2) = (at.vertex_uv(i1, slot.tex_coord) - a, at.vertex_uv(i2, slot.tex_coord) - a);
        let p = &scene.positions;
        let (e1, e2) = (p[i1] - p[i0], p[i2] - p[i0]);
        let r = d1.x * d2.y - d2.x * d1.y;
        if r.is_nan() || r.abs() <= 1e-20 {
            return n;
        }
        t = (e1 * d2.y - e2 * d1.y) / r;
        let b = (e2 * d1.x - e1 * d2.x) / r;
        sign = if n.cross(t).dot(b) < 0.0 { 1.0 } else { -1.0 };
    }
    t -= n * n.dot(t);
    let tl = t.length();
    if !(tl > 1e-12 && tl <= 3e38) {
        return n;
    }
    t /= tl;
    let b = n.cross(t) * sign;
    let v = c * 2.0 - 1.0;
    let scale = m.normal_scale;
    let mapped = t * (v.x * scale) + b * (v.y * scale) + n * v.z;
    let ml = mapped.length();
    if !(ml > 1e-12 && ml <= 3e38) {
        return n;
    }
    mapped / ml
}

/// As `pixel_ray`: the view-space ray (origin, direction) through the centre of pixel (x, y)
/// towards view depth `d`.
pub(crate) fn pixel_ray(f: &FrameUniform, x: u32, y: u32, d: f32) -> (Vec3, Vec3) {
    let target = view_position(f, Vec2::new(x as f32 + 0.5, y as f32 + 0.5), d);
    if f.ortho != 0 {
        (Vec3::new(target.x, target.y, 0.0), Vec3::NEG_Z)
    } else {
        (Vec3::ZERO, target)
    }
}

/// As `ray_barycentrics`: where the ray meets the view-space triangle (a, b, c), clamped.
pub(crate) fn ray_barycentrics(origin: Vec3, dir: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
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
    bary
}

/// As `ray_triangle` in `wgsl/shared/barycentric.wgsl`: where the ray `origin + t dir` meets the
/// triangle (a, b, c), `(t, barycentrics)`, or `None` outside it by more than `slack`.
pub(crate) fn ray_triangle(
    origin: Vec3,
    dir: Vec3,
    [a, b, c]: [Vec3; 3],
    slack: f32,
) -> Option<(f32, Vec3)> {
    let (e1, e2) = (b - a, c - a);
    let pv = dir.cross(e2);
    let det = e1.dot(pv);
    if det.is_nan() || det.abs() <= 1e-30 {
        return None;
    }
    let tv = origin - a;
    let qv = tv.cross(e1);
    let u = tv.dot(pv) / det;
    let v = dir.dot(qv) / det;
    let bary = Vec3::new(1.0 - u - v, u, v);
    if !bary.cmpge(Vec3::splat(-slack)).all() {
        return None;
    }
    let raw = bary.clamp(Vec3::ZERO, Vec3::ONE);
    Some((e2.dot(qv) / det, raw / (raw.x + raw.y + raw.z)))
}

/// As `triangle_opacity`: the opacity of triangle `id` of `scene` where the ray through the
/// centre of pixel (x, y) meets it at view depth `d` (1 for a triangle without a material).
pub(crate) fn triangle_opacity(
    f: &FrameUniform,
    scene: &Scene,
    id: usize,
    x: u32,
    y: u32,
    d: f32,
) -> f32 {
    let Some(m) = scene.triangle_materials.get(id).and_then(|&m| scene.materials.get(m as usize))
    else {
        return 1.0;
    };
    let tri = scene.triangles[id].map(|i| i as usize);
    let view = |i: usize| mat_mul(&f.view, scene.positions[i].extend(1.0).to_array()).xyz();
    let (origin, dir) = pixel_ray(f, x, y, d);
    let bary = ray_barycentrics(origin, dir, view(tri[0]), view(tri[1]), view(tri[2]));
    material_opacity(m, &Corners { scene, tri, bary })
}

/// As `material_opacity`: the material's opacity at a point (its base colour's alpha times its
/// base-colour texture's), NaN read as 0.
pub(crate) fn material_opacity(m: &Material, at: &Corners<'_>) -> f32 {
    let mut a = m.base_color.w;
    if let Some((t, slot, uv)) = at.read_slot(m.base_color_texture) {
        a *= sample_texture_rgba(t, &slot, uv, true).w;
    }
    unit(a)
}

/// As `unit`: `x` limited to [0, 1], NaN read as 0.
pub(crate) fn unit(x: f32) -> f32 {
    if x >= 0.0 { x.min(1.0) } else { 0.0 }
}

/// As `stored_depth`: the view depth `d` as the frame's position encoding holds it
/// ([`PositionEncoding`](crate::PositionEncoding), in `f.flags`).
pub fn stored_depth(f: &FrameUniform, d: f32) -> f32 {
    use crate::frame::{FRAME_POSITION_SCREEN_U16, FRAME_POSITION_VIEW_F16};
    if f.flags & FRAME_POSITION_VIEW_F16 != 0 {
        return half::f16::from_f32(d.min(65504.0)).to_f32();
    }
    if f.flags & FRAME_POSITION_SCREEN_U16 != 0 {
        let c = mat_mul(&f.proj, [0.0, 0.0, -d, 1.0]);
        let q = ((c.z / c.w).clamp(0.0, 1.0) * 65535.0).round_ties_even() / 65535.0;
        let p = &f.proj;
        let back = (q * p[3][3] - p[3][2]) / (q * p[2][3] - p[2][2]);
        return if back > 0.0 && back <= 3.0e38 { back } else { 3.0e38 };
    }
    d
}

/// As `surface_sample` in `wgsl/shared/surface.wgsl`: the surface of triangle `id` (vertex
/// indices `tri`) at barycentrics `bary`, turned to face the unit world direction `to_viewer`:
/// normal and material terms (no depth, no motion).
pub(crate) fn surface_sample(
    scene: &Scene,
    id: u32,
    [i0, i1, i2]: [usize; 3],
    bary: Vec3,
    to_viewer: Vec3,
) -> GSample {
    let (w0, w1, w2) = (scene.positions[i0], scene.positions[i1], scene.positions[i2]);
    let mut geo = (w1 - w0).cross(w2 - w0);
    let gl = geo.length();
    geo = if gl > 0.0 && gl <= 3e38 { geo / gl } else { to_viewer };
    let n_interp =
        scene.normals[i0] * bary.x + scene.normals[i1] * bary.y + scene.normals[i2] * bary.z;
    let nl = n_interp.length();
    let mut n = if nl > 1e-12 && nl <= 3e38 { n_interp / nl } else { geo };
    let at = Corners { scene, tri: [i0, i1, i2], bary };
    let mid = scene.triangle_materials[id as usize];
    if let Some(m) = scene.materials.get(mid as usize) {
        n = normal_mapped(m, &at, n);
    }
    if geo.dot(to_viewer) < 0.0 {
        geo = -geo;
        n = -n;
    }
    if n.dot(to_viewer) < 0.0 {
        n = (n - to_viewer * (n.dot(to_viewer) - 1e-3)).normalize();
    }
    if n.dot(n).is_nan() || n.dot(n) <= 0.5 {
        n = geo;
    }
    let mut s = GSample { normal: n, material: mid, ..GSample::default() };
    if let Some(m) = scene.materials.get(mid as usize) {
        let v = material_at(m, &at);
        s.base_color = v.base_color;
        s.roughness = v.roughness;
        s.metallic = v.metallic;
        s.reflectivity = v.reflectivity;
        s.occlusion = v.occlusion;
        s.emissive = v.emissive;
    }
    s
}

/// The G-buffer sample of visibility word `word` at pixel (x, y), the geometry taken as still.
pub fn resolve_pixel(f: &FrameUniform, scene: &Scene, word: u64, x: u32, y: u32) -> GSample {
    resolve_pixel_moved(f, scene, None, word, x, y)
}

/// [`resolve_pixel`] with each vertex's position in the last frame (`previous`, one per
/// position), read for the motion vector when `f.flags` has
/// [`FRAME_OBJECT_MOTION`](crate::frame::FRAME_OBJECT_MOTION), as the kernel reads its
/// previous-positions buffer.
pub fn resolve_pixel_moved(
    f: &FrameUniform,
    scene: &Scene,
    previous: Option<&[Vec3]>,
    word: u64,
    x: u32,
    y: u32,
) -> GSample {
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
    let (origin, dir) = pixel_ray(f, x, y, d);
    let bary = ray_barycentrics(origin, dir, a, b, c);
    let world = w0 * bary.x + w1 * bary.y + w2 * bary.z;
    let mut s = surface_sample(scene, id, [i0, i1, i2], bary, toward_camera(f, world));
    s.depth = stored_depth(f, d);
    let was = match previous {
        Some(last)
            if f.flags & crate::frame::FRAME_OBJECT_MOTION != 0
                && last.len() >= scene.positions.len() =>
        {
            last[i0] * bary.x + last[i1] * bary.y + last[i2] * bary.z
        }
        _ => world,
    };
    let pc = mat_mul(&f.prev_view_proj, was.extend(1.0).to_array());
    let nc = mat_mul(&f.view_proj, world.extend(1.0).to_array());
    if pc.w > 1e-20 && nc.w > 1e-20 {
        let motion = clip_to_pixel(nc, image_size(f)) - clip_to_pixel(pc, image_size(f));
        if motion.abs().cmplt(Vec2::splat(1e30)).all() {
            s.motion = motion;
        }
    }
    s
}

/// Resolves a whole visibility buffer, the geometry taken as still.
pub fn resolve(f: &FrameUniform, scene: &Scene, vis: &[u64]) -> Vec<GSample> {
    resolve_moved(f, scene, None, vis)
}

/// Resolves a whole visibility buffer as [`resolve_pixel_moved`] does each pixel.
pub fn resolve_moved(
    f: &FrameUniform,
    scene: &Scene,
    previous: Option<&[Vec3]>,
    vis: &[u64],
) -> Vec<GSample> {
    (0..f.height)
        .flat_map(|y| (0..f.width).map(move |x| (x, y)))
        .map(|(x, y)| {
            resolve_pixel_moved(f, scene, previous, vis[(y * f.width + x) as usize], x, y)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The wrap modes and filters on a 2x1 texture, black then white: texel centres at u = 1/4
    /// and 3/4.
    #[test]
    fn wrap_modes_and_filters_read_the_texels_the_sampler_names() {
        let t = Texture { width: 2, height: 1, rgba8: vec![0, 0, 0, 255, 255, 255, 255, 255] };
        let read = |wrap_s, filter, u: f32| {
            let slot = TextureRef { wrap_s, filter, ..TextureRef::new(0) };
            sample_texture(&t, &slot, Vec2::new(u, 0.5), false).x
        };
        let near = |a: f32, b: f32| (a - b).abs() < 1e-6;
        // Repeat: 1.25 reads as 0.25; halfway between the last and the first texel, the mean.
        assert!(near(read(Wrap::Repeat, Filter::Linear, 1.25), 0.0));
        assert!(near(read(Wrap::Repeat, Filter::Linear, 1.0), 0.5));
        // Clamp: past either edge the edge texel.
        assert!(near(read(Wrap::ClampToEdge, Filter::Linear, 1.7), 1.0));
        assert!(near(read(Wrap::ClampToEdge, Filter::Linear, -3.0), 0.0));
        assert!(near(read(Wrap::ClampToEdge, Filter::Linear, 1.0), 1.0));
        // Mirrored: 1.25 reads as 0.75, 2.25 as 0.25; at 1.0 the white texel meets its mirror.
        assert!(near(read(Wrap::MirroredRepeat, Filter::Linear, 1.25), 1.0));
        assert!(near(read(Wrap::MirroredRepeat, Filter::Linear, 2.25), 0.0));
        assert!(near(read(Wrap::MirroredRepeat, Filter::Linear, 1.0), 1.0));
        assert!(near(read(Wrap::MirroredRepeat, Filter::Linear, -0.25), 0.0));
        // Nearest: no blend between texels.
        assert!(near(read(Wrap::Repeat, Filter::Nearest, 0.49), 0.0));
        assert!(near(read(Wrap::Repeat, Filter::Nearest, 0.51), 1.0));
        assert!(near(read(Wrap::Repeat, Filter::Linear, 0.5), 0.5));
    }
}
