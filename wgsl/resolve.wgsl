// Resolve: visibility buffer -> G-buffer layer, one thread per pixel.
// defines: PACKED
//
// The pixel's triangle is intersected with the ray through the pixel centre (in view space) for
// perspective-correct barycentrics; normal, uv and position interpolate with them. The depth is
// the visibility buffer's own, so the layer separation holds exactly in the G-buffer too.
// src/cpu/resolve.rs is the same computation on the CPU.

#include "shared/frame.wgsl"
#include "shared/material.wgsl"
#include "shared/vis.wgsl"
#include "shared/gbuffer.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> positions: array<f32>;
@group(0) @binding(2) var<storage, read> normals: array<f32>;
@group(0) @binding(3) var<storage, read> uvs: array<f32>;
@group(0) @binding(4) var<storage, read> indices: array<u32>;
@group(0) @binding(5) var<storage, read> tri_materials: array<u32>;
@group(0) @binding(6) var<storage, read> materials: array<Material>;
@group(0) @binding(7) var<storage, read> texels: array<u32>;
@group(0) @binding(8) var<storage, read> vis: array<u32>;
@group(0) @binding(9) var<storage, read_write> gbuffer: array<GWord>;

fn load3(buf: u32, i: u32) -> vec3<f32> {
    if buf == 0u {
        return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
    }
    return vec3<f32>(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

fn texel(t: TextureRef, x: u32, y: u32, srgb: bool) -> vec3<f32> {
    let c = unpack4x8unorm(texels[t.offset + y * t.width + x]).rgb;
    return select(c, srgb_to_linear(c), srgb);
}

// Bilinear, repeating; sRGB texels are decoded before they are filtered.
fn sample_texture(t: TextureRef, uv: vec2<f32>, srgb: bool) -> vec3<f32> {
    let size = vec2<f32>(f32(t.width), f32(t.height));
    let p = fract(uv) * size - 0.5;
    let f = fract(p);
    let i0 = vec2<i32>(floor(p));
    let w = i32(t.width);
    let h = i32(t.height);
    let x0 = u32((i0.x % w + w) % w);
    let y0 = u32((i0.y % h + h) % h);
    let x1 = (x0 + 1u) % t.width;
    let y1 = (y0 + 1u) % t.height;
    let top = mix(texel(t, x0, y0, srgb), texel(t, x1, y0, srgb), f.x);
    let bottom = mix(texel(t, x0, y1, srgb), texel(t, x1, y1, srgb), f.x);
    return mix(top, bottom, f.y);
}

fn empty_sample() -> GSample {
    return GSample(0.0, vec3<f32>(0.0), vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, vec2<f32>(0.0), 0.0, 0u);
}

fn shade(pixel: vec2<u32>) -> GSample {
    let p = pixel.y * frame.width + pixel.x;
    let id = vis[2u * p];
    let depth_bits = vis[2u * p + 1u];
    if depth_bits == VIS_EMPTY || id >= frame.triangle_count {
        return empty_sample();
    }
    let d = bitcast<f32>(depth_bits);
    let i0 = indices[3u * id];
    let i1 = indices[3u * id + 1u];
    let i2 = indices[3u * id + 2u];
    let w0 = load3(0u, i0);
    let w1 = load3(0u, i1);
    let w2 = load3(0u, i2);
    let a = mat_mul(frame.view, vec4<f32>(w0, 1.0)).xyz;
    let b = mat_mul(frame.view, vec4<f32>(w1, 1.0)).xyz;
    let c = mat_mul(frame.view, vec4<f32>(w2, 1.0)).xyz;
    // Ray through the pixel centre, in view space.
    let target_point = view_position(frame, vec2<f32>(pixel) + 0.5, d);
    var origin = vec3<f32>(0.0);
    var dir = target_point;
    if frame.ortho != 0u {
        origin = vec3<f32>(target_point.xy, 0.0);
        dir = vec3<f32>(0.0, 0.0, -1.0);
    }
    // Moller-Trumbore, keeping barycentrics even slightly outside (the pixel centre is inside by
    // coverage; rounding may put it a hair outside), then clamped.
    let e1 = b - a;
    let e2 = c - a;
    let pv = cross(dir, e2);
    let det = dot(e1, pv);
    var bary = vec3<f32>(1.0 / 3.0);
    if abs(det) > 1e-30 {
        let tv = origin - a;
        let u = dot(tv, pv) / det;
        let v = dot(dir, cross(tv, e1)) / det;
        let raw = clamp(vec3<f32>(1.0 - u - v, u, v), vec3<f32>(0.0), vec3<f32>(1.0));
        let sum = raw.x + raw.y + raw.z;
        if sum > 0.0 {
            bary = raw / sum;
        }
    }
    let world = w0 * bary.x + w1 * bary.y + w2 * bary.z;

    // Normal: interpolated vertex normals, or the face normal where they are missing or broken.
    var geo = cross(w1 - w0, w2 - w0);
    let gl = length(geo);
    let eye = mat_mul(frame.inv_view, vec4<f32>(origin, 1.0)).xyz;
    var to_eye = normalize(eye - world);
    if frame.ortho != 0u {
        to_eye = normalize(mat_mul(frame.inv_view, vec4<f32>(0.0, 0.0, 1.0, 0.0)).xyz);
    }
    if gl > 0.0 && gl <= 3e38 {
        geo = geo / gl;
    } else {
        geo = to_eye;
    }
    let n_interp = load3(1u, i0) * bary.x + load3(1u, i1) * bary.y + load3(1u, i2) * bary.z;
    let nl = length(n_interp);
    var n = geo;
    if nl > 1e-12 && nl <= 3e38 {
        n = n_interp / nl;
    }
    // Face the camera (double-sided surfaces seen from behind, and interpolation past the horizon).
    if dot(geo, to_eye) < 0.0 {
        geo = -geo;
        n = -n;
    }
    if dot(n, to_eye) < 0.0 {
        n = normalize(n - to_eye * (dot(n, to_eye) - 1e-3));
    }
    if !(dot(n, n) > 0.5) {
        n = geo;
    }

    let mid = tri_materials[id];
    var s = empty_sample();
    s.depth = d;
    s.normal = n;
    s.material = mid;
    if mid < frame.material_count {
        let m = materials[mid];
        let count = arrayLength(&texels);
        let uv = vec2<f32>(uvs[2u * i0], uvs[2u * i0 + 1u]) * bary.x
            + vec2<f32>(uvs[2u * i1], uvs[2u * i1 + 1u]) * bary.y
            + vec2<f32>(uvs[2u * i2], uvs[2u * i2 + 1u]) * bary.z;
        let uv_ok = all(abs(uv) < vec2<f32>(1e6));
        var base = m.base_color.rgb;
        if uv_ok && uses_texture(m, MATERIAL_TEXTURED, base_texture(m), count) {
            base *= sample_texture(base_texture(m), uv, true);
        }
        var emissive = m.emissive;
        if uv_ok && uses_texture(m, MATERIAL_EMISSIVE_TEXTURED, emissive_texture(m), count) {
            emissive *= sample_texture(emissive_texture(m), uv, true);
        }
        var roughness = unit(m.roughness);
        var metallic = unit(m.metallic);
        var reflectivity = unit(m.reflectivity);
        if uv_ok && uses_texture(m, MATERIAL_METALLIC_ROUGHNESS_TEXTURED, metallic_roughness_texture(m), count) {
            let mr = sample_texture(metallic_roughness_texture(m), uv, false);
            roughness = unit(roughness * mr.g);
            metallic = unit(metallic * mr.b);
            // The glTF rule the loader applies to the factors, per texel.
            reflectivity = metallic * (1.0 - roughness);
        }
        s.base_color = bounded(base, 1.0);
        s.roughness = roughness;
        s.metallic = metallic;
        s.reflectivity = reflectivity;
        s.emissive = bounded(emissive, MAX_RADIANCE);
    }
    // Motion: where this point was on screen in the previous frame (static geometry).
    let pc = mat_mul(frame.prev_view_proj, vec4<f32>(world, 1.0));
    if pc.w > 1e-20 {
        let prev = vec2<f32>((pc.x / pc.w * 0.5 + 0.5) * f32(frame.width), (0.5 - pc.y / pc.w * 0.5) * f32(frame.height));
        let motion = vec2<f32>(pixel) + 0.5 - prev;
        if all(abs(motion) < vec2<f32>(1e30)) {
            s.motion = motion;
        }
    }
    return s;
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let words = gbuffer_encode(shade(gid.xy));
    for (var i = 0u; i < G_WORDS; i++) {
        gbuffer[p * G_WORDS + i] = words[i];
    }
}
