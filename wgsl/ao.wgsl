// Two-layer ambient obscurance (Scalable Ambient Obscurance on a deep G-buffer), one thread per
// pixel, written to AV in [0, 1] (1: fully visible).
//
// For the layer-0 surface X at the pixel (view-space position C, view-space normal n), N taps
// lie on a golden-angle spiral (a low-discrepancy set of directions for any N) of projected
// radius r_px = radius * scale / z, rotated per pixel;
// tap i is at distance r_px * (i + 0.5) / N and reads depth from pyramid level
// clamp(floor(log2(distance)) - mip_offset, 0, levels - 1), reconstructing the point at the
// pixel that texel came from (so an open plane gives exactly zero). Each tap gives, for each layer's
// point Y at the tap (v = Y - C):
//     O(X, Y) = max(1 - v.v / r^2, 0) * max((v.n - beta) / sqrt(v.v + eps), 0),   eps = 1e-4 r^2
// and contributes the larger of the two layers' values (only layer 0 without TWO_LAYERS), so a
// thin object in front no longer hides what lies behind it. Then
//     AV = clamp(1 - intensity * 2 / N * sum_i O_i, 0, 1),
// the normalisation of Scalable Ambient Obscurance (McGuire et al. 2012) that the deep
// G-buffer paper also uses. src/cpu/ao.rs is the same on the CPU.
//
// With SLICES (the `horizon` and `bitmask` estimators) the integral itself is estimated,
//     AV = 1 - intensity (1/pi) integral over the hemisphere of f(d(w)) cos(theta) dw,
//     f(d) = max(1 - d^2/r^2, 0), d(w): distance to the first surface in direction w,
// as the ground truth defines it, over the slices of shared/slices.wgsl: steps spaced evenly
// out to the projected radius (or to the screen's edge where the slice's line leaves the screen
// first) read the pyramid as `sao` does (level floor(log2 h) - mip_offset
// for a step h pixels away), but never a level coarser than the step spacing; each
// layer's point there hides the arc of its solid (`thickness` deep, layer 0's no deeper than
// layer 1's surface and layer 1's no deeper than the gap in front of it, for `bitmask`; without end, a height field, for `horizon`: thickness 0), and the
// sectors it hides first count at the falloff of its own distance (the surface is what those
// directions meet first; the solid only decides which directions they are: taking the solid's
// nearest point instead darkens with the thickness, measured). Points are lowered by beta
// along the normal, so a plane's own taps fall below its tangent plane and an open plane stays
// exactly 1; their falloff keeps the true distance. With g = f in the slices' sum,
//     AV = clamp(1 - intensity / S sum_slices |n_p| W_total / SECTORS sum_sectors f, 0, 1),
// which converges to the integral as slices and steps grow, up to what the two layers do not
// show. Steps spaced apart miss the tops of what rises between them, so each slice's sum falls
// short by an amount that shrinks as the steps grow; each slice takes its sum S and the sum
// S_half of every other step alone (the same points, no further reads) and counts
// S + extrapolation (S - S_half) (Richardson's extrapolation in the steps a side).
// defines: PACKED TWO_LAYERS SLICES

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/spiral.wgsl"
#include "shared/slices.wgsl"
#include "shared/mip.wgsl"

// Mirrors `AoUniform` in src/frame/uniforms.rs.
struct Ao {
    radius: f32,
    bias: f32,
    intensity: f32,
    samples: u32,
    // Pyramid levels and their offsets in the packed pyramid buffers (up to 8).
    levels: u32,
    // A tap at distance h pixels reads level floor(log2 h) - mip_offset.
    mip_offset: u32,
    // Slices per pixel (SLICES).
    slices: u32,
    // How far an occluder reaches behind its surface; 0: without end (SLICES).
    thickness: f32,
    // Frames since the temporal filter's history began (0 without it): turns the slices, so
    // that wgsl/temporal.wgsl averages other directions every frame (SLICES).
    turn: u32,
    // Weight of the difference from the estimate of every other step (SLICES).
    extrapolation: f32,
    _pad1: u32,
    _pad2: u32,
    offsets: array<vec4<u32>, 2>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> ao: Ao;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> pyramid0: array<f32>;
#if TWO_LAYERS
@group(0) @binding(4) var<storage, read> pyramid1: array<f32>;
#endif
@group(0) @binding(5) var<storage, read_write> av: array<f32>;

fn level_offset(level: u32) -> u32 {
    return ao.offsets[level / 4u][level % 4u];
}

fn normal_at(p: u32) -> vec3<f32> {
    return gword_normal(gbuffer[p * G_WORDS]);
}

fn obscurance(c: vec3<f32>, n: vec3<f32>, y: vec3<f32>) -> f32 {
    let v = y - c;
    let vv = dot(v, v);
    let r2 = ao.radius * ao.radius;
    return max(1.0 - vv / r2, 0.0) * max((dot(v, n) - ao.bias) / sqrt(vv + 1e-4 * r2), 0.0);
}

// The shading point of `pixel`: view-space position and normal, and the radius in pixels (0
// where there is nothing to obscure).
struct Centre {
    c: vec3<f32>,
    n: vec3<f32>,
    r_px: f32,
}

fn centre(pixel: vec2<u32>) -> Centre {
    var out: Centre;
    let p = pixel.y * frame.width + pixel.x;
    let z = pyramid0[p];
    if !(z > 0.0) || ao.samples == 0u || !(ao.radius > 0.0) {
        out.r_px = 0.0;
        return out;
    }
    out.c = view_position(frame, vec2<f32>(pixel) + 0.5, z);
    out.n = normalize(mat_mul(frame.view, vec4<f32>(normal_at(p), 0.0)).xyz);
    out.r_px = ao.radius * pixels_per_unit(frame, z);
    return out;
}

// The pyramid texel of `level` under pixel `tap`: its index and the pixel centre it came from.
fn pyramid_texel(tap: vec2<i32>, level: u32, index: ptr<function, u32>) -> vec2<f32> {
    return mip_texel(tap, level, level_offset(level), index);
}

// The pyramid level a tap h pixels away reads: floor(log2 h) - mip_offset, at most `coarsest`.
fn tap_level(h: f32, coarsest: u32) -> u32 {
    return mip_level(h, ao.mip_offset, coarsest);
}

fn visibility(pixel: vec2<u32>, c: vec3<f32>, n: vec3<f32>, r_px: f32) -> f32 {
    var sum = 0.0;
    for (var i = 0u; i < ao.samples; i++) {
        let h = spiral_distance(i, ao.samples, r_px);
        let tap = spiral_tap(pixel, i, ao.samples, r_px);
        if any(tap < vec2<i32>(0)) || tap.x >= i32(frame.width) || tap.y >= i32(frame.height) {
            continue;
        }
        var q = 0u;
        let at = pyramid_texel(tap, tap_level(h, ao.levels - 1u), &q);
        var o = 0.0;
        let z0 = pyramid0[q];
        if z0 > 0.0 {
            o = obscurance(c, n, view_position(frame, at, z0));
        }
#if TWO_LAYERS
        let z1 = pyramid1[q];
        if z1 > 0.0 {
            o = max(o, obscurance(c, n, view_position(frame, at, z1)));
        }
#endif
        sum += o;
    }
    return clamp(1.0 - ao.intensity * 2.0 / f32(ao.samples) * sum, 0.0, 1.0);
}


// The falloff the sectors a layer-0 point hides first take (`last`: the falloff of the side's
// point before it where the surface is taken to run on from that one, else -1). Those sectors lie
// between the point's direction and those of the side's nearer steps; where the surface runs on
// from the step before (a floor into the wall it meets) it meets them at distances between the
// two points', so they take the mean of the two falloffs (the surface between two steps taken as
// straight: the trapezoid rule). The caller joins the two where the earlier point lies nearer the
// later than the receiving point does (a pole in front of a wall is not joined to the wall). With
// the point's own falloff alone, a step's share was counted at its farther distance: too little
// occlusion by what the steps' spacing leaves between them (+0.02 of mean AV on the Cornell box,
// along its creases).
fn step_falloff(falloff: f32, last: f32) -> f32 {
    return select(falloff, 0.5 * (falloff + last), last >= 0.0);
}

// The sectors a slice's steps have hidden (all of them, or every other one for the
// extrapolation) and their falloff-weighted count; `last` and `last_y`: the falloff of the
// side's last layer-0 point (-1: none yet) and the point.
struct Hidden {
    occupied: u32,
    sum: f32,
    last: f32,
    last_y: vec3<f32>,
}

fn hidden_new() -> Hidden {
    return Hidden(0u, 0.0, -1.0, vec3<f32>(0.0));
}

// Counts the sectors `bits` of a layer-0 point y (its falloff `falloff`) that nothing hid
// before, at step_falloff, joined to the side's last point where y lies nearer it than c does.
fn hide_front(h: ptr<function, Hidden>, bits: u32, falloff: f32, y: vec3<f32>, c: vec3<f32>) {
    let joined = (*h).last >= 0.0 && length(y - (*h).last_y) < length(y - c);
    (*h).sum += step_falloff(falloff, select(-1.0, (*h).last, joined)) * f32(countOneBits(bits & ~(*h).occupied));
    (*h).occupied |= bits;
    (*h).last = falloff;
    (*h).last_y = y;
}

// Counts the sectors `bits` of a layer-1 point that nothing hid before, at its own falloff.
fn hide_behind(h: ptr<function, Hidden>, bits: u32, falloff: f32) {
    (*h).sum += falloff * f32(countOneBits(bits & ~(*h).occupied));
    (*h).occupied |= bits;
}

// `noise_at`: the texel whose slice turns the pixel takes (itself at full resolution; its texel
// at a lower one, so that every 4x4 block of texels holds the 16 turns).
fn slice_visibility(pixel: vec2<u32>, noise_at: vec2<u32>, c: vec3<f32>, n: vec3<f32>, r_px: f32) -> f32 {
    let slices = max(ao.slices, 1u);
    let steps = max(ao.samples / (2u * slices), 1u);
    let noise = slice_noise(noise_at, ao.turn);
    let r2 = ao.radius * ao.radius;
    var total = 0.0;
    for (var k = 0u; k < slices; k++) {
        let sl = slice_at(k, slices, noise, c, n);
        if !(sl.weight > 0.0) {
            continue;
        }
        // Every step's sectors, and every other step's (j even) for the extrapolation.
        var every = hidden_new();
        var half = hidden_new();
        // The two sides hold opposite halves of the arc; each spreads its steps over the radius
        // or, where the slice's line leaves the screen first, over the part on screen.
        for (var side = 0u; side < 2u; side++) {
            let along = select(1.0, -1.0, side == 1u);
            let spacing = slice_spacing(pixel, sl, along, r_px, steps);
            let level = mip_coarsest(spacing, ao.levels);
            every.last = -1.0;
            half.last = -1.0;
            for (var j = 0u; j < steps; j++) {
                let h = step_distance(spacing, j, steps, noise.y);
                // Finer levels for the near steps, as `sao` reads them, never coarser than the
                // step spacing.
                let step_level = tap_level(h, level);
                var tap: vec2<i32>;
                if !slice_tap(pixel, sl, h, along, &tap) {
                    continue;
                }
                var q = 0u;
                let at = pyramid_texel(tap, step_level, &q);
                let z0 = pyramid0[q];
                if !(z0 > 0.0) {
                    continue;
                }
                var z1 = 0.0;
#if TWO_LAYERS
                z1 = pyramid1[q];
#endif
                let backs = solid_backs(z0, z1, ao.thickness);
                let even = (j & 1u) == 0u;
                var front2 = 0.0;
                var bits = solid_sectors(sl, c, n, at, along, z0, backs.x, ao.bias, ao.radius, &front2);
                var falloff = max(1.0 - front2 / r2, 0.0);
                let y = view_position(frame, at, z0);
                hide_front(&every, bits, falloff, y, c);
                if even {
                    hide_front(&half, bits, falloff, y, c);
                }
                if z1 > z0 {
                    bits = solid_sectors(sl, c, n, at, along, z1, backs.y, ao.bias, ao.radius, &front2);
                    falloff = max(1.0 - front2 / r2, 0.0);
                    hide_behind(&every, bits, falloff);
                    if even {
                        hide_behind(&half, bits, falloff);
                    }
                }
            }
        }
        total += sl.weight * (every.sum + ao.extrapolation * (every.sum - half.sum)) / f32(SECTORS);
    }
    return clamp(1.0 - ao.intensity * total / f32(slices), 0.0, 1.0);
}

// The level of the rotated grid whose texels are computed (0: every pixel; 1: half, 2: quarter
// resolution, each texel at the pixel it stands for, wgsl/upsample.wgsl filling in the rest).
override LEVEL: u32 = 0u;

@compute @workgroup_size(8, 8)
fn ao_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = mip_size(LEVEL);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let pixel = mip_origin(LEVEL, gid.xy);
    let x = centre(pixel);
    var v = 1.0;
    if x.r_px > 0.0 {
#if SLICES
        v = slice_visibility(pixel, gid.xy, x.c, x.n, x.r_px);
#else
        v = visibility(pixel, x.c, x.n, x.r_px);
#endif
    }
    av[gid.y * size.x + gid.x] = v;
}
