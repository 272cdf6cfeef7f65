// Motion blur from both layers of the deep G-buffer: of the camera's motion and of geometry
// that moves.
//
// The shutter is open for `shutter` of the time between frames, up to each frame's instant. A
// surface point whose pixel is q now, with motion vector m(q) (its pixel now minus its pixel in
// the last frame, as the resolve writes it for each layer: camera and object motion both), stood
// a fraction s of a frame earlier at q - s m(q) (moving linearly between frames). For each of
// `samples` instants s_i = shutter (i + j) / samples (j: a per-pixel offset in [0, 1)) the
// kernel looks for the surfaces that stood at pixel p then: it walks from p one pixel a step out
// to max_blur s_i / shutter pixels (the longest streak followed over the whole shutter), and at
// each pixel q takes layer 0, and layer 1 (TWO_LAYERS), when its point stood within three
// quarters of a pixel of p's centre at s_i; the nearest of those is what p showed then. Layer 1
// is where the pass needs the deep G-buffer: where a surface in front has moved on, p showed
// what it now hides. The pixel takes the mean over the instants: layer 0's radiance from the
// image before this pass (`image`), layer 1's shaded with its direct light, emission and the
// ambient term (shared/layer1.wgsl); an instant that finds nothing keeps p's own value.
//
// Which way to walk: a surface found at q moved from p to q, so the walk must follow its
// motion. Each pixel walks along its own surface's motion, which follows the camera's: that
// motion changes smoothly across the image but for depth. Geometry moving by itself breaks it,
// so each pixel also walks along the motion of the fastest such surface near it (the
// reconstruction filter's "neighbourhood maximum velocity", of the objects' own motion):
// `motion_tiles` finds, per TILE x TILE tile, the surface (of those the pass reads) whose
// motion differs most (largest component) from what the camera alone gives it, and
// `motion_neighbours` the most of those within `tile_reach` tiles, enough to cover every pixel
// a walk reaches. A still pixel beside a moving object so shows the object passing over it.
// The second walk is left out where the first passes within half a pixel of where that motion
// puts its surfaces. A third motion near two others is not followed; a motion that is not
// finite never is.
//
// The neighbourhood's largest motion component M (of any surface) also bounds each walk: a point that stood within 0.75 px
// (per axis) of p's centre at instant s lies within s M + 0.75 of it now, so the walk's step k,
// whose pixel centre lies within half a pixel per axis of p's centre + k dir, can only find it
// while k |dir|_inf <= s M + 1.25, that is for k <= sqrt(2) (s M + 1.25): each instant's walk
// stops there (plus a pixel for rounding). This only leaves out steps that cannot find anything,
// so the image is the same as walking the full reach (the CPU reference walks it).
// src/cpu/motion_blur.rs is the same on the CPU.
// defines: PACKED TWO_LAYERS

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/spiral.wgsl"
#include "shared/shade.wgsl"
#include "shared/layer1.wgsl"

// Pixels per side of a tile of `motion_tiles`.
const TILE: u32 = 16u;

// Mirrors `MotionBlurUniform` in src/frame/uniforms.rs.
struct MotionBlur {
    ambient: vec3<f32>,
    shutter: f32,
    max_blur: f32,
    samples: u32,
    // Tiles each side that `motion_neighbours` looks over: ceil((max_blur + 1) / TILE).
    tile_reach: u32,
    // Tiles per row.
    tiles_x: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> motion: MotionBlur;
@group(0) @binding(2) var<storage, read> gbuffer0: array<GWord>;
@group(0) @binding(3) var<storage, read> gbuffer1: array<GWord>;
@group(0) @binding(4) var<storage, read> direct1: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> image: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> hdr: array<vec4<f32>>;
// Per tile (`tiles`) and per tile neighbourhood (`neighbours`): the motion (xy) of the surface
// moving most by itself and the largest component of that own motion (z), and the largest
// motion component of any surface (w).
@group(0) @binding(7) var<storage, read_write> tiles: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> neighbours: array<vec4<f32>>;

// The view depth (0: no surface) and the motion of layer 0 (`layer1` false) or 1 at pixel p.
fn depth_motion(p: u32, layer1: bool) -> vec3<f32> {
    var w0: GWord;
    var wm: GWord;
    if layer1 {
        w0 = gbuffer1[p * G_WORDS];
        wm = gbuffer1[p * G_WORDS + G_MOTION_WORD];
    } else {
        w0 = gbuffer0[p * G_WORDS];
        wm = gbuffer0[p * G_WORDS + G_MOTION_WORD];
    }
    return vec3<f32>(gword_depth(w0), gword_motion(wm));
}

// Whether a point now at the centre of pixel `q` with motion `m` stood within three quarters of
// a pixel of `centre` a fraction `s` of a frame earlier.
fn stood_at(q: vec2<f32>, m: vec2<f32>, s: f32, centre: vec2<f32>) -> bool {
    let d = abs(q + 0.5 - s * m - centre);
    return max(d.x, d.y) <= 0.75;
}

// The motion the camera alone gives the surface at view depth `d` seen through the centre
// `centre` of a pixel (the resolve's for still geometry; none where it stood behind the camera).
fn camera_motion(centre: vec2<f32>, d: f32) -> vec2<f32> {
    let pc = reproject(frame, centre, d).clip;
    if !(pc.w > 1e-20) {
        return vec2<f32>(0.0);
    }
    let prev = clip_to_pixel(pc, vec2<f32>(f32(frame.width), f32(frame.height)));
    return centre - prev;
}

// `best` (as a tile holds it) with the surface at pixel `centre` whose (depth, motion) is
// `sample`: the largest motion component, and the motion of the surface moving most by itself
// (the larger largest component of its motion less the camera's, the earlier one on a tie). A
// surface with no depth or a motion that is not finite does not count.
fn faster(best: vec4<f32>, sample: vec3<f32>, centre: vec2<f32>) -> vec4<f32> {
    let key = max(abs(sample.y), abs(sample.z));
    if !(sample.x > 0.0 && key <= 3.0e38) {
        return best;
    }
    var out = best;
    out.w = max(best.w, key);
    let own = abs(sample.yz - camera_motion(centre, sample.x));
    let own_key = max(own.x, own.y);
    if own_key <= 3.0e38 && own_key > best.z {
        out = vec4<f32>(sample.yz, own_key, out.w);
    }
    return out;
}

@compute @workgroup_size(8, 8)
fn motion_tiles(@builtin(global_invocation_id) gid: vec3<u32>) {
    let tiles_y = (frame.height + TILE - 1u) / TILE;
    if gid.x >= motion.tiles_x || gid.y >= tiles_y {
        return;
    }
    var best = vec4<f32>(0.0);
    for (var y = gid.y * TILE; y < min((gid.y + 1u) * TILE, frame.height); y++) {
        for (var x = gid.x * TILE; x < min((gid.x + 1u) * TILE, frame.width); x++) {
            let p = y * frame.width + x;
            let centre = vec2<f32>(f32(x), f32(y)) + 0.5;
            best = faster(best, depth_motion(p, false), centre);
#if TWO_LAYERS
            best = faster(best, depth_motion(p, true), centre);
#endif
        }
    }
    tiles[gid.y * motion.tiles_x + gid.x] = best;
}

@compute @workgroup_size(8, 8)
fn motion_neighbours(@builtin(global_invocation_id) gid: vec3<u32>) {
    let tiles_y = (frame.height + TILE - 1u) / TILE;
    if gid.x >= motion.tiles_x || gid.y >= tiles_y {
        return;
    }
    var best = vec4<f32>(0.0);
    let r = motion.tile_reach;
    for (var y = max(gid.y, r) - r; y <= min(gid.y + r, tiles_y - 1u); y++) {
        for (var x = max(gid.x, r) - r; x <= min(gid.x + r, motion.tiles_x - 1u); x++) {
            let t = tiles[y * motion.tiles_x + x];
            if t.z > best.z {
                best = vec4<f32>(t.xyz, best.w);
            }
            best.w = max(best.w, t.w);
        }
    }
    neighbours[gid.y * motion.tiles_x + gid.x] = best;
}

// What pixel p showed at instant s as one walk along `dir` finds it: `found` (the radiance and
// the nearest depth so far) with the nearer surface of each step that stood at p then.
fn walk(found: ptr<function, vec4<f32>>, nearest: ptr<function, f32>, centre: vec2<f32>, dir: vec2<f32>, s: f32, reach: u32) {
    for (var k = 0u; k <= reach; k++) {
        let at = floor(centre + f32(k) * dir);
        if any(at < vec2<f32>(0.0)) || at.x >= f32(frame.width) || at.y >= f32(frame.height) {
            break;
        }
        let q = u32(at.y) * frame.width + u32(at.x);
        let s0 = depth_motion(q, false);
        if s0.x > 0.0 && s0.x < *nearest && stood_at(at, s0.yz, s, centre) {
            *nearest = s0.x;
            *found = image[q];
        }
#if TWO_LAYERS
        let s1 = depth_motion(q, true);
        if s1.x > 0.0 && s1.x < *nearest && stood_at(at, s1.yz, s, centre) {
            *nearest = s1.x;
            *found = layer1_radiance(q, motion.ambient);
        }
#endif
    }
}

@compute @workgroup_size(8, 8)
fn motion_blur_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let own = depth_motion(p, false);
    let near = neighbours[(gid.y / TILE) * motion.tiles_x + gid.x / TILE];
    // The walks: along p's own motion when it moved half a pixel while the shutter was open;
    // along the motion of the neighbourhood's surface moving most by itself, when that surface
    // moved half a pixel by itself and on screen, unless the own walk passes within half a
    // pixel of where that motion puts the surfaces that stood at p (the same way, off the own
    // walk's line by at most the shutter's share of the motion across it).
    let speed = length(own.yz);
    let walk_own = own.x > 0.0 && speed * motion.shutter >= 0.5 && speed <= 3.0e38;
    let own_dir = own.yz / speed;
    let near_dir = near.xy / length(near.xy);
    let across = abs(own_dir.x * near.y - own_dir.y * near.x) * motion.shutter;
    let covered = walk_own && dot(own_dir, near.xy) > 0.0 && across <= 0.5;
    let near_moves = max(abs(near.x), abs(near.y)) * motion.shutter >= 0.5;
    let walk_near = near.z * motion.shutter >= 0.5 && near_moves && !covered;
    if !walk_own && !walk_near {
        hdr[p] = image[p];
        return;
    }
    let centre = vec2<f32>(gid.xy) + 0.5;
    let jitter = f32(pixel_hash(gid.xy) >> 20u) / 4096.0;
    var sum = vec4<f32>(0.0);
    for (var i = 0u; i < motion.samples; i++) {
        let s = motion.shutter * (f32(i) + jitter) / f32(motion.samples);
        let bound = 1.4143 * (s * near.w + 1.25) + 1.0;
        let reach = u32(min(motion.max_blur * s / motion.shutter, bound));
        var found = image[p];
        var nearest = 3.0e38;
        if walk_own {
            walk(&found, &nearest, centre, own_dir, s, reach);
        }
        if walk_near {
            walk(&found, &nearest, centre, near_dir, s, reach);
        }
        sum += found;
    }
    hdr[p] = sum / f32(motion.samples);
}
