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
