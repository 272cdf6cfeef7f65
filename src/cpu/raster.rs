//! CPU reference of `wgsl/raster.wgsl`: the same clipping, fixed-point snapping, exact edge
//! functions (i64 here, emulated 64-bit there), top-left rule and depth interpolation.

use glam::Vec3;

use crate::cpu::frame::{clip_to_pixel, image_size, mat_mul};
use crate::cpu::resolve::{triangle_opacity, unit};
use crate::frame::FrameUniform;
use crate::gbuffer::{VIS_EMPTY, vis_pack};
use crate::scene::AlphaMode;

const SUBPIXEL: i32 = 256;
const SMALL_EXTENT: i32 = 16;

/// The triangles the rasterizer reads: positions, indices and which triangles are double-sided.
pub struct RasterInput<'a> {
    /// Vertex positions.
    pub positions: &'a [Vec3],
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
    /// Per triangle: both faces visible.
    pub double_sided: &'a [bool],
    /// The scene whose materials' alpha modes apply (blended triangles left out of the opaque
    /// layers, masked ones tested), or `None`: every triangle is opaque.
    pub scene: Option<&'a crate::Scene>,
}

impl<'a> RasterInput<'a> {
    /// The triangles of `scene`; `double_sided` from [`double_sided_triangles`].
    pub fn new(scene: &'a crate::Scene, double_sided: &'a [bool]) -> Self {
        RasterInput {
            positions: &scene.positions,
            triangles: &scene.triangles,
            double_sided,
            scene: Some(scene),
        }
    }
}

/// What a raster draws of a triangle (`draw_kind` in the shader).
#[derive(Clone, Copy, Debug, PartialEq)]
enum DrawKind {
    None,
    All,
    /// The fragments whose opacity reaches the cutoff.
    Tested(f32),
}

/// As `draw_kind`: what the opaque raster (or, with `peel`, a peel) draws of triangle `t`.
fn draw_kind(input: &RasterInput, t: usize, peel: bool) -> DrawKind {
    let Some(scene) = input.scene else { return DrawKind::All };
    let Some(m) = scene.triangle_materials.get(t).and_then(|&m| scene.materials.get(m as usize))
    else {
        return DrawKind::All;
    };
    match (m.alpha_mode, peel) {
        (AlphaMode::Blend, true) => DrawKind::All,
        (_, true) | (AlphaMode::Blend, false) => DrawKind::None,
        (AlphaMode::Opaque, false) => DrawKind::All,
        (AlphaMode::Mask { cutoff }, false) => {
            if m.base_color_texture.is_some() {
                DrawKind::Tested(cutoff)
            } else if unit(m.base_color.w) >= cutoff {
                DrawKind::All
            } else {
                DrawKind::None
            }
        }
    }
}

/// Calls `fragment(x, y, view depth, triangle)` for every fragment [`rasterize`] gives that the
/// opaque raster (or, with `peel`, a peel) draws: the triangle's material allows it and, for a
/// masked one with a texture, its opacity there reaches the cutoff.
fn rasterize_drawn(
    f: &FrameUniform,
    input: &RasterInput,
    peel: bool,
    mut fragment: impl FnMut(u32, u32, f32, u32),
) {
    let kinds: Vec<DrawKind> =
        (0..input.triangles.len()).map(|t| draw_kind(input, t, peel)).collect();
    rasterize(f, input, |x, y, d, t| {
        let drawn = match kinds[t as usize] {
            DrawKind::None => false,
            DrawKind::All => true,
            DrawKind::Tested(cutoff) => input
                .scene
                .is_some_and(|scene| triangle_opacity(f, scene, t as usize, x, y, d) >= cutoff),
        };
        if drawn {
            fragment(x, y, d, t);
        }
    });
}

/// Per triangle of `scene`: whether its material is double-sided.
pub fn double_sided_triangles(scene: &crate::Scene) -> Vec<bool> {
    scene
        .triangle_materials
        .iter()
        .map(|&m| scene.materials.get(m as usize).is_some_and(|m| m.double_sided))
        .collect()
}

type ClipVertex = [f32; 4];

fn finite(x: f32) -> bool {
    x.abs() <= 3.0e38
}

fn transform(f: &FrameUniform, p: Vec3) -> ClipVertex {
    let v = mat_mul(&f.view, [p.x, p.y, p.z, 1.0]).to_array();
    let c = mat_mul(&f.proj, v).to_array();
    [c[0], c[1], c[3], -v[2]]
}

fn plane_distance(f: &FrameUniform, plane: u32, v: ClipVertex) -> f32 {
    match plane {
        0 => v[3] - f.near,
        1 => f.guard_x * v[2] - v[0],
        2 => f.guard_x * v[2] + v[0],
        3 => f.guard_y * v[2] - v[1],
        _ => f.guard_y * v[2] + v[1],
    }
}

fn lerp4(a: ClipVertex, b: ClipVertex, t: f32) -> ClipVertex {
    std::array::from_fn(|i| a[i] + (b[i] - a[i]) * t)
}

/// Whether triangle `t` must not be drawn: an index past the vertices or a non-finite position
/// (`rejection` in the shader, which also checks the material id against the material count).
fn rejected(input: &RasterInput, t: usize) -> bool {
    input.triangles[t]
        .iter()
        .any(|&i| input.positions.get(i as usize).is_none_or(|p| !p.is_finite()))
}

/// The clipped polygon of triangle `t` (empty when nothing is left).
fn clip_triangle(f: &FrameUniform, input: &RasterInput, t: usize) -> Vec<ClipVertex> {
    let tri = input.triangles[t];
    let mut poly: Vec<ClipVertex> =
        tri.iter().map(|&i| transform(f, input.positions[i as usize])).collect();
    let mut all_inside = true;
    for v in &poly {
        if !v.iter().all(|&x| finite(x)) {
            return Vec::new();
        }
        for plane in 0..5 {
            all_inside = all_inside && plane_distance(f, plane, *v) >= 0.0;
        }
    }
    if all_inside {
        return poly;
    }
    for plane in 0..5 {
        let n = poly.len();
        let mut out = Vec::with_capacity(n + 1);
        for i in 0..n {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let (da, db) = (plane_distance(f, plane, a), plane_distance(f, plane, b));
            if da >= 0.0 {
                out.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                out.push(if da >= 0.0 {
                    lerp4(a, b, da / (da - db))
                } else {
                    lerp4(b, a, db / (db - da))
                });
            }
        }
        if out.len() < 3 {
            return Vec::new();
        }
        poly = out;
    }
    poly
}

fn snap(f: &FrameUniform, v: ClipVertex) -> [i32; 2] {
    let px = (v[0] / v[2] * 0.5 + 0.5) * f.width as f32;
    let py = (0.5 - v[1] / v[2] * 0.5) * f.height as f32;
    [
        (px * SUBPIXEL as f32).round_ties_even() as i32,
        (py * SUBPIXEL as f32).round_ties_even() as i32,
    ]
}

fn edge(a: [i32; 2], b: [i32; 2], p: [i32; 2]) -> i64 {
    i64::from(b[0] - a[0]) * i64::from(p[1] - a[1])
        - i64::from(b[1] - a[1]) * i64::from(p[0] - a[0])
}

/// A set-up sub-triangle, as `struct Setup` in the WGSL.
#[derive(Clone, Copy, Debug)]
struct Setup {
    v: [[i32; 2]; 3],
    r: [f32; 3],
    q: [f32; 3],
    lo: [i32; 2],
    hi: [i32; 2],
    small: bool,
}

fn setup(
    f: &FrameUniform,
    input: &RasterInput,
    t: usize,
    poly: &[ClipVertex],
    k: usize,
) -> Option<Setup> {
    let c0 = poly[0];
    let (mut c1, mut c2) = (poly[k + 1], poly[k + 2]);
    let mut v = [snap(f, c0), snap(f, c1), snap(f, c2)];
    let o = edge(v[0], v[1], v[2]).signum();
    if o == 0 {
        return None;
    }
    let double_sided = input.double_sided.get(t).copied().unwrap_or(false);
    if o > 0 && !double_sided {
        return None;
    }
    if o < 0 {
        v.swap(1, 2);
        std::mem::swap(&mut c1, &mut c2);
    }
    let q = [1.0 / c0[2], 1.0 / c1[2], 1.0 / c2[2]];
    let r = [c0[3] * q[0], c1[3] * q[1], c2[3] * q[2]];
    let mn = [v[0][0].min(v[1][0]).min(v[2][0]), v[0][1].min(v[1][1]).min(v[2][1])];
    let mx = [v[0][0].max(v[1][0]).max(v[2][0]), v[0][1].max(v[1][1]).max(v[2][1])];
    let lo = [
        ((mn[0] - SUBPIXEL / 2 + SUBPIXEL - 1) >> 8).max(0),
        ((mn[1] - SUBPIXEL / 2 + SUBPIXEL - 1) >> 8).max(0),
    ];
    let hi = [
        ((mx[0] - SUBPIXEL / 2) >> 8).min(f.width as i32 - 1),
        ((mx[1] - SUBPIXEL / 2) >> 8).min(f.height as i32 - 1),
    ];
    if lo[0] > hi[0] || lo[1] > hi[1] {
        return None;
    }
    let small =
        mx[0] - mn[0] <= SMALL_EXTENT * SUBPIXEL && mx[1] - mn[1] <= SMALL_EXTENT * SUBPIXEL;
    Some(Setup { v, r, q, lo, hi, small })
}

fn top_left(a: [i32; 2], b: [i32; 2]) -> bool {
    let d = [b[0] - a[0], b[1] - a[1]];
    d[1] < 0 || (d[1] == 0 && d[0] > 0)
}

fn covers(e: i64, top_left_edge: bool) -> bool {
    e > 0 || (e == 0 && top_left_edge)
}

/// `wide_to_f32` of the WGSL: high word and low word converted separately.
fn wide_to_f32(e: i64) -> f32 {
    ((e >> 32) as i32) as f32 * 4294967296.0 + (e as u32) as f32
}

fn depth_at(e: [f32; 3], s: &Setup) -> f32 {
    let num = (e[0] * s.r[0] + e[1] * s.r[1]) + e[2] * s.r[2];
    let den = (e[0] * s.q[0] + e[1] * s.q[1]) + e[2] * s.q[2];
    num / den
}

/// Calls `fragment(x, y, view depth, triangle)` for every pixel centre every triangle covers,
/// after the same far-plane test as the GPU.
pub fn rasterize(
    f: &FrameUniform,
    input: &RasterInput,
    mut fragment: impl FnMut(u32, u32, f32, u32),
) {
    let mut emit = |x: i32, y: i32, d: f32, t: usize| {
        if d > 0.0 && d <= f.far {
            fragment(x as u32, y as u32, d, t as u32);
        }
    };
    for t in 0..input.triangles.len().min(f.triangle_count as usize) {
        if rejected(input, t) {
            continue;
        }
        let poly = clip_triangle(f, input, t);
        for k in 0..poly.len().saturating_sub(2) {
            let Some(s) = setup(f, input, t, &poly, k) else { continue };
            let [a, b, c] = s.v;
            let tl = [top_left(b, c), top_left(c, a), top_left(a, b)];
            for y in s.lo[1]..=s.hi[1] {
                for x in s.lo[0]..=s.hi[0] {
                    let p = [x * SUBPIXEL + SUBPIXEL / 2, y * SUBPIXEL + SUBPIXEL / 2];
                    let e = [edge(b, c, p), edge(c, a, p), edge(a, b, p)];
                    if covers(e[0], tl[0]) && covers(e[1], tl[1]) && covers(e[2], tl[2]) {
                        // Small triangles' edge values fit in i32 and convert in one step.
                        let ef = if s.small {
                            [e[0] as f32, e[1] as f32, e[2] as f32]
                        } else {
                            [wide_to_f32(e[0]), wide_to_f32(e[1]), wide_to_f32(e[2])]
                        };
                        emit(x, y, depth_at(ef, &s), t);
                    }
                }
            }
        }
    }
}

fn depth_of(word: u64) -> Option<f32> {
    (word != VIS_EMPTY).then(|| f32::from_bits((word >> 32) as u32))
}

/// Whether a fragment passes the layer-1 test against `zref` (as `layer1_accepts`).
fn layer1_accepts(f: &FrameUniform, zref: &[u64], x: u32, y: u32, d: f32, reproject: bool) -> bool {
    if !reproject {
        return depth_of(zref[(y * f.width + x) as usize]).is_some_and(|z0| d > z0 + f.dz);
    }
    let (pc, prev_d) = f.reproject(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5), d);
    if pc.w.is_nan() || pc.w <= 0.0 {
        return false;
    }
    let size = image_size(f);
    let prev = clip_to_pixel(pc, size);
    if !(prev.x >= 0.0 && prev.y >= 0.0 && prev.x < size.x && prev.y < size.y) {
        return false;
    }
    let (px, py) = (prev.x as u32, prev.y as u32);
    depth_of(zref[(py * f.width + px) as usize]).is_some_and(|z0| prev_d > z0 + f.dz)
}

/// Layer 0: the nearest fragment per pixel, ties to the smaller triangle id.
pub fn raster_layer0(f: &FrameUniform, input: &RasterInput) -> Vec<u64> {
    let mut vis = vec![VIS_EMPTY; (f.width * f.height) as usize];
    rasterize_drawn(f, input, false, |x, y, d, t| {
        let p = (y * f.width + x) as usize;
        vis[p] = vis[p].min(vis_pack(d, t));
    });
    vis
}

/// Layer 1: the nearest fragment per pixel that passes the separation test against `zref`
/// (this frame's layer 0 for the two-pass variant; the previous frame's otherwise).
pub fn raster_layer1(
    f: &FrameUniform,
    input: &RasterInput,
    zref: &[u64],
    reproject: bool,
) -> Vec<u64> {
    let mut vis = vec![VIS_EMPTY; (f.width * f.height) as usize];
    rasterize_drawn(f, input, false, |x, y, d, t| {
        if layer1_accepts(f, zref, x, y, d, reproject) {
            let p = (y * f.width + x) as usize;
            vis[p] = vis[p].min(vis_pack(d, t));
        }
    });
    vis
}

/// As `layer1_accepts` under `PEEL`: whether a fragment's word lies strictly behind the last
/// peel's (`previous`; 0 before the first peel) and strictly in front of layer 0's.
fn peel_accepts(word: u64, previous: u64, opaque: u64) -> bool {
    word > previous && word < opaque
}

/// One transparency peel (the `PEEL` variant): per pixel the nearest fragment of a blended
/// triangle whose word lies strictly behind `previous` (the last peel's words; `None` for the
/// first peel) and strictly in front of `opaque` (layer 0).
pub fn raster_peel(
    f: &FrameUniform,
    input: &RasterInput,
    previous: Option<&[u64]>,
    opaque: &[u64],
) -> Vec<u64> {
    let mut vis = vec![VIS_EMPTY; (f.width * f.height) as usize];
    rasterize_drawn(f, input, true, |x, y, d, t| {
        let p = (y * f.width + x) as usize;
        let word = vis_pack(d, t);
        if peel_accepts(word, previous.map_or(0, |prev| prev[p]), opaque[p]) {
            vis[p] = vis[p].min(word);
        }
    });
    vis
}

/// The fragments a peel after `last` would accept (the `UNPEELED` count).
pub fn unpeeled_fragments(
    f: &FrameUniform,
    input: &RasterInput,
    last: &[u64],
    opaque: &[u64],
) -> u32 {
    let mut n = 0;
    rasterize_drawn(f, input, true, |x, y, d, t| {
        let p = (y * f.width + x) as usize;
        let word = vis_pack(d, t);
        n += u32::from(peel_accepts(word, last[p], opaque[p]));
    });
    n
}

/// How many fragments cover each pixel (the watertightness count).
pub fn coverage_counts(f: &FrameUniform, input: &RasterInput) -> Vec<u32> {
    let mut counts = vec![0u32; (f.width * f.height) as usize];
    rasterize(f, input, |x, y, _, _| counts[(y * f.width + x) as usize] += 1);
    counts
}
