// Direct light: deferred shading of one G-buffer layer (layer 0, and layer 1 where the radiosity
// or the reflections read it) by every light in one pass
// (O(pixels x lights)), written as outgoing radiance (rgb, a = 1 where there is a surface).
// With SHADOWS, a light with shadow faces is attenuated by percentage-closer filtering of its
// shadow map ((2 pcf + 1)^2 taps): the point is pushed along its normal by a texel, and compared
// with a constant plus slope-scaled bias (in texels of the map at that depth).
// With DIFFUSE the Lambertian part alone ((1 - metallic) base colour / pi times the irradiance,
// the same in every direction) goes to `diffuse` too: the light the radiosity gather passes on,
// which does not depend on where the camera is.
// src/cpu/direct.rs is the same on the CPU.
// defines: PACKED SHADOWS DIFFUSE

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/gbuffer_read.wgsl"
#include "shared/light.wgsl"
#include "shared/shadow.wgsl"

// Mirrors `DirectUniform` in src/frame/uniforms.rs.
struct Direct {
    light_count: u32,
    pcf: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> direct: Direct;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> lights: array<Light>;
@group(0) @binding(4) var<storage, read_write> radiance: array<vec4<f32>>;
#if DIFFUSE
@group(0) @binding(8) var<storage, read_write> diffuse: array<vec4<f32>>;
#endif
#if SHADOWS
@group(0) @binding(5) var<storage, read> faces: array<ShadowFace>;
// Per light: (first face, face count); count 0 for a light without shadow.
@group(0) @binding(6) var<storage, read> light_faces: array<vec2<u32>>;
// All faces' visibility words (id, depth bits) back to back.
@group(0) @binding(7) var<storage, read> atlas: array<vec2<u32>>;

fn shadow(i: u32, light: Light, world: vec3<f32>, n: vec3<f32>, l: vec3<f32>) -> f32 {
    let info = light_faces[i];
    if info.y == 0u {
        return 1.0;
    }
    let f = faces[info.x + shadow_face_index(info.y, world - light.position)];
    let texel = shadow_texel_world(f, world);
    let p = world + n * (texel * SHADOW_NORMAL_OFFSET_TEXELS);
    let c = mat_mul(f.proj, mat_mul(f.view, vec4<f32>(p, 1.0)));
    if !(c.w > 0.0) {
        return 1.0;
    }
    let res = f32(f.resolution);
    let uv = vec2<f32>((c.x / c.w * 0.5 + 0.5) * res, (0.5 - c.y / c.w * 0.5) * res);
    let depth = -mat_mul(f.view, vec4<f32>(p, 1.0)).z;
    let cos_theta = clamp(dot(n, l), 0.05, 1.0);
    let tan_theta = sqrt(1.0 - cos_theta * cos_theta) / cos_theta;
    let bias = texel * (SHADOW_BIAS_TEXELS + SHADOW_SLOPE_TEXELS * min(tan_theta, 10.0));
    let center = vec2<i32>(floor(uv));
    let k = i32(direct.pcf);
    var lit = 0.0;
    for (var dy = -k; dy <= k; dy++) {
        for (var dx = -k; dx <= k; dx++) {
            let t = clamp(center + vec2<i32>(dx, dy), vec2<i32>(0), vec2<i32>(i32(f.resolution) - 1));
            let word = atlas[f.offset + u32(t.y) * f.resolution + u32(t.x)];
            if word.y == 0xffffffffu || depth <= bitcast<f32>(word.y) + bias {
                lit += 1.0;
            }
        }
    }
    let side = f32(2 * k + 1);
    return lit / (side * side);
}
#endif


@compute @workgroup_size(8, 8)
fn direct_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let s = sample_at(p);
    if !(s.depth > 0.0) {
        radiance[p] = vec4<f32>(0.0);
#if DIFFUSE
        diffuse[p] = vec4<f32>(0.0);
#endif
        return;
    }
    let world = mat_mul(frame.inv_view, vec4<f32>(view_position(frame, vec2<f32>(gid.xy) + 0.5, s.depth), 1.0)).xyz;
    var v = normalize(frame.inv_view[3].xyz - world);
    if frame.ortho != 0u {
        v = normalize(frame.inv_view[2].xyz);
    }
    var sum = vec3<f32>(0.0);
    var irradiance = vec3<f32>(0.0);
    for (var i = 0u; i < direct.light_count; i++) {
        var l: vec3<f32>;
        let e = light_at(lights[i], world, &l);
        let nl = dot(s.normal, l);
        if nl > 0.0 {
            var visible = 1.0;
#if SHADOWS
            visible = shadow(i, lights[i], world, s.normal, l);
#endif
            sum += brdf(s.normal, v, l, s.base_color, s.roughness, s.metallic) * e * nl * visible;
            irradiance += e * nl * visible;
        }
    }
    radiance[p] = vec4<f32>(sum, 1.0);
#if DIFFUSE
    diffuse[p] = vec4<f32>((1.0 - s.metallic) * s.base_color / PI * irradiance, 1.0);
#endif
}
