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
#include "shared/texture.wgsl"
#include "shared/barycentric.wgsl"
#include "shared/position.wgsl"

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
// The second coordinate set (2 per vertex) and the tangents (4 per vertex); a scene without
// them binds a short buffer, which reads as zero.
@group(0) @binding(10) var<storage, read> uvs1: array<f32>;
@group(0) @binding(11) var<storage, read> tangents: array<f32>;
// Each vertex's position in the last frame (read only with OBJECT_MOTION).
@group(0) @binding(12) var<storage, read> previous_positions: array<f32>;

fn load3(buf: u32, i: u32) -> vec3<f32> {
    if buf == 0u {
        return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
    }
    return vec3<f32>(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
}

fn previous_vertex(i: u32) -> vec3<f32> {
    return vec3<f32>(previous_positions[3u * i], previous_positions[3u * i + 1u], previous_positions[3u * i + 2u]);
}

fn vertex_tangent(i: u32) -> vec4<f32> {
    if 4u * i + 3u < arrayLength(&tangents) {
        return vec4<f32>(tangents[4u * i], tangents[4u * i + 1u], tangents[4u * i + 2u], tangents[4u * i + 3u]);
    }
    return vec4<f32>(0.0);
}

// The normal n turned by the tangent-space normal texture value c (linear rgb): the frame is
// the vertex tangents interpolated, or where they are missing the triangle's own
// texture-space frame (dP/du, with the bitangent's sign from dP/dv as glTF's coordinates run);
// n unchanged where no frame exists.
fn normal_mapped(n: vec3<f32>, c: vec3<f32>, scale: f32, tri: vec3<u32>, bary: vec3<f32>, w: array<vec3<f32>, 3>, coord_set: u32) -> vec3<f32> {
    let t0 = vertex_tangent(tri.x);
    let t1 = vertex_tangent(tri.y);
    let t2 = vertex_tangent(tri.z);
    var t = t0.xyz * bary.x + t1.xyz * bary.y + t2.xyz * bary.z;
    var sign = select(1.0, -1.0, t0.w < 0.0);
    if !(dot(t, t) > 1e-12 && dot(t, t) <= 3e38) {
        let a = vertex_uv(tri.x, coord_set);
        let d1 = vertex_uv(tri.y, coord_set) - a;
        let d2 = vertex_uv(tri.z, coord_set) - a;
        let e1 = w[1] - w[0];
        let e2 = w[2] - w[0];
        let r = d1.x * d2.y - d2.x * d1.y;
        if !(abs(r) > 1e-20) {
            return n;
        }
        t = (e1 * d2.y - e2 * d1.y) / r;
        let b = (e2 * d1.x - e1 * d2.x) / r;
        sign = select(-1.0, 1.0, dot(cross(n, t), b) < 0.0);
    }
    t = t - n * dot(n, t);
    let tl = length(t);
    if !(tl > 1e-12 && tl <= 3e38) {
        return n;
    }
    t = t / tl;
    let b = cross(n, t) * sign;
    let v = c * 2.0 - 1.0;
    let mapped = t * (v.x * scale) + b * (v.y * scale) + n * v.z;
    let ml = length(mapped);
    if !(ml > 1e-12 && ml <= 3e38) {
        return n;
    }
    return mapped / ml;
}

// Whether this frame's geometry moved (the frame's FRAME_OBJECT_MOTION, as a pipeline constant):
// without, the reads of the last frame's vertices are compiled out (see TEXTURES in
// shared/texture.wgsl for why).
override OBJECT_MOTION: bool = true;

fn empty_sample() -> GSample {
    return GSample(0.0, vec3<f32>(0.0), vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, vec2<f32>(0.0), 0.0, 1.0, 0u);
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
    let ray = pixel_ray(frame, vec2<f32>(pixel) + 0.5, d);
    let origin = ray.origin;
    let bary = ray_barycentrics(ray, a, b, c);
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
    let tri = vec3<u32>(i0, i1, i2);
    let mid = tri_materials[id];
    var s = empty_sample();
    if mid < frame.material_count {
        // Every texture the material uses, one loop iteration each: one copy of the sampling
        // code. Compiled out of a textureless scene's resolve (TEXTURES, shared/texture.wgsl).
        var texel_values: array<vec3<f32>, SLOT_COUNT>;
        var read = 0u;
        var pending = slot_bits(materials[mid].flags);
        while TEXTURES && pending != 0u {
            let k = firstTrailingBit(pending);
            pending &= pending - 1u;
            let r = read_slot(mid, k, tri, bary, k == SLOT_BASE_COLOR || k == SLOT_EMISSIVE);
            if r.ok {
                texel_values[k] = r.value.rgb;
                read |= 1u << k;
            }
        }
        if (read & (1u << SLOT_NORMAL)) != 0u {
            let t = materials[mid].slots[SLOT_NORMAL];
            n = normal_mapped(n, texel_values[SLOT_NORMAL], t.transform_u.w, tri, bary, array<vec3<f32>, 3>(w0, w1, w2), (t.sampler >> 5u) & 1u);
        }
        var base = materials[mid].base_color.rgb;
        if (read & (1u << SLOT_BASE_COLOR)) != 0u {
            base *= texel_values[SLOT_BASE_COLOR];
        }
        var emissive = materials[mid].emissive;
        if (read & (1u << SLOT_EMISSIVE)) != 0u {
            emissive *= texel_values[SLOT_EMISSIVE];
        }
        var roughness = unit(materials[mid].roughness);
        var metallic = unit(materials[mid].metallic);
        var reflectivity = unit(materials[mid].reflectivity);
        if (read & (1u << SLOT_METALLIC_ROUGHNESS)) != 0u {
            let mr = texel_values[SLOT_METALLIC_ROUGHNESS];
            roughness = unit(roughness * mr.g);
            metallic = unit(metallic * mr.b);
            // The glTF rule the loader applies to the factors, per texel.
            reflectivity = metallic * (1.0 - roughness);
        }
        if (read & (1u << SLOT_OCCLUSION)) != 0u {
            let strength = unit(materials[mid].slots[SLOT_OCCLUSION].transform_u.w);
            s.occlusion = unit(1.0 + strength * (texel_values[SLOT_OCCLUSION].r - 1.0));
        }
        s.base_color = bounded(base, 1.0);
        s.roughness = roughness;
        s.metallic = metallic;
        s.reflectivity = reflectivity;
        s.emissive = bounded(emissive, MAX_RADIANCE);
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
    s.depth = stored_depth(frame, d);
    s.normal = n;
    s.material = mid;
    // Motion: where this point was on screen in the previous frame: the same barycentrics on the
    // triangle as it stood then (OBJECT_MOTION), or the same world point (still geometry).
    var was = world;
    if OBJECT_MOTION && 3u * frame.vertex_count <= arrayLength(&previous_positions) {
        was = previous_vertex(i0) * bary.x + previous_vertex(i1) * bary.y + previous_vertex(i2) * bary.z;
    }
    let pc = mat_mul(frame.prev_view_proj, vec4<f32>(was, 1.0));
    if pc.w > 1e-20 {
        let prev = clip_to_pixel(pc, vec2<f32>(f32(frame.width), f32(frame.height)));
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
