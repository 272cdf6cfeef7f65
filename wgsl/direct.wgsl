// Direct light: deferred shading of the layer-0 G-buffer by every light in one pass
// (O(pixels x lights)), written as outgoing radiance (rgb, a = 1 where there is a surface).
// Shadows are not applied yet: every light is unoccluded.
// src/cpu/direct.rs is the same on the CPU.
// defines: PACKED

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/light.wgsl"

// Mirrors `DirectUniform` in src/passes/direct.rs.
struct Direct {
    light_count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> direct: Direct;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> lights: array<Light>;
@group(0) @binding(4) var<storage, read_write> radiance: array<vec4<f32>>;

fn sample_at(p: u32) -> GSample {
#if PACKED
    return gbuffer_decode(gbuffer[p * G_WORDS], gbuffer[p * G_WORDS + 1u]);
#else
    return gbuffer_decode(gbuffer[p * G_WORDS], gbuffer[p * G_WORDS + 1u], gbuffer[p * G_WORDS + 2u], gbuffer[p * G_WORDS + 3u]);
#endif
}

@compute @workgroup_size(8, 8)
fn direct_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let s = sample_at(p);
    if !(s.depth > 0.0) {
        radiance[p] = vec4<f32>(0.0);
        return;
    }
    let world = mat_mul(frame.inv_view, vec4<f32>(view_position(frame, vec2<f32>(gid.xy) + 0.5, s.depth), 1.0)).xyz;
    var v = normalize(frame.inv_view[3].xyz - world);
    if frame.ortho != 0u {
        v = normalize(frame.inv_view[2].xyz);
    }
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < direct.light_count; i++) {
        var l: vec3<f32>;
        let e = light_at(lights[i], world, &l);
        let nl = dot(s.normal, l);
        if nl > 0.0 {
            sum += brdf(s.normal, v, l, s.base_color, s.roughness, s.metallic) * e * nl;
        }
    }
    radiance[p] = vec4<f32>(sum, 1.0);
}
