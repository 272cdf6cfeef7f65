//! CPU mirror of `wgsl/shared/frame.wgsl`.

use glam::{Vec2, Vec3, Vec4};

use crate::frame::FrameUniform;

/// As `mat_mul`: `m * v` summed in the WGSL's order.
pub fn mat_mul(m: &[[f32; 4]; 4], v: [f32; 4]) -> Vec4 {
    Vec4::from_array(std::array::from_fn(|c| {
        ((m[0][c] * v[0] + m[1][c] * v[1]) + m[2][c] * v[2]) + m[3][c] * v[3]
    }))
}

/// As `clip_to_pixel`: the pixel coordinate of clip position `c` (`c.w > 0`) on an image of
/// `size` pixels.
pub fn clip_to_pixel(c: Vec4, size: Vec2) -> Vec2 {
    Vec2::new((c.x / c.w * 0.5 + 0.5) * size.x, (0.5 - c.y / c.w * 0.5) * size.y)
}

/// The image size of `f` in pixels, as the kernels' `vec2<f32>(f32(frame.width), ...)`.
pub fn image_size(f: &FrameUniform) -> Vec2 {
    Vec2::new(f.width as f32, f.height as f32)
}

/// As `toward_camera` in `wgsl/shared/frame.wgsl`: the unit world direction from world point
/// `world` towards the camera (its backward axis for an orthographic camera).
pub fn toward_camera(f: &FrameUniform, world: Vec3) -> Vec3 {
    if f.ortho != 0 {
        return Vec3::from_slice(&f.inv_view[2][..3]).normalize();
    }
    (Vec3::from_slice(&f.inv_view[3][..3]) - world).normalize()
}

/// As `pixels_per_unit`: pixels per scene unit at view depth `z` (anywhere for an orthographic
/// camera).
pub fn pixels_per_unit(f: &FrameUniform, z: f32) -> f32 {
    let scale = f.proj[1][1] * f.height as f32 * 0.5;
    if f.ortho != 0 { scale } else { scale / z }
}

/// As `view_position`: the view-space point at view depth `d` through pixel coordinate `px`.
pub fn view_position(f: &FrameUniform, px: Vec2, d: f32) -> Vec3 {
    let ndc = Vec2::new(px.x / f.width as f32 * 2.0 - 1.0, 1.0 - px.y / f.height as f32 * 2.0);
    if f.ortho != 0 {
        return Vec3::new(
            (ndc.x - f.proj[3][0]) / f.proj[0][0],
            (ndc.y - f.proj[3][1]) / f.proj[1][1],
            -d,
        );
    }
    Vec3::new(ndc.x * d / f.proj[0][0], ndc.y * d / f.proj[1][1], -d)
}

/// As `screen_exit`: the parameter t where the line `a + t d` (pixel coordinates) leaves the
/// screen, for t >= 0 and `a` on screen (3.4e38 where `d` is zero).
pub fn screen_exit(f: &FrameUniform, a: Vec2, d: Vec2) -> f32 {
    let exit = |a: f32, d: f32, size: u32| {
        if d != 0.0 { ((if d > 0.0 { size as f32 } else { 0.0 }) - a) / d } else { 3.4e38 }
    };
    exit(a.x, d.x, f.width).min(exit(a.y, d.y, f.height))
}
