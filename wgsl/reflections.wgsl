// Screen-space reflections against both layers.
//
// reflections_classify: one thread per 8x8 tile; a tile with a reflective layer-0 pixel is
//   appended to the tile list (other tiles do no work).
// reflections_args: indirect dispatch arguments from the list's length.
// reflections_march: one 8x8 workgroup per listed tile. For a reflective pixel the mirror
//   direction of the view ray is followed across the screen, from the pixel to where it leaves
//   the screen, passes the near plane or reaches `max_distance`, through the nearest-depth
//   pyramid of layer 0 (wgsl/pyramid.wgsl, pyramid_nearest): the ray's depth, exact along the
//   screen-space segment (1/z is linear in screen space; z itself for an orthographic camera),
//   is compared with a cell's nearest depth; a cell the ray crosses wholly in front of is
//   skipped and the next one is a level coarser, else the march descends. Layer 1 lies behind
//   layer 0, so the same bound skips it. In a pixel (level 0) the ray hits a layer where its
//   segment across the pixel meets the layer's shell, between the surface and `thickness`
//   behind it, from its front (layer 0 first, its depth taken on the plane of the pixel's point
//   and normal, so a ray leaving a plane never hits the plane's own neighbouring pixels; then
//   layer 1 when the frame drew it, at the pixel's depth). A hit sees the surface as the image
//   shows it, reflections left out (wgsl/shared/shade.wgsl: direct light, emission, and the
//   diffuse albedo times the gathered irradiance and the ambient term dimmed by the
//   obscurance), its direct light re-evaluated towards the point the ray left (the lights,
//   past their shadow maps: shared/lit.wgsl). A ray that leaves the screen, the distance or
//   the iteration budget sees the environment: the equirectangular map (src/environment.rs
//   gives the mapping) when one is set, else the constant sky. Hits fade out near the screen
//   edges; the confidence (alpha) is 1 for a hit far from the edges, 0 for the environment.
//   Output: reflectivity * colour.
// src/cpu/reflections.rs is the same on the CPU.
// defines: PACKED AO RADIOSITY SHADOWS

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/gbuffer_read.wgsl"
#include "shared/shade.wgsl"
#include "shared/lit.wgsl"
#include "shared/indirect.wgsl"

// Most cells one ray visits (each a pyramid read, or at level 0 a pixel's test).
const ITERATIONS: u32 = 64u;
const EDGE_FADE: f32 = 0.1;
// A ray of unbounded length is followed this many times the depth of its origin: its end
// projects within a thousandth of the screen's half-width of the vanishing point.
const UNBOUNDED: f32 = 1000.0;
// The ray stops this much in front of the near plane (relative).
const NEAR_MARGIN: f32 = 1.001;

// Mirrors `ReflectionsUniform` in src/frame/uniforms.rs.
struct Reflections {
    // The scene's ambient radiance: what a missed ray sees without an environment map, and the
    // ambient term of the surfaces rays hit (shade.wgsl).
    ambient: vec3<f32>,
    max_distance: f32,
    thickness: f32,
    tiles_x: u32,
    tiles_y: u32,
    // Environment map size (0: the constant sky).
    env_width: u32,
    env_height: u32,
    // Levels of the nearest-depth pyramid, their offsets and widths.
    levels: u32,
    // 1: the frame drew layer 1.
    two_layers: u32,
    // Directions averaged over a rough surface's glossy lobe (1: the mirror ray alone).
    lobe_samples: u32,
    offsets: array<vec4<u32>, 2>,
    widths: array<vec4<u32>, 2>,
    // Lights in the light buffer, and the shadow maps' filter radius (0 without them).
    light_count: u32,
    pcf: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Reflections;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> gbuffer1: array<GWord>;
@group(0) @binding(4) var<storage, read> lights: array<Light>;
#if SHADOWS
@group(0) @binding(5) var<storage, read> faces: array<ShadowFace>;
@group(0) @binding(13) var<storage, read> light_faces: array<vec2<u32>>;
@group(0) @binding(14) var<storage, read> atlas: array<vec2<u32>>;
#endif
// [0]: listed tiles; then the tile indices.
@group(0) @binding(6) var<storage, read_write> tiles: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> args: array<u32>;
@group(0) @binding(8) var<storage, read_write> reflections: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> environment_map: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> nearest: array<f32>;
#if AO
@group(0) @binding(11) var<storage, read> av: array<f32>;
#endif
#if RADIOSITY
@group(0) @binding(12) var<storage, read> irradiance: array<vec4<f32>>;
#endif

const TAU_R: f32 = 6.28318531;
// The fractional golden ratio: the lobe samples' second coordinates (a Fibonacci lattice).
const GOLDEN: f32 = 0.618034;
const PI_R: f32 = 3.14159265;

fn env_texel(x: i32, y: i32) -> vec3<f32> {
    return environment_map[u32(y) * params.env_width + u32(x)].rgb;
}

// The environment's radiance along world-space unit direction d (bilinear, u wraps).
fn environment(d: vec3<f32>) -> vec3<f32> {
    if params.env_width == 0u {
        return params.ambient;
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
    let size = indirect_size(atomicLoad(&tiles[0]));
    args[0] = size.x;
    args[1] = size.y;
    args[2] = size.z;
}

// The screen position (pixels) of view-space point q; q lies in front of the camera.
fn project(q: vec3<f32>) -> vec2<f32> {
    let c = mat_mul(frame.proj, vec4<f32>(q, 1.0));
    return clip_to_pixel(c, vec2<f32>(f32(frame.width), f32(frame.height)));
}

// What varies linearly along a screen-space segment: 1/z of view depth z (z itself for an
// orthographic camera), and back.
fn linear_of(z: f32) -> f32 {
    return select(1.0 / z, z, frame.ortho != 0u);
}

fn depth_of(k: f32) -> f32 {
    return select(1.0 / k, k, frame.ortho != 0u);
}

// The view depth of the plane of pixel q's layer-0 sample s (its point and normal n, in view
// space) where the view ray through the sub-pixel position xy meets it, not the depth at the
// pixel centre, so a ray leaving a plane never hits the plane's own neighbouring pixels.
fn plane_depth(s: GSample, n: vec3<f32>, q: u32, xy: vec2<f32>) -> f32 {
    let centre = vec2<f32>(f32(q % frame.width), f32(q / frame.width)) + 0.5;
    let c = view_position(frame, centre, s.depth);
    // The ray through xy is a + t b, t its view depth.
    let a = view_position(frame, xy, 0.0);
    let b = view_position(frame, xy, 1.0) - a;
    let facing = dot(n, b);
    if abs(facing) < 1e-4 * length(n) * length(b) {
        return s.depth;
    }
    return dot(n, c - a) / facing;
}

// The segment parameter where a ray from `a` along `d` (pixels per unit) leaves the cell
// `cell` of `size` pixels.
fn cell_exit(a: vec2<f32>, d: vec2<f32>, cell: vec2<u32>, size: f32) -> f32 {
    let far_side = (vec2<f32>(cell) + select(vec2<f32>(0.0), vec2<f32>(1.0), d > vec2<f32>(0.0))) * size;
    let t = (far_side - a) / d;
    return min(select(3.4e38, t.x, d.x != 0.0), select(3.4e38, t.y, d.y != 0.0));
}

fn nearest_at(level: u32, cell: vec2<u32>) -> f32 {
    let offset = params.offsets[level / 4u][level % 4u];
    return nearest[offset + cell.y * params.widths[level / 4u][level % 4u] + cell.x];
}

// The layer (0 or 1) pixel q shows where the ray r's segment across it, from xy_in at depth
// z_in to xy_out at depth z_out, meets it from the front (a surface whose normal faces along
// the ray is one the ray would reach from inside its solid); 2: neither.
fn layer_hit(q: u32, r: vec3<f32>, xy_in: vec2<f32>, z_in: f32, xy_out: vec2<f32>, z_out: f32) -> u32 {
    let s = sample_at(q);
    if s.depth > 0.0 {
        let n = mat_mul(frame.view, vec4<f32>(s.normal, 0.0)).xyz;
        let g_in = z_in - plane_depth(s, n, q, xy_in);
        let g_out = z_out - plane_depth(s, n, q, xy_out);
        if max(g_in, g_out) >= 0.0 && min(g_in, g_out) <= params.thickness && dot(n, r) < 0.0 {
            return 0u;
        }
    }
    if params.two_layers == 0u {
        return 2u;
    }
    let w1 = gbuffer1[q * G_WORDS];
    let d1 = gword_depth(w1);
    let n1 = mat_mul(frame.view, vec4<f32>(gword_normal(w1), 0.0)).xyz;
    if d1 > 0.0 && max(z_in, z_out) >= d1 && min(z_in, z_out) - d1 <= params.thickness && dot(n1, r) < 0.0 {
        return 1u;
    }
    return 2u;
}

// The direct light that sample s at pixel q sends back along the view-space ray direction d:
// the lights (past their shadow maps) re-evaluated towards the point the ray left, so that a
// highlight shows where the reflecting surface sees it, not where the camera does.
fn relit(s: GSample, q: u32, d: vec3<f32>) -> vec3<f32> {
    let centre = vec2<f32>(f32(q % frame.width), f32(q / frame.width)) + 0.5;
    let world = mat_mul(frame.inv_view, vec4<f32>(view_position(frame, centre, s.depth), 1.0)).xyz;
    let v = -normalize(mat_mul(frame.inv_view, vec4<f32>(d, 0.0)).xyz);
    return lit(s, world, v, params.light_count, params.pcf).radiance;
}

// What a ray along view-space direction d that hits `layer` at pixel q sees: the surface as the
// image shows it (shade.wgsl), its direct light re-evaluated towards the ray's origin. Layer 1
// has no gathered irradiance or obscurance of its own: the ambient term reaches it through the
// obscurance of layer 0 at the same pixel, its nearest neighbourhood.
fn seen_at(q: u32, layer: u32, d: vec3<f32>) -> vec3<f32> {
    var visibility = 1.0;
#if AO
    visibility = av[q];
#endif
    if layer == 1u {
        let w = gbuffer1[q * G_WORDS];
#if PACKED
        let s1 = gbuffer_decode(w, gbuffer1[q * G_WORDS + 1u]);
#else
        let s1 = gbuffer_decode(w, gbuffer1[q * G_WORDS + 1u], gbuffer1[q * G_WORDS + 2u], gbuffer1[q * G_WORDS + 3u]);
#endif
        return shaded(s1, relit(s1, q, d), visibility, vec4<f32>(0.0), params.ambient);
    }
    var e = vec4<f32>(0.0);
#if RADIOSITY
    e = irradiance[q];
#endif
    let s0 = sample_at(q);
    return shaded(s0, relit(s0, q, d), visibility, e, params.ambient);
}

// Where a reflected ray first meets a layer: pixel q, the layer (2: none) and the screen
// position where the ray entered the pixel.
struct Hit {
    q: u32,
    layer: u32,
    xy: vec2<f32>,
}

// Marches the ray from view-space point p (pixel `pixel`, view depth `depth`) along unit r.
fn march(pixel: vec2<u32>, depth: f32, p: vec3<f32>, r: vec3<f32>) -> Hit {
    var hit = Hit(0u, 2u, vec2<f32>(0.0));
    // The ray's length: the distance, the unbounded stand-in, and the near plane.
    var reach_3d = min(params.max_distance, UNBOUNDED * depth);
    if r.z > 0.0 {
        reach_3d = min(reach_3d, (-frame.near * NEAR_MARGIN - p.z) / r.z);
    }
    if !(reach_3d > 0.0) {
        return hit;
    }
    // The segment on screen from a (parameter 0) to the ray's end (1), and its depth.
    let a = vec2<f32>(pixel) + 0.5;
    let e = p + r * reach_3d;
    let d = project(e) - a;
    let k0 = linear_of(depth);
    let k1 = linear_of(-e.z);
    // Where the segment leaves the screen, if before its end.
    let t_end = min(1.0, screen_exit(frame, a, d));
    let reach = max(abs(d.x), abs(d.y));
    if !(reach > 0.5) {
        return hit;
    }
    // A thousandth of a pixel along the segment: past a cell's border into the next.
    let nudge = 1e-3 / reach;
    let top = params.levels - 1u;
    let inside = vec2<f32>(f32(frame.width), f32(frame.height)) - 1e-3;
    var level = 0u;
    var t = cell_exit(a, d, pixel, 1.0) + nudge;
    for (var i = 0u; i < ITERATIONS && t < t_end; i++) {
        let xy = clamp(a + d * t, vec2<f32>(0.0), inside);
        let size = f32(1u << level);
        let cell = vec2<u32>(xy / size);
        let t_out = min(cell_exit(a, d, cell, size), t_end);
        let z_in = depth_of(mix(k0, k1, t));
        let z_out = depth_of(mix(k0, k1, t_out));
        if level > 0u {
            let front = nearest_at(level, cell);
            if front > 0.0 && max(z_in, z_out) >= front {
                level -= 1u;
            } else {
                t = t_out + nudge;
                level = min(level + 1u, top);
            }
            continue;
        }
        let q = cell.y * frame.width + cell.x;
        let layer = layer_hit(q, r, xy, z_in, a + d * t_out, z_out);
        if layer < 2u {
            return Hit(q, layer, xy);
        }
        t = t_out + nudge;
        level = min(1u, top);
    }
    return hit;
}

// How much a hit at screen position xy is trusted: 1, fading to 0 within EDGE_FADE of the
// screen's edges.
fn edge_confidence(xy: vec2<f32>) -> f32 {
    let uv = xy / vec2<f32>(f32(frame.width), f32(frame.height));
    let edge = min(min(uv.x, 1.0 - uv.x), min(uv.y, 1.0 - uv.y));
    return clamp(edge / EDGE_FADE, 0.0, 1.0);
}

// The environment along view-space direction d.
fn environment_view(d: vec3<f32>) -> vec3<f32> {
    return environment(normalize(mat_mul(frame.inv_view, vec4<f32>(d, 0.0)).xyz));
}

// The view depth of `layer` at pixel q (0: no surface).
fn layer_depth(q: u32, layer: u32) -> f32 {
    if layer == 1u {
        return gword_depth(gbuffer1[q * G_WORDS]);
    }
    return gword_depth(gbuffer[q * G_WORDS]);
}

// A unit vector's orthonormal tangents (Duff et al. 2017, "Building an orthonormal basis,
// revisited").
fn tangents(n: vec3<f32>) -> mat2x3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return mat2x3<f32>(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

// The direction that a GGX microfacet (roughness alpha) reflects wo (unit, towards the viewer)
// into about the unit normal n, for the visible normal u picks (Heitz 2018, "Sampling the GGX
// distribution of visible normals"); a direction below the surface is mirrored above it.
// src/cpu/reflections.rs (`lobe_direction`) is the same on the CPU.
fn lobe_direction(n: vec3<f32>, wo: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let tb = tangents(n);
    let ve = normalize(vec3<f32>(dot(wo, tb[0]), dot(wo, tb[1]), max(dot(wo, n), 1e-4)));
    let vh = normalize(vec3<f32>(alpha * ve.x, alpha * ve.y, ve.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let radius = sqrt(u.x);
    let phi = TAU_R * u.y;
    let p1 = radius * cos(phi);
    let blend = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - blend) * sqrt(max(1.0 - p1 * p1, 0.0)) + blend * radius * sin(phi);
    let nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
    let m = normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    var l = 2.0 * dot(ve, m) * m - ve;
    l.z = abs(l.z);
    return normalize(l.x * tb[0] + l.y * tb[1] + l.z * n);
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
    let hit = march(pixel, s.depth, p, r);
    // What the mirror ray sees.
    var mirror = environment_view(r);
    var mirror_trust = 0.0;
    if hit.layer < 2u {
        mirror_trust = edge_confidence(hit.xy);
        mirror = mix(mirror, seen_at(hit.q, hit.layer, r), mirror_trust);
    }
    let alpha = s.roughness * s.roughness;
    if !(alpha > 0.0) || params.lobe_samples <= 1u {
        return vec4<f32>(s.reflectivity * mirror, mirror_trust);
    }
    // A glossy lobe: each direction the lobe reflects into is taken to travel as far as the
    // mirror ray did, and sees the surface the screen holds there when a layer's depth lies
    // within the thickness plus a quarter of that distance of it; otherwise it sees what the
    // mirror ray saw. When the mirror ray found nothing, each direction sees the environment.
    var reach = -1.0;
    if hit.layer < 2u {
        let centre = vec2<f32>(f32(hit.q % frame.width), f32(hit.q / frame.width)) + 0.5;
        reach = length(view_position(frame, centre, layer_depth(hit.q, hit.layer)) - p);
    }
    // The lobe widens with the roughness: all its directions from roughness 0.5 up, fewer
    // (at least two) in proportion below.
    let k = clamp(u32(ceil(f32(params.lobe_samples) * min(2.0 * s.roughness, 1.0))), 2u, params.lobe_samples);
    var sum = vec3<f32>(0.0);
    var trust = 0.0;
    for (var i = 0u; i < k; i++) {
        let u = vec2<f32>((f32(i) + 0.5) / f32(k), fract(f32(i) * GOLDEN));
        let l = lobe_direction(n, -v, alpha, u);
        if reach < 0.0 {
            sum += environment_view(l);
            continue;
        }
        var colour = mirror;
        var confidence = mirror_trust;
        let e = p + l * reach;
        let tolerance = params.thickness + 0.25 * reach;
        if e.z < -frame.near * NEAR_MARGIN {
            let xy = project(e);
            if all(xy >= vec2<f32>(0.0)) && all(xy < vec2<f32>(f32(frame.width), f32(frame.height))) {
                let q = u32(xy.y) * frame.width + u32(xy.x);
                var layer = 2u;
                let d0 = layer_depth(q, 0u);
                if d0 > 0.0 && abs(d0 + e.z) <= tolerance {
                    layer = 0u;
                } else if params.two_layers != 0u {
                    let d1 = layer_depth(q, 1u);
                    if d1 > 0.0 && abs(d1 + e.z) <= tolerance {
                        layer = 1u;
                    }
                }
                if layer < 2u {
                    confidence = edge_confidence(xy);
                    colour = mix(environment_view(l), seen_at(q, layer, l), confidence);
                }
            }
        }
        sum += colour;
        trust += confidence;
    }
    return vec4<f32>(s.reflectivity * sum / f32(k), trust / f32(k));
}

@compute @workgroup_size(8, 8)
fn reflections_march(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let entry = indirect_group(wid);
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
