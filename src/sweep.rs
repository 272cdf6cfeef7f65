//! What accuracy costs in time: render a grid of configurations of one scene and camera, time
//! every pass with GPU timestamps, and measure each effect's error against ground truth
//! ([`crate::truth`]) and its stability from frame to frame.
//!
//! Each configuration renders a slow camera move that ends at the measured camera: a warm-up
//! frame (pipelines), then [`SETTLE_FRAMES`] frames that let the temporal radiosity gather its
//! bounces, then [`MEASURED_FRAMES`] frames, turning [`MOTION_DEGREES`] about the target per
//! frame. The measured frames give the time of each pass (the median), the temporal instability
//! of each effect (the mean frame-to-frame change at the same surface point,
//! [`metrics::temporal_change`]), and the last one, seen from the measured camera, the errors:
//!
//! - obscurance: AV after the blur against world-space obscurance with the same radius and
//!   falloff;
//! - radiosity: the irradiance the composite takes from it (what the gather found) against diffuse
//!   indirect irradiance path traced with [`TRUTH_BOUNCES`] bounces (the temporal gather adds
//!   one bounce a frame);
//! - reflections (scenes with a reflective material): the reflected radiance against traced
//!   mirror reflections;
//! - the final image: RMSE, MAE and SSIM against the path-traced full image.
//!
//! The estimates are the same on every run, so re-running a sweep gives the same errors.

use std::path::Path;

use glam::Vec3;

use crate::environment::Environment;
use crate::gbuffer::GBufferLayer;
use crate::plan::{Effect, PassId};
use crate::scene::{Camera, Scene};
use crate::settings::{
    AoEstimator, AoSettings, DofSettings, Layer1Variant, MotionBlurSettings, PositionEncoding,
    Precision, RadiositySettings, Settings, TransparencySettings,
};
use crate::truth::metrics::{self, ErrorStats};
use crate::truth::{Shot, Shutter, Tracer, TruthImage};
use crate::{Error, Renderer, Result, SceneBuffers};

/// One configuration of the accuracy knobs.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Knobs {
    /// Obscurance estimator.
    pub ao_estimator: AoEstimator,
    /// Obscurance slices per pixel (`horizon`, `bitmask`).
    pub ao_slices: u32,
    /// Obscurance taps per pixel.
    pub ao_samples: u32,
    /// Weight of the history in the obscurance's temporal filter ([`AoSettings::alpha`]; 0:
    /// none).
    pub ao_alpha: f32,
    /// Weight of the obscurance steps' extrapolation ([`AoSettings::extrapolation`]; 0: none).
    pub ao_extrapolation: f32,
    /// Radius of the obscurance's blur in pixels ([`AoSettings::blur_radius`]; 0: none).
    pub ao_blur_radius: u32,
    /// Radiosity taps per pixel.
    pub radiosity_samples: u32,
    /// Radiosity slices per pixel (`slices` gather; its taps shared among them).
    pub radiosity_slices: u32,
    /// Taps per layer-1 point of the layer-1 gather ([`RadiositySettings::layer1_samples`];
    /// 0: none).
    pub radiosity_layer1_samples: u32,
    /// Weight of the slices gather's extrapolation ([`RadiositySettings::extrapolation`]).
    pub radiosity_extrapolation: f32,
    /// Radiosity slices a moving frame with the temporal history gathers
    /// ([`RadiositySettings::history_slices`]; 0: all).
    pub radiosity_history_slices: u32,
    /// Weight of the history in the radiosity's temporal filter while the view moves
    /// ([`RadiositySettings::alpha`]): the sweep's frames all move.
    pub radiosity_alpha: f32,
    /// G-buffer layers (1: layer 0 only, for both effects; 2: the deep G-buffer).
    pub layers: u32,
    /// G-buffer encoding.
    pub precision: Precision,
    /// How the G-buffer stores positions.
    pub position: PositionEncoding,
    /// Radiosity gather radius, in scene units. (The obscurance radius is not a knob: it
    /// defines the quantity, and the truth is traced with it.)
    pub radiosity_radius: f32,
    /// Obscurance pyramid level offset ([`AoSettings::mip_offset`]).
    pub mip_offset: u32,
    /// Radiosity gather source level offset ([`RadiositySettings::mip_offset`]).
    pub radiosity_mip_offset: u32,
    /// Obscurance resolution divisor ([`AoSettings::downsample`]).
    pub ao_downsample: u32,
    /// Radiosity resolution divisor ([`RadiositySettings::downsample`]).
    pub radiosity_downsample: u32,
    /// The light of the surfaces no layer holds, from the reflective shadow maps
    /// ([`RadiositySettings::offscreen`]).
    pub radiosity_offscreen: bool,
    /// Reflection rays the screen cannot place followed through the shadow maps
    /// ([`ReflectionSettings::shadow_maps`](crate::ReflectionSettings::shadow_maps)).
    pub reflection_shadow_maps: bool,
    /// Rays through the lens per pixel ([`DofSettings::samples`]; the depth of field runs when
    /// the sweep's camera has an aperture).
    pub dof_samples: u32,
    /// Blended surfaces peeled per pixel ([`TransparencySettings::layers`]; the transparency
    /// runs when the scene has a blended material).
    pub transparency_layers: u32,
    /// The share of the time between frames the shutter stays open
    /// ([`MotionBlurSettings::shutter`]; above 0 the motion blur runs, the camera turning
    /// [`MOTION_DEGREES`] a frame, and the image is compared with the truth over that shutter).
    pub shutter: f32,
    /// Minimum separation of layer 1 behind layer 0 (Δz), in scene units.
    pub dz: f32,
    /// How layer 1 is rasterized.
    pub layer1: Layer1Variant,
    /// Resolution scale: the frame is rendered at this fraction of the truth's size and its
    /// outputs are compared at the truth's pixels (nearest).
    pub scale: f32,
    /// The settings the knobs are set in ([`Grid::base`]).
    #[serde(skip)]
    pub base: Settings,
}

impl Knobs {
    /// The renderer settings of this configuration for a `width` x `height` image (the size
    /// [`Knobs::size`] gives): the knobs, set in [`Knobs::base`].
    pub fn settings(&self, width: u32, height: u32) -> Settings {
        let base = &self.base;
        Settings {
            layers: self.layers,
            precision: self.precision,
            position: self.position,
            dz: self.dz,
            layer1: self.layer1,
            ao: AoSettings {
                estimator: self.ao_estimator,
                slices: self.ao_slices,
                samples: self.ao_samples,
                alpha: self.ao_alpha,
                extrapolation: self.ao_extrapolation,
                blur_radius: self.ao_blur_radius,
                two_layers: self.layers == 2,
                mip_offset: self.mip_offset,
                downsample: self.ao_downsample,
                ..base.ao.clone()
            },
            dof: DofSettings { samples: self.dof_samples, ..base.dof.clone() },
            transparency: TransparencySettings {
                layers: self.transparency_layers,
                ..base.transparency.clone()
            },
            motion_blur: MotionBlurSettings { shutter: self.shutter, ..base.motion_blur.clone() },
            radiosity: RadiositySettings {
                samples: self.radiosity_samples,
                slices: self.radiosity_slices,
                layer1_samples: self.radiosity_layer1_samples,
                extrapolation: self.radiosity_extrapolation,
                history_slices: self.radiosity_history_slices,
                alpha: self.radiosity_alpha,
                radius: self.radiosity_radius,
                mip_offset: self.radiosity_mip_offset,
                downsample: self.radiosity_downsample,
                offscreen: self.radiosity_offscreen,
                ..base.radiosity.clone()
            },
            reflections: crate::ReflectionSettings {
                shadow_maps: self.reflection_shadow_maps,
                ..base.reflections.clone()
            },
            timings: true,
            width,
            height,
            ..base.clone()
        }
    }

    /// The size this configuration renders for a truth of `width` x `height`.
    pub fn size(&self, width: u32, height: u32) -> (u32, u32) {
        let side = |n: u32| ((n as f32 * self.scale).round() as u32).max(1);
        (side(width), side(height))
    }

    /// Checks the knobs (and the settings they make) for a truth of `width` x `height`.
    pub fn validate(&self, width: u32, height: u32) -> Result<()> {
        if !(self.scale > 0.0 && self.scale <= 1.0) {
            return Err(Error::setting("scale", format!("{} (must be in (0, 1])", self.scale)));
        }
        if !(1..=2).contains(&self.layers) {
            return Err(Error::setting("layers", format!("{} (1 or 2)", self.layers)));
        }
        if self.layer1 == Layer1Variant::Delay {
            return Err(Error::setting(
                "layer1",
                "delay (its image shows the camera of the frame before, not the one the truth \
                 is traced from; compare its layers with `render --layer1 delay`)",
            ));
        }
        let (w, h) = self.size(width, height);
        self.settings(w, h).validate()
    }
}

/// The grid a sweep renders: every combination of these values.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Obscurance estimators.
    pub ao_estimator: Vec<AoEstimator>,
    /// Obscurance slices.
    pub ao_slices: Vec<u32>,
    /// Obscurance taps.
    pub ao_samples: Vec<u32>,
    /// Obscurance temporal filter weights.
    pub ao_alpha: Vec<f32>,
    /// Obscurance steps' extrapolation weights.
    pub ao_extrapolation: Vec<f32>,
    /// Obscurance blur radii.
    pub ao_blur_radius: Vec<u32>,
    /// Radiosity taps.
    pub radiosity_samples: Vec<u32>,
    /// Radiosity slices.
    pub radiosity_slices: Vec<u32>,
    /// Layer-1 gather taps.
    pub radiosity_layer1_samples: Vec<u32>,
    /// Weights of the radiosity steps' extrapolation.
    pub radiosity_extrapolation: Vec<f32>,
    /// Radiosity slices a moving frame with the history gathers.
    pub radiosity_history_slices: Vec<u32>,
    /// Weights of the history in the radiosity's temporal filter.
    pub radiosity_alpha: Vec<f32>,
    /// Layer counts.
    pub layers: Vec<u32>,
    /// Encodings.
    pub precision: Vec<Precision>,
    /// Position encodings.
    pub position: Vec<PositionEncoding>,
    /// Radiosity gather radii.
    pub radiosity_radius: Vec<f32>,
    /// Obscurance pyramid level offsets.
    pub mip_offset: Vec<u32>,
    /// Radiosity gather source level offsets.
    pub radiosity_mip_offset: Vec<u32>,
    /// Obscurance resolution divisors.
    pub ao_downsample: Vec<u32>,
    /// Radiosity resolution divisors.
    pub radiosity_downsample: Vec<u32>,
    /// The off-screen light on or off.
    pub radiosity_offscreen: Vec<bool>,
    /// Reflection rays followed through the shadow maps or not.
    pub reflection_shadow_maps: Vec<bool>,
    /// Rays through the lens per pixel.
    pub dof_samples: Vec<u32>,
    /// Transparency layers (peels).
    pub transparency_layers: Vec<u32>,
    /// Shutters.
    pub shutter: Vec<f32>,
    /// Layer separations.
    pub dz: Vec<f32>,
    /// Layer-1 variants.
    pub layer1: Vec<Layer1Variant>,
    /// Resolution scales.
    pub scale: Vec<f32>,
    /// The settings every configuration starts from (what no knob sets, and the default of
    /// every knob left out): [`Settings::default`], whose lengths the command line scales to the
    /// scene ([`Settings::scaled`]), as `render` and `truth` do. Its obscurance radius and
    /// falloff define the obscurance the truth traces. The radiosity radius and Δz are knobs:
    /// their lists are their own (the command line defaults them to this base's values).
    pub base: Settings,
}

impl Default for Grid {
    fn default() -> Self {
        let settings = Settings::default();
        Grid {
            ao_estimator: vec![AoEstimator::Sao, AoEstimator::Bitmask],
            ao_slices: vec![settings.ao.slices],
            ao_samples: vec![4, 8, 16, 32, 64],
            ao_alpha: vec![settings.ao.alpha],
            ao_extrapolation: vec![settings.ao.extrapolation],
            ao_blur_radius: vec![settings.ao.blur_radius],
            radiosity_samples: vec![16, 32, 64],
            radiosity_slices: vec![settings.radiosity.slices],
            radiosity_layer1_samples: vec![settings.radiosity.layer1_samples],
            radiosity_extrapolation: vec![settings.radiosity.extrapolation],
            radiosity_history_slices: vec![settings.radiosity.history_slices],
            radiosity_alpha: vec![settings.radiosity.alpha],
            layers: vec![1, 2],
            precision: vec![Precision::Full],
            position: vec![settings.position],
            radiosity_radius: vec![settings.radiosity.radius],
            mip_offset: vec![settings.ao.mip_offset],
            radiosity_mip_offset: vec![settings.radiosity.mip_offset],
            ao_downsample: vec![settings.ao.downsample],
            radiosity_downsample: vec![settings.radiosity.downsample],
            radiosity_offscreen: vec![settings.radiosity.offscreen],
            reflection_shadow_maps: vec![settings.reflections.shadow_maps],
            dof_samples: vec![settings.dof.samples],
            transparency_layers: vec![settings.transparency.layers],
            shutter: vec![settings.motion_blur.shutter],
            dz: vec![settings.dz],
            layer1: vec![settings.layer1],
            scale: vec![1.0],
            base: settings,
        }
    }
}

impl Grid {
    /// Every configuration, in a fixed order (the tap counts vary fastest, the scale slowest).
    pub fn configurations(&self) -> Vec<Knobs> {
        /// Each configuration of `configs` once per value of `values`, set by `set`.
        fn times<T: Copy>(configs: Vec<Knobs>, values: &[T], set: fn(&mut Knobs, T)) -> Vec<Knobs> {
            configs
                .into_iter()
                .flat_map(|k| {
                    values.iter().map(move |&v| {
                        let mut k = k.clone();
                        set(&mut k, v);
                        k
                    })
                })
                .collect()
        }
        let settings = &self.base;
        let base = Knobs {
            ao_estimator: settings.ao.estimator,
            ao_slices: settings.ao.slices,
            ao_samples: settings.ao.samples,
            ao_alpha: settings.ao.alpha,
            ao_extrapolation: settings.ao.extrapolation,
            ao_blur_radius: settings.ao.blur_radius,
            radiosity_samples: settings.radiosity.samples,
            radiosity_slices: settings.radiosity.slices,
            radiosity_layer1_samples: settings.radiosity.layer1_samples,
            radiosity_extrapolation: settings.radiosity.extrapolation,
            radiosity_history_slices: settings.radiosity.history_slices,
            radiosity_alpha: settings.radiosity.alpha,
            layers: 2,
            precision: settings.precision,
            position: settings.position,
            radiosity_radius: settings.radiosity.radius,
            mip_offset: settings.ao.mip_offset,
            radiosity_mip_offset: settings.radiosity.mip_offset,
            ao_downsample: settings.ao.downsample,
            radiosity_downsample: settings.radiosity.downsample,
            radiosity_offscreen: settings.radiosity.offscreen,
            reflection_shadow_maps: settings.reflections.shadow_maps,
            dof_samples: settings.dof.samples,
            transparency_layers: settings.transparency.layers,
            shutter: settings.motion_blur.shutter,
            dz: settings.dz,
            layer1: settings.layer1,
            scale: 1.0,
            base: settings.clone(),
        };
        let k = times(vec![base], &self.scale, |k, v| k.scale = v);
        let k = times(k, &self.precision, |k, v| k.precision = v);
        let k = times(k, &self.position, |k, v| k.position = v);
        let k = times(k, &self.layer1, |k, v| k.layer1 = v);
        let k = times(k, &self.dz, |k, v| k.dz = v);
        let k = times(k, &self.mip_offset, |k, v| k.mip_offset = v);
        let k = times(k, &self.radiosity_mip_offset, |k, v| k.radiosity_mip_offset = v);
        let k = times(k, &self.ao_downsample, |k, v| k.ao_downsample = v);
        let k = times(k, &self.radiosity_downsample, |k, v| k.radiosity_downsample = v);
        let k = times(k, &self.radiosity_offscreen, |k, v| k.radiosity_offscreen = v);
        let k = times(k, &self.reflection_shadow_maps, |k, v| k.reflection_shadow_maps = v);
        let k = times(k, &self.dof_samples, |k, v| k.dof_samples = v);
        let k = times(k, &self.transparency_layers, |k, v| k.transparency_layers = v);
        let k = times(k, &self.shutter, |k, v| k.shutter = v);
        let k = times(k, &self.radiosity_radius, |k, v| k.radiosity_radius = v);
        let k = times(k, &self.radiosity_layer1_samples, |k, v| k.radiosity_layer1_samples = v);
        let k = times(k, &self.radiosity_extrapolation, |k, v| k.radiosity_extrapolation = v);
        let k = times(k, &self.radiosity_history_slices, |k, v| k.radiosity_history_slices = v);
        let k = times(k, &self.radiosity_alpha, |k, v| k.radiosity_alpha = v);
        let k = times(k, &self.layers, |k, v| k.layers = v);
        let k = times(k, &self.ao_estimator, |k, v| k.ao_estimator = v);
        let k = times(k, &self.ao_slices, |k, v| k.ao_slices = v);
        let k = times(k, &self.ao_samples, |k, v| k.ao_samples = v);
        let k = times(k, &self.ao_alpha, |k, v| k.ao_alpha = v);
        let k = times(k, &self.ao_extrapolation, |k, v| k.ao_extrapolation = v);
        let k = times(k, &self.ao_blur_radius, |k, v| k.ao_blur_radius = v);
        let k = times(k, &self.radiosity_slices, |k, v| k.radiosity_slices = v);
        times(k, &self.radiosity_samples, |k, v| k.radiosity_samples = v)
    }
}

/// Bounces of the path-traced indirect light and full image: the temporal gather adds one a
/// frame, and a sweep renders more frames than this before it measures.
pub const TRUTH_BOUNCES: u32 = 10;

/// The ground truth a sweep compares with.
pub struct Truth {
    /// World-space obscurance (the radius and falloff of [`Grid::base`]).
    pub ao: TruthImage,
    /// Diffuse indirect irradiance, [`TRUTH_BOUNCES`] bounces.
    pub indirect: TruthImage,
    /// Mirror reflections, when the scene has a reflective material.
    pub reflections: Option<TruthImage>,
    /// The full image.
    pub full: TruthImage,
    /// The full image over each open shutter of the grid, the camera turning
    /// [`MOTION_DEGREES`] a frame.
    pub open: Vec<(f32, TruthImage)>,
}

impl Truth {
    /// Rows of the images [`Truth::trace`] traces for `scene` and `grid` (what its progress
    /// counts).
    pub fn rows(scene: &Scene, grid: &Grid, height: u32) -> u64 {
        let images = if crate::SceneInfo::of(scene).reflective { 4 } else { 3 };
        u64::from(height) * (images + Self::open_shutters(grid).len() as u64)
    }

    /// The grid's open shutters, each once.
    fn open_shutters(grid: &Grid) -> Vec<f32> {
        let mut open: Vec<f32> = grid.shutter.iter().copied().filter(|s| *s > 0.0).collect();
        open.sort_by(f32::total_cmp);
        open.dedup();
        open
    }

    /// The full image a configuration with `shutter` is compared with.
    pub fn full_for(&self, shutter: f32) -> &TruthImage {
        self.open.iter().find(|(s, _)| *s == shutter).map_or(&self.full, |(_, t)| t)
    }

    /// Traces every truth of `scene` from `camera` at `width` x `height` with `spp` rays per
    /// pixel that `grid` needs (the full image over each of its open shutters besides the
    /// rest); missed rays see `environment` (else the scene's ambient). `progress` is called
    /// once per finished row of each image.
    pub fn trace(
        scene: &Scene,
        camera: &Camera,
        grid: &Grid,
        (size, spp): ((u32, u32), u32),
        environment: Option<&Environment>,
        progress: &(dyn Fn() + Sync),
    ) -> Result<Truth> {
        let tracer = Tracer::new(scene)?;
        let shot = |seed| Shot { camera, size, spp, seed };
        let bounces = TRUTH_BOUNCES;
        let reflections = if crate::SceneInfo::of(scene).reflective {
            Some(tracer.reflections(scene, &shot(3), environment, bounces, progress)?)
        } else {
            None
        };
        let ao = grid.base.ao.clone();
        Ok(Truth {
            ao: tracer.ambient_obscurance(scene, &shot(1), &ao, progress)?,
            indirect: tracer.indirect(scene, &shot(2), bounces, progress)?,
            reflections,
            full: tracer.full(scene, &shot(4), environment, bounces, progress)?,
            open: Self::open_shutters(grid)
                .into_iter()
                .map(|open| {
                    let before = camera.orbited(-MOTION_DEGREES);
                    let shutter = Shutter::camera(&before, open);
                    let image = tracer.full_in_motion(
                        scene,
                        &shot(5),
                        Some(&shutter),
                        environment,
                        bounces,
                        progress,
                    )?;
                    Ok((open, image))
                })
                .collect::<Result<_>>()?,
        })
    }
}

/// Mean frame-to-frame change of each effect over the measured frames.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Instability {
    /// AV.
    pub ao: f32,
    /// Confidence times E.
    pub indirect: f32,
    /// Reflected radiance (0 without reflections).
    pub reflections: f32,
    /// The final HDR image (its view-dependent highlights move with the camera too).
    pub image: f32,
}

/// One measured configuration.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// The knobs.
    pub knobs: Knobs,
    /// GPU milliseconds per pass (stable names), in order.
    pub passes: Vec<(String, f64)>,
    /// Sum of all passes.
    pub total_ms: f64,
    /// Obscurance error (AV after the blur).
    pub ao: ErrorStats,
    /// Radiosity error (the irradiance the composite takes from it: confidence times E).
    pub indirect: ErrorStats,
    /// Reflection error, when the scene reflects.
    pub reflections: Option<ErrorStats>,
    /// Error of the final image.
    pub full: ErrorStats,
    /// SSIM of the final image against the truth (1: identical).
    pub ssim: f32,
    /// Temporal instability per effect.
    pub instability: Instability,
}

impl Row {
    /// Milliseconds of the passes of `effect` ([`PassId::effect`](crate::PassId::effect)).
    pub fn ms_of(&self, effect: Effect) -> f64 {
        self.passes
            .iter()
            .filter(|(n, _)| PassId::effect_of(n) == Some(effect))
            .map(|(_, ms)| ms)
            .sum()
    }
}

/// What one frame produced, read back.
struct Snapshot {
    layer0: GBufferLayer,
    av: Vec<Vec3>,
    indirect: Vec<Vec3>,
    reflections: Option<Vec<Vec3>>,
    hdr: Vec<Vec3>,
}

impl Snapshot {
    fn read(renderer: &Renderer, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Snapshot> {
        let s = renderer.settings();
        let n = (s.width * s.height) as usize;
        let missing = |what: &str| Error::InvalidSetting {
            name: "sweep",
            message: format!("the scene's plan runs no {what}: nothing to measure"),
        };
        let terms = renderer.read_terms(device, queue)?;
        let av = terms.av.ok_or_else(|| missing("obscurance"))?;
        Ok(Snapshot {
            layer0: renderer.read_gbuffer(device, queue, 0)?,
            av: av.iter().take(n).map(|v| Vec3::splat(*v)).collect(),
            indirect: terms.indirect.ok_or_else(|| missing("radiosity"))?,
            reflections: terms.reflections,
            hdr: terms.hdr,
        })
    }
}

/// Frames of the camera move before the measured ones (the temporal radiosity settles).
pub const SETTLE_FRAMES: usize = 10;
/// Frames measured (times, instability); the last one is compared with the truth.
pub const MEASURED_FRAMES: usize = 4;
/// Degrees the camera turns about its target per frame of the move.
pub const MOTION_DEGREES: f32 = 0.25;

/// `values` of a `from` = (w, h) image at the pixels of a `to` image (nearest pixel centre).
fn resample<T: Copy>(values: &[T], from: (u32, u32), to: (u32, u32)) -> Vec<T> {
    if from == to {
        return values.to_vec();
    }
    let pick =
        |i: u32, n: u32, m: u32| (((i as f32 + 0.5) * n as f32 / m as f32) as u32).min(n - 1);
    (0..to.1)
        .flat_map(|y| (0..to.0).map(move |x| (x, y)))
        .map(|(x, y)| values[(pick(y, from.1, to.1) * from.0 + pick(x, from.0, to.0)) as usize])
        .collect()
}

/// Renders and measures one configuration; missed reflection rays see `environment`.
pub fn measure(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &SceneBuffers,
    camera: &Camera,
    truth: &Truth,
    knobs: &Knobs,
    environment: Option<&Environment>,
) -> Result<Row> {
    let full = truth.full_for(knobs.shutter);
    let target = (full.width, full.height);
    let size = knobs.size(target.0, target.1);
    let mut renderer = Renderer::new(device, queue, knobs.settings(size.0, size.1))?;
    renderer.set_environment(device, environment)?;
    let frames = SETTLE_FRAMES + MEASURED_FRAMES;
    let at = |i: usize| camera.orbited(-MOTION_DEGREES * (frames - 1 - i) as f32);
    // A warm-up frame builds the pipelines; the move starts from an empty history.
    renderer.render(device, queue, scene, &at(0))?;
    renderer.reset_history();
    let mut runs: Vec<Vec<crate::gpu::PassTiming>> = Vec::new();
    let mut changes = [0.0f64; 4];
    let mut previous: Option<Snapshot> = None;
    for i in 0..frames {
        // Every frame pays for every pass, as a scene with moving geometry would: a static
        // scene's kept shadow maps would hide what the shadow settings cost.
        renderer.redraw();
        renderer.render(device, queue, scene, &at(i))?;
        if i < SETTLE_FRAMES - 1 {
            continue;
        }
        let now = Snapshot::read(&renderer, device, queue)?;
        if let Some(before) = &previous {
            runs.push(renderer.timings(device)?);
            let change = |a: &[Vec3], b: &[Vec3]| {
                f64::from(metrics::temporal_change(a, b, &before.layer0, &now.layer0).0)
            };
            changes[0] += change(&before.av, &now.av);
            changes[1] += change(&before.indirect, &now.indirect);
            if let (Some(a), Some(b)) = (&before.reflections, &now.reflections) {
                changes[2] += change(a, b);
            }
            changes[3] += change(&before.hdr, &now.hdr);
        }
        previous = Some(now);
    }
    let last = previous.expect("at least one measured frame");
    let timings: Vec<(String, f64)> = runs[0]
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let mut ms: Vec<f64> = runs.iter().filter_map(|r| r.get(i).map(|t| t.ms)).collect();
            ms.sort_by(f64::total_cmp);
            (t.name.clone(), ms[ms.len() / 2])
        })
        .collect();
    let up = |values: &[Vec3]| resample(values, size, target);
    let mask: Vec<bool> =
        resample(&last.layer0.samples, size, target).iter().map(|s| s.depth > 0.0).collect();
    let hdr = up(&last.hdr);
    let seen: Vec<bool> = mask.iter().zip(&full.visible).map(|(a, b)| *a && *b).collect();
    let n = MEASURED_FRAMES as f64;
    let instability = |i: usize| (changes[i] / n) as f32;
    let passes = timings;
    Ok(Row {
        knobs: knobs.clone(),
        total_ms: passes.iter().map(|(_, ms)| ms).sum(),
        passes,
        ao: metrics::compare(&up(&last.av), &mask, &truth.ao),
        indirect: metrics::compare(&up(&last.indirect), &mask, &truth.indirect),
        reflections: match (&last.reflections, &truth.reflections) {
            (Some(r), Some(t)) => Some(metrics::compare(&up(r), &mask, t)),
            _ => None,
        },
        full: metrics::compare(&hdr, &mask, full),
        ssim: metrics::ssim(&hdr, &full.value, &seen, target, 1.0),
        instability: Instability {
            ao: instability(0),
            indirect: instability(1),
            reflections: instability(2),
            image: instability(3),
        },
    })
}

/// Timed frames per configuration (the median of their times is kept).
pub const TIMED_FRAMES: usize = 3;

/// Indices of `points` (ms, error) on the Pareto front (no other point is both faster and more
/// accurate), sorted by time.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        points[a].0.total_cmp(&points[b].0).then(points[a].1.total_cmp(&points[b].1))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// Writes `rows` as CSV: the knobs, every pass's ms (one column per pass name), the total, and
/// per effect its RMSE, MAE, the truth's noise floor and mean and the temporal instability (reflection
/// columns only when the scene reflects); for the final image also its SSIM.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        for (n, _) in &r.passes {
            if !names.contains(&n.as_str()) {
                names.push(n);
            }
        }
    }
    let reflective = rows.iter().any(|r| r.reflections.is_some());
    let mut out = String::from(
        "ao_estimator,ao_slices,ao_samples,ao_alpha,ao_extrapolation,ao_blur_radius,radiosity_samples,radiosity_slices,radiosity_layer1_samples,radiosity_extrapolation,radiosity_history_slices,radiosity_alpha,layers,precision,position,radiosity_radius,mip_offset,radiosity_mip_offset,ao_downsample,radiosity_downsample,radiosity_offscreen,reflection_shadow_maps,dof_samples,transparency_layers,shutter,dz,layer1,scale",
    );
    for n in &names {
        out += &format!(",ms_{n}");
    }
    out += ",total_ms,ao_ms,radiosity_ms";
    if reflective {
        out += ",reflections_ms";
    }
    let effects: &[&str] = if reflective {
        &["ao", "indirect", "reflections", "image"]
    } else {
        &["ao", "indirect", "image"]
    };
    for e in effects {
        out += &format!(
            ",{e}_rmse,{e}_mae,{e}_truth_stderr,{e}_truth_mean,{e}_estimate_mean,{e}_median_rel,{e}_instability"
        );
    }
    out += ",image_ssim\n";
    for r in rows {
        let k = &r.knobs;
        out += &format!(
            "{:?},{},{},{},{},{},{},{},{},{},{},{},{},{:?},{},{},{},{},{},{},{},{},{},{},{},{},{:?},{}",
            k.ao_estimator,
            k.ao_slices,
            k.ao_samples,
            k.ao_alpha,
            k.ao_extrapolation,
            k.ao_blur_radius,
            k.radiosity_samples,
            k.radiosity_slices,
            k.radiosity_layer1_samples,
            k.radiosity_extrapolation,
            k.radiosity_history_slices,
            k.radiosity_alpha,
            k.layers,
            k.precision,
            k.position.name(),
            k.radiosity_radius,
            k.mip_offset,
            k.radiosity_mip_offset,
            k.ao_downsample,
            k.radiosity_downsample,
            k.radiosity_offscreen,
            k.reflection_shadow_maps,
            k.dof_samples,
            k.transparency_layers,
            k.shutter,
            k.dz,
            k.layer1,
            k.scale
        );
        for n in &names {
            let ms = r.passes.iter().find(|(p, _)| p == n).map_or(0.0, |(_, ms)| *ms);
            out += &format!(",{ms:.4}");
        }
        out += &format!(
            ",{:.4},{:.4},{:.4}",
            r.total_ms,
            r.ms_of(Effect::Ao),
            r.ms_of(Effect::Radiosity)
        );
        if reflective {
            out += &format!(",{:.4}", r.ms_of(Effect::Reflections));
        }
        let i = &r.instability;
        let mut stats = vec![(r.ao, i.ao), (r.indirect, i.indirect)];
        if reflective {
            stats.push((r.reflections.unwrap_or_default(), i.reflections));
        }
        stats.push((r.full, i.image));
        for (e, flicker) in stats {
            out += &format!(
                ",{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5}",
                e.rmse,
                e.mae,
                e.truth_stderr,
                e.truth_mean,
                e.estimate_mean,
                e.median_relative,
                flicker
            );
        }
        out += &format!(",{:.4}\n", r.ssim);
    }
    crate::output::write_bytes(path, out.as_bytes())
}

/// The (ms, RMSE) points of one effect, in row order.
fn points(rows: &[Row], ms: impl Fn(&Row) -> f64, error: impl Fn(&Row) -> f32) -> Vec<(f64, f64)> {
    rows.iter().map(|r| (ms(r), f64::from(error(r)))).collect()
}

/// Writes `rows` as a Markdown table (the knobs that vary, each effect's ms and RMSE, the final
/// image's RMSE, SSIM and instability; Pareto-optimal rows per effect marked), headed by what
/// was measured where.
pub fn write_markdown(path: &Path, rows: &[Row], heading: &str) -> Result<()> {
    let ao_front = pareto_front(&points(rows, |r| r.ms_of(Effect::Ao), |r| r.ao.rmse));
    let rad_front =
        pareto_front(&points(rows, |r| r.ms_of(Effect::Radiosity), |r| r.indirect.rmse));
    let image_front = pareto_front(&points(rows, |r| r.total_ms, |r| r.full.rmse));
    // Knob columns: the tap counts and layers always, the others where the grid varies them.
    type Column = (&'static str, fn(&Knobs) -> String);
    let optional: [Column; 25] = [
        ("AO estimator", |k| k.ao_estimator.name().to_string()),
        ("AO slices", |k| k.ao_slices.to_string()),
        ("AO history weight", |k| k.ao_alpha.to_string()),
        ("AO extrapolation", |k| k.ao_extrapolation.to_string()),
        ("AO blur radius", |k| k.ao_blur_radius.to_string()),
        ("radiosity slices", |k| k.radiosity_slices.to_string()),
        ("precision", |k| format!("{:?}", k.precision)),
        ("position", |k| k.position.name().to_string()),
        ("radiosity radius", |k| k.radiosity_radius.to_string()),
        ("layer-1 radiosity taps", |k| k.radiosity_layer1_samples.to_string()),
        ("radiosity extrapolation", |k| k.radiosity_extrapolation.to_string()),
        ("radiosity slices with history", |k| k.radiosity_history_slices.to_string()),
        ("radiosity history weight", |k| k.radiosity_alpha.to_string()),
        ("MIP offset", |k| k.mip_offset.to_string()),
        ("radiosity MIP offset", |k| k.radiosity_mip_offset.to_string()),
        ("AO downsample", |k| k.ao_downsample.to_string()),
        ("radiosity downsample", |k| k.radiosity_downsample.to_string()),
        ("off-screen light", |k| k.radiosity_offscreen.to_string()),
        ("reflections through shadow maps", |k| k.reflection_shadow_maps.to_string()),
        ("lens rays", |k| k.dof_samples.to_string()),
        ("transparency layers", |k| k.transparency_layers.to_string()),
        ("shutter", |k| k.shutter.to_string()),
        ("Δz", |k| k.dz.to_string()),
        ("layer 1", |k| format!("{:?}", k.layer1)),
        ("scale", |k| k.scale.to_string()),
    ];
    let varying: Vec<&Column> = optional
        .iter()
        .filter(|(_, f)| rows.iter().any(|r| f(&r.knobs) != f(&rows[0].knobs)))
        .collect();
    let mut out = format!("{heading}\n\n| AO taps | radiosity taps | layers |");
    for (name, _) in &varying {
        out += &format!(" {name} |");
    }
    out += " AO ms | AO RMSE | radiosity ms | indirect RMSE | frame ms | image RMSE | SSIM | AO instability | indirect instability |\n";
    out += &format!(
        "|---:|---:|---:|{}---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        "---|".repeat(varying.len())
    );
    for (i, r) in rows.iter().enumerate() {
        let k = &r.knobs;
        let mark = |front: &[usize]| if front.contains(&i) { " *" } else { "" };
        out += &format!("| {} | {} | {} |", k.ao_samples, k.radiosity_samples, k.layers);
        for (_, value) in &varying {
            out += &format!(" {} |", value(k));
        }
        out += &format!(
            " {:.2} | {:.4}{} | {:.2} | {:.4}{} | {:.2} | {:.4}{} | {:.3} | {:.5} | {:.5} |\n",
            r.ms_of(Effect::Ao),
            r.ao.rmse,
            mark(&ao_front),
            r.ms_of(Effect::Radiosity),
            r.indirect.rmse,
            mark(&rad_front),
            r.total_ms,
            r.full.rmse,
            mark(&image_front),
            r.ssim,
            r.instability.ao,
            r.instability.indirect
        );
    }
    out += "\n`*`: on the Pareto front of that effect (no configuration is both faster and more accurate); the image's front is over the whole frame's time.\n";
    crate::output::write_bytes(path, out.as_bytes())
}

/// The font of the plots (DejaVu Sans, assets/fonts/, under its own free licence).
static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Draws `pareto.png`: one panel per effect, every configuration's relative error (RMSE over the
/// truth's mean) against the GPU milliseconds of that effect's passes (the final image: of the
/// whole frame), and its Pareto front ringed and joined. Where the grid sweeps the obscurance
/// estimator, the obscurance panel draws each estimator in its own colour with its own front
/// (thin line) and a legend, so that each estimator's error against time can be read apart.
/// Points whose time or error is not finite (a configuration that measured NaN) are left out;
/// a panel without points is drawn empty.
pub fn plot_pareto(path: &Path, rows: &[Row], title: &str) -> Result<()> {
    crate::output::write_replacing(path, |tmp| draw_pareto(tmp, path, rows, title))
}

/// One group of a panel's points: its label, its colour and its (ms, relative error) points.
type Group = (String, plotters::style::RGBColor, Vec<(f64, f64)>);

/// One panel of [`plot_pareto`]: its caption and its points, in groups drawn each in a colour
/// (one unlabelled group where nothing splits them).
struct Panel {
    name: &'static str,
    groups: Vec<Group>,
}

/// Colours of the obscurance panel's groups, in the grid's order of its estimators (the first,
/// the panel's colour where nothing splits it).
const AO_COLOURS: [(u8, u8, u8); 3] = [(31, 119, 180), (255, 127, 14), (148, 103, 189)];

/// Draws [`plot_pareto`]'s picture into `target` (errors name `path`).
fn draw_pareto(target: &Path, path: &Path, rows: &[Row], title: &str) -> Result<()> {
    use plotters::prelude::*;
    let fail =
        |e: &dyn std::fmt::Display| Error::ImageWrite { path: path.into(), message: e.to_string() };
    // Registering twice is harmless; the first registration stays.
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let relative = |e: &ErrorStats| e.rmse / e.truth_mean.max(1e-9);
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let single = |name, colour, points: Vec<(f64, f64)>| Panel {
        name,
        groups: vec![(String::new(), colour, points.into_iter().filter(finite).collect())],
    };
    // The obscurance's points, one group per estimator the grid holds (in the grid's order).
    let mut estimators: Vec<AoEstimator> = Vec::new();
    for r in rows {
        if !estimators.contains(&r.knobs.ao_estimator) {
            estimators.push(r.knobs.ao_estimator);
        }
    }
    let ao_groups = estimators
        .iter()
        .enumerate()
        .map(|(i, &estimator)| {
            let (r, g, b) = AO_COLOURS[i % AO_COLOURS.len()];
            let points = rows
                .iter()
                .filter(|r| r.knobs.ao_estimator == estimator)
                .map(|r| (r.ms_of(Effect::Ao), f64::from(relative(&r.ao))))
                .filter(finite)
                .collect();
            let label =
                if estimators.len() > 1 { estimator.name().to_string() } else { String::new() };
            (label, RGBColor(r, g, b), points)
        })
        .collect();
    let mut panels_data = vec![
        Panel { name: "ambient obscurance", groups: ao_groups },
        single(
            "radiosity (multi-bounce)",
            RGBColor(214, 39, 40),
            points(rows, |r| r.ms_of(Effect::Radiosity), |r| relative(&r.indirect)),
        ),
    ];
    if rows.iter().all(|r| r.reflections.is_some()) {
        panels_data.push(single(
            "reflections",
            RGBColor(44, 160, 44),
            points(
                rows,
                |r| r.ms_of(Effect::Reflections),
                |r| relative(&r.reflections.unwrap_or_default()),
            ),
        ));
    }
    panels_data.push(single(
        "final image (whole frame)",
        RGBColor(90, 90, 90),
        points(rows, |r| r.total_ms, |r| relative(&r.full)),
    ));
    // One panel per effect, each with its own axes: the effects' times and errors differ by
    // orders of magnitude.
    let root = BitMapBackend::new(target, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(|e| fail(&e))?;
    let panels = root.split_evenly((2, 2));
    for (data, panel) in panels_data.iter().zip(&panels) {
        let points: Vec<(f64, f64)> =
            data.groups.iter().flat_map(|(_, _, p)| p.iter().copied()).collect();
        let range = |values: &mut dyn Iterator<Item = f64>| {
            let (lo, hi) = values.fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
            if lo > hi {
                return 0.0..1.0;
            }
            let pad = ((hi - lo) * 0.1).max(hi.abs() * 0.01).max(1e-6);
            (lo - pad)..(hi + pad)
        };
        let x = range(&mut points.iter().map(|p| p.0));
        let y = range(&mut points.iter().map(|p| p.1));
        let mut chart = ChartBuilder::on(panel)
            .caption(data.name, ("sans-serif", 17))
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(x.start.max(0.0)..x.end, y)
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc("GPU ms")
            .y_desc("RMSE / truth mean")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(|e| fail(&e))?;
        let split = data.groups.len() > 1;
        for (label, colour, group) in &data.groups {
            let colour = *colour;
            let drawn = chart
                .draw_series(group.iter().map(|p| Circle::new(*p, 3, colour.mix(0.5).filled())))
                .map_err(|e| fail(&e))?;
            if split {
                drawn
                    .label(label.as_str())
                    .legend(move |(x, y)| Circle::new((x, y), 4, colour.filled()));
                // Each group's own front, thin: its error against its time.
                let front: Vec<(f64, f64)> =
                    pareto_front(group).into_iter().map(|i| group[i]).collect();
                chart
                    .draw_series(LineSeries::new(front, colour.mix(0.8).stroke_width(1)))
                    .map_err(|e| fail(&e))?;
            }
        }
        // The front over every group, ringed and joined (each ring in its group's colour).
        let colour_of = |p: &(f64, f64)| {
            data.groups
                .iter()
                .find(|(_, _, g)| g.contains(p))
                .map_or(RGBColor(0, 0, 0), |(_, c, _)| *c)
        };
        let front: Vec<(f64, f64)> = pareto_front(&points).into_iter().map(|i| points[i]).collect();
        chart
            .draw_series(front.iter().map(|p| Circle::new(*p, 5, colour_of(p).stroke_width(2))))
            .map_err(|e| fail(&e))?;
        // A panel of no rows has no group.
        let line = match data.groups.as_slice() {
            [(_, colour, _)] => *colour,
            _ => RGBColor(40, 40, 40),
        };
        chart.draw_series(LineSeries::new(front, line.stroke_width(2))).map_err(|e| fail(&e))?;
        if split {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK.mix(0.4))
                .label_font(("sans-serif", 12))
                .draw()
                .map_err(|e| fail(&e))?;
        }
    }
    panels
        .last()
        .filter(|_| panels_data.len() < panels.len())
        .map(|p| {
            p.draw_text(
                "ringed and joined: the Pareto front",
                &("sans-serif", 15).into_text_style(p),
                (40, 40),
            )
        })
        .transpose()
        .map_err(|e| fail(&e))?;
    root.present().map_err(|e| fail(&e))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plot of nothing, or of configurations that measured NaN or infinity, is drawn (empty
    /// panels) instead of searching forever for an axis range.
    #[test]
    fn the_plot_draws_empty_and_non_finite_sets() {
        let dir = std::env::temp_dir().join(format!("deep-gbuffer-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let nan = ErrorStats { rmse: f32::NAN, truth_mean: 1.0, ..ErrorStats::default() };
        let row = Row {
            knobs: Grid::default().configurations()[0].clone(),
            passes: vec![("ao".into(), f64::INFINITY), ("radiosity".into(), f64::NAN)],
            total_ms: f64::NAN,
            ao: nan,
            indirect: nan,
            reflections: Some(nan),
            full: nan,
            ssim: f32::NAN,
            instability: Instability::default(),
        };
        // Two estimators, one measured and one not: the obscurance panel splits into groups, one
        // of them empty.
        let fine = ErrorStats { rmse: 0.05, truth_mean: 0.8, ..ErrorStats::default() };
        let mut sao = row.clone();
        sao.knobs.ao_estimator = AoEstimator::Sao;
        sao.passes = vec![("ao".into(), 3.0), ("radiosity".into(), 9.0)];
        (sao.total_ms, sao.ao, sao.indirect, sao.full) = (40.0, fine, fine, fine);
        let mut bitmask = row.clone();
        bitmask.knobs.ao_estimator = AoEstimator::Bitmask;
        for rows in [Vec::new(), vec![row.clone(), row], vec![sao, bitmask]] {
            let path = dir.join("pareto.png");
            plot_pareto(&path, &rows, "nothing to see").unwrap();
            assert!(image::open(&path).is_ok());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_grid_is_every_combination_with_the_taps_varying_fastest() {
        let grid = Grid {
            ao_estimator: vec![AoEstimator::Bitmask],
            ao_samples: vec![4, 8],
            radiosity_samples: vec![5, 9],
            layers: vec![1, 2],
            scale: vec![0.5, 1.0],
            layer1: vec![Layer1Variant::TwoPass, Layer1Variant::Reproject],
            ..Grid::default()
        };
        let c = grid.configurations();
        assert_eq!(c.len(), 32);
        for (i, a) in c.iter().enumerate() {
            assert!(c[i + 1..].iter().all(|b| b != a), "configuration {i} repeats");
        }
        let key =
            |k: &Knobs| (k.scale, k.layer1 as u8, k.layers, k.ao_samples, k.radiosity_samples);
        assert_eq!(key(&c[0]), (0.5, 0, 1, 4, 5));
        assert_eq!(key(&c[1]), (0.5, 0, 1, 4, 9));
        assert_eq!(key(&c[2]), (0.5, 0, 1, 8, 5));
        assert_eq!(key(&c[31]), (1.0, 2, 2, 8, 9));
        assert!(c.iter().all(|k| k.dz == Settings::default().dz && k.precision == Precision::Full));
    }

    /// The knobs are set in the grid's base settings: what no knob sets (the obscurance radius
    /// and bias, the reflections' settings) comes from it, as from the command line's
    /// scene-scaled defaults.
    #[test]
    fn configurations_start_from_the_grid_base() {
        let base = Settings::default().scaled(512.0);
        let grid = Grid {
            ao_samples: vec![8],
            radiosity_samples: vec![9],
            radiosity_layer1_samples: vec![0, 4],
            radiosity_slices: vec![1, 4],
            base,
            ..Grid::default()
        };
        let configurations = grid.configurations();
        // The default grid's two estimators and two layer counts, times the two knobs here.
        assert_eq!(configurations.len(), 2 * 2 * 2 * 2);
        let knobs: Vec<(u32, u32)> = configurations
            .iter()
            .map(|k| k.settings(64, 48).radiosity)
            .map(|r| (r.layer1_samples, r.slices))
            .collect();
        for pair in [(0, 1), (0, 4), (4, 1), (4, 4)] {
            assert!(knobs.contains(&pair), "{pair:?} missing from {knobs:?}");
        }
        for k in configurations {
            let s = k.settings(64, 48);
            assert_eq!((s.width, s.height, s.ao.samples, s.radiosity.samples), (64, 48, 8, 9));
            assert_eq!(s.ao.radius, grid.base.ao.radius);
            assert_eq!(s.ao.bias, grid.base.ao.bias);
            assert_eq!(s.reflections, grid.base.reflections);
            assert_eq!(s.ao.radius, 512.0 * Settings::default().ao.radius);
            assert!(s.timings);
        }
    }
}
