// Depth- and normal-aware upsample of an effect computed at 1 / 2^LEVEL of the image's width
// and height back to every pixel. Texel t of the low-resolution image was computed at the pixel
// mip_origin(LEVEL, t) (shared/mip.wgsl: the rotated grid of the depth pyramid, a real pixel of
// its block); each pixel takes its four nearest texels with their bilinear weights times the
// blur's depth and normal weight (shared/bilateral.wgsl) of the surface at each texel's
// pixel against its own layer-0 surface, so nothing bleeds across depth edges or creases. Where
// none of the four passes (all weights 0) it takes the 4x4 texels around with the blur's
// weights alone, and where none of those passes either, the texel whose surface lies nearest in
// depth; a pixel without a surface, or whose 4x4 texels have none, takes EMPTY.
// src/cpu/upsample.rs is the same on the CPU.
// defines: PACKED VEC4

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/mip.wgsl"
#include "shared/bilateral.wgsl"
#include "shared/value.wgsl"


// The level the effect was computed at (1: half, 2: quarter resolution) and the value of pixels
// without a surface, fixed per pipeline.
override LEVEL: u32 = 1u;
override EMPTY: f32 = 0.0;

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> low: array<Value>;
@group(0) @binding(4) var<storage, read_write> full: array<Value>;

// One texel's part in a pixel's value: whether it stands for a surface, its value, its depth gap
// to the pixel's surface and the blur's depth and normal weight against it.
struct Candidate {
    valid: bool,
    value: Value,
    gap: f32,
    weight: f32,
}

fn candidate(t: vec2<u32>, size: vec2<u32>, z: f32, n: vec3<f32>) -> Candidate {
    var c: Candidate;
    let o = mip_origin(LEVEL, t);
    let w0 = gbuffer[(o.y * frame.width + o.x) * G_WORDS];
    let zo = gword_depth(w0);
    c.valid = zo > 0.0;
    if !c.valid {
        return c;
    }
    c.value = low[t.y * size.x + t.x];
    c.gap = abs(zo - z);
    c.weight = bilateral_weight(zo, gword_normal(w0), z, n);
    return c;
}

@compute @workgroup_size(8, 8)
fn upsample_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let z = gword_depth(gbuffer[p * G_WORDS]);
    if !(z > 0.0) {
        full[p] = Value(EMPTY);
        return;
    }
    let n = gword_normal(gbuffer[p * G_WORDS]);
    let size = mip_size(LEVEL);
    let last = vec2<f32>(size - 1u);
    let at = (vec2<f32>(gid.xy) + 0.5) / f32(1u << LEVEL) - 0.5;
    let base = floor(at);
    let f = at - base;
    var mean = Mean();
    for (var j = 0u; j < 4u; j++) {
        let corner = vec2<f32>(f32(j & 1u), f32(j >> 1u));
        let t = vec2<u32>(clamp(base + corner, vec2<f32>(0.0), last));
        let c = candidate(t, size, z, n);
        if c.valid {
            let b = select(1.0 - f, f, corner > vec2<f32>(0.5));
            mean_add(&mean, c.value, b.x * b.y * c.weight);
        }
    }
    if mean.weight > 0.0 {
        full[p] = mean_value(mean);
        return;
    }
    // No texel of the four stands for this surface (a thin strip, or an edge the rotated grid
    // picked the other side of): the 4x4 texels around, evenly weighted, else the one whose
    // surface lies nearest in depth.
    var nearest = Value(EMPTY);
    var nearest_gap = 3.0e38;
    for (var j = 0u; j < 16u; j++) {
        let t = vec2<u32>(clamp(base + vec2<f32>(f32(j & 3u), f32(j >> 2u)) - 1.0, vec2<f32>(0.0), last));
        let c = candidate(t, size, z, n);
        if c.valid {
            mean_add(&mean, c.value, c.weight);
            if c.gap < nearest_gap {
                nearest_gap = c.gap;
                nearest = c.value;
            }
        }
    }
    if mean.weight > 0.0 {
        full[p] = mean_value(mean);
    } else {
        full[p] = nearest;
    }
}
