//! What the lighting passes and the plan need to know of a scene besides its geometry: its
//! lights, its ambient (sky) radiance and whether any material reflects.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::{Light, LightKind, Scene};
use crate::{Error, Result};

/// Lights, ambient and material facts of a scene, kept on the CPU beside its
/// [`SceneBuffers`](crate::SceneBuffers). For imported buffers the host fills it in.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneInfo {
    /// Punctual lights.
    pub lights: Vec<Light>,
    /// Ambient (sky) radiance, linear rgb.
    pub ambient: Vec3,
    /// Some material may reflect: a reflectivity above zero, or a metallic-roughness texture
    /// on a metallic factor above zero (its reflectivity is per texel).
    pub reflective: bool,
    /// Some material emits light.
    pub emissive: bool,
    /// Some material is blended ([`AlphaMode::Blend`](super::AlphaMode::Blend); for imported
    /// buffers: some material's flags hold [`MATERIAL_BLEND`](super::upload::MATERIAL_BLEND)).
    /// Blended triangles are left out of the opaque layers, so without this set (and the
    /// transparency passes it calls for) they are not drawn at all.
    pub blended: bool,
    /// Some material is masked ([`AlphaMode::Mask`](super::AlphaMode::Mask); for imported
    /// buffers: some material's flags hold [`MATERIAL_MASK`](super::upload::MATERIAL_MASK)).
    /// Without it the rasterizer is built without the per-fragment alpha test (code that no
    /// fragment runs still costs on some devices), and a masked material with a texture is
    /// drawn whole.
    pub masked: bool,
    /// No material samples a texture (for imported buffers: no material's flags name a texture
    /// slot). The kernels that read textures (the resolve, the alpha test, the transparency's
    /// opacity) are then built without those reads (code that no pixel runs still costs on some
    /// devices: on lavapipe it tripled an untextured scene's resolve). A material that names a
    /// texture in a scene marked textureless is drawn with its factors alone and counted in
    /// [`Diagnostics::untextured_triangles`](crate::Diagnostics).
    pub textureless: bool,
    /// Bounds of the geometry (what directional shadow maps must cover); `None`: unknown, the
    /// directional shadow map then covers a cube of side 100 around the origin.
    pub bounds: Option<(Vec3, Vec3)>,
}

impl SceneInfo {
    /// The facts of `scene`.
    pub fn of(scene: &Scene) -> SceneInfo {
        SceneInfo {
            lights: scene.lights.clone(),
            ambient: scene.ambient,
            reflective: scene.materials.iter().any(|m| {
                m.reflectivity > 0.0 || (m.metallic_roughness_texture.is_some() && m.metallic > 0.0)
            }),
            emissive: scene.materials.iter().any(|m| m.emissive.max_element() > 0.0),
            blended: scene.materials.iter().any(|m| m.alpha_mode == super::AlphaMode::Blend),
            masked: scene
                .materials
                .iter()
                .any(|m| matches!(m.alpha_mode, super::AlphaMode::Mask { .. })),
            textureless: scene
                .materials
                .iter()
                .all(|m| m.texture_slots().iter().all(Option::is_none)),
            bounds: scene.bounds(),
        }
    }

    /// Checks lights and ambient: finite, non-negative, unit directions, cone angles in order.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, m: &str| Err(Error::InvalidScene(format!("light `{name}`: {m}")));
        if !(self.ambient.min_element() >= 0.0 && self.ambient.max_element() <= super::MAX_RADIANCE)
        {
            return Err(Error::InvalidScene(format!(
                "ambient {} must be finite, >= 0 and at most {:e}",
                self.ambient,
                super::MAX_RADIANCE
            )));
        }
        for l in &self.lights {
            if !(l.color.is_finite()
                && l.color.min_element() >= 0.0
                && l.intensity.is_finite()
                && l.intensity >= 0.0)
            {
                return bad(&l.name, "colour and intensity must be finite and >= 0");
            }
            let radiance = l.color * l.intensity;
            if !radiance.is_finite() || radiance.max_element() > super::MAX_RADIANCE {
                return bad(
                    &l.name,
                    &format!(
                        "colour x intensity {radiance} exceeds {:e} (or overflows)",
                        super::MAX_RADIANCE
                    ),
                );
            }
            let (position, direction, range) = match l.kind {
                LightKind::Directional { direction } => (Vec3::ZERO, Some(direction), None),
                LightKind::Point { position, range } => (position, None, range),
                LightKind::Spot { position, direction, range, inner_cone, outer_cone } => {
                    if !(0.0 <= inner_cone
                        && inner_cone <= outer_cone
                        && outer_cone <= std::f32::consts::FRAC_PI_2)
                    {
                        return bad(
                            &l.name,
                            "cone angles must satisfy 0 <= inner <= outer <= pi/2",
                        );
                    }
                    (position, Some(direction), range)
                }
            };
            if !position.is_finite() {
                return bad(&l.name, "position is not finite");
            }
            if direction.is_some_and(|d| !(d.is_finite() && d.length_squared() > 0.0)) {
                return bad(&l.name, "direction must be finite and non-zero");
            }
            if range.is_some_and(|r| !(r.is_finite() && r > 0.0)) {
                return bad(&l.name, "range must be finite and > 0");
            }
        }
        Ok(())
    }
}

/// Light kinds in [`GpuLight::kind`].
pub const LIGHT_DIRECTIONAL: u32 = 0;
/// A point light.
pub const LIGHT_POINT: u32 = 1;
/// A spot light.
pub const LIGHT_SPOT: u32 = 2;

/// A light as the kernels read it. Mirrors `struct Light` in `wgsl/shared/light.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuLight {
    /// Position (point, spot).
    pub position: [f32; 3],
    /// [`LIGHT_DIRECTIONAL`], [`LIGHT_POINT`] or [`LIGHT_SPOT`].
    pub kind: u32,
    /// Unit direction the light travels (directional, spot).
    pub direction: [f32; 3],
    /// Range (0: infinite).
    pub range: f32,
    /// Colour times intensity.
    pub radiance: [f32; 3],
    /// Cosine of the inner cone angle (spot).
    pub cos_inner: f32,
    /// Cosine of the outer cone angle (spot).
    pub cos_outer: f32,
    /// Padding.
    pub _pad: [u32; 3],
}

const _: () = assert!(std::mem::size_of::<GpuLight>() == 64);

impl GpuLight {
    /// The GPU form of `light`.
    pub fn new(light: &Light) -> GpuLight {
        let radiance = (light.color * light.intensity).to_array();
        let base = GpuLight { radiance, ..GpuLight::default() };
        match light.kind {
            LightKind::Directional { direction } => GpuLight {
                kind: LIGHT_DIRECTIONAL,
                direction: direction.normalize().to_array(),
                ..base
            },
            LightKind::Point { position, range } => GpuLight {
                kind: LIGHT_POINT,
                position: position.to_array(),
                range: range.unwrap_or(0.0),
                ..base
            },
            LightKind::Spot { position, direction, range, inner_cone, outer_cone } => GpuLight {
                kind: LIGHT_SPOT,
                position: position.to_array(),
                direction: direction.normalize().to_array(),
                range: range.unwrap_or(0.0),
                cos_inner: inner_cone.cos(),
                cos_outer: outer_cone.cos(),
                ..base
            },
        }
    }
}
