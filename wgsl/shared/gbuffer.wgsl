// One G-buffer sample and its two encodings. Mirrors src/gbuffer.rs.
//
// Full (PACKED undefined), 4 x vec4<f32> per pixel:
//   [view depth, normal.xyz] [base colour.rgb, roughness] [emissive.rgb, metallic]
//   [motion.xy (pixels, current - previous), reflectivity + occlusion, material id]
//   where reflectivity + occlusion = round(4095 reflectivity) + 4096 round(4095 occlusion), an
//   integer below 2^24 (exact as f32)
// Packed (PACKED), 2 x vec4<u32> per pixel:
//   [depth f32 bits, octahedral normal snorm16x2, base colour + roughness unorm8x4, emissive.rg f16x2]
//   [emissive.b + metallic f16x2, motion f16x2, reflectivity unorm16 | material id << 16 (id < 65536),
//    occlusion unorm16]
// Normals are world space, unit length, facing the camera; depth 0 marks a pixel with no surface.

struct GSample {
    depth: f32,
    normal: vec3<f32>,
    base_color: vec3<f32>,
    roughness: f32,
    emissive: vec3<f32>,
    metallic: f32,
    motion: vec2<f32>,
    reflectivity: f32,
    // The material's ambient occlusion (its occlusion texture; 1 without one).
    occlusion: f32,
    material: u32,
}

const F16_MAX: f32 = 65504.0;

fn oct_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z >= 0.0 {
        return p;
    }
    return (1.0 - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
}

fn oct_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}

// f32 <-> binary16 by hand: the pack2x16float builtin needs a capability some devices lack.
fn f16_bits(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    let sign = (b >> 16u) & 0x8000u;
    let a = b & 0x7fffffffu;
    if a >= 0x47800000u {
        return sign | select(0x7c00u, 0x7e00u, a > 0x7f800000u);
    }
    if a < 0x38800000u {
        return sign | u32(round(bitcast<f32>(a) * 16777216.0));
    }
    // Round the mantissa to 10 bits, ties to even, and rebias the exponent.
    return sign | ((a + 0x0fffu + ((a >> 13u) & 1u) - 0x38000000u) >> 13u);
}

fn f16_value(h: u32) -> f32 {
    let sign = (h & 0x8000u) << 16u;
    let e = (h >> 10u) & 0x1fu;
    let m = h & 0x3ffu;
    if e == 0u {
        return select(1.0, -1.0, sign != 0u) * f32(m) * 5.9604645e-8;
    }
    if e == 31u {
        return bitcast<f32>(sign | 0x7f800000u | (m << 13u));
    }
    return bitcast<f32>(sign | ((e + 112u) << 23u) | (m << 13u));
}

#if PACKED
fn pack_half2(v: vec2<f32>) -> u32 {
    return f16_bits(v.x) | (f16_bits(v.y) << 16u);
}

fn unpack_half2(w: u32) -> vec2<f32> {
    return vec2<f32>(f16_value(w & 0xffffu), f16_value(w >> 16u));
}

alias GWord = vec4<u32>;
const G_WORDS: u32 = 2u;

fn gbuffer_encode(s: GSample) -> array<vec4<u32>, 2> {
    let e = min(s.emissive, vec3<f32>(F16_MAX));
    let m = clamp(s.motion, vec2<f32>(-F16_MAX), vec2<f32>(F16_MAX));
    var normal = 0u;
    if s.depth > 0.0 {
        normal = pack2x16snorm(oct_encode(s.normal));
    }
    return array<vec4<u32>, 2>(
        vec4<u32>(bitcast<u32>(s.depth), normal, pack4x8unorm(vec4<f32>(s.base_color, s.roughness)), pack_half2(e.rg)),
        vec4<u32>(pack_half2(vec2<f32>(e.b, s.metallic)), pack_half2(m),
                  (pack2x16unorm(vec2<f32>(s.reflectivity, 0.0)) & 0xffffu) | (min(s.material, 0xffffu) << 16u),
                  pack2x16unorm(vec2<f32>(s.occlusion, 0.0))),
    );
}

// The view depth held by a sample's first word (0: no surface).
fn gword_depth(w0: GWord) -> f32 {
    return bitcast<f32>(w0.x);
}

// The world-space normal held by a sample's first word (0 where there is no surface).
fn gword_normal(w0: GWord) -> vec3<f32> {
    return select(vec3<f32>(0.0), oct_decode(unpack2x16snorm(w0.y)), bitcast<f32>(w0.x) > 0.0);
}

// The word of a sample that holds its motion, and the motion it holds.
const G_MOTION_WORD: u32 = 1u;

fn gword_motion(w: GWord) -> vec2<f32> {
    return unpack_half2(w.y);
}

fn gbuffer_decode(w0: vec4<u32>, w1: vec4<u32>) -> GSample {
    var s: GSample;
    s.depth = bitcast<f32>(w0.x);
    s.normal = select(vec3<f32>(0.0), oct_decode(unpack2x16snorm(w0.y)), s.depth > 0.0);
    let c = unpack4x8unorm(w0.z);
    s.base_color = c.rgb;
    s.roughness = c.a;
    let bm = unpack_half2(w1.x);
    s.emissive = vec3<f32>(unpack_half2(w0.w), bm.x);
    s.metallic = bm.y;
    s.motion = unpack_half2(w1.y);
    s.reflectivity = unpack2x16unorm(w1.z & 0xffffu).x;
    s.occlusion = unpack2x16unorm(w1.w).x;
    s.material = w1.z >> 16u;
    return s;
}
#else
alias GWord = vec4<f32>;
const G_WORDS: u32 = 4u;

fn gbuffer_encode(s: GSample) -> array<vec4<f32>, 4> {
    return array<vec4<f32>, 4>(
        vec4<f32>(s.depth, s.normal),
        vec4<f32>(s.base_color, s.roughness),
        vec4<f32>(s.emissive, s.metallic),
        vec4<f32>(s.motion, pack_factors(s.reflectivity, s.occlusion), f32(s.material)),
    );
}

// Reflectivity and occlusion (12 bits each) as one integer-valued f32.
fn pack_factors(reflectivity: f32, occlusion: f32) -> f32 {
    let r = u32(round(clamp(reflectivity, 0.0, 1.0) * 4095.0));
    let o = u32(round(clamp(occlusion, 0.0, 1.0) * 4095.0));
    return f32(r + (o << 12u));
}

fn unpack_factors(x: f32) -> vec2<f32> {
    let v = u32(x);
    return vec2<f32>(f32(v & 0xfffu) / 4095.0, f32(v >> 12u) / 4095.0);
}

// The view depth held by a sample's first word (0: no surface).
fn gword_depth(w0: GWord) -> f32 {
    return w0.x;
}

// The world-space normal held by a sample's first word.
fn gword_normal(w0: GWord) -> vec3<f32> {
    return w0.yzw;
}

// The word of a sample that holds its motion, and the motion it holds.
const G_MOTION_WORD: u32 = 3u;

fn gword_motion(w: GWord) -> vec2<f32> {
    return w.xy;
}

fn gbuffer_decode(w0: vec4<f32>, w1: vec4<f32>, w2: vec4<f32>, w3: vec4<f32>) -> GSample {
    let factors = unpack_factors(w3.z);
    return GSample(w0.x, w0.yzw, w1.rgb, w1.a, w2.rgb, w2.a, w3.xy, factors.x, factors.y, u32(w3.w));
}
#endif
