// Depth of field through a thin lens, from both layers of the deep G-buffer.
//
// A lens of radius A focused at view depth F: the ray through lens point A u (u in the unit
// disc) and pixel p's point on the focus plane reaches, at view depth z, the point whose pinhole
// pixel is p - c(z) u, with c(z) = A s (1/F - 1/z) the signed circle of confusion in pixels (s:
// pixels per scene unit at depth 1). So each lens ray is a line across the image along which the
// depth it has reached grows with c: 1/z(c) = 1/F - c / (A s). For each of `samples` lens points
// (a Vogel disc turned per pixel) the kernel walks c over the range between the scene's nearest
// and farthest depths (within max_coc either way; while 1/z > 0),
// one pixel of image travel a step, on steps c = k dc so that c = 0 (the focus plane, pixel p
// itself) is one of them, and reads both layers at the pixel q = p - c u. The ray stops at the
// first surface it has reached: layer 0 where z(c) >= z0(q) and it crossed z0 in this step or
// lies no more than `thickness` z0 behind it; a ray farther behind runs on behind that surface
// (it is thinner than that), and stops at layer 1 likewise (TWO_LAYERS: what the nearest
// surface hides is what a blurred foreground edge uncovers). The pixel takes the mean of what
// its rays found: layer 0's radiance from the composite (`sharp`), layer 1's shaded as the
// composite shades a surface without obscurance, radiosity or reflections (direct light,
// emission, the ambient term). A ray that leaves the image or passes behind everything takes
// the sky where its walk ended on the sky, else the pinhole value sharp[p].
// src/cpu/dof.rs is the same on the CPU.
// defines: PACKED TWO_LAYERS

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/spiral.wgsl"
#include "shared/shade.wgsl"
#include "shared/layer1.wgsl"

// Mirrors `DofUniform` in src/frame/uniforms.rs.
struct Dof {
    ambient: vec3<f32>,
    // A s: the circle of confusion in pixels per unit of 1/F - 1/z.
    lens_px: f32,
    // The signed circles of confusion of the scene's nearest and farthest view depths, within
    // max_coc either way: the range a lens ray walks.
    coc_range: vec2<f32>,
    inv_focus: f32,
    samples: u32,
    thickness: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> dof: Dof;
@group(0) @binding(2) var<storage, read> gbuffer0: array<GWord>;
@group(0) @binding(3) var<storage, read> gbuffer1: array<GWord>;
@group(0) @binding(4) var<storage, read> direct1: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> sharp: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> hdr: array<vec4<f32>>;

// Whether a ray now at inverse depth `inv_z` (`inv_prev` a step before) has reached a surface at
// view depth z (0: none): it is behind it, and either crossed its depth in this step or is no
// more than `thickness` z behind it.
fn reached(inv_prev: f32, inv_z: f32, z: f32) -> bool {
    return z > 0.0 && inv_z <= 1.0 / z && (inv_prev > 1.0 / z || inv_z >= 1.0 / (z * (1.0 + dof.thickness)));
}

// What the ray through lens point u (unit disc) finds for pixel p.
fn lens_ray(pixel: vec2<u32>, u: vec2<f32>) -> vec4<f32> {
    let p = pixel.y * frame.width + pixel.x;
    let travel = length(u);
    if !(travel * max(-dof.coc_range.x, dof.coc_range.y) >= 0.5) {
        // The ray stays within half a pixel of p: the pinhole ray.
        return sharp[p];
    }
    let dc = 1.0 / travel;
    let k_lo = i32(ceil(dof.coc_range.x / dc));
    let k_hi = i32(floor(dof.coc_range.y / dc));
    var last = p;
    var inv_prev = dof.inv_focus - f32(k_lo - 1) * dc / dof.lens_px;
    for (var k = k_lo; k <= k_hi; k++) {
        let c = f32(k) * dc;
        let inv_z = dof.inv_focus - c / dof.lens_px;
        if !(inv_z > 0.0) {
            break;
        }
        let at = floor(vec2<f32>(pixel) + 0.5 - c * u);
        if any(at < vec2<f32>(0.0)) || at.x >= f32(frame.width) || at.y >= f32(frame.height) {
            return sharp[p];
        }
        let q = u32(at.y) * frame.width + u32(at.x);
        last = q;
        let z0 = gword_depth(gbuffer0[q * G_WORDS]);
        if reached(inv_prev, inv_z, z0) {
            return sharp[q];
        }
#if TWO_LAYERS
        if z0 > 0.0 && inv_z < 1.0 / (z0 * (1.0 + dof.thickness)) {
            let z1 = gword_depth(gbuffer1[q * G_WORDS]);
            if reached(inv_prev, inv_z, z1) {
                return layer1_radiance(q, dof.ambient);
            }
        }
#endif
        inv_prev = inv_z;
    }
    if !(gword_depth(gbuffer0[last * G_WORDS]) > 0.0) {
        return sharp[last];
    }
    return sharp[p];
}

@compute @workgroup_size(8, 8)
fn dof_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let rotation = f32(pixel_hash(gid.xy) >> 20u) / 4096.0;
    var sum = vec4<f32>(0.0);
    for (var i = 0u; i < dof.samples; i++) {
        let r = sqrt((f32(i) + 0.5) / f32(dof.samples));
        let angle = fract(f32(i) * GOLDEN_TURNS + rotation) * TAU;
        sum += lens_ray(gid.xy, r * vec2<f32>(cos(angle), sin(angle)));
    }
    hdr[gid.y * frame.width + gid.x] = sum / f32(dof.samples);
}
