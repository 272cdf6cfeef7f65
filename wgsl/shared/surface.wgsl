// The surface of a triangle where a ray meets it, shared by the resolve (the camera's rays) and
// the reflections (rays that meet what the shadow maps hold). Reads the including kernel's
// bindings `positions`, `normals`, `indices`, `tri_materials`, `materials`, `texels`, `uvs`,
// `uvs1` and `tangents` (4 floats per vertex; a short buffer reads as none).
// src/cpu/resolve.rs (`surface_sample`) is the same on the CPU.

#include "shared/frame.wgsl"
#include "shared/material.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/texture.wgsl"

fn load3(buf: u32, i: u32) -> vec3<f32> {
    if buf == 0u {
        return vec3<f32>(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u]);
    }
    return vec3<f32>(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
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

fn empty_sample() -> GSample {
    return GSample(0.0, vec3<f32>(0.0), vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, vec2<f32>(0.0), 0.0, 1.0, 0u);
}

// The surface of triangle `id` (vertex indices `tri`, world positions `w`) at barycentrics `bary`,
// turned to face the unit world direction `to_viewer`: its normal (interpolated, normal mapped)
// and material terms; the depth and the motion are the caller's.
fn surface_sample(id: u32, tri: vec3<u32>, w: array<vec3<f32>, 3>, bary: vec3<f32>, to_viewer: vec3<f32>) -> GSample {
    // Normal: interpolated vertex normals, or the face normal where they are missing or broken.
    var geo = cross(w[1] - w[0], w[2] - w[0]);
    let gl = length(geo);
    if gl > 0.0 && gl <= 3e38 {
        geo = geo / gl;
    } else {
        geo = to_viewer;
    }
    let n_interp = load3(1u, tri.x) * bary.x + load3(1u, tri.y) * bary.y + load3(1u, tri.z) * bary.z;
    let nl = length(n_interp);
    var n = geo;
    if nl > 1e-12 && nl <= 3e38 {
        n = n_interp / nl;
    }
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
            n = normal_mapped(n, texel_values[SLOT_NORMAL], t.transform_u.w, tri, bary, w, (t.sampler >> 5u) & 1u);
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
    // Face the viewer (double-sided surfaces seen from behind, and interpolation past the horizon).
    if dot(geo, to_viewer) < 0.0 {
        geo = -geo;
        n = -n;
    }
    if dot(n, to_viewer) < 0.0 {
        n = normalize(n - to_viewer * (dot(n, to_viewer) - 1e-3));
    }
    if !(dot(n, n) > 0.5) {
        n = geo;
    }
    s.normal = n;
    s.material = mid;
    return s;
}
