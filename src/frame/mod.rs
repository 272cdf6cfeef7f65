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
mod source;
mod uniforms;

pub use pyramid::{Level, MAX_LEVELS, PyramidLayout, mip_size};
pub use shadow::{
    Cluster, LightFaces, OffscreenUniform, RSM_CLUSTER_SIDE, RSM_CLUSTERS_PER_FACE,
    RSM_CLUSTERS_PER_PIXEL, RSM_HELD_MARGIN, RSM_RESOLUTION, ShadowFace, face, face_cameras,
    light_faces,
};
pub use source::{RGB9E5_MAX, SourceTexel, pack_normal, pack_rgb9e5, unpack_rgb9e5};
pub use uniforms::{
    AoUniform, CompositeUniform, DirectUniform, DofUniform, FillParams, LevelUniform, MOTION_TILE,
    MotionBlurUniform, RadiosityUniform, RasterCounters, ReflectionsUniform, TemporalUniform,
    TransparencyUniform,
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
    DofUniform::LAYOUT,
    MotionBlurUniform::LAYOUT,
    TransparencyUniform::LAYOUT,
    LevelUniform::LAYOUT,
    FillParams::LAYOUT,
    ShadowFace::LAYOUT,
    OffscreenUniform::LAYOUT,
    TemporalUniform::LAYOUT,
    Cluster::LAYOUT,
    GpuLight::LAYOUT,
    GpuMaterial::LAYOUT,
    GpuTextureSlot::LAYOUT,
    SourceTexel::LAYOUT,
];

mirrored!(
    GpuMaterial,
    "shared/material.wgsl",
    "Material",
    [base_color, emissive, roughness, metallic, reflectivity, flags, alpha_cutoff, slots]
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
    /// World to clip, made as [`prev_view_proj`](FrameUniform::prev_view_proj) is (so that a
    /// point's motion under a still camera is exactly 0).
    pub view_proj: [[f32; 4]; 4],
    /// The previous frame's world to clip.
    pub prev_view_proj: [[f32; 4]; 4],
    /// Reprojection of a fragment at pixel coordinate (x, y) and view depth d to the previous
    /// frame, with [`reproject_fixed`](FrameUniform::reproject_fixed) (see
    /// [`FrameUniform::reproject`]): columns 0-2 the previous clip position's terms in `d x`,
    /// `d y` and `d`; column 3 (x, y, z) the previous view depth's.
    pub reproject_scaled: [[f32; 4]; 4],
    /// The terms in `x`, `y` and 1, laid out as
    /// [`reproject_scaled`](FrameUniform::reproject_scaled).
    pub reproject_fixed: [[f32; 4]; 4],
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
    /// Bits: [`FRAME_DIAGNOSTICS`], [`FRAME_POSITION_SCREEN_U16`], [`FRAME_POSITION_VIEW_F16`],
    /// [`FRAME_OBJECT_MOTION`].
    pub flags: u32,
}

/// [`FrameUniform::flags`] bit: the raster that reads this frame counts rejected input (the
/// camera's layer 0; not the shadow maps, so each triangle counts once a frame).
pub const FRAME_DIAGNOSTICS: u32 = 1;
/// [`FrameUniform::flags`] bit: the G-buffer holds positions as
/// [`PositionEncoding::ScreenU16`](crate::PositionEncoding::ScreenU16) would.
pub const FRAME_POSITION_SCREEN_U16: u32 = 2;
/// [`FrameUniform::flags`] bit: the G-buffer holds positions as
/// [`PositionEncoding::ViewF16`](crate::PositionEncoding::ViewF16) would.
pub const FRAME_POSITION_VIEW_F16: u32 = 4;

impl crate::settings::PositionEncoding {
    /// Its [`FrameUniform::flags`] bits.
    pub fn frame_flags(self) -> u32 {
        match self {
            Self::ViewDepthF32 => 0,
            Self::ScreenU16 => FRAME_POSITION_SCREEN_U16,
            Self::ViewF16 => FRAME_POSITION_VIEW_F16,
        }
    }
}

/// [`FrameUniform::flags`] bit: the geometry moved since the last frame; the resolve reads each
/// vertex's last position from the previous-positions buffer for the motion vectors (without
/// it the geometry is taken as still, and only the camera moves).
pub const FRAME_OBJECT_MOTION: u32 = 8;

const _: () = assert!(std::mem::size_of::<FrameUniform>() == 8 * 64 + 12 * 4);

mirrored!(
    FrameUniform,
    "shared/frame.wgsl",
    "Frame",
    [
        view,
        proj,
        inv_view,
        prev_view,
        view_proj,
        prev_view_proj,
        reproject_scaled,
        reproject_fixed,
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

/// The reprojection terms of [`FrameUniform::reproject_scaled`] and
/// [`FrameUniform::reproject_fixed`]. A fragment's view position is affine in (x, y) for a given
/// depth d: `v = d (x ua + y ub + uc) + (x va + y vb + vc)` (perspective: the u terms; orthographic:
/// uc = (0, 0, -1) and the v terms), so its previous clip position `T (v, 1)` (T: view to the
/// previous clip space) and previous view depth `-S (v, 1).z` (S: view to the previous view space)
/// are too. Computed in f64 from the two cameras.
fn reprojection(
    current: CameraMatrices,
    previous: CameraMatrices,
    width: u32,
    height: u32,
    ortho: bool,
) -> ([[f32; 4]; 4], [[f32; 4]; 4]) {
    use glam::{DMat4, DVec3, DVec4};
    let inv_view = current.view.as_dmat4().inverse();
    let t = previous.proj.as_dmat4() * previous.view.as_dmat4() * inv_view;
    let s = previous.view.as_dmat4() * inv_view;
    let p = current.proj.as_dmat4();
    let (p00, p11) = (p.x_axis.x, p.y_axis.y);
    let (x, y) = (
        DVec3::new(2.0 / (f64::from(width) * p00), 0.0, 0.0),
        DVec3::new(0.0, -2.0 / (f64::from(height) * p11), 0.0),
    );
    let (u, v) = if ortho {
        let c = DVec3::new((-1.0 - p.w_axis.x) / p00, (1.0 - p.w_axis.y) / p11, 0.0);
        ([DVec3::ZERO, DVec3::ZERO, DVec3::NEG_Z], [x, y, c])
    } else {
        ([x, y, DVec3::new(-1.0 / p00, 1.0 / p11, -1.0)], [DVec3::ZERO; 3])
    };
    let clip = |m: DVec3| t * m.extend(0.0);
    let depth = |m: DVec3| -(s * m.extend(0.0)).z;
    let columns = |terms: [DVec3; 3], last: DVec4, depth_last: f64| {
        let d = DVec4::new(depth(terms[0]), depth(terms[1]), depth(terms[2]) + depth_last, 0.0);
        DMat4::from_cols(clip(terms[0]), clip(terms[1]), clip(terms[2]) + last, d)
            .as_mat4()
            .to_cols_array_2d()
    };
    (columns(u, DVec4::ZERO, 0.0), columns(v, t.w_axis, -s.w_axis.z))
}

impl FrameUniform {
    /// Where a fragment at pixel coordinate `px` (pixel centres at .5) and view depth `d` was in
    /// the previous frame: its clip position and view depth (as `reproject` in
    /// `wgsl/shared/frame.wgsl`).
    pub fn reproject(&self, px: glam::Vec2, d: f32) -> (glam::Vec4, f32) {
        let col = |m: &[[f32; 4]; 4], i: usize| glam::Vec4::from_array(m[i]);
        let (a, b) = (&self.reproject_scaled, &self.reproject_fixed);
        let pc = d * ((col(a, 0) * px.x + col(a, 1) * px.y) + col(a, 2))
            + ((col(b, 0) * px.x + col(b, 1) * px.y) + col(b, 2));
        let (ad, bd) = (col(a, 3), col(b, 3));
        let prev_d =
            d * ((px.x * ad.x + px.y * ad.y) + ad.z) + ((px.x * bd.x + px.y * bd.y) + bd.z);
        (pc, prev_d)
    }

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
        let (reproject_scaled, reproject_fixed) =
            reprojection(current, previous, width, height, camera.is_orthographic());
        FrameUniform {
            view: current.view.to_cols_array_2d(),
            proj: current.proj.to_cols_array_2d(),
            inv_view: current.view.inverse().to_cols_array_2d(),
            prev_view: previous.view.to_cols_array_2d(),
            view_proj: (current.proj * current.view).to_cols_array_2d(),
            prev_view_proj: (previous.proj * previous.view).to_cols_array_2d(),
            reproject_scaled,
            reproject_fixed,
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
