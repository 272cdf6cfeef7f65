// How a material reads one texture. Mirrors `GpuTextureSlot` in src/scene/upload.rs.
struct TextureSlot {
    offset: u32,
    width: u32,
    height: u32,
    // bits 0-1: wrap across u, 2-3: across v (0 repeat, 1 clamp to edge, 2 mirrored repeat);
    // bit 4: nearest texel; bit 5: coordinate set 1
    sampler: u32,
    // uv' = (dot(transform_u.xy, uv) + transform_u.z, dot(transform_v.xy, uv) + transform_v.z);
    // transform_u.w: the slot's scale (normal scale, occlusion strength)
    transform_u: vec4<f32>,
    transform_v: vec4<f32>,
}

// A material as the kernels read it. Mirrors `GpuMaterial` in src/scene/upload.rs.
struct Material {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    roughness: f32,
    metallic: f32,
    reflectivity: f32,
    // bit 0: double-sided; bit 1 + k: texture slot k is used; MATERIAL_MASK, MATERIAL_BLEND
    flags: u32,
    // The opacity below which a masked material is cut away.
    alpha_cutoff: f32,
    slots: array<TextureSlot, 5>,
}

// The largest emitted radiance a material may give (`MAX_RADIANCE` in src/scene/mod.rs): the
// host's material buffers are not checked by the CPU, so the kernels bound what they read.
const MAX_RADIANCE: f32 = 1e20;

const MATERIAL_DOUBLE_SIDED: u32 = 1u;
// Alpha modes (`MATERIAL_MASK`, `MATERIAL_BLEND` in src/scene/upload.rs).
const MATERIAL_MASK: u32 = 64u;
const MATERIAL_BLEND: u32 = 128u;
// The texture slots, in the order of `Material::slots` (`SLOT_*` in src/scene/upload.rs).
const SLOT_BASE_COLOR: u32 = 0u;
const SLOT_EMISSIVE: u32 = 1u;
const SLOT_METALLIC_ROUGHNESS: u32 = 2u;
const SLOT_NORMAL: u32 = 3u;
const SLOT_OCCLUSION: u32 = 4u;
const SLOT_COUNT: u32 = 5u;

// The texture slots a material's flags say it uses, as bits 0..SLOT_COUNT-1.
fn slot_bits(flags: u32) -> u32 {
    return (flags >> 1u) & ((1u << SLOT_COUNT) - 1u);
}

// Whether texture slot t lies inside a texel buffer of texel_count texels (checked without
// overflow: the host's materials are not checked by the CPU).
fn texture_fits(t: TextureSlot, texel_count: u32) -> bool {
    let w = t.width;
    let h = t.height;
    return w > 0u && h > 0u && w <= texel_count && h <= texel_count / w && t.offset <= texel_count - w * h;
}

// v limited to [0, hi], NaN read as 0 (a comparison with NaN is false).
fn bounded(v: vec3<f32>, hi: f32) -> vec3<f32> {
    return select(vec3<f32>(0.0), min(v, vec3<f32>(hi)), v >= vec3<f32>(0.0));
}

// x limited to [0, 1], NaN read as 0.
fn unit(x: f32) -> f32 {
    return select(0.0, min(x, 1.0), x >= 0.0);
}
