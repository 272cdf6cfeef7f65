// Screen-space radiosity from both layers, with temporal multi-bounce.
//
// radiosity_feedback: B, the outgoing radiance the gather reads: reflected light, boosted, plus
//   emission, B = boost(rho) (D + delta (1 - metallic) rho / pi * E_prev) + Le, with D the
//   Lambertian part of the direct light ((1 - metallic) rho / pi times its irradiance: a
//   surface's specular highlight goes towards the camera, not to every surface around) and E_prev the
//   previous frame's filtered irradiance at this point spread over its whole hemisphere (the
//   irradiance found over the share it covers; reprojected; 0 where there is none) and
//   boost(rho) = unsaturated + (saturated - unsaturated) (max rho - min rho) / max rho (1 by
//   default: energy conserving). Layer 1 reflects the irradiance the last frame's layer-1 gather
//   found at its point (below; reprojected by layer 1's motion, none where that point was not
//   layer 1's last frame or the gather did not run), or none: B1 = boost D1 + Le1.
//   It writes level 0 of the gather source, 40 bytes a pixel and the only thing the taps
//   read: both layers' view depths, B in RGB9E5, view-space normals (octahedral, 2x16 snorm),
//   H, the radiance of the surface's far side (below), and the direction layer 0's direct light
//   comes from (`light_direction`; only the far side of a solid reads it).
// radiosity_source_level: the levels above, a rotated-grid MIP chain as the obscurance's depth
//   pyramid (each texel one real pixel's depths and B). A tap h pixels away reads level
//   floor(log2 h) - mip_offset (the slices never coarser than their step spacing) and its point
//   is reconstructed at the pixel that texel came from: far taps read a small, cache-friendly
//   level, and the work per tap is one 32-byte load (all but the light direction).
// With the normal test (the default), a surface a step finds may face away from X
// (n_Y . (X - Y) < 0, beyond a small slack): X then sees the far side of its solid, not the
// side the camera sees, and the light the camera's side sends (its direct light above all: a
// sphere lit from above seen from the ground beside it) does not reach X.
// Such a surface still hides its sectors but sends H, the part of B that does not depend on
// which way the surface faces: its emission (the ground truth's surfaces emit on both sides)
// and the indirect light it reflects, boost delta (1 - metallic) rho / pi E_prev (none on the
// first frame, nor on layer 1 without its gather).
// radiosity_gather: over the N spiral taps (wgsl/shared/spiral.wgsl, turned every frame) of a
//   world-space radius, Y from layer 0, or from layer 1 where the layer-0 point fails; a tap
//   counts only with w.n_X > 0 and, unless the test is off, w.n_Y < 0 (Y faces X). With M the
//   number of taps that count,
//     cosine (default): E(X) = pi * sum B(Y) (w.n_X) / sum (w.n_X)
//     paper:            E(X) = 2 pi / M * sum B(Y) (w.n_X)
//   (src/settings.rs, Normalization, says why the default differs), and the confidence
//   conf = M / N; it writes conf E (the light of the share of the hemisphere its taps stand for)
//   and conf.
//   With SLICES (the default `slices` estimator) the gather runs over the slices of
//   shared/slices.wgsl instead: steps out to the world-space radius (or, where the slice's line
//   leaves the screen first, to the screen's edge) read both layers' points at
//   full resolution, each point's solid (`thickness` deep, layer 0's no deeper than layer 1's
//   surface) hides an arc of sectors, and the sectors a point hides first take its B: each
//   surface's light arrives at the cosine-weighted solid angle it subtends from X, none
//   through a surface that hides it, and (with the normal test, the default) a surface facing
//   away sends H, and only a layer-0 point's own patch sends its light: the rest of its solid,
//   the side the camera does not see, sends that light relit for a surface facing X (*A
//   point's own surface and the far side of its solid*, below). With g = B in the slices' sum
//   the surfaces deliver
//     E_seen = (pi / S) sum_slices |n_p| W_total / SECTORS sum_sectors B
//   over the share c = (1 / S) sum_slices |n_p| W_total / SECTORS (sectors hidden) of the
//   cosine-weighted hemisphere, and writes E_seen and c: the directions no surface covers are
//   left to the ambient term. The steps crowd towards X as the obscurance's do (t^1.5 of the
//   reach, shared/slices.wgsl's step_distance), and each slice's E_seen and c are extrapolated
//   from what every other step alone finds (`extrapolation`, k): E + k (E - E_half). Steps
//   spaced apart leave open the directions of what stands between them (the fins of an engine
//   between two steps that land beyond them), so both grow with the steps; the extrapolation
//   removes the first order of that (README, *Steps crowded towards the point*). The spiral
//   turns every frame (jitter), and so do the slices.
// radiosity_gather with RECEIVER = 1 (`radiosity.layer1`, `layer1_samples` taps): the same
//   gather at layer 1's points, so that a surface the camera does not see passes on the light
//   it receives: without it a bounce that lands behind layer 0 stops there (the Cornell box's
//   32nd frame: 0.77 of the multi-bounce truth without, 0.82 with; README). It writes, for the
//   next frame's feedback only, E / c (the light found spread over the whole hemisphere, as the
//   feedback spreads layer 0's) and the point's view depth, by which the next frame tells that
//   its reprojected layer-1 point is the same. It runs at the texels that hold a layer-1 point
//   only: radiosity_layer1_list lists them (the records cleared first), radiosity_layer1_dispatch
//   turns their count into an indirect dispatch, radiosity_gather_listed gathers at each.
// Both write the irradiance itself, not a mean to be scaled by the confidence, so that the blur
// and the temporal filter average it linearly (a mean of products is not the product of means:
// a pixel that saw little but bright light next to one that saw much dim light would otherwise
// read as much bright light).
// The temporal filter (`radiosity.temporal`) is wgsl/temporal.wgsl with VEC4: E_t = E (1 - alpha)
//   + E_{t-1} alpha, irradiance and coverage alike, where the point keeps its history
//   (shared/history.wgsl). The history holds layer 0's irradiance only.
// src/cpu/radiosity.rs is the same on the CPU.
// defines: PACKED SLICES
// constants: LEVEL (the gather's resolution), RECEIVER (the layer whose points gather),
// LAYER1_BOUNCE (the feedback reads the last frame's layer-1 gather)

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/spiral.wgsl"
#include "shared/vis.wgsl"
#include "shared/slices.wgsl"
#include "shared/mip.wgsl"
#include "shared/level.wgsl"
#include "shared/rgb9e5.wgsl"
#include "shared/indirect.wgsl"
#include "shared/list.wgsl"
#include "shared/light.wgsl"

// Mirrors `RadiosityUniform` in src/frame/uniforms.rs.
struct Radiosity {
    radius: f32,
    samples: u32,
    damping: f32,
    alpha: f32,
    tolerance: f32,
    normal_test: u32,
    // 1 when the previous frame's history may be used.
    history: u32,
    // Frames since the history began: turns the spiral every frame.
    turn: u32,
    // 0: cosine-weighted mean, 1: the paper's 2 pi / M.
    normalization: u32,
    boost_unsaturated: f32,
    boost_saturated: f32,
    // Slices per pixel (SLICES).
    slices: u32,
    // How far a surface reaches behind itself, in scene units (SLICES).
    thickness: f32,
    // 0: spiral, 1: slices (the kernel is chosen by define; the CPU reference reads this).
    estimator: u32,
    // Levels of the gather source and their offsets in its buffer (up to 8).
    levels: u32,
    // A tap h pixels away reads level floor(log2 h) - mip_offset of the source.
    mip_offset: u32,
    // Taps per layer-1 point of the layer-1 gather (RECEIVER = 1).
    layer1_samples: u32,
    // Weight of the steps' extrapolation (SLICES).
    extrapolation: f32,
    _pad1: u32,
    _pad2: u32,
    offsets: array<vec4<u32>, 2>,
}

// boost(rho): the colour boost of reflected light (1 with the default settings).
fn boost(rho: vec3<f32>) -> f32 {
    let hi = max(rho.r, max(rho.g, rho.b));
    let lo = min(rho.r, min(rho.g, rho.b));
    var saturation = 0.0;
    if hi > 0.0 {
        saturation = (hi - lo) / hi;
    }
    return params.boost_unsaturated + (params.boost_saturated - params.boost_unsaturated) * saturation;
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Radiosity;
@group(0) @binding(2) var<storage, read> gbuffer0: array<GWord>;
@group(0) @binding(3) var<storage, read> gbuffer1: array<GWord>;
// The Lambertian part of each layer's direct radiance (the direct kernel's DIFFUSE output): the
// light a surface sends every way alike, whatever the camera's view of it.
@group(0) @binding(4) var<storage, read> diffuse0: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> diffuse1: array<vec4<f32>>;
// The gather source, one texel per pixel at level 0 and a rotated-grid MIP chain above it.
// Mirrors `SourceTexel` in src/frame/source.rs.
struct SourceTexel {
    // View depths of layer 0 and 1 as f32 bits (0: no surface).
    depth: vec2<u32>,
    // B of each layer in RGB9E5.
    radiance: vec2<u32>,
    // View-space normal of each layer, octahedral in 2x16 snorm (0 where there is no surface).
    normal: vec2<u32>,
    // H of each layer in RGB9E5: what the surface's far side sends.
    hidden: vec2<u32>,
    // The direction layer 0's direct light comes from (view space, octahedral in 2x16 snorm;
    // `light_direction`), which relights the far side of its solid.
    light: u32,
    _pad: u32,
}

@group(0) @binding(6) var<storage, read_write> source: array<SourceTexel>;
@group(0) @binding(7) var<uniform> level: PyramidLevel;
// The scene's lights, whose direction at each point the feedback keeps (`light_direction`).
@group(0) @binding(15) var<storage, read> lights: array<Light>;
@group(0) @binding(8) var<storage, read_write> raw: array<vec4<f32>>;
// The previous frame's filtered irradiance and coverage (wgsl/temporal.wgsl), and its layer-0
// visibility words: shared/history.wgsl's history_at reads them.
@group(0) @binding(9) var<storage, read> history_in: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> prev_vis0: array<u32>;
// The layer-1 gather at the texels of the rotated grid's level LEVEL: E / c (rgb) and the view
// depth of the point that gathered (a; 0: none). Written by the gather with RECEIVER = 1, read by
// the next frame's feedback with LAYER1_BOUNCE.
@group(0) @binding(12) var<storage, read_write> layer1_gathered: array<vec4<f32>>;
// The texels the layer-1 gather runs at (those whose pixel holds a layer-1 point), listed by
// radiosity_layer1_list (shared/list.wgsl), and the gather's indirect dispatch arguments. A
// pixel that holds no layer-1 point then costs the gather nothing, on a driver that runs every
// lane of a SIMD group where one lane works as on a GPU. The records of the texels not listed
// are cleared before the list.
@group(0) @binding(13) var<storage, read_write> list: array<atomic<u32>>;
@group(0) @binding(14) var<storage, read_write> list_args: array<u32>;

// Whether the feedback reads `layer1_gathered` (the last frame ran the layer-1 gather).
override LAYER1_BOUNCE: bool = false;

fn sample0(p: u32) -> GSample {
#if PACKED
    return gbuffer_decode(gbuffer0[p * G_WORDS], gbuffer0[p * G_WORDS + 1u]);
#else
    return gbuffer_decode(gbuffer0[p * G_WORDS], gbuffer0[p * G_WORDS + 1u], gbuffer0[p * G_WORDS + 2u], gbuffer0[p * G_WORDS + 3u]);
#endif
}

fn sample1(p: u32) -> GSample {
#if PACKED
    return gbuffer_decode(gbuffer1[p * G_WORDS], gbuffer1[p * G_WORDS + 1u]);
#else
    return gbuffer_decode(gbuffer1[p * G_WORDS], gbuffer1[p * G_WORDS + 1u], gbuffer1[p * G_WORDS + 2u], gbuffer1[p * G_WORDS + 3u]);
#endif
}

fn finite3(v: vec3<f32>) -> bool {
    return all(abs(v) <= vec3<f32>(3.0e38));
}

// The filtered history's values (shared/history.wgsl): irradiance and coverage, as
// wgsl/temporal.wgsl keeps them.
#include "shared/irradiance.wgsl"

#include "shared/history.wgsl"

// The last frame's layer-1 gather at the layer-1 point of `pixel` (sample s), spread over the
// hemisphere (E / c): read at the texel of level LEVEL over the point's last pixel, and only
// where that texel's point lay within `tolerance` of the point's surface there (0 elsewhere).
fn layer1_history_at(pixel: vec2<u32>, s: GSample) -> vec3<f32> {
    var p: Previous;
    if params.history == 0u || !previous_point(pixel, s, &p) {
        return vec3<f32>(0.0);
    }
    let t = vec2<u32>(p.px) >> vec2<u32>(LEVEL);
    let g = layer1_gathered[t.y * mip_size(LEVEL).x + t.x];
    let centre = vec2<f32>(mip_origin(LEVEL, t)) + 0.5;
    if !(g.a > 0.0 && abs(depth_at(p, centre) - g.a) <= params.tolerance) || !finite3(g.rgb) {
        return vec3<f32>(0.0);
    }
    return max(g.rgb, vec3<f32>(0.0));
}

// What a gather's irradiance and coverage g stand for over the whole hemisphere: E / c, pi times
// the weighted mean radiance of the surfaces it saw (the directions it did not cover take their
// mean; at most pi max B, so the feedback gain bounds it), 0 where it covered nothing.
fn spread(g: vec4<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), g.rgb / max(g.a, 1e-6), g.a > 0.0);
}

// The indirect light sample s reflects every way alike (its Lambertian part) from irradiance e,
// damped and boosted (`b`, its boost) for the next bounce, plus its emission: what its far side
// sends.
fn reflected(s: GSample, b: f32, e: vec3<f32>) -> vec3<f32> {
    return b * params.damping * (1.0 - s.metallic) * s.occlusion * s.base_color / PI_R * e + s.emissive;
}

// A sample's normal as the gather source holds it, in view space (0 where there is no surface).
fn pack_normal(s: GSample) -> u32 {
    let n = mat_mul(frame.view, vec4<f32>(s.normal, 0.0)).xyz;
    if !(s.depth > 0.0) || !(dot(n, n) > 0.0) {
        return 0u;
    }
    return pack2x16snorm(oct_encode(n));
}

// The direction (view space, packed as the normals) that the direct light on sample s at pixel
// position p comes from: the lights' directions weighted by the luminance of the irradiance
// each delivers on its normal, unshadowed (one light's own direction; 0 where none reaches it,
// whose B then holds no direct light to relight).
fn light_direction(s: GSample, p: vec2<f32>) -> u32 {
    if !(s.depth > 0.0) {
        return 0u;
    }
    let world = mat_mul(frame.inv_view, vec4<f32>(view_position(frame, p, s.depth), 1.0)).xyz;
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < arrayLength(&lights); i++) {
        var l: vec3<f32>;
        let e = dot(light_at(lights[i], world, &l), vec3<f32>(0.2126, 0.7152, 0.0722));
        sum += e * max(dot(s.normal, l), 0.0) * l;
    }
    let d = mat_mul(frame.view, vec4<f32>(sum, 0.0)).xyz;
    if !(dot(d, d) > 0.0) || !finite3(d) {
        return 0u;
    }
    return pack2x16snorm(oct_encode(normalize(d)));
}

@compute @workgroup_size(8, 8)
fn radiosity_feedback(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let s0 = sample0(p);
    var out0 = vec3<f32>(0.0);
    var hidden0 = vec3<f32>(0.0);
    if s0.depth > 0.0 {
        // The next bounce spreads what the gather found over the whole hemisphere.
        var valid = false;
        let h = history_at(gid.xy, s0, params.history != 0u, params.tolerance, &valid);
        let e = select(vec3<f32>(0.0), spread(h), valid);
        let b0 = boost(s0.base_color);
        hidden0 = reflected(s0, b0, e);
        out0 = b0 * diffuse0[p].rgb + hidden0;
    }
    let s1 = sample1(p);
    var out1 = vec3<f32>(0.0);
    var hidden1 = vec3<f32>(0.0);
    if s1.depth > 0.0 {
        let b1 = boost(s1.base_color);
        // Without the last frame's layer-1 gather the reflected part is 0: compiled out.
        hidden1 = s1.emissive;
        if LAYER1_BOUNCE {
            hidden1 = reflected(s1, b1, layer1_history_at(gid.xy, s1));
        }
        out1 = b1 * diffuse1[p].rgb + hidden1;
    }
    out0 = select(vec3<f32>(0.0), out0, finite3(out0));
    out1 = select(vec3<f32>(0.0), out1, finite3(out1));
    hidden0 = select(vec3<f32>(0.0), hidden0, finite3(hidden0) && finite3(out0));
    hidden1 = select(vec3<f32>(0.0), hidden1, finite3(hidden1) && finite3(out1));
    source[p] = SourceTexel(
        vec2<u32>(bitcast<u32>(s0.depth), bitcast<u32>(s1.depth)),
        vec2<u32>(pack_rgb9e5(out0), pack_rgb9e5(out1)),
        vec2<u32>(pack_normal(s0), pack_normal(s1)),
        vec2<u32>(pack_rgb9e5(hidden0), pack_rgb9e5(hidden1)),
        light_direction(s0, vec2<f32>(gid.xy) + 0.5),
        0u,
    );
}

// Level `level` of the gather source from the level below (the rotated grid of
// shared/level.wgsl: depths and radiance of one real pixel, never a blend across an edge).
@compute @workgroup_size(8, 8)
fn radiosity_source_level(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= level.dst_width || gid.y >= level.dst_height {
        return;
    }
    source[level.dst_offset + gid.y * level.dst_width + gid.x] = source[rotated_grid_pick(level, gid.xy)];
}

// Texel q of the gather source as the taps read it: all but its light direction, which only
// `far_side_light` reads (on llvmpipe every storage load is a loop over the lanes).
fn tap_texel(q: u32) -> SourceTexel {
    return SourceTexel(source[q].depth, source[q].radiance, source[q].normal, source[q].hidden, 0u, 0u);
}

fn source_offset(l: u32) -> u32 {
    return params.offsets[l / 4u][l % 4u];
}

const PI_R: f32 = 3.14159265;

// What the surface of `layer` in texel t (pixel centre `at`, view depth z) sends towards the
// view-space point c: B where it faces c (or without the normal test), else H (its far side's).
fn sent(t: SourceTexel, layer: u32, c: vec3<f32>, at: vec2<f32>, z: f32) -> vec3<f32> {
    if params.normal_test == 0u {
        return unpack_rgb9e5(t.radiance[layer]);
    }
    let d = c - view_position(frame, at, z);
    return sent_towards(t, layer, oct_decode(unpack2x16snorm(t.normal[layer])), d, length(d));
}

// As `sent`, with the surface's normal and d = c - its point (|d| = `reach`) at hand.
fn sent_towards(t: SourceTexel, layer: u32, normal: vec3<f32>, d: vec3<f32>, reach: f32) -> vec3<f32> {
    // A surface in c's own plane (seen edge-on, or c's neighbour on a flat wall, where rounding
    // picks the sign) counts as facing it.
    if dot(d, normal) > -FACING_SLACK * reach {
        return unpack_rgb9e5(t.radiance[layer]);
    }
    return unpack_rgb9e5(t.hidden[layer]);
}

// How far (the cosine) a surface may turn away from a point and still count as facing it.
const FACING_SLACK: f32 = 1e-3;

// A point's own surface and the far side of its solid (with the normal test). The camera sees one
// side of a solid, a receiving point X may see another: the ground beside a sphere sees its
// underside, X in an engine's fin groove the face of the next fin, while the steps find the
// side the camera sees. A layer-0 point stands for the patch of its surface between the
// midpoints to the steps before and after it (on its tangent plane: `own_sectors`); the sectors
// that patch hides first take what the point sends (B, or H where it faces away from X). The
// rest of the arc its solid hides first is the solid's far side as X sees it: it takes
// `far_side_light`, the point's light relit for a surface facing X. Without the split, every
// sector of a point's solid took its B, and the estimate grew past the truth as the steps
// grew (2CylinderEngine at 320x240, first frame without the extrapolation: 1.34 of the truth
// at 256 taps, the sphere field 1.12; README, *The far side of a solid*).

// Where the ray through pixel position p meets the plane through y with normal ny (view
// space), its view depth held within a factor 2 of z0 (a plane the camera sees edge-on).
fn on_plane(p: vec2<f32>, y: vec3<f32>, ny: vec3<f32>, z0: f32) -> vec3<f32> {
    // The ray: o + z d at view depth z (view_position is affine in the depth).
    let o = select(vec3<f32>(0.0), view_position(frame, p, 0.0), frame.ortho != 0u);
    let d = select(view_position(frame, p, 1.0), vec3<f32>(0.0, 0.0, -1.0), frame.ortho != 0u);
    let den = dot(d, ny);
    var z = select(z0, dot(y - o, ny) / den, abs(den) > 1e-6);
    if !(z > 0.0) {
        z = z0;
    }
    return o + d * clamp(z, 0.5 * z0, 2.0 * z0);
}

// The sectors (of slice sl, on side `along`) that the patch of the point y (normal ny, view
// depth z0, at pixel position `at`) hides from c: its tangent plane from `before` pixels before
// `at` along the slice to `after` pixels past it.
fn own_sectors(sl: Slice, c: vec3<f32>, at: vec2<f32>, along: f32, before: f32, after: f32, y: vec3<f32>, ny: vec3<f32>, z0: f32) -> u32 {
    let a = on_plane(at - along * before * sl.dir, y, ny, z0);
    let b = on_plane(at + along * after * sl.dir, y, ny, z0);
    return sector_bits(sl, weight_in(sl, a - c, along), weight_in(sl, b - c, along));
}

// The cosine of the light on a point's own normal is taken as no less than this (a point the
// light grazes has a B too small to scale).
const RELIGHT_FLOOR: f32 = 0.1;

// What the far side of the layer-0 solid in source texel q (its point y, normal ny) sends
// towards X at c: H, the part of B that does not depend on the facing, plus the rest of B
// relit for a surface that faces X: times the cosine of the light's direction there (the
// texel's `light`) over its cosine at the point's own normal, at most 1 (the point's shadowing
// is taken for its far side's, and the side the camera sees is the only one measured: a far
// side sending more let a 24x18 Cornell box flicker past 128 frames and the gathered light
// past what any texel sends). A sphere's underside under a high sun sends next to nothing.
fn far_side_light(q: u32, t: SourceTexel, c: vec3<f32>, y: vec3<f32>, ny: vec3<f32>) -> vec3<f32> {
    let h = unpack_rgb9e5(t.hidden[0]);
    let l = oct_decode(unpack2x16snorm(source[q].light));
    let toward = max(dot(normalize(c - y), l), 0.0);
    let relit = min(toward / max(dot(ny, l), RELIGHT_FLOOR), 1.0);
    return h + max(unpack_rgb9e5(t.radiance[0]) - h, vec3<f32>(0.0)) * relit;
}

// The sectors a slice's steps have hidden and the light they sent: every step's, or every
// other step's for the extrapolation.
struct Gathered {
    occupied: u32,
    sum: vec3<f32>,
}

// How many of `bits` nothing in g hid before.
fn first_hidden(g: Gathered, bits: u32) -> u32 {
    return countOneBits(bits & ~g.occupied);
}

// Sends `light` into the sectors a point hid first: `first` of every step's, `first_half` of
// every other step's.
fn send(every: ptr<function, Gathered>, half: ptr<function, Gathered>, light: vec3<f32>, first: u32, first_half: u32) {
    (*every).sum += light * f32(first);
    (*half).sum += light * f32(first_half);
}

// Marks `bits` hidden among every step's sectors, and among every other step's on an `even`
// step.
fn occupy(every: ptr<function, Gathered>, half: ptr<function, Gathered>, bits: u32, even: bool) {
    (*every).occupied |= bits;
    (*half).occupied |= select(0u, bits, even);
}

// The `slices` gather at `pixel` (sample s of layer RECEIVER): irradiance and confidence.
// `noise_at`: the texel whose slice turns the pixel takes (itself at full resolution; its texel
// at a lower one, so that every 4x4 block of texels holds the 16 turns).
fn slices_gather(pixel: vec2<u32>, noise_at: vec2<u32>, s: GSample) -> vec4<f32> {
    let c = view_position(frame, vec2<f32>(pixel) + 0.5, s.depth);
    let n = normalize(mat_mul(frame.view, vec4<f32>(s.normal, 0.0)).xyz);
    let r_px = params.radius * pixels_per_unit(frame, s.depth);
    let slices = max(params.slices, 1u);
    let steps = max(taps() / (2u * slices), 1u);
    let noise = slice_noise(noise_at, params.turn);
    var seen = vec3<f32>(0.0);
    var covered = 0.0;
    for (var k = 0u; k < slices; k++) {
        let sl = slice_at(k, slices, noise, c, n);
        if !(sl.weight > 0.0) {
            continue;
        }
        var every = Gathered(0u, vec3<f32>(0.0));
        var half = Gathered(0u, vec3<f32>(0.0));
        // The two sides hold opposite halves of the arc: their order does not matter.
        for (var side = 0u; side < 2u; side++) {
            let along = select(1.0, -1.0, side == 1u);
            // The steps spread over the radius or, where the slice's line leaves the screen
            // first, over what the screen holds of it.
            let spacing = slice_spacing(pixel, sl, along, r_px, steps);
            let coarsest = mip_coarsest(spacing, params.levels);
            // The distances of the two steps before this one (x: the one before; 0 before the
            // first, the receiver itself) and of the two after it, carried along.
            var prev = vec2<f32>(0.0);
            var next = vec2<f32>(step_distance(spacing, 0u, steps, noise.y), step_distance(spacing, 1u, steps, noise.y));
            for (var j = 0u; j < steps; j++) {
                let h = next.x;
                next = vec2<f32>(next.y, step_distance(spacing, j + 2u, steps, noise.y));
                let before = prev;
                prev = vec2<f32>(h, prev.x);
                let even = (j & 1u) == 0u;
                let step_level = mip_level(h, params.mip_offset, coarsest);
                var tap: vec2<i32>;
                if !slice_tap(pixel, sl, h, along, &tap) {
                    continue;
                }
                var q = 0u;
                let at = mip_texel(tap, step_level, source_offset(step_level), &q);
                let t = tap_texel(q);
                let z0 = bitcast<f32>(t.depth.x);
                if !(z0 > 0.0) {
                    continue;
                }
                let z1 = bitcast<f32>(t.depth.y);
                let backs = solid_backs(z0, z1, params.thickness);
                var front2 = 0.0;
                var bits = solid_sectors(sl, c, n, at, along, z0, backs.x, 0.0, params.radius, &front2);
                if bits != 0u {
                    if params.normal_test != 0u {
                        let y = view_position(frame, at, z0);
                        let ny = oct_decode(unpack2x16snorm(t.normal[0]));
                        // The point's own patch reaches halfway to the steps before and after it
                        // (among every other step's, for the extrapolation's half, halfway to the
                        // steps two away), and at least over the texel's own footprint (steps
                        // closer than a pixel read the same point).
                        let texel = 0.5 * f32(1u << step_level);
                        let own = own_sectors(sl, c, at, along, max(0.5 * (h - before.x), texel), max(0.5 * (next.x - h), texel), y, ny, z0);
                        var own_half = 0u;
                        if even {
                            own_half = own_sectors(sl, c, at, along, max(0.5 * (h - before.y), texel), max(0.5 * (next.y - h), texel), y, ny, z0);
                        }
                        let all = bits | own;
                        let all_half = bits | own_half;
                        let first = first_hidden(every, all);
                        let first_half = select(0u, first_hidden(half, all_half), even);
                        let mine = first_hidden(every, own);
                        let mine_half = select(0u, first_hidden(half, own_half), even);
                        let d = c - y;
                        send(&every, &half, sent_towards(t, 0u, ny, d, length(d)), mine, mine_half);
                        if first + first_half > mine + mine_half {
                            send(&every, &half, far_side_light(q, t, c, y, ny), first - mine, first_half - mine_half);
                        }
                        every.occupied |= all;
                        half.occupied |= select(0u, all_half, even);
                    } else {
                        let first = first_hidden(every, bits);
                        let first_half = select(0u, first_hidden(half, bits), even);
                        send(&every, &half, unpack_rgb9e5(t.radiance[0]), first, first_half);
                        occupy(&every, &half, bits, even);
                    }
                }
                if z1 > z0 {
                    bits = solid_sectors(sl, c, n, at, along, z1, backs.y, 0.0, params.radius, &front2);
                    let first = first_hidden(every, bits);
                    let first_half = select(0u, first_hidden(half, bits), even);
                    if first + first_half > 0u {
                        send(&every, &half, sent(t, 1u, c, at, z1), first, first_half);
                    }
                    occupy(&every, &half, bits, even);
                }
            }
        }
        // Richardson's extrapolation in the steps a side, as the obscurance's.
        let k = params.extrapolation;
        let hidden = f32(countOneBits(every.occupied));
        let hidden_half = f32(countOneBits(half.occupied));
        seen += sl.weight * max(every.sum + k * (every.sum - half.sum), vec3<f32>(0.0)) / f32(SECTORS);
        covered += sl.weight * max(hidden + k * (hidden - hidden_half), 0.0) / f32(SECTORS);
    }
    // An extrapolated coverage past the whole hemisphere is taken as the whole, the light found
    // scaled with it (the mean radiance over what it covers, E / c, kept).
    let share = covered / f32(slices);
    return vec4<f32>(PI_R * seen / f32(slices) / max(share, 1.0), min(share, 1.0));
}

// The `spiral` gather at `pixel` (sample s of layer RECEIVER): irradiance and confidence.
fn spiral_gather(pixel: vec2<u32>, s: GSample) -> vec4<f32> {
    let c = view_position(frame, vec2<f32>(pixel) + 0.5, s.depth);
    let n = normalize(mat_mul(frame.view, vec4<f32>(s.normal, 0.0)).xyz);
    let r_px = params.radius * pixels_per_unit(frame, s.depth);
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    var m = 0u;
    let samples = taps();
    for (var i = 0u; i < samples; i++) {
        let tap = spiral_tap_turned(pixel, i, samples, r_px, params.turn);
        if any(tap < vec2<i32>(0)) || tap.x >= i32(frame.width) || tap.y >= i32(frame.height) {
            continue;
        }
        let tap_level = mip_level(spiral_distance(i, samples, r_px), params.mip_offset, params.levels - 1u);
        var q = 0u;
        let at = mip_texel(tap, tap_level, source_offset(tap_level), &q);
        let t = tap_texel(q);
        // The normals come from the G-buffer of the pixel the texel was taken from.
        let o = u32(at.y) * frame.width + u32(at.x);
        for (var layer = 0u; layer < 2u; layer++) {
            var depth: f32;
            var normal: vec3<f32>;
            if layer == 0u {
                depth = bitcast<f32>(t.depth.x);
                normal = gword_normal(gbuffer0[o * G_WORDS]);
            } else {
                depth = bitcast<f32>(t.depth.y);
                normal = gword_normal(gbuffer1[o * G_WORDS]);
            }
            if !(depth > 0.0) {
                continue;
            }
            let v = view_position(frame, at, depth) - c;
            let len = length(v);
            if !(len > 1e-6) {
                continue;
            }
            let w = v / len;
            let wn_x = dot(w, n);
            let wn_y = dot(w, normalize(mat_mul(frame.view, vec4<f32>(normal, 0.0)).xyz));
            if wn_x > 0.0 && (params.normal_test == 0u || wn_y < 0.0) {
                let radiance = unpack_rgb9e5(t.radiance[layer]);
                sum += radiance * wn_x;
                weight += wn_x;
                m += 1u;
                break;
            }
        }
    }
    var e = vec3<f32>(0.0);
    if m > 0u {
        if params.normalization == 0u {
            e = PI_R * sum / weight;
        } else {
            e = 2.0 * PI_R / f32(m) * sum;
        }
    }
    let confidence = f32(m) / f32(samples);
    return vec4<f32>(e * confidence, confidence);
}

// The level of the rotated grid whose texels the gather computes (0: every pixel; 1: half, 2:
// quarter resolution, each texel at the pixel it stands for, wgsl/upsample.wgsl filling in the
// rest before the temporal filter).
override LEVEL: u32 = 0u;

// The layer whose points gather: 0 (`radiosity`) or 1 (`radiosity.layer1`).
override RECEIVER: u32 = 0u;

// Taps per point of the gathering layer.
fn taps() -> u32 {
    if RECEIVER == 1u {
        return params.layer1_samples;
    }
    return params.samples;
}

@compute @workgroup_size(8, 8)
fn radiosity_gather(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = mip_size(LEVEL);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    gather_texel(gid.xy);
}

// Lists the texels whose pixel holds a layer-1 point for radiosity_gather_listed.
@compute @workgroup_size(8, 8)
fn radiosity_layer1_list(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = mip_size(LEVEL);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let pixel = mip_origin(LEVEL, gid.xy);
    if gword_depth(gbuffer1[(pixel.y * frame.width + pixel.x) * G_WORDS]) > 0.0 {
        list_append(gid.y * size.x + gid.x);
    }
}

// The listed texels' count as indirect dispatch arguments, 64 texels a workgroup.
@compute @workgroup_size(1)
fn radiosity_layer1_dispatch() {
    list_write_args();
}

// The gather at the listed texels (RECEIVER = 1).
@compute @workgroup_size(64)
fn radiosity_gather_listed(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    var t = 0u;
    if list_item(wid, li, &t) {
        let width = mip_size(LEVEL).x;
        gather_texel(vec2<u32>(t % width, t / width));
    }
}

// The gather at texel `at` of level LEVEL.
fn gather_texel(at: vec2<u32>) {
    let pixel = mip_origin(LEVEL, at);
    let t = at.y * mip_size(LEVEL).x + at.x;
    var s: GSample;
    if RECEIVER == 1u {
        s = sample1(pixel.y * frame.width + pixel.x);
    } else {
        s = sample0(pixel.y * frame.width + pixel.x);
    }
    var g = vec4<f32>(0.0);
    if s.depth > 0.0 && taps() > 0u {
#if SLICES
        g = slices_gather(pixel, at, s);
#else
        g = spiral_gather(pixel, s);
#endif
    }
    if RECEIVER == 1u {
        layer1_gathered[t] = layer1_record(g, s.depth);
    } else {
        raw[t] = g;
    }
}

// What the layer-1 gather keeps of its irradiance and confidence g at a point of view depth z:
// E / c (0 where it found nothing) and z (0 where there is no point).
fn layer1_record(g: vec4<f32>, z: f32) -> vec4<f32> {
    if !(z > 0.0) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(select(vec3<f32>(0.0), spread(g), finite3(g.rgb)), z);
}
