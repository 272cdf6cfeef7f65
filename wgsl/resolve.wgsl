// Resolve: visibility buffer -> G-buffer layer, one thread per pixel.
// defines: PACKED
//
// The pixel's triangle is intersected with the ray through the pixel centre (in view space) for
// perspective-correct barycentrics; normal, uv and position interpolate with them. The depth is
// the visibility buffer's own, so the layer separation holds exactly in the G-buffer too.
// src/cpu/resolve.rs is the same computation on the CPU.

#include "shared/frame.wgsl"
#include "shared/material.wgsl"
#include "shared/vis.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/surface.wgsl"
#include "shared/barycentric.wgsl"
#include "shared/position.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> uvs: array<f32>;
@group(0) @binding(4) var<storage, read> indices: array<u32>;
@group(0) @binding(5) var<storage, read> tri_materials: array<u32>;
@group(0) @binding(6) var<storage, read> materials: array<Material>;
@group(0) @binding(7) var<storage, read> texels: array<u32>;
@group(0) @binding(8) var<storage, read> vis: array<u32>;
@group(0) @binding(9) var<storage, read_write> gbuffer: array<GWord>;
// The second coordinate set (2 per vertex) and the tangents (4 per vertex); a scene without
// them binds a short buffer, which reads as zero.
@group(0) @binding(10) var<storage, read> uvs1: array<f32>;
@group(0) @binding(11) var<storage, read> tangents: array<f32>;
// Each vertex's position in the last frame (read only with OBJECT_MOTION).
@group(0) @binding(12) var<storage, read> previous_positions: array<f32>;

fn previous_vertex(i: u32) -> vec3<f32> {
    return vec3<f32>(previous_positions[3u * i], previous_positions[3u * i + 1u], previous_positions[3u * i + 2u]);
}

// Whether this frame's geometry moved (the frame's FRAME_OBJECT_MOTION, as a pipeline constant):
// without, the reads of the last frame's vertices are compiled out (see TEXTURES in
// shared/texture.wgsl for why).
override OBJECT_MOTION: bool = true;

fn shade(pixel: vec2<u32>) -> GSample {
    let p = pixel.y * frame.width + pixel.x;
    let id = vis[2u * p];
    let depth_bits = vis[2u * p + 1u];
    if depth_bits == VIS_EMPTY || id >= frame.triangle_count {
        return empty_sample();
    }
    let d = bitcast<f32>(depth_bits);
    let i0 = indices[3u * id];
    let i1 = indices[3u * id + 1u];
    let i2 = indices[3u * id + 2u];
    let w0 = load3(0u, i0);
    let w1 = load3(0u, i1);
    let w2 = load3(0u, i2);
    let a = mat_mul(frame.view, vec4<f32>(w0, 1.0)).xyz;
    let b = mat_mul(frame.view, vec4<f32>(w1, 1.0)).xyz;
    let c = mat_mul(frame.view, vec4<f32>(w2, 1.0)).xyz;
    let ray = pixel_ray(frame, vec2<f32>(pixel) + 0.5, d);
    let bary = ray_barycentrics(ray, a, b, c);
    let world = w0 * bary.x + w1 * bary.y + w2 * bary.z;

    var s = surface_sample(id, vec3<u32>(i0, i1, i2), array<vec3<f32>, 3>(w0, w1, w2), bary, toward_camera(frame, world));
    s.depth = stored_depth(frame, d);
    // Motion: where this point was on screen in the previous frame: the same barycentrics on the
    // triangle as it stood then (OBJECT_MOTION), or the same world point (still geometry).
    var was = world;
    if OBJECT_MOTION && 3u * frame.vertex_count <= arrayLength(&previous_positions) {
        was = previous_vertex(i0) * bary.x + previous_vertex(i1) * bary.y + previous_vertex(i2) * bary.z;
    }
    let pc = mat_mul(frame.prev_view_proj, vec4<f32>(was, 1.0));
    if pc.w > 1e-20 {
        let prev = clip_to_pixel(pc, vec2<f32>(f32(frame.width), f32(frame.height)));
        let motion = vec2<f32>(pixel) + 0.5 - prev;
        if all(abs(motion) < vec2<f32>(1e30)) {
            s.motion = motion;
        }
    }
    return s;
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let words = gbuffer_encode(shade(gid.xy));
    for (var i = 0u; i < G_WORDS; i++) {
        gbuffer[p * G_WORDS + i] = words[i];
    }
}
