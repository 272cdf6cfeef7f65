// Motion blur of the camera's motion, from both layers of the deep G-buffer.
//
// The shutter is open for `shutter` of the time between frames, up to each frame's instant. A
// surface point whose pixel is q now, with motion vector m(q) (its pixel now minus its pixel in
// the last frame, as the resolve writes it for each layer), stood a fraction s of a frame
// earlier at q - s m(q) (moving linearly between frames). For each of `samples` instants
// s_i = shutter (i + j) / samples (j: a per-pixel offset in [0, 1)) the kernel looks for the
// surfaces that stood at pixel p then: it walks from p along p's own motion, one pixel a step,
// out to max_blur s_i / shutter pixels (the longest streak followed over the whole shutter),
// and at each pixel q takes layer 0, and layer 1 (TWO_LAYERS), when its point stood within
// three quarters of a pixel of p's centre at s_i; the nearest of those is what p showed then.
// Layer 1 is where the pass needs the deep G-buffer: where a surface in front has moved on, p
// showed what it now hides. The pixel takes the mean over the instants: layer 0's radiance from
// the image before this pass (`image`), layer 1's shaded with its direct light, emission and the
// ambient term (shared/layer1.wgsl); an instant that finds nothing keeps p's own value.
// Surfaces moving against p's motion are not followed. src/cpu/motion_blur.rs is the same on
// the CPU.
//
// `motion_max` first finds M, the largest motion component (|m|_inf) of any surface the pass
// reads. A point that stood within 0.75 px (per axis) of p's centre at instant s lies within
// s M + 0.75 of it now, so the walk's step k, whose pixel centre lies within half a pixel per
// axis of p's centre + k dir, can only find it while k |dir|_inf <= s M + 1.25, that is for
// k <= sqrt(2) (s M + 1.25): each instant's walk stops there (plus a pixel for rounding). This
// only leaves out steps that cannot find anything, so the image is the same as walking the full
// reach (the CPU reference walks it).
// defines: PACKED TWO_LAYERS

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/spiral.wgsl"
#include "shared/shade.wgsl"
#include "shared/layer1.wgsl"

// Mirrors `MotionBlurUniform` in src/frame/uniforms.rs.
struct MotionBlur {
    ambient: vec3<f32>,
    shutter: f32,
    max_blur: f32,
    samples: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> motion: MotionBlur;
@group(0) @binding(2) var<storage, read> gbuffer0: array<GWord>;
@group(0) @binding(3) var<storage, read> gbuffer1: array<GWord>;
@group(0) @binding(4) var<storage, read> direct1: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> image: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> hdr: array<vec4<f32>>;
// M's bits (a non-negative f32 orders as its bits), cleared before `motion_max`.
@group(0) @binding(7) var<storage, read_write> largest: array<atomic<u32>>;

var<workgroup> group_largest: atomic<u32>;

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

@compute @workgroup_size(8, 8)
fn motion_max(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if li == 0u {
        atomicStore(&group_largest, 0u);
    }
    workgroupBarrier();
    if gid.x < frame.width && gid.y < frame.height {
        let p = gid.y * frame.width + gid.x;
        var m = abs(depth_motion(p, false).yz);
#if TWO_LAYERS
        m = max(m, abs(depth_motion(p, true).yz));
#endif
        atomicMax(&group_largest, bitcast<u32>(max(m.x, m.y)));
    }
    workgroupBarrier();
    if li == 0u {
        atomicMax(&largest[0], atomicLoad(&group_largest));
    }
}

@compute @workgroup_size(8, 8)
fn motion_blur_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let own = depth_motion(p, false);
    let speed = length(own.yz);
    if !(own.x > 0.0) || !(speed * motion.shutter >= 0.5) {
        // Nothing here moved half a pixel while the shutter was open.
        hdr[p] = image[p];
        return;
    }
    let dir = own.yz / speed;
    let centre = vec2<f32>(gid.xy) + 0.5;
    let jitter = f32(pixel_hash(gid.xy) >> 20u) / 4096.0;
    var sum = vec4<f32>(0.0);
    let m_max = bitcast<f32>(atomicLoad(&largest[0]));
    for (var i = 0u; i < motion.samples; i++) {
        let s = motion.shutter * (f32(i) + jitter) / f32(motion.samples);
        let bound = 1.4143 * (s * m_max + 1.25) + 1.0;
        let reach = u32(min(motion.max_blur * s / motion.shutter, bound));
        var best = image[p];
        var nearest = 3.0e38;
        for (var k = 0u; k <= reach; k++) {
            let at = floor(centre + f32(k) * dir);
            if any(at < vec2<f32>(0.0)) || at.x >= f32(frame.width) || at.y >= f32(frame.height) {
                break;
            }
            let q = u32(at.y) * frame.width + u32(at.x);
            let s0 = depth_motion(q, false);
            if s0.x > 0.0 && s0.x < nearest && stood_at(at, s0.yz, s, centre) {
                nearest = s0.x;
                best = image[q];
            }
#if TWO_LAYERS
            let s1 = depth_motion(q, true);
            if s1.x > 0.0 && s1.x < nearest && stood_at(at, s1.yz, s, centre) {
                nearest = s1.x;
                best = layer1_radiance(q, motion.ambient);
            }
#endif
        }
        sum += best;
    }
    hdr[p] = sum / f32(motion.samples);
}
