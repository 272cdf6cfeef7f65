//! `wgsl/resolve.wgsl`: visibility buffer to G-buffer layer.

use super::fill::Fill;
use super::{FrameContext, PointList, Recorder, Stage};
use crate::SceneBuffers;
use crate::gpu::{self, slots::resolve as slot};
use crate::plan::PassId;

/// The side of the square tiles the frame's own resolve lists (`tile_count` in
/// wgsl/resolve.wgsl).
const TILE: u32 = 8;

/// The G-buffer layers and the kernel that fills them from the visibility buffers.
pub(crate) struct ResolveStage {
    gbuffer: [wgpu::Buffer; 2],
    /// Each layer's 8x8 tiles that hold a surface, which its resolve runs over (wgsl/resolve.wgsl).
    listed: [PointList; 2],
    /// The scene's vertex positions as the last frames saw them, for the motion vectors of
    /// geometry that moves.
    positions: Option<Positions>,
}

/// Two copies of a scene's vertex positions: the one this frame's resolve reads as the last
/// frame's, and the one it copies this frame's positions into (the next frame's last).
struct Positions {
    /// The scene's positions buffer these copy (a scene uploaded or imported anew has another).
    of: wgpu::Buffer,
    copies: [wgpu::Buffer; 2],
    /// The copy that holds the positions of the latest frame copied.
    latest: usize,
    /// [`Renderer::geometry_changed`](crate::Renderer::geometry_changed)'s count at that frame.
    generation: u64,
    /// This frame copies the positions (into `copies[latest]`).
    copy: bool,
    /// The geometry moved since the last frame (`copies[latest ^ 1]` holds where it stood).
    moved: bool,
    /// The copy of the vertex words (as many as the scene's positions have).
    fill: Fill,
}

impl ResolveStage {
    /// Two layers of `width` x `height` records of `record` bytes each.
    pub(crate) fn new(device: &wgpu::Device, (width, height): (u32, u32), record: u64) -> Self {
        let pixels = u64::from(width) * u64::from(height);
        let g = |label| {
            gpu::storage_buffer(device, label, pixels * record, wgpu::BufferUsages::empty())
        };
        let tiles = u64::from(width.div_ceil(TILE)) * u64::from(height.div_ceil(TILE));
        let list = |label| PointList::new(device, label, tiles);
        ResolveStage {
            gbuffer: [g("deep-gbuffer.resolve.layer0"), g("deep-gbuffer.resolve.layer1")],
            listed: [list("deep-gbuffer.resolve.list0"), list("deep-gbuffer.resolve.list1")],
            positions: None,
        }
    }

    /// The G-buffer of `layer` (0 or 1).
    pub(crate) fn gbuffer(&self, layer: usize) -> &wgpu::Buffer {
        &self.gbuffer[layer.min(1)]
    }

    /// Whether the geometry of `scene` moved since the last frame this stage resolved:
    /// [`Renderer::geometry_changed`](crate::Renderer::geometry_changed) was called since
    /// (its count is `generation`) and that frame had the same scene.
    pub(crate) fn moved(&self, scene: &SceneBuffers, generation: u64) -> bool {
        let bytes = scene.position_bytes();
        self.positions.as_ref().is_some_and(|p| {
            p.of == scene.buffers().positions
                && p.fill.bytes() == bytes
                && p.generation != generation
        })
    }

    /// Makes ready the copies of `scene`'s positions for a frame at `generation`; returns
    /// whether its geometry moved since the last frame (the frame's `FRAME_OBJECT_MOTION`).
    /// The first frame of a scene copies its positions; after it, a frame copies them only
    /// when the geometry changed, into the other copy, so the last frame's stay readable.
    pub(crate) fn prepare(
        &mut self,
        device: &wgpu::Device,
        scene: &SceneBuffers,
        generation: u64,
    ) -> bool {
        let moved = self.moved(scene, generation);
        let positions = &scene.buffers().positions;
        let bytes = scene.position_bytes();
        match self.positions.as_mut() {
            Some(p) if p.of == *positions && p.fill.bytes() == bytes => {
                p.copy = moved;
                p.moved = moved;
                if moved {
                    p.latest ^= 1;
                    p.generation = generation;
                }
            }
            _ => {
                let copy =
                    |label| gpu::storage_buffer(device, label, bytes, wgpu::BufferUsages::empty());
                self.positions = Some(Positions {
                    of: positions.clone(),
                    copies: [
                        copy("deep-gbuffer.resolve.positions0"),
                        copy("deep-gbuffer.resolve.positions1"),
                    ],
                    latest: 0,
                    generation,
                    copy: true,
                    moved: false,
                    fill: Fill::new(device, bytes, 0),
                });
            }
        }
        moved
    }

    /// The vertex positions of the last frame, when the geometry moved since.
    pub(crate) fn previous(&self) -> Option<&wgpu::Buffer> {
        self.positions.as_ref().filter(|p| p.moved).map(|p| &p.copies[p.latest ^ 1])
    }
}

impl Stage for ResolveStage {
    /// Copies this frame's positions, before any pass reads the copies.
    fn begin(&self, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        let Some(p) = self.positions.as_ref().filter(|p| p.copy) else { return };
        if !ctx.plan.contains(&PassId::Resolve) {
            return;
        }
        let mut pass = rec.encoder().begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("deep-gbuffer.resolve.positions"),
            timestamp_writes: None,
        });
        let into = &p.copies[p.latest];
        p.fill.record_copy(ctx.device, ctx.pipelines, &mut pass, &ctx.scene.b.positions, into);
    }

    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        debug_assert_eq!(*id, PassId::Resolve);
        let layers = ctx.plan.layers as usize;
        for list in self.listed.iter().take(layers) {
            list.clear(rec.encoder());
        }
        let mut pass = rec.pass(id);
        let vis = [ctx.raster.vis0(), ctx.raster.vis1()];
        for ((vis, gbuffer), list) in
            vis.into_iter().zip(&self.gbuffer).zip(&self.listed).take(layers)
        {
            resolve_listed(ctx, &mut pass, vis, gbuffer, list);
        }
    }
}

/// Records the resolve of visibility buffer `vis` into the G-buffer layer `gbuffer` over the 8x8
/// tiles that hold a surface, listed in `list` first (cleared before; the other tiles get the
/// empty record): the same records as [`resolve_layer`], without the cost of the empty tiles on
/// a driver that runs a SIMD group's idle lanes.
fn resolve_listed(
    ctx: &FrameContext<'_>,
    pass: &mut wgpu::ComputePass<'_>,
    vis: &wgpu::Buffer,
    gbuffer: &wgpu::Buffer,
    PointList { list, args }: &PointList,
) {
    let kernel = |entry| resolve_pipeline(ctx, entry);
    let (w, h) = ctx.size();
    let tiles = w.div_ceil(TILE) * h.div_ceil(TILE);
    let listing = [(slot::FRAME, ctx.frame), (slot::VIS, vis), (slot::GBUFFER, gbuffer)];
    let listing = [&listing[..], &[(slot::LIST, list)]].concat();
    let groups = gpu::dispatch_size(tiles.div_ceil(64));
    kernel("resolve_tiles").dispatch(ctx.device, pass, &listing, groups);
    let count = [(slot::LIST, list), (slot::LIST_ARGS, args)];
    kernel("resolve_tiles_args").dispatch(ctx.device, pass, &count, (1, 1));
    // Not `args`: a dispatch may not read its indirect buffer as storage.
    let mut entries = resolve_entries(ctx, (ctx.frame, vis, gbuffer));
    entries.push((slot::LIST, list));
    kernel("resolve_listed").dispatch_indirect(ctx.device, pass, &entries, args, 0);
}

/// Records the resolve of visibility buffer `vis` into the G-buffer layer `gbuffer`, over the
/// whole image or with the workgroups `args` holds (8x8 pixels each).
pub(crate) fn resolve_layer(
    ctx: &FrameContext<'_>,
    pass: &mut wgpu::ComputePass<'_>,
    vis: &wgpu::Buffer,
    gbuffer: &wgpu::Buffer,
    args: Option<&wgpu::Buffer>,
) {
    resolve_view(ctx, pass, (ctx.frame, ctx.size()), vis, gbuffer, args);
}

/// [`resolve_layer`] for the view of `frame` (its uniform, and its size in pixels): the camera's
/// or a reflective shadow map face's.
pub(crate) fn resolve_view(
    ctx: &FrameContext<'_>,
    pass: &mut wgpu::ComputePass<'_>,
    (frame, size): (&wgpu::Buffer, (u32, u32)),
    vis: &wgpu::Buffer,
    gbuffer: &wgpu::Buffer,
    args: Option<&wgpu::Buffer>,
) {
    let pipeline = resolve_pipeline(ctx, "resolve");
    let entries = resolve_entries(ctx, (frame, vis, gbuffer));
    match args {
        Some(args) => pipeline.dispatch_indirect(ctx.device, pass, &entries, args, 0),
        None => pipeline.dispatch_pixels(ctx.device, pass, &entries, size),
    }
}

/// The resolve kernel's entry point `entry`, built for the frame: the texture code only where
/// the scene's materials may sample textures, the last frame's vertices only where the geometry
/// moved (wgsl/resolve.wgsl), the position encoding in use alone (wgsl/shared/position.wgsl).
fn resolve_pipeline(ctx: &FrameContext<'_>, entry: &'static str) -> std::sync::Arc<gpu::Pipeline> {
    let defines = ctx.settings.precision.defines();
    let constants = [
        super::textures_constant(ctx.scene),
        ("OBJECT_MOTION", f64::from(u8::from(ctx.previous_positions.is_some()))),
        ("POSITION_FLAGS", f64::from(ctx.settings.position.frame_flags())),
    ];
    ctx.pipelines.get(ctx.device, "resolve", entry, &defines, &constants)
}

/// The buffers a resolve of `vis` into `gbuffer` reads, for the view of uniform `frame`.
fn resolve_entries<'a>(
    ctx: &FrameContext<'a>,
    (frame, vis, gbuffer): (&'a wgpu::Buffer, &'a wgpu::Buffer, &'a wgpu::Buffer),
) -> Vec<(gpu::Slot, &'a wgpu::Buffer)> {
    let positions = &ctx.scene.buffers().positions;
    let mut entries = vec![
        (slot::FRAME, frame),
        (slot::VIS, vis),
        (slot::GBUFFER, gbuffer),
        (slot::PREVIOUS_POSITIONS, ctx.previous_positions.unwrap_or(positions)),
    ];
    entries.extend(super::surface_entries!(slot, ctx.scene));
    entries
}
