// Depth pyramids: camera-space (view) depth MIP chains of one G-buffer layer. Level 0 copies the
// G-buffer's view depth (pyramid_base). 0 marks "no surface".
// - pyramid_level: the rotated grid of shared/level.wgsl (one real depth of each 2x2 block). The
//   obscurance reads it.
// - pyramid_nearest: level l + 1 holds the nearest depth of its 2x2 block (0 only where all four
//   are empty), so texel (x, y) of level l bounds every pixel in [x, x + 1) x [y, y + 1) times
//   2^l from the front. The reflections' hierarchical march reads it.
// All levels are packed into one f32 buffer at offsets from `PyramidLayout` (src/frame/pyramid.rs).
// src/cpu/pyramid.rs is the same on the CPU.
// defines: PACKED

#include "shared/gbuffer.wgsl"
#include "shared/level.wgsl"

@group(0) @binding(0) var<uniform> level: PyramidLevel;
@group(0) @binding(1) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(2) var<storage, read_write> pyramid: array<f32>;

@compute @workgroup_size(8, 8)
fn pyramid_base(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= level.dst_width || gid.y >= level.dst_height {
        return;
    }
    let p = gid.y * level.dst_width + gid.x;
    pyramid[level.dst_offset + p] = gword_depth(gbuffer[p * G_WORDS]);
}

@compute @workgroup_size(8, 8)
fn pyramid_level(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= level.dst_width || gid.y >= level.dst_height {
        return;
    }
    pyramid[level.dst_offset + gid.y * level.dst_width + gid.x] = pyramid[rotated_grid_pick(level, gid.xy)];
}

// The nearer of two depths, 0 (no surface) counting as infinitely far.
fn nearer(a: f32, b: f32) -> f32 {
    if a > 0.0 && (b <= 0.0 || a < b) {
        return a;
    }
    return b;
}

@compute @workgroup_size(8, 8)
fn pyramid_nearest(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= level.dst_width || gid.y >= level.dst_height {
        return;
    }
    let x0 = 2u * gid.x;
    let y0 = 2u * gid.y;
    let x1 = min(x0 + 1u, level.src_width - 1u);
    let y1 = min(y0 + 1u, level.src_height - 1u);
    let row0 = level.src_offset + y0 * level.src_width;
    let row1 = level.src_offset + y1 * level.src_width;
    let top = nearer(pyramid[row0 + x0], pyramid[row0 + x1]);
    let bottom = nearer(pyramid[row1 + x0], pyramid[row1 + x1]);
    pyramid[level.dst_offset + gid.y * level.dst_width + gid.x] = nearer(top, bottom);
}
