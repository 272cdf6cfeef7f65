// A material as the kernels read it. Mirrors `GpuMaterial` in src/scene/upload.rs.
struct Material {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    roughness: f32,
    metallic: f32,
    reflectivity: f32,
    // bit 0: double-sided; bit 1: base-colour texture; bit 2: emissive texture; bit 3:
    // metallic-roughness texture
    flags: u32,
    texture_offset: u32,
    texture_width: u32,
    texture_height: u32,
    emissive_offset: u32,
    emissive_width: u32,
    emissive_height: u32,
    metallic_roughness_offset: u32,
    metallic_roughness_width: u32,
    metallic_roughness_height: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    _pad3: u32,
}

// The largest emitted radiance a material may give (`MAX_RADIANCE` in src/scene/mod.rs): the
// host's material buffers are not checked by the CPU, so the kernels bound what they read.
const MAX_RADIANCE: f32 = 1e20;

const MATERIAL_DOUBLE_SIDED: u32 = 1u;
const MATERIAL_TEXTURED: u32 = 2u;
const MATERIAL_EMISSIVE_TEXTURED: u32 = 4u;
const MATERIAL_METALLIC_ROUGHNESS_TEXTURED: u32 = 8u;

// Where a texture lies in the texel buffer.
struct TextureRef {
    offset: u32,
    width: u32,
    height: u32,
}

// Whether material m has a texture that lies wholly inside a texel buffer of `texel_count`
// texels (checked without overflow: the host's materials are not checked by the CPU).
fn base_texture(m: Material) -> TextureRef {
    return TextureRef(m.texture_offset, m.texture_width, m.texture_height);
}

fn emissive_texture(m: Material) -> TextureRef {
    return TextureRef(m.emissive_offset, m.emissive_width, m.emissive_height);
}

fn metallic_roughness_texture(m: Material) -> TextureRef {
    return TextureRef(m.metallic_roughness_offset, m.metallic_roughness_width, m.metallic_roughness_height);
}

// Whether material m uses the texture of flag `bit` and it lies inside a texel buffer of
// texel_count texels.
fn uses_texture(m: Material, bit: u32, t: TextureRef, texel_count: u32) -> bool {
    return (m.flags & bit) != 0u && texture_fits(t, texel_count);
}

// Whether material m names a texture that does not lie inside a texel buffer of texel_count
// texels (the resolve then leaves that texture out).
fn textures_outside(m: Material, texel_count: u32) -> bool {
    return ((m.flags & MATERIAL_TEXTURED) != 0u && !texture_fits(base_texture(m), texel_count))
        || ((m.flags & MATERIAL_EMISSIVE_TEXTURED) != 0u && !texture_fits(emissive_texture(m), texel_count))
        || ((m.flags & MATERIAL_METALLIC_ROUGHNESS_TEXTURED) != 0u && !texture_fits(metallic_roughness_texture(m), texel_count));
}

fn texture_fits(t: TextureRef, texel_count: u32) -> bool {
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
