// Resolve: visibility buffer -> G-buffer layer, one thread per pixel.
// defines: PACKED
//
// `resolve` runs at every pixel. A frame's own layers go through a list of 8x8 tiles instead,
// since on a driver that runs every lane of a SIMD group where one lane works (llvmpipe) a pixel
// without a surface costs as much as one with: `resolve_tiles` lists the tiles that hold a
// surface and writes the empty record over the others, `resolve_tiles_args` sizes the dispatch,
// and `resolve_listed` resolves the listed tiles. The records are the same either way.
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
#include "shared/indirect.wgsl"
#include "shared/list.wgsl"

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
// The tiles `resolve_listed` resolves, and its dispatch arguments (shared/list.wgsl).
@group(0) @binding(13) var<storage, read_write> list: array<atomic<u32>>;
@group(0) @binding(14) var<storage, read_write> list_args: array<u32>;

fn previous_vertex(i: u32) -> vec3<f32> {
    return vec3<f32>(previous_positions[3u * i], previous_positions[3u * i + 1u], previous_positions[3u * i + 2u]);
}

// Whether this frame's geometry moved (the frame's FRAME_OBJECT_MOTION, as a pipeline constant):
// without, the reads of the last frame's vertices are compiled out (see TEXTURES in
// shared/texture.wgsl for why).
override OBJECT_MOTION: bool = true;

// Whether pixel p's visibility word holds a surface the resolve can shade.
fn holds_surface(p: u32) -> bool {
    return vis[2u * p + 1u] != VIS_EMPTY && vis[2u * p] < frame.triangle_count;
}

fn shade(pixel: vec2<u32>) -> GSample {
    let p = pixel.y * frame.width + pixel.x;
    if !holds_surface(p) {
        return empty_sample();
    }
    let id = vis[2u * p];
    let depth_bits = vis[2u * p + 1u];
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
    // Both ends projected alike: the point's own place on screen now (its pixel centre up to the
    // rounding of the barycentrics), not the pixel centre, so that a still point's motion is 0.
    let pc = mat_mul(frame.prev_view_proj, vec4<f32>(was, 1.0));
    let nc = mat_mul(frame.view_proj, vec4<f32>(world, 1.0));
    if pc.w > 1e-20 && nc.w > 1e-20 {
        let size = vec2<f32>(f32(frame.width), f32(frame.height));
        let motion = clip_to_pixel(nc, size) - clip_to_pixel(pc, size);
        if all(abs(motion) < vec2<f32>(1e30)) {
            s.motion = motion;
        }
    }
    return s;
}

fn write_record(p: u32, s: GSample) {
    let words = gbuffer_encode(s);
    for (var i = 0u; i < G_WORDS; i++) {
        gbuffer[p * G_WORDS + i] = words[i];
    }
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    write_record(gid.y * frame.width + gid.x, shade(gid.xy));
}

// The 8x8 tiles of the image, and the pixel of tile t at offset `at` within it.
fn tile_count() -> vec2<u32> {
    return (vec2<u32>(frame.width, frame.height) + 7u) / 8u;
}

fn tile_pixel(t: u32, at: vec2<u32>) -> vec2<u32> {
    let tiles = tile_count();
    return vec2<u32>(t % tiles.x, t / tiles.x) * 8u + at;
}

// One thread per tile: lists the tiles that hold a surface and writes the empty record over the
// others.
@compute @workgroup_size(64)
fn resolve_tiles(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) n: vec3<u32>) {
    let tiles = tile_count();
    let t = gid.x + gid.y * n.x * 64u;
    if t >= tiles.x * tiles.y {
        return;
    }
    var found = false;
    for (var i = 0u; i < 64u && !found; i++) {
        let pixel = tile_pixel(t, vec2<u32>(i % 8u, i / 8u));
        found = pixel.x < frame.width && pixel.y < frame.height && holds_surface(pixel.y * frame.width + pixel.x);
    }
    if found {
        list_append(t);
        return;
    }
    for (var i = 0u; i < 64u; i++) {
        let pixel = tile_pixel(t, vec2<u32>(i % 8u, i / 8u));
        if pixel.x < frame.width && pixel.y < frame.height {
            write_record(pixel.y * frame.width + pixel.x, empty_sample());
        }
    }
}

// The listed tiles' count as indirect dispatch arguments, a workgroup each.
@compute @workgroup_size(1)
fn resolve_tiles_args() {
    list_write_group_args();
}

// Resolves the listed tiles, one 8x8 workgroup each.
@compute @workgroup_size(8, 8)
fn resolve_listed(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    var t = 0u;
    if !list_group_item(wid, &t) {
        return;
    }
    let pixel = tile_pixel(t, lid.xy);
    if pixel.x < frame.width && pixel.y < frame.height {
        write_record(pixel.y * frame.width + pixel.x, shade(pixel));
    }
}
