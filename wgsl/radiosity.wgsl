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
//   It writes level 0 of the gather source, 32 bytes a pixel and the only thing the taps
//   read: both layers' view depths, B in RGB9E5, view-space normals (octahedral, 2x16 snorm)
//   and H, the radiance of the surface's far side (below).
// radiosity_source_level: the levels above, a rotated-grid MIP chain as the obscurance's depth
//   pyramid (each texel one real pixel's depths and B). A tap h pixels away reads level
//   floor(log2 h) - mip_offset (the slices never coarser than their step spacing) and its point
//   is reconstructed at the pixel that texel came from: far taps read a small, cache-friendly
//   level, and the work per tap is one 32-byte load.
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
//   surface, layer 1's no deeper than the gap in front of it: shared/slices.wgsl's
//   solid_backs) hides an arc of sectors, and the sectors a point hides first take its B: each
//   surface's light arrives at the cosine-weighted solid angle it subtends from X, none
//   through a surface that hides it, and (with the normal test, the default) a surface facing
//   away sends H. With g = B in the slices' sum the surfaces deliver
//     E_seen = (pi / S) sum_slices |n_p| W_total / SECTORS sum_sectors B
//   over the share c = (1 / S) sum_slices |n_p| W_total / SECTORS (sectors hidden) of the
//   cosine-weighted hemisphere, and writes E_seen and c: the directions no surface covers are
//   left to the ambient term. The steps crowd towards X as the obscurance's do (t^1.5 of the
//   reach, shared/slices.wgsl's step_distance), and each slice's E_seen and c are extrapolated
//   from what every other step alone finds (`extrapolation`, k): E + k (E - E_half). Steps
//   spaced apart leave open the directions of what stands between them (the fins of an engine
//   between two steps that land beyond them), so both grow with the steps; the extrapolation
//   removes the first order of that (docs/accuracy.md, *Steps crowded towards the point*). The spiral
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
}

@group(0) @binding(6) var<storage, read_write> source: array<SourceTexel>;
@group(0) @binding(7) var<uniform> level: PyramidLevel;
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

// Curved surfaces (with the normal test). The camera sees one side of a curved surface, the
// receiving point X another: the ground beside a sphere sees its shadowed underside, while the
// steps find the sunlit side the camera sees, whose solid hides the directions in which X sees
// that underside (the ground around a lone sphere, `builtin:grid-200`, read 3.3x the truth's first
// bounce, the share of its hemisphere covered near the sphere's closed form). Two rules give those
// directions the light of the side X sees rather than of the side the camera sees:
// - along a side of a slice, a point that faces X less squarely than the point before it (the two
//   joined as one surface: the earlier lies nearer the later than X does) on a surface that bends
//   between them (their normals further apart than BEND_COS) sends what that earlier point sent: X
//   sees, in the directions it hides first, the part of the surface that turns towards X (on a
//   sphere, the side below the one the camera sees lit; in an engine's fins, the face of a fin
//   whose back the camera sees);
// - a point that starts a surface (joined to none before it), faces X at a grazing angle (cosine
//   under GRAZING) and lies on a surface that bends away from X within X's distance (told by the
//   next step's point: `grazing_light`) sends a blend from H towards B by its cosine over GRAZING:
//   its solid hides the far side of a curved object, which X sees and the camera does not.
// With them, at 160x120 and with the steps then spread evenly, that ground read 2.1x, and the
// sphere field's 32nd frame 1.149 of the ten-bounce truth (1.188 without; docs/accuracy.md,
// *Curved surfaces*). Reading the next texel along the
// slice instead of waiting for the next step cost the gather 20% more on llvmpipe for figures
// within 0.01; the rules cost it about 11%.
const BEND_COS: f32 = 0.95;
const GRAZING: f32 = 0.3;
const BEND_REACH: f32 = 0.5;

// The last layer-0 point that hid sectors on a side of a slice: what it sent, where it lies,
// its normal and the cosine at which it faces the receiver (below -1: none yet).
struct Sender {
    light: vec3<f32>,
    y: vec3<f32>,
    n: vec3<f32>,
    facing: f32,
}

// A layer-0 point that starts a surface and faces the receiver X at a grazing angle, whose light
// waits for the next step's point to tell whether its surface bends away from X: B, H (packed),
// the cosine at which it faces X, the sectors it hid first, where it lies and its normal.
struct Grazing {
    on: bool,
    b: vec3<f32>,
    h: u32,
    facing: f32,
    count: u32,
    // The sectors it hid first among every other step's (the extrapolation's half).
    count_half: u32,
    y: vec3<f32>,
    n: vec3<f32>,
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

// What the grazing point g sends towards X (view point c), the next step along the slice finding
// the layer-0 point y2 (normal n2; `found` false where it found none): a blend from H towards B
// by its cosine over GRAZING where its surface bends away from X within X's distance (the next
// point faces X less squarely: convex as seen from X, where a groove's floor turns towards X;
// and the normal turns by more than BEND_REACH per |X - y| of the way between the two points,
// the turn taken as the chord between the unit normals), else B.
fn grazing_light(g: Grazing, c: vec3<f32>, found: bool, y2: vec3<f32>, n2: vec3<f32>) -> vec3<f32> {
    if !found {
        return g.b;
    }
    let away = dot(n2, c - y2) / max(length(c - y2), 1e-30) < g.facing;
    if away && length(n2 - g.n) * length(c - g.y) > BEND_REACH * max(length(y2 - g.y), 1e-6) {
        return mix(unpack_rgb9e5(g.h), g.b, max(g.facing, 0.0) / GRAZING);
    }
    return g.b;
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
            var last = Sender(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), -2.0);
            var grazing: Grazing;
            grazing.on = false;
            for (var j = 0u; j < steps; j++) {
                let h = step_distance(spacing, j, steps, noise.y);
                let even = (j & 1u) == 0u;
                let step_level = mip_level(h, params.mip_offset, coarsest);
                var tap: vec2<i32>;
                var t: SourceTexel;
                var at = vec2<f32>(0.0);
                var z0 = 0.0;
                if slice_tap(pixel, sl, h, along, &tap) {
                    var q = 0u;
                    at = mip_texel(tap, step_level, source_offset(step_level), &q);
                    t = source[q];
                    z0 = bitcast<f32>(t.depth.x);
                }
                let found = z0 > 0.0;
                let z1 = bitcast<f32>(t.depth.y);
                let backs = solid_backs(z0, z1, params.thickness);
                var front2 = 0.0;
                var bits = 0u;
                if found {
                    bits = solid_sectors(sl, c, n, at, along, z0, backs.x, 0.0, params.radius, &front2);
                }
                var y = vec3<f32>(0.0);
                var ny = vec3<f32>(0.0);
                if found && params.normal_test != 0u && (grazing.on || bits != 0u) {
                    y = view_position(frame, at, z0);
                    ny = oct_decode(unpack2x16snorm(t.normal[0]));
                }
                if grazing.on {
                    last.light = grazing_light(grazing, c, found, y, ny);
                    send(&every, &half, last.light, grazing.count, grazing.count_half);
                    grazing.on = false;
                }
                if !found {
                    continue;
                }
                var first = first_hidden(every, bits);
                var first_half = select(0u, first_hidden(half, bits), even);
                if bits != 0u {
                    var light = unpack_rgb9e5(t.radiance[0]);
                    if params.normal_test != 0u {
                        let d = c - y;
                        let reach = length(d);
                        light = sent_towards(t, 0u, ny, d, reach);
                        // The rules for curved surfaces (above).
                        var facing = dot(ny, d) / max(reach, 1e-30);
                        let joined = last.facing >= -1.0 && dot(y - last.y, y - last.y) < reach * reach;
                        if joined && dot(ny, last.n) < BEND_COS && last.facing > facing {
                            light = last.light;
                            facing = last.facing;
                        } else if !joined && facing < GRAZING {
                            grazing = Grazing(true, light, t.hidden[0], facing, first, first_half, y, ny);
                        }
                        last = Sender(light, y, ny, facing);
                    }
                    // A grazing point's light waits for the next step.
                    if !grazing.on {
                        send(&every, &half, light, first, first_half);
                    }
                }
                occupy(&every, &half, bits, even);
                if z1 > z0 {
                    bits = solid_sectors(sl, c, n, at, along, z1, backs.y, 0.0, params.radius, &front2);
                    first = first_hidden(every, bits);
                    first_half = select(0u, first_hidden(half, bits), even);
                    if first + first_half > 0u {
                        send(&every, &half, sent(t, 1u, c, at, z1), first, first_half);
                    }
                    occupy(&every, &half, bits, even);
                }
            }
            // A grazing point with no step after it: nothing tells that its surface bends.
            if grazing.on {
                send(&every, &half, grazing.b, grazing.count, grazing.count_half);
            }
        }
        // Richardson's extrapolation in the steps a side, as the obscurance's.
        let k = params.extrapolation;
        let hidden = f32(countOneBits(every.occupied));
        let hidden_half = f32(countOneBits(half.occupied));
        seen += sl.weight * max(every.sum + k * (every.sum - half.sum), vec3<f32>(0.0)) / f32(SECTORS);
        covered += sl.weight * max(hidden + k * (hidden - hidden_half), 0.0) / f32(SECTORS);
    }
    return vec4<f32>(PI_R * seen / f32(slices), min(covered / f32(slices), 1.0));
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
        let t = source[q];
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
