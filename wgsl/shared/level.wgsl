// One level's build of a rotated-grid MIP chain (wgsl/pyramid.wgsl): as in Scalable Ambient
// Obscurance, texel t of level l + 1 takes texel (2 t.x + (t.y & 1 ^ 1), 2 t.y + (t.x & 1 ^ 1))
// of level l (clamped to its size), so every level holds real values (no averages across
// edges) and the choice varies from block to block.

// Mirrors `LevelUniform` in src/frame/uniforms.rs.
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

// The index of the texel of the level below that texel t of level `l` takes.
fn rotated_grid_pick(l: PyramidLevel, t: vec2<u32>) -> u32 {
    let sx = min(2u * t.x + ((t.y & 1u) ^ 1u), l.src_width - 1u);
    let sy = min(2u * t.y + ((t.x & 1u) ^ 1u), l.src_height - 1u);
    return l.src_offset + sy * l.src_width + sx;
}
