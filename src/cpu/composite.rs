//! CPU reference of `wgsl/composite.wgsl` and of the shading it shares with the reflections
//! (`wgsl/shared/shade.wgsl`).

use glam::{Vec3, Vec4};

use crate::gbuffer::GSample;

/// As `shaded`: the radiance the image shows at surface `s`, reflections left out: `direct`,
/// the emission, and the diffuse albedo times `occlusion (E / pi + min(1 - conf, AV) ambient)`,
/// where `irradiance` holds the gather's irradiance E (rgb) and coverage conf (w).
pub fn shaded(s: &GSample, direct: Vec3, visibility: f32, irradiance: Vec4, ambient: Vec3) -> Vec3 {
    let confidence = irradiance.w.clamp(0.0, 1.0);
    let albedo = (1.0 - s.metallic) * s.base_color;
    let reflected = albedo
        * s.occlusion
        * (irradiance.truncate() / std::f32::consts::PI
            + (1.0 - confidence).min(visibility) * ambient);
    direct + reflected + s.emissive
}

/// As `layer1_radiance` (`wgsl/shared/layer1.wgsl`): layer 1's radiance at a pixel, with its
/// direct light, emission and the ambient term only (alpha 1).
pub fn layer1_radiance(s: &GSample, direct: Vec3, ambient: Vec3) -> Vec4 {
    shaded(s, direct, 1.0, Vec4::ZERO, ambient).extend(1.0)
}

/// DIRECT + AV * AMBIENT + RADIOSITY + emission per pixel; the sky where there is no surface.
/// `radiosity` is the irradiance the gather found (rgb) and the share of the hemisphere it
/// covers (w) per pixel.
pub fn composite(
    layer: &[GSample],
    direct: &[Vec3],
    av: Option<&[f32]>,
    radiosity: Option<&[Vec4]>,
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
            let irradiance = radiosity.map_or(Vec4::ZERO, |r| r[p]);
            shaded(s, direct[p], visibility, irradiance, ambient)
        })
        .collect()
}
