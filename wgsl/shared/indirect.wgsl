// Indirect dispatches of one-dimensional workgroups: x up to 65535 (the smallest limit a device
// may have), the rest folded into y, as `gpu::dispatch_size` folds direct ones (though 0 groups
// stay 0 here: nothing runs).

// The arguments for `groups` workgroups.
fn indirect_size(groups: u32) -> vec3<u32> {
    return vec3<u32>(min(groups, 65535u), (groups + 65534u) / 65535u, 1u);
}

// The flat index of workgroup `wid` of such a dispatch.
fn indirect_group(wid: vec3<u32>) -> u32 {
    return wid.x + wid.y * 65535u;
}
