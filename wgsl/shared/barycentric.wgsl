// Where the ray through a pixel centre meets a triangle: perspective-correct barycentrics for
// the resolve and the rasterizer's alpha test (`pixel_ray` / `ray_barycentrics` in
// src/cpu/resolve.rs).

#include "shared/frame.wgsl"

// A ray in view space.
struct PixelRay {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

// The ray through pixel point px (pixels) towards view depth d: from the eye, or straight along
// -z from the image plane for an orthographic camera.
fn pixel_ray(f: Frame, px: vec2<f32>, d: f32) -> PixelRay {
    let target_point = view_position(f, px, d);
    if f.ortho != 0u {
        return PixelRay(vec3<f32>(target_point.xy, 0.0), vec3<f32>(0.0, 0.0, -1.0));
    }
    return PixelRay(vec3<f32>(0.0), target_point);
}

// Moller-Trumbore against the view-space triangle (a, b, c), keeping barycentrics even slightly
// outside (the pixel centre is inside by coverage; rounding may put it a hair outside), then
// clamped; the centroid for a degenerate triangle.
fn ray_barycentrics(ray: PixelRay, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let pv = cross(ray.dir, e2);
    let det = dot(e1, pv);
    var bary = vec3<f32>(1.0 / 3.0);
    if abs(det) > 1e-30 {
        let tv = ray.origin - a;
        let u = dot(tv, pv) / det;
        let v = dot(ray.dir, cross(tv, e1)) / det;
        let raw = clamp(vec3<f32>(1.0 - u - v, u, v), vec3<f32>(0.0), vec3<f32>(1.0));
        let sum = raw.x + raw.y + raw.z;
        if sum > 0.0 {
            bary = raw / sum;
        }
    }
    return bary;
}

// Where the ray origin + t dir meets the triangle (a, b, c) (Moller-Trumbore, either side):
// (t, barycentrics), or t = -1 where it misses (outside the triangle by more than `slack` of its
// barycentric coordinates, parallel to it, or degenerate).
fn ray_triangle(origin: vec3<f32>, dir: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, slack: f32) -> vec4<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let pv = cross(dir, e2);
    let det = dot(e1, pv);
    if !(abs(det) > 1e-30) {
        return vec4<f32>(-1.0, 0.0, 0.0, 0.0);
    }
    let tv = origin - a;
    let qv = cross(tv, e1);
    let u = dot(tv, pv) / det;
    let v = dot(dir, qv) / det;
    let bary = vec3<f32>(1.0 - u - v, u, v);
    if !all(bary >= vec3<f32>(-slack)) {
        return vec4<f32>(-1.0, 0.0, 0.0, 0.0);
    }
    let raw = clamp(bary, vec3<f32>(0.0), vec3<f32>(1.0));
    return vec4<f32>(dot(e2, qv) / det, raw / (raw.x + raw.y + raw.z));
}
