// Per-frame constants shared by every kernel. Mirrors `FrameUniform` in src/frame/mod.rs.
struct Frame {
    view: mat4x4<f32>,
    proj: mat4x4<f32>,
    inv_view: mat4x4<f32>,
    prev_view: mat4x4<f32>,
    // World to clip, this frame's and the previous frame's, each one product made on the CPU the
    // same way, so that a point's motion under a still camera is exactly 0.
    view_proj: mat4x4<f32>,
    prev_view_proj: mat4x4<f32>,
    // A fragment's previous clip position and view depth, affine in (d x, d y, d) and (x, y, 1):
    // see `reproject`.
    reproject_scaled: mat4x4<f32>,
    reproject_fixed: mat4x4<f32>,
    width: u32,
    height: u32,
    near: f32,
    far: f32,
    guard_x: f32,
    guard_y: f32,
    dz: f32,
    ortho: u32,
    triangle_count: u32,
    material_count: u32,
    vertex_count: u32,
    flags: u32,
}

// Frame.flags bit: this raster counts rejected input into the diagnostics words.
const FRAME_DIAGNOSTICS: u32 = 1u;
// Frame.flags bits: how the G-buffer stores positions (`PositionEncoding`; neither: f32 depth).
const FRAME_POSITION_SCREEN_U16: u32 = 2u;
const FRAME_POSITION_VIEW_F16: u32 = 4u;
// Frame.flags bit: the geometry moved since the last frame (the resolve's motion vectors read
// the vertices' last positions).
const FRAME_OBJECT_MOTION: u32 = 8u;

// m * v written out, so every implementation sums in the same order.
fn mat_mul(m: mat4x4<f32>, v: vec4<f32>) -> vec4<f32> {
    return ((m[0] * v.x + m[1] * v.y) + m[2] * v.z) + m[3] * v.w;
}

// View-space position of the surface at view depth `d` seen through pixel coordinate `px`.
fn view_position(f: Frame, px: vec2<f32>, d: f32) -> vec3<f32> {
    let ndc = vec2<f32>(px.x / f32(f.width) * 2.0 - 1.0, 1.0 - px.y / f32(f.height) * 2.0);
    if f.ortho != 0u {
        return vec3<f32>((ndc.x - f.proj[3].x) / f.proj[0].x, (ndc.y - f.proj[3].y) / f.proj[1].y, -d);
    }
    return vec3<f32>(ndc.x * d / f.proj[0].x, ndc.y * d / f.proj[1].y, -d);
}

// Pixels per scene unit at view depth z (anywhere for an orthographic camera): one over the
// distance between neighbouring pixels' rays there. src/cpu/frame.rs has the same.
fn pixels_per_unit(f: Frame, z: f32) -> f32 {
    let scale = f.proj[1].y * f32(f.height) * 0.5;
    return select(scale / z, scale, f.ortho != 0u);
}

// The unit world direction from world point `world` towards the camera (its backward axis for an
// orthographic camera). src/cpu/frame.rs has the same.
fn toward_camera(f: Frame, world: vec3<f32>) -> vec3<f32> {
    if f.ortho != 0u {
        return normalize(f.inv_view[2].xyz);
    }
    return normalize(f.inv_view[3].xyz - world);
}

// The pixel coordinate of clip position c (c.w > 0) on an image of `size` pixels (the camera's
// image, or a shadow map's face): where view_position's ray through it passes.
fn clip_to_pixel(c: vec4<f32>, size: vec2<f32>) -> vec2<f32> {
    return vec2<f32>((c.x / c.w * 0.5 + 0.5) * size.x, (0.5 - c.y / c.w * 0.5) * size.y);
}

// The parameter t where the line a + t d (pixel coordinates) leaves the screen, for t >= 0 and
// a on screen (3.4e38 where d is zero).
fn screen_exit(f: Frame, a: vec2<f32>, d: vec2<f32>) -> f32 {
    let size = vec2<f32>(f32(f.width), f32(f.height));
    let t = (select(vec2<f32>(0.0), size, d > vec2<f32>(0.0)) - a) / d;
    return min(select(3.4e38, t.x, d.x != 0.0), select(3.4e38, t.y, d.y != 0.0));
}

// Where the surface at view depth d seen through pixel coordinate px was in the previous frame:
// its clip position and view depth.
// `FrameUniform::reproject` in src/frame/mod.rs is the same on the CPU.
struct Reprojected {
    clip: vec4<f32>,
    depth: f32,
}

fn reproject(f: Frame, px: vec2<f32>, d: f32) -> Reprojected {
    let a = f.reproject_scaled;
    let b = f.reproject_fixed;
    let clip = d * ((a[0] * px.x + a[1] * px.y) + a[2]) + ((b[0] * px.x + b[1] * px.y) + b[2]);
    let depth = d * ((px.x * a[3].x + px.y * a[3].y) + a[3].z) + ((px.x * b[3].x + px.y * b[3].y) + b[3].z);
    return Reprojected(clip, depth);
}
