//! What the GPU kernels and their CPU twins share, free of any device: the camera matrices, the
//! per-frame constants every kernel reads, and every `#[repr(C)]` struct mirrored in WGSL.
//!
//! Both `passes/` (which upload these) and `cpu/` (which read them as the shaders do) import
//! this module; it imports neither. Each mirrored struct names its WGSL twin and is listed in
//! [`MIRRORED`], which a test holds against naga's layout of the WGSL struct.

use bytemuck::{Pod, Zeroable};
use glam::Mat4;

use crate::scene::upload::{GpuMaterial, GpuTextureSlot};
use crate::scene::{Camera, GpuLight};

mod pyramid;
mod shadow;
mod uniforms;

pub use pyramid::{Level, MAX_LEVELS, PyramidLayout};
pub use shadow::{LightFaces, ShadowFace, face, face_cameras, light_faces};
pub use uniforms::{
    AoUniform, CompositeUniform, DirectUniform, FillParams, LevelUniform, RadiosityUniform,
    RasterCounters, ReflectionsUniform,
};

/// A `#[repr(C)]` struct's size and field offsets, and the WGSL struct it mirrors.
#[derive(Clone, Copy, Debug)]
pub struct MirrorLayout {
    /// The Rust type.
    pub rust: &'static str,
    /// The WGSL file under `wgsl/` that declares (or includes) the twin.
    pub file: &'static str,
    /// The WGSL struct's name.
    pub wgsl: &'static str,
    /// `size_of` the Rust type.
    pub size: usize,
    /// Field name and byte offset (padding fields left out).
    pub fields: &'static [(&'static str, usize)],
}

/// Implemented by every struct mirrored in WGSL (see [`MIRRORED`]).
pub trait Mirrored: Pod {
    /// Its layout and its twin.
    const LAYOUT: MirrorLayout;
}

/// Declares `$ty` the mirror of the WGSL struct `$wgsl` in `wgsl/$file`, with `$field`s.
macro_rules! mirrored {
    ($ty:ty, $file:expr, $wgsl:expr, [$($field:ident),* $(,)?]) => {
        impl $crate::frame::Mirrored for $ty {
            const LAYOUT: $crate::frame::MirrorLayout = $crate::frame::MirrorLayout {
                rust: stringify!($ty),
                file: $file,
                wgsl: $wgsl,
                size: std::mem::size_of::<$ty>(),
                fields: &[$((stringify!($field), std::mem::offset_of!($ty, $field))),*],
            };
        }
    };
}
pub(crate) use mirrored;

/// Every struct the kernels share with the CPU by layout (the scene's `GpuMaterial` and
/// `GpuLight` are defined with the scene, which they describe, and declared mirrors here).
pub const MIRRORED: &[MirrorLayout] = &[
    FrameUniform::LAYOUT,
    AoUniform::LAYOUT,
    RadiosityUniform::LAYOUT,
    ReflectionsUniform::LAYOUT,
    DirectUniform::LAYOUT,
    CompositeUniform::LAYOUT,
    LevelUniform::LAYOUT,
    FillParams::LAYOUT,
    ShadowFace::LAYOUT,
    GpuLight::LAYOUT,
    GpuMaterial::LAYOUT,
    GpuTextureSlot::LAYOUT,
];

mirrored!(
    GpuMaterial,
    "shared/material.wgsl",
    "Material",
    [base_color, emissive, roughness, metallic, reflectivity, flags, slots]
);
mirrored!(
    GpuTextureSlot,
    "shared/material.wgsl",
    "TextureSlot",
    [offset, width, height, sampler, transform_u, transform_v]
);
mirrored!(
    GpuLight,
    "direct.wgsl",
    "Light",
    [position, kind, direction, range, radiance, cos_inner, cos_outer]
);

/// Pixels beyond each side of the viewport inside which vertices are snapped without clipping.
/// Fixed-point coordinates stay below 2^28 (1/256 pixel), so exact edge functions fit in i64.
pub const GUARD_BAND_PIXELS: f32 = 1_048_576.0;

/// Largest image side (settings refuse larger): keeps fixed-point coordinates within the guard
/// band's bound.
pub use crate::settings::MAX_IMAGE_SIDE;

/// Mirrors `struct Frame` in `wgsl/shared/frame.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct FrameUniform {
    /// World to view.
    pub view: [[f32; 4]; 4],
    /// View to clip.
    pub proj: [[f32; 4]; 4],
    /// View to world.
    pub inv_view: [[f32; 4]; 4],
    /// The previous frame's world to view.
    pub prev_view: [[f32; 4]; 4],
    /// The previous frame's world to clip.
    pub prev_view_proj: [[f32; 4]; 4],
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Near view depth.
    pub near: f32,
    /// Far view depth (`f32::MAX` when infinite).
    pub far: f32,
    /// Guard band half-width in NDC units (x).
    pub guard_x: f32,
    /// Guard band half-height in NDC units (y).
    pub guard_y: f32,
    /// Minimum separation of layer 1 behind layer 0, in scene units.
    pub dz: f32,
    /// 1 for an orthographic camera.
    pub ortho: u32,
    /// Triangles in the scene.
    pub triangle_count: u32,
    /// Materials in the scene.
    pub material_count: u32,
    /// Vertices in the scene.
    pub vertex_count: u32,
    /// Bits: [`FRAME_DIAGNOSTICS`].
    pub flags: u32,
}

/// [`FrameUniform::flags`] bit: the raster that reads this frame counts rejected input (the
/// camera's layer 0; not the shadow maps, so each triangle counts once a frame).
pub const FRAME_DIAGNOSTICS: u32 = 1;

const _: () = assert!(std::mem::size_of::<FrameUniform>() == 5 * 64 + 12 * 4);

mirrored!(
    FrameUniform,
    "shared/frame.wgsl",
    "Frame",
    [
        view,
        proj,
        inv_view,
        prev_view,
        prev_view_proj,
        width,
        height,
        near,
        far,
        guard_x,
        guard_y,
        dz,
        ortho,
        triangle_count,
        material_count,
        vertex_count,
        flags
    ]
);

/// The matrices of one camera at one image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraMatrices {
    /// World to view.
    pub view: Mat4,
    /// View to clip.
    pub proj: Mat4,
}

impl CameraMatrices {
    /// The matrices of `camera` for a `width` x `height` image.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        CameraMatrices {
            view: camera.view(),
            proj: camera.projection(width as f32 / height as f32),
        }
    }
}

impl FrameUniform {
    /// The uniform for `current` after `previous` (the same camera on a first frame).
    pub fn new(
        camera: &Camera,
        current: CameraMatrices,
        previous: CameraMatrices,
        width: u32,
        height: u32,
        dz: f32,
        counts: (u32, u32, u32),
    ) -> Self {
        let (near, far) = camera.depth_range();
        FrameUniform {
            view: current.view.to_cols_array_2d(),
            proj: current.proj.to_cols_array_2d(),
            inv_view: current.view.inverse().to_cols_array_2d(),
            prev_view: previous.view.to_cols_array_2d(),
            prev_view_proj: (previous.proj * previous.view).to_cols_array_2d(),
            width,
            height,
            near,
            far,
            guard_x: 1.0 + 2.0 * GUARD_BAND_PIXELS / width as f32,
            guard_y: 1.0 + 2.0 * GUARD_BAND_PIXELS / height as f32,
            dz,
            ortho: camera.is_orthographic() as u32,
            triangle_count: counts.0,
            material_count: counts.1,
            vertex_count: counts.2,
            flags: 0,
        }
    }
}
