// Screen-space reflections against both layers.
//
// reflections_classify: one thread per 8x8 tile; a tile with a reflective layer-0 pixel is
//   appended to the tile list (other tiles do no work).
// reflections_args: indirect dispatch arguments from the list's length.
// reflections_march: one 8x8 workgroup per listed tile. For a reflective pixel the mirror
//   direction of the view ray is marched in view space in at most STEPS equal steps up to
//   `max_distance`; a step hits where the ray is behind a layer's surface by no more than
//   `thickness` (layer 0 first, its depth taken on the plane of the pixel's point and normal at
//   the step's exact sub-pixel position; then layer 1, at the pixel's depth), and returns that pixel's outgoing radiance: the
//   radiosity pass's B (direct + emission + the previous frame's indirect light) when it runs,
//   else direct + emission (layer 0) or direct (layer 1). A ray that leaves the screen or the
//   distance sees the environment: the equirectangular map (src/environment.rs gives the
//   mapping) when one is set, else the constant sky. Hits fade out near the screen edges; the
//   confidence (alpha) is 1 for a hit far from the edges, 0 for the environment. Output:
//   reflectivity * colour.
// src/cpu/reflections.rs is the same on the CPU.
// defines: PACKED

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/gbuffer_read.wgsl"

const STEPS: u32 = 48u;
const EDGE_FADE: f32 = 0.1;

// Mirrors `ReflectionsUniform` in src/frame/uniforms.rs.
struct Reflections {
    sky: vec3<f32>,
    max_distance: f32,
    thickness: f32,
    tiles_x: u32,
    tiles_y: u32,
    // Environment map size (0: the constant sky).
    env_width: u32,
    env_height: u32,
    // 1: radiance0 already holds emission (the radiosity pass's B).
    with_emission: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Reflections;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> gbuffer1_depth: array<u32>;
@group(0) @binding(4) var<storage, read> radiance0: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> radiance1: array<vec4<f32>>;
// [0]: listed tiles; then the tile indices.
@group(0) @binding(6) var<storage, read_write> tiles: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> args: array<u32>;
@group(0) @binding(8) var<storage, read_write> reflections: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> environment_map: array<vec4<f32>>;

const TAU_R: f32 = 6.28318531;
const PI_R: f32 = 3.14159265;

fn env_texel(x: i32, y: i32) -> vec3<f32> {
    return environment_map[u32(y) * params.env_width + u32(x)].rgb;
}

// The environment's radiance along world-space unit direction d (bilinear, u wraps).
fn environment(d: vec3<f32>) -> vec3<f32> {
    if params.env_width == 0u {
        return params.sky;
    }
    let w = i32(params.env_width);
    let h = i32(params.env_height);
    let u = 0.5 + atan2(d.x, -d.z) / TAU_R;
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI_R;
    let x = u * f32(w) - 0.5;
    let y = clamp(v * f32(h) - 0.5, 0.0, f32(h - 1));
    let fx = x - floor(x);
    let fy = y - floor(y);
    let x0 = ((i32(floor(x)) % w) + w) % w;
    let x1 = (x0 + 1) % w;
    let y0 = i32(floor(y));
    let y1 = min(y0 + 1, h - 1);
    let top = mix(env_texel(x0, y0), env_texel(x1, y0), fx);
    let bottom = mix(env_texel(x0, y1), env_texel(x1, y1), fx);
    return mix(top, bottom, fy);
}

@compute @workgroup_size(64)
fn reflections_classify(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) n: vec3<u32>) {
    let tile = gid.x + gid.y * n.x * 64u;
    if tile >= params.tiles_x * params.tiles_y {
        return;
    }
    let origin = vec2<u32>(tile % params.tiles_x, tile / params.tiles_x) * 8u;
    var any_reflective = false;
    for (var i = 0u; i < 64u; i++) {
        let p = origin + vec2<u32>(i % 8u, i / 8u);
        if p.x < frame.width && p.y < frame.height {
            let s = sample_at(p.y * frame.width + p.x);
            any_reflective = any_reflective || (s.depth > 0.0 && s.reflectivity > 0.0);
        }
    }
    if any_reflective {
        let slot = atomicAdd(&tiles[0], 1u);
        atomicStore(&tiles[1u + slot], tile);
    }
}

@compute @workgroup_size(1)
fn reflections_args() {
    let count = atomicLoad(&tiles[0]);
    args[0] = min(count, 65535u);
    args[1] = (count + 65534u) / 65535u;
    args[2] = 1u;
}

// The pixel (x, y) and view depth of view-space point q, or x < 0 when it is off screen.
fn project(q: vec3<f32>) -> vec3<f32> {
    let c = mat_mul(frame.proj, vec4<f32>(q, 1.0));
    if !(c.w > 0.0) {
        return vec3<f32>(-1.0);
    }
    let px = vec2<f32>((c.x / c.w * 0.5 + 0.5) * f32(frame.width), (0.5 - c.y / c.w * 0.5) * f32(frame.height));
    if !(px.x >= 0.0 && px.y >= 0.0 && px.x < f32(frame.width) && px.y < f32(frame.height)) {
        return vec3<f32>(-1.0);
    }
    return vec3<f32>(px, -q.z);
}

// The view depth of pixel q's layer-0 surface where the view ray through the sub-pixel position
// xy meets it: the plane of the pixel's point and normal, not the depth at the pixel centre, so
// a ray leaving a plane never hits the plane's own neighbouring pixels. Depth 0: no surface.
fn surface_depth(q: u32, xy: vec2<f32>) -> f32 {
    let s = sample_at(q);
    if !(s.depth > 0.0) {
        return 0.0;
    }
    let centre = vec2<f32>(f32(q % frame.width), f32(q / frame.width)) + 0.5;
    let c = view_position(frame, centre, s.depth);
    let n = mat_mul(frame.view, vec4<f32>(s.normal, 0.0)).xyz;
    // The ray through xy is a + t b, t its view depth.
    let a = view_position(frame, xy, 0.0);
    let b = view_position(frame, xy, 1.0) - a;
    let facing = dot(n, b);
    if abs(facing) < 1e-4 * length(n) * length(b) {
        return s.depth;
    }
    return dot(n, c - a) / facing;
}

fn trace(pixel: vec2<u32>) -> vec4<f32> {
    let s = sample_at(pixel.y * frame.width + pixel.x);
    if !(s.depth > 0.0) || !(s.reflectivity > 0.0) {
        return vec4<f32>(0.0);
    }
    let p = view_position(frame, vec2<f32>(pixel) + 0.5, s.depth);
    let n = normalize(mat_mul(frame.view, vec4<f32>(s.normal, 0.0)).xyz);
    var v = normalize(p);
    if frame.ortho != 0u {
        v = vec3<f32>(0.0, 0.0, -1.0);
    }
    let r = reflect(v, n);
    let step = params.max_distance / f32(STEPS);
    let sky = environment(normalize(mat_mul(frame.inv_view, vec4<f32>(r, 0.0)).xyz));
    var colour = sky;
    var confidence = 0.0;
    for (var i = 1u; i <= STEPS; i++) {
        let hit = project(p + r * (step * f32(i)));
        if hit.x < 0.0 {
            break;
        }
        let q = u32(hit.y) * frame.width + u32(hit.x);
        let d0 = surface_depth(q, hit.xy);
        var layer = 2u;
        if d0 > 0.0 && hit.z >= d0 && hit.z - d0 <= params.thickness {
            layer = 0u;
        } else {
            let w1 = gbuffer1_depth[2u * q + 1u];
            let d1 = bitcast<f32>(w1);
            if w1 != 0xffffffffu && hit.z >= d1 && hit.z - d1 <= params.thickness {
                layer = 1u;
            }
        }
        if layer < 2u {
            var seen = radiance0[q].rgb;
            if params.with_emission == 0u {
                seen += sample_at(q).emissive;
            }
            if layer == 1u {
                seen = radiance1[q].rgb;
            }
            let uv = hit.xy / vec2<f32>(f32(frame.width), f32(frame.height));
            let edge = min(min(uv.x, 1.0 - uv.x), min(uv.y, 1.0 - uv.y));
            confidence = clamp(edge / EDGE_FADE, 0.0, 1.0);
            colour = mix(sky, seen, confidence);
            break;
        }
    }
    return vec4<f32>(s.reflectivity * colour, confidence);
}

@compute @workgroup_size(8, 8)
fn reflections_march(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let entry = wid.x + wid.y * 65535u;
    if entry >= atomicLoad(&tiles[0]) {
        return;
    }
    let tile = atomicLoad(&tiles[1u + entry]);
    let pixel = vec2<u32>(tile % params.tiles_x, tile / params.tiles_x) * 8u + lid.xy;
    if pixel.x >= frame.width || pixel.y >= frame.height {
        return;
    }
    reflections[pixel.y * frame.width + pixel.x] = trace(pixel);
}
