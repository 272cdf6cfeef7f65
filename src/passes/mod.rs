//! The GPU side of each kernel.
//!
//! A *stage* owns the pipelines, buffers, uniforms and bind groups of one part of the frame and
//! records the [passes](crate::plan::PassId) it owns from a [`FrameContext`]: what the frame
//! reads (scene, settings, plan) and what the stages before it wrote. The renderer prepares
//! every stage the plan needs, then walks the plan and hands each pass to its stage.
//!
//! `blur`, `fill`, `present`, `pyramid` and `temporal` are kernels that stages share (the
//! obscurance and the radiosity both blur and filter over time; the raster and the shadow maps
//! both fill).

pub(crate) mod ao;
pub(crate) mod baseline;
pub(crate) mod blur;
pub(crate) mod composite;
pub(crate) mod direct;
pub(crate) mod dof;
pub(crate) mod fill;
pub(crate) mod motion_blur;
pub(crate) mod offscreen;
pub(crate) mod present;
pub(crate) mod pyramid;
pub(crate) mod radiosity;
pub(crate) mod raster;
pub(crate) mod reflections;
pub(crate) mod resolve;
pub(crate) mod shadow;
pub(crate) mod temporal;
pub(crate) mod transparency;
pub(crate) mod upsample;

use crate::SceneBuffers;
use crate::gpu::{PassTraffic, Pipelines, Timestamps, traffic};
use crate::plan::{PassId, Plan};
use crate::settings::Settings;

/// A list of the items (pixels, texels) a kernel runs at, built on the GPU each frame, and the
/// indirect dispatch over it (`wgsl/shared/list.wgsl`: 64 items a workgroup).
pub(crate) struct PointList {
    /// The count, then an item each.
    pub list: wgpu::Buffer,
    /// The dispatch arguments (not bound with the dispatch that reads them).
    pub args: wgpu::Buffer,
}

impl PointList {
    /// A list of up to `capacity` items, its buffers labelled `label` and `label_args`.
    pub(crate) fn new(device: &wgpu::Device, label: &str, capacity: u64) -> Self {
        let buffer =
            |label: &str, size, usage| crate::gpu::storage_buffer(device, label, size, usage);
        PointList {
            list: buffer(label, (1 + capacity) * 4, wgpu::BufferUsages::empty()),
            args: buffer(&format!("{label}_args"), 12, wgpu::BufferUsages::INDIRECT),
        }
    }

    /// Empties the list (before the kernel that appends to it).
    pub(crate) fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.clear_buffer(&self.list, 0, Some(4));
    }
}

/// Records a frame's passes into the caller's encoder, each in a compute pass of its own, named
/// by its [`PassId`], timed when timestamps are on, and with the bytes it binds counted
/// ([`traffic`]).
pub(crate) struct Recorder<'a> {
    encoder: &'a mut wgpu::CommandEncoder,
    timestamps: Option<&'a mut Timestamps>,
    recorded: Vec<PassId>,
}

impl<'a> Recorder<'a> {
    pub(crate) fn new(
        encoder: &'a mut wgpu::CommandEncoder,
        mut timestamps: Option<&'a mut Timestamps>,
    ) -> Self {
        if let Some(t) = timestamps.as_deref_mut() {
            t.reset();
        }
        traffic::begin();
        Recorder { encoder, timestamps, recorded: Vec::new() }
    }

    /// Begins the compute pass of `id` (end it by dropping it before the next call).
    pub(crate) fn pass(&mut self, id: &PassId) -> wgpu::ComputePass<'static> {
        self.recorded.push(id.clone());
        let name = id.name();
        traffic::pass(&name);
        let label = format!("deep-gbuffer.{name}");
        let timestamp_writes = self.timestamps.as_deref_mut().and_then(|t| t.pass(&name));
        self.encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&label),
                timestamp_writes,
            })
            .forget_lifetime()
    }

    /// The encoder, for copies and clears between passes.
    pub(crate) fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        self.encoder
    }

    /// Resolves the timestamps and returns the passes recorded, in order, and the bytes each
    /// binds.
    pub(crate) fn finish(self) -> (Vec<PassId>, Vec<PassTraffic>) {
        if let Some(t) = &self.timestamps {
            t.resolve(self.encoder);
        }
        (self.recorded, traffic::finish())
    }
}

/// The bind entries of the scene buffers `wgsl/shared/surface.wgsl` reads (a triangle's surface
/// where a ray meets it), for the kernel whose generated slots module is `$slot`.
macro_rules! surface_entries {
    ($slot:ident, $scene:expr) => {{
        let scene: &crate::SceneBuffers = $scene;
        let b = scene.buffers();
        [
            ($slot::POSITIONS, &b.positions),
            ($slot::NORMALS, &b.normals),
            ($slot::UVS, &b.uvs),
            ($slot::INDICES, &b.indices),
            ($slot::TRI_MATERIALS, &b.triangle_materials),
            ($slot::MATERIALS, &b.materials),
            ($slot::TEXELS, &b.texels),
            ($slot::UVS1, &scene.uvs1),
            ($slot::TANGENTS, &scene.tangents),
        ]
    }};
}
pub(crate) use surface_entries;

/// The pipeline constant `TEXTURES` (`wgsl/shared/texture.wgsl`) for `scene`: texture reads
/// compiled in unless the scene is marked [`textureless`](crate::SceneInfo::textureless).
pub(crate) fn textures_constant(scene: &SceneBuffers) -> (&'static str, f64) {
    ("TEXTURES", f64::from(u8::from(!scene.info().textureless)))
}

/// The shadow inputs of the direct kernel.
#[derive(Clone, Copy)]
pub(crate) struct ShadowInputs<'a> {
    /// `ShadowFace` per face.
    pub faces: &'a wgpu::Buffer,
    /// `(first face, face count)` per light.
    pub light_faces: &'a wgpu::Buffer,
    /// Every face's visibility words.
    pub atlas: &'a wgpu::Buffer,
}

/// What `wgsl/offscreen.wgsl` reads of the reflective shadow maps.
#[derive(Clone, Copy)]
pub(crate) struct RsmInputs<'a> {
    /// `ShadowFace` per face (at [`RSM_RESOLUTION`](crate::frame::RSM_RESOLUTION), offsets in
    /// texels).
    pub faces: &'a wgpu::Buffer,
    /// The light of each face.
    pub face_lights: &'a wgpu::Buffer,
    /// Every face's visibility words.
    pub vis: &'a wgpu::Buffer,
    /// Every face's G-buffer records.
    pub gbuffer: &'a wgpu::Buffer,
    /// How many faces.
    pub count: u32,
}

/// What the frame's stages read: the frame's inputs, and the targets the stages before wrote.
pub(crate) struct FrameContext<'a> {
    pub device: &'a wgpu::Device,
    pub pipelines: &'a Pipelines,
    pub scene: &'a SceneBuffers,
    pub settings: &'a Settings,
    pub plan: &'a Plan,
    /// The frame uniform ([`FrameUniform`](crate::frame::FrameUniform)).
    pub frame: &'a wgpu::Buffer,
    /// The rasterizer and its visibility buffers (the shadow maps draw with it too).
    pub raster: &'a raster::RasterStage,
    /// The G-buffer layers.
    pub gbuffer: [&'a wgpu::Buffer; 2],
    /// The vertex positions of the last frame, when the geometry moved since (the motion of
    /// moving geometry, the positions `Predict` extrapolates).
    pub previous_positions: Option<&'a wgpu::Buffer>,
    /// The shadow maps, when the plan draws them.
    pub shadows: Option<ShadowInputs<'a>>,
    /// The reflective shadow maps, when the plan adds the off-screen light.
    pub rsm: Option<RsmInputs<'a>>,
    /// Direct radiance of each layer.
    pub direct: [&'a wgpu::Buffer; 2],
    /// Its Lambertian part, of each layer (written when the radiosity runs).
    pub diffuse: [&'a wgpu::Buffer; 2],
    /// The direct-light stage, which lights other G-buffers too (the transparency's peels).
    pub lighting: &'a direct::DirectStage,
    /// The ambient visibility the composite reads, when obscurance runs.
    pub av: Option<&'a wgpu::Buffer>,
    /// The irradiance the composite reads, when radiosity runs.
    pub irradiance: Option<&'a wgpu::Buffer>,
    /// The reflected radiance, when reflections run.
    pub reflections: Option<&'a wgpu::Buffer>,
    /// The environment map missed reflection rays see, when one is set.
    pub environment: Option<&'a wgpu::Buffer>,
    /// The HDR image the frame ends in.
    pub hdr: &'a wgpu::Buffer,
    /// Two images of the HDR image's size for the passes after the composite (depth of field,
    /// motion blur), when the plan runs one.
    pub post: Option<[&'a wgpu::Buffer; 2]>,
}

impl<'a> FrameContext<'a> {
    /// The image size.
    pub(crate) fn size(&self) -> (u32, u32) {
        (self.settings.width, self.settings.height)
    }

    /// The image `pass` reads (`None` for the composite, which makes one) and the one it writes:
    /// the composite writes the HDR image, or the first post pass's input when the plan runs
    /// post passes ([`PassId::is_post`]); each post pass reads the one before's output, and the
    /// last writes the HDR image.
    pub(crate) fn image_io(&self, pass: &PassId) -> (Option<&'a wgpu::Buffer>, &'a wgpu::Buffer) {
        let posts: Vec<&PassId> = self.plan.passes.iter().filter(|p| p.is_post()).collect();
        let Some(spare) = self.post.filter(|_| !posts.is_empty()) else {
            return (None, self.hdr);
        };
        match posts.iter().position(|p| *p == pass) {
            None => (None, spare[0]),
            Some(i) => {
                let output = if i + 1 == posts.len() { self.hdr } else { spare[(i + 1) % 2] };
                (Some(spare[i % 2]), output)
            }
        }
    }
}

/// One part of the frame: records the passes it owns.
pub(crate) trait Stage {
    /// Records work outside any pass that the frame needs before its passes (clears). Called on
    /// every stage made so far, whether or not the plan runs it.
    fn begin(&self, _ctx: &FrameContext<'_>, _rec: &mut Recorder<'_>) {}

    /// Records `pass`, one of the stage's own.
    fn record(&self, pass: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>);
}
