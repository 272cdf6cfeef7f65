//! CPU reference of `wgsl/composite.wgsl`.

use glam::Vec3;

use crate::gbuffer::GSample;

/// DIRECT + AV * AMBIENT + RADIOSITY + emission per pixel; the sky where there is no surface.
/// `radiosity` is the irradiance the gather found (rgb) and the share of the hemisphere it
/// covers (w) per pixel.
pub fn composite(
    layer: &[GSample],
    direct: &[Vec3],
    av: Option<&[f32]>,
    radiosity: Option<&[glam::Vec4]>,
    ambient: Vec3,
) -> Vec<Vec3> {
    layer
        .iter()
        .enumerate()
        .map(|(p, s)| {
            if s.depth.is_nan() || s.depth <= 0.0 {
                return ambient;
            }
            let visibility = av.map_or(1.0, |a| a[p]);
            let (e, confidence) =
                radiosity.map_or((Vec3::ZERO, 0.0), |r| (r[p].truncate(), r[p].w.clamp(0.0, 1.0)));
            let albedo = (1.0 - s.metallic) * s.base_color;
            let reflected =
                albedo * (e / std::f32::consts::PI + (1.0 - confidence) * visibility * ambient);
            direct[p] + reflected + s.emissive
        })
        .collect()
}
