// Composite: DIRECT + AV * AMBIENT + RADIOSITY + emission into an HDR image (rgb, a = 1 on
// surfaces), as wgsl/shared/shade.wgsl shades a surface: AV is 1 without obscurance (AO
// undefined), the gather's irradiance and coverage 0 without RADIOSITY (which leaves
// AV * ambient * albedo). Pixels without a surface show the sky. With REFLECTIONS the reflected
// radiance (already scaled by the reflectivity) is added.
// src/cpu/composite.rs is the same on the CPU.
// defines: PACKED AO RADIOSITY REFLECTIONS

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/gbuffer_read.wgsl"
#include "shared/shade.wgsl"

// Mirrors `CompositeUniform` in src/frame/uniforms.rs.
struct Composite {
    ambient: vec3<f32>,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> composite: Composite;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> direct: array<vec4<f32>>;
#if AO
@group(0) @binding(4) var<storage, read> av: array<f32>;
#endif
@group(0) @binding(5) var<storage, read_write> hdr: array<vec4<f32>>;
#if RADIOSITY
@group(0) @binding(6) var<storage, read> radiosity: array<vec4<f32>>;
#endif
#if REFLECTIONS
@group(0) @binding(7) var<storage, read> reflections: array<vec4<f32>>;
#endif


@compute @workgroup_size(8, 8)
fn composite_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let s = sample_at(p);
    if !(s.depth > 0.0) {
        hdr[p] = vec4<f32>(composite.ambient, 0.0);
        return;
    }
    var visibility = 1.0;
#if AO
    visibility = av[p];
#endif
    var irradiance = vec4<f32>(0.0);
#if RADIOSITY
    irradiance = radiosity[p];
#endif
    var mirrored = vec3<f32>(0.0);
#if REFLECTIONS
    mirrored = reflections[p].rgb;
#endif
    hdr[p] = vec4<f32>(shaded(s, direct[p].rgb, visibility, irradiance, composite.ambient) + mirrored, 1.0);
}
