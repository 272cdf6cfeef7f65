// Separable depth- and normal-aware (bilateral) blur of a scalar image (or, with VEC4, of a
// vec4 image), one direction per dispatch (VERTICAL or not). A tap's weight is a Gaussian of its
// distance times shared/bilateral.wgsl's depth and normal weight, so nothing bleeds across depth
// edges or creases, and with PLANE (the obscurance) its plane weight too, so that what varies
// from pixel to pixel with the geometry (a groove's floor against its rim) is not averaged
// away; pixels without a surface are skipped. Each tap reads the first word of its G-buffer
// record alone (depth and normal), not the whole record.
// src/cpu/blur.rs is the same on the CPU.
// defines: PACKED VERTICAL VEC4 PLANE

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/bilateral.wgsl"
#include "shared/value.wgsl"


// The radius in pixels, fixed per pipeline. A pipeline constant, not a uniform: lavapipe
// specializes shaders on uniform values that bound loops and, fed a new frame each time, kept
// compiling variants (about 20 ms and 1 MiB a frame at 32x24).
override RADIUS: u32 = 0u;

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> source: array<Value>;
@group(0) @binding(4) var<storage, read_write> blurred: array<Value>;


@compute @workgroup_size(8, 8)
fn blur_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let centre = gbuffer[p * G_WORDS];
    let zc = gword_depth(centre);
    if !(zc > 0.0) || RADIUS == 0u {
        blurred[p] = source[p];
        return;
    }
#if VERTICAL
    let step = vec2<i32>(0, 1);
#else
    let step = vec2<i32>(1, 0);
#endif
    let r = i32(RADIUS);
    let sigma = max(f32(r), 1.0) * 0.5;
#if PLANE
    let pc = view_position(frame, vec2<f32>(gid.xy) + 0.5, zc);
    let nc = mat_mul(frame.view, vec4<f32>(gword_normal(centre), 0.0)).xyz;
    let footprint = 1.0 / pixels_per_unit(frame, zc);
#endif
    var mean = Mean();
    for (var k = -r; k <= r; k++) {
        let tap = vec2<i32>(gid.xy) + step * k;
        if any(tap < vec2<i32>(0)) || tap.x >= i32(frame.width) || tap.y >= i32(frame.height) {
            continue;
        }
        let q = u32(tap.y) * frame.width + u32(tap.x);
        let word = gbuffer[q * G_WORDS];
        let z = gword_depth(word);
        if !(z > 0.0) {
            continue;
        }
        let fk = f32(k);
        let gauss = exp(-fk * fk / (2.0 * sigma * sigma));
        var w = gauss * bilateral_weight(z, gword_normal(word), zc, gword_normal(centre));
#if PLANE
        w *= plane_weight(view_position(frame, vec2<f32>(tap) + 0.5, z), pc, nc, footprint);
#endif
        mean_add(&mean, source[q], w);
    }
    if mean.weight > 0.0 {
        blurred[p] = mean_value(mean);
    } else {
        blurred[p] = source[p];
    }
}
