// RGB9E5, the shared-exponent encoding of EXT_texture_shared_exponent: three 9-bit mantissas and
// one 5-bit exponent (bias 15) in 4 bytes, for non-negative radiance up to 65408, each channel
// within 2^-9 of the largest. NaN and negative channels read 0, larger ones the maximum.
// Every step is exact (exponents from the bits, scaling by powers of two), so the GPU and
// src/frame/source.rs, the same on the CPU, agree to the bit.

const RGB9E5_MAX: f32 = 65408.0;

fn pack_rgb9e5(c: vec3<f32>) -> u32 {
    let v = select(vec3<f32>(0.0), min(c, vec3<f32>(RGB9E5_MAX)), c > vec3<f32>(0.0));
    let m = max(v.r, max(v.g, v.b));
    // floor(log2 m) from the exponent bits; below 2^-16 the shared exponent stays at its least.
    var e = max(i32((bitcast<u32>(m) >> 23u) & 0xffu) - 127, -16) + 16;
    if floor(ldexp(m, 24 - e) + 0.5) >= 512.0 {
        e += 1;
    }
    let s = vec3<u32>(floor(ldexp(v, vec3<i32>(24 - e)) + 0.5));
    return s.r | (s.g << 9u) | (s.b << 18u) | (u32(e) << 27u);
}

fn unpack_rgb9e5(w: u32) -> vec3<f32> {
    let m = vec3<u32>(w & 0x1ffu, (w >> 9u) & 0x1ffu, (w >> 18u) & 0x1ffu);
    return ldexp(vec3<f32>(m), vec3<i32>(i32(w >> 27u) - 24));
}
