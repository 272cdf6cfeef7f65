//! Which passes a frame runs: only those the scene and the settings call for.
//!
//! A [`PassId`] names one pass; its [`name`](PassId::name) is the only spelling of a pass name
//! (`--timings`, `--plan`, the sweep's columns and the tests all use it). A [`Plan`] is the
//! ordered list of passes one frame records, computed from a scene's [`SceneInfo`] and the
//! [`Settings`], with the reason for each effect it leaves out. The renderer walks it: a pass
//! not in the plan issues no GPU work and has no timing.

use std::borrow::Cow;
use std::fmt;

use crate::scene::{Camera, Projection, SceneInfo};
use crate::settings::{Layer1Variant, Settings};

/// One pass of a frame.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum PassId {
    /// Empties the visibility buffers.
    RasterClear,
    /// Rasterizes layer 0.
    RasterLayer0,
    /// Rasterizes layer 1 against this frame's layer 0 (the two-pass variant, and the first
    /// frame of the one-pass variants).
    RasterLayer1,
    /// Rasterizes both layers in one pass against the previous frame's layer 0.
    RasterLayers,
    /// Rasterizes layer 0 for the next frame's layer-1 test (`Predict`: from the predicted
    /// camera; `Delay`: from the camera the next frame shows).
    RasterNext,
    /// Visibility buffers to G-buffer attributes.
    Resolve,
    /// The depth pyramid of each layer obscurance reads.
    Pyramid,
    /// Ambient obscurance.
    Ao,
    /// The temporal filter of the obscurance ([`AoSettings::alpha`](crate::AoSettings::alpha)).
    AoTemporal,
    /// The bilateral blur of the obscurance.
    AoBlur,
    /// The shadow map of one light.
    Shadow {
        /// Index of the light in the scene's lights.
        light: usize,
        /// The light's name.
        name: String,
    },
    /// Direct light (with the shadow maps) of each layer the later passes read.
    Direct,
    /// Outgoing radiance of both layers and the radiosity gather.
    Radiosity,
    /// The light of the surfaces neither layer holds, from the lights' reflective shadow maps,
    /// added to the gather ([`RadiositySettings::offscreen`](crate::RadiositySettings::offscreen)).
    RadiosityOffscreen,
    /// The radiosity gather at layer 1's points, for the next frame's bounce
    /// ([`RadiositySettings::layer1_samples`](crate::RadiositySettings::layer1_samples)).
    RadiosityLayer1,
    /// The temporal filter of the gathered irradiance.
    RadiosityTemporal,
    /// The bilateral blur of the filtered irradiance.
    RadiosityBlur,
    /// Screen-space reflections.
    Reflections,
    /// The transparency peels: each the next blended surface in front of layer 0, resolved,
    /// lit and accumulated.
    TransparencyPeel,
    /// `DIRECT + AV * AMBIENT + RADIOSITY + REFLECTIONS` into the HDR image.
    Composite,
    /// The peeled blended surfaces over the composite.
    TransparencyComposite,
    /// Depth of field: the composite seen through the camera's lens.
    Dof,
    /// Motion blur: the image over the time the shutter is open.
    MotionBlur,
}

/// The part of the renderer that records a pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StageId {
    Raster,
    Resolve,
    Ao,
    Shadows,
    Direct,
    Radiosity,
    Reflections,
    Transparency,
    Composite,
    Dof,
    MotionBlur,
}

impl PassId {
    /// Every pass but the per-light shadow passes, in frame order.
    pub const FIXED: [PassId; 22] = [
        PassId::RasterClear,
        PassId::RasterLayer0,
        PassId::RasterLayer1,
        PassId::RasterLayers,
        PassId::RasterNext,
        PassId::Resolve,
        PassId::Pyramid,
        PassId::Ao,
        PassId::AoTemporal,
        PassId::AoBlur,
        PassId::Direct,
        PassId::Radiosity,
        PassId::RadiosityOffscreen,
        PassId::RadiosityLayer1,
        PassId::RadiosityTemporal,
        PassId::RadiosityBlur,
        PassId::Reflections,
        PassId::TransparencyPeel,
        PassId::Composite,
        PassId::TransparencyComposite,
        PassId::Dof,
        PassId::MotionBlur,
    ];

    /// The pass's name: `raster.layer0`, `ao.blur`, `shadow.<light name>`, ...
    pub fn name(&self) -> Cow<'static, str> {
        Cow::Borrowed(match self {
            PassId::RasterClear => "raster.clear",
            PassId::RasterLayer0 => "raster.layer0",
            PassId::RasterLayer1 => "raster.layer1",
            PassId::RasterLayers => "raster.layers",
            PassId::RasterNext => "raster.next",
            PassId::Resolve => "resolve",
            PassId::Pyramid => "pyramid",
            PassId::Ao => "ao",
            PassId::AoTemporal => "ao.temporal",
            PassId::AoBlur => "ao.blur",
            PassId::Shadow { name, .. } => return Cow::Owned(format!("shadow.{name}")),
            PassId::Direct => "direct",
            PassId::Radiosity => "radiosity",
            PassId::RadiosityOffscreen => "radiosity.offscreen",
            PassId::RadiosityLayer1 => "radiosity.layer1",
            PassId::RadiosityTemporal => "radiosity.temporal",
            PassId::RadiosityBlur => "radiosity.blur",
            PassId::Reflections => "reflections",
            PassId::Composite => "composite",
            PassId::TransparencyPeel => "transparency.peel",
            PassId::TransparencyComposite => "transparency.composite",
            PassId::Dof => "dof",
            PassId::MotionBlur => "motion_blur",
        })
    }

    /// The effect whose cost the pass is (`None`: the G-buffer and the composite, which every
    /// frame pays).
    pub fn effect(&self) -> Option<Effect> {
        match self {
            PassId::Pyramid | PassId::Ao | PassId::AoTemporal | PassId::AoBlur => Some(Effect::Ao),
            PassId::Shadow { .. } => Some(Effect::Shadows),
            PassId::Direct => Some(Effect::Direct),
            PassId::Radiosity
            | PassId::RadiosityOffscreen
            | PassId::RadiosityLayer1
            | PassId::RadiosityTemporal
            | PassId::RadiosityBlur => Some(Effect::Radiosity),
            PassId::Reflections => Some(Effect::Reflections),
            PassId::TransparencyPeel | PassId::TransparencyComposite => Some(Effect::Transparency),
            PassId::Dof => Some(Effect::Dof),
            PassId::MotionBlur => Some(Effect::MotionBlur),
            _ => None,
        }
    }

    /// The effect of the pass named `name` (as [`PassId::name`] spells it), if any.
    pub fn effect_of(name: &str) -> Option<Effect> {
        if name.starts_with("shadow.") {
            return Some(Effect::Shadows);
        }
        PassId::FIXED.iter().find(|p| p.name() == name).and_then(PassId::effect)
    }

    pub(crate) fn stage(&self) -> StageId {
        match self {
            PassId::RasterClear
            | PassId::RasterLayer0
            | PassId::RasterLayer1
            | PassId::RasterLayers
            | PassId::RasterNext => StageId::Raster,
            PassId::Resolve => StageId::Resolve,
            PassId::Pyramid | PassId::Ao | PassId::AoTemporal | PassId::AoBlur => StageId::Ao,
            PassId::Shadow { .. } => StageId::Shadows,
            PassId::Direct => StageId::Direct,
            PassId::Radiosity
            | PassId::RadiosityOffscreen
            | PassId::RadiosityLayer1
            | PassId::RadiosityTemporal
            | PassId::RadiosityBlur => StageId::Radiosity,
            PassId::Reflections => StageId::Reflections,
            PassId::Composite => StageId::Composite,
            PassId::TransparencyPeel | PassId::TransparencyComposite => StageId::Transparency,
            PassId::Dof => StageId::Dof,
            PassId::MotionBlur => StageId::MotionBlur,
        }
    }

    /// Whether the pass reads the composite's image and writes another (the transparency's
    /// composite, depth of field, motion blur: they run after it, in plan order, the last
    /// writing the HDR image).
    pub fn is_post(&self) -> bool {
        matches!(self, PassId::TransparencyComposite | PassId::Dof | PassId::MotionBlur)
    }

    /// Whether the pass draws or resolves the G-buffer (left out when the caller provides one).
    pub fn is_gbuffer(&self) -> bool {
        matches!(self.stage(), StageId::Raster | StageId::Resolve)
    }

    /// Whether the pass writes the same result on a still frame as on the frame before: it
    /// reads nothing that changes from frame to frame but the camera, the scene and the shadow
    /// maps (the G-buffer, the depth pyramid, the obscurance, the direct light; not the
    /// radiosity, which gathers anew every frame until its mean is kept, nor the reflections,
    /// which read it). A still frame keeps these passes' results ([`Plan::reused`]).
    pub fn same_when_still(&self) -> bool {
        self.is_gbuffer() || matches!(self.effect(), Some(Effect::Ao | Effect::Direct))
    }
}

impl fmt::Display for PassId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

/// The effects a frame can run, each switched by [`Effects`](crate::Effects) and the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Effect {
    /// Ambient obscurance (needs an ambient term).
    Ao,
    /// Direct light (needs a light).
    Direct,
    /// Shadow maps (need direct light and a light that casts shadows).
    Shadows,
    /// Screen-space radiosity (needs a light or an emissive material).
    Radiosity,
    /// Screen-space reflections (need a reflective material).
    Reflections,
    /// Depth of field (needs a camera lens with an aperture).
    Dof,
    /// Motion blur (needs an open shutter and a camera that moved since the last frame).
    MotionBlur,
    /// Transparency (needs a blended material).
    Transparency,
}

impl Effect {
    /// Every effect.
    pub const ALL: [Effect; 8] = [
        Effect::Ao,
        Effect::Direct,
        Effect::Shadows,
        Effect::Radiosity,
        Effect::Reflections,
        Effect::Dof,
        Effect::MotionBlur,
        Effect::Transparency,
    ];

    /// The effect's name, as `--effects` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Effect::Ao => "ao",
            Effect::Direct => "direct",
            Effect::Shadows => "shadows",
            Effect::Radiosity => "radiosity",
            Effect::Reflections => "reflections",
            Effect::Dof => "dof",
            Effect::MotionBlur => "motion_blur",
            Effect::Transparency => "transparency",
        }
    }
}

/// Why an effect does not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// Switched off in the settings.
    Disabled,
    /// The scene does not call for it (no ambient term, no light...).
    NotNeeded,
    /// Its radius covers less than a pixel even where the scene comes nearest the camera: its
    /// taps could not leave the pixel they start from, so it would change nothing.
    UnderAPixel,
    /// Neither the camera nor the geometry moved since the last frame (or there is none):
    /// nothing moved while the shutter was open.
    Still,
}

/// The passes of one frame, in order, and why each effect left out is left out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    /// G-buffer layers rasterized (layer 1 only when an effect reads it).
    pub layers: u32,
    /// Obscurance reads both layers.
    pub ao_two_layers: bool,
    /// The passes, in the order they are recorded (steady state: a one-pass layer-1 variant
    /// rasterizes both layers in `raster.layers` once it has a previous frame).
    pub passes: Vec<PassId>,
    /// The effects that do not run, and why.
    pub left_out: Vec<(Effect, Reason)>,
    /// Passes this frame does not record because an earlier frame wrote what they would write,
    /// and it is still in place: their results are read as if they had run, and their effects
    /// run.
    /// - Shadow passes whose maps an earlier frame drew, when nothing they depend on changed
    ///   since (the light, the scene's buffers, the shadow settings; see
    ///   [`Renderer::geometry_changed`](crate::Renderer::geometry_changed)).
    /// - On a still frame, the passes [`PassId::same_when_still`] names (the G-buffer, the depth
    ///   pyramid, the obscurance and the direct light): a frame is still when its frame
    ///   constants (the camera, the last frame's camera, the image) are the last frame's, the
    ///   scene and its buffers and the passes are the same, no shadow map or transparency peel
    ///   is drawn, and the renderer drew the last frame's G-buffer itself. So a view that stops
    ///   moving keeps them from its second still frame on (the first still frame's G-buffer is
    ///   the first with no motion), while the radiosity goes on gathering its next bounces.
    /// - On a still frame past the radiosity's settled mean of
    ///   [`RadiositySettings::kept_after`](crate::RadiositySettings::kept_after) frames, the
    ///   radiosity's passes; and the reflections on a still frame that runs neither the
    ///   obscurance nor the radiosity.
    pub reused: Vec<PassId>,
}

/// The most pixels a world-space `length` spans in an image `height` pixels tall seen through
/// `camera`, over a scene within `bounds`: at the scene's nearest point (no nearer than the near
/// plane) for a perspective camera, anywhere for an orthographic one; infinite when the bounds
/// are unknown or the eye is inside them.
pub fn pixels_spanned(
    camera: &Camera,
    height: u32,
    bounds: Option<(glam::Vec3, glam::Vec3)>,
    length: f32,
) -> f32 {
    let distance = match (camera.projection, bounds) {
        (Projection::Orthographic { .. }, _) => 1.0,
        (Projection::Perspective { near, .. }, Some((lo, hi))) => {
            let outside = (lo - camera.eye).max(camera.eye - hi).max(glam::Vec3::ZERO).length();
            outside.max(near)
        }
        (Projection::Perspective { .. }, None) => return f32::INFINITY,
    };
    let pixels = camera.pixels_of(length, distance, height);
    if pixels.is_nan() { f32::INFINITY } else { pixels }
}

impl Plan {
    /// The plan for a scene with `info` under `settings`, whatever the camera (an effect whose
    /// radius is under a pixel still runs: see [`for_view`](Plan::for_view); depth of field,
    /// which needs a camera lens, does not).
    pub fn new(info: &SceneInfo, settings: &Settings) -> Plan {
        Plan::build(info, settings, None)
    }

    /// The plan for a scene with `info` under `settings` seen through `camera`: as
    /// [`new`](Plan::new), and the obscurance and the radiosity are left out
    /// ([`Reason::UnderAPixel`]) when their radius spans less than a pixel even at the scene's
    /// nearest point ([`pixels_spanned`]).
    pub fn for_view(info: &SceneInfo, settings: &Settings, camera: &Camera) -> Plan {
        Plan::build(info, settings, Some(camera))
    }

    fn build(info: &SceneInfo, settings: &Settings, camera: Option<&Camera>) -> Plan {
        let e = &settings.effects;
        let mut left_out = Vec::new();
        let covers = |radius: f32| {
            camera.is_none_or(|c| pixels_spanned(c, settings.height, info.bounds, radius) >= 1.0)
        };
        let mut decide = |effect: Effect, enabled: bool, needed: bool, covers: bool| {
            let reason = match (enabled, needed, covers) {
                (false, _, _) => Some(Reason::Disabled),
                (true, false, _) => Some(Reason::NotNeeded),
                (true, true, false) => Some(Reason::UnderAPixel),
                (true, true, true) => None,
            };
            if let Some(r) = reason {
                left_out.push((effect, r));
            }
            reason.is_none()
        };
        let ao = decide(
            Effect::Ao,
            settings.ao.enabled && e.ao,
            info.ambient.max_element() > 0.0,
            covers(settings.ao.radius),
        );
        let direct = decide(Effect::Direct, e.direct, !info.lights.is_empty(), true);
        let shadow_lights: Vec<PassId> = info
            .lights
            .iter()
            .enumerate()
            .filter(|(_, l)| l.casts_shadows)
            .map(|(light, l)| PassId::Shadow { light, name: l.name.clone() })
            .collect();
        let shadows = decide(
            Effect::Shadows,
            e.shadows && settings.shadows.enabled,
            direct && !shadow_lights.is_empty(),
            true,
        );
        let radiosity = decide(
            Effect::Radiosity,
            settings.radiosity.enabled && e.radiosity,
            !info.lights.is_empty() || info.emissive,
            covers(settings.radiosity.radius),
        );
        let reflections = decide(
            Effect::Reflections,
            settings.reflections.enabled && e.reflections,
            info.reflective,
            true,
        );
        let dof = decide(
            Effect::Dof,
            settings.dof.enabled && e.dof,
            camera.is_some_and(|c| c.lens.blurs()),
            true,
        );
        // Whether the camera moved is the renderer's to say (it keeps the last frame's camera):
        // see `Plan::without_motion`.
        let motion_blur = decide(
            Effect::MotionBlur,
            settings.motion_blur.enabled && e.motion_blur,
            settings.motion_blur.shutter > 0.0,
            true,
        );
        let transparency = decide(
            Effect::Transparency,
            settings.transparency.enabled && e.transparency,
            info.blended,
            true,
        );
        let wants_layer1 = (ao && settings.ao.two_layers)
            || radiosity
            || reflections
            || (dof && settings.dof.two_layers)
            || (motion_blur && settings.motion_blur.two_layers);
        let layers = match settings.layers {
            1 => 1,
            2 => 2,
            _ => 1 + u32::from(wants_layer1),
        };
        let mut passes = vec![PassId::RasterClear];
        if layers == 2 && settings.layer1 != Layer1Variant::TwoPass {
            passes.push(PassId::RasterLayers);
            if matches!(settings.layer1, Layer1Variant::Predict | Layer1Variant::Delay) {
                passes.push(PassId::RasterNext);
            }
        } else {
            passes.push(PassId::RasterLayer0);
            if layers == 2 {
                passes.push(PassId::RasterLayer1);
            }
        }
        passes.push(PassId::Resolve);
        if ao {
            passes.extend([PassId::Pyramid, PassId::Ao]);
            if settings.ao.temporal() {
                passes.push(PassId::AoTemporal);
            }
            if settings.ao.blur_radius > 0 {
                passes.push(PassId::AoBlur);
            }
        }
        if shadows {
            passes.extend(shadow_lights);
        }
        if direct {
            passes.push(PassId::Direct);
        }
        if radiosity {
            passes.push(PassId::Radiosity);
            if shadows && settings.radiosity.offscreen {
                passes.push(PassId::RadiosityOffscreen);
            }
            if layers == 2 && settings.radiosity.layer1_samples > 0 {
                passes.push(PassId::RadiosityLayer1);
            }
            passes.push(PassId::RadiosityTemporal);
            if settings.radiosity.blur_radius > 0 {
                passes.push(PassId::RadiosityBlur);
            }
        }
        if reflections {
            passes.push(PassId::Reflections);
        }
        if transparency {
            passes.push(PassId::TransparencyPeel);
        }
        passes.push(PassId::Composite);
        if transparency {
            passes.push(PassId::TransparencyComposite);
        }
        if dof {
            passes.push(PassId::Dof);
        }
        if motion_blur {
            passes.push(PassId::MotionBlur);
        }
        Plan {
            layers,
            ao_two_layers: layers == 2 && settings.ao.two_layers,
            passes,
            left_out,
            reused: Vec::new(),
        }
    }

    /// This plan for a frame whose camera and geometry have not moved since the last one (or
    /// that has no last one): motion blur has nothing to blur, and is left out
    /// ([`Reason::Still`]).
    pub fn without_motion(mut self) -> Plan {
        if self.runs(Effect::MotionBlur) {
            self.passes.retain(|p| *p != PassId::MotionBlur);
            self.left_out.push((Effect::MotionBlur, Reason::Still));
        }
        self
    }

    /// Whether `effect` runs.
    pub fn runs(&self, effect: Effect) -> bool {
        self.reason(effect).is_none()
    }

    /// Why `effect` does not run (`None`: it runs).
    pub fn reason(&self, effect: Effect) -> Option<Reason> {
        self.left_out.iter().find(|(e, _)| *e == effect).map(|(_, r)| *r)
    }

    /// Whether the plan records `pass`.
    pub fn contains(&self, pass: &PassId) -> bool {
        self.passes.contains(pass)
    }

    /// The lights that get shadow maps, drawn this frame or reused: index and name, in atlas
    /// order.
    pub fn shadow_lights(&self) -> Vec<(usize, &str)> {
        let mut lights: Vec<(usize, &str)> = self
            .passes
            .iter()
            .chain(&self.reused)
            .filter_map(|p| match p {
                PassId::Shadow { light, name } => Some((*light, name.as_str())),
                _ => None,
            })
            .collect();
        lights.sort_by_key(|&(light, _)| light);
        lights
    }

    /// The pass names, in order.
    pub fn names(&self) -> Vec<String> {
        self.passes.iter().map(|p| p.name().into_owned()).collect()
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let why = |e: Effect| match self.reason(e) {
            None => "runs",
            Some(Reason::Disabled) => "off (disabled)",
            Some(Reason::NotNeeded) => "off (the scene does not call for it)",
            Some(Reason::UnderAPixel) => {
                "off (its radius spans less than a pixel where the scene is nearest)"
            }
            Some(Reason::Still) => {
                "off (neither the camera nor the geometry moved since the last frame)"
            }
        };
        writeln!(f, "layers:  {}", self.layers)?;
        writeln!(
            f,
            "ao:      {}{}",
            why(Effect::Ao),
            if self.ao_two_layers { ", two layers" } else { "" }
        )?;
        writeln!(f, "direct:  {}", why(Effect::Direct))?;
        writeln!(
            f,
            "radiosity: {}{}{}",
            why(Effect::Radiosity),
            if self.contains(&PassId::RadiosityLayer1) { ", layer 1 gathers" } else { "" },
            if self.contains(&PassId::RadiosityOffscreen) {
                ", off-screen light from the shadow maps"
            } else {
                ""
            }
        )?;
        writeln!(f, "reflections: {}", why(Effect::Reflections))?;
        writeln!(f, "dof:     {}", why(Effect::Dof))?;
        writeln!(f, "motion blur: {}", why(Effect::MotionBlur))?;
        writeln!(f, "transparency: {}", why(Effect::Transparency))?;
        let shadows: Vec<String> = self
            .shadow_lights()
            .into_iter()
            .map(|(light, name)| {
                let kept = self
                    .reused
                    .iter()
                    .any(|p| matches!(p, PassId::Shadow { light: l, .. } if *l == light));
                if kept { format!("{name} (kept from an earlier frame)") } else { name.to_string() }
            })
            .collect();
        if shadows.is_empty() {
            writeln!(f, "shadows: none")?;
        } else {
            writeln!(f, "shadows: {}", shadows.join(", "))?;
        }
        let still: Vec<String> = self
            .reused
            .iter()
            .filter(|p| p.same_when_still())
            .map(|p| p.name().into_owned())
            .collect();
        if !still.is_empty() {
            writeln!(f, "kept from the last frame (still): {}", still.join(", "))?;
        }
        write!(f, "passes:  {}", self.names().join(", "))
    }
}
