// Present: copies the HDR composite into a caller's storage texture (rgba32float, or with F16
// rgba16float), for hosts that want a texture rather than a buffer.
// defines: F16

#include "shared/frame.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> hdr: array<vec4<f32>>;
#if F16
@group(0) @binding(2) var output: texture_storage_2d<rgba16float, write>;
#else
@group(0) @binding(2) var output: texture_storage_2d<rgba32float, write>;
#endif

@compute @workgroup_size(8, 8)
fn present_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    textureStore(output, gid.xy, hdr[gid.y * frame.width + gid.x]);
}
