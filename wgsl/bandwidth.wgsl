// Memory bandwidth probes (src/gpu/bandwidth.rs): `bandwidth_write` writes each word of
// `written` once; `bandwidth_read` reads each word of `source` once and folds what a thread read
// into one value, stored only when it differs from a value the data always folds to (so that
// no read can be left out, and the reads are all the traffic). Workgroup g of n takes the g-th
// of n contiguous blocks of vec4<u32> words, its threads side by side (lanes read neighbouring
// words: coalesced on a GPU, streamed on a CPU).

@group(0) @binding(0) var<storage, read_write> written: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read> source: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;

// The words of workgroup `group` of `groups` over `count` words: [first, end).
fn block(group: u32, groups: u32, count: u32) -> vec2<u32> {
    let size = ((count + groups - 1u) / groups + 255u) / 256u * 256u;
    return vec2<u32>(min(group * size, count), min(group * size + size, count));
}

@compute @workgroup_size(256)
fn bandwidth_write(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32, @builtin(num_workgroups) n: vec3<u32>) {
    let b = block(wid.x, n.x, arrayLength(&written));
    for (var i = b.x + lid; i < b.y; i += 256u) {
        written[i] = vec4<u32>(i);
    }
}

@compute @workgroup_size(256)
fn bandwidth_read(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32, @builtin(num_workgroups) n: vec3<u32>) {
    let b = block(wid.x, n.x, arrayLength(&source));
    var sum = vec4<u32>(0u);
    for (var i = b.x + lid; i < b.y; i += 256u) {
        sum ^= source[i];
    }
    // The write pass stores vec4(i): the components always fold to the same value.
    if sum.x != sum.y {
        sums[0] = sum.x;
    }
}
