// The depth- and normal-aware weight of the bilateral filters (wgsl/blur.wgsl, wgsl/upsample.wgsl)
// for a sample at view depth z with normal n against the centre's zc, nc:
//     max(0, 1 - |z - zc| / (DEPTH_TOLERANCE zc)) max(0, n.nc)^8,
// so nothing bleeds across depth edges or creases. src/cpu/blur.rs (`bilateral_weight`,
// `plane_weight`) is the same on the CPU.

const DEPTH_TOLERANCE: f32 = 0.05;

fn bilateral_weight(z: f32, n: vec3<f32>, zc: f32, nc: vec3<f32>) -> f32 {
    let depth_weight = max(0.0, 1.0 - abs(z - zc) / (DEPTH_TOLERANCE * zc));
    let c = max(dot(n, nc), 0.0);
    let c2 = c * c;
    let c4 = c2 * c2;
    return depth_weight * c4 * c4;
}

// The weight of a sample at view-space point q against the centre's point c and view-space
// normal nc by its distance from the centre's tangent plane, in `footprint`s (the distance
// between neighbouring pixels' rays at the centre's depth, 1 / pixels_per_unit):
//     max(0, 1 - |nc.(q - c)| / footprint).
// A neighbour on the centre's plane weighs 1 however slanted the plane, one a pixel's footprint
// off it 0: the floor and top of a groove narrower than the depth tolerance stay apart.
fn plane_weight(q: vec3<f32>, c: vec3<f32>, nc: vec3<f32>, footprint: f32) -> f32 {
    return max(0.0, 1.0 - abs(dot(nc, q - c)) / footprint);
}
