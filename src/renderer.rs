//! [`Renderer`]: the deep G-buffer stage, recorded into a caller's command encoder.
//!
//! The renderer owns one stage per part of the frame (`passes/`). Each frame it computes the
//! [`Plan`], prepares the stages the plan needs (allocating, writing their constants), then
//! walks the plan and lets each pass's stage record it.

use std::sync::Arc;

use glam::Vec3;

use crate::environment::Environment;
use crate::frame::{
    CameraMatrices, FRAME_DIAGNOSTICS, FRAME_OBJECT_MOTION, FrameUniform, RasterCounters,
};
use crate::gbuffer::{self, GBufferLayer};
use crate::gpu::{self, PassTiming, Pipelines, Requirements, Timestamps};
use crate::passes::ao::AoStage;
use crate::passes::composite::CompositeStage;
use crate::passes::direct::DirectStage;
use crate::passes::dof::DofStage;
use crate::passes::motion_blur::MotionBlurStage;
use crate::passes::offscreen::OffscreenBuffers;
use crate::passes::present::Present;
use crate::passes::radiosity::{RadiosityBuffers, RadiosityStage};
use crate::passes::raster::RasterStage;
use crate::passes::reflections::ReflectionsStage;
use crate::passes::resolve::ResolveStage;
use crate::passes::shadow::ShadowStage;
use crate::passes::transparency::TransparencyStage;
use crate::passes::{FrameContext, Recorder, Stage};
use crate::plan::{Effect, PassId, Plan, StageId};
use crate::scene::Camera;
use crate::settings::{AtomicPath, RasterWork, Settings};
use crate::{Error, Result, SceneBuffers};

/// Counters the GPU keeps while rasterizing, read with [`Renderer::diagnostics`]. A still frame
/// draws nothing ([`Plan::reused`]) and keeps the counters of the frame that drew its G-buffer.
///
/// The `rejected_*` and `untextured_triangles` counters check what the CPU cannot: the contents
/// of a host's [imported](crate::SceneBuffers::import) buffers. A rejected triangle is not drawn
/// (it never reaches a kernel that would read through its bad index); each is counted once a
/// frame, by the camera's layer-0 raster. Scenes uploaded from a [`Scene`](crate::Scene) are
/// validated on the CPU and always count 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Diagnostics {
    /// Triangles (after clipping) rasterized by the large-triangle tiles in the last frame,
    /// summed over every raster of the frame (both layers and the shadow maps).
    pub large_triangles: u32,
    /// Large triangles dropped because the bin was full (0 unless the bin is undersized).
    pub dropped_triangles: u32,
    /// Triangles rejected because a vertex index is not below the vertex count.
    pub rejected_indices: u32,
    /// Triangles rejected because their material id is not below the material count.
    pub rejected_materials: u32,
    /// Triangles rejected because a vertex position is NaN or infinite.
    pub rejected_positions: u32,
    /// Triangles drawn with their material's factors alone because a texture of it does not
    /// lie inside the texel buffer (or has a zero size), or because the scene is marked
    /// [`textureless`](crate::SceneInfo::textureless).
    pub untextured_triangles: u32,
    /// Blended fragments in front of the opaque surfaces that lie behind the last transparency
    /// peel ([`TransparencySettings::layers`](crate::TransparencySettings)): left out of the
    /// image (what lies behind them shows through).
    pub unpeeled_fragments: u32,
}

impl Diagnostics {
    /// Triangles not drawn because of bad input.
    pub fn rejected_triangles(&self) -> u32 {
        self.rejected_indices + self.rejected_materials + self.rejected_positions
    }

    /// Whether any input was rejected or drawn without its texture.
    pub fn has_bad_input(&self) -> bool {
        self.rejected_triangles() + self.untextured_triangles > 0
    }

    /// One line per non-zero counter of lost or degraded geometry, for a log.
    pub fn warnings(&self) -> Vec<String> {
        [
            (
                self.dropped_triangles,
                "large triangles did not fit the raster bin and were not drawn",
            ),
            (
                self.rejected_indices,
                "triangles have a vertex index past the vertex count (not drawn)",
            ),
            (
                self.rejected_materials,
                "triangles have a material id past the material count (not drawn)",
            ),
            (
                self.rejected_positions,
                "triangles have a NaN or infinite vertex position (not drawn)",
            ),
            (
                self.untextured_triangles,
                "triangles' textures lie outside the texel buffer or the scene is marked \
                 textureless (drawn untextured)",
            ),
            (
                self.unpeeled_fragments,
                "blended fragments lie behind the last transparency layer (left out; \
                 --transparency-layers takes more)",
            ),
        ]
        .into_iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{n} {what}"))
        .collect()
    }
}

impl From<RasterCounters> for Diagnostics {
    fn from(c: RasterCounters) -> Self {
        Diagnostics {
            large_triangles: c.binned,
            dropped_triangles: c.dropped,
            rejected_indices: c.rejected_indices,
            rejected_materials: c.rejected_materials,
            rejected_positions: c.rejected_positions,
            untextured_triangles: c.untextured,
            unpeeled_fragments: c.unpeeled,
        }
    }
}

/// Each lighting term of the last frame, read back, one value per pixel (row-major).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Terms {
    /// Ambient visibility AV in [0, 1], as the composite reads it; `None` without obscurance.
    pub av: Option<Vec<f32>>,
    /// Direct radiance of layer 0 (zero where no light runs).
    pub direct: Vec<Vec3>,
    /// The indirect irradiance the gather found (the surfaces it saw, over the share of the
    /// hemisphere they cover); `None` without radiosity. The rest of the hemisphere, which no
    /// surface covered, is the ambient term's; the ground truth of diffuse indirect light
    /// leaves the sky out the same way.
    pub indirect: Option<Vec<Vec3>>,
    /// The radiosity term the composite adds: the diffuse albedo / pi times `indirect`.
    pub radiosity: Option<Vec<Vec3>>,
    /// Reflected radiance (times the reflectivity); `None` without reflections.
    pub reflections: Option<Vec<Vec3>>,
    /// The HDR image.
    pub hdr: Vec<Vec3>,
}

/// Passes one frame can time (the capacity of the timestamp query set).
const MAX_TIMED_PASSES: u32 = 32;

/// The parts of the frame, one stage each (those the plan has not needed yet are `None`).
struct Stages {
    raster: RasterStage,
    resolve: ResolveStage,
    ao: Option<AoStage>,
    shadows: Option<ShadowStage>,
    direct: DirectStage,
    radiosity: Option<RadiosityStage>,
    reflections: Option<ReflectionsStage>,
    transparency: Option<TransparencyStage>,
    composite: CompositeStage,
    dof: Option<DofStage>,
    motion_blur: Option<MotionBlurStage>,
}

impl Stages {
    fn new(device: &wgpu::Device, s: &Settings, int64: bool) -> Stages {
        let pixels = u64::from(s.width) * u64::from(s.height);
        Stages {
            raster: RasterStage::new(device, int64, s.raster_work, pixels),
            resolve: ResolveStage::new(
                device,
                (s.width, s.height),
                gbuffer::bytes_per_pixel(s.precision),
            ),
            ao: None,
            shadows: None,
            direct: DirectStage::new(device, pixels),
            radiosity: None,
            reflections: None,
            transparency: None,
            composite: CompositeStage::new(device, pixels),
            dof: None,
            motion_blur: None,
        }
    }

    /// The stage that records passes of `id`'s kind (prepared for the plan).
    fn get(&self, id: StageId) -> &dyn Stage {
        let prepared = "the stage was prepared for the plan";
        match id {
            StageId::Raster => &self.raster,
            StageId::Resolve => &self.resolve,
            StageId::Ao => self.ao.as_ref().expect(prepared),
            StageId::Shadows => self.shadows.as_ref().expect(prepared),
            StageId::Direct => &self.direct,
            StageId::Radiosity => self.radiosity.as_ref().expect(prepared),
            StageId::Reflections => self.reflections.as_ref().expect(prepared),
            StageId::Transparency => self.transparency.as_ref().expect(prepared),
            StageId::Composite => &self.composite,
            StageId::Dof => self.dof.as_ref().expect(prepared),
            StageId::MotionBlur => self.motion_blur.as_ref().expect(prepared),
        }
    }

    /// Every stage made so far, in frame order.
    fn each(&self) -> Vec<&dyn Stage> {
        let mut stages: Vec<&dyn Stage> = vec![&self.raster, &self.resolve];
        stages.extend(self.ao.as_ref().map(|s| s as &dyn Stage));
        stages.extend(self.shadows.as_ref().map(|s| s as &dyn Stage));
        stages.push(&self.direct);
        stages.extend(self.radiosity.as_ref().map(|s| s as &dyn Stage));
        stages.extend(self.reflections.as_ref().map(|s| s as &dyn Stage));
        stages.extend(self.transparency.as_ref().map(|s| s as &dyn Stage));
        stages.push(&self.composite);
        stages.extend(self.dof.as_ref().map(|s| s as &dyn Stage));
        stages.extend(self.motion_blur.as_ref().map(|s| s as &dyn Stage));
        stages
    }

    /// What the frame's passes read: `i` and the stages' targets.
    fn context<'a>(&'a self, i: FrameInputs<'a>) -> FrameContext<'a> {
        let FrameInputs { device, pipelines, scene, settings, plan, frame, environment } = i;
        let runs = |e: Effect| plan.runs(e);
        let radiosity = self.radiosity.as_ref().filter(|_| runs(Effect::Radiosity));
        let radiosity = radiosity.map(|r| r.buffers(settings));
        FrameContext {
            device,
            pipelines,
            scene,
            settings,
            plan,
            frame,
            raster: &self.raster,
            gbuffer: [self.resolve.gbuffer(0), self.resolve.gbuffer(1)],
            previous_positions: self.resolve.previous(),
            shadows: self
                .shadows
                .as_ref()
                .filter(|_| runs(Effect::Shadows))
                .map(ShadowStage::inputs),
            rsm: self.shadows.as_ref().and_then(|s| s.rsm_inputs(plan)),
            direct: [self.direct.radiance(0), self.direct.radiance(1)],
            diffuse: [self.direct.diffuse(0), self.direct.diffuse(1)],
            lighting: &self.direct,
            av: self.ao.as_ref().filter(|_| runs(Effect::Ao)).map(|a| a.av(settings)),
            irradiance: radiosity.map(|r| r.irradiance),
            reflections: self
                .reflections
                .as_ref()
                .filter(|_| runs(Effect::Reflections))
                .map(|r| r.output()),
            environment,
            hdr: self.composite.hdr(),
            post: self.composite.post(),
        }
    }
}

/// What a frame reads besides the stages' targets.
struct FrameInputs<'a> {
    device: &'a wgpu::Device,
    pipelines: &'a Pipelines,
    scene: &'a SceneBuffers,
    settings: &'a Settings,
    plan: &'a Plan,
    frame: &'a wgpu::Buffer,
    environment: Option<&'a wgpu::Buffer>,
}

/// An environment map on the GPU: texels and size.
struct EnvironmentBuffer {
    texels: wgpu::Buffer,
    size: (u32, u32),
}

/// Renders deep G-buffers on a device it borrows.
///
/// Create it once per device; call [`encode`](Renderer::encode) once per frame and
/// [`resize`](Renderer::resize) when the image size changes.
pub struct Renderer {
    settings: Settings,
    pipelines: Arc<Pipelines>,
    /// The frame uniform every kernel reads.
    frame: wgpu::Buffer,
    stages: Stages,
    present: Present,
    /// The last frame's camera (`None`: the next frame is a first frame).
    history: Option<CameraMatrices>,
    /// [`Layer1Variant::Delay`](crate::Layer1Variant::Delay): the camera the last call was
    /// given, which the next frame shows.
    pending: Option<Camera>,
    /// The camera the last frame's image shows.
    image_camera: Option<Camera>,
    timestamps: Option<Timestamps>,
    /// The last frame: its constants, its plan and the passes recorded.
    last_frame: Option<FrameUniform>,
    plan: Option<Plan>,
    recorded: Vec<PassId>,
    /// The bytes each of the last frame's passes binds.
    traffic: Vec<crate::gpu::PassTraffic>,
    environment: Option<EnvironmentBuffer>,
    /// The last frame [`render`](Renderer::render) submitted, still perhaps on the GPU.
    in_flight: Option<wgpu::SubmissionIndex>,
    /// Advanced by [`geometry_changed`](Renderer::geometry_changed): shadow maps drawn before
    /// it are not reused, and the geometry's motion is read from where it stood.
    geometry_generation: u64,
    /// Advanced by [`geometry_changed`](Renderer::geometry_changed) and
    /// [`redraw_shadow_maps`](Renderer::redraw_shadow_maps): shadow maps drawn before it are not
    /// reused.
    shadow_generation: u64,
    /// What the last frame wrote that a still frame keeps (`None` after a provided G-buffer or
    /// [`reset_history`](Renderer::reset_history)).
    still: Option<StillKey>,
    /// [`redraw`](Renderer::redraw) was called: the next frame keeps nothing.
    redraw: bool,
    /// [`set_environment`](Renderer::set_environment) was called: the next frame runs the
    /// reflections (missed rays see the environment) even where a still view would keep them.
    environment_changed: bool,
    /// Frames in a row whose view (camera, last camera, scene) was the last frame's: the
    /// radiosity's filter averages longer as it grows
    /// ([`RadiositySettings::history_weight`](crate::RadiositySettings::history_weight)).
    still_frames: u32,
    /// The still frame after which the host said the radiosity settled
    /// ([`settle`](Renderer::settle)); `None` once the view moves.
    settled_at: Option<u32>,
}

/// What a frame's [`PassId::same_when_still`] passes wrote depends on: a later frame with the
/// same key would write the same, and keeps it ([`Plan::reused`]).
#[derive(PartialEq)]
struct StillKey {
    /// The frame constants (the camera, the last frame's camera, the image, the flags).
    uniform: FrameUniform,
    /// The names of the frame's passes, drawn or kept, shadow maps and `ao.temporal` aside,
    /// sorted.
    passes: Vec<String>,
    /// The scene's buffers ([`SceneBuffers::identity`]).
    scene: [wgpu::Buffer; 6],
    /// [`Renderer::geometry_changed`]'s count.
    generation: u64,
}

impl StillKey {
    fn new(uniform: FrameUniform, scene: &SceneBuffers, plan: &Plan, generation: u64) -> StillKey {
        let mut passes: Vec<String> = plan
            .passes
            .iter()
            .chain(&plan.reused)
            // A still view's frames add the obscurance's mean (`ao.temporal`) to the plan.
            .filter(|p| !matches!(p, PassId::Shadow { .. } | PassId::AoTemporal))
            .map(|p| p.name().into_owned())
            .collect();
        passes.sort();
        StillKey { uniform, passes, scene: scene.identity(), generation }
    }
}

impl Renderer {
    /// Features deep-gbuffer cannot run without (none: every path has a fallback).
    pub fn required_features() -> wgpu::Features {
        wgpu::Features::empty()
    }

    /// The features of the 64-bit atomic raster path.
    pub fn int64_features() -> wgpu::Features {
        wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX
    }

    /// Features used when present: 64-bit atomics (one raster pass instead of two; with
    /// `SHADER_INT64_ATOMIC_ALL_OPS` also the raster's early depth test, which loads a word before
    /// its atomic) and timestamp queries (per-pass GPU timings).
    pub fn optional_features() -> wgpu::Features {
        Self::int64_features()
            | wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS
            | wgpu::Features::TIMESTAMP_QUERY
    }

    /// Limits deep-gbuffer needs beyond the WebGPU defaults: 16 storage buffers per stage (the
    /// rasterizer reads the materials' textures and coordinates for the alpha test besides its
    /// own buffers). Raise `max_storage_buffer_binding_size` to the adapter's for large images
    /// (a layer at 1920x1080 in full precision is 133 MB).
    pub fn required_limits() -> wgpu::Limits {
        wgpu::Limits { max_storage_buffers_per_shader_stage: 16, ..wgpu::Limits::default() }
    }

    /// All of the above, for [`Gpu::new`](crate::gpu::Gpu::new): adapters with 64-bit atomics
    /// are preferred.
    pub fn requirements() -> Requirements {
        Requirements {
            features: Self::required_features(),
            optional_features: Self::optional_features(),
            preferred_features: Self::int64_features(),
            limits: Self::required_limits(),
        }
    }

    /// Creates the renderer's pipelines and targets on `device`.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, settings: Settings) -> Result<Renderer> {
        let pipelines = Arc::new(Pipelines::default());
        gpu::scoped(device, "deep-gbuffer.renderer", || {
            Self::create(device, queue, settings, pipelines)
        })
    }

    /// Whether the raster uses 64-bit atomics on `device` under `settings`.
    fn int64_path(device: &wgpu::Device, settings: &Settings) -> Result<bool> {
        let features = device.features();
        match settings.atomics {
            AtomicPath::Auto => Ok(features.contains(Self::int64_features())),
            AtomicPath::Int64 => {
                for (feature, name) in [
                    (wgpu::Features::SHADER_INT64, "SHADER_INT64"),
                    (wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX, "SHADER_INT64_ATOMIC_MIN_MAX"),
                ] {
                    if !features.contains(feature) {
                        return Err(Error::MissingFeature(name));
                    }
                }
                Ok(true)
            }
            AtomicPath::Int32 => Ok(false),
        }
    }

    /// Refuses settings whose targets the device cannot bind.
    fn check_limits(device: &wgpu::Device, settings: &Settings) -> Result<()> {
        let limits = device.limits();
        let needed = Self::required_limits().max_storage_buffers_per_shader_stage;
        if limits.max_storage_buffers_per_shader_stage < needed {
            return Err(Error::ExceedsLimit {
                what: "a shader stage".into(),
                needed: u64::from(needed),
                limit: u64::from(limits.max_storage_buffers_per_shader_stage),
                unit: "storage buffers",
            });
        }
        let pixels = u64::from(settings.width) * u64::from(settings.height);
        let binding_limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        let gbuffer_bytes = pixels * gbuffer::bytes_per_pixel(settings.precision);
        if gbuffer_bytes > binding_limit {
            // What would fit: the packed precision, or the most pixels at this one.
            let packed = pixels * gbuffer::bytes_per_pixel(crate::Precision::Packed);
            let hint = match settings.precision {
                crate::Precision::Full if packed <= binding_limit => {
                    "; the packed precision would fit".to_string()
                }
                _ => format!(
                    "; at most {} pixels fit at this precision",
                    binding_limit / gbuffer::bytes_per_pixel(settings.precision)
                ),
            };
            return Err(Error::ExceedsLimit {
                what: format!(
                    "a {}x{} G-buffer layer ({} precision{hint})",
                    settings.width,
                    settings.height,
                    settings.precision.name()
                ),
                needed: gbuffer_bytes,
                limit: binding_limit,
                unit: "bytes",
            });
        }
        Ok(())
    }

    fn create(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        settings: Settings,
        pipelines: Arc<Pipelines>,
    ) -> Result<Renderer> {
        settings.validate()?;
        let int64 = Self::int64_path(device, &settings)?;
        Self::check_limits(device, &settings)?;
        Ok(Renderer {
            pipelines,
            frame: gpu::uniform_buffer_for::<FrameUniform>(device, "deep-gbuffer.frame"),
            stages: Stages::new(device, &settings, int64),
            present: Present::new(),
            history: None,
            pending: None,
            image_camera: None,
            timestamps: if settings.timings {
                Timestamps::new(device, queue, MAX_TIMED_PASSES)
            } else {
                None
            },
            last_frame: None,
            plan: None,
            recorded: Vec::new(),
            traffic: Vec::new(),
            environment: None,
            in_flight: None,
            geometry_generation: 0,
            shadow_generation: 0,
            still: None,
            redraw: false,
            environment_changed: false,
            still_frames: 0,
            settled_at: None,
            settings,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Changes the image size between frames. Every per-pixel target is reallocated and the
    /// temporal history restarts (the next frame is a first frame, as after
    /// [`reset_history`](Renderer::reset_history)); compiled pipelines and the environment map
    /// are kept. A size the device cannot hold is an error that leaves the renderer as it was.
    pub fn resize(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        width: u32,
        height: u32,
    ) -> Result<()> {
        if (width, height) == (self.settings.width, self.settings.height) {
            return Ok(());
        }
        let settings = Settings { width, height, ..self.settings.clone() };
        let pipelines = self.pipelines.clone();
        let mut next = gpu::scoped(device, "deep-gbuffer.renderer", || {
            Self::create(device, queue, settings, pipelines)
        })?;
        // The kept bind groups hold the old targets.
        self.pipelines.forget_bind_groups();
        next.environment = self.environment.take();
        next.in_flight = self.in_flight.take();
        *self = next;
        Ok(())
    }

    /// Sets the equirectangular environment that reflection rays see when they leave the screen
    /// (`None`: the scene's constant ambient sky, the default). The map is uploaded once and
    /// kept until the next call.
    pub fn set_environment(
        &mut self,
        device: &wgpu::Device,
        environment: Option<&Environment>,
    ) -> Result<()> {
        self.environment = match environment {
            None => None,
            Some(env) => {
                let bytes: &[u8] = bytemuck::cast_slice(env.texels());
                let limit = device.limits().max_storage_buffer_binding_size;
                if bytes.len() as u64 > limit {
                    return Err(Error::ExceedsLimit {
                        what: format!("a {}x{} environment map", env.width(), env.height()),
                        needed: bytes.len() as u64,
                        limit,
                        unit: "bytes",
                    });
                }
                let texels =
                    gpu::storage_buffer_init(device, "deep-gbuffer.reflections.environment", bytes);
                Some(EnvironmentBuffer { texels, size: (env.width(), env.height()) })
            }
        };
        self.environment_changed = true;
        Ok(())
    }

    /// `"int64"` (one 64-bit atomicMin per fragment) or `"int32"` (depth pass, then id pass).
    pub fn raster_path(&self) -> &'static str {
        if self.stages.raster.int64() { "int64" } else { "int32" }
    }

    /// How the rasterizer shares out its work on this device: [`RasterWork::Gpu`] or
    /// [`RasterWork::Cpu`] (what [`RasterWork::Auto`] chose, or what was asked).
    pub fn raster_work(&self) -> RasterWork {
        self.stages.raster.work()
    }

    /// Forgets the previous frame (a camera cut): the next frame rasterizes layer 1 exactly.
    pub fn reset_history(&mut self) {
        self.history = None;
        self.still = None;
        self.settled_at = None;
    }

    /// Tells the renderer that the radiosity's bounces have settled under the still view of the
    /// last frame (the host measured it: `deep-gbuffer render` waits until the mean irradiance
    /// over four frames differs by less than 0.5% from the four before). From the next frame
    /// that shows the same view the radiosity's temporal filter keeps the mean of the frames
    /// since, as it would after the
    /// [`RadiositySettings::settle_frames`](crate::RadiositySettings::settle_frames) still frames
    /// (a bound for any scene, 112 with the defaults): the gather's noise, which the turned
    /// slices make different every frame, then falls as one over the square root of the frames,
    /// where the exponential filter keeps it at a fixed share of one frame's; after
    /// [`RadiositySettings::kept_after`](crate::RadiositySettings::kept_after) such frames the
    /// still view keeps the mean and runs no radiosity pass. Told again under the same view, it
    /// keeps the first time. A frame whose view moves, or
    /// [`reset_history`](Self::reset_history), forgets it.
    pub fn settle(&mut self) {
        // Told again, or past the bound already: the mean goes on, it does not start over.
        self.settled_at.get_or_insert(self.still_frames);
    }

    /// The still frames the radiosity's filter weighs by: past [`settle`](Self::settle), as
    /// many past `settle_frames` as have stood still since (never fewer than the still frames:
    /// a view told late, past the bound, goes on averaging).
    fn radiosity_still(&self) -> u32 {
        self.radiosity_still_at(self.still_frames)
    }

    /// [`radiosity_still`](Self::radiosity_still) on the `still`-th still frame in a row.
    fn radiosity_still_at(&self, still: u32) -> u32 {
        match self.settled_at {
            Some(at) if still > at => {
                self.settings.radiosity.settle_frames().saturating_add(still - at).max(still)
            }
            _ => still,
        }
    }

    /// Tells the renderer that the scene's geometry or materials changed in place (the host
    /// wrote new positions, indices or materials into the buffers a [`SceneBuffers`] holds): the
    /// next frame redraws every shadow map and runs every pass a still frame would keep.
    /// Without it, a light's shadow map is drawn once and kept while the light, the scene's
    /// bounds, the shadow settings and the scene's buffers (a scene uploaded or imported anew
    /// has new ones) stay the same, and a still camera keeps its G-buffer, obscurance (once its
    /// still frames have averaged it) and direct light; the plan lists the kept passes in
    /// [`Plan::reused`]. For the shadow maps the camera
    /// does not matter: it may move freely.
    ///
    /// It also gives moving geometry its motion: the renderer keeps a copy of the scene's vertex
    /// positions as the last frame drew them (two position buffers' worth of memory; copied on a
    /// scene's first frame and on each frame after this call), and the next frame's resolve
    /// writes each surface's motion from where its triangle stood then, so the motion blur,
    /// which then runs even under a still camera, and the radiosity's reprojection follow moving
    /// objects. Call it once per frame in which positions changed, after writing them.
    pub fn geometry_changed(&mut self) {
        self.geometry_generation += 1;
        self.shadow_generation += 1;
    }

    /// Makes the next frame redraw every shadow map, as after
    /// [`geometry_changed`](Renderer::geometry_changed), without taking the geometry for
    /// moved: what a benchmark of the shadow maps' cost calls before each frame.
    pub fn redraw_shadow_maps(&mut self) {
        self.shadow_generation += 1;
    }

    /// Makes the next frame run every pass of its plan, keeping nothing from earlier frames (the
    /// shadow maps, and on a still frame the G-buffer, obscurance and direct light;
    /// [`Plan::reused`]), without taking the geometry for moved: what a benchmark of a whole
    /// frame's cost calls before each frame. The image is the same either way.
    pub fn redraw(&mut self) {
        self.redraw_shadow_maps();
        self.redraw = true;
    }

    /// The plan for `scene` seen through `camera` under this renderer's settings (what
    /// [`encode`](Renderer::encode) will run; [`Plan::for_view`]). The first frame of a one-pass
    /// layer-1 variant rasterizes the layers in two passes (`raster.layer0`, `raster.layer1`)
    /// instead of `raster.layers`. A shadow map an
    /// earlier frame drew is kept while nothing it depends on changed (see
    /// [`geometry_changed`](Renderer::geometry_changed)): its pass moves to [`Plan::reused`].
    ///
    /// A still frame (the camera and the last frame's camera those of the frame before, the
    /// scene and its buffers the same, nothing redrawn) keeps the last frame's G-buffer,
    /// obscurance and direct light: those passes move to [`Plan::reused`] too
    /// ([`redraw`](Renderer::redraw) makes the next frame run them), but for the obscurance on
    /// the first [`AoSettings::still_frames`](crate::AoSettings::still_frames) still frames,
    /// which average it. Once the radiosity's settled mean holds
    /// [`RadiositySettings::kept_after`](crate::RadiositySettings::kept_after) frames its
    /// passes are kept too, and the reflections whenever neither the obscurance nor the
    /// radiosity runs in the frame (what they read is then the last frame's).
    pub fn plan(&self, scene: &SceneBuffers, camera: &Camera) -> Plan {
        self.plan_for(scene, camera, false)
    }

    /// [`plan`](Renderer::plan); `provided`: the caller wrote this frame's G-buffer, so no
    /// pass is kept for a still frame.
    fn plan_for(&self, scene: &SceneBuffers, camera: &Camera, provided: bool) -> Plan {
        let mut plan = Plan::for_view(scene.info(), &self.settings, camera);
        let (w, h) = (self.settings.width, self.settings.height);
        let still = self.history.is_none_or(|last| last == CameraMatrices::new(camera, w, h));
        if still && !self.stages.resolve.moved(scene, self.geometry_generation) {
            plan = plan.without_motion();
        }
        if self.history.is_none()
            && let Some(i) = plan.passes.iter().position(|p| *p == PassId::RasterLayers)
        {
            plan.passes.splice(i..=i, [PassId::RasterLayer0, PassId::RasterLayer1]);
        }
        if let Some(shadows) = &self.stages.shadows {
            let lights = shadows.kept(scene, &plan, &self.settings, self.shadow_generation);
            let kept: Vec<PassId> = plan
                .passes
                .iter()
                .filter(|p| matches!(p, PassId::Shadow { light, .. } if lights.contains(light)))
                .cloned()
                .collect();
            plan.passes.retain(|p| !kept.contains(p));
            plan.reused = kept;
        }
        if !provided && self.is_still(scene, camera, &plan) {
            // The obscurance goes on averaging turned slices for a while, with the temporal
            // filter or, without it, in a mean of the still frames alone.
            let ao =
                plan.runs(Effect::Ao) && self.settings.ao.runs_when_still(self.still_frames + 1);
            // The radiosity, once its settled mean holds enough frames; the reflections,
            // whenever nothing they read (the obscurance, the radiosity) runs this frame.
            let radiosity = plan.runs(Effect::Radiosity)
                && !self
                    .settings
                    .radiosity
                    .kept_when_still(self.radiosity_still_at(self.still_frames + 1));
            let reflections_kept = !ao && !radiosity && !self.environment_changed;
            if ao
                && !plan.contains(&PassId::AoTemporal)
                && let Some(i) = plan.passes.iter().position(|p| *p == PassId::Ao)
            {
                plan.passes.insert(i + 1, PassId::AoTemporal);
            }
            let (mut kept, mut run): (Vec<PassId>, Vec<PassId>) =
                plan.passes.into_iter().partition(|p| match p.effect() {
                    Some(Effect::Radiosity) => !radiosity,
                    Some(Effect::Reflections) => reflections_kept,
                    _ => {
                        p.same_when_still()
                            && !(ao
                                && matches!(p, PassId::Ao | PassId::AoTemporal | PassId::AoBlur))
                    }
                });
            // With nothing before them to run, the composite and the passes after it would
            // write the image they wrote.
            if run.iter().all(|p| p.stage() == StageId::Composite || p.is_post()) {
                kept.append(&mut run);
            }
            plan.passes = run;
            plan.reused.extend(kept);
        }
        plan
    }

    /// Whether a frame of `plan` (its shadow maps decided) from `camera` would write what the
    /// last frame's [`PassId::same_when_still`] passes wrote: the same [`StillKey`], and
    /// nothing drawn this frame that shares the rasterizer's counters (a shadow map, a
    /// transparency peel).
    fn is_still(&self, scene: &SceneBuffers, camera: &Camera, plan: &Plan) -> bool {
        let draws = plan
            .passes
            .iter()
            .any(|p| matches!(p, PassId::Shadow { .. } | PassId::TransparencyPeel));
        !draws && !self.redraw && self.same_view(scene, camera, plan)
    }

    /// Whether a frame of `plan` from `camera` has the last frame's [`StillKey`]: the same
    /// camera, last camera, scene and passes.
    fn same_view(&self, scene: &SceneBuffers, camera: &Camera, plan: &Plan) -> bool {
        let Some(last) = &self.still else { return false };
        let key = StillKey::new(
            self.constants(scene, camera, false),
            scene,
            plan,
            self.geometry_generation,
        );
        *last == key
    }

    /// The frame constants of a frame from `camera` after this renderer's last frame;
    /// `moved`: the geometry moved since (the resolve reads its last positions).
    fn constants(&self, scene: &SceneBuffers, camera: &Camera, moved: bool) -> FrameUniform {
        let s = &self.settings;
        let current = CameraMatrices::new(camera, s.width, s.height);
        let previous = self.history.unwrap_or(current);
        FrameUniform {
            flags: FRAME_DIAGNOSTICS
                | s.position.frame_flags()
                | if moved { FRAME_OBJECT_MOTION } else { 0 },
            ..FrameUniform::new(camera, current, previous, s.width, s.height, s.dz, scene.counts())
        }
    }

    /// The plan of the last [`encode`](Renderer::encode).
    pub fn last_plan(&self) -> Option<&Plan> {
        self.plan.as_ref()
    }

    /// The passes the last [`encode`](Renderer::encode) recorded, in order.
    pub fn passes(&self) -> &[PassId] {
        &self.recorded
    }

    /// Records one frame, every pass of its [`plan`](Renderer::plan), into `encoder`. Submit
    /// it, then read the results with [`read_terms`](Renderer::read_terms) or
    /// [`read_gbuffer`](Renderer::read_gbuffer), or use
    /// [`gbuffer_buffer`](Renderer::gbuffer_buffer) in your own passes. GPU validation errors
    /// while recording (buffers of another device, for one) are returned as [`Error::Gpu`];
    /// after an error the encoder should be dropped, not submitted.
    pub fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        camera: &Camera,
    ) -> Result<()> {
        let result = gpu::scoped(device, "deep-gbuffer.frame", || {
            self.encode_frame(device, queue, encoder, scene, camera, false)
        });
        // A frame that failed wrote nothing a still frame could keep.
        if result.is_err() {
            self.still = None;
        }
        result
    }

    /// Records a frame; `provided`: the G-buffer layers and visibility depths were written by
    /// [`render_gbuffer`](Renderer::render_gbuffer), so no raster or resolve pass runs.
    fn encode_frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        camera: &Camera,
        provided: bool,
    ) -> Result<()> {
        camera.validate()?;
        // With one frame of latency the frame shows the camera given the call before.
        let given = camera;
        let delayed = self.settings.layer1 == crate::Layer1Variant::Delay;
        let shown = if delayed { self.pending.clone() } else { None };
        let camera = shown.as_ref().unwrap_or(given);
        let mut plan = self.plan_for(scene, camera, provided);
        self.still_frames = if !provided && self.same_view(scene, camera, &plan) {
            self.still_frames + 1
        } else {
            0
        };
        if self.still_frames == 0 {
            self.settled_at = None;
        }
        // Set again once the frame is recorded: a frame that stops on an error keeps nothing.
        self.still = None;
        self.redraw = false;
        self.environment_changed = false;
        if provided {
            plan.passes.retain(|p| !p.is_gbuffer());
            // The peels are drawn against the rasterizer's layer 0, which a provided G-buffer
            // does not come with.
            if plan.runs(Effect::Transparency) {
                plan.passes.retain(|p| p.effect() != Some(Effect::Transparency));
                plan.left_out.push((Effect::Transparency, crate::plan::Reason::NotNeeded));
            }
        }
        let current = self.prepare(device, queue, scene, (camera, given), &plan)?;
        let stages = &self.stages;
        let ctx = stages.context(FrameInputs {
            device,
            pipelines: &self.pipelines,
            scene,
            settings: &self.settings,
            plan: &plan,
            frame: &self.frame,
            environment: self.environment.as_ref().map(|e| &e.texels),
        });
        let mut rec = Recorder::new(encoder, self.timestamps.as_mut());
        for stage in stages.each() {
            stage.begin(&ctx, &mut rec);
        }
        for pass in &plan.passes {
            stages.get(pass.stage()).record(pass, &ctx, &mut rec);
        }
        (self.recorded, self.traffic) = rec.finish();
        debug_assert_eq!(self.recorded, plan.passes, "the recorded passes are the plan's");
        if let Some(shadows) = self.stages.shadows.as_mut() {
            shadows.drew(scene, &plan, self.shadow_generation);
        }
        self.still = match (&self.last_frame, provided) {
            (Some(uniform), false) => {
                Some(StillKey::new(*uniform, scene, &plan, self.geometry_generation))
            }
            _ => None,
        };
        self.plan = Some(plan);
        self.history = Some(current);
        self.image_camera = Some(camera.clone());
        if delayed {
            self.pending = Some(given.clone());
        }
        Ok(())
    }

    /// The camera the last frame's image shows: the one it was given, or with
    /// [`Layer1Variant::Delay`](crate::Layer1Variant::Delay) the one given the frame before
    /// (`None` before the first frame).
    pub fn image_camera(&self) -> Option<&Camera> {
        self.image_camera.as_ref()
    }

    /// Writes the frame's constants and makes every stage `plan` needs ready for it; returns
    /// this frame's camera matrices. `camera` is the one the frame shows, `given` the one it was
    /// given (they differ with one frame of latency).
    fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        (camera, given): (&Camera, &Camera),
        plan: &Plan,
    ) -> Result<CameraMatrices> {
        let moved = plan.contains(&PassId::Resolve)
            && self.stages.resolve.prepare(device, scene, self.geometry_generation);
        let uniform = self.constants(scene, camera, moved);
        let s = &self.settings;
        let current = CameraMatrices::new(camera, s.width, s.height);
        let previous = self.history.unwrap_or(current);
        let counts = scene.counts();
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(&uniform));
        self.last_frame = Some(uniform);
        // The layer 0 the next frame's layer 1 is tested against: from the camera that frame
        // will show (Delay) or from this one moved again as it moved since the last (Predict).
        let next = plan.contains(&PassId::RasterNext).then(|| {
            let (w, h) = (s.width, s.height);
            if s.layer1 == crate::Layer1Variant::Delay {
                let m = CameraMatrices::new(given, w, h);
                FrameUniform::new(given, m, m, w, h, s.dz, counts)
            } else {
                let view = current.view * previous.view.inverse() * current.view;
                let m = CameraMatrices { view, proj: current.proj };
                FrameUniform::new(camera, m, current, w, h, s.dz, counts)
            }
        });
        let radiosity_still = self.radiosity_still();
        let st = &mut self.stages;
        let kept = plan.reused.iter().any(PassId::is_gbuffer);
        // The largest target the rasterizer draws: the image or a shadow-map face.
        let face = u64::from(s.shadows.resolution).pow(2);
        let targets = (u64::from(s.width) * u64::from(s.height)).max(face);
        st.raster.prepare(device, queue, (scene, targets), next.as_ref(), kept);
        if plan.runs(Effect::Shadows) {
            let shadows = ShadowStage::for_plan(st.shadows.take(), device, s, scene, plan)?;
            shadows.prepare(queue, scene);
            st.shadows = Some(shadows);
        }
        if plan.runs(Effect::Ao)
            && st.ao.as_ref().is_none_or(|a| a.two_layers() != plan.ao_two_layers)
        {
            st.ao = Some(AoStage::new(device, s, plan.ao_two_layers));
        }
        if let Some(ao) = st.ao.as_mut() {
            if plan.contains(&PassId::Ao) {
                let filters = plan.contains(&PassId::AoTemporal);
                ao.prepare(queue, s, (self.history.is_some(), filters), self.still_frames);
            } else if !plan.reused.contains(&PassId::Ao) {
                ao.skipped();
            }
        }
        st.direct.prepare(queue, scene, s, plan);
        // A still view that keeps its radiosity keeps this frame's buffers as they are.
        if plan.contains(&PassId::Radiosity) {
            // The history is usable only if this stage drew the last frame.
            let history = self.history.is_some() && st.radiosity.is_some();
            let radiosity = st.radiosity.get_or_insert_with(|| RadiosityStage::new(device, s));
            // The reflective shadow maps' faces the off-screen light sums (none without it).
            let offscreen =
                st.shadows.as_ref().and_then(|s| s.rsm_inputs(plan)).map_or(0, |r| r.count);
            radiosity.prepare(device, queue, s, (history, radiosity_still), plan, offscreen);
        }
        if plan.runs(Effect::Reflections) {
            let reflections =
                st.reflections.get_or_insert_with(|| ReflectionsStage::new(device, s));
            let env = self.environment.as_ref().map(|e| e.size);
            reflections.prepare(queue, s, scene, plan, env);
        }
        if plan.runs(Effect::Transparency) {
            let t = st.transparency.get_or_insert_with(|| TransparencyStage::new(device, s));
            t.prepare(queue, scene);
        }
        st.composite.prepare(queue, scene);
        if plan.passes.iter().any(PassId::is_post) {
            st.composite.make_post(device);
        }
        if plan.runs(Effect::Dof) {
            let dof = st.dof.get_or_insert_with(|| DofStage::new(device));
            dof.prepare(queue, s, camera, scene.info());
        }
        if plan.runs(Effect::MotionBlur) {
            let motion = st.motion_blur.get_or_insert_with(|| MotionBlurStage::new(device, s));
            motion.prepare(queue, s, scene.info());
        }
        Ok(current)
    }

    /// [`encode`](Renderer::encode), then copies the HDR composite (`vec4<f32>` per pixel, row
    /// major) into the caller's `target` buffer (COPY_DST, at least `width * height * 16` bytes).
    pub fn encode_to(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        camera: &Camera,
        target: &wgpu::Buffer,
    ) -> Result<()> {
        let bytes = u64::from(self.settings.width) * u64::from(self.settings.height) * 16;
        if target.size() < bytes || !target.usage().contains(wgpu::BufferUsages::COPY_DST) {
            return Err(Error::ImportedBuffer {
                name: "target",
                message: format!(
                    "needs COPY_DST usage and {bytes} bytes (has {} bytes, {:?})",
                    target.size(),
                    target.usage()
                ),
            });
        }
        self.encode(device, queue, encoder, scene, camera)?;
        encoder.copy_buffer_to_buffer(self.stages.composite.hdr(), 0, target, 0, bytes);
        Ok(())
    }

    /// [`encode`](Renderer::encode), then writes the HDR composite into the caller's storage
    /// texture: `Rgba32Float` or `Rgba16Float`, the renderer's size, with STORAGE_BINDING usage.
    pub fn encode_to_texture(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        camera: &Camera,
        texture: &wgpu::Texture,
    ) -> Result<()> {
        let format = texture.format();
        if !matches!(format, wgpu::TextureFormat::Rgba32Float | wgpu::TextureFormat::Rgba16Float) {
            return Err(Error::ImportedBuffer {
                name: "texture",
                message: format!("format {format:?}; expected Rgba32Float or Rgba16Float"),
            });
        }
        let (w, h) = (self.settings.width, self.settings.height);
        let size = texture.size();
        if (size.width, size.height) != (w, h)
            || !texture.usage().contains(wgpu::TextureUsages::STORAGE_BINDING)
        {
            return Err(Error::ImportedBuffer {
                name: "texture",
                message: format!(
                    "{}x{} with {:?}; needs {w}x{h} and STORAGE_BINDING",
                    size.width,
                    size.height,
                    texture.usage()
                ),
            });
        }
        self.encode(device, queue, encoder, scene, camera)?;
        gpu::scoped(device, "deep-gbuffer.present", || {
            let hdr = self.stages.composite.hdr();
            let pipelines = &self.pipelines;
            self.present.record(device, pipelines, encoder, &self.frame, hdr, texture);
            Ok(())
        })
    }

    /// Encodes and submits one frame on `queue`.
    pub fn render(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        camera: &Camera,
    ) -> Result<()> {
        self.submit_frame(device, queue, scene, camera, false)
    }

    /// Shades a deep G-buffer that the caller provides instead of rasterizing one: the layers
    /// (one, or two when the plan reads layer 1; of the renderer's size) are uploaded in the full
    /// encoding and every pass after `resolve` runs on them, with the scene's lights, materials
    /// and shadow casters and `camera`'s matrices. This is how the kernels are tested on stored
    /// G-buffers (fixtures/gbuffer/), and how a host that draws its own G-buffer uses the
    /// lighting alone. Needs [`Precision::Full`](crate::Precision::Full).
    pub fn render_gbuffer(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        camera: &Camera,
        layers: &[GBufferLayer],
    ) -> Result<()> {
        self.check_provided(scene, camera, layers)?;
        let s = &self.settings;
        let empty = GBufferLayer {
            width: s.width,
            height: s.height,
            samples: vec![Default::default(); (s.width * s.height) as usize],
        };
        let layer1 = layers.get(1).unwrap_or(&empty);
        let raster = &self.stages.raster;
        let targets = [
            (self.stages.resolve.gbuffer(0), raster.next_vis0()),
            (self.stages.resolve.gbuffer(1), raster.vis1()),
        ];
        for (l, (gbuffer, vis)) in [&layers[0], layer1].into_iter().zip(targets) {
            queue.write_buffer(gbuffer, 0, bytemuck::cast_slice(&l.encode_full()));
            let words: Vec<u64> =
                l.samples
                    .iter()
                    .map(|s| {
                        if s.depth > 0.0 {
                            gbuffer::vis_pack(s.depth, 0)
                        } else {
                            gbuffer::VIS_EMPTY
                        }
                    })
                    .collect();
            queue.write_buffer(vis, 0, bytemuck::cast_slice(&words));
        }
        self.submit_frame(device, queue, scene, camera, true)
    }

    /// Refuses provided G-buffer layers that do not fit this renderer and `scene`'s plan.
    fn check_provided(
        &self,
        scene: &SceneBuffers,
        camera: &Camera,
        layers: &[GBufferLayer],
    ) -> Result<()> {
        let s = &self.settings;
        if s.precision != crate::Precision::Full {
            return Err(Error::setting(
                "precision",
                "a provided G-buffer is uploaded in the full encoding (set precision to full)",
            ));
        }
        let needed = self.plan(scene, camera).layers as usize;
        if layers.len() < needed || layers.len() > 2 {
            return Err(Error::setting(
                "gbuffer",
                format!("{} layers given, the plan reads {needed} (give 1 or 2)", layers.len()),
            ));
        }
        for (i, l) in layers.iter().enumerate() {
            if (l.width, l.height) != (s.width, s.height)
                || l.samples.len() != (s.width * s.height) as usize
            {
                return Err(Error::setting(
                    "gbuffer",
                    format!(
                        "layer {i} is {}x{} with {} samples, the renderer is {}x{}",
                        l.width,
                        l.height,
                        l.samples.len(),
                        s.width,
                        s.height
                    ),
                ));
            }
            if let Some(p) =
                l.samples.iter().position(|x| !x.channels().iter().all(|w| w.is_finite()))
            {
                return Err(Error::setting(
                    "gbuffer",
                    format!("layer {i} pixel {p} holds a NaN or infinite value"),
                ));
            }
        }
        Ok(())
    }

    /// Records a frame into an encoder of its own and submits it, GPU errors caught.
    fn submit_frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        camera: &Camera,
        provided: bool,
    ) -> Result<()> {
        let result = gpu::scoped(device, "deep-gbuffer.frame", || {
            let label = Some("deep-gbuffer.frame");
            let mut encoder =
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label });
            self.encode_frame(device, queue, &mut encoder, scene, camera, provided)?;
            let index = queue.submit([encoder.finish()]);
            // At most two frames in flight: wait for the one before. This also lets the device
            // free what finished frames used; without it a loop of renders that never polls
            // keeps every frame's transient objects alive.
            if let Some(previous) = self.in_flight.replace(index) {
                device
                    .poll(wgpu::PollType::Wait { submission_index: Some(previous), timeout: None })
                    .map_err(|e| Error::Gpu {
                        label: "deep-gbuffer.frame".into(),
                        message: e.to_string(),
                    })?;
            }
            Ok(())
        });
        if result.is_err() {
            self.still = None;
        }
        result
    }

    /// Per-pass GPU times of the last submitted frame (empty without `TIMESTAMP_QUERY`), named
    /// as [`PassId::name`] spells them, with the bytes each pass binds ([`Renderer::traffic`]).
    pub fn timings(&self, device: &wgpu::Device) -> Result<Vec<PassTiming>> {
        let mut timings = match &self.timestamps {
            Some(t) => t.read(device)?,
            None => Vec::new(),
        };
        for t in &mut timings {
            if let Some(traffic) = self.traffic.iter().find(|p| p.name == t.name) {
                (t.read_bytes, t.written_bytes) = (traffic.read_bytes, traffic.written_bytes);
            }
        }
        Ok(timings)
    }

    /// The bytes each pass of the last recorded frame binds (each storage buffer once per pass,
    /// at its whole size, read-only or read-write), in the order the passes ran: divided by the
    /// device's bandwidth ([`measure_bandwidth`](crate::gpu::measure_bandwidth)), the time under
    /// which a pass that reads and writes each of those bytes once cannot run.
    pub fn traffic(&self) -> &[crate::gpu::PassTraffic] {
        &self.traffic
    }

    /// The visibility buffer of `layer` (0 or 1): `u64` words `(depth bits << 32) | triangle id`.
    pub fn visibility_buffer(&self, layer: usize) -> &wgpu::Buffer {
        if layer == 0 { self.stages.raster.vis0() } else { self.stages.raster.vis1() }
    }

    /// The G-buffer of `layer` (layout in `wgsl/shared/gbuffer.wgsl`).
    pub fn gbuffer_buffer(&self, layer: usize) -> &wgpu::Buffer {
        self.stages.resolve.gbuffer(layer)
    }

    /// Refuses a layer the last frame did not draw.
    fn check_drawn(&self, layer: usize) -> Result<()> {
        let drawn = self.plan.as_ref().map_or(0, |p| p.layers as usize);
        if layer >= drawn {
            return Err(Error::LayerNotDrawn { layer, drawn });
        }
        Ok(())
    }

    /// Reads a visibility buffer back (waits for the GPU); a layer the last frame did not draw
    /// is [`Error::LayerNotDrawn`].
    pub fn read_visibility(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        layer: usize,
    ) -> Result<Vec<u64>> {
        self.check_drawn(layer)?;
        let bytes = gpu::read_buffer(device, queue, self.visibility_buffer(layer))?;
        let n = (self.settings.width * self.settings.height) as usize;
        Ok(bytemuck::pod_collect_to_vec::<u8, u64>(&bytes[..n * 8]))
    }

    /// Reads and decodes a G-buffer layer (waits for the GPU); a layer the last frame did not
    /// draw is [`Error::LayerNotDrawn`].
    pub fn read_gbuffer(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        layer: usize,
    ) -> Result<GBufferLayer> {
        self.check_drawn(layer)?;
        let bytes = gpu::read_buffer(device, queue, self.gbuffer_buffer(layer))?;
        let s = &self.settings;
        GBufferLayer::decode(&bytes, s.width, s.height, s.precision)
    }

    /// Whether the last frame ran `effect`.
    fn ran(&self, effect: Effect) -> bool {
        self.plan.as_ref().is_some_and(|p| p.runs(effect))
    }

    /// The ambient visibility AV in [0, 1] per pixel (f32, row-major; blurred unless the blur
    /// radius is 0), or `None` when obscurance is off.
    pub fn ao_buffer(&self) -> Option<&wgpu::Buffer> {
        let ao = self.stages.ao.as_ref().filter(|_| self.ran(Effect::Ao))?;
        Some(ao.av(&self.settings))
    }

    /// The obscurance before the blur, or `None` when obscurance has not run.
    pub fn ao_raw_buffer(&self) -> Option<&wgpu::Buffer> {
        self.stages.ao.as_ref().map(AoStage::raw)
    }

    /// The obscurance after its temporal filter, before the blur (f32 per pixel), or `None`
    /// when obscurance has not run or runs without the filter ([`AoSettings::alpha`](crate::AoSettings) 0).
    pub fn ao_filtered_buffer(&self) -> Option<&wgpu::Buffer> {
        self.stages.ao.as_ref().and_then(AoStage::filtered)
    }

    /// The obscurance as computed at 1 / [`AoSettings::downsample`](crate::AoSettings) of the
    /// image's width and height (f32 per texel of that level of the rotated grid, before the
    /// upsample), or `None` when obscurance has not run or runs at full resolution.
    pub fn ao_low_buffer(&self) -> Option<&wgpu::Buffer> {
        self.stages.ao.as_ref().and_then(AoStage::low)
    }

    /// The depth pyramid of `layer` (levels packed as in
    /// [`PyramidLayout`](crate::frame::PyramidLayout)), or `None` when obscurance has not run.
    pub fn pyramid_buffer(&self, layer: usize) -> Option<&wgpu::Buffer> {
        self.stages.ao.as_ref().map(|ao| ao.pyramid(layer))
    }

    /// The shadow maps of the last frame, every face's visibility words back to back (in the
    /// order of [`light_faces`](crate::frame::light_faces)), or `None` without shadows.
    pub fn shadow_atlas_buffer(&self) -> Option<&wgpu::Buffer> {
        self.stages.shadows.as_ref().filter(|_| self.ran(Effect::Shadows)).map(ShadowStage::atlas)
    }

    /// The radiosity buffers of the last frame, or `None` when radiosity is off.
    pub fn radiosity_buffers(&self) -> Option<RadiosityBuffers<'_>> {
        let r = self.stages.radiosity.as_ref().filter(|_| self.ran(Effect::Radiosity))?;
        Some(r.buffers(&self.settings))
    }

    /// The off-screen light's buffers of the last frame, or `None` when it did not run
    /// ([`RadiositySettings::offscreen`](crate::RadiositySettings::offscreen)).
    pub fn offscreen_buffers(&self) -> Option<OffscreenBuffers<'_>> {
        let rsm = self.stages.shadows.as_ref()?.rsm_inputs(self.plan.as_ref()?)?;
        let clusters = self.stages.radiosity.as_ref()?.clusters()?;
        Some(OffscreenBuffers {
            faces: rsm.faces,
            face_lights: rsm.face_lights,
            vis: rsm.vis,
            records: rsm.gbuffer,
            face_count: rsm.count,
            clusters,
        })
    }

    /// The reflected radiance (rgb, scaled by the reflectivity) and its confidence (a) of the
    /// last frame, `vec4<f32>` per pixel; `None` when no reflection pass ran.
    pub fn reflections_buffer(&self) -> Option<&wgpu::Buffer> {
        let r = self.stages.reflections.as_ref().filter(|_| self.ran(Effect::Reflections))?;
        Some(r.output())
    }

    /// The HDR image of the last frame: `vec4<f32>` per pixel, linear radiance (a = 1 on
    /// surfaces, 0 on the sky).
    pub fn hdr_buffer(&self) -> &wgpu::Buffer {
        self.stages.composite.hdr()
    }

    /// The composite's image when a pass that reads it ran in the last frame (the
    /// transparency's composite, depth of field, motion blur: `hdr_buffer` then holds their
    /// result), else `None`.
    pub fn sharp_buffer(&self) -> Option<&wgpu::Buffer> {
        let ran = self.plan.as_ref().is_some_and(|p| p.passes.iter().any(PassId::is_post));
        self.stages.composite.post().filter(|_| ran).map(|[first, _]| first)
    }

    /// The direct radiance of layer 0 in the last frame (`vec4<f32>` per pixel; zero when no
    /// light runs).
    pub fn direct_buffer(&self) -> &wgpu::Buffer {
        self.stages.direct.radiance(0)
    }

    /// The direct radiance of layer 1 (computed when the radiosity, the depth of field or the
    /// motion blur read it).
    pub fn direct1_buffer(&self) -> &wgpu::Buffer {
        self.stages.direct.radiance(1)
    }

    /// The Lambertian part of the direct radiance of `layer` (0 or 1; `vec4<f32>` per pixel,
    /// written when the radiosity runs): `(1 - metallic) base colour / pi` times the direct
    /// irradiance, the light the radiosity gather passes on.
    pub fn diffuse_buffer(&self, layer: usize) -> &wgpu::Buffer {
        self.stages.direct.diffuse(layer)
    }

    /// Reads an f32 per-pixel buffer such as [`ao_buffer`](Renderer::ao_buffer) back.
    pub fn read_f32(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<f32>> {
        let bytes = gpu::read_buffer(device, queue, buffer)?;
        Ok(bytemuck::pod_collect_to_vec::<u8, f32>(&bytes[..bytes.len() / 4 * 4]))
    }

    /// Reads a `vec4<f32>` per-pixel buffer (HDR, direct radiance) back, one value per pixel.
    pub fn read_vec4(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<glam::Vec4>> {
        let values = self.read_f32(device, queue, buffer)?;
        let n = (self.settings.width * self.settings.height) as usize;
        Ok(values.chunks_exact(4).take(n).map(glam::Vec4::from_slice).collect())
    }

    /// Reads a `vec4<f32>` per-pixel image (HDR, direct radiance) back as rgb.
    pub fn read_rgb(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        buffer: &wgpu::Buffer,
    ) -> Result<Vec<Vec3>> {
        Ok(self.read_vec4(device, queue, buffer)?.into_iter().map(|v| v.truncate()).collect())
    }

    /// Reads every lighting term of the last frame back (waits for the GPU).
    pub fn read_terms(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Terms> {
        let n = (self.settings.width * self.settings.height) as usize;
        let av = match self.ao_buffer() {
            Some(b) => Some(self.read_f32(device, queue, b)?.into_iter().take(n).collect()),
            None => None,
        };
        let (indirect, radiosity) = match self.radiosity_buffers() {
            Some(r) => {
                let e = self.read_vec4(device, queue, r.irradiance)?;
                let indirect: Vec<Vec3> = e.iter().map(|c| c.truncate()).collect();
                let layer0 = self.read_gbuffer(device, queue, 0)?;
                let radiosity = indirect
                    .iter()
                    .zip(&layer0.samples)
                    .map(|(e, s)| (1.0 - s.metallic) * s.base_color / std::f32::consts::PI * *e)
                    .collect();
                (Some(indirect), Some(radiosity))
            }
            None => (None, None),
        };
        let reflections = match self.reflections_buffer() {
            Some(b) => Some(self.read_rgb(device, queue, b)?),
            None => None,
        };
        Ok(Terms {
            av,
            direct: self.read_rgb(device, queue, self.direct_buffer())?,
            indirect,
            radiosity,
            reflections,
            hdr: self.read_rgb(device, queue, self.hdr_buffer())?,
        })
    }

    /// The frame constants of the last [`encode`](Renderer::encode): what the CPU references
    /// need to reproduce the frame.
    pub fn frame_uniform(&self) -> Option<&FrameUniform> {
        self.last_frame.as_ref()
    }

    /// The uniform buffer holding the last frame's [`FrameUniform`] (camera and image size),
    /// for passes of the caller's that follow this stage.
    pub fn frame_buffer(&self) -> &wgpu::Buffer {
        &self.frame
    }

    /// Reads the raster counters and the bad-input counts of the last frame that drew the G-buffer
    /// (waits for the GPU).
    pub fn diagnostics(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Diagnostics> {
        Ok(self.stages.raster.rasterizer.counters(device, queue)?.into())
    }
}
