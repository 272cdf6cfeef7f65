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
// as the ground truth defines it. Directions are grouped in slices: planes through the view
// vector V, one per screen direction phi (phi in [0, pi), turned per pixel). In a slice a
// direction is its angle theta from V, the hemisphere is theta in [gamma - pi/2, gamma + pi/2]
// (gamma: the angle of the normal projected into the slice, n_p), and dw = |sin theta| dtheta
// dphi, so the slice's share of the integral is
//     |n_p| integral f(d(theta)) cos(theta - gamma) |sin theta| dtheta,
// whose weight W(theta) has a closed form. The slice's arc is cut into SECTORS sectors of equal
// weight (a sector is a bit), and steps marched outwards on both sides along the slice's screen
// line read each layer's point at that pixel (the pyramid level whose texels match the step
// spacing). A point hides the arc from its own direction to the direction of its back: the
// point `thickness` behind it along its view ray, no deeper than the next layer's surface there
// (`bitmask`), or without end (`horizon`, thickness 0: a height field). A point whose solid
// comes within r of the shading point hides the sectors of that arc that no nearer step hid
// yet, counted at the falloff of the point's own distance (the surface is what a direction
// meets first; the solid behind it only decides which directions those are: taking the solid's
// nearest point instead darkens with the thickness, measured). Points are lowered by beta along
// the normal (a plane's own taps fall below its tangent plane: an open plane stays exactly 1).
// Then
//     AV = clamp(1 - intensity / S sum_slices |n_p| W_total hidden_weight / SECTORS, 0, 1),
// the Monte Carlo estimate over phi (dphi / pi per slice): it converges to the integral as
// slices and steps grow, up to what the two layers do not show.
// defines: PACKED TWO_LAYERS SLICES

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/spiral.wgsl"

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

fn level_size(level: u32) -> vec2<u32> {
    var size = vec2<u32>(frame.width, frame.height);
    for (var i = 0u; i < level; i++) {
        size = (size + 1u) / 2u;
    }
    return size;
}

// The full-resolution pixel whose depth texel t of `level` holds (the rotated-grid choices of
// wgsl/pyramid.wgsl followed back down), so a tap's point is reconstructed where it really is.
fn texel_origin(level: u32, t: vec2<u32>) -> vec2<u32> {
    var p = t;
    for (var l = level; l > 0u; l--) {
        let below = level_size(l - 1u);
        p = min(vec2<u32>(2u * p.x + ((p.y & 1u) ^ 1u), 2u * p.y + ((p.x & 1u) ^ 1u)), below - 1u);
    }
    return p;
}

fn normal_at(p: u32) -> vec3<f32> {
#if PACKED
    return gbuffer_decode(gbuffer[p * G_WORDS], gbuffer[p * G_WORDS + 1u]).normal;
#else
    return gbuffer[p * G_WORDS].yzw;
#endif
}

fn obscurance(c: vec3<f32>, n: vec3<f32>, y: vec3<f32>) -> f32 {
    let v = y - c;
    let vv = dot(v, v);
    let r2 = ao.radius * ao.radius;
    return max(1.0 - vv / r2, 0.0) * max((dot(v, n) - ao.bias) / sqrt(vv + 1e-4 * r2), 0.0);
}

fn visibility(pixel: vec2<u32>) -> f32 {
    let p = pixel.y * frame.width + pixel.x;
    let z = pyramid0[p];
    if !(z > 0.0) || ao.samples == 0u || !(ao.radius > 0.0) {
        return 1.0;
    }
    let c = view_position(frame, vec2<f32>(pixel) + 0.5, z);
    let n = normalize(mat_mul(frame.view, vec4<f32>(normal_at(p), 0.0)).xyz);
    let r_px = ao.radius * pixels_per_unit(frame, z);
    var sum = 0.0;
    for (var i = 0u; i < ao.samples; i++) {
        let h = spiral_distance(i, ao.samples, r_px);
        let tap = spiral_tap(pixel, i, ao.samples, r_px);
        if any(tap < vec2<i32>(0)) || tap.x >= i32(frame.width) || tap.y >= i32(frame.height) {
            continue;
        }
        let level = u32(clamp(i32(floor(log2(max(h, 1.0)))) - i32(ao.mip_offset), 0, i32(ao.levels) - 1));
        let t = vec2<u32>(tap) >> vec2<u32>(level);
        let q = level_offset(level) + t.y * level_size(level).x + t.x;
        let at = vec2<f32>(texel_origin(level, t)) + 0.5;
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

const SECTORS: u32 = 32u;
const PI: f32 = 3.14159265;

// The pyramid texel of `level` under pixel `tap`: its index and the pixel centre it came from.
fn pyramid_texel(tap: vec2<i32>, level: u32, index: ptr<function, u32>) -> vec2<f32> {
    let t = vec2<u32>(tap) >> vec2<u32>(level);
    *index = level_offset(level) + t.y * level_size(level).x + t.x;
    return vec2<f32>(texel_origin(level, t)) + 0.5;
}

// Antiderivative of cos(t - gamma) sin(t).
fn arc_f(t: f32, gamma: f32) -> f32 {
    return -0.25 * cos(2.0 * t - gamma) + 0.5 * t * sin(gamma);
}

// W(theta): the weight integral of cos(t - gamma) |sin t| from the arc's start gamma - pi/2.
fn arc_weight(theta: f32, gamma: f32) -> f32 {
    let start = arc_f(gamma - 0.5 * PI, gamma);
    if theta <= 0.0 {
        return start - arc_f(theta, gamma);
    }
    return start + arc_f(theta, gamma) - 2.0 * arc_f(0.0, gamma);
}

// One slice's frame: V, gamma and the arc's total weight.
struct Slice {
    v: vec3<f32>,
    gamma: f32,
    total: f32,
    // Offset in [0, 1) of the sectors' centres (turned per pixel, so that no direction is
    // always rounded the same way).
    offset: f32,
}

// The slice angle of direction d from a tap on the slice's `side` (+-1): d turned about V into
// the slice, on that side (its angle from V kept, as a tap just off the slice's line should
// count; a projection could carry a point below the tangent plane into the hemisphere).
fn angle_in(sl: Slice, d: vec3<f32>, side: f32) -> f32 {
    return side * acos(clamp(dot(d, sl.v) / max(length(d), 1e-30), -1.0, 1.0));
}

// The sectors whose centres lie in the arc between directions theta0 and theta1.
fn sector_bits(sl: Slice, theta0: f32, theta1: f32) -> u32 {
    let lo = clamp(min(theta0, theta1), sl.gamma - 0.5 * PI, sl.gamma + 0.5 * PI);
    let hi = clamp(max(theta0, theta1), sl.gamma - 0.5 * PI, sl.gamma + 0.5 * PI);
    let scale = f32(SECTORS) / sl.total;
    let first = i32(ceil(arc_weight(lo, sl.gamma) * scale - sl.offset));
    let last = min(i32(floor(arc_weight(hi, sl.gamma) * scale - sl.offset)), i32(SECTORS) - 1);
    let a = max(first, 0);
    if last < a {
        return 0u;
    }
    let count = u32(last - a + 1);
    let ones = select((1u << count) - 1u, 0xffffffffu, count >= 32u);
    return ones << u32(a);
}

// Distance from c to the segment from y to y + (back - y) (back at infinity when `endless`,
// along the direction of back - y).
fn segment_distance(c: vec3<f32>, y: vec3<f32>, back: vec3<f32>, endless: bool) -> f32 {
    let d = back - y;
    let dd = dot(d, d);
    var t = 0.0;
    if dd > 0.0 {
        t = max(dot(c - y, d) / dd, 0.0);
        if !endless {
            t = min(t, 1.0);
        }
    }
    return length(y + d * t - c);
}

// The sectors a point at view depth z (pixel centre `at`, on the slice's positive side when
// side > 0) hides from c, and the falloff they take (none unless its solid comes within r);
// `back` is the depth its solid ends at (0: without end, towards theta = +-pi on its side: the
// far end of its view ray, seen from c, lies off c's own ray on the tap's side).
fn hidden(sl: Slice, c: vec3<f32>, n: vec3<f32>, at: vec2<f32>, side: f32, z: f32, back: f32, bits: ptr<function, u32>) -> f32 {
    // Lowered by beta along the normal.
    let lower = n * ao.bias;
    let y = view_position(frame, at, z) - lower;
    let endless = !(back > z);
    var far = view_position(frame, at, select(back, 2.0 * z, endless)) - lower;
    let nearest = segment_distance(c, y, far, endless);
    let r2 = ao.radius * ao.radius;
    // A point on or below the tangent plane hides nothing, nor does the solid behind it (its
    // view ray runs away from the camera, further below).
    if !(nearest * nearest < r2) || !(dot(y - c, n) > 0.0) {
        *bits = 0u;
        return 0.0;
    }
    let theta0 = angle_in(sl, y - c, side);
    var theta1 = angle_in(sl, far - c, side);
    if endless {
        theta1 = PI * side;
    }
    *bits = sector_bits(sl, theta0, theta1);
    let front = dot(y - c, y - c);
    return max(1.0 - front / r2, 0.0);
}

fn slice_visibility(pixel: vec2<u32>) -> f32 {
    let p = pixel.y * frame.width + pixel.x;
    let z = pyramid0[p];
    if !(z > 0.0) || ao.samples == 0u || !(ao.radius > 0.0) {
        return 1.0;
    }
    let c = view_position(frame, vec2<f32>(pixel) + 0.5, z);
    let n = normalize(mat_mul(frame.view, vec4<f32>(normal_at(p), 0.0)).xyz);
    let v = select(normalize(-c), vec3<f32>(0.0, 0.0, 1.0), frame.ortho != 0u);
    let r_px = ao.radius * pixels_per_unit(frame, z);
    let slices = max(ao.slices, 1u);
    let steps = max(ao.samples / (2u * slices), 1u);
    let spacing = r_px / f32(steps);
    let level = u32(clamp(i32(floor(log2(max(spacing, 1.0)))), 0, i32(ao.levels) - 1));
    let hash = pixel_hash(pixel);
    let turn = f32(hash >> 20u) / 4096.0;
    let jitter = f32((hash >> 8u) & 0xfffu) / 4096.0;
    let offset = f32(hash & 0xffu) / 256.0 + 0.5 / 256.0;
    var total = 0.0;
    for (var k = 0u; k < slices; k++) {
        let phi = PI * (f32(k) + turn) / f32(slices);
        let dir = vec2<f32>(cos(phi), sin(phi));
        // Screen y runs down, view y up.
        let s_view = vec3<f32>(dir.x, -dir.y, 0.0);
        var sl: Slice;
        sl.v = v;
        let axis = normalize(s_view - v * dot(s_view, v));
        let plane = cross(v, axis);
        let np = n - plane * dot(n, plane);
        let np_len = length(np);
        if !(np_len > 1e-6) {
            continue;
        }
        sl.gamma = clamp(atan2(dot(np, axis), dot(np, v)), -0.5 * PI, 0.5 * PI);
        sl.total = arc_weight(sl.gamma + 0.5 * PI, sl.gamma);
        sl.offset = offset;
        var occupied = 0u;
        var hidden_weight = 0.0;
        for (var j = 0u; j < steps; j++) {
            let h = spacing * (f32(j) + jitter);
            for (var side = 0u; side < 2u; side++) {
                let along = select(1.0, -1.0, side == 1u);
                let tap = vec2<i32>(floor(vec2<f32>(pixel) + 0.5 + along * h * dir));
                if any(tap < vec2<i32>(0)) || tap.x >= i32(frame.width) || tap.y >= i32(frame.height) || all(vec2<u32>(tap) == pixel) {
                    continue;
                }
                var q = 0u;
                let at = pyramid_texel(tap, level, &q);
                let z0 = pyramid0[q];
                if !(z0 > 0.0) {
                    continue;
                }
                var z1 = 0.0;
#if TWO_LAYERS
                z1 = pyramid1[q];
#endif
                var back0 = 0.0;
                if ao.thickness > 0.0 {
                    back0 = z0 + ao.thickness;
                    if z1 > z0 {
                        back0 = min(back0, z1);
                    }
                } else if z1 > z0 {
                    back0 = z1;
                }
                var bits = 0u;
                let f0 = hidden(sl, c, n, at, along, z0, back0, &bits);
                hidden_weight += f0 * f32(countOneBits(bits & ~occupied));
                occupied |= bits;
                if z1 > z0 {
                    let back1 = select(0.0, z1 + ao.thickness, ao.thickness > 0.0);
                    let f1 = hidden(sl, c, n, at, along, z1, back1, &bits);
                    hidden_weight += f1 * f32(countOneBits(bits & ~occupied));
                    occupied |= bits;
                }
            }
        }
        total += np_len * sl.total * hidden_weight / f32(SECTORS);
    }
    return clamp(1.0 - ao.intensity * total / f32(slices), 0.0, 1.0);
}

@compute @workgroup_size(8, 8)
fn ao_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
#if SLICES
    av[gid.y * frame.width + gid.x] = slice_visibility(gid.xy);
#else
    av[gid.y * frame.width + gid.x] = visibility(gid.xy);
#endif
}
