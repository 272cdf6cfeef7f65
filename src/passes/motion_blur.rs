//! `wgsl/motion_blur.wgsl`: motion blur of the camera's motion and of moving geometry.

use super::{FrameContext, Recorder, Stage};
use crate::frame::{MOTION_TILE, MotionBlurUniform};
use crate::gpu::{self, slots::motion_blur as slot};
use crate::plan::PassId;
use crate::scene::SceneInfo;
use crate::settings::Settings;

/// The motion blur: its constants and the fastest motion of each tile and its neighbourhood.
pub(crate) struct MotionBlurStage {
    uniform: wgpu::Buffer,
    tiles: wgpu::Buffer,
    neighbours: wgpu::Buffer,
    /// Tiles per row and column.
    tile_count: (u32, u32),
}

impl MotionBlurStage {
    /// The stage for `s`'s image size.
    pub(crate) fn new(device: &wgpu::Device, s: &Settings) -> Self {
        let tile_count = (s.width.div_ceil(MOTION_TILE), s.height.div_ceil(MOTION_TILE));
        let bytes = u64::from(tile_count.0) * u64::from(tile_count.1) * 16;
        let tiles = |label| gpu::storage_buffer(device, label, bytes, wgpu::BufferUsages::empty());
        MotionBlurStage {
            uniform: gpu::uniform_buffer_for::<MotionBlurUniform>(
                device,
                "deep-gbuffer.motion_blur",
            ),
            tiles: tiles("deep-gbuffer.motion_blur.tiles"),
            neighbours: tiles("deep-gbuffer.motion_blur.neighbours"),
            tile_count,
        }
    }

    /// Writes the frame's constants for `scene`.
    pub(crate) fn prepare(&self, queue: &wgpu::Queue, s: &Settings, scene: &SceneInfo) {
        let uniform = MotionBlurUniform::new(&s.motion_blur, scene.ambient.to_array(), s.width);
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }
}

impl Stage for MotionBlurStage {
    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        debug_assert_eq!(*id, PassId::MotionBlur);
        let mut pass = rec.pass(id);
        let mut defines = ctx.settings.precision.defines();
        if ctx.settings.motion_blur.two_layers && ctx.plan.layers == 2 {
            defines.push("TWO_LAYERS");
        }
        let get = |entry| ctx.pipelines.get(ctx.device, "motion_blur", entry, &defines, &[]);
        let (Some(image), hdr) = ctx.image_io(id) else {
            unreachable!("a post pass reads an image");
        };
        let entries = [
            (slot::FRAME, ctx.frame),
            (slot::MOTION, &self.uniform),
            (slot::GBUFFER0, ctx.gbuffer[0]),
            (slot::GBUFFER1, ctx.gbuffer[1]),
            (slot::DIRECT1, ctx.direct[1]),
            (slot::IMAGE, image),
            (slot::HDR, hdr),
            (slot::TILES, &self.tiles),
            (slot::NEIGHBOURS, &self.neighbours),
        ];
        get("motion_tiles").dispatch_pixels(ctx.device, &mut pass, &entries, self.tile_count);
        get("motion_neighbours").dispatch_pixels(ctx.device, &mut pass, &entries, self.tile_count);
        get("motion_blur_main").dispatch_pixels(ctx.device, &mut pass, &entries, ctx.size());
    }
}
