// Off-screen light for the radiosity: reflective shadow maps (Dachsbacher and Stamminger 2005)
// for the surfaces that neither layer holds.
//
// The screen-space gather sees only what the two layers hold. A room seen from level with its
// light misses the brightest source of indirect light there is, the ceiling around the light,
// which lies above the screen's top; a box's side turned to the light and from the camera is in
// no layer at all. What each light lights first is what its shadow map's faces see: the shadow
// stage draws them again at RSM_RESOLUTION texels a side and resolves them into G-buffer
// records (the resolve's kernel, textures and normal maps included), once per light and kept
// with the shadow maps.
//
// offscreen_clusters: one workgroup per 8x8 texels of a face. Each texel is a patch of the
//   surface its light sees first: at world point P (the face's ray through the texel centre to
//   the visibility word's depth), normal n (towards the light), perpendicular area A_perp
//   (the texel's solid angle times the squared distance for a point or spot light, its square
//   for a directional one) and area A = A_perp / max(n.l, 0.1). It reflects
//   L = (1 - metallic) rho occlusion / pi E (n.l) + Le, E the light's irradiance there
//   (light_at), so that L A = (1 - metallic) rho occlusion / pi E A_perp min(n.l / 0.1, 1) + Le A
//   whatever its slope. A texel whose point one of this frame's layers holds (it projects onto a
//   pixel whose layer-0 or layer-1 depth lies within `held_tolerance` of its own) is left out:
//   the gather already counts it; within HELD_MARGIN of the screen's edge it counts in part
//   (`unheld`). The rest sum into one cluster: sum L A (flux), sum A (area), their area-weighted
//   mean point and normal (not renormalized: a cluster of patches facing many ways sends less
//   towards any one).
// offscreen_add: at each layer-0 point X (normal n_X) with the gather's irradiance E and
//   coverage c, over the clusters that hold a texel (offscreen_compact lists them in order) of
//   which (x, y) mod 4 picks one in `stride`, at most 32 (turned every frame, weighted by
//   stride; the blur and the temporal filter join them; past 512 clusters a frame's 4x4 block
//   covers 16 of the stride's residues, and the frames the rest),
//     E_off = sum flux (n_X . w) (-n . w) / (d^2 + A / pi),  c_off = sum A (n_X . w) (-n . w) / (pi (d^2 + A / pi)),
//   w the unit direction from X to the cluster and d its distance: each cluster a disc of area A
//   (bounded as a disc is where d is small), its light arriving at the cosine-weighted solid
//   angle it subtends. Nothing tests whether something stands between X and the cluster (RSM's
//   approximation): a cluster behind X's own surface faces away or lies below its horizon.
//   The clusters fill at most the share 1 - c the gather left open: where c_off exceeds it,
//   E_off and c_off are scaled by (1 - c) / c_off. E += E_off, c += c_off. Each cluster's
//   radiance flux / A is a mean of its texels', so E stays within pi times the largest
//   radiance the gather or the clusters hold.
// src/cpu/offscreen.rs is the same on the CPU.
// defines: PACKED

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/gbuffer_read.wgsl"
#include "shared/light.wgsl"
#include "shared/shadow.wgsl"
#include "shared/spiral.wgsl"
#include "shared/vis.wgsl"

// Mirrors `OffscreenUniform` in src/frame/shadow.rs.
struct Offscreen {
    // Faces of every shadow-casting light, RSM_RESOLUTION texels a side each.
    faces: u32,
    // Frames since the radiosity's history began: turns which clusters a pixel takes.
    turn: u32,
    // Whether this frame has layer 1 (its depths bound as vis1).
    layers: u32,
    _pad: u32,
}

// Texels a face side, the clusters a pixel sums at most, and the strip along the screen's edge
// where a held point still counts in part (a share of the screen's height): set from
// src/frame/shadow.rs's RSM_* constants. A cluster's side in texels is the cluster kernel's
// workgroup (RSM_CLUSTER_SIDE there names it).
override RSM_RESOLUTION: u32 = 64u;
const CLUSTER_SIDE: u32 = 8u;
override CLUSTERS_PER_FACE: u32 = (RSM_RESOLUTION / CLUSTER_SIDE) * (RSM_RESOLUTION / CLUSTER_SIDE);
override CLUSTERS_PER_PIXEL: u32 = 32u;
override HELD_MARGIN: f32 = 0.1;

// Mirrors `Cluster` in src/frame/shadow.rs.
struct Cluster {
    // Area-weighted mean world point, and the area (0: an empty cluster).
    position: vec3<f32>,
    area: f32,
    // Area-weighted mean normal (length at most 1).
    normal: vec3<f32>,
    _pad0: f32,
    // sum L A.
    flux: vec3<f32>,
    _pad1: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Offscreen;
@group(0) @binding(2) var<storage, read> lights: array<Light>;
// The RSM faces (ShadowFace at RSM_RESOLUTION, offset in texels), the light of each, their
// visibility words and their G-buffer records, back to back.
@group(0) @binding(3) var<storage, read> faces: array<ShadowFace>;
@group(0) @binding(4) var<storage, read> face_lights: array<u32>;
@group(0) @binding(5) var<storage, read> rsm_vis: array<u32>;
@group(0) @binding(6) var<storage, read> rsm: array<GWord>;
// This frame's visibility words of both layers (layer 1's unused without it).
@group(0) @binding(7) var<storage, read> vis0: array<u32>;
@group(0) @binding(8) var<storage, read> vis1: array<u32>;
@group(0) @binding(9) var<storage, read_write> clusters: array<Cluster>;
// This frame's layer 0, the points that receive the clusters' light (read by sample_at).
@group(0) @binding(10) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(11) var<storage, read_write> raw: array<vec4<f32>>;
// The clusters that hold a texel, in cluster order, and ([0]) how many.
@group(0) @binding(12) var<storage, read_write> lit: array<Cluster>;
@group(0) @binding(13) var<storage, read_write> lit_count: array<u32>;

// A pixel sums one in `stride` of `count` clusters: the smallest power of two that keeps them
// within CLUSTERS_PER_PIXEL (many lights' clusters cost each pixel no more).
fn stride_for(count: u32) -> u32 {
    var stride = 1u;
    while stride * CLUSTERS_PER_PIXEL < count {
        stride *= 2u;
    }
    return stride;
}

// Which of the `stride` residues pixel `pixel` sums this frame: the 16 pixels of a 4x4 block
// take different ones, turned every frame (by one, or past 16 by the block's 16, so that the
// frames cover every residue in turn).
fn stride_phase(pixel: vec2<u32>, stride: u32, turn: u32) -> u32 {
    let b = (pixel.x & 3u) + 4u * (pixel.y & 3u);
    return (b + select(turn, 16u * turn, stride > 16u)) % stride;
}

fn rsm_sample(t: u32) -> GSample {
#if PACKED
    return gbuffer_decode(rsm[t * G_WORDS], rsm[t * G_WORDS + 1u]);
#else
    return gbuffer_decode(rsm[t * G_WORDS], rsm[t * G_WORDS + 1u], rsm[t * G_WORDS + 2u], rsm[t * G_WORDS + 3u]);
#endif
}

// The world point of face f's view-space point v (the face's view is rigid: R^T (v - t)).
fn face_world(f: ShadowFace, v: vec3<f32>) -> vec3<f32> {
    let u = v - f.view[3].xyz;
    return vec3<f32>(dot(f.view[0].xyz, u), dot(f.view[1].xyz, u), dot(f.view[2].xyz, u));
}

// How much of the world point `world` (normal n) the clusters carry: 1 where none of this
// frame's layers holds it, 0 where one does (it projects onto a pixel whose layer-0 or layer-1
// depth lies within the tolerance of its own) far enough from the screen's edge, rising to 1
// at the edge over HELD_MARGIN of the screen's height: the gather's steps rarely land in a thin
// strip along the edge.
fn unheld(world: vec3<f32>, n: vec3<f32>) -> f32 {
    let v = mat_mul(frame.view, vec4<f32>(world, 1.0));
    let c = mat_mul(frame.proj, v);
    if !(c.w > 0.0) {
        return 1.0;
    }
    let size = vec2<f32>(f32(frame.width), f32(frame.height));
    let px = clip_to_pixel(c, size);
    if !(px.x >= 0.0 && px.y >= 0.0 && px.x < size.x && px.y < size.y) {
        return 1.0;
    }
    let z = -v.z;
    let q = u32(px.y) * frame.width + u32(px.x);
    let tolerance = held_tolerance(v.xyz, mat_mul(frame.view, vec4<f32>(n, 0.0)).xyz, z);
    let z0 = vis0[2u * q + 1u];
    let z1 = vis1[2u * q + 1u];
    let held = (z0 != VIS_EMPTY && abs(bitcast<f32>(z0) - z) <= tolerance)
        || (params.layers == 2u && z1 != VIS_EMPTY && abs(bitcast<f32>(z1) - z) <= tolerance);
    if !held {
        return 1.0;
    }
    let edge = min(min(px.x, size.x - px.x), min(px.y, size.y - px.y));
    return clamp(1.0 - edge / max(HELD_MARGIN * size.y, 1e-6), 0.0, 1.0);
}

// How far a pixel's depth may lie from a point's (view-space v, normal n, view depth z) on the
// same surface: two pixels' footprint times the surface's slope to the view ray (at most 10),
// and a thousandth of the depth for rounding.
fn held_tolerance(v: vec3<f32>, n: vec3<f32>, z: f32) -> f32 {
    return depth_slope_span(frame, v, n, 2.0) + 1e-3 * z;
}

var<workgroup> shared_flux: array<vec4<f32>, 64>;
var<workgroup> shared_point: array<vec4<f32>, 64>;
var<workgroup> shared_normal: array<vec4<f32>, 64>;

@compute @workgroup_size(8, 8)
fn offscreen_clusters(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) li: u32, @builtin(local_invocation_id) lid: vec3<u32>) {
    let cells = RSM_RESOLUTION / CLUSTER_SIDE;
    let face = wid.x / cells;
    let texel = vec2<u32>((wid.x % cells) * CLUSTER_SIDE + lid.x, wid.y * CLUSTER_SIDE + lid.y);
    var flux = vec3<f32>(0.0);
    var area = 0.0;
    var point = vec3<f32>(0.0);
    var normal = vec3<f32>(0.0);
    if face < params.faces {
        let f = faces[face];
        let t = f.offset + texel.y * RSM_RESOLUTION + texel.x;
        let depth_bits = rsm_vis[2u * t + 1u];
        let s = rsm_sample(t);
        if depth_bits != VIS_EMPTY && s.depth > 0.0 {
            let depth = bitcast<f32>(depth_bits);
            let res = f32(RSM_RESOLUTION);
            let ndc = vec2<f32>((f32(texel.x) + 0.5) / res * 2.0 - 1.0, 1.0 - (f32(texel.y) + 0.5) / res * 2.0);
            var v: vec3<f32>;
            var perpendicular: f32;
            if f.ortho != 0u {
                v = vec3<f32>((ndc.x - f.proj[3].x) / f.proj[0].x, (ndc.y - f.proj[3].y) / f.proj[1].y, -depth);
                perpendicular = f.texel * f.texel;
            } else {
                let unit = vec3<f32>(ndc.x / f.proj[0].x, ndc.y / f.proj[1].y, -1.0);
                v = unit * depth;
                // The texel's solid angle texel^2 / |unit|^3 times the squared distance.
                perpendicular = f.texel * f.texel * depth * depth / length(unit);
            }
            let world = face_world(f, v);
            let light = lights[face_lights[face]];
            var l = vec3<f32>(0.0);
            let e = light_at(light, world, &l);
            let cos_l = max(dot(s.normal, l), 0.0);
            let a = perpendicular / max(cos_l, 0.1);
            let reflected = (1.0 - s.metallic) * s.occlusion * s.base_color / PI * e * perpendicular * min(cos_l / 0.1, 1.0);
            let sent = reflected + s.emissive * a;
            let ok = all(abs(sent) <= vec3<f32>(3.0e38)) && a <= 3.0e38 && all(abs(world) <= vec3<f32>(3.0e38));
            let weight = unheld(world, s.normal);
            if ok && weight > 0.0 {
                flux = sent * weight;
                area = a * weight;
                point = world * area;
                normal = s.normal * area;
            }
        }
    }
    shared_flux[li] = vec4<f32>(flux, area);
    shared_point[li] = vec4<f32>(point, 0.0);
    shared_normal[li] = vec4<f32>(normal, 0.0);
    for (var half = 32u; half > 0u; half >>= 1u) {
        workgroupBarrier();
        if li < half {
            shared_flux[li] += shared_flux[li + half];
            shared_point[li] += shared_point[li + half];
            shared_normal[li] += shared_normal[li + half];
        }
    }
    if li == 0u && face < params.faces {
        let sum = shared_flux[0];
        var c = Cluster();
        if sum.a > 0.0 && sum.a <= 3.0e38 {
            c = Cluster(shared_point[0].xyz / sum.a, sum.a, shared_normal[0].xyz / sum.a, 0.0, sum.rgb, 0.0);
        }
        clusters[face * CLUSTERS_PER_FACE + wid.y * cells + wid.x % cells] = c;
    }
}

var<workgroup> scan: array<u32, 64>;

// The clusters that hold a texel, in order: one workgroup scans them 64 at a time.
@compute @workgroup_size(64)
fn offscreen_compact(@builtin(local_invocation_index) li: u32) {
    let count = params.faces * CLUSTERS_PER_FACE;
    var base = 0u;
    for (var start = 0u; start < count; start += 64u) {
        let k = start + li;
        var c = Cluster();
        var flag = 0u;
        if k < count {
            c = clusters[k];
            flag = u32(c.area > 0.0);
        }
        scan[li] = flag;
        for (var d = 1u; d < 64u; d <<= 1u) {
            workgroupBarrier();
            var v = scan[li];
            if li >= d {
                v += scan[li - d];
            }
            workgroupBarrier();
            scan[li] = v;
        }
        workgroupBarrier();
        if flag != 0u {
            lit[base + scan[li] - 1u] = c;
        }
        base += scan[63];
        workgroupBarrier();
    }
    if li == 0u {
        lit_count[0] = base;
    }
}

@compute @workgroup_size(8, 8)
fn offscreen_add(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let s = sample_at(p);
    if !(s.depth > 0.0) {
        return;
    }
    let x = mat_mul(frame.inv_view, vec4<f32>(view_position(frame, vec2<f32>(gid.xy) + 0.5, s.depth), 1.0)).xyz;
    let n = s.normal;
    let count = lit_count[0];
    let stride = stride_for(count);
    let phase = stride_phase(gid.xy, stride, params.turn);
    var e = vec3<f32>(0.0);
    var covered = 0.0;
    for (var k = phase; k < count; k += stride) {
        let c = lit[k];
        let d = c.position - x;
        let d2 = dot(d, d);
        if !(d2 > 0.0) {
            continue;
        }
        let w = d * inverseSqrt(d2);
        let cos_x = dot(n, w);
        let cos_p = -dot(c.normal, w);
        if cos_x <= 0.0 || cos_p <= 0.0 {
            continue;
        }
        let g = cos_x * cos_p / (d2 + c.area / PI);
        e += c.flux * g;
        covered += c.area * g / PI;
    }
    // The clusters fill at most the share of the hemisphere the gather left open: nothing
    // tells which of them a surface on screen hides, and without the cap overlapping clusters
    // could add up to more than the whole hemisphere.
    let g = raw[p];
    let open = clamp(1.0 - g.a, 0.0, 1.0);
    let share = covered * f32(stride);
    let scale = select(f32(stride), f32(stride) * open / share, share > open);
    let sum = g.rgb + e * scale;
    if all(abs(sum) <= vec3<f32>(3.0e38)) {
        raw[p] = vec4<f32>(sum, min(g.a + covered * scale, 1.0));
    }
}
