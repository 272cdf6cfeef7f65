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

// The largest emitted radiance a material may give (`MAX_RADIANCE` in src/scene/mod.rs): the
// host's material buffers are not checked by the CPU, so the kernels bound what they read.
const MAX_RADIANCE: f32 = 1e20;

const MATERIAL_DOUBLE_SIDED: u32 = 1u;
const MATERIAL_TEXTURED: u32 = 2u;

// Whether material m has a texture that lies wholly inside a texel buffer of `texel_count`
// texels (checked without overflow: the host's materials are not checked by the CPU).
fn texture_fits(m: Material, texel_count: u32) -> bool {
    let w = m.texture_width;
    let h = m.texture_height;
    return w > 0u && h > 0u && w <= texel_count && h <= texel_count / w && m.texture_offset <= texel_count - w * h;
}

// v limited to [0, hi], NaN read as 0 (a comparison with NaN is false).
fn bounded(v: vec3<f32>, hi: f32) -> vec3<f32> {
    return select(vec3<f32>(0.0), min(v, vec3<f32>(hi)), v >= vec3<f32>(0.0));
}

// x limited to [0, 1], NaN read as 0.
fn unit(x: f32) -> f32 {
    return select(0.0, min(x, 1.0), x >= 0.0);
}
