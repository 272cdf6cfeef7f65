// The tap pattern shared by the screen-space gathers (ambient obscurance, radiosity): N taps on
// a golden-angle spiral (a low-discrepancy set of directions for any N), tap i at distance
// r_px (i + 0.5) / N, the whole spiral rotated per pixel by an integer hash (exact on every
// device). src/cpu/ao.rs has the same functions.

// The golden angle in turns (1 - 1 / phi).
const GOLDEN_TURNS: f32 = 0.381966011;
const TAU: f32 = 6.28318531;

fn pixel_hash(pixel: vec2<u32>) -> u32 {
    var h = (pixel.x * 0x8da6b343u) ^ (pixel.y * 0xd8163841u);
    h ^= h >> 16u;
    h *= 0x7feb352du;
    h ^= h >> 15u;
    h *= 0x846ca68bu;
    h ^= h >> 16u;
    return h;
}

// How far the view depth of a surface (view-space point v, normal n) runs over `pixels` of the
// screen: that many pixels' footprint at its depth times the surface's slope to the view ray
// (the tangent of their angle, at most 10). src/cpu/spiral.rs has the same.
fn depth_slope_span(f: Frame, v: vec3<f32>, n: vec3<f32>, pixels: f32) -> f32 {
    var ray = vec3<f32>(0.0, 0.0, -1.0);
    if f.ortho == 0u {
        ray = normalize(v);
    }
    let cos_v = clamp(abs(dot(normalize(n), ray)), 0.0995, 1.0);
    let slope = sqrt(1.0 - cos_v * cos_v) / cos_v;
    return pixels * slope / pixels_per_unit(f, max(-v.z, 1e-6));
}

// Distance in pixels of tap i of n.
fn spiral_distance(i: u32, n: u32, r_px: f32) -> f32 {
    return r_px * (f32(i) + 0.5) / f32(n);
}

// The pixel of tap i of n around `pixel` for a spiral of radius r_px.
fn spiral_tap(pixel: vec2<u32>, i: u32, n: u32, r_px: f32) -> vec2<i32> {
    return spiral_tap_turned(pixel, i, n, r_px, 0u);
}

// The same spiral turned by `turn` golden-angle steps (a temporal filter that turns it every
// frame averages different taps).
fn spiral_tap_turned(pixel: vec2<u32>, i: u32, n: u32, r_px: f32, turn: u32) -> vec2<i32> {
    let rotation = f32(((pixel_hash(pixel) >> 20u) + (turn % 4096u) * 1565u) % 4096u) / 4096.0;
    let angle = fract(f32(i) * GOLDEN_TURNS + rotation) * TAU;
    let h = spiral_distance(i, n, r_px);
    return vec2<i32>(floor(vec2<f32>(pixel) + 0.5 + h * vec2<f32>(cos(angle), sin(angle))));
}
