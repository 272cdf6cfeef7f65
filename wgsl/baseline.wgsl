// The hardware-raster baseline for benchmarks: the same triangles (pulled from the same
// storage buffers) drawn by the fixed-function rasterizer into a depth target and an id target,
// so one run shows what compute rasterization costs against the hardware.
// defines:

#include "shared/frame.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) triangle: u32,
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> VertexOut {
    let v = indices[vi];
    let p = vec4<f32>(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u], 1.0);
    var out: VertexOut;
    out.position = mat_mul(frame.proj, mat_mul(frame.view, p));
    out.triangle = vi / 3u;
    return out;
}

@fragment
fn fs(in: VertexOut) -> @location(0) u32 {
    return in.triangle;
}
