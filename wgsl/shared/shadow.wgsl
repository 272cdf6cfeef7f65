// Shadow-map lookup: percentage-closer filtering over depth maps drawn by the compute rasterizer
// (visibility words, depth in the high word). Mirrors `ShadowFace` in src/frame/shadow.rs;
// src/cpu/direct.rs has the same functions. Needs shared/frame.wgsl.

struct ShadowFace {
    view: mat4x4<f32>,
    proj: mat4x4<f32>,
    // World size of one texel: at unit view depth (perspective) or anywhere (orthographic).
    texel: f32,
    ortho: u32,
    // First visibility word of this face in the atlas.
    offset: u32,
    resolution: u32,
}

// Constant and slope-scaled depth bias, in texels, and the normal offset, in texels.
const SHADOW_BIAS_TEXELS: f32 = 1.0;
const SHADOW_SLOPE_TEXELS: f32 = 2.0;
const SHADOW_NORMAL_OFFSET_TEXELS: f32 = 1.0;

// Which face of a light's `count` faces (1, or 6 for a point light: +x, -x, +y, -y, +z, -z)
// sees `d`, the direction from the light to the point.
fn shadow_face_index(count: u32, d: vec3<f32>) -> u32 {
    if count < 6u {
        return 0u;
    }
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1u, 0u, d.x > 0.0);
    }
    if a.y >= a.z {
        return select(3u, 2u, d.y > 0.0);
    }
    return select(5u, 4u, d.z > 0.0);
}

fn shadow_texel_world(f: ShadowFace, world: vec3<f32>) -> f32 {
    if f.ortho != 0u {
        return f.texel;
    }
    return f.texel * max(-mat_mul(f.view, vec4<f32>(world, 1.0)).z, 0.0);
}

#if SHADOWS
// The face of light i (`light`, which has a shadow map) whose view holds world point `world`.
fn shadow_face_at(i: u32, light: Light, world: vec3<f32>) -> ShadowFace {
    let info = light_faces[i];
    return faces[info.x + shadow_face_index(info.y, world - light.position)];
}

// The share of `light` (the i-th) that reaches the world point `world` (normal n, unit l towards
// the light) past its shadow map, with (2 pcf + 1)^2 taps. Reads the including kernel's
// bindings `faces` (ShadowFace per face), `light_faces` ((first face, face count) per light,
// count 0 for a light without shadow) and `atlas` (the faces' visibility words back to back).
fn shadow(i: u32, light: Light, world: vec3<f32>, n: vec3<f32>, l: vec3<f32>, pcf: u32) -> f32 {
    if light_faces[i].y == 0u {
        return 1.0;
    }
    let f = shadow_face_at(i, light, world);
    let texel = shadow_texel_world(f, world);
    let p = world + n * (texel * SHADOW_NORMAL_OFFSET_TEXELS);
    let c = mat_mul(f.proj, mat_mul(f.view, vec4<f32>(p, 1.0)));
    if !(c.w > 0.0) {
        return 1.0;
    }
    let res = f32(f.resolution);
    let uv = clip_to_pixel(c, vec2<f32>(res));
    let depth = -mat_mul(f.view, vec4<f32>(p, 1.0)).z;
    let cos_theta = clamp(dot(n, l), 0.05, 1.0);
    let tan_theta = sqrt(1.0 - cos_theta * cos_theta) / cos_theta;
    let bias = texel * (SHADOW_BIAS_TEXELS + SHADOW_SLOPE_TEXELS * min(tan_theta, 10.0));
    let center = vec2<i32>(floor(uv));
    let k = i32(pcf);
    var passed = 0.0;
    for (var dy = -k; dy <= k; dy++) {
        for (var dx = -k; dx <= k; dx++) {
            let t = clamp(center + vec2<i32>(dx, dy), vec2<i32>(0), vec2<i32>(i32(f.resolution) - 1));
            let word = atlas[f.offset + u32(t.y) * f.resolution + u32(t.x)];
            if word.y == 0xffffffffu || depth <= bitcast<f32>(word.y) + bias {
                passed += 1.0;
            }
        }
    }
    let side = f32(2 * k + 1);
    return passed / (side * side);
}
#endif
