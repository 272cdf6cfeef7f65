//! Settings of a [`Renderer`](crate::Renderer).

use crate::{Error, Result};

/// Largest image side: the rasterizer's fixed-point coordinates stay within the guard band's
/// bound ([`GUARD_BAND_PIXELS`](crate::frame::GUARD_BAND_PIXELS)).
pub const MAX_IMAGE_SIDE: u32 = 16_384;

/// How layer 1 (the nearest surface at least Δz behind layer 0) is rasterized.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(serde::Serialize)]
pub enum Layer1Variant {
    /// Exact: a second raster pass against this frame's final layer 0.
    #[default]
    TwoPass,
    /// One pass for both layers, layer 1 against the previous frame's layer 0 at the same pixel.
    Previous,
    /// One pass, layer 1 against the previous frame's layer 0 at the fragment's reprojected
    /// position (as in the paper).
    Reproject,
    /// One pass, layer 1 against a layer 0 the frame before drew from this frame's predicted
    /// camera: the last camera motion repeated (view matrix `V_t V_{t-1}^-1 V_t`; exact for a
    /// camera moving at constant linear and angular velocity). Costs a layer-0 raster per frame
    /// (`raster.next`); geometry that moved since the last frame
    /// ([`Renderer::geometry_changed`](crate::Renderer::geometry_changed)) is drawn moved on as
    /// it moved (each vertex at `2 p_t - p_{t-1}`).
    Predict,
    /// One pass with one frame of latency: each frame draws the layer 0 of the camera it is
    /// given (`raster.next`) and shows the camera given the frame before, whose layer 0 is then
    /// known exactly, so layer 1 is the two-pass one. The image of a frame belongs to the camera
    /// before ([`Renderer::image_camera`](crate::Renderer::image_camera) says which; the first
    /// frame shows its own camera, the second that one again). Moving objects must be moved a
    /// frame late too for the separation to stay exact.
    Delay,
}

/// How the G-buffer stores its attributes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(serde::Serialize)]
pub enum Precision {
    /// f32 everything: 64 bytes per pixel per layer.
    #[default]
    Full,
    /// Octahedral 16-bit normals, 8-bit colours, 16-bit floats: 32 bytes per pixel per layer.
    /// Depth stays f32.
    Packed,
}

impl Precision {
    /// The encoding's name, as `--precision` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Precision::Full => "full",
            Precision::Packed => "packed",
        }
    }

    /// The WGSL defines of this encoding (`PACKED` or none).
    pub fn defines(self) -> Vec<&'static str> {
        match self {
            Precision::Full => Vec::new(),
            Precision::Packed => vec!["PACKED"],
        }
    }
}

/// How the G-buffer stores where a surface is (the G-buffer precision study's question). Every
/// kernel reconstructs a surface's view-space position from its pixel centre and the view depth
/// it reads back, so an encoding matters through the depth it gives back: the resolve stores
/// the depth as the encoding would hold it, and every later pass sees that. The visibility
/// buffer keeps exact f32 depths (the raster and its layer test do not change).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(serde::Serialize)]
pub enum PositionEncoding {
    /// The view depth as an f32 (4 bytes); x and y from the pixel. Exact.
    #[default]
    ViewDepthF32,
    /// The post-perspective position (x/w, y/w, z/w) mapped to [0, 1] in three 16-bit integers
    /// (6 bytes), the depth recovered through the inverse of the projection: its error grows
    /// with the square of the depth for a perspective camera (1/z is what z/w spaces evenly).
    ScreenU16,
    /// The view-space position as three binary16 floats (6 bytes): a relative error of at most
    /// 2^-11 at any depth; depths past 65504 are held at 65504.
    ViewF16,
}

impl PositionEncoding {
    /// The encoding's name, as `--position-encoding` spells it.
    pub fn name(self) -> &'static str {
        match self {
            PositionEncoding::ViewDepthF32 => "view-depth-f32",
            PositionEncoding::ScreenU16 => "screen-u16",
            PositionEncoding::ViewF16 => "view-f16",
        }
    }

    /// Bytes the encoding takes per pixel and layer.
    pub fn bytes(self) -> u32 {
        match self {
            PositionEncoding::ViewDepthF32 => 4,
            PositionEncoding::ScreenU16 | PositionEncoding::ViewF16 => 6,
        }
    }
}

/// How the obscurance pass estimates `1 - (1/pi) integral max(1 - d^2/r^2, 0) cos(theta) dw`
/// (`wgsl/ao.wgsl`, documented there).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(serde::Serialize)]
pub enum AoEstimator {
    /// Scalable Ambient Obscurance's sum over spiral taps (each layer's larger term), with its
    /// normalisation `2 / N`: it under-occludes creases and contacts whatever the tap count.
    Sao,
    /// Slices through the view direction, each marching the depth pyramid on both sides; every
    /// surface seen is a height field (solid behind it). The cosine-weighted arc each tap hides
    /// is counted once, at the falloff of the first surface that hides it, in closed form: the
    /// estimate converges to the integral as slices and steps grow wherever the scene is a
    /// height field.
    Horizon,
    /// As `horizon`, but a surface is solid only `thickness` behind itself, and no deeper than
    /// the next layer's surface at that pixel, which is solid behind itself in turn (no deeper
    /// than the gap between the two): thin objects in front of others stop hiding them.
    #[default]
    Bitmask,
}

impl AoEstimator {
    /// The estimator's name, as `--ao-estimator` spells it.
    pub fn name(self) -> &'static str {
        match self {
            AoEstimator::Sao => "sao",
            AoEstimator::Horizon => "horizon",
            AoEstimator::Bitmask => "bitmask",
        }
    }
}

/// Named accuracy levels, chosen from the Pareto fronts that `deep-gbuffer sweep` measured on the
/// shipped scenes (README, *Accuracy and cost*). Each sets the obscurance's estimator, taps,
/// slices and blur radius, the radiosity's taps, the number of layers the effects read and the
/// G-buffer encoding (full: the packed encoding measured no faster on lavapipe; it halves the
/// G-buffer's memory), whether reflections follow rays through the shadow maps (all but
/// `Low`), and the slices a moving view's radiosity takes a frame with its filter's weight (one
/// of two under 0.9 up to `Balanced`; every slice under 0.85 from `High` on, as they were
/// measured: a moving view's light lags less, for more time); the rest stays as given.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(serde::Serialize)]
pub enum Preset {
    /// `bitmask` obscurance and `slices` radiosity with 32 taps each, both at half resolution,
    /// layer 0 only: the cheapest point of both fronts (below the error of 16 taps at full
    /// resolution, in less time); reflections on screen only (no rays followed through the
    /// shadow maps, [`ReflectionSettings::shadow_maps`]).
    Low,
    /// 32 obscurance and 32 radiosity taps, both layers: the defaults.
    Balanced,
    /// 64 obscurance taps on 4 slices with a blur of radius 3, and 32 radiosity taps, both
    /// layers: a lower obscurance error and less obscurance flicker than the same taps on 2
    /// slices with the default blur, on each of the three scenes measured (more slices leave
    /// less of the slices' pattern for the blur to remove, and a narrower blur keeps detail).
    High,
    /// `High`'s obscurance and 64 radiosity taps, both layers: the lowest errors and the least
    /// radiosity flicker measured.
    Ultra,
}

impl Preset {
    /// Applies the preset's knobs to `settings` (the radiosity on 2 slices, one of them a moving
    /// frame up to `Balanced`; the obscurance on 2, or 4 with a narrower blur from `High` on).
    pub fn apply(self, settings: &mut Settings) {
        let blur = AoSettings::default().blur_radius;
        // Obscurance taps, slices and blur radius, radiosity taps, layers, resolution divisor.
        let (ao, ao_slices, ao_blur, radiosity, layers, downsample) = match self {
            Preset::Low => (32, 2, blur, 32, 1, 2),
            Preset::Balanced => (32, 2, blur, 32, 2, 1),
            Preset::High => (64, 4, 3, 32, 2, 1),
            Preset::Ultra => (64, 4, 3, 64, 2, 1),
        };
        settings.ao.downsample = downsample;
        settings.radiosity.downsample = downsample;
        settings.ao.estimator = AoEstimator::Bitmask;
        settings.ao.samples = ao;
        settings.ao.slices = ao_slices;
        settings.ao.blur_radius = ao_blur;
        settings.ao.two_layers = layers == 2;
        settings.radiosity.estimator = RadiosityEstimator::Slices;
        settings.radiosity.samples = radiosity;
        settings.radiosity.slices = 2;
        // Every slice under the filter weight `High` and `Ultra` were measured with (0.85), or
        // the defaults' one slice a moving frame under theirs.
        let every_slice = matches!(self, Preset::High | Preset::Ultra);
        let defaults = RadiositySettings::default();
        (settings.radiosity.history_slices, settings.radiosity.alpha) =
            if every_slice { (0, 0.85) } else { (defaults.history_slices, defaults.alpha) };
        // Two layers where an effect reads them (the plan decides), never forced on a scene
        // that needs none.
        settings.layers = if layers == 1 { 1 } else { 0 };
        settings.precision = Precision::Full;
        settings.reflections.shadow_maps = self != Preset::Low;
    }
}

/// Which atomics the rasterizer uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(serde::Serialize)]
pub enum AtomicPath {
    /// 64-bit atomics when the device has them, else 32-bit.
    #[default]
    Auto,
    /// One 64-bit `atomicMin` per fragment (needs `SHADER_INT64_ATOMIC_MIN_MAX`).
    Int64,
    /// Two passes of 32-bit atomics (depth, then id); runs everywhere.
    Int32,
}

/// How the rasterizer shares out its work (`wgsl/raster.wgsl`); every choice draws the same
/// visibility buffers, bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(serde::Serialize)]
pub enum RasterWork {
    /// By the device's type: `cpu` for a CPU driver, `gpu` for every other device.
    #[default]
    Auto,
    /// For a GPU, which runs thousands of threads and skips a branch no thread of a wave takes:
    /// triangles up to 16 pixels across drawn by their own thread, a binned triangle spread at 8
    /// of its 16x16 tiles a workgroup, tiles wholly outside it skipped before the exact test,
    /// and the early depth test (a load of the word before the atomic, which spares the atomic
    /// where the fragment cannot win; on the 64-bit path where the device loads 64-bit atomics).
    Gpu,
    /// For a CPU driver, which runs a few threads and every branch: up to 64 pixels by one
    /// thread, 64 tiles a workgroup, no tile test (it would cost every pixel and skip none), and
    /// no early depth test (such a driver reads a storage buffer lane by lane, so the load costs
    /// about what the atomic it spares does).
    Cpu,
}

impl RasterWork {
    /// Its name, as `--raster-work` spells it.
    pub fn name(self) -> &'static str {
        match self {
            RasterWork::Auto => "auto",
            RasterWork::Gpu => "gpu",
            RasterWork::Cpu => "cpu",
        }
    }
}

/// Ambient obscurance (`wgsl/ao.wgsl`, documented there with its exact estimator).
#[derive(Clone, Debug, PartialEq)]
pub struct AoSettings {
    /// Run the obscurance passes.
    pub enabled: bool,
    /// The estimator.
    pub estimator: AoEstimator,
    /// Slices per pixel of the `horizon` and `bitmask` estimators (each turned per pixel); their
    /// `samples` taps are shared among the slices, half on each side. 1 to 16.
    pub slices: u32,
    /// How far an occluder reaches behind its visible surface, as a fraction of `radius`
    /// (`bitmask`): relative, so that it follows the scale the radius is chosen for. Layer 0's
    /// no deeper than layer 1's surface, layer 1's no deeper than the gap in front of it.
    pub thickness: f32,
    /// World-space radius of the neighbourhood, in scene units.
    pub radius: f32,
    /// Taps per pixel.
    pub samples: u32,
    /// Weight k of the steps' extrapolation (`horizon`, `bitmask`): each slice's obscurance is
    /// `O + k (O - O_half)`, `O_half` what every other step alone finds (Richardson's
    /// extrapolation in the steps a side). Steps spaced apart miss the tops of what rises
    /// between them, so the obscurance falls short of the truth's by an amount that shrinks
    /// as the steps grow, between `steps^-1.4` and `steps^-2` on the scenes measured;
    /// `k = 1 / (2^1.4 - 1) = 0.6` removes the slower of those to first order, at no extra
    /// pyramid read (k = 1 over-obscured the Cornell box). 0: the plain estimate. 0 to 2.
    pub extrapolation: f32,
    /// Bias β, in scene units: each tap's point is lowered by β along the normal before it is
    /// tested against the tangent plane (suppresses self-occlusion on tessellated curves); its
    /// falloff keeps its true distance. 0.001 at the Cornell box's scale (a five-hundredth of the
    /// radius): ten times that, Scalable Ambient Obscurance's value, gave a higher RMSE on 12
    /// of the 14 scenes, cameras and sizes measured (docs/accuracy.md, *The obscurance's bias*).
    pub bias: f32,
    /// Scale of the obscurance sum.
    pub intensity: f32,
    /// Take each tap's larger contribution from both layers (the deep G-buffer estimator);
    /// `false` reads layer 0 only.
    pub two_layers: bool,
    /// Radius of the bilateral blur in pixels (0: no blur). It removes the pattern of the
    /// slices' turns and keeps to each surface (depth, normal, and within a pixel's footprint
    /// of the centre's tangent plane), but also averages each pixel with neighbours on its
    /// surface whose obscurance differs, so
    /// more slices (a finer pattern) want a narrower blur: 4 on 2 slices, 3 on 4 (the `High`
    /// preset), 2 at 128 taps on 4 slices measured lowest on a dense scene (README, *`high`
    /// re-picked*).
    pub blur_radius: u32,
    /// How far below the tap distance the depth pyramid is read: a tap at distance h pixels
    /// reads level floor(log2 h) - `mip_offset` (the paper's log q'); smaller reads coarser
    /// levels (faster, cache-friendlier, blurrier depth), larger finer ones. 0 to 8.
    pub mip_offset: u32,
    /// Compute the obscurance at 1 / `downsample` of the image's width and height (1, 2 or 4),
    /// each value at a real pixel of its block, and fill in the rest with a depth- and
    /// normal-aware upsample (`wgsl/upsample.wgsl`).
    pub downsample: u32,
    /// Weight alpha in [0, 1) of the history in the obscurance's temporal filter
    /// (`wgsl/temporal.wgsl`, `ao.temporal`); 0: no filter, each frame of a moving view alone (a
    /// still view still averages its frames: [`still_frames`](Self::still_frames)). With it the
    /// slices (`horizon`, `bitmask`) turn every frame, and the filter averages what each frame's
    /// directions found at the same surface point over about `(1 + alpha) / (1 - alpha)` frames.
    pub alpha: f32,
    /// Slices the `horizon` and `bitmask` estimators take in a frame that has the temporal
    /// filter's history (0, or [`slices`](Self::slices) and above: all of them), each with the
    /// same steps a side: the history holds what the others would find, and the pass costs
    /// about `history_slices / slices` of its time on every frame but a first one.
    pub history_slices: u32,
    /// How far (view depth, scene units) the previous frame's layer 0 may lie from a point's
    /// surface for the point to keep its history (scaled with the scene, as the radius is).
    pub history_tolerance: f32,
    /// Frames a still view goes on computing the obscurance, the slices (or the spiral) turned
    /// each frame and each frame weighed as one of the mean of the frames since the view stood
    /// still (with the temporal filter, once that weighs more than `alpha`), before it keeps
    /// the result: a still view's AV converges toward the estimator's with this many times the
    /// slices, and the blur narrows as the mean grows ([`blur_radius_for`](Self::blur_radius_for)).
    /// Without the filter a moving view's frames stand alone. 0: a still view keeps its first
    /// frame's AV (and, without the filter, the renderer keeps no history: two f32 images
    /// fewer).
    pub still_frames: u32,
}

impl Default for AoSettings {
    fn default() -> Self {
        AoSettings {
            enabled: true,
            estimator: AoEstimator::default(),
            slices: 2,
            thickness: 0.75,
            radius: 0.5,
            samples: 32,
            bias: 0.001,
            extrapolation: 0.6,
            intensity: 1.0,
            two_layers: true,
            blur_radius: 4,
            mip_offset: 3,
            downsample: 1,
            alpha: 0.0,
            history_slices: 0,
            history_tolerance: 0.0001,
            still_frames: 16,
        }
    }
}

impl AoSettings {
    /// Whether the temporal filter runs (`ao.temporal`): `alpha` above 0.
    pub fn temporal(&self) -> bool {
        self.alpha > 0.0
    }

    /// Whether the `still`-th still frame in a row (1: the first that repeats the view) computes
    /// the obscurance again rather than keeping the last frame's: the first
    /// [`still_frames`](Self::still_frames).
    pub fn runs_when_still(&self, still: u32) -> bool {
        still <= self.still_frames
    }

    /// The temporal filter's weight of the history on the `still`-th still frame in a row (0:
    /// the camera or the scene moved, or a first frame): with the filter `alpha`, and on a
    /// still frame `max(alpha, 1 - 1 / (still + 1))`, the mean of the frames since the view
    /// stood still (the moving frames' history counting as one); without it 0 on a moving
    /// frame and `1 - 1 / still` on a still one, the mean of the still frames (a moving frame
    /// keeps no history).
    pub fn history_weight(&self, still: u32) -> f32 {
        if still == 0 {
            return self.alpha;
        }
        if !self.temporal() {
            return 1.0 - 1.0 / still as f32;
        }
        self.alpha.max(1.0 - 1.0 / (still as f32 + 1.0))
    }

    /// The blur's radius over a mean of `averaged` frames (1: a frame alone): `blur_radius /
    /// sqrt(averaged)`, rounded, at least 1 (0 stays 0). The blur removes the pattern of the
    /// slices' turns and their noise; the mean of frames whose slices turned removes them too,
    /// so the blur narrows to average as many samples as it did over one frame and stops
    /// averaging a pixel with neighbours whose obscurance differs (*The obscurance over time*,
    /// README).
    pub fn blur_radius_for(&self, averaged: f32) -> u32 {
        if self.blur_radius == 0 || averaged.is_nan() || averaged <= 1.0 {
            return self.blur_radius;
        }
        (self.blur_radius as f32 / averaged.sqrt()).round().max(1.0) as u32
    }

    /// The slices and taps of a frame's obscurance: all of them without the `history`, else
    /// [`history_slices`](Self::history_slices) of the slices with the same steps a side
    /// (the slice estimators with the temporal filter only).
    pub fn frame_taps(&self, history: bool) -> (u32, u32) {
        let some = self.history_slices;
        if !history || !self.temporal() || self.estimator == AoEstimator::Sao {
            return (self.slices, self.samples);
        }
        history_slice_taps(self.slices, some, self.samples)
    }

    /// How deep an occluder's solid reaches behind its surface, in scene units: `thickness`
    /// times the radius for `bitmask`, 0 (without end) for `horizon` (and unused by `sao`).
    pub fn solid_depth(&self) -> f32 {
        match self.estimator {
            AoEstimator::Bitmask => self.thickness * self.radius,
            AoEstimator::Horizon | AoEstimator::Sao => 0.0,
        }
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(Error::setting(
                "ao.radius",
                format!("{} (must be finite and > 0)", self.radius),
            ));
        }
        if self.samples == 0 || self.samples > 256 {
            return Err(Error::setting(
                "ao.samples",
                format!("{} (must be 1 to 256)", self.samples),
            ));
        }
        if !(self.bias.is_finite() && self.bias >= 0.0) {
            return Err(Error::setting(
                "ao.bias",
                format!("{} (must be finite and >= 0)", self.bias),
            ));
        }
        if !(self.extrapolation.is_finite() && (0.0..=2.0).contains(&self.extrapolation)) {
            return Err(Error::setting(
                "ao.extrapolation",
                format!("{} (must be 0 to 2)", self.extrapolation),
            ));
        }
        if !(self.intensity.is_finite() && self.intensity >= 0.0) {
            return Err(Error::setting(
                "ao.intensity",
                format!("{} (must be finite and >= 0)", self.intensity),
            ));
        }
        if !(1..=16).contains(&self.slices) {
            return Err(Error::setting("ao.slices", format!("{} (must be 1 to 16)", self.slices)));
        }
        if !(self.thickness.is_finite() && self.thickness > 0.0) {
            return Err(Error::setting(
                "ao.thickness",
                format!("{} (must be finite and > 0)", self.thickness),
            ));
        }
        if self.mip_offset > 8 {
            return Err(Error::setting(
                "ao.mip_offset",
                format!("{} (at most 8)", self.mip_offset),
            ));
        }
        check_downsample("ao.downsample", self.downsample)?;
        if self.blur_radius > 32 {
            return Err(Error::setting(
                "ao.blur_radius",
                format!("{} (at most 32)", self.blur_radius),
            ));
        }
        if !(self.alpha >= 0.0 && self.alpha < 1.0) {
            return Err(Error::setting("ao.alpha", format!("{} (must be in [0, 1))", self.alpha)));
        }
        if self.history_slices > 16 {
            return Err(Error::setting(
                "ao.history_slices",
                format!("{} (must be 0 to 16)", self.history_slices),
            ));
        }
        if !(self.history_tolerance.is_finite() && self.history_tolerance >= 0.0) {
            return Err(Error::setting(
                "ao.history_tolerance",
                format!("{} (must be finite and >= 0)", self.history_tolerance),
            ));
        }
        Ok(())
    }
}

/// Screen-space radiosity (`wgsl/radiosity.wgsl`, documented there).
#[derive(Clone, Debug, PartialEq)]
pub struct RadiositySettings {
    /// Run the radiosity passes.
    pub enabled: bool,
    /// The gather.
    pub estimator: RadiosityEstimator,
    /// Slices per pixel of the `slices` gather, its taps shared among them. 1 to 16.
    pub slices: u32,
    /// How far a surface reaches behind itself, as a fraction of `radius` (`slices`; as
    /// [`AoSettings::thickness`]).
    pub thickness: f32,
    /// World-space gather radius, in scene units. The `slices` steps spread over the radius or
    /// the part of it on screen, so a radius past the screen's edge costs nothing more; 3 (1.5
    /// times the reference extent, [`Settings::REFERENCE_EXTENT`]) lets the floor of a room
    /// that size gather from its ceiling.
    pub radius: f32,
    /// Taps per pixel.
    pub samples: u32,
    /// Damping delta in (0, 1] of the indirect light fed back for the next bounce.
    pub damping: f32,
    /// Weight alpha in [0, 1) of the history in the temporal filter while the camera or the
    /// scene moves. A view that stands still takes [`still_alpha`](Self::still_alpha) until its
    /// bounces settle and then averages ([`history_weight`](Self::history_weight)).
    pub alpha: f32,
    /// Weight in [0, 1) of the history in the temporal filter while the view stands still,
    /// until its bounces settle. Each frame carries the next bounce a step further, leaving
    /// `c = a + (1 - a) feedback_gain` of the way to the fixed point (0.94 at 0.7, against
    /// 0.97 at 0.85, the weight a still view took before, and 0.98 at `alpha`'s 0.9), so a
    /// lower weight reaches the multi-bounce light in fewer frames for more of each frame's
    /// noise (`sqrt((1 - a) / (1 + a))` of one frame's, which the average after settling
    /// removes): at 0.7 the 32nd still frame of 2CylinderEngine reads 0.90 of the ten-bounce
    /// truth against 0.81 at 0.85, and its frame-to-frame change is about twice as large
    /// (README, *A still view's faster filter*). `alpha` itself: no change when the view stops.
    pub still_alpha: f32,
    /// History is kept where the previous layer 0 (whose irradiance the history holds) lies
    /// within this distance (scene units, along the previous view axis) of the point's surface
    /// at the centre of the pixel the point fell in: its tangent plane there, as far as a
    /// surface at that slope runs from the point (a point hidden last frame has no history).
    pub history_tolerance: f32,
    /// Take a surface's outgoing light only where it faces the gathering point (w.n_Y < 0).
    /// `spiral`: other taps do not count. `slices`: a surface facing away still hides what lies
    /// behind it, and sends what its far side sends instead of what the camera sees of it: its
    /// emission and the indirect light it reflects (none on the first frame, and none from
    /// layer 1 without its gather, [`layer1_samples`](Self::layer1_samples)), not its direct
    /// light (a sphere lit from above, seen from the ground beside it, shows the ground its dark
    /// side). With it, `slices` also lets a curved surface send the side the gathering point
    /// sees: a point facing it less squarely than the point before it on one bending surface
    /// sends that point's light, and a point starting a surface at a grazing angle, on a surface
    /// that bends away, blends towards its far side's light (`wgsl/radiosity.wgsl`, *Curved
    /// surfaces*). Off, every surface sends its visible side's light both ways.
    pub normal_test: bool,
    /// Radius of the bilateral blur after the temporal filter, in pixels (0: none).
    pub blur_radius: u32,
    /// Turn the tap spiral (or the slices and their steps' jitter) every frame, so the temporal
    /// filter averages different taps (less noise, a little flicker); off, a static camera
    /// converges to a fixed point.
    pub jitter: bool,
    /// How the counted taps are normalised into irradiance (`spiral` only).
    pub normalization: Normalization,
    /// Colour boost of the light a surface reflects into B; [`Boost::ONE`] conserves energy.
    pub boost: Boost,
    /// How far below the tap distance the gather source is read: a tap h pixels away reads
    /// level floor(log2 h) - `mip_offset` of its MIP chain (as [`AoSettings::mip_offset`]);
    /// smaller reads coarser levels (faster), larger finer ones. 0 to 8; the default 4 costs no
    /// measurable accuracy against ray-traced truth (3 and below do: README, "Radiosity").
    pub mip_offset: u32,
    /// Gather at 1 / `downsample` of the image's width and height (1, 2 or 4), each value at a
    /// real pixel of its block, and fill in the rest with a depth- and normal-aware upsample
    /// (`wgsl/upsample.wgsl`) before the temporal filter.
    pub downsample: u32,
    /// Taps per layer-1 point of a second gather (`radiosity.layer1`, at the same resolution)
    /// that finds the irradiance of the surfaces the camera does not see, so that they reflect
    /// it on the next frame's bounce; 0: none (layer 1 sends its direct light and emission
    /// alone, and a bounce that lands behind layer 0 stops there). 0 to 256; runs only where
    /// layer 1 is drawn.
    pub layer1_samples: u32,
    /// Weight k of the steps' extrapolation (`slices`): each slice's irradiance and coverage are
    /// `E + k (E - E_half)` and `c + k (c - c_half)`, the halves what every other step alone
    /// finds, as the obscurance's ([`AoSettings::extrapolation`]). Steps spaced apart leave
    /// open the directions of what stands between them (an engine's fins between two steps
    /// that land beyond them), so the light found grows with the steps; 0.6 takes the
    /// obscurance's order of convergence. 0: the plain estimate. 0 to 2.
    pub extrapolation: f32,
    /// Add the light of the surfaces that neither layer holds, as each shadow-casting light's
    /// reflective shadow map sees them (`wgsl/offscreen.wgsl`): the ceiling around a light above
    /// the screen's top, a side turned to the light and away from the camera. Runs with the
    /// shadow maps (`radiosity.offscreen`), and only where some light casts shadows.
    pub offscreen: bool,
    /// Slices a `slices` gather takes in a frame whose view moved and that has the temporal
    /// filter's history (0 or [`slices`](Self::slices) and above: all of them), each with the
    /// same steps a side, in the layer-1 gather too. The slices turn every frame
    /// ([`jitter`](Self::jitter); without it every frame takes them all), so the history holds
    /// the light the others would find, and the gather costs `history_slices / slices` of its
    /// time on every moving frame but a first one; a still view takes them all (its bounces
    /// settle and average, and one slice's noise would lower where they settle). The temporal
    /// filter averages over about `(1 + alpha) / (1 - alpha)` frames (19 at the default alpha
    /// 0.9): the mean is the same, and the noise left in the filtered light that of `slices /
    /// history_slices` times fewer taps over that many frames. The default, one of the two
    /// slices with alpha 0.9, flickers about as much as every slice with alpha 0.85 and costs
    /// the moving Cornell box's frame about 0.8 of its time, for indirect light that lags a
    /// moving camera a little more (README, "One slice a moving frame").
    pub history_slices: u32,
    /// Frames of a settled still view's mean after which the view keeps its radiosity: once
    /// the bounces have settled ([`settle_frames`](Self::settle_frames), or
    /// `Renderer::settle`) the temporal filter averages the frames since
    /// ([`history_weight`](Self::history_weight)), and after this many the still frames run no
    /// radiosity pass (the plan lists them as reused) until the view moves, keeping the mean
    /// (its noise `1 / sqrt(kept_after)` of one frame's; the default's, 256 frames, a
    /// sixteenth). 0: a still view never keeps it.
    pub kept_after: u32,
}

/// How the radiosity pass gathers irradiance from what the layers show (`wgsl/radiosity.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(serde::Serialize)]
pub enum RadiosityEstimator {
    /// Spiral taps, each counted at the cosine of its direction (as `Normalization` says), with
    /// a confidence M / N that hands the rest of the hemisphere to the ambient term.
    Spiral,
    /// The slices of the obscurance's `bitmask` estimator: each surface a step finds gives its
    /// radiance to the directions it hides first, at their true cosine-weighted solid angle
    /// (no light through a surface). The share of the hemisphere the surfaces cover is the
    /// confidence; the rest is left to the ambient term.
    #[default]
    Slices,
}

/// How the radiosity gather turns its counted taps into irradiance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[derive(serde::Serialize)]
pub enum Normalization {
    /// `E = pi * sum B(Y) (w.n_X) / sum (w.n_X)`: pi times the cosine-weighted mean radiance of
    /// the counted taps. Surroundings of uniform radiance B give exactly `pi B`, the true
    /// irradiance, whatever the taps' directions, so the estimate never exceeds what the
    /// surroundings deliver (energy is conserved pixel by pixel).
    #[default]
    Cosine,
    /// `E = 2 pi / M * sum B(Y) (w.n_X)` over the M counted taps, the paper's form. It assumes
    /// the taps' directions are uniform over the hemisphere; screen-space taps are not, and a
    /// pixel whose few counted taps all lie near its normal reads up to `2 pi B`, twice the
    /// truth.
    Paper,
}

/// The colour boost of the reflected light fed back into B:
/// `boost(rho) = unsaturated + (saturated - unsaturated) * (max rho - min rho) / max rho`, so a
/// grey surface gets `unsaturated`, a fully saturated one `saturated`. Both 1 (the default) is
/// physically based and conserves energy; larger values exaggerate colour bleeding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Boost {
    /// Factor for grey albedo.
    pub unsaturated: f32,
    /// Factor for fully saturated albedo.
    pub saturated: f32,
}

impl Boost {
    /// No boost: `boost(rho) = 1`, energy conserving.
    pub const ONE: Boost = Boost { unsaturated: 1.0, saturated: 1.0 };

    /// The boost of albedo `rho` (linear rgb).
    pub fn of(&self, rho: [f32; 3]) -> f32 {
        let max = rho[0].max(rho[1]).max(rho[2]);
        let min = rho[0].min(rho[1]).min(rho[2]);
        let saturation = if max > 0.0 { (max - min) / max } else { 0.0 };
        self.unsaturated + (self.saturated - self.unsaturated) * saturation
    }
}

impl Default for Boost {
    fn default() -> Self {
        Boost::ONE
    }
}

impl Default for RadiositySettings {
    fn default() -> Self {
        RadiositySettings {
            enabled: true,
            estimator: RadiosityEstimator::default(),
            slices: 2,
            thickness: 0.75,
            radius: 3.0,
            samples: 32,
            damping: 0.8,
            alpha: 0.9,
            still_alpha: 0.7,
            history_tolerance: 0.01,
            normal_test: true,
            blur_radius: 6,
            jitter: true,
            normalization: Normalization::Cosine,
            boost: Boost::ONE,
            mip_offset: 4,
            downsample: 1,
            layer1_samples: 8,
            extrapolation: 0.6,
            offscreen: true,
            history_slices: 1,
            kept_after: 256,
        }
    }
}

impl RadiositySettings {
    /// Still frames in a row after which the temporal filter starts to average rather than
    /// forget: the frames the bounces take to settle. Each still frame leaves at most `c =
    /// still_alpha + (1 - still_alpha) feedback_gain` of the history's distance to its fixed
    /// point (0.94 with the defaults), so after `ln(1e-3) / ln c` frames (112) less than a
    /// thousandth of it is left, and the slower filter after it costs no more than that.
    pub fn settle_frames(&self) -> u32 {
        let c = self.still_alpha + (1.0 - self.still_alpha) * self.feedback_gain();
        if !(c > 0.0 && c < 1.0) {
            return 0;
        }
        // A float-to-integer cast saturates.
        (1e-3f32.ln() / c.ln()).ceil() as u32
    }

    /// Whether the `still`-th still frame in a row of a still view (counted as the filter
    /// counts it, [`history_weight`](Self::history_weight)) keeps the radiosity of the frame
    /// before: [`kept_after`](Self::kept_after) frames of the settled mean are behind it.
    pub fn kept_when_still(&self, still: u32) -> bool {
        self.kept_after > 0 && still > self.settle_frames().saturating_add(self.kept_after)
    }

    /// The slices and taps of a frame's gathers (the `slices` of the pixel gather, its taps and
    /// the layer-1 gather's): all of them without the `history` or on the `still`-th still frame
    /// in a row (above 0), else [`history_slices`](Self::history_slices) of the slices with the
    /// same steps a side.
    pub fn frame_taps(&self, history: bool, still: u32) -> (u32, u32, u32) {
        if !history || still > 0 || !self.jitter || self.estimator != RadiosityEstimator::Slices {
            return (self.slices, self.samples, self.layer1_samples);
        }
        let (slices, samples) = history_slice_taps(self.slices, self.history_slices, self.samples);
        let (_, layer1) = history_slice_taps(self.slices, self.history_slices, self.layer1_samples);
        (slices, samples, layer1)
    }

    /// The most frames a still view's filter averages over (its history weight stops at
    /// `1 - 1/1024`, where a new frame still counts in f32).
    pub const LONGEST_AVERAGE: u32 = 1024;

    /// The temporal filter's weight of the history on the `still`-th still frame in a row (0: the
    /// camera or the scene moved, or a first frame): `alpha` at 0, then
    /// [`still_alpha`](Self::still_alpha), and past [`settle_frames`](Self::settle_frames)
    /// `max(still_alpha, 1 - 1 / (n + 1))` with `n` the frames past it (at most
    /// [`LONGEST_AVERAGE`](Self::LONGEST_AVERAGE)): the mean of the frames since, so that the
    /// gather's noise, which the turned slices make different every frame, falls as the view
    /// stands and stops flickering, where an exponential filter would keep it at
    /// `sqrt((1 - a) / (1 + a))` of one frame's. Without [`jitter`](Self::jitter) every frame
    /// gathers the same taps: there is no noise to average, and it stays `still_alpha`.
    pub fn history_weight(&self, still: u32) -> f32 {
        if still == 0 {
            return self.alpha;
        }
        if !self.jitter {
            return self.still_alpha;
        }
        let n = still.saturating_sub(self.settle_frames()).min(Self::LONGEST_AVERAGE - 1);
        self.still_alpha.max(1.0 - 1.0 / (n as f32 + 1.0))
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        if !(1..=16).contains(&self.slices) {
            return Err(Error::setting(
                "radiosity.slices",
                format!("{} (must be 1 to 16)", self.slices),
            ));
        }
        if !(self.thickness.is_finite() && self.thickness > 0.0) {
            return Err(Error::setting(
                "radiosity.thickness",
                format!("{} (must be finite and > 0)", self.thickness),
            ));
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(Error::setting(
                "radiosity.radius",
                format!("{} (must be finite and > 0)", self.radius),
            ));
        }
        if self.samples == 0 || self.samples > 256 {
            return Err(Error::setting(
                "radiosity.samples",
                format!("{} (must be 1 to 256)", self.samples),
            ));
        }
        if self.history_slices > 16 {
            return Err(Error::setting(
                "radiosity.history_slices",
                format!("{} (must be 0 to 16)", self.history_slices),
            ));
        }
        if !(self.extrapolation.is_finite() && (0.0..=2.0).contains(&self.extrapolation)) {
            return Err(Error::setting(
                "radiosity.extrapolation",
                format!("{} (must be 0 to 2)", self.extrapolation),
            ));
        }
        if self.layer1_samples > 256 {
            return Err(Error::setting(
                "radiosity.layer1_samples",
                format!("{} (must be 0 to 256)", self.layer1_samples),
            ));
        }
        if !(self.damping > 0.0 && self.damping <= 1.0) {
            return Err(Error::setting(
                "radiosity.damping",
                format!("{} (must be in (0, 1])", self.damping),
            ));
        }
        if !(self.alpha >= 0.0 && self.alpha < 1.0) {
            return Err(Error::setting(
                "radiosity.alpha",
                format!("{} (must be in [0, 1))", self.alpha),
            ));
        }
        if !(self.still_alpha >= 0.0 && self.still_alpha < 1.0) {
            return Err(Error::setting(
                "radiosity.still_alpha",
                format!("{} (must be in [0, 1))", self.still_alpha),
            ));
        }
        if self.blur_radius > 32 {
            return Err(Error::setting(
                "radiosity.blur_radius",
                format!("{} (at most 32)", self.blur_radius),
            ));
        }
        if self.mip_offset > 8 {
            return Err(Error::setting(
                "radiosity.mip_offset",
                format!("{} (at most 8)", self.mip_offset),
            ));
        }
        check_downsample("radiosity.downsample", self.downsample)?;
        if !(self.history_tolerance.is_finite() && self.history_tolerance >= 0.0) {
            return Err(Error::setting(
                "radiosity.history_tolerance",
                format!("{} (must be finite and >= 0)", self.history_tolerance),
            ));
        }
        for (name, value) in [
            ("radiosity.boost.unsaturated", self.boost.unsaturated),
            ("radiosity.boost.saturated", self.boost.saturated),
        ] {
            if !(value.is_finite() && (0.0..=16.0).contains(&value)) {
                return Err(Error::setting(name, format!("{value} (must be in [0, 16])")));
            }
        }
        let gain = self.feedback_gain();
        if gain >= 1.0 {
            return Err(Error::setting(
                "radiosity.damping",
                format!(
                    "feedback gain {gain} (normalisation factor x damping {} x largest boost) must \
                     stay below 1, or the fed-back light can grow without bound",
                    self.damping
                ),
            ));
        }
        Ok(())
    }

    /// The most the fed-back light can grow per frame: `k * damping * max boost`, with `k` = 1
    /// for the `slices` gather and for the spiral's [`Normalization::Cosine`] (each reads at
    /// most `pi max B`: a weighted mean of what it saw) and 2 for [`Normalization::Paper`] (at
    /// most `2 pi max B`), and an albedo of at most 1. Below 1 the irradiance stays below
    /// `k pi (max boost x max direct + max emission) / (1 - gain)`.
    pub fn feedback_gain(&self) -> f32 {
        let k = match (self.estimator, self.normalization) {
            (RadiosityEstimator::Slices, _) | (_, Normalization::Cosine) => 1.0,
            (RadiosityEstimator::Spiral, Normalization::Paper) => 2.0,
        };
        k * self.damping * self.boost.unsaturated.max(self.boost.saturated)
    }
}

/// Screen-space reflections (`wgsl/reflections.wgsl`).
#[derive(Clone, Debug, PartialEq)]
pub struct ReflectionSettings {
    /// Run the reflection pass where a material reflects.
    pub enabled: bool,
    /// How far a reflection ray is followed, in scene units; `f32::INFINITY` (the default):
    /// until it leaves the screen. The march is hierarchical, so its cost follows the cells the
    /// ray crosses, not this length.
    pub max_distance: f32,
    /// How far behind a surface a ray may pass and still hit it, in scene units.
    pub thickness: f32,
    /// Directions averaged over the glossy lobe (GGX, alpha = roughness^2) of a surface of
    /// roughness 0.5 or more, in 1..=64; a smoother surface takes fewer in proportion to its
    /// roughness (at least 2), and roughness 0 is a mirror. 1 traces the mirror ray alone.
    pub lobe_samples: u32,
    /// Follow the mirror rays the screen cannot place (those that find nothing on screen, run
    /// into the side of a solid the camera does not see, or hit a silhouette) through the
    /// lights' shadow maps, where the surfaces each light sees first are held, lit
    /// (`wgsl/reflections.wgsl`, `reflections_hidden`). Only where the frame draws shadow maps.
    pub shadow_maps: bool,
}

impl Default for ReflectionSettings {
    fn default() -> Self {
        ReflectionSettings {
            enabled: true,
            max_distance: f32::INFINITY,
            thickness: 0.1,
            lobe_samples: 8,
            shadow_maps: true,
        }
    }
}

impl ReflectionSettings {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        if self.max_distance.is_nan() || self.max_distance <= 0.0 {
            return Err(Error::setting(
                "reflections.max_distance",
                format!("{} (must be > 0; infinite: to the screen's edge)", self.max_distance),
            ));
        }
        if !(self.thickness.is_finite() && self.thickness > 0.0) {
            return Err(Error::setting(
                "reflections.thickness",
                format!("{} (must be finite and > 0)", self.thickness),
            ));
        }
        if !(1..=64).contains(&self.lobe_samples) {
            return Err(Error::setting(
                "reflections.lobe_samples",
                format!("{} (must be in 1..=64)", self.lobe_samples),
            ));
        }
        Ok(())
    }
}

/// Shadow maps (`src/passes/shadow.rs`).
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowSettings {
    /// Draw shadow maps for the lights that cast shadows.
    pub enabled: bool,
    /// Side of each shadow-map face in texels.
    pub resolution: u32,
    /// Percentage-closer filtering radius in texels: (2 pcf + 1)^2 taps; 0 gives hard shadows.
    pub pcf: u32,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        ShadowSettings { enabled: true, resolution: 512, pcf: 1 }
    }
}

impl ShadowSettings {
    /// The smallest and largest resolution [`resolution_for`](ShadowSettings::resolution_for)
    /// picks.
    pub const AUTO_RESOLUTION: (u32, u32) = (512, 4096);

    /// A shadow-map resolution for a `width` x `height` image of a scene with `bounds` seen by
    /// `camera`: about one texel per pixel where the scene fills the view. The scene's bounding
    /// sphere (radius r, centre at distance d from the eye) spans
    /// `N = height * r / (d * tan(fov_y / 2))` pixels (`height * 2 r / view height` for an
    /// orthographic camera; the image's larger side when the eye is inside the sphere), at most
    /// the image's larger side; the resolution is the power of two at or above N, within
    /// [`AUTO_RESOLUTION`](ShadowSettings::AUTO_RESOLUTION). A directional light's map covers
    /// the bounds, so its texels are then about as large as the pixels showing them. The
    /// device may hold fewer: see [`within`](ShadowSettings::within).
    pub fn resolution_for(
        width: u32,
        height: u32,
        camera: &crate::Camera,
        bounds: Option<(glam::Vec3, glam::Vec3)>,
    ) -> u32 {
        let (lo, hi) = Self::AUTO_RESOLUTION;
        // An image without pixels (which the settings refuse) still gets a resolution.
        let side = width.max(height).max(1) as f32;
        let Some((a, b)) = bounds else { return lo };
        let r = (b - a).length() * 0.5;
        let d = ((a + b) * 0.5 - camera.eye).length();
        let inside = !camera.is_orthographic() && d <= r;
        let n = if inside { side } else { camera.pixels_of(2.0 * r, d, height) };
        let n = if n.is_finite() { n.clamp(1.0, side) } else { side };
        (n.ceil() as u32).next_power_of_two().clamp(lo, hi)
    }

    /// Bytes of `faces` shadow-map faces at `resolution` (a visibility word, 8 bytes, a texel).
    pub fn atlas_bytes(resolution: u32, faces: usize) -> u64 {
        u64::from(resolution) * u64::from(resolution) * 8 * faces as u64
    }

    /// `resolution` halved until `faces` shadow-map faces of it
    /// ([`atlas_bytes`](ShadowSettings::atlas_bytes)) fit in `byte_limit` bytes (the device's
    /// largest storage binding), at least 16.
    pub fn within(resolution: u32, faces: usize, byte_limit: u64) -> u32 {
        let mut r = resolution.max(16);
        while r > 16 && Self::atlas_bytes(r, faces) > byte_limit {
            r /= 2;
        }
        r
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        if !(16..=4096).contains(&self.resolution) {
            return Err(Error::setting(
                "shadows.resolution",
                format!("{} (must be 16 to 4096)", self.resolution),
            ));
        }
        if self.pcf > 4 {
            return Err(Error::setting("shadows.pcf", format!("{} (at most 4)", self.pcf)));
        }
        Ok(())
    }
}

/// Settings of a [`Renderer`](crate::Renderer).
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// G-buffer layers: 0 lets the [`Plan`](crate::plan::Plan) decide (2 when an effect reads
    /// layer 1, else 1); 1 or 2 forces that many (2: for a host that reads layer 1 itself).
    pub layers: u32,
    /// Minimum separation Δz of layer 1 behind layer 0, in scene units (0: second-nearest).
    pub dz: f32,
    /// Layer-1 variant.
    pub layer1: Layer1Variant,
    /// G-buffer precision.
    pub precision: Precision,
    /// How the G-buffer stores positions (the depth every pass reads back).
    pub position: PositionEncoding,
    /// Atomic path.
    pub atomics: AtomicPath,
    /// How the rasterizer shares out its work (by the device's type unless set).
    pub raster_work: RasterWork,
    /// Record GPU timestamps per pass (when the device has `TIMESTAMP_QUERY`).
    pub timings: bool,
    /// Ambient obscurance.
    pub ao: AoSettings,
    /// Shadow maps.
    pub shadows: ShadowSettings,
    /// Screen-space radiosity.
    pub radiosity: RadiositySettings,
    /// Screen-space reflections.
    pub reflections: ReflectionSettings,
    /// Depth of field (runs when the camera's lens has an aperture).
    pub dof: DofSettings,
    /// Motion blur (runs when the shutter is open and the camera moved since the last frame).
    pub motion_blur: MotionBlurSettings,
    /// Transparency (runs when the scene has a blended material).
    pub transparency: TransparencySettings,
    /// Effects switched on; the [`Plan`](crate::plan::Plan) runs them where the scene calls for them.
    pub effects: Effects,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            width: 640,
            height: 480,
            layers: 0,
            dz: 0.05,
            layer1: Layer1Variant::TwoPass,
            precision: Precision::Full,
            position: PositionEncoding::ViewDepthF32,
            atomics: AtomicPath::Auto,
            raster_work: RasterWork::Auto,
            timings: true,
            ao: AoSettings::default(),
            shadows: ShadowSettings::default(),
            radiosity: RadiositySettings::default(),
            reflections: ReflectionSettings::default(),
            dof: DofSettings::default(),
            motion_blur: MotionBlurSettings::default(),
            transparency: TransparencySettings::default(),
            effects: Effects::default(),
        }
    }
}

impl Settings {
    /// Settings for a `width` x `height` image, the rest default.
    pub fn with_size(width: u32, height: u32) -> Self {
        Settings { width, height, ..Settings::default() }
    }

    /// How far across (the largest side of its bounds, in scene units) a scene is that the
    /// default lengths suit: the Cornell box's 2 units.
    pub const REFERENCE_EXTENT: f32 = 2.0;

    /// The factor [`scaled`](Settings::scaled) applies for a scene `extent` units across: the
    /// power of two nearest to `extent / REFERENCE_EXTENT` (1 for the Cornell box; steps of two
    /// keep the settings still while a scene's bounds change a little). 1 for an extent that is
    /// not finite and positive.
    pub fn scale_for(extent: f32) -> f32 {
        if !(extent.is_finite() && extent > 0.0) {
            return 1.0;
        }
        (extent / Self::REFERENCE_EXTENT).log2().round().clamp(-60.0, 60.0).exp2()
    }

    /// These settings with every length multiplied by `scale`: the obscurance radius, bias and
    /// history tolerance, the radiosity radius and history tolerance, Δz, and the reflections' distance and
    /// thickness. Counts, pixels and fractions stay.
    pub fn scaled(mut self, scale: f32) -> Self {
        self.ao.radius *= scale;
        self.ao.bias *= scale;
        self.ao.history_tolerance *= scale;
        self.radiosity.radius *= scale;
        self.radiosity.history_tolerance *= scale;
        self.dz *= scale;
        self.reflections.max_distance *= scale;
        self.reflections.thickness *= scale;
        self
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::setting(
                "size",
                format!("{}x{} has no pixels", self.width, self.height),
            ));
        }
        if self.width > MAX_IMAGE_SIDE || self.height > MAX_IMAGE_SIDE {
            return Err(Error::setting(
                "size",
                format!("{}x{} exceeds {MAX_IMAGE_SIDE} pixels on a side", self.width, self.height),
            ));
        }
        if self.layers > 2 {
            return Err(Error::setting(
                "layers",
                format!("{} (must be 0 for automatic, 1 or 2)", self.layers),
            ));
        }
        if !(self.dz >= 0.0 && self.dz.is_finite()) {
            return Err(Error::setting("dz", format!("{} (must be finite and >= 0)", self.dz)));
        }
        if self.ao.enabled {
            self.ao.validate()?;
        }
        if self.shadows.enabled {
            self.shadows.validate()?;
        }
        if self.radiosity.enabled {
            self.radiosity.validate()?;
        }
        if self.reflections.enabled {
            self.reflections.validate()?;
        }
        if self.dof.enabled {
            self.dof.validate()?;
        }
        if self.motion_blur.enabled {
            self.motion_blur.validate()?;
        }
        if self.transparency.enabled {
            self.transparency.validate()?;
        }
        Ok(())
    }
}

/// The effects a user can switch on or off (`--effects`); the plan runs an enabled effect only
/// when the scene calls for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Effects {
    /// Ambient obscurance (needs an ambient term).
    pub ao: bool,
    /// Direct light (needs a light).
    pub direct: bool,
    /// Shadow maps (need direct light and a light that casts shadows).
    pub shadows: bool,
    /// Screen-space radiosity (needs a light or an emissive material).
    pub radiosity: bool,
    /// Screen-space reflections (need a reflective material).
    pub reflections: bool,
    /// Depth of field (needs a camera lens with an aperture).
    pub dof: bool,
    /// Motion blur (needs an open shutter and a moving camera).
    pub motion_blur: bool,
    /// Transparency (needs a blended material).
    pub transparency: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            ao: true,
            direct: true,
            shadows: true,
            radiosity: true,
            reflections: true,
            dof: true,
            motion_blur: true,
            transparency: true,
        }
    }
}

impl Effects {
    /// Parses `auto` (everything the scene calls for) or a comma-separated list (`ao,direct`).
    pub fn parse(text: &str) -> crate::Result<Effects> {
        if text.trim() == "auto" {
            return Ok(Effects::default());
        }
        let mut e = Effects {
            ao: false,
            direct: false,
            shadows: false,
            radiosity: false,
            reflections: false,
            dof: false,
            motion_blur: false,
            transparency: false,
        };
        for name in text.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            match name {
                "ao" => e.ao = true,
                "direct" => e.direct = true,
                "shadows" => e.shadows = true,
                "radiosity" => e.radiosity = true,
                "reflections" => e.reflections = true,
                "dof" => e.dof = true,
                "motion_blur" => e.motion_blur = true,
                "transparency" => e.transparency = true,
                other => {
                    return Err(crate::Error::setting(
                        "effects",
                        format!(
                            "unknown effect `{other}` (known: ao, direct, shadows, radiosity, reflections, dof, motion_blur, transparency; or auto)"
                        ),
                    ));
                }
            }
        }
        Ok(e)
    }
}

/// A slices estimator's slices and taps in a frame that takes `some` of its `slices` (0, or
/// `slices` and above: all of them) with the same steps a side: the kernels take
/// `max(taps / (2 slices), 1)` steps a side, and no taps stay none.
fn history_slice_taps(slices: u32, some: u32, taps: u32) -> (u32, u32) {
    if some == 0 || some >= slices || taps == 0 {
        return (slices, taps);
    }
    (some, (taps / (2 * slices)).max(1) * 2 * some)
}

/// Refuses a `downsample` other than 1, 2 or 4.
fn check_downsample(name: &'static str, downsample: u32) -> Result<()> {
    if matches!(downsample, 1 | 2 | 4) {
        Ok(())
    } else {
        Err(Error::setting(name, format!("{downsample} (must be 1, 2 or 4)")))
    }
}

/// The level of the rotated-grid MIP chain an effect computed at 1 / `downsample` of the image's
/// size is computed at (0 at full resolution, 1 at half, 2 at quarter).
pub fn downsample_level(downsample: u32) -> u32 {
    downsample.max(1).ilog2()
}

/// Depth of field through the camera's thin lens ([`Lens`](crate::scene::Lens); `wgsl/dof.wgsl`,
/// documented there): per pixel, rays through `samples` points of the lens are marched across
/// the image, through both layers, to the first surface they meet.
#[derive(Clone, Debug, PartialEq)]
pub struct DofSettings {
    /// Run the pass (when the lens has an aperture).
    pub enabled: bool,
    /// Rays through the lens per pixel. 1 to 256.
    pub samples: u32,
    /// The largest circle of confusion followed, in pixels (radius); surfaces blurred more are
    /// found only within it. 1 to 256.
    pub max_coc: f32,
    /// How far behind its surface a layer is solid, as a fraction of its view depth: a lens ray
    /// passing behind a surface by more runs on to what lies behind (layer 1, or beyond).
    pub thickness: f32,
    /// Let rays find layer 1 behind a surface they pass (the deep G-buffer's use here); `false`
    /// stops them at layer 0.
    pub two_layers: bool,
}

impl Default for DofSettings {
    fn default() -> Self {
        DofSettings { enabled: true, samples: 24, max_coc: 32.0, thickness: 0.1, two_layers: true }
    }
}

impl DofSettings {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        if !(1..=256).contains(&self.samples) {
            return Err(Error::setting(
                "dof.samples",
                format!("{} (must be 1 to 256)", self.samples),
            ));
        }
        if !(self.max_coc.is_finite() && (1.0..=256.0).contains(&self.max_coc)) {
            return Err(Error::setting(
                "dof.max_coc",
                format!("{} (must be 1 to 256 pixels)", self.max_coc),
            ));
        }
        if !(self.thickness.is_finite() && self.thickness > 0.0) {
            return Err(Error::setting(
                "dof.thickness",
                format!("{} (must be finite and > 0)", self.thickness),
            ));
        }
        Ok(())
    }
}

/// Motion blur of the camera's motion (`wgsl/motion_blur.wgsl`, documented there): per pixel,
/// `samples` instants of the shutter, each the nearest surface of either layer whose motion
/// vector puts it at the pixel then.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionBlurSettings {
    /// Run the pass (when the shutter is open and the camera moved).
    pub enabled: bool,
    /// How long the shutter stays open before each frame's instant, as a fraction of the time
    /// between frames, in [0, 1] (0, the default: closed, no motion blur).
    pub shutter: f32,
    /// Instants of the shutter per pixel. 1 to 256.
    pub samples: u32,
    /// The longest streak followed, in pixels; faster motion is followed this far. 1 to 256.
    pub max_blur: f32,
    /// Let the pixels see layer 1 where the surface in front has moved off it (the deep
    /// G-buffer's use here); `false` reads layer 0 only.
    pub two_layers: bool,
}

impl Default for MotionBlurSettings {
    fn default() -> Self {
        MotionBlurSettings {
            enabled: true,
            shutter: 0.0,
            samples: 16,
            max_blur: 32.0,
            two_layers: true,
        }
    }
}

impl MotionBlurSettings {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        if !(0.0..=1.0).contains(&self.shutter) {
            return Err(Error::setting(
                "motion_blur.shutter",
                format!("{} (must be in [0, 1])", self.shutter),
            ));
        }
        if !(1..=256).contains(&self.samples) {
            return Err(Error::setting(
                "motion_blur.samples",
                format!("{} (must be 1 to 256)", self.samples),
            ));
        }
        if !(self.max_blur.is_finite() && (1.0..=256.0).contains(&self.max_blur)) {
            return Err(Error::setting(
                "motion_blur.max_blur",
                format!("{} (must be 1 to 256 pixels)", self.max_blur),
            ));
        }
        Ok(())
    }
}

/// Transparency by depth peeling (`wgsl/transparency.wgsl`, documented there): the `layers`
/// nearest blended surfaces in front of the opaque layer 0 are peeled one at a time by the
/// rasterizer, each shaded (direct light with shadows, the unoccluded ambient term, emission)
/// and blended over what lies behind it.
#[derive(Clone, Debug, PartialEq)]
pub struct TransparencySettings {
    /// Run the passes (when the scene has a blended material).
    pub enabled: bool,
    /// Blended surfaces peeled per pixel (k), 1 to [`MAX_PEELS`]. Surfaces beyond the k-th
    /// nearest are left out: what lies behind them shows through as if they were not there.
    pub layers: u32,
}

/// The most transparency layers (peels) a frame may take.
pub const MAX_PEELS: u32 = 16;

impl Default for TransparencySettings {
    fn default() -> Self {
        TransparencySettings { enabled: true, layers: 4 }
    }
}

impl TransparencySettings {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_PEELS).contains(&self.layers) {
            return Err(Error::setting(
                "transparency.layers",
                format!("{} (must be 1 to {MAX_PEELS})", self.layers),
            ));
        }
        Ok(())
    }
}
