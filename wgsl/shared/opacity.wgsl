// The opacity of a triangle at a pixel, for the rasterizer's alpha test and the transparency's
// blend (`triangle_opacity` in src/cpu/resolve.rs, which takes the pixel's centre), seen from
// frame `f` (the caller's frame uniform, or a copy loaded before a loop). The including kernel
// declares the bindings `positions`, `indices`, `tri_materials`, `materials`, `texels`, `uvs` and
// `uvs1`.

#include "shared/texture.wgsl"
#include "shared/barycentric.wgsl"

// Vertex i's view-space position.
fn opacity_vertex(f: Frame, i: u32) -> vec3<f32> {
    let p = vec4<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u], 1.0);
    return mat_mul(f.view, p).xyz;
}

// The opacity of triangle t where the ray through pixel point px meets it at view depth d.
fn triangle_opacity(f: Frame, t: u32, px: vec2<f32>, d: f32) -> f32 {
    let tri = vec3<u32>(indices[3u * t], indices[3u * t + 1u], indices[3u * t + 2u]);
    let ray = pixel_ray(f, px, d);
    let bary = ray_barycentrics(ray, opacity_vertex(f, tri.x), opacity_vertex(f, tri.y), opacity_vertex(f, tri.z));
    return material_opacity(tri_materials[t], tri, bary);
}
