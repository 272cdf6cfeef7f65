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
//   past their shadow maps: shared/lit.wgsl) at its roughness widened by the share of the
//   reflector's glossy lobe the ray stands for (widened_roughness). A ray that leaves the screen, the distance or
//   the iteration budget sees the environment: the equirectangular map (src/environment.rs
//   gives the mapping) when one is set, else the constant sky. Hits fade out near the screen
//   edges; the confidence (alpha) is 1 for a hit far from the edges, 0 for the environment.
//   Output: reflectance * colour (the reflectivity, tinted by the base colour as far as the
//   surface is a metal).
// reflections_hidden (FOLLOW, with SHADOWS): the mirror rays the march could not place, which it
//   lists (`followed`, one thread each; reflections_hidden_args sizes the dispatch): those that
//   found nothing on screen, ran into the side of a solid the camera does not see (layer 0's
//   shell met from behind: the march stops there, HIDDEN_SIDE) or hit a silhouette pixel. What a
//   light sees first is a surface too, lit by it, and often one neither layer holds (the side of
//   a sphere turned from the camera, towards the sun). Each ray, up to 1.25 times where the
//   march stopped (found nothing: the scene's bounding sphere), takes HIDDEN_STEPS even steps
//   through every shadow-casting light's map; where a step lies behind the surface the map holds
//   at its texel and the step before did not, HIDDEN_REFINE bisections find the crossing and
//   the ray is intersected exactly with the triangles the map holds on either side of it (a ray
//   that only enters a shadow meets neither). The nearest hit over the lights is shaded from its
//   triangle (shared/surface.wgsl: normal, material, textures), lit towards the point the ray
//   left (shared/lit.wgsl), with the ambient term and no obscurance or gathered light, its
//   roughness widened by what the reflecting pixel gathers over (its lobe and its footprint)
//   times (1 + distance x the hit's curvature); at a silhouette only where the camera does not
//   see the side the ray meets. It replaces the pixel's reflection, confidence 1.
// src/cpu/reflections.rs is the same on the CPU.
// defines: PACKED AO RADIOSITY SHADOWS FOLLOW (with SHADOWS: reflections_hidden)

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/gbuffer_read.wgsl"
#include "shared/shade.wgsl"
#include "shared/lit.wgsl"
#include "shared/indirect.wgsl"
#include "shared/list.wgsl"

// A followed ray's reach where the march found nothing: to the scene's edge.
const TO_SCENE_EDGE: f32 = 3.4e38;
// A march's outcome where it ran into the side of a solid the camera does not see.
const HIDDEN_SIDE: u32 = 3u;
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
    // The scene's bounding sphere (world centre, radius; 0: rays are not followed through the
    // shadow maps).
    bounds: vec4<f32>,
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
// The reflective tiles (shared/list.wgsl: [0] their count, then the tile indices) and the
// march's dispatch arguments, a workgroup a tile.
@group(0) @binding(6) var<storage, read_write> list: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> list_args: array<u32>;
@group(0) @binding(8) var<storage, read_write> reflections: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> environment_map: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> nearest: array<f32>;
#if AO
@group(0) @binding(11) var<storage, read> av: array<f32>;
#endif
#if RADIOSITY
@group(0) @binding(12) var<storage, read> irradiance: array<vec4<f32>>;
#endif
#if SHADOWS
#if FOLLOW
// The scene, for the surfaces the shadow maps hold (shared/surface.wgsl).
@group(0) @binding(15) var<storage, read> positions: array<f32>;
@group(0) @binding(16) var<storage, read> normals: array<f32>;
@group(0) @binding(17) var<storage, read> uvs: array<f32>;
@group(0) @binding(18) var<storage, read> indices: array<u32>;
@group(0) @binding(19) var<storage, read> tri_materials: array<u32>;
@group(0) @binding(20) var<storage, read> materials: array<Material>;
@group(0) @binding(21) var<storage, read> texels: array<u32>;
@group(0) @binding(22) var<storage, read> uvs1: array<f32>;
@group(0) @binding(23) var<storage, read> tangents: array<f32>;
// The rays reflections_hidden follows: [0] their count, then (pixel, how far: `follow` in the
// march) per ray.
@group(0) @binding(24) var<storage, read_write> followed: array<atomic<u32>>;
// reflections_hidden's indirect dispatch arguments.
@group(0) @binding(25) var<storage, read_write> hidden_args: array<u32>;
#include "shared/surface.wgsl"
#include "shared/barycentric.wgsl"
#endif
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
        list_append(tile);
    }
}

@compute @workgroup_size(1)
fn reflections_args() {
    list_write_group_args();
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

// What the ray r's segment across pixel q, from xy_in at depth z_in to xy_out at depth z_out,
// meets there: the layer (0 or 1) it meets from the front; 2: neither; HIDDEN_SIDE: layer 0's
// shell from behind (its surface faces along the ray): the ray runs into the side of that solid
// the camera does not see, which no layer holds, and stops there.
fn layer_hit(q: u32, r: vec3<f32>, xy_in: vec2<f32>, z_in: f32, xy_out: vec2<f32>, z_out: f32) -> u32 {
    let s = sample_at(q);
    if s.depth > 0.0 {
        let n = mat_mul(frame.view, vec4<f32>(s.normal, 0.0)).xyz;
        let g_in = z_in - plane_depth(s, n, q, xy_in);
        let g_out = z_out - plane_depth(s, n, q, xy_out);
        if max(g_in, g_out) >= 0.0 && min(g_in, g_out) <= params.thickness {
            return select(HIDDEN_SIDE, 0u, dot(n, r) < 0.0);
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

// What sample s reflects of the radiance arriving along its mirror direction: its reflectivity,
// tinted by its base colour as far as it is a metal (the F0 its specular BRDF takes: a gold
// surface reflects gold, a dielectric's reflection keeps the light's colour).
fn reflectance(s: GSample) -> vec3<f32> {
    return s.reflectivity * mix(vec3<f32>(1.0), s.base_color, s.metallic);
}

// A GGX roughness widened by `blur` (the spread, as a GGX alpha, of the directions the
// reflecting pixel gathers through the ray that met it) and by the turn of a curved surface's
// normal over the patch those directions cover `t` away (`curvature`, radians per unit): a
// sharp highlight is averaged over the lobe it is seen through, as the truth's rays average it,
// instead of taken where one direction happens to land.
fn widened_roughness(roughness: f32, blur: f32, t: f32, curvature: f32) -> f32 {
    let widened = blur * (1.0 + t * min(curvature, 1e6));
    let a = roughness * roughness;
    return sqrt(sqrt(a * a + widened * widened));
}

// The first word of pixel q's `layer`.
fn layer_word(q: u32, layer: u32) -> GWord {
    if layer == 1u {
        return gbuffer1[q * G_WORDS];
    }
    return gbuffer[q * G_WORDS];
}

// The change of `layer`'s normal across pixel q along `axis` (0: x, 1: y): its length and the
// distance between the two neighbours' points, where both neighbours lie on screen and hold a
// surface within a tenth of q's depth (the same surface); (0, 0) elsewhere.
fn normal_change(q: u32, layer: u32, axis: u32) -> vec2<f32> {
    let d = gword_depth(layer_word(q, layer));
    let pixel = vec2<i32>(i32(q % frame.width), i32(q / frame.width));
    let step = select(vec2<i32>(0, 1), vec2<i32>(1, 0), axis == 0u);
    let a0 = pixel - step;
    let a1 = pixel + step;
    if any(a0 < vec2<i32>(0)) || a1.x >= i32(frame.width) || a1.y >= i32(frame.height) {
        return vec2<f32>(0.0);
    }
    let w0 = layer_word(u32(a0.y) * frame.width + u32(a0.x), layer);
    let w1 = layer_word(u32(a1.y) * frame.width + u32(a1.x), layer);
    let d0 = gword_depth(w0);
    let d1 = gword_depth(w1);
    if !(d0 > 0.0 && d1 > 0.0 && abs(d0 - d) < 0.1 * d && abs(d1 - d) < 0.1 * d) {
        return vec2<f32>(0.0);
    }
    let dn = length(gword_normal(w1) - gword_normal(w0));
    if !(dn < 1e30) {
        return vec2<f32>(0.0);
    }
    let p0 = view_position(frame, vec2<f32>(a0) + 0.5, d0);
    let p1 = view_position(frame, vec2<f32>(a1) + 0.5, d1);
    return vec2<f32>(dn, length(p1 - p0));
}

// The curvature (radians of normal per unit) of `layer`'s surface at pixel q: the larger of
// the two axes' normal change over its distance.
fn layer_curvature(q: u32, layer: u32) -> f32 {
    var curvature = 0.0;
    for (var axis = 0u; axis < 2u; axis++) {
        let change = normal_change(q, layer, axis);
        let c = change.x / change.y;
        if change.y > 0.0 && c < 1e30 {
            curvature = max(curvature, c);
        }
    }
    return curvature;
}

// The direct light that sample s at pixel q of `layer` sends back along the view-space ray
// direction d, which came `t` from the reflecting point through a lobe of spread `blur`: the
// lights (past their shadow maps) re-evaluated towards the point the ray left, so that a
// highlight shows where the reflecting surface sees it, not where the camera does.
fn relit(s_in: GSample, q: u32, layer: u32, d: vec3<f32>, blur: f32, t: f32) -> vec3<f32> {
    var s = s_in;
    if blur > 0.0 {
        s.roughness = widened_roughness(s.roughness, blur, t, layer_curvature(q, layer));
    }
    let centre = vec2<f32>(f32(q % frame.width), f32(q / frame.width)) + 0.5;
    let world = mat_mul(frame.inv_view, vec4<f32>(view_position(frame, centre, s.depth), 1.0)).xyz;
    let v = -normalize(mat_mul(frame.inv_view, vec4<f32>(d, 0.0)).xyz);
    return lit(s, world, v, params.light_count, params.pcf).radiance;
}

// What a ray along view-space direction d that hits `layer` at pixel q sees: the surface as the
// image shows it (shade.wgsl), its direct light re-evaluated towards the ray's origin `t` away
// and widened by the lobe's spread `blur` (relit). Layer 1
// has no gathered irradiance or obscurance of its own: the ambient term reaches it through the
// obscurance of layer 0 at the same pixel, its nearest neighbourhood.
fn seen_at(q: u32, layer: u32, d: vec3<f32>, blur: f32, t: f32) -> vec3<f32> {
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
        return shaded(s1, relit(s1, q, 1u, d, blur, t), visibility, vec4<f32>(0.0), params.ambient);
    }
    var e = vec4<f32>(0.0);
#if RADIOSITY
    e = irradiance[q];
#endif
    let s0 = sample_at(q);
    return shaded(s0, relit(s0, q, 0u, d, blur, t), visibility, e, params.ambient);
}

// Where a reflected ray first meets a layer: pixel q, the layer (2: none) and the screen
// position where the ray entered the pixel.
struct Hit {
    q: u32,
    layer: u32,
    xy: vec2<f32>,
}

// A reflecting sample's view-space set-up: its point, unit normal, the unit direction from the
// eye to the point (the camera's axis for an orthographic camera) and that direction mirrored.
struct Mirror {
    p: vec3<f32>,
    n: vec3<f32>,
    v: vec3<f32>,
    r: vec3<f32>,
}

// The mirror set-up of sample s at `pixel`: shared by the march and the followed rays.
fn mirror_at(pixel: vec2<u32>, s: GSample) -> Mirror {
    let p = view_position(frame, vec2<f32>(pixel) + 0.5, s.depth);
    let n = normalize(mat_mul(frame.view, vec4<f32>(s.normal, 0.0)).xyz);
    var v = normalize(p);
    if frame.ortho != 0u {
        v = vec3<f32>(0.0, 0.0, -1.0);
    }
    return Mirror(p, n, v, reflect(v, n));
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
        if layer != 2u {
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
fn lobe_frame(n: vec3<f32>) -> mat2x3<f32> {
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
    let tb = lobe_frame(n);
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

// Whether layer 0 at pixel q borders a surface much farther or nearer (a depth step of more
// than the reflections' thickness to a pixel beside it, or none there).
fn silhouette(q: u32) -> bool {
    let x = i32(q % frame.width);
    let y = i32(q / frame.width);
    let z = layer_depth(q, 0u);
    var beside = array<vec2<i32>, 4>(vec2<i32>(1, 0), vec2<i32>(-1, 0), vec2<i32>(0, 1), vec2<i32>(0, -1));
    for (var k = 0u; k < 4u; k++) {
        let t = vec2<i32>(x, y) + beside[k];
        if all(t >= vec2<i32>(0)) && t.x < i32(frame.width) && t.y < i32(frame.height) {
            let zt = layer_depth(u32(t.y) * frame.width + u32(t.x), 0u);
            if !(zt > 0.0) || abs(zt - z) > params.thickness {
                return true;
            }
        }
    }
    return false;
}

fn trace(pixel: vec2<u32>) -> vec4<f32> {
    let s = sample_at(pixel.y * frame.width + pixel.x);
    if !(s.depth > 0.0) || !(s.reflectivity > 0.0) {
        return vec4<f32>(0.0);
    }
    let m = mirror_at(pixel, s);
    let p = m.p;
    let n = m.n;
    let v = m.v;
    let r = m.r;
    let hit = march(pixel, s.depth, p, r);
    // How far the mirror ray went on screen, to what it hit (its reach for the lobe below).
    var went = 0.0;
    if hit.layer != 2u {
        let centre = vec2<f32>(f32(hit.q % frame.width), f32(hit.q / frame.width)) + 0.5;
        went = length(view_position(frame, centre, layer_depth(hit.q, min(hit.layer, 1u))) - p);
    }
    // The directions taken over a rough surface's glossy lobe (1: the mirror ray alone): all of
    // them from roughness 0.5 up, fewer (at least two) in proportion below. Each stands for
    // 1 / k of the lobe, and what it hits is widened by that share's spread (alpha / sqrt k).
    let alpha = s.roughness * s.roughness;
    var k = 1u;
    if alpha > 0.0 && params.lobe_samples > 1u {
        k = clamp(u32(ceil(f32(params.lobe_samples) * min(2.0 * s.roughness, 1.0))), 2u, params.lobe_samples);
    }
    let blur = select(0.0, alpha / sqrt(f32(k)), alpha > 0.0);
    // What the mirror ray sees.
    var mirror = environment_view(r);
    var mirror_trust = 0.0;
    if hit.layer < 2u {
        mirror_trust = edge_confidence(hit.xy);
        mirror = mix(mirror, seen_at(hit.q, hit.layer, r, blur, went), mirror_trust);
    }
#if SHADOWS
#if FOLLOW
    // How far reflections_hidden follows the ray through the shadow maps: not at all past an
    // ordinary hit (0); to the scene's edge where it found nothing (+inf) and to the side it ran
    // into (+went), taking what it meets there; to a silhouette it hit (-went), taking what it
    // meets there only where the camera does not see it (the ray may have passed the
    // silhouette's pixel onto the side behind it).
    var follow = 0.0;
    if hit.layer == 2u {
        follow = TO_SCENE_EDGE;
    } else if hit.layer == HIDDEN_SIDE {
        follow = went;
    } else if hit.layer == 0u && silhouette(hit.q) {
        follow = -went;
    }
    if follow != 0.0 {
        let slot = atomicAdd(&followed[0], 1u);
        atomicStore(&followed[1u + 2u * slot], pixel.y * frame.width + pixel.x);
        atomicStore(&followed[2u + 2u * slot], bitcast<u32>(follow));
    }
#endif
#endif
    if k == 1u {
        return vec4<f32>(reflectance(s) * mirror, mirror_trust);
    }
    // A glossy lobe: each direction the lobe reflects into is taken to travel as far as the
    // mirror ray did, and sees the surface the screen holds there when a layer's depth lies
    // within the thickness plus a quarter of that distance of it; otherwise it sees what the
    // mirror ray saw. When the mirror ray found nothing, each direction sees the environment.
    let reach = select(-1.0, went, hit.layer < 2u);
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
                    colour = mix(environment_view(l), seen_at(q, layer, l, blur, reach), confidence);
                }
            }
        }
        sum += colour;
        trust += confidence;
    }
    return vec4<f32>(reflectance(s) * sum / f32(k), trust / f32(k));
}

@compute @workgroup_size(8, 8)
fn reflections_march(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    var tile = 0u;
    if !list_group_item(wid, &tile) {
        return;
    }
    let pixel = vec2<u32>(tile % params.tiles_x, tile / params.tiles_x) * 8u + lid.xy;
    if pixel.x >= frame.width || pixel.y >= frame.height {
        return;
    }
    reflections[pixel.y * frame.width + pixel.x] = trace(pixel);
}

#if SHADOWS
#if FOLLOW
// Even steps of a ray through the shadow maps, and bisections of the step where it passes
// behind a surface.
const HIDDEN_STEPS: u32 = 16u;
const HIDDEN_REFINE: u32 = 6u;
// How far outside a triangle (in barycentric coordinates) an exact hit may fall: the crossing
// lies on a texel's triangle up to the map's rounding.
const HIDDEN_SLACK: f32 = 1e-4;

// Light i's shadow map at world point p: `gap`, how far (along the face's view) the surface the
// map holds at p's texel lies behind p (> 0: p lies in front of it, towards the light), and that
// surface's triangle; `ok` is false off the map or where the light sees nothing.
struct MapPoint {
    gap: f32,
    id: u32,
    ok: bool,
}

fn map_point(i: u32, p: vec3<f32>) -> MapPoint {
    let f = shadow_face_at(i, lights[i], p);
    let v = mat_mul(f.view, vec4<f32>(p, 1.0));
    return map_at(f, mat_mul(f.proj, v), v.z);
}

// The same at the point of face f's clip position c and view z `vz`.
fn map_at(f: ShadowFace, c: vec4<f32>, vz: f32) -> MapPoint {
    var out = MapPoint(0.0, 0u, false);
    if !(c.w > 0.0) {
        return out;
    }
    let res = f32(f.resolution);
    let uv = clip_to_pixel(c, vec2<f32>(res));
    if !(all(uv >= vec2<f32>(0.0)) && all(uv < vec2<f32>(res))) {
        return out;
    }
    let t = vec2<u32>(uv);
    let word = atlas[f.offset + t.y * f.resolution + t.x];
    if word.y == 0xffffffffu {
        return out;
    }
    return MapPoint(bitcast<f32>(word.y) + vz, word.x, true);
}

// Light i's map at the point o + d t of a ray, for t in [0, t_end]: a light of one face (sun,
// spot) interpolates the ray's clip position and view z between its ends (both are affine in
// the point), a point light picks the face of each point.
struct RayInMap {
    i: u32,
    one_face: bool,
    face: ShadowFace,
    c0: vec4<f32>,
    c1: vec4<f32>,
    z0: f32,
    z1: f32,
}

fn ray_in_map(i: u32, o: vec3<f32>, d: vec3<f32>, t_end: f32) -> RayInMap {
    let info = light_faces[i];
    let f = faces[info.x];
    let v0 = mat_mul(f.view, vec4<f32>(o, 1.0));
    let v1 = mat_mul(f.view, vec4<f32>(o + d * t_end, 1.0));
    return RayInMap(i, info.y == 1u, f, mat_mul(f.proj, v0), mat_mul(f.proj, v1), v0.z, v1.z);
}

fn map_along(m: RayInMap, o: vec3<f32>, d: vec3<f32>, t: f32, t_end: f32) -> MapPoint {
    if m.one_face {
        let s = t / t_end;
        return map_at(m.face, m.c0 + (m.c1 - m.c0) * s, m.z0 + (m.z1 - m.z0) * s);
    }
    return map_point(m.i, o + d * t);
}

// Where a world-space ray meets the surface of a triangle: its parameter (-1: none), the
// triangle and the barycentrics there.
struct HiddenHit {
    t: f32,
    id: u32,
    bary: vec3<f32>,
}

fn triangle_vertices(id: u32) -> vec3<u32> {
    return vec3<u32>(indices[3u * id], indices[3u * id + 1u], indices[3u * id + 2u]);
}

// Where the ray o + t d meets triangle `id` for t in (t_min, t_max], if it does.
fn triangle_hit(id: u32, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> HiddenHit {
    var out = HiddenHit(-1.0, id, vec3<f32>(0.0));
    if id >= frame.triangle_count {
        return out;
    }
    let tri = triangle_vertices(id);
    let h = ray_triangle(o, d, load3(0u, tri.x), load3(0u, tri.y), load3(0u, tri.z), HIDDEN_SLACK);
    if h.x > t_min && h.x <= t_max {
        out.t = h.x;
        out.bary = h.yzw;
    }
    return out;
}

// The parameter where the ray from world point o along unit d leaves the scene's bounding sphere
// (within `max_distance`); 0 without bounds.
fn scene_exit(o: vec3<f32>, d: vec3<f32>) -> f32 {
    let r = params.bounds.w;
    if !(r > 0.0) {
        return 0.0;
    }
    let m = o - params.bounds.xyz;
    let b = dot(m, d);
    let c = dot(m, m) - r * r;
    let t = -b + sqrt(max(b * b - c, 0.0));
    return clamp(t, 0.0, params.max_distance);
}

// The first surface that a light's shadow map holds and the ray from world point o along unit d
// meets within t_end (the nearest over the lights).
fn hidden_hit(o: vec3<f32>, d: vec3<f32>, t_end: f32) -> HiddenHit {
    var best = HiddenHit(-1.0, 0u, vec3<f32>(0.0));
    if !(t_end > 0.0) {
        return best;
    }
    var reach = t_end;
    // Past the point's own surface.
    let t_min = 1e-4 * params.bounds.w;
    for (var i = 0u; i < params.light_count; i++) {
        if light_faces[i].y == 0u {
            continue;
        }
        let ray = ray_in_map(i, o, d, t_end);
        var t0 = 0.0;
        var front = true;
        for (var k = 1u; k <= HIDDEN_STEPS; k++) {
            let t1 = t_end * f32(k) / f32(HIDDEN_STEPS);
            if t0 >= reach {
                break;
            }
            let m = map_along(ray, o, d, t1, t_end);
            let behind = m.ok && m.gap < 0.0;
            if behind && front {
                // The ray passed behind the map's surface between t0 and t1: where, and the
                // triangles held on either side of that point.
                var lo = t0;
                var hi = t1;
                var id_hi = m.id;
                var id_lo = m.id;
                for (var b = 0u; b < HIDDEN_REFINE; b++) {
                    let mid = 0.5 * (lo + hi);
                    let mm = map_along(ray, o, d, mid, t_end);
                    if mm.ok && mm.gap < 0.0 {
                        hi = mid;
                        id_hi = mm.id;
                    } else {
                        lo = mid;
                        if mm.ok {
                            id_lo = mm.id;
                        }
                    }
                }
                var h = triangle_hit(id_hi, o, d, t_min, reach);
                if h.t < 0.0 && id_lo != id_hi {
                    h = triangle_hit(id_lo, o, d, t_min, reach);
                }
                if h.t > 0.0 {
                    best = h;
                    reach = h.t;
                    break;
                }
            }
            front = !behind;
            t0 = t1;
        }
    }
    return best;
}

// Whether the camera sees the side of hit h's triangle (at world point x) that the ray from o
// meets, where a layer could hold it: the screen's own hit then stands.
fn faces_camera(h: HiddenHit, x: vec3<f32>, o: vec3<f32>) -> bool {
    let tri = triangle_vertices(h.id);
    let w0 = load3(0u, tri.x);
    let geo = cross(load3(0u, tri.y) - w0, load3(0u, tri.z) - w0);
    return dot(geo, toward_camera(frame, x)) * dot(geo, o - x) > 0.0;
}

// What a ray along unit d sees at hidden hit h: the surface lit towards the ray's origin,
// its roughness widened by `blur`, the spread (GGX alpha) of the directions the reflecting
// pixel gathers.
fn hidden_seen(h: HiddenHit, d: vec3<f32>, blur: f32) -> vec3<f32> {
    let tri = triangle_vertices(h.id);
    let w = array<vec3<f32>, 3>(load3(0u, tri.x), load3(0u, tri.y), load3(0u, tri.z));
    var s = surface_sample(h.id, tri, w, h.bary, -d);
    // The lobe's spread of directions moves the hit over a curved surface: its normal turns by
    // the spread times the distance times the curvature (from the vertex normals).
    var curvature = 0.0;
    for (var e = 0u; e < 3u; e++) {
        let ni = load3(1u, tri[e]);
        let nj = load3(1u, tri[(e + 1u) % 3u]);
        let len = length(w[(e + 1u) % 3u] - w[e]);
        if len > 0.0 && dot(ni, ni) > 0.0 && dot(nj, nj) > 0.0 {
            // Finite only: a vertex normal past f32's range normalizes to NaN.
            let c = length(normalize(nj) - normalize(ni)) / len;
            if c < 1e30 {
                curvature = max(curvature, c);
            }
        }
    }
    s.roughness = widened_roughness(s.roughness, blur, h.t, curvature);
    let world = w[0] * h.bary.x + w[1] * h.bary.y + w[2] * h.bary.z;
    return shaded(s, lit(s, world, -d, params.light_count, params.pcf).radiance, 1.0, vec4<f32>(0.0), params.ambient);
}

@compute @workgroup_size(1)
fn reflections_hidden_args() {
    let size = indirect_size((atomicLoad(&followed[0]) + 63u) / 64u);
    hidden_args[0] = size.x;
    hidden_args[1] = size.y;
    hidden_args[2] = size.z;
}

@compute @workgroup_size(64)
fn reflections_hidden(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let entry = indirect_group(wid) * 64u + lid;
    if entry >= atomicLoad(&followed[0]) {
        return;
    }
    let q = atomicLoad(&followed[1u + 2u * entry]);
    let follow = bitcast<f32>(atomicLoad(&followed[2u + 2u * entry]));
    let s = sample_at(q);
    let gid = vec2<u32>(q % frame.width, q / frame.width);
    let m = mirror_at(gid, s);
    let o = mat_mul(frame.inv_view, vec4<f32>(m.p, 1.0)).xyz;
    let r = normalize(mat_mul(frame.inv_view, vec4<f32>(m.r, 0.0)).xyz);
    let reach = min(scene_exit(o, r), 1.25 * abs(follow) + params.thickness);
    let hit = hidden_hit(o, r, reach);
    if hit.t < 0.0 || (follow < 0.0 && faces_camera(hit, o + r * hit.t, o)) {
        return;
    }
    // The pixel's own spread of normals (its footprint on a curved surface): a quarter of the
    // change of the normal across the two pixels either side, per axis.
    var spread = 0.0;
    for (var axis = 0u; axis < 2u; axis++) {
        let dn = 0.25 * normal_change(q, 0u, axis).x;
        spread += dn * dn;
    }
    let alpha = s.roughness * s.roughness;
    reflections[q] = vec4<f32>(reflectance(s) * hidden_seen(hit, r, sqrt(alpha * alpha + 2.0 * spread)), 1.0);
}
#endif
#endif
