//! `wgsl/raster.wgsl`: the compute rasterizer that writes visibility buffers.
//!
//! One raster step is three dispatches: `raster_small` over all triangles (small ones are
//! rasterized in place, large ones binned), `bin_args` (indirect arguments) and `raster_large`
//! (indirect, 16x16 tiles). On the 32-bit path every step runs twice: a depth phase, then an id
//! phase; on the 64-bit path once.

use std::collections::HashMap;

use crate::SceneBuffers;
use crate::gpu;

/// What one raster step writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RasterMode {
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
}

struct Pipelines {
    small: wgpu::ComputePipeline,
    args: wgpu::ComputePipeline,
    /// One per bin (the `BIN` override): few tiles, many tiles.
    large: [wgpu::ComputePipeline; 2],
}

/// Bytes of the bin counters and diagnostics words (12 u32, see `bins` in `wgsl/raster.wgsl`).
pub const BINS_BYTES: u64 = 48;
/// Bytes of the indirect arguments (two dispatches of 4 u32).
pub const ARGS_BYTES: u64 = 32;

/// Bytes of the bin entries for `triangles` triangles: two bins, each with room for two
/// clipped sub-triangles per triangle plus slack, 8 bytes an entry, within `limit`.
pub fn bin_bytes(triangles: u32, limit: u64) -> u64 {
    ((u64::from(triangles) * 2 + 1024) * 2 * 8).min(limit & !15)
}

/// The buffers one raster step reads and writes.
pub struct RasterTargets<'a> {
    /// The frame uniform.
    pub frame: &'a wgpu::Buffer,
    /// Bin counters ([`BINS_BYTES`]).
    pub bins: &'a wgpu::Buffer,
    /// The bins' entries ([`bin_bytes`]).
    pub large: &'a wgpu::Buffer,
    /// Indirect arguments for `raster_large` ([`ARGS_BYTES`], INDIRECT usage).
    pub args: &'a wgpu::Buffer,
    /// Layer 0 visibility buffer (Layer0, Both).
    pub vis0: Option<&'a wgpu::Buffer>,
    /// Layer 1 visibility buffer (Layer1, Both).
    pub vis1: Option<&'a wgpu::Buffer>,
    /// The visibility buffer layer 1 is separated from (Layer1, Both).
    pub zref: Option<&'a wgpu::Buffer>,
    /// Per-pixel fragment counts (Count).
    pub counts: Option<&'a wgpu::Buffer>,
}

/// The raster kernels, for one atomic path, built on first use per mode.
pub struct RasterPass {
    int64: bool,
    pipelines: HashMap<(RasterMode, bool), Pipelines>,
}

impl RasterPass {
    /// `int64`: use 64-bit atomics (the device must have them).
    pub fn new(int64: bool) -> Self {
        RasterPass { int64, pipelines: HashMap::new() }
    }

    /// Whether this uses the 64-bit atomic path.
    pub fn int64(&self) -> bool {
        self.int64
    }

    fn pipelines(
        &mut self,
        device: &wgpu::Device,
        mode: RasterMode,
        depth_phase: bool,
    ) -> &Pipelines {
        let int64 = self.int64;
        self.pipelines.entry((mode, depth_phase)).or_insert_with(|| {
            let mut defines: Vec<&str> = match mode {
                RasterMode::Layer0 => vec!["WRITE_L0"],
                RasterMode::Layer1 => vec!["WRITE_L1"],
                RasterMode::Both { reproject: false } => vec!["WRITE_L0", "WRITE_L1"],
                RasterMode::Both { reproject: true } => vec!["WRITE_L0", "WRITE_L1", "REPROJECT"],
                RasterMode::Count => vec!["COUNT"],
            };
            if int64 {
                defines.push("INT64");
            } else if depth_phase {
                defines.push("DEPTH_PHASE");
            }
            Pipelines {
                small: gpu::compute_pipeline(device, "raster", "raster_small", &defines),
                args: gpu::compute_pipeline(device, "raster", "bin_args", &defines),
                large: [0.0, 1.0].map(|bin| {
                    gpu::compute_pipeline_with(
                        device,
                        "raster",
                        "raster_large",
                        &defines,
                        &[("BIN", bin)],
                    )
                }),
            }
        })
    }

    /// Records one raster step (both phases on the 32-bit path) into `pass`.
    pub fn encode(
        &mut self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        scene: &SceneBuffers,
        mode: RasterMode,
        t: &RasterTargets<'_>,
    ) {
        let phases: &[bool] =
            if self.int64 || mode == RasterMode::Count { &[false] } else { &[true, false] };
        let b = scene.buffers();
        for &depth_phase in phases {
            let p = self.pipelines(device, mode, depth_phase);
            let mut entries: Vec<(u32, &wgpu::Buffer)> = vec![
                (0, t.frame),
                (1, &b.positions),
                (2, &b.indices),
                (3, &b.triangle_materials),
                (4, &b.materials),
                (5, t.bins),
                (6, t.large),
            ];
            let optional = [(8, t.vis0), (9, t.vis1), (10, t.zref), (11, t.counts)];
            let wanted: &[u32] = match mode {
                RasterMode::Layer0 => &[8],
                RasterMode::Layer1 => &[9, 10],
                RasterMode::Both { .. } => &[8, 9, 10],
                RasterMode::Count => &[11],
            };
            for (binding, buffer) in optional {
                if wanted.contains(&binding) {
                    entries.push((binding, buffer.expect("the mode's buffers are given")));
                }
            }
            let large = p
                .large
                .each_ref()
                .map(|l| gpu::bind_group(device, "deep-gbuffer.raster.large", l, &entries));
            if wanted.contains(&8) {
                // raster_small checks textures against the texel buffer's length.
                entries.push((12, &b.texels));
            }
            let small = gpu::bind_group(device, "deep-gbuffer.raster.small", &p.small, &entries);
            let args = gpu::bind_group(
                device,
                "deep-gbuffer.raster.args",
                &p.args,
                &[(5, t.bins), (6, t.large), (7, t.args)],
            );
            let (x, y) = gpu::dispatch_size(scene.triangle_count().div_ceil(64));
            pass.set_pipeline(&p.small);
            pass.set_bind_group(0, &small, &[]);
            pass.dispatch_workgroups(x, y, 1);
            pass.set_pipeline(&p.args);
            pass.set_bind_group(0, &args, &[]);
            pass.dispatch_workgroups(1, 1, 1);
            for (offset, (pipeline, group)) in p.large.iter().zip(&large).enumerate() {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups_indirect(t.args, offset as u64 * 16);
            }
        }
    }
}

/// Runs the `COUNT` variant: how many fragments cover each pixel (every covered pixel centre of
/// every triangle, no depth test). Watertightness tests read it; it waits for the GPU.
pub fn coverage_counts(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &SceneBuffers,
    frame: &crate::gpu::FrameUniform,
) -> crate::Result<Vec<u32>> {
    let pixels = u64::from(frame.width) * u64::from(frame.height);
    let uniform =
        gpu::uniform_buffer(device, "deep-gbuffer.raster.count.frame", bytemuck::bytes_of(frame));
    let bins = gpu::storage_buffer(
        device,
        "deep-gbuffer.raster.count.bins",
        BINS_BYTES,
        wgpu::BufferUsages::empty(),
    );
    let args = gpu::storage_buffer(
        device,
        "deep-gbuffer.raster.count.args",
        ARGS_BYTES,
        wgpu::BufferUsages::INDIRECT,
    );
    let large_bytes =
        bin_bytes(scene.triangle_count(), device.limits().max_storage_buffer_binding_size);
    let large = gpu::storage_buffer(
        device,
        "deep-gbuffer.raster.count.large",
        large_bytes,
        wgpu::BufferUsages::empty(),
    );
    let counts = gpu::storage_buffer(
        device,
        "deep-gbuffer.raster.count.counts",
        pixels * 4,
        wgpu::BufferUsages::empty(),
    );
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("deep-gbuffer.raster.count"),
    });
    encoder.clear_buffer(&counts, 0, None);
    encoder.clear_buffer(&bins, 0, None);
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("deep-gbuffer.raster.count"),
            timestamp_writes: None,
        });
        let targets = RasterTargets {
            frame: &uniform,
            bins: &bins,
            large: &large,
            args: &args,
            vis0: None,
            vis1: None,
            zref: None,
            counts: Some(&counts),
        };
        RasterPass::new(false).encode(device, &mut pass, scene, RasterMode::Count, &targets);
    }
    queue.submit([encoder.finish()]);
    let bytes = gpu::read_buffer(device, queue, &counts)?;
    Ok(bytemuck::pod_collect_to_vec::<u8, u32>(&bytes[..(pixels * 4) as usize]))
}
