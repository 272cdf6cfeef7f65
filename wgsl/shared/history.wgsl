// Where a point of this frame was in the previous one, and the previous frame's filtered value
// there: the reprojection the temporal filters (wgsl/temporal.wgsl) and the radiosity's
// feedback share. src/cpu has no twin: the filters' tests run frames on the GPU.
//
// history_at reads bindings the including kernel declares by name (WGSL cannot pass a storage
// buffer to a function, so the names are the contract): `prev_vis0`, the previous frame's
// layer-0 visibility words, and `history_in`, its filtered values, an `array<Value>` of the
// kernel's `Value` type, with its `usable` and `Mean` (shared/value.wgsl or
// shared/irradiance.wgsl, included before this file).
// Needs shared/frame.wgsl, shared/gbuffer.wgsl, shared/spiral.wgsl and shared/vis.wgsl.

// Where the point of a sample was in the previous frame.
struct Previous {
    // Its position in the previous frame's pixels.
    px: vec2<f32>,
    // The point and its normal in the previous frame's view space.
    v: vec3<f32>,
    n: vec3<f32>,
    // How far its surface's view depth runs over one pixel (depth_slope_span, linear in the
    // pixels): found once for the pixels depth_at reads around it.
    span: f32,
}

// Where the point of sample s at `pixel` was in the previous frame (false when off the screen
// or when there is no point).
fn previous_point(pixel: vec2<u32>, s: GSample, out: ptr<function, Previous>) -> bool {
    if !(s.depth > 0.0) {
        return false;
    }
    let prev = vec2<f32>(pixel) + 0.5 - s.motion;
    if !(prev.x >= 0.0 && prev.y >= 0.0 && prev.x < f32(frame.width) && prev.y < f32(frame.height)) {
        return false;
    }
    let world = mat_mul(frame.inv_view, vec4<f32>(view_position(frame, vec2<f32>(pixel) + 0.5, s.depth), 1.0));
    let v = mat_mul(frame.prev_view, world).xyz;
    let n = mat_mul(frame.prev_view, vec4<f32>(s.normal, 0.0)).xyz;
    *out = Previous(prev, v, n, depth_slope_span(frame, v, n, 1.0));
    return true;
}

// The view depth the surface of point p had at pixel centre `centre` of the previous frame: where
// that pixel's ray meets p's tangent plane, moved from p's own depth by no more than a slanted
// surface runs over their distance (depth_slope_span: the slope at most 10; the rays taken with
// this frame's projection). A pixel's depth belongs to its centre, up to sqrt(1/2) pixel from the
// point: held against the point's own depth, a floor seen at a slant lost its history at every
// turn of the camera (README, "Slanted surfaces keep their history"), and held against any depth
// within that run, a surface uncovered beside one that moved away could take its history.
fn depth_at(p: Previous, centre: vec2<f32>) -> f32 {
    let o = view_position(frame, centre, 0.0);
    let dir = view_position(frame, centre, 1.0) - o;
    let own = -p.v.z;
    let t = dot(p.v - o, p.n) / dot(dir, p.n);
    let span = p.span * length(centre - p.px);
    return own + select(0.0, clamp(t - own, -span, span), abs(t) <= 3.0e38);
}

// The previous frame's filtered value at the layer-0 point of `pixel` (sample s), where there
// is a `history` at all: the bilinear mean of the four pixels around the point's position in the
// previous frame, over those whose layer 0 lies within `tolerance` (view depth, scene units) of
// the point's surface at that pixel's centre (the same surface) and holds a usable value, their
// weights renormalized. `valid` tells whether any does (the zero value where none). A point that
// was hidden (in layer 1, or not at all) has none: taking the layer-0 value there would paint
// the surface that covered it. (The nearest pixel alone moves the history by up to half a pixel
// each frame: the obscurance's creases and fins drifted and blurred into their neighbours over
// the frames a point stays in view, README "The obscurance over time".)
fn history_at(pixel: vec2<u32>, s: GSample, history: bool, tolerance: f32, valid: ptr<function, bool>) -> Value {
    *valid = false;
    var p: Previous;
    if !history || !previous_point(pixel, s, &p) {
        return Value();
    }
    let f = p.px - 0.5;
    let base = vec2<i32>(floor(f));
    // Less than the rasterizer's 1/256 pixel from a pixel centre is that centre: a motion the
    // raster cannot resolve moves nothing, and a neighbour's sliver of weight must not lend its
    // history to a point uncovered where the camera did not move (a still camera's motion is 0
    // exactly: wgsl/resolve.wgsl).
    var t = f - vec2<f32>(base);
    t = select(t, round(t), abs(t - round(t)) < vec2<f32>(1.0 / 256.0));
    let size = vec2<i32>(i32(frame.width), i32(frame.height));
    var mean = Mean();
    for (var k = 0u; k < 4u; k++) {
        let o = vec2<u32>(k & 1u, k >> 1u);
        let at = base + vec2<i32>(o);
        let w = select(1.0 - t.x, t.x, o.x == 1u) * select(1.0 - t.y, t.y, o.y == 1u);
        if any(at < vec2<i32>(0)) || any(at >= size) || !(w > 0.0) {
            continue;
        }
        let q = u32(at.y) * frame.width + u32(at.x);
        let z0 = prev_vis0[2u * q + 1u];
        if z0 == VIS_EMPTY || !(abs(depth_at(p, vec2<f32>(at) + 0.5) - bitcast<f32>(z0)) <= tolerance) {
            continue;
        }
        let h = history_in[q];
        if usable(h) {
            mean_add(&mean, h, w);
        }
    }
    if !(mean.weight > 0.0) {
        return Value();
    }
    *valid = true;
    return mean_value(mean);
}
