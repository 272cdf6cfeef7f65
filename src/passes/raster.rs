//! `wgsl/raster.wgsl`: the compute rasterizer that writes visibility buffers.
//!
//! One raster step is three dispatches: `raster_small` over all triangles (small ones are
//! rasterized in place, large ones binned), `bin_args` (indirect arguments) and `raster_large`
//! (indirect, 16x16 tiles). On the 32-bit path every step runs twice: a depth phase, then an id
//! phase; on the 64-bit path once.
//!
//! A binned triangle's set-up is stored once (64 bytes, `Binned` in the shader) and read by every
//! workgroup that draws it; it gets one workgroup per 8 of its 16x16 tiles, the first implied by
//! its entry and the others listed as work items (8 bytes each).

use super::fill::Fill;
use super::{FrameContext, Recorder, Stage};
use crate::SceneBuffers;
use crate::frame::{FrameUniform, RasterCounters};
use crate::gpu::{self, Pipelines, slots::raster as slot};
use crate::plan::PassId;
use crate::settings::{Layer1Variant, RasterWork};

/// What one raster step writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum RasterMode {
    /// Layer 0 only.
    Layer0,
    /// Layer 1 only, against `zref` (the final layer 0 of this frame).
    Layer1,
    /// Both layers in one pass, layer 1 against `zref` (the previous frame's layer 0), compared
    /// at the same pixel or, with `reproject`, at the fragment's position in the previous frame.
    Both {
        /// Compare at the reprojected position.
        reproject: bool,
    },
    /// Count every covered fragment per pixel into a u32 buffer (watertightness tests).
    Count,
    /// One transparency peel: blended triangles only, into `vis1`, the nearest fragment behind
    /// `zref` (the previous peel) and in front of `opaque` (this frame's layer 0).
    Peel,
    /// Counts the fragments a peel after `zref` would accept into the diagnostics.
    Unpeeled,
}

impl RasterMode {
    fn defines(self) -> Vec<&'static str> {
        match self {
            RasterMode::Layer0 => vec!["WRITE_L0"],
            RasterMode::Layer1 => vec!["WRITE_L1"],
            RasterMode::Both { reproject: false } => vec!["WRITE_L0", "WRITE_L1"],
            RasterMode::Both { reproject: true } => vec!["WRITE_L0", "WRITE_L1", "REPROJECT"],
            RasterMode::Count => vec!["COUNT"],
            RasterMode::Peel => vec!["WRITE_L1", "PEEL"],
            RasterMode::Unpeeled => vec!["WRITE_L1", "PEEL", "UNPEELED"],
        }
    }
}

/// Bytes of the indirect arguments (one dispatch of 4 u32).
const ARGS_BYTES: u64 = 16;

/// Bytes of a binned triangle's set-up (`Binned`).
const ENTRY_BYTES: u64 = 64;

/// Bytes of a work item (`items`: entry and slice).
const ITEM_BYTES: u64 = 8;

/// Binned triangles and work items with room for `triangles` triangles drawn into targets of up
/// to `pixels` pixels, each within `limit` bytes: one entry per triangle plus slack for clipped
/// sub-triangles (only triangles over 16 pixels across are binned), and as many work items plus
/// four per 16x16 tile of the target. A triangle takes a slice per `TILES_PER_SLICE` tiles of its
/// bounds (8 shared out as on a GPU, 64 on a CPU driver), so at 8 the tiles' share holds the
/// slices of 32 triangles whose bounds cover the target: few large triangles (a room's walls at
/// 3840x2160) each get their slices, where room for the triangle count alone left them one
/// workgroup each.
fn bin_sizes(triangles: u32, pixels: u64, limit: u64) -> (u64, u64) {
    let entries = u64::from(triangles) + 4096;
    let items = entries + pixels.div_ceil(256) * 4;
    let within = |count: u64, size: u64| (count * size).min(limit / size * size);
    (within(entries, ENTRY_BYTES), within(items, ITEM_BYTES))
}

/// One raster step: the camera it draws with, what it writes, and the buffers it writes
/// besides the rasterizer's own.
#[derive(Clone, Copy)]
pub(crate) struct Draw<'a> {
    /// The frame uniform of the camera drawn from.
    pub frame: &'a wgpu::Buffer,
    /// What the step writes.
    pub mode: RasterMode,
    /// Layer 0 visibility buffer (Layer0, Both).
    pub vis0: Option<&'a wgpu::Buffer>,
    /// Layer 1 visibility buffer (Layer1, Both).
    pub vis1: Option<&'a wgpu::Buffer>,
    /// The visibility buffer layer 1 is separated from (Layer1, Both).
    pub zref: Option<&'a wgpu::Buffer>,
    /// Per-pixel fragment counts (Count).
    pub counts: Option<&'a wgpu::Buffer>,
    /// The opaque layer 0 peeled fragments lie in front of (Peel).
    pub opaque: Option<&'a wgpu::Buffer>,
    /// Where a peel writes the indirect arguments of its per-pixel kernels (Peel).
    pub peel_args: Option<&'a wgpu::Buffer>,
    /// Vertex positions to draw instead of the scene's.
    pub positions: Option<&'a wgpu::Buffer>,
}

impl<'a> Draw<'a> {
    /// A step drawn with `frame` in `mode`, its targets to be set.
    pub(crate) fn new(frame: &'a wgpu::Buffer, mode: RasterMode) -> Self {
        Draw {
            frame,
            mode,
            vis0: None,
            vis1: None,
            zref: None,
            counts: None,
            opaque: None,
            peel_args: None,
            positions: None,
        }
    }
}

/// The rasterizer's pipeline constants for `work` (resolved: [`RasterWork::Gpu`] or
/// [`RasterWork::Cpu`]): the largest triangle one thread draws, the 16x16 tiles a binned
/// triangle's workgroup takes, and whether tiles wholly outside the triangle skip the exact test.
///
/// A GPU runs thousands of threads at once and starts a workgroup cheaply: small triangles stay
/// small (16 pixels) and a binned triangle is spread thin (8 tiles a workgroup). A CPU driver
/// runs a few threads, and each workgroup costs it about as much as drawing a few tiles
/// (lavapipe, 2 cores, 1920x1080: the Cornell box's layer 0 took 67 ms at 8 tiles a workgroup,
/// 41 at 64, 48 at 256; the 2CylinderEngine's 415 at (16, 8), 320 at (16, 64), 185 at (64, 64)),
/// so it gets fewer, larger ones. A GPU skips the exact test of a tile outside the triangle (the
/// tile's threads all take the branch); a CPU driver runs both sides of every branch, so there
/// the test only adds its arithmetic to every pixel (lavapipe, Cornell 1920x1080, five
/// alternated rounds: layer 0 14.2-18.8 ms with it, median 14.8; 11.8-16.2 without, median
/// 12.3).
fn work_constants(work: RasterWork) -> [(&'static str, f64); 3] {
    let (small_extent, tiles_per_slice, tile_test) = match work {
        RasterWork::Cpu => (64u8, 64u8, false),
        RasterWork::Gpu | RasterWork::Auto => (16, 8, true),
    };
    [
        ("SMALL_EXTENT", f64::from(small_extent)),
        ("TILES_PER_SLICE", f64::from(tiles_per_slice)),
        ("TILE_TEST", f64::from(u8::from(tile_test))),
    ]
}

/// `work` on `device`: [`RasterWork::Auto`] resolved by the device's type.
fn resolve_work(work: RasterWork, device: &wgpu::Device) -> RasterWork {
    match work {
        RasterWork::Auto if device.adapter_info().device_type == wgpu::DeviceType::Cpu => {
            RasterWork::Cpu
        }
        RasterWork::Auto => RasterWork::Gpu,
        asked => asked,
    }
}

/// The rasterizer: its atomic path, bins, counters and indirect arguments.
pub(crate) struct Rasterizer {
    int64: bool,
    /// How the work is shared out (resolved: `Gpu` or `Cpu`).
    work: RasterWork,
    /// The early depth test: for GPU work (on the 64-bit path where the device loads 64-bit
    /// atomics; [`RasterWork::Cpu`] says why not for a CPU driver).
    early_test: bool,
    /// Bin counters and diagnostics ([`RasterCounters`]).
    bins: wgpu::Buffer,
    args: wgpu::Buffer,
    /// Binned triangles' set-up.
    large: wgpu::Buffer,
    /// Work items: slices past the first of binned triangles.
    items: wgpu::Buffer,
}

impl Rasterizer {
    /// `int64`: use 64-bit atomics (the device must have them); `work`: how to share out the
    /// work.
    pub(crate) fn new(device: &wgpu::Device, int64: bool, work: RasterWork) -> Self {
        let storage = |label, size, usage| gpu::storage_buffer(device, label, size, usage);
        let work = resolve_work(work, device);
        Rasterizer {
            int64,
            work,
            early_test: work == RasterWork::Gpu
                && (!int64
                    || device.features().contains(wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS)),
            bins: storage(
                "deep-gbuffer.raster.bins",
                std::mem::size_of::<RasterCounters>() as u64,
                wgpu::BufferUsages::empty(),
            ),
            args: storage("deep-gbuffer.raster.args", ARGS_BYTES, wgpu::BufferUsages::INDIRECT),
            large: storage("deep-gbuffer.raster.large", ENTRY_BYTES, wgpu::BufferUsages::empty()),
            items: storage("deep-gbuffer.raster.items", ITEM_BYTES, wgpu::BufferUsages::empty()),
        }
    }

    /// Makes the bins large enough for `scene` drawn into targets of up to `pixels` pixels.
    pub(crate) fn reserve(&mut self, device: &wgpu::Device, scene: &SceneBuffers, pixels: u64) {
        let limit = device.limits().max_storage_buffer_binding_size;
        let (entries, items) = bin_sizes(scene.triangle_count(), pixels, limit);
        let usage = wgpu::BufferUsages::empty();
        if self.large.size() < entries {
            self.large = gpu::storage_buffer(device, "deep-gbuffer.raster.large", entries, usage);
        }
        if self.items.size() < items {
            self.items = gpu::storage_buffer(device, "deep-gbuffer.raster.items", items, usage);
        }
    }

    /// Records one raster step (both phases on the 32-bit path) of `scene`.
    pub(crate) fn draw(
        &self,
        device: &wgpu::Device,
        pipelines: &Pipelines,
        pass: &mut wgpu::ComputePass<'_>,
        scene: &SceneBuffers,
        t: Draw<'_>,
    ) {
        let (frame, mode) = (t.frame, t.mode);
        let once = matches!(mode, RasterMode::Count | RasterMode::Unpeeled);
        let phases: &[bool] = if self.int64 || once { &[false] } else { &[true, false] };
        let b = scene.buffers();
        let mut entries = vec![
            (slot::FRAME, frame),
            (slot::POSITIONS, t.positions.unwrap_or(&b.positions)),
            (slot::INDICES, &b.indices),
            (slot::TRI_MATERIALS, &b.triangle_materials),
            (slot::MATERIALS, &b.materials),
            (slot::BINS, &self.bins),
            (slot::LARGE, &self.large),
            (slot::ITEMS, &self.items),
            (slot::ARGS, &self.args),
            (slot::TEXELS, &b.texels),
            (slot::UVS, &b.uvs),
            (slot::UVS1, &scene.uvs1),
        ];
        let optional = [
            (slot::VIS0, t.vis0),
            (slot::VIS1, t.vis1),
            (slot::ZREF, t.zref),
            (slot::COUNTS, t.counts),
            (slot::OPAQUE, t.opaque),
            (slot::PEEL_ARGS, t.peel_args),
        ];
        entries.extend(optional.into_iter().filter_map(|(s, b)| Some((s, b?))));
        let groups = gpu::dispatch_size(scene.triangle_count().div_ceil(64));
        // The alpha test only where the scene has masked materials; a textureless scene's
        // triangles that name textures counted as drawn untextured (wgsl/raster.wgsl).
        let [small, slices, tile_test] = work_constants(self.work);
        let constants = [
            small,
            slices,
            tile_test,
            ("ALPHA_TEST", f64::from(u8::from(scene.info().masked))),
            super::textures_constant(scene),
        ];
        let mut defines = Vec::new();
        for &depth_phase in phases {
            defines = mode.defines();
            if self.int64 {
                defines.push("INT64");
            } else if depth_phase {
                defines.push("DEPTH_PHASE");
            }
            if self.early_test {
                defines.push("EARLY_TEST");
            }
            let get = |entry| pipelines.get(device, "raster", entry, &defines, &constants);
            get("raster_small").dispatch(device, pass, &entries, groups);
            get("bin_args").dispatch(device, pass, &entries, (1, 1));
            get("raster_large").dispatch_indirect(device, pass, &entries, &self.args, 0);
        }
        if mode == RasterMode::Peel && t.peel_args.is_some() {
            let p = pipelines.get(device, "raster", "peel_dispatch", &defines, &constants);
            p.dispatch(device, pass, &entries, (1, 1));
        }
    }

    /// Reads the counters of the frames since the bins were last cleared (waits for the GPU).
    pub(crate) fn counters(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> crate::Result<RasterCounters> {
        let bytes = gpu::read_buffer(device, queue, &self.bins)?;
        Ok(bytemuck::pod_read_unaligned(&bytes[..std::mem::size_of::<RasterCounters>()]))
    }
}

/// The camera's raster: the rasterizer, both layers' visibility buffers, and last frame's layer 0
/// (which the one-pass layer-1 variants and the radiosity history read).
pub(crate) struct RasterStage {
    pub(crate) rasterizer: Rasterizer,
    vis0: [wgpu::Buffer; 2],
    vis1: wgpu::Buffer,
    /// The layer 0 `raster.next` drew for the next frame (`Predict`, `Delay`), and the frame
    /// uniform of the camera it drew from.
    next: wgpu::Buffer,
    next_frame: wgpu::Buffer,
    /// Which `vis0` holds this (or, between frames, the last) frame's layer 0.
    current: usize,
    /// This frame keeps the last frame's layers (a still frame, [`crate::Plan::reused`]): its
    /// layer 0 is the last frame's, so the "previous" layer 0 is the current one.
    kept: bool,
    fill: Fill,
    /// The vertex positions `Predict` expects the next frame to have, moving as they moved
    /// since the last (drawn by `raster.next` when the geometry moved), and their extrapolation.
    predicted: Option<(wgpu::Buffer, Fill)>,
}

impl RasterStage {
    /// The visibility buffers of a `pixels`-pixel image.
    pub(crate) fn new(device: &wgpu::Device, int64: bool, work: RasterWork, pixels: u64) -> Self {
        let vis =
            |label| gpu::storage_buffer(device, label, pixels * 8, wgpu::BufferUsages::empty());
        let vis1 = vis("deep-gbuffer.raster.vis1");
        RasterStage {
            rasterizer: Rasterizer::new(device, int64, work),
            vis0: [vis("deep-gbuffer.raster.vis0.a"), vis("deep-gbuffer.raster.vis0.b")],
            next: vis("deep-gbuffer.raster.next"),
            next_frame: gpu::uniform_buffer_for::<FrameUniform>(device, "deep-gbuffer.raster.next"),
            fill: Fill::new(device, vis1.size(), u32::MAX),
            vis1,
            current: 0,
            kept: false,
            predicted: None,
        }
    }

    /// Starts a frame: the bins fit `scene` drawn into targets of up to `pixels` pixels (the
    /// image, a shadow-map face), and this frame writes the other layer-0 buffer, or with `kept`
    /// (a still frame) keeps the last frame's layers; `next`: the frame uniform `raster.next`
    /// draws with, when the plan runs it.
    pub(crate) fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (scene, pixels): (&SceneBuffers, u64),
        next: Option<&FrameUniform>,
        kept: bool,
    ) {
        self.rasterizer.reserve(device, scene, pixels);
        self.kept = kept;
        if !kept {
            self.current = 1 - self.current;
        }
        if let Some(next) = next {
            queue.write_buffer(&self.next_frame, 0, bytemuck::bytes_of(next));
            let bytes = scene.position_bytes();
            if self.predicted.as_ref().is_none_or(|(_, fill)| fill.bytes() != bytes) {
                let label = "deep-gbuffer.raster.predicted";
                let buffer = gpu::storage_buffer(device, label, bytes, wgpu::BufferUsages::empty());
                self.predicted = Some((buffer, Fill::new(device, bytes, 0)));
            }
        }
    }

    /// Whether this uses the 64-bit atomic path.
    pub(crate) fn int64(&self) -> bool {
        self.rasterizer.int64
    }

    /// How the work is shared out: [`RasterWork::Gpu`] or [`RasterWork::Cpu`].
    pub(crate) fn work(&self) -> RasterWork {
        self.rasterizer.work
    }

    /// This frame's layer 0 (the last frame's, between frames).
    pub(crate) fn vis0(&self) -> &wgpu::Buffer {
        &self.vis0[self.current]
    }

    /// The layer 0 of the frame before (this frame's on a still frame, which kept it).
    pub(crate) fn previous_vis0(&self) -> &wgpu::Buffer {
        if self.kept { self.vis0() } else { self.next_vis0() }
    }

    /// The layer-0 buffer the next frame will write.
    pub(crate) fn next_vis0(&self) -> &wgpu::Buffer {
        &self.vis0[1 - self.current]
    }

    /// Layer 1.
    pub(crate) fn vis1(&self) -> &wgpu::Buffer {
        &self.vis1
    }
}

impl Stage for RasterStage {
    fn begin(&self, _ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        // A still frame draws nothing and keeps the counters of the frame that drew its layers.
        if !self.kept {
            rec.encoder().clear_buffer(&self.rasterizer.bins, 0, None);
        }
    }

    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        let mut pass = rec.pass(id);
        let (vis0, vis1) = (self.vis0(), &self.vis1);
        let draw = |mode| Draw::new(ctx.frame, mode);
        let step = match id {
            PassId::RasterClear => {
                self.fill.record(ctx.device, ctx.pipelines, &mut pass, vis0);
                if ctx.plan.layers == 2 {
                    self.fill.record(ctx.device, ctx.pipelines, &mut pass, vis1);
                }
                return;
            }
            PassId::RasterLayer0 => Draw { vis0: Some(vis0), ..draw(RasterMode::Layer0) },
            PassId::RasterNext => {
                self.fill.record(ctx.device, ctx.pipelines, &mut pass, &self.next);
                let mut step = Draw {
                    vis0: Some(&self.next),
                    ..Draw::new(&self.next_frame, RasterMode::Layer0)
                };
                // Predict: the geometry moves on as it moved since the last frame.
                if let (Layer1Variant::Predict, Some(earlier), Some((predicted, extrapolate))) =
                    (ctx.settings.layer1, ctx.previous_positions, self.predicted.as_ref())
                {
                    let now = &ctx.scene.buffers().positions;
                    let (device, pipelines) = (ctx.device, ctx.pipelines);
                    extrapolate.record_extrapolate(
                        device,
                        pipelines,
                        &mut pass,
                        [now, earlier],
                        predicted,
                    );
                    step.positions = Some(predicted);
                }
                step
            }
            PassId::RasterLayer1 => {
                Draw { vis1: Some(vis1), zref: Some(vis0), ..draw(RasterMode::Layer1) }
            }
            PassId::RasterLayers => Draw {
                vis0: Some(vis0),
                vis1: Some(vis1),
                zref: Some(match ctx.settings.layer1 {
                    Layer1Variant::Predict | Layer1Variant::Delay => &self.next,
                    _ => self.previous_vis0(),
                }),
                ..draw(RasterMode::Both {
                    reproject: ctx.settings.layer1 == Layer1Variant::Reproject,
                })
            },
            other => unreachable!("{other} is not a raster pass"),
        };
        self.rasterizer.draw(ctx.device, ctx.pipelines, &mut pass, ctx.scene, step);
    }
}

/// Runs the `COUNT` variant with its work shared out as `work` says: how many fragments cover
/// each pixel (every covered pixel centre of every triangle, no depth test). Watertightness tests
/// read it; it waits for the GPU.
pub fn coverage_counts(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &SceneBuffers,
    frame: &FrameUniform,
    work: RasterWork,
) -> crate::Result<Vec<u32>> {
    let pixels = u64::from(frame.width) * u64::from(frame.height);
    let uniform =
        gpu::uniform_buffer(device, "deep-gbuffer.raster.count.frame", bytemuck::bytes_of(frame));
    let mut rasterizer = Rasterizer::new(device, false, work);
    rasterizer.reserve(device, scene, pixels);
    let counts = gpu::storage_buffer(
        device,
        "deep-gbuffer.raster.count.counts",
        pixels * 4,
        wgpu::BufferUsages::empty(),
    );
    let pipelines = Pipelines::default();
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("deep-gbuffer.raster.count"),
    });
    encoder.clear_buffer(&counts, 0, None);
    encoder.clear_buffer(&rasterizer.bins, 0, None);
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("deep-gbuffer.raster.count"),
            timestamp_writes: None,
        });
        let step = Draw { counts: Some(&counts), ..Draw::new(&uniform, RasterMode::Count) };
        rasterizer.draw(device, &pipelines, &mut pass, scene, step);
    }
    queue.submit([encoder.finish()]);
    let bytes = gpu::read_buffer(device, queue, &counts)?;
    Ok(bytemuck::pod_collect_to_vec::<u8, u32>(&bytes[..(pixels * 4) as usize]))
}
