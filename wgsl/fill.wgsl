// Fills a u32 buffer with one value (clears visibility buffers to empty), copies one (keeps
// the scene's vertex positions for the next frame's motion vectors: a host's buffer need not
// allow copies, only storage), or extrapolates f32 words (predicts the next frame's positions).
// Mirrors `FillParams` in src/frame/uniforms.rs.
struct FillParams {
    value: u32,
    count: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: FillParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read> source: array<u32>;
@group(0) @binding(3) var<storage, read> earlier: array<u32>;

@compute @workgroup_size(256)
fn fill(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) n: vec3<u32>) {
    let i = gid.x + gid.y * n.x * 256u;
    if i < params.count {
        data[i] = params.value;
    }
}

@compute @workgroup_size(256)
fn copy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) n: vec3<u32>) {
    let i = gid.x + gid.y * n.x * 256u;
    if i < params.count {
        data[i] = source[i];
    }
}

// f32 words one step further along the way they went from `earlier` to `source`:
// 2 source - earlier (vertex positions a frame ahead, moving as they moved).
@compute @workgroup_size(256)
fn extrapolate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) n: vec3<u32>) {
    let i = gid.x + gid.y * n.x * 256u;
    if i < params.count {
        data[i] = bitcast<u32>(2.0 * bitcast<f32>(source[i]) - bitcast<f32>(earlier[i]));
    }
}
