// Depth pyramid: camera-space (view) depth MIP chain of one G-buffer layer, as in Scalable
// Ambient Obscurance. Level 0 copies the G-buffer's view depth; level l + 1 takes one texel of
// each 2x2 block of level l in a rotated-grid pattern, so every level holds real depths (no
// averages across edges) and the choice varies from block to block. 0 marks "no surface".
// All levels are packed into one f32 buffer at offsets from `PyramidLayout` (src/frame/pyramid.rs).
// src/cpu/pyramid.rs is the same on the CPU.
// defines: PACKED

#include "shared/gbuffer.wgsl"

struct PyramidLevel {
    src_offset: u32,
    src_width: u32,
    src_height: u32,
    dst_offset: u32,
    dst_width: u32,
    dst_height: u32,
    _pad0: u32,
    _pad1: u32,
}

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
    // Rotated grid: (1, 1), (0, 1), (1, 0) or (0, 0) of the 2x2 block by the parity of x and y.
    let sx = min(2u * gid.x + ((gid.y & 1u) ^ 1u), level.src_width - 1u);
    let sy = min(2u * gid.y + ((gid.x & 1u) ^ 1u), level.src_height - 1u);
    pyramid[level.dst_offset + gid.y * level.dst_width + gid.x] = pyramid[level.src_offset + sy * level.src_width + sx];
}
