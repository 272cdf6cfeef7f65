// Software rasterization of both deep G-buffer layers into visibility buffers.
// defines: WRITE_L0 WRITE_L1 REPROJECT INT64 EARLY_TEST DEPTH_PHASE COUNT PEEL UNPEELED
//
// raster_small: one thread per input triangle: transform, clip against the near plane and the
//   guard band (in homogeneous space), snap to 1/256-pixel fixed point, cull back faces, then
//   rasterize triangles whose extent is at most SMALL_EXTENT pixels right here, and bin the
//   others: their set-up (snapped vertices, depth terms) is stored once in `large`, with one
//   slice per TILES_PER_SLICE of the 16x16 tiles their bounds cover. Slice 0 of entry e is
//   implicit; slices 1.. are work items appended to `items`.
// bin_args: turns the counts into indirect dispatch arguments: one workgroup per entry and one
//   per work item.
// raster_large: one 16x16 workgroup per (binned triangle, slice), one pixel per thread; slice i
//   of n walks the triangle's tiles i, i + n, ... So a triangle's workgroups follow its size
//   (a screen-filling triangle costs about its pixels, spread over many workgroups), and no
//   thread repeats the set-up.
//
// The early depth test (EARLY_TEST): a fragment first reads the word it would lower and skips the
// atomic when it cannot win (words only decrease, so the result is the same). A GPU's work has it
// (on the 64-bit path where the device loads 64-bit atomics); a CPU driver, which reads a storage
// buffer lane by lane, goes straight to the atomic (src/settings.rs, `RasterWork`).
//
// Coverage is exact: pixel centres are tested with integer edge functions (exact 64-bit for
// large triangles) and the top-left rule, so adjacent triangles neither crack nor overlap.
// src/cpu/raster.rs is the same algorithm on the CPU.
//
// Variants (defines): WRITE_L0 writes layer 0; WRITE_L1 writes layer 1, accepting a fragment
// only if its view depth exceeds zref's depth + dz (zref: the final layer 0 for the two-pass
// variant, the previous frame's layer 0 otherwise; REPROJECT compares at the fragment's
// reprojected position in the previous frame). INT64 / DEPTH_PHASE: see shared/vis.wgsl.
// COUNT counts every covered fragment instead (watertightness tests).
//
// Materials: blended triangles (MATERIAL_BLEND) are left out of the opaque layers (and so of the
// shadow maps, drawn by the same kernel); a masked one (MATERIAL_MASK) is a hole wherever its
// opacity (base colour alpha times the base-colour texture's alpha, at the fragment's
// perspective-correct barycentrics) is below its cutoff: dropped whole when it has no texture and
// its factor is below, tested per fragment when it has one. PEEL (with WRITE_L1) draws blended
// triangles only, into vis1: the nearest fragment whose word (depth, id) lies strictly behind
// the previous peel's word in zref and strictly in front of the opaque layer 0 (`opaque`), so k
// such steps peel the k nearest blended surfaces in front of the opaque ones, ties by id.
// UNPEELED (with PEEL) writes nothing: it counts the fragments such a step would accept (those
// behind the last peel) into the diagnostics, once (one phase on the 32-bit path too). A peel
// notes in bins[PEELED] that it found a fragment; `peel_dispatch` turns that into the indirect
// arguments of the peel's per-pixel kernels (none when it found nothing) and clears it.

#include "shared/frame.wgsl"
#include "shared/material.wgsl"
#include "shared/wide.wgsl"
#include "shared/vis.wgsl"
#include "shared/opacity.wgsl"
#include "shared/indirect.wgsl"

const SUBPIXEL: i32 = 256;
// Triangles at most SMALL_EXTENT pixels across are drawn by their own thread (at most 64: the
// edge functions of that path are i32). Drawn by one thread, a triangle's pixels run one after
// the other; binned, they take a workgroup: few pixels on a wide GPU, more on a CPU driver.
override SMALL_EXTENT: i32 = 16;
// A binned triangle gets one slice (workgroup) per TILES_PER_SLICE tiles of its bounds.
override TILES_PER_SLICE: u32 = 8u;
// Whether a binned triangle's threads skip the exact test in tiles wholly outside it: on a GPU
// a tile's threads take that branch together; a driver that runs both sides of every branch
// only pays for the test (`RasterWork`). The pixels drawn are the same either way.
override TILE_TEST: bool = true;
const MAX_POLY: u32 = 9u;

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;
@group(0) @binding(3) var<storage, read> tri_materials: array<u32>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
// [0]: triangles binned since the last bin_args, [2]: entries of the current raster_large
// dispatch, [4] and [6]: the same for work items; [1]: triangles dropped for lack of room,
// [3]: binned triangles this frame; [DIAG_*]: triangles rejected (or drawn untextured) for bad
// input, counted by the camera's layer-0 raster only (frame.flags & FRAME_DIAGNOSTICS).
@group(0) @binding(5) var<storage, read_write> bins: array<atomic<u32>>;
// A binned (clipped sub-)triangle, set up.
struct Binned {
    v0: vec2<i32>,
    v1: vec2<i32>,
    v2: vec2<i32>,
    triangle: u32,
    // Workgroups drawing it.
    slices: u32,
    r: vec3<f32>,
    q: vec3<f32>,
}
@group(0) @binding(6) var<storage, read_write> large: array<Binned>;
// Slices 1.. of binned triangles: (entry, slice).
@group(0) @binding(13) var<storage, read_write> items: array<vec2<u32>>;
@group(0) @binding(7) var<storage, read_write> args: array<u32>;
#if WRITE_L0
@group(0) @binding(8) var<storage, read_write> vis0: array<VisWord>;
#endif
#if WRITE_L1
@group(0) @binding(9) var<storage, read_write> vis1: array<VisWord>;
@group(0) @binding(10) var<storage, read> zref: array<u32>;
#endif
#if COUNT
@group(0) @binding(11) var<storage, read_write> counts: array<atomic<u32>>;
#endif
// The texels, read by the alpha test; the diagnostics check that textures lie inside it.
@group(0) @binding(12) var<storage, read> texels: array<u32>;
// Texture coordinates (sets 0 and 1) for the alpha test.
@group(0) @binding(14) var<storage, read> uvs: array<f32>;
@group(0) @binding(15) var<storage, read> uvs1: array<f32>;
#if PEEL
// This frame's opaque layer 0: peeled fragments lie in front of it.
@group(0) @binding(16) var<storage, read> opaque: array<u32>;
// The workgroups of the peel's per-pixel kernels (8x8 pixels each), or none.
@group(0) @binding(17) var<storage, read_write> peel_args: array<u32>;
#endif

// Diagnostics words in `bins` (`RasterCounters` in src/frame/uniforms.rs).
const DIAG_UNPEELED: u32 = 5u;
const PEELED: u32 = 7u;
const DIAG_INDEX: u32 = 8u;
const DIAG_MATERIAL: u32 = 9u;
const DIAG_POSITION: u32 = 10u;
const DIAG_TEXTURE: u32 = 11u;

// A clip-space vertex: (x, y, w, view depth).
alias ClipVertex = vec4<f32>;

struct Setup {
    v0: vec2<i32>,
    v1: vec2<i32>,
    v2: vec2<i32>,
    // d / w and 1 / w per vertex: view depth interpolates as sum(e r) / sum(e q).
    r: vec3<f32>,
    q: vec3<f32>,
    // Pixel range covered (inclusive), already clamped to the viewport.
    lo: vec2<i32>,
    hi: vec2<i32>,
    // 0: nothing to draw, 1: small, 2: large
    kind: u32,
}

// At most 3e38 in magnitude, NaN excluded by its exponent bits: a comparison with NaN may be
// folded away by a compiler that assumes there are none.
fn finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u && abs(x) <= 3.0e38;
}

fn position(vertex: u32) -> vec3<f32> {
    return vec3<f32>(positions[3u * vertex], positions[3u * vertex + 1u], positions[3u * vertex + 2u]);
}

fn transform(world: vec3<f32>) -> ClipVertex {
    let p = vec4<f32>(world, 1.0);
    let v = mat_mul(frame.view, p);
    let c = mat_mul(frame.proj, v);
    return vec4<f32>(c.x, c.y, c.w, -v.z);
}

fn plane_distance(plane: u32, v: ClipVertex) -> f32 {
    switch plane {
        case 0u: { return v.w - frame.near; }
        case 1u: { return frame.guard_x * v.z - v.x; }
        case 2u: { return frame.guard_x * v.z + v.x; }
        case 3u: { return frame.guard_y * v.z - v.y; }
        default: { return frame.guard_y * v.z + v.y; }
    }
}

// Clips triangle t against the near plane and the guard band. Returns the polygon's vertex count
// (0 when nothing is left); its fan (0, k + 1, k + 2) gives the sub-triangles.
fn clip_triangle(t: u32, poly: ptr<function, array<ClipVertex, MAX_POLY>>) -> u32 {
    (*poly)[0] = transform(position(indices[3u * t]));
    (*poly)[1] = transform(position(indices[3u * t + 1u]));
    (*poly)[2] = transform(position(indices[3u * t + 2u]));
    var all_inside = true;
    for (var i = 0u; i < 3u; i++) {
        let v = (*poly)[i];
        if !(finite(v.x) && finite(v.y) && finite(v.z) && finite(v.w)) {
            return 0u;
        }
        for (var plane = 0u; plane < 5u; plane++) {
            all_inside = all_inside && plane_distance(plane, v) >= 0.0;
        }
    }
    if all_inside {
        return 3u;
    }
    var n = 3u;
    var out: array<ClipVertex, MAX_POLY>;
    for (var plane = 0u; plane < 5u; plane++) {
        var m = 0u;
        for (var i = 0u; i < n; i++) {
            let a = (*poly)[i];
            let b = (*poly)[(i + 1u) % n];
            let da = plane_distance(plane, a);
            let db = plane_distance(plane, b);
            if da >= 0.0 {
                out[m] = a;
                m++;
            }
            if (da >= 0.0) != (db >= 0.0) {
                // Always interpolate from the inside vertex, so that the edge shared with a
                // neighbouring triangle is cut at exactly the same point.
                if da >= 0.0 {
                    out[m] = a + (b - a) * (da / (da - db));
                } else {
                    out[m] = b + (a - b) * (db / (db - da));
                }
                m++;
            }
        }
        n = m;
        if n < 3u {
            return 0u;
        }
        for (var i = 0u; i < n; i++) {
            (*poly)[i] = out[i];
        }
    }
    return n;
}

fn snap(v: ClipVertex) -> vec2<i32> {
    let px = (v.x / v.z * 0.5 + 0.5) * f32(frame.width);
    let py = (0.5 - v.y / v.z * 0.5) * f32(frame.height);
    return vec2<i32>(i32(round(px * f32(SUBPIXEL))), i32(round(py * f32(SUBPIXEL))));
}

// Sign of the doubled signed area of (a, b, c), exactly.
fn orientation(a: vec2<i32>, b: vec2<i32>, c: vec2<i32>) -> i32 {
    return wide_sign(wide_sub(wide_mul(b.x - a.x, c.y - a.y), wide_mul(b.y - a.y, c.x - a.x)));
}

// Sets up sub-triangle `k` of the clipped polygon of triangle t.
fn setup(t: u32, poly: ptr<function, array<ClipVertex, MAX_POLY>>, k: u32) -> Setup {
    var s: Setup;
    s.kind = 0u;
    let c0 = (*poly)[0];
    var c1 = (*poly)[k + 1u];
    var c2 = (*poly)[k + 2u];
    s.v0 = snap(c0);
    s.v1 = snap(c1);
    s.v2 = snap(c2);
    let o = orientation(s.v0, s.v1, s.v2);
    if o == 0 {
        return s;
    }
    // Counter-clockwise in NDC (y up) is negative area in pixel space (y down): front facing.
    // raster_small rejected triangles whose material id is out of range.
    let double_sided = (materials[tri_materials[t]].flags & MATERIAL_DOUBLE_SIDED) != 0u;
    if o > 0 && !double_sided {
        return s;
    }
    if o < 0 {
        let tv = s.v1;
        s.v1 = s.v2;
        s.v2 = tv;
        let tc = c1;
        c1 = c2;
        c2 = tc;
    }
    s.q = vec3<f32>(1.0 / c0.z, 1.0 / c1.z, 1.0 / c2.z);
    s.r = vec3<f32>(c0.w, c1.w, c2.w) * s.q;
    bound(&s);
    if any(s.lo > s.hi) {
        return s;
    }
    let extent = max(max(s.v0, s.v1), s.v2) - min(min(s.v0, s.v1), s.v2);
    s.kind = select(2u, 1u, extent.x <= SMALL_EXTENT * SUBPIXEL && extent.y <= SMALL_EXTENT * SUBPIXEL);
    return s;
}

// The pixel range of s's vertices: the first and last pixel whose centre (i * 256 + 128) lies
// in their bounds, clamped to the viewport.
fn bound(s: ptr<function, Setup>) {
    let mn = min(min((*s).v0, (*s).v1), (*s).v2);
    let mx = max(max((*s).v0, (*s).v1), (*s).v2);
    (*s).lo = max((mn - vec2<i32>(SUBPIXEL / 2) + vec2<i32>(SUBPIXEL - 1)) >> vec2<u32>(8u), vec2<i32>(0));
    (*s).hi = min((mx - vec2<i32>(SUBPIXEL / 2)) >> vec2<u32>(8u), vec2<i32>(i32(frame.width) - 1, i32(frame.height) - 1));
}

// Top-left rule for an edge a -> b of a triangle with positive area (pixel space, y down).
fn top_left(a: vec2<i32>, b: vec2<i32>) -> bool {
    let d = b - a;
    return d.y < 0 || (d.y == 0 && d.x > 0);
}

fn covers(e: i32, top_left_edge: bool) -> bool {
    return e > 0 || (e == 0 && top_left_edge);
}

// Whether the word (d, t) orders strictly before / after the word of depth bits hi and id lo.
fn word_before(d: f32, t: u32, hi: u32, lo: u32) -> bool {
    let db = bitcast<u32>(d);
    return db < hi || (db == hi && t < lo);
}

fn word_after(d: f32, t: u32, hi: u32, lo: u32) -> bool {
    let db = bitcast<u32>(d);
    return db > hi || (db == hi && t > lo);
}

fn layer1_accepts(pixel: vec2<i32>, d: f32, t: u32, f: Frame) -> bool {
#if WRITE_L1
#if PEEL
    let p = u32(pixel.y) * f.width + u32(pixel.x);
    return word_after(d, t, zref[2u * p + 1u], zref[2u * p]) && word_before(d, t, opaque[2u * p + 1u], opaque[2u * p]);
#else
#if REPROJECT
    let r = reproject(f, vec2<f32>(pixel) + 0.5, d);
    let pc = r.clip;
    if !(pc.w > 0.0) {
        return false;
    }
    let prev = clip_to_pixel(pc, vec2<f32>(f32(f.width), f32(f.height)));
    if !(prev.x >= 0.0 && prev.y >= 0.0 && prev.x < f32(f.width) && prev.y < f32(f.height)) {
        return false;
    }
    let pp = vec2<u32>(prev);
    let z0 = zref[2u * (pp.y * f.width + pp.x) + 1u];
    return z0 != VIS_EMPTY && r.depth > bitcast<f32>(z0) + f.dz;
#else
    let z0 = zref[2u * (u32(pixel.y) * f.width + u32(pixel.x)) + 1u];
    return z0 != VIS_EMPTY && d > bitcast<f32>(z0) + f.dz;
#endif
#endif
#else
    return false;
#endif
}

// Whether the scene has masked materials (SceneInfo::masked): without, the alpha test is
// compiled out. With it, only the triangles that need the test (DRAW_TESTED) run the pixel
// loops that hold it: on llvmpipe, code inside a loop costs every iteration even where no
// fragment takes it (the engine at 640x480 with one masked material: 8-10x the raster's time
// when every pixel loop held the test).
override ALPHA_TEST: bool = true;

// A fragment of a triangle that needs the alpha test: dropped where its opacity is below its
// material's cutoff.
fn fragment_tested(pixel: vec2<i32>, d: f32, t: u32, f: Frame) {
    if ALPHA_TEST && triangle_opacity(f, t, vec2<f32>(pixel) + 0.5, d) < materials[tri_materials[t]].alpha_cutoff {
        return;
    }
    fragment(pixel, d, t, f);
}

// A fragment's reads of the frame uniform come from `f`, which the kernel loads before its pixel
// loops: a driver may not keep a uniform's values in registers across the loops' atomics, and
// then reloads them for every fragment (on llvmpipe `Reproject`'s two matrices, reloaded, cost
// it more than the rest of its layer-1 test).
fn fragment(pixel: vec2<i32>, d: f32, t: u32, f: Frame) {
    if !(d > 0.0 && d <= f.far) {
        return;
    }
    let p = u32(pixel.y) * f.width + u32(pixel.x);
#if COUNT
    atomicAdd(&counts[p], 1u);
#endif
#if WRITE_L0
    vis0_write(p, d, t);
#endif
#if WRITE_L1
    if layer1_accepts(pixel, d, t, f) {
#if UNPEELED
        atomicAdd(&bins[DIAG_UNPEELED], 1u);
#else
        vis1_write(p, d, t);
#if PEEL
        atomicStore(&bins[PEELED], 1u);
#endif
#endif
    }
#endif
}

fn depth_at(e: vec3<f32>, s: Setup) -> f32 {
    return dot(e, s.r) / dot(e, s.q);
}

// The depth of small triangle s at pixel (x, y), or -1 where it does not cover the pixel's
// centre; a, b, c: its vertices relative to the first pixel centre, tl: its top-left edges.
fn small_depth(s: Setup, a: vec2<i32>, b: vec2<i32>, c: vec2<i32>, tl: vec3<bool>, x: i32, y: i32) -> f32 {
    let p = (vec2<i32>(x, y) - s.lo) * SUBPIXEL;
    let e0 = (c.x - b.x) * (p.y - b.y) - (c.y - b.y) * (p.x - b.x);
    let e1 = (a.x - c.x) * (p.y - c.y) - (a.y - c.y) * (p.x - c.x);
    let e2 = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
    if covers(e0, tl.x) && covers(e1, tl.y) && covers(e2, tl.z) {
        return depth_at(vec3<f32>(f32(e0), f32(e1), f32(e2)), s);
    }
    return -1.0;
}

fn raster_small_triangle(s: Setup, t: u32, tested: bool, f: Frame) {
    // Everything relative to the first pixel centre, so it fits in i32.
    let o = s.lo * SUBPIXEL + vec2<i32>(SUBPIXEL / 2);
    let a = s.v0 - o;
    let b = s.v1 - o;
    let c = s.v2 - o;
    let tl = vec3<bool>(top_left(b, c), top_left(c, a), top_left(a, b));
    // Two loops, so that only the triangles that need the alpha test run the one that holds it.
    if ALPHA_TEST && tested {
        for (var y = s.lo.y; y <= s.hi.y; y++) {
            for (var x = s.lo.x; x <= s.hi.x; x++) {
                let d = small_depth(s, a, b, c, tl, x, y);
                if d != -1.0 {
                    fragment_tested(vec2<i32>(x, y), d, t, f);
                }
            }
        }
        return;
    }
    for (var y = s.lo.y; y <= s.hi.y; y++) {
        for (var x = s.lo.x; x <= s.hi.x; x++) {
            let d = small_depth(s, a, b, c, tl, x, y);
            if d != -1.0 {
                fragment(vec2<i32>(x, y), d, t, f);
            }
        }
    }
}

// What this raster draws of triangle t (its material id in range): nothing, every covered
// fragment, or the fragments that pass the alpha test.
const DRAW_NONE: u32 = 0u;
const DRAW_ALL: u32 = 1u;
const DRAW_TESTED: u32 = 2u;

fn draw_kind(t: u32) -> u32 {
#if COUNT
    return DRAW_ALL;
#else
    let mid = tri_materials[t];
    let flags = materials[mid].flags;
#if PEEL
    return select(DRAW_NONE, DRAW_ALL, (flags & MATERIAL_BLEND) != 0u);
#else
    if (flags & MATERIAL_BLEND) != 0u {
        return DRAW_NONE;
    }
    if (flags & MATERIAL_MASK) == 0u {
        return DRAW_ALL;
    }
    // (A textureless scene's resolve draws a textured material with its factors alone; so
    // does its alpha test.)
    if TEXTURES && (slot_bits(flags) & (1u << SLOT_BASE_COLOR)) != 0u {
        return DRAW_TESTED;
    }
    return select(DRAW_NONE, DRAW_ALL, unit(materials[mid].base_color.a) >= materials[mid].alpha_cutoff);
#endif
#endif
}

// Why triangle t must not be drawn: 0 when it can be, else the diagnostics word that counts it.
// The imported buffers are the host's, unchecked by the CPU: an index past the vertices or the
// materials would read another triangle's data (or, without robust access, out of bounds).
fn rejection(t: u32) -> u32 {
    let i = vec3<u32>(indices[3u * t], indices[3u * t + 1u], indices[3u * t + 2u]);
    if any(i >= vec3<u32>(frame.vertex_count)) {
        return DIAG_INDEX;
    }
    if tri_materials[t] >= frame.material_count {
        return DIAG_MATERIAL;
    }
    for (var k = 0u; k < 3u; k++) {
        let p = position(i[k]);
        if !(finite(p.x) && finite(p.y) && finite(p.z)) {
            return DIAG_POSITION;
        }
    }
    return 0u;
}

// Whether material mid names a texture that the resolve leaves out: one that does not lie
// inside the texel buffer, or any in a scene marked textureless. Asked only by a raster that
// counts diagnostics, and read field by field (a whole material is 288 bytes).
fn texture_outside(mid: u32) -> bool {
#if WRITE_L0
#if PEEL
    return false;
#endif
    if (frame.flags & FRAME_DIAGNOSTICS) == 0u {
        return false;
    }
    var pending = slot_bits(materials[mid].flags);
    if !TEXTURES {
        return pending != 0u;
    }
    var outside = false;
    while pending != 0u && !outside {
        let k = firstTrailingBit(pending);
        pending &= pending - 1u;
        outside = !texture_fits(materials[mid].slots[k], arrayLength(&texels));
    }
    return outside;
#else
    return false;
#endif
}

// Counted once a frame: by the layer-0 raster, in its last phase on the 32-bit path.
fn count_diagnostic(word: u32) {
#if WRITE_L0
#if !DEPTH_PHASE
    if (frame.flags & FRAME_DIAGNOSTICS) != 0u {
        atomicAdd(&bins[word], 1u);
    }
#endif
#endif
}

@compute @workgroup_size(64)
fn raster_small(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) n: vec3<u32>) {
    let t = gid.x + gid.y * n.x * 64u;
    if t >= frame.triangle_count {
        return;
    }
    let rejected = rejection(t);
    if rejected != 0u {
        count_diagnostic(rejected);
        return;
    }
    if texture_outside(tri_materials[t]) {
        count_diagnostic(DIAG_TEXTURE);
    }
    let kind = draw_kind(t);
    if kind == DRAW_NONE {
        return;
    }
    let f = frame;
    var poly: array<ClipVertex, MAX_POLY>;
    let count = clip_triangle(t, &poly);
    for (var k = 0u; k + 2u < count; k++) {
        let s = setup(t, &poly, k);
        if s.kind == 1u {
            raster_small_triangle(s, t, kind == DRAW_TESTED, f);
        } else if s.kind == 2u {
            bin_triangle(s, t);
        }
    }
}

// The 16x16 tiles across and down that s's pixel bounds span, from their first pixel.
fn tile_span(s: Setup) -> vec2<u32> {
    return vec2<u32>((s.hi - s.lo) / 16 + 1);
}

// Stores s's set-up in `large` and appends its slices past the first to `items`. Where the room
// left holds only some of its slices the triangle takes those (its workgroups each walk more
// tiles: slower, never lost); without room for its entry it is dropped and counted.
fn bin_triangle(s: Setup, t: u32) {
    let entry = atomicAdd(&bins[0], 1u);
    if entry >= arrayLength(&large) {
        atomicAdd(&bins[1], 1u);
        return;
    }
    let tiles = tile_span(s);
    var slices = (tiles.x * tiles.y + TILES_PER_SLICE - 1u) / TILES_PER_SLICE;
    if slices > 1u {
        // Every item below min(total asked, room) is written by the triangle that reserved it,
        // so `bin_args` dispatches no unwritten item.
        let room = arrayLength(&items);
        let base = atomicAdd(&bins[4], slices - 1u);
        let got = select(0u, min(slices - 1u, room - base), base < room);
        for (var i = 0u; i < got; i++) {
            items[base + i] = vec2<u32>(entry, i + 1u);
        }
        slices = got + 1u;
    }
    large[entry] = Binned(s.v0, s.v1, s.v2, t, slices, s.r, s.q);
}

@compute @workgroup_size(1)
fn bin_args() {
    let binned = atomicExchange(&bins[0], 0u);
    let entries = min(binned, arrayLength(&large));
    atomicStore(&bins[2], entries);
    atomicAdd(&bins[3], binned);
    let extra = min(atomicExchange(&bins[4], 0u), arrayLength(&items));
    atomicStore(&bins[6], extra);
    let size = indirect_size(entries + extra);
    args[0] = size.x;
    args[1] = size.y;
    args[2] = size.z;
}

// What moving (m, in 1/256 pixels) adds to the edge function of a -> b.
fn edge_step(a: vec2<i32>, b: vec2<i32>, m: vec2<i32>) -> Wide {
    return wide_sub(wide_mul(b.x - a.x, m.y), wide_mul(b.y - a.y, m.x));
}

// Exact edge function of a -> b at point p (all in 1/256 pixels): what moving from a to p adds
// to it (edge_step), the function being 0 at a.
fn edge_wide(a: vec2<i32>, b: vec2<i32>, p: vec2<i32>) -> Wide {
    return edge_step(a, b, p - a);
}

fn covers_wide(e: Wide, top_left_edge: bool) -> bool {
    let s = wide_sign(e);
    return s > 0 || (s == 0 && top_left_edge);
}

// Whether every pixel centre of the tile [lo, hi] (pixels) lies strictly outside edge a -> b.
// Decided in f32 at the corner where the edge function is largest, with a margin far above the
// rounding error (relative 2^-20 of the terms), so it only skips tiles that are certainly
// outside; pixels of the other tiles get the exact test.
fn tile_outside_edge(a: vec2<i32>, b: vec2<i32>, lo: vec2<i32>, hi: vec2<i32>) -> bool {
    let d = b - a;
    let px = select(lo.x, hi.x, d.y < 0) * SUBPIXEL + SUBPIXEL / 2;
    let py = select(lo.y, hi.y, d.x > 0) * SUBPIXEL + SUBPIXEL / 2;
    let t1 = f32(d.x) * f32(py - a.y);
    let t2 = f32(d.y) * f32(px - a.x);
    return t1 - t2 + (abs(t1) + abs(t2)) * 1e-6 + 1.0 < 0.0;
}

fn tile_outside(s: Setup, lo: vec2<i32>, hi: vec2<i32>) -> bool {
    return tile_outside_edge(s.v1, s.v2, lo, hi) || tile_outside_edge(s.v2, s.v0, lo, hi) || tile_outside_edge(s.v0, s.v1, lo, hi);
}

@compute @workgroup_size(16, 16)
fn raster_large(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let group = indirect_group(wid);
    let entries = atomicLoad(&bins[2]);
    var entry = group;
    var slice = 0u;
    if group >= entries {
        if group - entries >= atomicLoad(&bins[6]) {
            return;
        }
        let item = items[group - entries];
        entry = item.x;
        slice = item.y;
    }
    let b = large[entry];
    var s: Setup;
    s.v0 = b.v0;
    s.v1 = b.v1;
    s.v2 = b.v2;
    s.r = b.r;
    s.q = b.q;
    bound(&s);
    let tl = vec3<bool>(top_left(s.v1, s.v2), top_left(s.v2, s.v0), top_left(s.v0, s.v1));
    var w = walk_start(s, slice, b.slices, vec2<i32>(lid.xy));
    let f = frame;
    // Two loops, so that only the triangles that need the alpha test run the one that holds it.
    if ALPHA_TEST && draw_kind(b.triangle) == DRAW_TESTED {
        for (; w.tile.y < w.tiles.y; walk_next(&w)) {
            let d = walk_depth(s, tl, w);
            if d != -1.0 {
                fragment_tested(w.pixel, d, b.triangle, f);
            }
        }
        return;
    }
    for (; w.tile.y < w.tiles.y; walk_next(&w)) {
        let d = walk_depth(s, tl, w);
        if d != -1.0 {
            fragment(w.pixel, d, b.triangle, f);
        }
    }
}

// A workgroup's walk over the tiles slice, slice + slices, ... (in row order) of a binned
// triangle's 16x16 tiles, from one thread's view: the tile, the thread's pixel in it, and the
// exact edge functions there. A step adds to them what the move to the next tile adds (one of two
// moves: on along the row, or on with a wrap to the next row), so a tile costs no division and no
// 64-bit product; integer sums are exact, so the edge functions are those of the pixel itself.
struct Walk {
    // The tile (across, down) and the tiles of the triangle's bounds.
    tile: vec2<u32>,
    tiles: vec2<u32>,
    // Tiles across and down from one tile of the walk to the next, before a wrap.
    step: vec2<u32>,
    pixel: vec2<i32>,
    // Edge functions (v1, v2), (v2, v0), (v0, v1) at the pixel's centre.
    e0: Wide,
    e1: Wide,
    e2: Wide,
    // What a step adds to them, without and with a wrap.
    on0: Wide,
    on1: Wide,
    on2: Wide,
    wrap0: Wide,
    wrap1: Wide,
    wrap2: Wide,
}

fn walk_start(s: Setup, slice: u32, slices: u32, local: vec2<i32>) -> Walk {
    var w: Walk;
    w.tiles = tile_span(s);
    w.tile = vec2<u32>(slice % w.tiles.x, slice / w.tiles.x);
    w.step = vec2<u32>(slices % w.tiles.x, slices / w.tiles.x);
    w.pixel = s.lo + vec2<i32>(w.tile) * 16 + local;
    let p = w.pixel * SUBPIXEL + vec2<i32>(SUBPIXEL / 2);
    w.e0 = edge_wide(s.v1, s.v2, p);
    w.e1 = edge_wide(s.v2, s.v0, p);
    w.e2 = edge_wide(s.v0, s.v1, p);
    let on = vec2<i32>(w.step) * (16 * SUBPIXEL);
    let wrap = on + vec2<i32>(-i32(w.tiles.x), 1) * (16 * SUBPIXEL);
    w.on0 = edge_step(s.v1, s.v2, on);
    w.on1 = edge_step(s.v2, s.v0, on);
    w.on2 = edge_step(s.v0, s.v1, on);
    w.wrap0 = edge_step(s.v1, s.v2, wrap);
    w.wrap1 = edge_step(s.v2, s.v0, wrap);
    w.wrap2 = edge_step(s.v0, s.v1, wrap);
    return w;
}

fn walk_next(w: ptr<function, Walk>) {
    var tile = (*w).tile + (*w).step;
    let wraps = tile.x >= (*w).tiles.x;
    if wraps {
        tile += vec2<u32>(0u - (*w).tiles.x, 1u);
    }
    (*w).pixel += vec2<i32>(tile - (*w).tile) * 16;
    (*w).tile = tile;
    (*w).e0 = wide_add((*w).e0, select((*w).on0, (*w).wrap0, wraps));
    (*w).e1 = wide_add((*w).e1, select((*w).on1, (*w).wrap1, wraps));
    (*w).e2 = wide_add((*w).e2, select((*w).on2, (*w).wrap2, wraps));
}

// The depth of binned triangle s (top-left edges tl) at the walk's pixel, or -1 where the tile
// lies wholly outside an edge, the pixel outside the bounds, or its centre uncovered.
fn walk_depth(s: Setup, tl: vec3<bool>, w: Walk) -> f32 {
    let tile_lo = s.lo + vec2<i32>(w.tile) * 16;
    if (TILE_TEST && tile_outside(s, tile_lo, min(tile_lo + 15, s.hi))) || !all(w.pixel <= s.hi) {
        return -1.0;
    }
    if covers_wide(w.e0, tl.x) && covers_wide(w.e1, tl.y) && covers_wide(w.e2, tl.z) {
        return depth_at(vec3<f32>(wide_to_f32(w.e0), wide_to_f32(w.e1), wide_to_f32(w.e2)), s);
    }
    return -1.0;
}

@compute @workgroup_size(1)
fn peel_dispatch() {
#if PEEL
    let found = atomicExchange(&bins[PEELED], 0u) != 0u;
    peel_args[0] = select(0u, (frame.width + 7u) / 8u, found);
    peel_args[1] = select(0u, (frame.height + 7u) / 8u, found);
    peel_args[2] = 1u;
#endif
}
