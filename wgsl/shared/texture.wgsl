// Texture reads shared by the kernels that read materials' textures (the resolve; the
// rasterizer's and the transparency's opacity). The including kernel declares the bindings
// `materials`, `texels` (RGBA8 texels), `uvs` and `uvs1` (2 floats per vertex; a short `uvs1`
// reads as zero). src/cpu/resolve.rs is the same on the CPU.

#include "shared/material.wgsl"

// Whether the scene's materials may sample textures (not `SceneInfo::textureless`), a pipeline
// constant of every kernel that reads them: without, every texture read is compiled out (the
// resolve's, the rasterizer's alpha test's, the transparency's opacity) and a material's
// factors stand alone. A SIMD driver that runs both sides of every branch runs a loop's body at
// least once even where no lane enters it: on llvmpipe the sampling code, run for nothing,
// tripled the resolve of an untextured scene.
override TEXTURES: bool = true;

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

// One texel: rgb decoded from sRGB when srgb is set, alpha always linear.
fn texel(t: TextureSlot, x: u32, y: u32, srgb: bool) -> vec4<f32> {
    let c = unpack4x8unorm(texels[t.offset + y * t.width + x]);
    return vec4<f32>(select(c.rgb, srgb_to_linear(c.rgb), srgb), c.a);
}

// A coordinate brought into one period of its wrap mode (exactly, before it is scaled to
// texels, so that a large coordinate keeps its precision): [0, 1) repeating, [0, 1] clamped,
// [0, 2) mirrored.
fn wrap_reduce(u: f32, mode: u32) -> f32 {
    if mode == 1u {
        return clamp(u, 0.0, 1.0);
    }
    if mode == 2u {
        return u - 2.0 * floor(u * 0.5);
    }
    return fract(u);
}

// Texel index i (in [-1, 2n] after wrap_reduce) as the wrap mode reads it.
fn wrap_index(i: i32, n: i32, mode: u32) -> u32 {
    if mode == 1u {
        return u32(clamp(i, 0, n - 1));
    }
    if mode == 2u {
        if i < 0 {
            return 0u;
        }
        if i < n {
            return u32(i);
        }
        if i - n < n {
            return u32(n - 1 - (i - n));
        }
        return 0u;
    }
    return u32((i % n + n) % n);
}

// Texture slot t at uv (already transformed), wrapped and filtered as its sampler says; sRGB
// texels are decoded before they are filtered.
fn sample_texture(t: TextureSlot, uv: vec2<f32>, srgb: bool) -> vec4<f32> {
    let size = vec2<f32>(f32(t.width), f32(t.height));
    let ws = t.sampler & 3u;
    let wt = (t.sampler >> 2u) & 3u;
    let r = vec2<f32>(wrap_reduce(uv.x, ws), wrap_reduce(uv.y, wt));
    let w = i32(t.width);
    let h = i32(t.height);
    if (t.sampler & 16u) != 0u {
        let i = vec2<i32>(floor(r * size));
        return texel(t, wrap_index(i.x, w, ws), wrap_index(i.y, h, wt), srgb);
    }
    let p = r * size - 0.5;
    let f = fract(p);
    let i0 = vec2<i32>(floor(p));
    let x0 = wrap_index(i0.x, w, ws);
    let y0 = wrap_index(i0.y, h, wt);
    let x1 = wrap_index(i0.x + 1, w, ws);
    let y1 = wrap_index(i0.y + 1, h, wt);
    let top = mix(texel(t, x0, y0, srgb), texel(t, x1, y0, srgb), f.x);
    let bottom = mix(texel(t, x0, y1, srgb), texel(t, x1, y1, srgb), f.x);
    return mix(top, bottom, f.y);
}

// Vertex i's coordinates in set 0 or 1 (zero where the buffer holds none).
fn vertex_uv(i: u32, coord_set: u32) -> vec2<f32> {
    if coord_set == 0u {
        return vec2<f32>(uvs[2u * i], uvs[2u * i + 1u]);
    }
    if 2u * i + 1u < arrayLength(&uvs1) {
        return vec2<f32>(uvs1[2u * i], uvs1[2u * i + 1u]);
    }
    return vec2<f32>(0.0);
}

// The point's coordinates as slot t reads them: its set interpolated, then its transform.
fn slot_uv(t: TextureSlot, tri: vec3<u32>, bary: vec3<f32>) -> vec2<f32> {
    let coord_set = (t.sampler >> 5u) & 1u;
    let uv = vertex_uv(tri.x, coord_set) * bary.x + vertex_uv(tri.y, coord_set) * bary.y + vertex_uv(tri.z, coord_set) * bary.z;
    return vec2<f32>(dot(t.transform_u.xy, uv) + t.transform_u.z, dot(t.transform_v.xy, uv) + t.transform_v.z);
}

// Texture slot k (which material mid uses) at this point: whether it is read (its texture fits
// the texel buffer and its coordinates are finite and moderate) and its value (rgba). The
// including kernel declares `materials` too.
struct SlotRead {
    ok: bool,
    value: vec4<f32>,
}

// (Material `mid` is read field by field from the binding: a whole material is 288 bytes.)
fn read_slot(mid: u32, k: u32, tri: vec3<u32>, bary: vec3<f32>, srgb: bool) -> SlotRead {
    if !TEXTURES {
        return SlotRead(false, vec4<f32>(0.0));
    }
    let t = materials[mid].slots[k];
    let uv = slot_uv(t, tri, bary);
    if !(texture_fits(t, arrayLength(&texels)) && all(abs(uv) < vec2<f32>(1e6))) {
        return SlotRead(false, vec4<f32>(0.0));
    }
    return SlotRead(true, sample_texture(t, uv, srgb));
}

// The opacity of material mid at a point (triangle tri's vertices, barycentrics bary): its base
// colour's alpha times its base-colour texture's, in [0, 1] (NaN read as 0).
// (`material_opacity` in src/cpu/resolve.rs.)
fn material_opacity(mid: u32, tri: vec3<u32>, bary: vec3<f32>) -> f32 {
    var a = materials[mid].base_color.a;
    if (slot_bits(materials[mid].flags) & (1u << SLOT_BASE_COLOR)) != 0u {
        let r = read_slot(mid, SLOT_BASE_COLOR, tri, bary, true);
        if r.ok {
            a *= r.value.a;
        }
    }
    return unit(a);
}
