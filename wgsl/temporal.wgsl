// The temporal filter of a per-pixel estimate (the radiosity's irradiance and coverage with
// VEC4, the obscurance's AV without): each frame's value is blended with the previous frame's
// filtered value at the same surface point,
//     V_t = V (1 - alpha) + V_{t-1} alpha
// where the point has a history (shared/history.wgsl's history_at: the previous frame's layer 0
// at the pixel the point fell in lies on the point's surface), otherwise V. A value that is not
// usable (not finite, or out of its range) never enters the history: this frame's is replaced
// by EMPTY (no light; full visibility), a stored one is not taken.
// Estimators that turn their taps every frame (the slices, the spiral) see other directions
// each frame, so the filter averages their noise away over the frames a surface stays in view.
// defines: PACKED VEC4

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"
#include "shared/gbuffer_read.wgsl"
#include "shared/spiral.wgsl"
#include "shared/vis.wgsl"
#include "shared/value.wgsl"

#if VEC4
const EMPTY: Value = vec4<f32>(0.0);
#else
const EMPTY: Value = 1.0;
#endif

// Mirrors `TemporalUniform` in src/frame/uniforms.rs.
struct Temporal {
    // Weight alpha of the history, in [0, 1).
    alpha: f32,
    // How far (view depth, scene units) the previous frame's layer 0 may lie from the point's
    // surface for the point to keep its history.
    tolerance: f32,
    // 1 when the previous frame's filtered values may be used.
    history: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Temporal;
@group(0) @binding(2) var<storage, read> gbuffer: array<GWord>;
@group(0) @binding(3) var<storage, read> prev_vis0: array<u32>;
@group(0) @binding(4) var<storage, read> current: array<Value>;
@group(0) @binding(5) var<storage, read> history_in: array<Value>;
@group(0) @binding(6) var<storage, read_write> history_out: array<Value>;

#include "shared/history.wgsl"

@compute @workgroup_size(8, 8)
fn temporal_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let p = gid.y * frame.width + gid.x;
    let now = current[p];
    var v = select(EMPTY, now, usable(now));
    var valid = false;
    let h = history_at(gid.xy, sample_at(p), params.history != 0u, params.tolerance, &valid);
    if valid {
        // mix(v, h, alpha), exactly v where the history equals it, kept in range
        // (shared/mean.wgsl).
        v = bounded(v + (h - v) * params.alpha);
    }
    history_out[p] = select(EMPTY, v, usable(v));
}
