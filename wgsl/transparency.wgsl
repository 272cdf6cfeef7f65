// Transparency by depth peeling: blended surfaces over the opaque image.
//
// The rasterizer's PEEL variant (wgsl/raster.wgsl) finds, per pixel, the nearest fragment of a
// blended triangle strictly behind the previous peel and strictly in front of the opaque layer
// 0; the resolve turns it into a G-buffer sample and the direct pass lights it (with the shadow
// maps of the opaque scene). `accumulate` then adds that surface behind the ones peeled before
// it, front to back:
//     C += (1 - A) a S,   A += (1 - A) a,
// where S is the surface shaded as the composite shades one without obscurance, radiosity or
// reflections (direct light, emission, the ambient term: `shaded` in shared/shade.wgsl) and a
// its opacity at the pixel (base colour alpha times texture alpha). `composite` lays the sum
// over the opaque image: out = C + (1 - A) behind, which is the back-to-front blend
// C = a S + (1 - a) C_behind applied layer by layer. Blended surfaces cast no shadows and
// receive no obscurance, radiosity or reflections; surfaces past the k-th peel are left out.
// src/cpu/transparency.rs is the same on the CPU.
// defines: PACKED

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/gbuffer_read.wgsl"
#include "shared/shade.wgsl"
#include "shared/vis.wgsl"
#include "shared/opacity.wgsl"

// Mirrors `TransparencyUniform` in src/frame/uniforms.rs.
struct Transparency {
    ambient: vec3<f32>,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> transparency: Transparency;
// The peel's G-buffer sample, direct radiance and visibility word.
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> direct: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> vis: array<u32>;
@group(0) @binding(5) var<storage, read> positions: array<f32>;
@group(0) @binding(6) var<storage, read> indices: array<u32>;
@group(0) @binding(7) var<storage, read> tri_materials: array<u32>;
@group(0) @binding(8) var<storage, read> materials: array<Material>;
@group(0) @binding(9) var<storage, read> texels: array<u32>;
@group(0) @binding(10) var<storage, read> uvs: array<f32>;
@group(0) @binding(11) var<storage, read> uvs1: array<f32>;
// Per pixel: the blended radiance C (rgb) and coverage A (a) of the peels so far.
@group(0) @binding(12) var<storage, read_write> accum: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read> behind: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read_write> image: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let id = vis[2u * p];
    let depth_bits = vis[2u * p + 1u];
    if depth_bits == VIS_EMPTY || id >= frame.triangle_count || tri_materials[id] >= frame.material_count {
        return;
    }
    let s = sample_at(p);
    let colour = shaded(s, direct[p].rgb, 1.0, vec4<f32>(0.0), transparency.ambient);
    let a = triangle_opacity(frame, id, vec2<f32>(gid.xy) + 0.5, bitcast<f32>(depth_bits));
    var acc = accum[p];
    let w = (1.0 - acc.a) * a;
    acc = vec4<f32>(acc.rgb + w * colour, acc.a + w);
    accum[p] = acc;
}

@compute @workgroup_size(8, 8)
fn composite(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let acc = accum[p];
    let b = behind[p];
    image[p] = vec4<f32>(acc.rgb + (1.0 - acc.a) * b.rgb, b.a + (1.0 - b.a) * acc.a);
}
