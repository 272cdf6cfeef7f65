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
#if LISTED
#include "shared/list.wgsl"
#endif

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
// The pixels to light (shared/list.wgsl).
@group(0) @binding(9) var<storage, read_write> list: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> list_args: array<u32>;
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
        list_append(p);
    }
}

// The listed pixels' count as indirect dispatch arguments.
@compute @workgroup_size(1)
fn direct_list_args() {
    list_write_args();
}

// Lights the listed pixels.
@compute @workgroup_size(64)
fn direct_listed(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    var p = 0u;
    if list_item(wid, li, &p) {
        shade(vec2<u32>(p % frame.width, p / frame.width));
    }
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
    let v = toward_camera(frame, world);
    let light = lit(s, world, v, direct.light_count, direct.pcf);
    radiance[p] = vec4<f32>(light.radiance, 1.0);
#if DIFFUSE
    diffuse[p] = vec4<f32>((1.0 - s.metallic) * s.base_color / PI * light.irradiance, 1.0);
#endif
}
