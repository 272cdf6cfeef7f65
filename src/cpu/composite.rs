//! CPU reference of `wgsl/composite.wgsl`.

use glam::Vec3;

use crate::gbuffer::GSample;

/// DIRECT + AV * AMBIENT + emission per pixel; the sky where there is no surface.
pub fn composite(
    layer: &[GSample],
    direct: &[Vec3],
    av: Option<&[f32]>,
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
            direct[p] + visibility * ((1.0 - s.metallic) * s.base_color * ambient) + s.emissive
        })
        .collect()
}
