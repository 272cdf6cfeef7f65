// A rotated-grid MIP chain (wgsl/pyramid.wgsl: level l + 1 takes one texel of each 2x2 block of
// level l) of the frame's size, its levels packed into one buffer at the offsets of
// `PyramidLayout` (src/frame/pyramid.rs), and which level a tap reads. The obscurance taps the
// depth pyramids through it, the radiosity its gather source. Needs shared/frame.wgsl.
// src/cpu/pyramid.rs is the same on the CPU.

// The size of `level`: the frame's halved (rounding up) `level` times, which is the frame's size
// divided by 2^level, rounded up (no loop: the taps ask for it at every step).
fn mip_size(level: u32) -> vec2<u32> {
    let size = vec2<u32>(frame.width, frame.height);
    return (size + vec2<u32>((1u << level) - 1u)) >> vec2<u32>(level);
}

// The full-resolution pixel texel t of `level` was taken from (the rotated-grid choices followed
// back down), so a tap's point is reconstructed where it really is.
fn mip_origin(level: u32, t: vec2<u32>) -> vec2<u32> {
    var p = t;
    for (var l = level; l > 0u; l--) {
        let below = mip_size(l - 1u);
        p = min(vec2<u32>(2u * p.x + ((p.y & 1u) ^ 1u), 2u * p.y + ((p.x & 1u) ^ 1u)), below - 1u);
    }
    return p;
}

// The texel of `level` (whose first texel lies at `offset`) under pixel `tap`: its index, and
// the centre of the pixel it came from.
fn mip_texel(tap: vec2<i32>, level: u32, offset: u32, index: ptr<function, u32>) -> vec2<f32> {
    let t = vec2<u32>(tap) >> vec2<u32>(level);
    *index = offset + t.y * mip_size(level).x + t.x;
    return vec2<f32>(mip_origin(level, t)) + 0.5;
}

// floor(log2 x) for x >= 1 (1 for anything less, NaN included), exactly: the exponent bits
// (a log2 instruction may round 2^k - epsilon up to k).
fn floor_log2(x: f32) -> i32 {
    return i32((bitcast<u32>(max(x, 1.0)) >> 23u) & 0xffu) - 127;
}

// The level a tap h pixels away reads: floor(log2 h) - mip_offset, within [0, coarsest].
fn mip_level(h: f32, mip_offset: u32, coarsest: u32) -> u32 {
    return u32(clamp(floor_log2(h) - i32(mip_offset), 0, i32(coarsest)));
}

// The coarsest level a march of steps `spacing` pixels apart reads: floor(log2 spacing), within
// the chain's `levels` (a step never skips texels of the level it reads).
fn mip_coarsest(spacing: f32, levels: u32) -> u32 {
    return u32(clamp(floor_log2(spacing), 0, i32(levels) - 1));
}
