// A list of the items (pixels, texels, tiles) a kernel runs at, built each frame, and the indirect
// dispatch over it, 64 items a workgroup or one workgroup an item (src/passes/mod.rs,
// `PointList`): the includer binds
// `list` ([0] the count, which the encoder clears, then the items) and `list_args` (the
// arguments; a separate buffer, as a dispatch may not read its indirect buffer as storage).
// Needs shared/indirect.wgsl.

// Appends `item`.
fn list_append(item: u32) {
    atomicStore(&list[1u + atomicAdd(&list[0], 1u)], item);
}

// Writes the count's dispatch arguments (one thread).
fn list_write_args() {
    let size = indirect_size((atomicLoad(&list[0]) + 63u) / 64u);
    list_args[0] = size.x;
    list_args[1] = size.y;
    list_args[2] = size.z;
}

// The item of invocation `li` of workgroup `wid` of that dispatch, or false past the count.
fn list_item(wid: vec3<u32>, li: u32, item: ptr<function, u32>) -> bool {
    let i = indirect_group(wid) * 64u + li;
    if i >= atomicLoad(&list[0]) {
        return false;
    }
    *item = atomicLoad(&list[1u + i]);
    return true;
}

// Writes the arguments of a dispatch of one workgroup per item (one thread).
fn list_write_group_args() {
    let size = indirect_size(atomicLoad(&list[0]));
    list_args[0] = size.x;
    list_args[1] = size.y;
    list_args[2] = size.z;
}

// The item of workgroup `wid` of that dispatch, or false past the count.
fn list_group_item(wid: vec3<u32>, item: ptr<function, u32>) -> bool {
    let i = indirect_group(wid);
    if i >= atomicLoad(&list[0]) {
        return false;
    }
    *item = atomicLoad(&list[1u + i]);
    return true;
}
