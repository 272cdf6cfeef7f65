//! The faces of shadow maps: each shadow-casting light's depth is drawn by the compute
//! rasterizer (`wgsl/raster.wgsl`, layer 0) from the light and read by `wgsl/direct.wgsl`
//! through `wgsl/shared/shadow.wgsl`. Directional lights get one orthographic face covering the
//! scene's bounds, spot lights one perspective face covering the outer cone, point lights six
//! faces.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::{CameraMatrices, FrameUniform, mirrored};
use crate::scene::{Camera, Light, LightKind, Projection};

/// Mirrors `struct ShadowFace` in `wgsl/shared/shadow.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct ShadowFace {
    /// World to the face's view.
    pub view: [[f32; 4]; 4],
    /// The face's projection.
    pub proj: [[f32; 4]; 4],
    /// World size of a texel at unit depth (perspective) or anywhere (orthographic).
    pub texel: f32,
    /// 1 for an orthographic face.
    pub ortho: u32,
    /// First visibility word of the face in the atlas.
    pub offset: u32,
    /// Side of the face in texels.
    pub resolution: u32,
}

const _: () = assert!(std::mem::size_of::<ShadowFace>() == 144);
mirrored!(ShadowFace, "direct.wgsl", "ShadowFace", [view, proj, texel, ortho, offset, resolution]);

/// The cameras of `light`'s faces, for a scene within `bounds`.
pub fn face_cameras(light: &Light, bounds: (Vec3, Vec3)) -> Vec<Camera> {
    let center = (bounds.0 + bounds.1) * 0.5;
    let radius = ((bounds.1 - bounds.0).length() * 0.5).max(1e-3);
    match light.kind {
        LightKind::Directional { direction } => {
            let d = direction.normalize();
            vec![Camera {
                eye: center - d * (2.0 * radius),
                target: center,
                // A sun straight above or below looks along Y: take Z as up there.
                up: if d.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y },
                projection: Projection::Orthographic {
                    height: 2.0 * radius,
                    near: radius * 1e-3,
                    far: 4.0 * radius,
                },
                lens: Default::default(),
            }]
        }
        LightKind::Spot { position, direction, outer_cone, .. } => vec![Camera {
            eye: position,
            target: position + direction.normalize(),
            up: if direction.normalize().y.abs() > 0.99 { Vec3::Z } else { Vec3::Y },
            projection: Projection::Perspective {
                fov_y_deg: (2.0 * outer_cone).to_degrees().clamp(1.0, 170.0),
                near: radius * 1e-4,
                far: None,
                reverse_z: false,
            },
            lens: Default::default(),
        }],
        LightKind::Point { position, .. } => {
            [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z]
                .into_iter()
                .map(|axis| Camera {
                    eye: position,
                    target: position + axis,
                    up: if axis.y.abs() > 0.5 { Vec3::Z } else { Vec3::Y },
                    projection: Projection::Perspective {
                        fov_y_deg: 90.0,
                        near: radius * 1e-4,
                        far: None,
                        reverse_z: false,
                    },
                    lens: Default::default(),
                })
                .collect()
        }
    }
}

/// The frame uniform the rasterizer draws a face with, and the face as the lookup reads it.
pub fn face(
    camera: &Camera,
    resolution: u32,
    offset: u32,
    counts: (u32, u32, u32),
) -> (FrameUniform, ShadowFace) {
    let m = CameraMatrices::new(camera, resolution, resolution);
    let uniform = FrameUniform::new(camera, m, m, resolution, resolution, 0.0, counts);
    let texel = match camera.projection {
        // 2 tan(fov / 2) / resolution at unit depth.
        Projection::Perspective { .. } => 2.0 / (m.proj.y_axis.y * resolution as f32),
        Projection::Orthographic { height, .. } => height / resolution as f32,
    };
    let face = ShadowFace {
        view: m.view.to_cols_array_2d(),
        proj: m.proj.to_cols_array_2d(),
        texel,
        ortho: camera.is_orthographic() as u32,
        offset,
        resolution,
    };
    (uniform, face)
}

/// The faces of one shadow-casting light.
pub struct LightFaces {
    /// Index of the light in the scene's lights.
    pub light: usize,
    /// Index of its first face among all faces (atlas order).
    pub first: usize,
    /// Per face: the rasterizer's frame uniform and the lookup's face.
    pub faces: Vec<(FrameUniform, ShadowFace)>,
}

/// Every shadow-casting light's faces at `resolution`, in atlas order. `counts` are the scene's
/// (triangles, materials, vertices) for the rasterizer's uniform.
pub fn light_faces(
    info: &crate::scene::SceneInfo,
    resolution: u32,
    counts: (u32, u32, u32),
) -> Vec<LightFaces> {
    let bounds = info.bounds.unwrap_or((Vec3::splat(-50.0), Vec3::splat(50.0)));
    let face_words = resolution * resolution;
    let mut first = 0;
    let mut out = Vec::new();
    for (light, l) in info.lights.iter().enumerate().filter(|(_, l)| l.casts_shadows) {
        let faces: Vec<(FrameUniform, ShadowFace)> = face_cameras(l, bounds)
            .iter()
            .enumerate()
            .map(|(k, camera)| face(camera, resolution, (first + k) as u32 * face_words, counts))
            .collect();
        let n = faces.len();
        out.push(LightFaces { light, first, faces });
        first += n;
    }
    out
}

// The off-screen light's constants (`wgsl/offscreen.wgsl` takes them as pipeline constants;
// `cpu::offscreen` reads them here).

/// Texels a side of a light's reflective shadow map faces.
pub const RSM_RESOLUTION: u32 = 64;
/// Texels a side of a cluster: the cluster kernel's workgroup (`CLUSTER_SIDE`, 8x8, which this
/// names; the kernel's reduction is written for it).
pub const RSM_CLUSTER_SIDE: u32 = 8;
/// Clusters per reflective shadow map face.
pub const RSM_CLUSTERS_PER_FACE: u32 =
    (RSM_RESOLUTION / RSM_CLUSTER_SIDE) * (RSM_RESOLUTION / RSM_CLUSTER_SIDE);
/// The most clusters a pixel sums a frame.
pub const RSM_CLUSTERS_PER_PIXEL: u32 = 32;
/// The strip along the screen's edge, as a share of its height, where a point a layer holds
/// still counts in part in the clusters (the gather's steps rarely land there).
pub const RSM_HELD_MARGIN: f32 = 0.1;

/// Mirrors `struct Offscreen` in `wgsl/offscreen.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct OffscreenUniform {
    /// Reflective shadow map faces of every shadow-casting light.
    pub faces: u32,
    /// Frames since the radiosity's history began (turns which clusters a pixel sums).
    pub turn: u32,
    /// The frame's layers (layer 1's depths are read with 2).
    pub layers: u32,
    pub _pad: u32,
}

mirrored!(OffscreenUniform, "offscreen.wgsl", "Offscreen", [faces, turn, layers]);

impl OffscreenUniform {
    /// The constants for `faces` faces, the radiosity's `turn` and the frame's `layers`.
    pub fn new(faces: u32, turn: u32, layers: u32) -> Self {
        OffscreenUniform { faces, turn, layers, _pad: 0 }
    }
}

/// Mirrors `struct Cluster` in `wgsl/offscreen.wgsl`: the surface patches of one 8x8-texel
/// block of a reflective shadow map face that no layer holds.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Cluster {
    /// Area-weighted mean world point.
    pub position: [f32; 3],
    /// Summed area (0: an empty cluster).
    pub area: f32,
    /// Area-weighted mean normal (length at most 1).
    pub normal: [f32; 3],
    pub _pad0: f32,
    /// Summed reflected radiance times area, `sum L A`.
    pub flux: [f32; 3],
    pub _pad1: f32,
}

mirrored!(Cluster, "offscreen.wgsl", "Cluster", [position, area, normal, flux]);
