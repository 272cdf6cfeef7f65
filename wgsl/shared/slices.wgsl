// Slices of the hemisphere, shared by the obscurance (`horizon`, `bitmask`) and the radiosity
// gather (`slices`). src/cpu/slices.rs is the same on the CPU.
//
// A slice is the plane through the view vector V and one screen direction phi (turned per
// pixel). In it a direction is its angle theta from V, the hemisphere around the normal is
// theta in [gamma - pi/2, gamma + pi/2] (gamma: the angle of the normal projected into the
// slice, n_p), and dw = |sin theta| dtheta dphi, so the slice holds
//     |n_p| integral g(theta) cos(theta - gamma) |sin theta| dtheta
// of any cosine-weighted integral integral g(w) cos dw, over phi in [0, pi). The weight
// W(theta) of the arc from its start has a closed form; the arc is cut into SECTORS sectors of
// equal weight (one bit each, their centres offset per pixel so that no direction is always
// rounded the same way). Steps marched outwards on both sides of the slice's screen line read
// each layer's point at that pixel; a point hides the arc from its own direction to the
// direction of its back (a solid along its view ray, `back` deep, or without end), and a sector
// takes the value of the first point that hides it. With S slices at phi = pi (k + turn) / S
// the integral is (pi / S) sum_slices |n_p| W_total / SECTORS sum_sectors g.
// Needs shared/frame.wgsl and shared/spiral.wgsl.

const SECTORS: u32 = 32u;
const SLICE_PI: f32 = 3.14159265;

// One slice at a pixel: V, gamma, the arc's total weight W_total and its share of the
// integral |n_p| W_total (0 when the normal is perpendicular to the slice).
struct Slice {
    dir: vec2<f32>,
    v: vec3<f32>,
    gamma: f32,
    total: f32,
    weight: f32,
    offset: f32,
    // sin and cos of gamma; W(theta) = w_neg - F(theta) for theta <= 0, w_pos + F(theta) above,
    // F(t) = -cos(2 t - gamma) / 4 + t sin(gamma) / 2 the antiderivative of cos(t - gamma) sin t,
    // so that a direction's weight costs no trigonometry past its angle.
    sin_gamma: f32,
    cos_gamma: f32,
    w_neg: f32,
    w_pos: f32,
}

// A pixel's turn of the slices, jitter of the steps and offset of the sectors; the turn and the
// jitter moved on by `frame_turn` steps of the golden ratio and of the plastic number's second
// R2 constant (0.5698), so that temporal accumulation sees other slices and other distances
// along them (the radiosity's 32nd frame on 2CylinderEngine read 0.45 of the truth with the
// jitter fixed, 0.52 with it turned: README). The turn follows a
// 4x4 Bayer pattern (plus a little of the pixel's hash, so that the pattern does not show), so
// that every 4x4 block, and so every blur window, holds 16 evenly spread turns: a bright source
// that one pixel's slices happen to cross is not a lone outlier the blur would spread into a
// blot. The jitter and offset come from the pixel's hash.
fn slice_noise(pixel: vec2<u32>, frame_turn: u32) -> vec3<f32> {
    let hash = pixel_hash(pixel);
    let b = pixel & vec2<u32>(3u);
    // The 4x4 Bayer matrix, row by row: 0 8 2 10 / 12 4 14 6 / 3 11 1 9 / 15 7 13 5.
    let bayer = ((b.x & 1u) << 3u | (b.y & 1u) << 2u | (b.x >> 1u) << 1u | (b.y >> 1u)) ^ ((b.y & 1u) << 3u | (b.y >> 1u) << 1u);
    let within = f32(hash >> 24u) / 256.0;
    let turn = fract((f32(bayer) + within) / 16.0 + f32(frame_turn % 4096u) * 0.618034);
    let jitter = fract(f32((hash >> 8u) & 0xfffu) / 4096.0 + f32(frame_turn % 4096u) * 0.5698403);
    let offset = f32(hash & 0xffu) / 256.0 + 0.5 / 256.0;
    return vec3<f32>(turn, jitter, offset);
}

// The pixel of the step at `h` pixels on `side` (+-1) of slice `sl` through `pixel`, and
// whether it lies on screen and is not `pixel` itself.
fn slice_tap(pixel: vec2<u32>, sl: Slice, h: f32, side: f32, tap: ptr<function, vec2<i32>>) -> bool {
    *tap = vec2<i32>(floor(vec2<f32>(pixel) + 0.5 + side * h * sl.dir));
    let t = *tap;
    return all(t >= vec2<i32>(0)) && t.x < i32(frame.width) && t.y < i32(frame.height) && any(vec2<u32>(t) != pixel);
}

// The spacing (pixels) of `steps` steps on `side` (+-1) of slice `sl` through `pixel`: they
// spread over the radius `r_px` or, where the slice's line leaves the screen first, over the
// part on screen (a step off screen finds nothing).
fn slice_spacing(pixel: vec2<u32>, sl: Slice, side: f32, r_px: f32, steps: u32) -> f32 {
    return min(r_px, screen_exit(frame, vec2<f32>(pixel) + 0.5, sl.dir * side)) / f32(steps);
}

// How far (pixels) step j of `steps` lies along a side whose steps would lie `spacing` apart if
// spread evenly: at t^1.5 of the side's reach, t = (j + jitter) / steps, so that they crowd
// towards the point, where the falloff (the obscurance's) and the cosine weigh most and a groove
// narrower than the even spacing would fall between two steps. Both slice estimators place
// their steps so. (For the obscurance an even spread left the
// engine's fin grooves open: RMSE 0.0948 against 0.0825 at 160x120; t^2 thinned the far steps
// until the Cornell box's creases at a distance lost occlusion: bias +0.013. For the radiosity,
// docs/accuracy.md, *Steps crowded towards the point*.)
fn step_distance(spacing: f32, j: u32, steps: u32, jitter: f32) -> f32 {
    let t = (f32(j) + jitter) / f32(steps);
    return spacing * f32(steps) * t * sqrt(t);
}

// Slice k of `count` at the view-space point c (normal n) with the pixel's noise.
fn slice_at(k: u32, count: u32, noise: vec3<f32>, c: vec3<f32>, n: vec3<f32>) -> Slice {
    var sl: Slice;
    let phi = SLICE_PI * (f32(k) + noise.x) / f32(count);
    sl.dir = vec2<f32>(cos(phi), sin(phi));
    sl.v = select(normalize(-c), vec3<f32>(0.0, 0.0, 1.0), frame.ortho != 0u);
    // Screen y runs down, view y up.
    let s_view = vec3<f32>(sl.dir.x, -sl.dir.y, 0.0);
    let axis = normalize(s_view - sl.v * dot(s_view, sl.v));
    let plane = cross(sl.v, axis);
    let np = n - plane * dot(n, plane);
    let np_len = length(np);
    sl.gamma = clamp(atan2(dot(np, axis), dot(np, sl.v)), -0.5 * SLICE_PI, 0.5 * SLICE_PI);
    sl.sin_gamma = sin(sl.gamma);
    sl.cos_gamma = cos(sl.gamma);
    // W(theta) = -F(theta) + F(gamma - pi/2) below 0 and F(theta) + F(gamma - pi/2) - 2 F(0)
    // above, with F(gamma -+ pi/2) = cos(gamma) / 4 + (gamma -+ pi/2) sin(gamma) / 2 and
    // F(0) = -cos(gamma) / 4; so W_total = W(gamma + pi/2) = cos(gamma) + gamma sin(gamma).
    sl.w_neg = 0.25 * sl.cos_gamma + 0.5 * (sl.gamma - 0.5 * SLICE_PI) * sl.sin_gamma;
    sl.w_pos = sl.w_neg + 0.5 * sl.cos_gamma;
    sl.total = sl.cos_gamma + sl.gamma * sl.sin_gamma;
    sl.weight = select(0.0, np_len * sl.total, np_len > 1e-6);
    sl.offset = noise.z;
    return sl;
}

// The weight W (from the arc's start) of direction d from a tap on the slice's `side` (+-1): d
// turned about V into the slice, on that side (its angle theta from V kept, as a tap just off the
// slice's line should count; a projection could carry a point below the tangent plane into the
// hemisphere). 0 before the arc, W_total past it. With c = cos theta and s = sin theta,
// cos(2 theta - gamma) = (2c^2 - 1) cos gamma + 2 s c sin gamma: one acos per direction.
fn weight_in(sl: Slice, d: vec3<f32>, side: f32) -> f32 {
    let c = clamp(dot(d, sl.v) / max(length(d), 1e-30), -1.0, 1.0);
    let theta = side * acos(c);
    if theta <= sl.gamma - 0.5 * SLICE_PI {
        return 0.0;
    }
    if theta >= sl.gamma + 0.5 * SLICE_PI {
        return sl.total;
    }
    let s = side * sqrt(max(1.0 - c * c, 0.0));
    let f = -0.25 * ((2.0 * c * c - 1.0) * sl.cos_gamma + 2.0 * s * c * sl.sin_gamma) + 0.5 * theta * sl.sin_gamma;
    return select(sl.w_pos + f, sl.w_neg - f, theta <= 0.0);
}

// The sectors whose centres lie in the arc between the directions of weights w0 and w1.
fn sector_bits(sl: Slice, w0: f32, w1: f32) -> u32 {
    let scale = f32(SECTORS) / sl.total;
    let first = i32(ceil(min(w0, w1) * scale - sl.offset));
    let last = min(i32(floor(max(w0, w1) * scale - sl.offset)), i32(SECTORS) - 1);
    let a = max(first, 0);
    if last < a {
        return 0u;
    }
    let count = u32(last - a + 1);
    let ones = select((1u << count) - 1u, 0xffffffffu, count >= 32u);
    return ones << u32(a);
}

// Distance from c to the segment from y to back (a ray on from y when `endless`).
fn segment_distance(c: vec3<f32>, y: vec3<f32>, back: vec3<f32>, endless: bool) -> f32 {
    let d = back - y;
    let dd = dot(d, d);
    var t = 0.0;
    if dd > 0.0 {
        t = max(dot(c - y, d) / dd, 0.0);
        if !endless {
            t = min(t, 1.0);
        }
    }
    return length(y + d * t - c);
}

// Where the solids of a step's two layers end (view depth; 0: without end). A thickness of 0
// makes every surface solid without end (a height field); otherwise layer 0 reaches `thickness`
// behind itself but no deeper than layer 1's surface, and layer 1 reaches `thickness` behind
// itself but no deeper than the gap in front of it (z1 - z0): what lies close behind layer 0
// is as fine as that gap (the next fin of a row of fins). A solid as deep as the thickness
// there closed gaps that are open: the Cornell box's obscurance RMSE 0.0402 -> 0.0368, the
// engine's 0.0570 -> 0.0532 (320x240; README, *The second layer's solid*).
fn solid_backs(z0: f32, z1: f32, thickness: f32) -> vec2<f32> {
    if thickness > 0.0 {
        var back0 = z0 + thickness;
        if z1 > z0 {
            back0 = min(back0, z1);
        }
        return vec2<f32>(back0, z1 + min(thickness, max(z1 - z0, 0.0)));
    }
    return vec2<f32>(select(0.0, z1, z1 > z0), 0.0);
}

// The sectors that the solid of a point at view depth z (pixel centre `at`, on the slice's side
// `side` = +-1) hides from c: none unless the solid comes within `radius` of c and the point,
// lowered by `lower` along the normal n, lies above c's tangent plane (its solid runs away from
// the camera, further below). `back`: the depth its solid ends at, 0 for without end (towards
// theta = +-pi on its side: the far end of its view ray, seen from c, lies off c's own ray on
// the tap's side). `front2`: the squared distance from c to the point itself, not lowered (the
// lowering decides which directions the solid hides, not how far the surface is: with the
// lowered point's distance a point above the tangent plane came nearer by up to `lower`).
fn solid_sectors(sl: Slice, c: vec3<f32>, n: vec3<f32>, at: vec2<f32>, side: f32, z: f32, back: f32, lower: f32, radius: f32, front2: ptr<function, f32>) -> u32 {
    let down = n * lower;
    let point = view_position(frame, at, z);
    let y = point - down;
    let endless = !(back > z);
    let far = view_position(frame, at, select(back, 2.0 * z, endless)) - down;
    let nearest = segment_distance(c, y, far, endless);
    *front2 = dot(point - c, point - c);
    if !(nearest < radius) || !(dot(y - c, n) > 0.0) {
        return 0u;
    }
    let w0 = weight_in(sl, y - c, side);
    // Without end: towards theta = +-pi, past the arc's end on the tap's side.
    var w1 = select(0.0, sl.total, side > 0.0);
    if !endless {
        w1 = weight_in(sl, far - c, side);
    }
    return sector_bits(sl, w0, w1);
}
