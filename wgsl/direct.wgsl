// Direct light: deferred shading of one G-buffer layer (layer 0, and layer 1 where the radiosity
// or the lens and shutter read it) by every light in one pass
// (O(pixels x lights)), written as outgoing radiance (rgb, a = 1 where there is a surface).
// With SHADOWS, a light with shadow faces is attenuated by percentage-closer filtering of its
// shadow map ((2 pcf + 1)^2 taps): the point is pushed along its normal by a texel, and compared
// with a constant plus slope-scaled bias (in texels of the map at that depth).
// With DIFFUSE the Lambertian part alone ((1 - metallic) base colour / pi times the irradiance,
// the same in every direction) goes to `diffuse` too: the light the radiosity gather passes on,
// which does not depend on where the camera is.
// With LISTED the layer is lit at the pixels `direct_list` finds a surface at only (layer 1,
// which few pixels hold; the encoder clears the targets and the list's count before).
// src/cpu/direct.rs is the same on the CPU.
// defines: PACKED SHADOWS DIFFUSE LISTED

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/gbuffer_read.wgsl"
#include "shared/lit.wgsl"
#include "shared/indirect.wgsl"

// Mirrors `DirectUniform` in src/frame/uniforms.rs.
struct Direct {
    light_count: u32,
    pcf: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> direct: Direct;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> lights: array<Light>;
@group(0) @binding(4) var<storage, read_write> radiance: array<vec4<f32>>;
#if DIFFUSE
@group(0) @binding(8) var<storage, read_write> diffuse: array<vec4<f32>>;
#endif
#if SHADOWS
@group(0) @binding(5) var<storage, read> faces: array<ShadowFace>;
// Per light: (first face, face count); count 0 for a light without shadow.
@group(0) @binding(6) var<storage, read> light_faces: array<vec2<u32>>;
// All faces' visibility words (id, depth bits) back to back.
@group(0) @binding(7) var<storage, read> atlas: array<vec2<u32>>;
#endif

#if LISTED
// The count, then the pixels to light.
@group(0) @binding(9) var<storage, read_write> points: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> args: array<u32>;
#endif

@compute @workgroup_size(8, 8)
fn direct_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    shade(gid.xy);
}

#if LISTED
// Lists the pixels that hold a surface.
@compute @workgroup_size(8, 8)
fn direct_list(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    if gword_depth(gbuffer[p * G_WORDS]) > 0.0 {
        atomicStore(&points[1u + atomicAdd(&points[0], 1u)], p);
    }
}

// The listed pixels' count as indirect dispatch arguments.
@compute @workgroup_size(1)
fn direct_list_args() {
    let size = list_size(atomicLoad(&points[0]));
    args[0] = size.x;
    args[1] = size.y;
    args[2] = size.z;
}

// Lights the listed pixels.
@compute @workgroup_size(64)
fn direct_listed(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let i = indirect_group(wid) * 64u + li;
    if i >= atomicLoad(&points[0]) {
        return;
    }
    let p = atomicLoad(&points[1u + i]);
    shade(vec2<u32>(p % frame.width, p / frame.width));
}
#endif

// Writes the direct light of the layer's sample at `pixel` (0 where it holds none).
fn shade(pixel: vec2<u32>) {
    let p = pixel.y * frame.width + pixel.x;
    let s = sample_at(p);
    if !(s.depth > 0.0) {
        radiance[p] = vec4<f32>(0.0);
#if DIFFUSE
        diffuse[p] = vec4<f32>(0.0);
#endif
        return;
    }
    let world = mat_mul(frame.inv_view, vec4<f32>(view_position(frame, vec2<f32>(pixel) + 0.5, s.depth), 1.0)).xyz;
    var v = normalize(frame.inv_view[3].xyz - world);
    if frame.ortho != 0u {
        v = normalize(frame.inv_view[2].xyz);
    }
    let light = lit(s, world, v, direct.light_count, direct.pcf);
    radiance[p] = vec4<f32>(light.radiance, 1.0);
#if DIFFUSE
    diffuse[p] = vec4<f32>((1.0 - s.metallic) * s.base_color / PI * light.irradiance, 1.0);
#endif
}
