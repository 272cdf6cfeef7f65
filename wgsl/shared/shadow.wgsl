// Shadow-map lookup: percentage-closer filtering over depth maps drawn by the compute rasterizer
// (visibility words, depth in the high word). Mirrors `ShadowFace` in src/frame/shadow.rs;
// src/cpu/direct.rs has the same functions.

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
