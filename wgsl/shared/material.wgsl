// A material as the kernels read it. Mirrors `GpuMaterial` in src/scene/upload.rs.
struct Material {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    roughness: f32,
    metallic: f32,
    reflectivity: f32,
    // bit 0: double-sided; bit 1: has a base-colour texture
    flags: u32,
    texture_offset: u32,
    texture_width: u32,
    texture_height: u32,
    _pad0: u32,
    _pad1: u32,
}

const MATERIAL_DOUBLE_SIDED: u32 = 1u;
const MATERIAL_TEXTURED: u32 = 2u;

// Whether material m has a texture that lies wholly inside a texel buffer of `texel_count`
// texels (checked without overflow: the host's materials are not checked by the CPU).
fn texture_fits(m: Material, texel_count: u32) -> bool {
    let w = m.texture_width;
    let h = m.texture_height;
    return w > 0u && h > 0u && w <= texel_count && h <= texel_count / w && m.texture_offset <= texel_count - w * h;
}
