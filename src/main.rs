//! The `deep-gbuffer` command line: render a scene's deep G-buffer, describe the device.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use deep_gbuffer::gpu::{Gpu, GpuOptions};
use deep_gbuffer::scene::{Limits, Projection};
use deep_gbuffer::{
    AoEstimator, AoSettings, AtomicPath, Boost, Camera, Effect, Effects, Environment, Error,
    Layer1Variant, Normalization, PassId, PositionEncoding, Precision, Preset, RadiosityEstimator,
    RadiositySettings, RasterWork, Renderer, Result, Scene, SceneBuffers, SceneInfo, Settings,
    ShadowSettings, output,
};
use glam::Vec3;

#[derive(Parser)]
#[command(
    name = "deep-gbuffer",
    version,
    about = "Two-layer deep G-buffers by compute software rasterization"
)]
struct Cli {
    /// Open the adapter whose name contains this (see `deep-gbuffer info`).
    #[arg(long, global = true)]
    adapter: Option<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene: its deep G-buffer layers and the composite image.
    Render(Box<RenderArgs>),
    /// Print the adapter, backend, driver, features and the active raster path.
    Info,
    /// Ground truth by ray tracing on the CPU, optionally compared with the GPU's estimate.
    Truth(Box<TruthArgs>),
    /// Render a grid of accuracy settings, time every pass and measure each effect's error
    /// against ground truth: sweep.csv, sweep.md and pareto.png.
    Sweep(Box<SweepArgs>),
}

/// What a scene file may make the loaders allocate (`deep_gbuffer::scene::Limits`).
#[derive(clap::Args)]
struct LimitArgs {
    /// Most vertices one glTF accessor may declare.
    #[arg(long, default_value_t = Limits::default().vertices)]
    max_vertices: u64,
    /// Most triangles in the scene, every instance counted.
    #[arg(long, default_value_t = Limits::default().triangles)]
    max_triangles: u64,
    /// Most node instances (a node counts once per path from a scene root).
    #[arg(long, default_value_t = Limits::default().instances)]
    max_instances: u64,
    /// Most texels decoded over all textures (checked from each image's header).
    #[arg(long, default_value_t = Limits::default().texels)]
    max_texels: u64,
}

impl LimitArgs {
    fn limits(&self) -> Limits {
        Limits {
            vertices: self.max_vertices,
            triangles: self.max_triangles,
            instances: self.max_instances,
            texels: self.max_texels,
        }
    }
}

#[derive(clap::Args)]
struct SweepArgs {
    #[command(flatten)]
    limits: LimitArgs,
    /// A .gltf, .glb or .obj file, or builtin:NAME.
    #[arg(default_value = "builtin:cornell")]
    scene: String,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Image size, WxH.
    #[arg(long, default_value = "160x120", value_parser = parse_size)]
    size: (u32, u32),
    #[command(flatten)]
    view: ViewArgs,
    /// Rays per pixel of the ground truth.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Obscurance estimators to sweep (comma separated).
    #[arg(long, value_delimiter = ',', value_enum, default_value = listed_names(&deep_gbuffer::sweep::Grid::default().ao_estimator))]
    ao_estimator: Vec<AoEstimator>,
    /// Obscurance slice counts to sweep (horizon, bitmask).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().ao_slices))]
    ao_slices: Vec<u32>,
    /// Obscurance tap counts to sweep.
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().ao_samples))]
    ao_samples: Vec<u32>,
    /// Radiosity tap counts to sweep.
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().radiosity_samples))]
    radiosity_samples: Vec<u32>,
    /// Radiosity slice counts to sweep (`slices` gather; the taps are shared among them).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().radiosity_slices))]
    radiosity_slices: Vec<u32>,
    /// Layer-1 gather tap counts to sweep (0: none).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().radiosity_layer1_samples))]
    radiosity_layer1_samples: Vec<u32>,
    /// Weights of the radiosity steps' extrapolation to sweep (0: none).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().radiosity_extrapolation))]
    radiosity_extrapolation: Vec<f32>,
    /// Obscurance temporal filter weights to sweep (0: no filter).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().ao_alpha))]
    ao_alpha: Vec<f32>,
    /// Weights of the obscurance steps' extrapolation.
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().ao_extrapolation))]
    ao_extrapolation: Vec<f32>,
    /// Radii of the obscurance's blur to sweep, in pixels (0: none).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().ao_blur_radius))]
    ao_blur_radius: Vec<u32>,
    /// Radiosity slices a moving frame with the temporal history gathers, to sweep (0: all).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().radiosity_history_slices))]
    radiosity_history_slices: Vec<u32>,
    /// Weights of the history in the radiosity's temporal filter to sweep, in [0, 1) (the
    /// sweep's frames move).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().radiosity_alpha))]
    radiosity_alpha: Vec<f32>,
    /// Layer counts to sweep (1, 2).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().layers))]
    layers: Vec<u32>,
    /// G-buffer encodings to sweep.
    #[arg(long, value_delimiter = ',', value_enum, default_value = listed_names(&deep_gbuffer::sweep::Grid::default().precision))]
    precision: Vec<Precision>,
    /// Position encodings to sweep.
    #[arg(long, value_delimiter = ',', value_enum, default_value = listed_names(&deep_gbuffer::sweep::Grid::default().position))]
    position_encoding: Vec<PositionEncoding>,
    /// Radiosity gather radii to sweep, in scene units [default: the default radius scaled to
    /// the scene, as `render` takes it].
    #[arg(long, value_delimiter = ',')]
    radiosity_radius: Option<Vec<f32>>,
    /// Obscurance pyramid level offsets to sweep (a tap at h pixels reads level log2 h - offset).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().mip_offset))]
    mip_offset: Vec<u32>,
    /// Radiosity gather source level offsets to sweep (a tap at h pixels reads level log2 h -
    /// offset).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().radiosity_mip_offset))]
    radiosity_mip_offset: Vec<u32>,
    /// Obscurance resolution divisors to sweep (1, 2, 4).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().ao_downsample))]
    ao_downsample: Vec<u32>,
    /// Radiosity resolution divisors to sweep (1, 2, 4).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().radiosity_downsample))]
    radiosity_downsample: Vec<u32>,
    /// The off-screen light (the reflective shadow maps' clusters) on, off or both, as
    /// `true,false`.
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().radiosity_offscreen))]
    radiosity_offscreen: Vec<bool>,
    /// Reflection rays the screen cannot place followed through the shadow maps or not, or
    /// both, as `true,false`.
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().reflection_shadow_maps))]
    reflection_shadow_maps: Vec<bool>,
    /// Rays through the lens per pixel to sweep (the depth of field runs when --camera gives an
    /// aperture; the truth then samples the lens).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().dof_samples))]
    dof_samples: Vec<u32>,
    /// Transparency layers (peels) to sweep (the transparency runs when the scene has a
    /// blended material; the truth blends stochastically).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().transparency_layers))]
    transparency_layers: Vec<u32>,
    /// Shutters to sweep, shares of the time between frames (above 0 the motion blur runs as
    /// the camera turns; the truth is traced over each shutter).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().shutter))]
    shutter: Vec<f32>,
    /// Layer separations Δz to sweep, in scene units [default: the default Δz scaled to the
    /// scene, as `render` takes it].
    #[arg(long, value_delimiter = ',')]
    dz: Option<Vec<f32>>,
    /// Layer-1 variants to sweep.
    #[arg(long, value_delimiter = ',', value_enum, default_value = listed_names(&deep_gbuffer::sweep::Grid::default().layer1))]
    layer1: Vec<Layer1Variant>,
    /// Resolution scales to sweep (the frame at this fraction of --size, compared at --size).
    #[arg(long, value_delimiter = ',', default_value = listed(&deep_gbuffer::sweep::Grid::default().scale))]
    scale: Vec<f32>,
    /// Equirectangular EXR that missed rays see (else the scene's ambient sky).
    #[arg(long)]
    environment: Option<PathBuf>,
}

/// The effects the ground-truth tracer computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum TruthEffect {
    /// World-space ambient obscurance with the obscurance kernel's radius and falloff.
    Ao,
    /// Diffuse indirect irradiance by path tracing (--bounces surfaces per path).
    Indirect,
    /// Reflections: reflectivity (tinted by the base colour as far as the surface is a metal)
    /// times the mean radiance over the glossy lobe (the mirror direction for roughness 0).
    Reflections,
    /// The full image by path tracing, with the same lights, materials and sky.
    Full,
}

#[derive(clap::Args)]
struct TruthArgs {
    #[command(flatten)]
    limits: LimitArgs,
    /// A .gltf, .glb or .obj file, or builtin:NAME.
    #[arg(default_value = "builtin:cornell")]
    scene: String,
    /// Image size, WxH.
    #[arg(long, default_value = "160x120", value_parser = parse_size)]
    size: (u32, u32),
    #[command(flatten)]
    view: ViewArgs,
    /// The effect to trace.
    #[arg(long, value_enum, default_value_t = TruthEffect::Ao)]
    effect: TruthEffect,
    /// Rays per pixel.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Seed of the per-pixel sample streams (the same seed gives the same image).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write the truth as linear EXR; its per-pixel standard error goes to FILE-stderr.exr.
    #[arg(long)]
    exr: Option<PathBuf>,
    /// Write the truth as PNG (ao: values in [0, 1] as they are; indirect, reflections, full:
    /// tone mapped as `render --out`).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Surfaces along a path for --effect indirect (1: one bounce); for reflections and full,
    /// the surfaces after the first.
    #[arg(long, default_value_t = 1)]
    bounces: u32,
    /// Equirectangular EXR that missed rays see (reflections, full; else the scene's ambient).
    #[arg(long)]
    environment: Option<PathBuf>,
    /// Degrees the camera turned about its target (around its up axis) since the frame before,
    /// and each frame before that: with --shutter above 0, `--effect full` is traced over the
    /// open shutter (the camera moving from the one before to this one), and --compare's frames
    /// look from where the camera was, the last from this camera (a camera orbiting at that
    /// speed).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    turn: f32,
    /// The triangles of a material (by name or index) moved by DX,DY,DZ since the frame before,
    /// MATERIAL:DX,DY,DZ: with --shutter above 0, `--effect full` is traced over the open
    /// shutter with the material's vertices moving, and --compare renders the frame before
    /// (the material back by the offset), then this one.
    #[arg(long = "move", value_parser = parse_move, allow_hyphen_values = true)]
    moving: Option<(String, Vec3)>,
    /// Frames the GPU renders before --compare reads its estimate (temporal multi-bounce).
    #[arg(long, default_value_t = 1)]
    frames: u32,
    /// Frames more of the last frame's view after --frames, the radiosity's filter keeping
    /// their mean (`Renderer::settle`, as `render` does once the radiosity settles).
    #[arg(long, default_value_t = 0)]
    average: u32,
    /// The GPU estimate's accuracy preset (with --compare), as `render --preset` takes it;
    /// explicit options override it.
    #[arg(long, value_enum)]
    preset: Option<Preset>,
    /// The GPU estimate's minimum separation of layer 1 behind layer 0 (with --compare), in
    /// scene units [default: 0.05 times the scene's scale].
    #[arg(long, allow_hyphen_values = true)]
    dz: Option<f32>,
    /// The obscurance's radius, and the GPU estimate's other settings (with --compare).
    #[command(flatten)]
    estimators: EffectArgs,
    /// Render the GPU's estimate with the same settings and print its error next to its GPU time.
    #[arg(long)]
    compare: bool,
    /// With --compare: write the GPU's estimate as linear EXR (the pixels no surface covers
    /// black), to set beside the truth's --exr pixel by pixel.
    #[arg(long, requires = "compare")]
    estimate_exr: Option<PathBuf>,
    /// With --compare: write where the GPU's estimate errs as PNG: white where it meets the
    /// truth, shading to red where it is too high and to blue where it is too low (full colour
    /// at --error-scale), dark grey outside the pixels compared.
    #[arg(long, requires = "compare")]
    error_png: Option<PathBuf>,
    /// The error --error-png shows at full colour, in the effect's units [default: 0.25 for
    /// ao, the truth's mean for the others].
    #[arg(long, requires = "error_png", allow_hyphen_values = true)]
    error_scale: Option<f32>,
}

/// The obscurance's settings (render, and truth's GPU estimate). Those not given keep the
/// default's (or the preset's) value.
#[derive(clap::Args)]
struct AoArgs {
    /// Obscurance estimator (see `wgsl/ao.wgsl`) [default: bitmask, or the preset's].
    #[arg(long, value_enum)]
    ao_estimator: Option<AoEstimator>,
    /// Obscurance radius in scene units [default: 0.5 times the scene's scale].
    #[arg(long)]
    ao_radius: Option<f32>,
    /// Obscurance taps per pixel [default: 32, or the preset's].
    #[arg(long)]
    ao_samples: Option<u32>,
    /// Slices per pixel of the horizon and bitmask estimators, their taps shared among them
    /// [default: 2, or the preset's].
    #[arg(long)]
    ao_slices: Option<u32>,
    /// How far an occluder reaches behind its visible surface, as a fraction of the radius
    /// (bitmask; layer 0's no deeper than layer 1's surface, layer 1's no deeper than the gap in
    /// front of it) [default: 0.75].
    #[arg(long)]
    ao_thickness: Option<f32>,
    /// Weight of the steps' extrapolation of the horizon and bitmask estimators, 0 to 2 (0:
    /// none) [default: 0.6].
    #[arg(long)]
    ao_extrapolation: Option<f32>,
    /// Obscurance from layer 0 only (to compare with the two-layer estimator).
    #[arg(long)]
    ao_one_layer: bool,
    /// Radius of the obscurance's bilateral blur in pixels, 0 to 32 (0: none) [default: 4, or the
    /// preset's].
    #[arg(long)]
    ao_blur_radius: Option<u32>,
    /// Compute the obscurance at 1/N of the image's width and height (1, 2 or 4), upsampled by
    /// depth and normal [default: 1].
    #[arg(long)]
    ao_downsample: Option<u32>,
    /// Weight of the history in the obscurance's temporal filter, in [0, 1); 0: no filter
    /// [default: 0].
    #[arg(long)]
    ao_alpha: Option<f32>,
    /// Slices the horizon and bitmask estimators take in a frame that has the temporal
    /// filter's history, each with the same steps a side (0: all) [default: 0].
    #[arg(long)]
    ao_history_slices: Option<u32>,
    /// Frames a still view goes on computing the obscurance, its slices turned each frame,
    /// keeping their mean under a blur that narrows as the mean grows (0: it keeps its first
    /// frame's) [default: 16].
    #[arg(long)]
    ao_still_frames: Option<u32>,
}

impl AoArgs {
    /// Sets what was given on `ao`.
    fn apply(&self, ao: &mut AoSettings) {
        ao.radius = self.ao_radius.unwrap_or(ao.radius);
        ao.estimator = self.ao_estimator.unwrap_or(ao.estimator);
        ao.samples = self.ao_samples.unwrap_or(ao.samples);
        ao.slices = self.ao_slices.unwrap_or(ao.slices);
        ao.thickness = self.ao_thickness.unwrap_or(ao.thickness);
        ao.extrapolation = self.ao_extrapolation.unwrap_or(ao.extrapolation);
        ao.downsample = self.ao_downsample.unwrap_or(ao.downsample);
        ao.alpha = self.ao_alpha.unwrap_or(ao.alpha);
        ao.history_slices = self.ao_history_slices.unwrap_or(ao.history_slices);
        ao.still_frames = self.ao_still_frames.unwrap_or(ao.still_frames);
        ao.blur_radius = self.ao_blur_radius.unwrap_or(ao.blur_radius);
        if self.ao_one_layer {
            ao.two_layers = false;
        }
    }
}

/// The radiosity gather's settings (render, and truth's GPU estimate). Those not given keep the
/// default's (or the preset's) value.
#[derive(clap::Args)]
struct RadiosityArgs {
    /// Radiosity gather (see `wgsl/radiosity.wgsl`) [default: slices].
    #[arg(long, value_enum)]
    radiosity_estimator: Option<RadiosityEstimator>,
    /// Radiosity gather radius in scene units [default: 3 times the scene's scale].
    #[arg(long)]
    radiosity_radius: Option<f32>,
    /// Radiosity taps per pixel [default: 32, or the preset's].
    #[arg(long)]
    radiosity_samples: Option<u32>,
    /// How far a surface the slices gather finds reaches behind itself, as a fraction of the
    /// gather's radius (layer 0's no deeper than layer 1's surface, layer 1's no deeper than the
    /// gap in front of it) [default: 0.75].
    #[arg(long)]
    radiosity_thickness: Option<f32>,
    /// Slices per pixel of the slices gather [default: 2].
    #[arg(long)]
    radiosity_slices: Option<u32>,
    /// Slices the slices gather takes in a frame whose view moved and that has the temporal
    /// history (they turn every frame; a first frame and a still view take all), 0 to 16 (0:
    /// all) [default: 1].
    #[arg(long)]
    radiosity_history_slices: Option<u32>,
    /// Taps per layer-1 point of the gather that lets surfaces the camera does not see pass on
    /// the light they receive in the next frame's bounce, 0 to 256 (0: none) [default: 8].
    #[arg(long)]
    radiosity_layer1_samples: Option<u32>,
    /// Weight of the slices gather's extrapolation from every other step, 0 to 2 (0: none)
    /// [default: 0.6].
    #[arg(long)]
    radiosity_extrapolation: Option<f32>,
    /// A radiosity tap h pixels away reads level floor(log2 h) - this of the gather source,
    /// 0 to 8 [default: 4].
    #[arg(long)]
    radiosity_mip_offset: Option<u32>,
    /// Gather the radiosity at 1/N of the image's width and height (1, 2 or 4), upsampled by
    /// depth and normal [default: 1].
    #[arg(long)]
    radiosity_downsample: Option<u32>,
    /// Damping delta of the indirect light fed back into the next frame's radiosity, in (0, 1]
    /// [default: 0.8].
    #[arg(long)]
    damping: Option<f32>,
    /// Weight of the history in the radiosity's temporal filter while the camera or the scene
    /// moves, in [0, 1) [default: 0.9].
    #[arg(long)]
    radiosity_alpha: Option<f32>,
    /// Weight of the history in the radiosity's temporal filter while the view stands still,
    /// until the bounces settle, in [0, 1): lower reaches the later bounces in fewer frames,
    /// with more noise in each [default: 0.7].
    #[arg(long)]
    radiosity_still_alpha: Option<f32>,
    /// Frames of a settled still view's mean after which the view keeps its radiosity and
    /// runs no radiosity pass until it moves; 0: never [default: 256].
    #[arg(long)]
    radiosity_kept_after: Option<u32>,
    /// Take a surface's outgoing light only where it faces the gathering point; a slices
    /// gather takes what a surface facing away sends from its far side, its emission and the
    /// indirect light it reflects, and from a curved surface the side the point sees (see
    /// `RadiositySettings::normal_test`) [default: on].
    #[arg(long, value_name = "on|off", value_parser = clap::builder::BoolishValueParser::new())]
    radiosity_normal_test: Option<bool>,
    /// Add the light of the surfaces neither layer holds, from each shadow-casting light's
    /// reflective shadow map (see `RadiositySettings::offscreen`) [default: on].
    #[arg(long, value_name = "on|off", value_parser = clap::builder::BoolishValueParser::new())]
    radiosity_offscreen: Option<bool>,
}

impl RadiosityArgs {
    /// Sets what was given on `r`.
    fn apply(&self, r: &mut RadiositySettings) {
        r.radius = self.radiosity_radius.unwrap_or(r.radius);
        r.estimator = self.radiosity_estimator.unwrap_or(r.estimator);
        r.samples = self.radiosity_samples.unwrap_or(r.samples);
        r.thickness = self.radiosity_thickness.unwrap_or(r.thickness);
        r.slices = self.radiosity_slices.unwrap_or(r.slices);
        r.layer1_samples = self.radiosity_layer1_samples.unwrap_or(r.layer1_samples);
        r.extrapolation = self.radiosity_extrapolation.unwrap_or(r.extrapolation);
        r.history_slices = self.radiosity_history_slices.unwrap_or(r.history_slices);
        r.mip_offset = self.radiosity_mip_offset.unwrap_or(r.mip_offset);
        r.downsample = self.radiosity_downsample.unwrap_or(r.downsample);
        r.damping = self.damping.unwrap_or(r.damping);
        r.alpha = self.radiosity_alpha.unwrap_or(r.alpha);
        r.still_alpha = self.radiosity_still_alpha.unwrap_or(r.still_alpha);
        r.kept_after = self.radiosity_kept_after.unwrap_or(r.kept_after);
        r.normal_test = self.radiosity_normal_test.unwrap_or(r.normal_test);
        r.offscreen = self.radiosity_offscreen.unwrap_or(r.offscreen);
    }
}

/// The settings of the obscurance, the radiosity and the reflections (render, and truth's GPU
/// estimate); those not given keep the default's (or the preset's) value.
#[derive(clap::Args)]
struct EffectArgs {
    #[command(flatten)]
    ao: AoArgs,
    #[command(flatten)]
    radiosity: RadiosityArgs,
    #[command(flatten)]
    reflections: ReflectionArgs,
    #[command(flatten)]
    dof: DofArgs,
    #[command(flatten)]
    motion_blur: MotionBlurArgs,
    /// Blended surfaces peeled per pixel, 1 to 16 (it runs when the scene has a blended
    /// material: glTF alphaMode BLEND, OBJ d or Tr below 1) [default: 4].
    #[arg(long)]
    transparency_layers: Option<u32>,
}

impl EffectArgs {
    /// Sets what was given on `s`.
    fn apply(&self, s: &mut Settings) {
        self.ao.apply(&mut s.ao);
        self.radiosity.apply(&mut s.radiosity);
        self.reflections.apply(&mut s.reflections);
        self.dof.apply(&mut s.dof);
        self.motion_blur.apply(&mut s.motion_blur);
        s.transparency.layers = self.transparency_layers.unwrap_or(s.transparency.layers);
    }
}

/// The motion blur's settings (it runs when the shutter is open and the camera moved since the
/// last frame, as `--orbit` moves it). Those not given keep the default's value.
#[derive(clap::Args)]
struct MotionBlurArgs {
    /// How long the shutter stays open before each frame, as a fraction of the time between
    /// frames, 0 to 1 [default: 0, no motion blur].
    #[arg(long)]
    shutter: Option<f32>,
    /// Instants of the shutter per pixel [default: 16].
    #[arg(long)]
    motion_samples: Option<u32>,
    /// The longest streak followed, in pixels [default: 32].
    #[arg(long)]
    motion_max_blur: Option<f32>,
    /// Read layer 0 only (do not show what a moving surface uncovers).
    #[arg(long)]
    motion_one_layer: bool,
}

impl MotionBlurArgs {
    /// Sets what was given on `m`.
    fn apply(&self, m: &mut deep_gbuffer::MotionBlurSettings) {
        m.shutter = self.shutter.unwrap_or(m.shutter);
        m.samples = self.motion_samples.unwrap_or(m.samples);
        m.max_blur = self.motion_max_blur.unwrap_or(m.max_blur);
        if self.motion_one_layer {
            m.two_layers = false;
        }
    }
}

/// The depth of field's settings (it runs when the camera's lens has an aperture:
/// `--camera aperture=R,focus=D`). Those not given keep the default's value.
#[derive(clap::Args)]
struct DofArgs {
    /// Rays through the lens per pixel [default: 24].
    #[arg(long)]
    dof_samples: Option<u32>,
    /// The largest circle of confusion followed, in pixels [default: 32].
    #[arg(long)]
    dof_max_coc: Option<f32>,
    /// Stop lens rays at layer 0 (do not let them find what it hides).
    #[arg(long)]
    dof_one_layer: bool,
}

impl DofArgs {
    /// Sets what was given on `d`.
    fn apply(&self, d: &mut deep_gbuffer::DofSettings) {
        d.samples = self.dof_samples.unwrap_or(d.samples);
        d.max_coc = self.dof_max_coc.unwrap_or(d.max_coc);
        if self.dof_one_layer {
            d.two_layers = false;
        }
    }
}

/// The reflections' settings (render, and truth's GPU estimate). Those not given keep the
/// default's value.
#[derive(clap::Args)]
struct ReflectionArgs {
    /// How far a reflection ray is followed, in scene units [default: to the screen's edge].
    #[arg(long)]
    reflection_distance: Option<f32>,
    /// How far behind a surface a reflection ray may pass and still hit it, in scene units
    /// [default: 0.1 times the scene's scale].
    #[arg(long)]
    reflection_thickness: Option<f32>,
    /// Directions averaged over the glossy lobe of a surface of roughness 0.5 or more (fewer
    /// for smoother ones; 1: the mirror ray alone) [default: 8].
    #[arg(long)]
    reflection_lobe_samples: Option<u32>,
    /// Leave the rays the screen cannot place at the environment instead of following them
    /// through the lights' shadow maps (faster where much reflects the sky).
    #[arg(long)]
    reflection_screen_only: bool,
}

impl ReflectionArgs {
    /// Sets what was given on `r`.
    fn apply(&self, r: &mut deep_gbuffer::ReflectionSettings) {
        r.max_distance = self.reflection_distance.unwrap_or(r.max_distance);
        r.thickness = self.reflection_thickness.unwrap_or(r.thickness);
        r.lobe_samples = self.reflection_lobe_samples.unwrap_or(r.lobe_samples);
        if self.reflection_screen_only {
            r.shadow_maps = false;
        }
    }
}

#[derive(clap::Args)]
struct RenderArgs {
    #[command(flatten)]
    limits: LimitArgs,
    /// A .gltf, .glb or .obj file, or builtin:NAME (cornell, grid, grid-<triangles>).
    #[arg(default_value = "builtin:cornell")]
    scene: String,
    /// Image size, WxH.
    #[arg(long, default_value = "640x480", value_parser = parse_size)]
    size: (u32, u32),
    #[command(flatten)]
    view: ViewArgs,
    /// Side of each shadow-map face in texels, 16 to 4096 [default: about one texel per pixel
    /// where the scene fills the view, a power of two from 512 to 4096].
    #[arg(long)]
    shadow_resolution: Option<u32>,
    /// Write depth, normal and base colour of the layers the frame drew, and each lighting term
    /// (ao, direct, radiosity, indirect, reflections; those the frame ran), as PNG and EXR into
    /// this folder.
    #[arg(long)]
    layers: Option<PathBuf>,
    /// Write the HDR composite, tone mapped, as PNG.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the image as linear EXR.
    #[arg(long)]
    exr: Option<PathBuf>,
    /// Write per-pass GPU times (timestamp queries) as JSON.
    #[arg(long)]
    timings: Option<PathBuf>,
    /// Minimum separation of layer 1 behind layer 0, in scene units [default: 0.05 times the
    /// scene's scale].
    #[arg(long)]
    dz: Option<f32>,
    /// How layer 1 is rasterized.
    #[arg(long, value_enum, default_value_t = Layer1Variant::TwoPass)]
    layer1: Layer1Variant,
    /// G-buffer precision (default: full, or the preset's).
    #[arg(long, value_enum)]
    precision: Option<Precision>,
    /// How the G-buffer stores positions: the depth every pass after the resolve reads back.
    #[arg(long, value_enum, default_value_t = PositionEncoding::ViewDepthF32)]
    position_encoding: PositionEncoding,
    /// Accuracy preset: tap counts, slices, the obscurance's blur, layers and precision (explicit
    /// options override it).
    #[arg(long, value_enum)]
    preset: Option<Preset>,
    /// Raster atomics.
    #[arg(long, value_enum, default_value_t = AtomicPath::Auto)]
    atomics: AtomicPath,
    /// How the rasterizer shares out its work (the same pixels either way).
    #[arg(long, value_enum, default_value_t = RasterWork::Auto)]
    raster_work: RasterWork,
    /// Frames to render (the outputs are the last frame's) [default: until the radiosity
    /// settles, when it runs: its mean irradiance over 4 frames differs by less than 0.5% from
    /// the 4 before, at most 128 frames; and, for a still camera, at least 1 + the obscurance's
    /// still frames (--ao-still-frames), whose mean it then shows; else 1].
    #[arg(long)]
    frames: Option<u32>,
    /// Frames rendered after the radiosity settles (without --frames), each averaged in: the
    /// temporal filter keeps the mean of the frames since (`Renderer::settle`), so the
    /// gather's noise falls as one over the square root of their count (0: stop when it
    /// settles).
    #[arg(long, default_value_t = DEFAULT_AVERAGE, conflicts_with = "frames")]
    average: u32,
    /// Degrees the camera orbits about the target (around the up axis) over all frames: the
    /// first frame at 0, the last at this angle (needs --frames).
    #[arg(long, default_value_t = 0.0, requires = "frames")]
    orbit: f32,
    /// Move the triangles of a material (by name or index) by DX,DY,DZ scene units a frame,
    /// MATERIAL:DX,DY,DZ, arriving where the scene has it at the last frame (needs --frames; with
    /// --shutter the motion blur follows it; the last frame is the one `truth --move` traces).
    #[arg(long = "move", value_parser = parse_move, requires = "frames")]
    moving: Option<(String, Vec3)>,
    /// Write every frame as DIR/frame_NNNN.png.
    #[arg(long)]
    out_seq: Option<PathBuf>,
    /// Print the plan (which passes a frame runs, and why the others do not) and stop, without
    /// rendering.
    #[arg(long, conflicts_with_all = ["out", "exr", "layers", "timings", "out_seq"])]
    plan: bool,
    /// Effects to run: `auto` (all the scene calls for) or a list such as `ao,direct`.
    #[arg(long, default_value = "auto")]
    effects: String,
    /// Exposure (a factor on the HDR image before the tone map of --out).
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Turn ambient obscurance off.
    #[arg(long)]
    no_ao: bool,
    #[command(flatten)]
    estimators: EffectArgs,
    /// How the spiral radiosity gather normalises its taps (cosine conserves energy; paper is
    /// 2 pi / M).
    #[arg(long, value_enum, default_value_t = Normalization::Cosine)]
    normalization: Normalization,
    /// Equirectangular EXR environment that reflection rays see when they leave the screen
    /// (default: the scene's constant ambient sky).
    #[arg(long)]
    environment: Option<std::path::PathBuf>,
    /// Colour boost of reflected light, UNSATURATED,SATURATED (1,1: none, energy conserving).
    /// The feedback gain, normalisation factor (cosine 1, paper 2) x damping x the larger boost,
    /// must stay below 1.
    #[arg(long, default_value = "1,1", value_parser = parse_boost)]
    boost: Boost,
}

/// A list's default as the option takes it, comma separated (made once, when the parser is
/// built, and kept for the program's life).
fn listed<T: std::fmt::Display>(values: &[T]) -> &'static str {
    let text: Vec<String> = values.iter().map(T::to_string).collect();
    Box::leak(text.join(",").into_boxed_str())
}

/// As [`listed`], for values named as the command line spells them.
fn listed_names<T: ValueEnum>(values: &[T]) -> &'static str {
    let names: Vec<String> = values
        .iter()
        .filter_map(|v| v.to_possible_value())
        .map(|v| v.get_name().to_owned())
        .collect();
    Box::leak(names.join(",").into_boxed_str())
}

fn parse_boost(s: &str) -> std::result::Result<Boost, String> {
    let (a, b) = s.split_once(',').ok_or_else(|| format!("`{s}` is not UNSATURATED,SATURATED"))?;
    let parse = |v: &str| v.trim().parse::<f32>().map_err(|e| format!("`{v}`: {e}"));
    Ok(Boost { unsaturated: parse(a)?, saturated: parse(b)? })
}

fn parse_move(s: &str) -> std::result::Result<(String, Vec3), String> {
    let (name, by) = s.rsplit_once(':').ok_or_else(|| format!("`{s}` is not MATERIAL:DX,DY,DZ"))?;
    let by: Vec<f32> = by
        .split(',')
        .map(|v| v.trim().parse::<f32>().map_err(|e| format!("`{v}`: {e}")))
        .collect::<std::result::Result<_, _>>()?;
    match by[..] {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => {
            Ok((name.to_owned(), Vec3::new(x, y, z)))
        }
        _ => Err(format!("`{s}`: the offset is three finite numbers DX,DY,DZ")),
    }
}

fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("`{s}` is not WxH"))?;
    let w: u32 = w.trim().parse().map_err(|_| format!("`{w}` is not a width"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("`{h}` is not a height"))?;
    Ok((w, h))
}

/// Applies `eye=x,y,z,target=x,y,z,fov=deg,aperture=r,focus=d` to `camera`.
fn apply_camera(camera: &mut Camera, spec: &str) -> Result<()> {
    let bad = |m: String| Error::InvalidSetting { name: "camera", message: m };
    let mut key: Option<&str> = None;
    let mut values: Vec<(&str, Vec<f32>)> = Vec::new();
    for token in spec.split(',') {
        let token = token.trim();
        let value = match token.split_once('=') {
            Some((k, _)) if k.trim().is_empty() => {
                return Err(bad(format!("`{token}` in `{spec}`: a value without its key")));
            }
            Some((k, v)) => {
                key = Some(k.trim());
                values.push((k.trim(), Vec::new()));
                v
            }
            None => token,
        };
        let k = key.ok_or_else(|| bad(format!("`{spec}`: expected key=value")))?;
        let v: f32 = value.trim().parse().map_err(|_| match value.trim() {
            "" => bad(format!("`{k}` has an empty value in `{spec}`")),
            _ => bad(format!("`{value}` in {k} is not a number")),
        })?;
        values.last_mut().expect("a key was pushed").1.push(v);
    }
    for (k, v) in values {
        match (k, v.as_slice()) {
            ("eye", &[x, y, z]) => camera.eye = Vec3::new(x, y, z),
            ("target", &[x, y, z]) => camera.target = Vec3::new(x, y, z),
            ("up", &[x, y, z]) => camera.up = Vec3::new(x, y, z),
            ("fov", &[deg]) => match &mut camera.projection {
                Projection::Perspective { fov_y_deg, .. } => *fov_y_deg = deg,
                Projection::Orthographic { .. } => {
                    return Err(bad("fov given for an orthographic camera".into()));
                }
            },
            ("near", &[d]) => match &mut camera.projection {
                Projection::Perspective { near, .. } | Projection::Orthographic { near, .. } => {
                    *near = d
                }
            },
            ("far", &[d]) => match &mut camera.projection {
                Projection::Perspective { far, .. } => *far = Some(d),
                Projection::Orthographic { far, .. } => *far = d,
            },
            ("aperture", &[r]) => camera.lens.radius = r,
            ("focus", &[d]) => camera.lens.focus = d,
            (k, v) => {
                return Err(bad(format!(
                    "`{k}` with {} values (expected eye, target, up: 3; fov, near, far, aperture, \
                     focus: 1)",
                    v.len()
                )));
            }
        }
    }
    camera.validate()
}

fn truth(adapter: &Option<String>, args: TruthArgs) -> Result<()> {
    let (w, h) = args.size;
    for path in [&args.out, &args.exr, &args.estimate_exr, &args.error_png].into_iter().flatten() {
        output::check_writable(path)?;
    }
    if let Some(scale) = args.error_scale
        && !(scale.is_finite() && scale > 0.0)
    {
        return Err(Error::InvalidSetting {
            name: "error_scale",
            message: format!("{scale} (must be finite and > 0)"),
        });
    }
    let (scene, camera) = args.view.scene_and_camera(&args.scene, args.size, &args.limits)?;
    // The GPU estimate's settings, checked before the truth is traced; the truth's obscurance
    // has their radius.
    let mut settings = scaled_defaults(&scene);
    (settings.width, settings.height) = (w, h);
    if let Some(preset) = args.preset {
        preset.apply(&mut settings);
    }
    settings.dz = args.dz.unwrap_or(settings.dz);
    args.estimators.apply(&mut settings);
    settings.validate()?;
    let ao = settings.ao.clone();
    if !args.turn.is_finite() {
        return Err(Error::InvalidSetting {
            name: "turn",
            message: format!("{} (must be finite)", args.turn),
        });
    }
    let before = camera.orbited(-args.turn);
    // The vertex positions of the frame before, when a material moved since.
    let positions_before = match &args.moving {
        Some((name, by)) => Some(scene.positions_moved(scene.material_named(name)?, -*by)?),
        None => None,
    };
    let shutter = settings.motion_blur.shutter;
    let moved = args.turn != 0.0 || positions_before.is_some();
    let in_motion = (moved && shutter > 0.0).then_some(deep_gbuffer::truth::Shutter {
        before: &before,
        open: shutter,
        positions_before: positions_before.as_deref(),
    });
    let tracer = deep_gbuffer::truth::Tracer::new(&scene)?;
    let effect = args.effect.to_possible_value().expect("every effect is listed");
    let effect = effect.get_name();
    let message = format!("tracing {effect} at {w}x{h}, {} rays per pixel, rows", args.spp);
    let bar = Progress::new(u64::from(h), message);
    let started = std::time::Instant::now();
    let progress = || bar.inc();
    let (spp, seed, bounces) = (args.spp, args.seed, args.bounces);
    let environment = args.environment.as_deref().map(Environment::load_exr).transpose()?;
    let env = environment.as_ref();
    let shot = deep_gbuffer::truth::Shot { camera: &camera, size: (w, h), spp, seed };
    let image = match args.effect {
        TruthEffect::Ao => tracer.ambient_obscurance(&scene, &shot, &ao, &progress)?,
        TruthEffect::Indirect => tracer.indirect(&scene, &shot, bounces, &progress)?,
        TruthEffect::Reflections => tracer.reflections(&scene, &shot, env, bounces, &progress)?,
        TruthEffect::Full => {
            tracer.full_in_motion(&scene, &shot, in_motion.as_ref(), env, bounces, &progress)?
        }
    };
    bar.finish();
    println!(
        "truth {effect}: {w}x{h}, {} rays per pixel, {:.1} s; mean standard error {:.5}",
        args.spp,
        started.elapsed().as_secs_f32(),
        image.mean_stderr()
    );
    if let Some(path) = &args.exr {
        output::write_exr(path, w, h, &image.value)?;
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("truth");
        let stderr_path = path.with_file_name(format!("{stem}-stderr.exr"));
        output::write_exr(&stderr_path, w, h, &image.stderr)?;
    }
    if let Some(path) = &args.out {
        match args.effect {
            TruthEffect::Ao => output::write_png_display(path, w, h, &image.value)?,
            // Radiance and irradiance: tone mapped as `render --out` maps its image.
            TruthEffect::Indirect | TruthEffect::Reflections | TruthEffect::Full => {
                output::write_png_linear(path, w, h, &output::tonemap(&image.value, 1.0))?
            }
        }
    }
    if args.compare {
        let gpu = open_gpu(adapter)?;
        let buffers = SceneBuffers::upload(&gpu.device, &scene)?;
        let mut renderer = Renderer::new(&gpu.device, &gpu.queue, settings)?;
        renderer.set_environment(&gpu.device, env)?;
        if args.frames == 0 {
            return Err(Error::InvalidSetting {
                name: "frames",
                message: "0 (at least one)".into(),
            });
        }
        // With a turn the frames before the last look from where the camera was, a turn
        // further back each, and with a move they see the material where it was.
        for frame in 0..args.frames {
            let last = frame + 1 == args.frames;
            let back = (args.frames - 1 - frame) as f32;
            // The last frame (and every frame without a turn) is the traced camera itself.
            let at = if last || args.turn == 0.0 {
                camera.clone()
            } else {
                camera.orbited(-args.turn * back)
            };
            if let Some(positions) = &positions_before {
                let now = if last { &scene.positions } else { positions };
                buffers.write_positions(&gpu.queue, now)?;
                renderer.geometry_changed();
            }
            renderer.render(&gpu.device, &gpu.queue, &buffers, &at)?;
        }
        if args.average > 0 {
            average_settled(&mut renderer, &gpu, &buffers, &camera, args.average, None)?;
        }
        let terms = renderer.read_terms(&gpu.device, &gpu.queue)?;
        let (estimate, effect, what) = match args.effect {
            TruthEffect::Ao => (
                terms.av.map(|av| av.iter().map(|v| Vec3::splat(*v)).collect()),
                Some(Effect::Ao),
                "obscurance",
            ),
            TruthEffect::Indirect => (terms.indirect, Some(Effect::Radiosity), "radiosity"),
            TruthEffect::Reflections => {
                (terms.reflections, Some(Effect::Reflections), "reflections")
            }
            TruthEffect::Full => (Some(terms.hdr), None, "image"),
        };
        let Some(estimate) = estimate else {
            return Err(Error::InvalidSetting {
                name: "effect",
                message: format!("the scene's plan runs no {what} to compare"),
            });
        };
        let layer0 = renderer.read_gbuffer(&gpu.device, &gpu.queue, 0)?;
        let mask: Vec<bool> = layer0.samples.iter().map(|s| s.depth > 0.0).collect();
        let stats = deep_gbuffer::truth::metrics::compare(&estimate, &mask, &image);
        if let Some(path) = &args.estimate_exr {
            let covered: Vec<Vec3> =
                estimate.iter().zip(&mask).map(|(v, m)| if *m { *v } else { Vec3::ZERO }).collect();
            output::write_exr(path, w, h, &covered)?;
        }
        let timings = renderer.timings(&gpu.device)?;
        // The image costs the whole frame.
        let timed: Vec<_> = timings
            .iter()
            .filter(|t| effect.is_none() || PassId::effect_of(&t.name) == effect)
            .collect();
        let ms: f64 = timed.iter().map(|t| t.ms).sum();
        let passes: Vec<&str> = match effect {
            Some(_) => timed.iter().map(|t| t.name.as_str()).collect(),
            None => vec!["every pass"],
        };
        if args.effect == TruthEffect::Full {
            let seen: Vec<bool> = mask.iter().zip(&image.visible).map(|(a, b)| *a && *b).collect();
            let ssim =
                deep_gbuffer::truth::metrics::ssim(&estimate, &image.value, &seen, (w, h), 1.0);
            println!("gpu image: SSIM {ssim:.4} against the truth (tone-mapped luminance)");
        }
        println!(
            "gpu {what}: rmse {:.4}, mae {:.4} over {} pixels (truth noise {:.4}, mean {:.4} vs truth {:.4}, ratio {:.3}; median relative error {:+.3} where the truth exceeds a tenth of its mean); {} {:.3} ms on {}",
            stats.rmse,
            stats.mae,
            stats.pixels,
            stats.truth_stderr,
            stats.estimate_mean,
            stats.truth_mean,
            stats.estimate_mean / stats.truth_mean,
            stats.median_relative,
            passes.join(" + "),
            ms,
            gpu.describe()
        );
        if let Some(path) = &args.error_png {
            // The truth's mean is 0 (or not a number) only where nothing was compared.
            let scale = match (args.error_scale, args.effect) {
                (Some(scale), _) => scale,
                (None, TruthEffect::Ao) => 0.25,
                (None, _) if stats.truth_mean > 0.0 => stats.truth_mean,
                (None, _) => 1.0,
            };
            let map = deep_gbuffer::truth::metrics::error_map(&estimate, &mask, &image, scale);
            output::write_png_display(path, w, h, &map)?;
            println!(
                "error map: {} (full red: the estimate {scale:.4} or more too high; full blue: as much too low)",
                path.display()
            );
        }
    }
    Ok(())
}

/// Progress on stderr: a bar on a terminal; else (piped, logged) a plain line at each tenth.
struct Progress {
    bar: Option<indicatif::ProgressBar>,
    message: String,
    len: u64,
    done: std::sync::atomic::AtomicU64,
}

impl Progress {
    fn new(len: u64, message: String) -> Self {
        use std::io::IsTerminal;
        let bar = std::io::stderr().is_terminal().then(|| {
            let style =
                indicatif::ProgressStyle::with_template("{msg} {bar:40} {pos}/{len}, {eta} left")
                    .expect("a valid template");
            let bar = indicatif::ProgressBar::new(len).with_style(style);
            bar.set_message(message.clone());
            bar
        });
        Progress { bar, message, len: len.max(1), done: Default::default() }
    }

    /// One more step done (from any thread).
    fn inc(&self) {
        if let Some(bar) = &self.bar {
            bar.inc(1);
            return;
        }
        let done = self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if done * 10 / self.len > (done - 1) * 10 / self.len {
            eprintln!("{}: {done}/{}", self.message, self.len);
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

fn sweep(adapter: &Option<String>, args: SweepArgs) -> Result<()> {
    use deep_gbuffer::sweep;
    let (w, h) = args.size;
    let (scene, camera) = args.view.scene_and_camera(&args.scene, args.size, &args.limits)?;
    // Every configuration starts from the defaults with their lengths scaled to the scene (the
    // obscurance radius, which the truth is traced with, among them), as `render` takes them.
    let base = scaled_defaults(&scene);
    let grid = sweep::Grid {
        ao_estimator: args.ao_estimator,
        ao_slices: args.ao_slices,
        ao_samples: args.ao_samples,
        ao_alpha: args.ao_alpha,
        ao_extrapolation: args.ao_extrapolation,
        ao_blur_radius: args.ao_blur_radius,
        radiosity_samples: args.radiosity_samples,
        radiosity_slices: args.radiosity_slices,
        radiosity_layer1_samples: args.radiosity_layer1_samples,
        radiosity_extrapolation: args.radiosity_extrapolation,
        radiosity_history_slices: args.radiosity_history_slices,
        radiosity_alpha: args.radiosity_alpha,
        layers: args.layers,
        precision: args.precision,
        position: args.position_encoding,
        radiosity_radius: args.radiosity_radius.unwrap_or(vec![base.radiosity.radius]),
        mip_offset: args.mip_offset,
        radiosity_mip_offset: args.radiosity_mip_offset,
        ao_downsample: args.ao_downsample,
        radiosity_downsample: args.radiosity_downsample,
        radiosity_offscreen: args.radiosity_offscreen,
        reflection_shadow_maps: args.reflection_shadow_maps,
        dof_samples: args.dof_samples,
        transparency_layers: args.transparency_layers,
        shutter: args.shutter,
        dz: args.dz.unwrap_or(vec![base.dz]),
        layer1: args.layer1,
        scale: args.scale,
        base,
    };
    let configurations = grid.configurations();
    for k in &configurations {
        k.validate(w, h)?;
    }
    let environment = args.environment.as_deref().map(Environment::load_exr).transpose()?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| Error::Io { path: args.out.clone(), source: e })?;
    let gpu = open_gpu(adapter)?;
    let buffers = SceneBuffers::upload(&gpu.device, &scene)?;
    let bar = Progress::new(
        sweep::Truth::rows(&scene, &grid, h),
        format!("ground truth, {} rays per pixel", args.spp),
    );
    let env = environment.as_ref();
    let truth =
        sweep::Truth::trace(&scene, &camera, &grid, ((w, h), args.spp), env, &|| bar.inc())?;
    bar.finish();
    let bar = Progress::new(configurations.len() as u64 + 1, "configurations".into());
    // One unrecorded measurement first: on lavapipe the first configuration a process measures
    // can run its raster tens of times slower in every frame (704 ms against 16 ms measured).
    if let Some(first) = configurations.first() {
        sweep::measure(&gpu.device, &gpu.queue, &buffers, &camera, &truth, first, env)?;
        bar.inc();
    }
    let mut rows = Vec::new();
    for k in &configurations {
        rows.push(sweep::measure(&gpu.device, &gpu.queue, &buffers, &camera, &truth, k, env)?);
        bar.inc();
    }
    bar.finish();
    let heading = format!(
        "Sweep of {} at {w}x{h} on {}; truth {} rays per pixel, {} bounces (noise: obscurance {:.4}, irradiance {:.4}, image {:.4}); {} settling and {} measured frames turning {} degrees each",
        args.scene,
        gpu.describe(),
        args.spp,
        sweep::TRUTH_BOUNCES,
        truth.ao.mean_stderr(),
        truth.indirect.mean_stderr(),
        truth.full.mean_stderr(),
        sweep::SETTLE_FRAMES,
        sweep::MEASURED_FRAMES,
        sweep::MOTION_DEGREES
    );
    sweep::write_csv(&args.out.join("sweep.csv"), &rows)?;
    sweep::write_markdown(&args.out.join("sweep.md"), &rows, &heading)?;
    // The plot's title names the file alone (a long path would run off the picture); sweep.md
    // keeps the path as given.
    let name = std::path::Path::new(&args.scene)
        .file_name()
        .map_or_else(|| args.scene.clone(), |n| n.to_string_lossy().into_owned());
    sweep::plot_pareto(&args.out.join("pareto.png"), &rows, &format!("{name} at {w}x{h}"))?;
    println!("{heading}");
    println!("{} configurations -> {}", rows.len(), args.out.display());
    Ok(())
}

/// The camera a command looks through: the scene's own, changed by `--camera`, or fitted to
/// the scene by `--fit`.
#[derive(clap::Args)]
struct ViewArgs {
    /// Camera: eye=x,y,z,target=x,y,z,up=x,y,z,fov=deg,near=d,far=d, and a thin lens:
    /// aperture=r (lens radius, scene units; 0: pinhole) and focus=d (view depth in focus) (any
    /// subset; the rest from the scene's camera).
    #[arg(long)]
    camera: Option<String>,
    /// Move the camera along its line of sight until the whole scene is in view (its direction
    /// and field of view stay; the file's camera keeps its vertical field of view at any
    /// aspect, so a tight one may cut the scene off).
    #[arg(long)]
    fit: bool,
}

impl ViewArgs {
    /// Loads `spec` (warnings printed), adds the default lights if it has none, and takes its
    /// camera with the `--camera` changes applied, fitted to the scene at the aspect of `size`
    /// with `--fit`.
    fn scene_and_camera(
        &self,
        spec: &str,
        (w, h): (u32, u32),
        limits: &LimitArgs,
    ) -> Result<(Scene, Camera)> {
        let mut scene = Scene::from_spec_with(spec, &limits.limits())?;
        for warning in &scene.warnings {
            eprintln!("warning: {warning}");
        }
        if scene.ensure_lights() {
            eprintln!("note: the scene has no light; it is lit by the default sun and sky");
        }
        let mut cam = scene.camera_or_default();
        if let Some(spec) = &self.camera {
            let near_given = spec.split(',').any(|t| t.trim().starts_with("near="));
            apply_camera(&mut cam, spec)?;
            // A moved camera keeps no near plane that would cut what it now sees.
            if !near_given && let Projection::Perspective { near, .. } = &mut cam.projection {
                *near = near.min(scene.near_plane_from(cam.eye));
            }
        }
        if self.fit {
            cam = scene.fit_camera(&cam, w as f32 / h.max(1) as f32);
            cam.validate()?;
        }
        Ok((scene, cam))
    }
}

/// The default settings with their lengths scaled to `scene`'s size
/// ([`Settings::scale_for`]), said in a note when they are not the defaults.
fn scaled_defaults(scene: &Scene) -> Settings {
    let extent = scene.extent();
    let scale = Settings::scale_for(extent);
    let settings = Settings::default().scaled(scale);
    if scale != 1.0 {
        eprintln!(
            "note: default lengths x{scale} for a scene {extent:.3} units across (obscurance radius {}, radiosity radius {}, dz {}; options override)",
            settings.ao.radius, settings.radiosity.radius, settings.dz
        );
    }
    settings
}

fn open_gpu(cli_adapter: &Option<String>) -> Result<Gpu> {
    Gpu::new(&GpuOptions { adapter: cli_adapter.clone() }, &Renderer::requirements())
}

fn info(adapter: &Option<String>) -> Result<()> {
    let gpu = open_gpu(adapter)?;
    let i = gpu.adapter.get_info();
    println!("adapter:  {}", i.name);
    println!("backend:  {:?}", i.backend);
    println!("type:     {:?}", i.device_type);
    println!("driver:   {} {}", i.driver, i.driver_info);
    let f = gpu.device.features();
    for (name, feature) in [
        ("SHADER_INT64", wgpu::Features::SHADER_INT64),
        ("SHADER_INT64_ATOMIC_MIN_MAX", wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX),
        ("TIMESTAMP_QUERY", wgpu::Features::TIMESTAMP_QUERY),
    ] {
        println!("feature:  {name}: {}", if f.contains(feature) { "yes" } else { "no" });
    }
    let l = gpu.device.limits();
    println!("limit:    max storage buffer binding {} bytes", l.max_storage_buffer_binding_size);
    let renderer = Renderer::new(&gpu.device, &gpu.queue, Settings::with_size(64, 64))?;
    let path = match renderer.raster_path() {
        "int64" => "int64 (one 64-bit atomicMin per fragment)",
        _ => "int32 (depth pass, then id pass; the device lacks 64-bit atomics)",
    };
    println!("raster:   {path}; work shared out as on a {}", renderer.raster_work().name());
    Ok(())
}

/// Most frames a still camera renders for its radiosity to settle (`render` without --frames):
/// at 640x480 the original Cornell box settles after 76 frames and 2CylinderEngine after 88.
const SETTLE_MAX_FRAMES: u32 = 128;
/// Frames between two looks at the radiosity while it settles.
const SETTLE_STEP: u32 = 4;
/// The radiosity has settled when the mean irradiance of its last `SETTLE_STEP` frames differs
/// by at most this fraction from that of the `SETTLE_STEP` frames before: means over frames,
/// so that the turned slices' noise in one frame's mean (on a small image as large as the
/// change looked for) neither stops a climbing view nor keeps a settled one going.
const SETTLE_CHANGE: f64 = 0.005;
/// Frames `render` averages after the radiosity settles, unless told otherwise.
const DEFAULT_AVERAGE: u32 = 32;

/// Waits for the frames submitted, so that a progress count follows the GPU, not the queue.
fn wait_for_frame(gpu: &Gpu) -> Result<()> {
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(drop)
        .map_err(|e| Error::Gpu { label: "frame".into(), message: e.to_string() })
}

/// Writes the last frame's image, tone mapped at `exposure`, as `dir/frame_NNNN.png` (`index`).
fn write_sequence_frame(
    renderer: &Renderer,
    gpu: &Gpu,
    dir: &std::path::Path,
    index: u32,
    exposure: f32,
) -> Result<()> {
    let hdr = renderer.read_rgb(&gpu.device, &gpu.queue, renderer.hdr_buffer())?;
    let s = renderer.settings();
    let path = dir.join(format!("frame_{index:04}.png"));
    output::write_png_linear(&path, s.width, s.height, &output::tonemap(&hdr, exposure))
}

/// Renders `frames` more frames of the still `camera` after the radiosity settled, the
/// temporal filter keeping their mean ([`Renderer::settle`]); `sequence`: the folder each frame
/// is written to (`render --out-seq`), the first frame's number and the exposure.
fn average_settled(
    renderer: &mut Renderer,
    gpu: &Gpu,
    buffers: &SceneBuffers,
    camera: &Camera,
    frames: u32,
    sequence: Option<(&std::path::Path, u32, f32)>,
) -> Result<()> {
    renderer.settle();
    let bar = Progress::new(u64::from(frames), "averaged frames".into());
    for k in 0..frames {
        renderer.render(&gpu.device, &gpu.queue, buffers, camera)?;
        if let Some((dir, first, exposure)) = sequence {
            write_sequence_frame(renderer, gpu, dir, first + k, exposure)?;
        }
        wait_for_frame(gpu)?;
        bar.inc();
    }
    bar.finish();
    eprintln!("note: averaged {frames} more frames of the settled view (--average sets how many)");
    Ok(())
}

/// The mean irradiance (over pixels and channels) the composite reads from the radiosity.
fn mean_irradiance(renderer: &Renderer, gpu: &Gpu) -> Result<f64> {
    let Some(buffers) = renderer.radiosity_buffers() else { return Ok(0.0) };
    let e = renderer.read_vec4(&gpu.device, &gpu.queue, buffers.irradiance)?;
    let sum: f64 = e.iter().map(|v| f64::from(v.x + v.y + v.z)).filter(|v| v.is_finite()).sum();
    Ok(sum / (3 * e.len().max(1)) as f64)
}

#[derive(serde::Serialize)]
struct TimingsFile<'a> {
    adapter: String,
    /// The machine's load average (1, 5, 15 minutes) when the frame was timed, if known.
    load: Option<[f32; 3]>,
    width: u32,
    height: u32,
    raster_path: &'a str,
    /// How the rasterizer shared out its work (`gpu` or `cpu`).
    raster_work: &'a str,
    triangles: u32,
    /// Clipped triangles too large for one thread, rasterized by tiles.
    binned_triangles: u32,
    passes: Vec<deep_gbuffer::gpu::PassTiming>,
    /// Shadow passes the frame did not run: their maps were kept from an earlier frame.
    reused: Vec<String>,
    total_ms: f64,
}

fn render(adapter: &Option<String>, args: RenderArgs) -> Result<()> {
    if !(args.exposure.is_finite() && args.exposure > 0.0) {
        return Err(Error::InvalidSetting {
            name: "exposure",
            message: format!("{} (must be finite and > 0)", args.exposure),
        });
    }
    // Where the outputs go, before any work: a wrong path fails now, not after the frames.
    for path in [&args.out, &args.exr, &args.timings].into_iter().flatten() {
        output::check_writable(path)?;
    }
    for dir in [&args.layers, &args.out_seq].into_iter().flatten() {
        std::fs::create_dir_all(dir).map_err(|e| Error::Io { path: dir.clone(), source: e })?;
    }
    let (scene, mut camera) = args.view.scene_and_camera(&args.scene, args.size, &args.limits)?;
    let mut settings = scaled_defaults(&scene);
    settings.width = args.size.0;
    settings.height = args.size.1;
    let (w, h) = args.size;
    let auto_shadows = ShadowSettings::resolution_for(w, h, &camera, scene.bounds());
    settings.shadows.resolution = args.shadow_resolution.unwrap_or(auto_shadows);
    settings.dz = args.dz.unwrap_or(settings.dz);
    settings.layer1 = args.layer1;
    settings.atomics = args.atomics;
    settings.raster_work = args.raster_work;
    settings.ao.enabled = !args.no_ao;
    settings.radiosity.normalization = args.normalization;
    settings.radiosity.boost = args.boost;
    settings.effects = Effects::parse(&args.effects)?;
    if let Some(preset) = args.preset {
        preset.apply(&mut settings);
    }
    if let Some(p) = args.precision {
        settings.precision = p;
    }
    settings.position = args.position_encoding;
    args.estimators.apply(&mut settings);
    settings.validate()?;
    let gpu = open_gpu(adapter)?;
    if args.shadow_resolution.is_none() {
        // The default, as large as the device holds for all the lights' faces.
        let faces = deep_gbuffer::frame::light_faces(&SceneInfo::of(&scene), 16, (0, 0, 0))
            .iter()
            .map(|l| l.faces.len())
            .sum();
        let l = gpu.device.limits();
        let limit = l.max_storage_buffer_binding_size.min(l.max_buffer_size);
        settings.shadows.resolution = ShadowSettings::within(auto_shadows, faces, limit);
    }
    let buffers = SceneBuffers::upload(&gpu.device, &scene)?;
    let mut renderer = Renderer::new(&gpu.device, &gpu.queue, settings.clone())?;
    if let Some(path) = &args.environment {
        renderer.set_environment(&gpu.device, Some(&Environment::load_exr(path)?))?;
    }
    if args.plan {
        // The plan alone: what a frame would run, without rendering one.
        println!("{}", renderer.plan(&buffers, &camera));
        return Ok(());
    }
    if args.frames == Some(0) || !args.orbit.is_finite() {
        return Err(Error::InvalidSetting {
            name: "frames",
            message: "at least one frame, and a finite orbit".into(),
        });
    }
    // Without --frames, a still camera renders until the temporal radiosity settles, and at
    // least until its obscurance has averaged its still frames (`AoSettings::still_frames`).
    let plan = renderer.plan(&buffers, &camera);
    let still = args.orbit == 0.0 && args.moving.is_none();
    let ao_frames = if still && plan.runs(Effect::Ao) { 1 + settings.ao.still_frames } else { 1 };
    let settle = args.frames.is_none() && plan.runs(Effect::Radiosity);
    let frames =
        args.frames.unwrap_or(if settle { SETTLE_MAX_FRAMES.max(ao_frames) } else { ao_frames });
    if args.frames.is_none() && !settle && ao_frames > 1 {
        eprintln!(
            "note: the obscurance averages {} still frames (--frames sets a count)",
            ao_frames - 1
        );
    }
    // The mean irradiance of the frames since the last look, and the last look's.
    let mut window = 0.0;
    let mut last_mean: Option<f64> = None;
    let start = camera.clone();
    let moving = match &args.moving {
        Some((name, by)) => Some((scene.material_named(name)?, *by)),
        None => None,
    };
    let bar = (frames > 1).then(|| Progress::new(u64::from(frames), "frames".into()));
    for i in 0..frames {
        let turn = if frames > 1 { i as f32 / (frames - 1) as f32 } else { 0.0 };
        camera = start.orbited(args.orbit * turn);
        if let Some((material, by)) = moving {
            let back = (frames - 1 - i) as f32;
            buffers.write_positions(&gpu.queue, &scene.positions_moved(material, -by * back)?)?;
            renderer.geometry_changed();
        }
        renderer.render(&gpu.device, &gpu.queue, &buffers, &camera)?;
        if let Some(dir) = &args.out_seq {
            write_sequence_frame(&renderer, &gpu, dir, i, args.exposure)?;
        }
        if let Some(bar) = &bar {
            wait_for_frame(&gpu)?;
            bar.inc();
        }
        if settle {
            window += mean_irradiance(&renderer, &gpu)? / f64::from(SETTLE_STEP);
        }
        if settle && (i + 1).is_multiple_of(SETTLE_STEP) {
            let mean = std::mem::take(&mut window);
            let settled = i + 1 >= ao_frames
                && last_mean.is_some_and(|m| (mean - m).abs() <= SETTLE_CHANGE * mean);
            if settled || i + 1 == frames {
                if let Some(bar) = &bar {
                    bar.finish();
                }
                let how = if settled { "settled" } else { "stopped unsettled" };
                eprintln!(
                    "note: the radiosity {how} after {} frames (--frames sets a count)",
                    i + 1
                );
                if settled && args.average > 0 {
                    let sequence = args.out_seq.as_deref().map(|d| (d, i + 1, args.exposure));
                    average_settled(
                        &mut renderer,
                        &gpu,
                        &buffers,
                        &camera,
                        args.average,
                        sequence,
                    )?;
                }
                break;
            }
            last_mean = Some(mean);
        }
    }
    if let Some(bar) = &bar {
        bar.finish();
    }
    let layer_count = renderer.last_plan().map_or(1, |p| p.layers as usize);
    let layers = (0..layer_count)
        .map(|l| renderer.read_gbuffer(&gpu.device, &gpu.queue, l))
        .collect::<Result<Vec<_>>>()?;
    let diagnostics = renderer.diagnostics(&gpu.device, &gpu.queue)?;
    for line in diagnostics.warnings() {
        eprintln!("warning: {line}");
    }
    let (w, h) = (settings.width, settings.height);
    let terms = renderer.read_terms(&gpu.device, &gpu.queue)?;
    if let Some(dir) = &args.layers {
        output::write_layers(dir, &layers)?;
        if let Some(av) = &terms.av {
            let grey: Vec<Vec3> = av.iter().map(|&v| Vec3::splat(v)).collect();
            output::write_png_display(&dir.join("ao.png"), w, h, &grey)?;
            output::write_exr(&dir.join("ao.exr"), w, h, &grey)?;
        }
        // Each lighting term alone, tone mapped like the image: direct radiance, the radiosity
        // term as the composite adds it, and the indirect irradiance it comes from (what
        // `truth --effect indirect` traces), and the reflected radiance (`--effect reflections`).
        let lit = [
            ("direct", Some(&terms.direct)),
            ("radiosity", terms.radiosity.as_ref()),
            ("indirect", terms.indirect.as_ref()),
            ("reflections", terms.reflections.as_ref()),
        ];
        for (name, term) in lit {
            let Some(term) = term else { continue };
            let png = dir.join(format!("{name}.png"));
            output::write_png_linear(&png, w, h, &output::tonemap(term, args.exposure))?;
            output::write_exr(&dir.join(format!("{name}.exr")), w, h, term)?;
        }
    }
    let image = terms.hdr;
    if let Some(path) = &args.out {
        output::write_png_linear(path, w, h, &output::tonemap(&image, args.exposure))?;
    }
    if let Some(path) = &args.exr {
        output::write_exr(path, w, h, &image)?;
    }
    if let Some(path) = &args.timings {
        let passes = renderer.timings(&gpu.device)?;
        if renderer.passes().is_empty() {
            eprintln!(
                "note: the last frame kept every pass from the frames before (a settled still \
                 view); the timings list is empty and `reused` names them"
            );
        } else if passes.is_empty() {
            eprintln!("warning: the device has no timestamp queries; the timings list is empty");
        }
        let file = TimingsFile {
            adapter: gpu.adapter.get_info().name,
            load: deep_gbuffer::gpu::load_average(),
            width: w,
            height: h,
            raster_path: renderer.raster_path(),
            raster_work: renderer.raster_work().name(),
            triangles: buffers.triangle_count(),
            binned_triangles: diagnostics.large_triangles,
            // (A float sum of nothing is -0.)
            total_ms: passes.iter().fold(0.0, |sum, p| sum + p.ms),
            passes,
            reused: renderer
                .last_plan()
                .map(|p| p.reused.iter().map(|r| r.name().into_owned()).collect())
                .unwrap_or_default(),
        };
        let json = serde_json::to_string_pretty(&file).expect("plain data serializes");
        output::write_bytes(path, json.as_bytes())?;
    }
    if args.out.is_none() && args.exr.is_none() && args.layers.is_none() && args.timings.is_none() {
        eprintln!("rendered {w}x{h}; nothing written (give --out, --exr, --layers or --timings)");
    }
    Ok(())
}

fn main() -> ExitCode {
    private_runtime_dir();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return argument_error(e),
    };
    let result = match cli.command {
        Command::Render(args) => render(&cli.adapter, *args),
        Command::Info => info(&cli.adapter),
        Command::Truth(args) => truth(&cli.adapter, *args),
        Command::Sweep(args) => sweep(&cli.adapter, *args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Help and version print as asked (exit 0); a wrong argument is one line, `error: ...` and
/// where to look, with exit code 1 like every other error.
fn argument_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            let _ = e.print();
            ExitCode::SUCCESS
        }
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = e.print();
            ExitCode::FAILURE
        }
        _ => {
            let text = e.render().to_string();
            // The first paragraph: the message, and what clap puts on the lines below it (the
            // arguments missing, the values an enumerated option takes).
            let paragraph: Vec<&str> = text
                .lines()
                .map(str::trim)
                .skip_while(|l| l.is_empty())
                .take_while(|l| !l.is_empty())
                .collect();
            let joined = paragraph.join(" ");
            let line = joined.trim_end_matches('.');
            let line = match line {
                "" => "error: bad arguments".to_string(),
                l if l.starts_with("error:") => l.to_string(),
                l => format!("error: {l}"),
            };
            eprintln!("{line} (`--help` lists the options)");
            ExitCode::FAILURE
        }
    }
}

/// Mesa's window-system layer warns on every run when `XDG_RUNTIME_DIR` is unset or not a
/// directory, though this program opens no window: give it a private one (mode 700) in the
/// temporary folder.
fn private_runtime_dir() {
    let usable =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if usable {
        return;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::{DirBuilderExt, MetadataExt};
        let uid = std::fs::metadata("/proc/self").map(|m| m.uid()).unwrap_or(0);
        let dir = std::env::temp_dir().join(format!("deep-gbuffer-runtime-{uid}"));
        // Made now or by an earlier run; used only while it is ours and private.
        let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        let private = std::fs::symlink_metadata(&dir)
            .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.mode() & 0o077 == 0);
        if private {
            // SAFETY: called first thing in `main`, before any thread is started, so nothing
            // reads the environment concurrently.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}
