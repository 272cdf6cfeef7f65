//! `wgsl/transparency.wgsl`: blended surfaces peeled, lit and laid over the opaque image.
//!
//! `transparency.peel` records, for each of the k peels, the rasterizer's `PEEL` step into one
//! of two visibility buffers (the other holds the previous peel), the resolve and the direct
//! light of what it found (into a G-buffer layer and a radiance buffer of the stage's own) and
//! `accumulate`. `transparency.composite` is a post pass: it lays the sum over the composite.

use super::fill::Fill;
use super::raster::{Draw, RasterMode};
use super::{FrameContext, Recorder, Stage};
use crate::SceneBuffers;
use crate::frame::TransparencyUniform;
use crate::gpu::{self, slots::transparency as slot};
use crate::plan::{Effect, PassId};
use crate::settings::Settings;

/// The peels' buffers and the accumulated blend.
pub(crate) struct TransparencyStage {
    uniform: wgpu::Buffer,
    /// Visibility words of the current and the previous peel.
    peels: [wgpu::Buffer; 2],
    /// The current peel resolved and lit.
    gbuffer: wgpu::Buffer,
    radiance: wgpu::Buffer,
    /// C (rgb) and A (a) per pixel.
    accum: wgpu::Buffer,
    /// The workgroups of the current peel's per-pixel kernels (none when it found nothing).
    args: wgpu::Buffer,
    empty: Fill,
}

impl TransparencyStage {
    /// The buffers of a frame of `s`'s size.
    pub(crate) fn new(device: &wgpu::Device, s: &Settings) -> Self {
        let pixels = u64::from(s.width) * u64::from(s.height);
        let buffer =
            |label, bytes| gpu::storage_buffer(device, label, bytes, wgpu::BufferUsages::empty());
        let peels = [
            buffer("deep-gbuffer.transparency.peel.a", pixels * 8),
            buffer("deep-gbuffer.transparency.peel.b", pixels * 8),
        ];
        TransparencyStage {
            uniform: gpu::uniform_buffer_for::<TransparencyUniform>(
                device,
                "deep-gbuffer.transparency",
            ),
            empty: Fill::new(device, pixels * 8, u32::MAX),
            peels,
            gbuffer: buffer(
                "deep-gbuffer.transparency.gbuffer",
                pixels * crate::gbuffer::bytes_per_pixel(s.precision),
            ),
            radiance: buffer("deep-gbuffer.transparency.radiance", pixels * 16),
            accum: buffer("deep-gbuffer.transparency.accum", pixels * 16),
            args: gpu::storage_buffer(
                device,
                "deep-gbuffer.transparency.args",
                16,
                wgpu::BufferUsages::INDIRECT,
            ),
        }
    }

    /// Writes the frame's constants.
    pub(crate) fn prepare(&self, queue: &wgpu::Queue, scene: &SceneBuffers) {
        let uniform = TransparencyUniform { ambient: scene.info().ambient.to_array(), _pad: 0 };
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }

    /// The bindings both kernels read.
    fn entries<'a>(&'a self, ctx: &FrameContext<'a>) -> Vec<(gpu::Slot, &'a wgpu::Buffer)> {
        let b = ctx.scene.buffers();
        vec![
            (slot::FRAME, ctx.frame),
            (slot::TRANSPARENCY, &self.uniform),
            (slot::GBUFFER, &self.gbuffer),
            (slot::DIRECT, &self.radiance),
            (slot::POSITIONS, &b.positions),
            (slot::INDICES, &b.indices),
            (slot::TRI_MATERIALS, &b.triangle_materials),
            (slot::MATERIALS, &b.materials),
            (slot::TEXELS, &b.texels),
            (slot::UVS, &b.uvs),
            (slot::UVS1, &ctx.scene.uvs1),
            (slot::ACCUM, &self.accum),
        ]
    }
}

impl Stage for TransparencyStage {
    fn begin(&self, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        if ctx.plan.contains(&PassId::TransparencyPeel) {
            rec.encoder().clear_buffer(&self.accum, 0, None);
            // The "previous peel" of the first: words of 0, before every fragment.
            rec.encoder().clear_buffer(&self.peels[1], 0, None);
            if !ctx.plan.runs(Effect::Direct) {
                rec.encoder().clear_buffer(&self.radiance, 0, None);
            }
        }
    }

    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        let mut pass = rec.pass(id);
        let defines = ctx.settings.precision.defines();
        let mut entries = self.entries(ctx);
        match id {
            PassId::TransparencyPeel => {
                // The opacity reads textures only where the scene may have them.
                let textures = [super::textures_constant(ctx.scene)];
                let accumulate = ctx.pipelines.get(
                    ctx.device,
                    "transparency",
                    "accumulate",
                    &defines,
                    &textures,
                );
                // Peel k writes peels[k % 2] against the other (the previous peel).
                let step = |k: usize, mode| Draw {
                    vis1: Some(&self.peels[k % 2]),
                    zref: Some(&self.peels[1 - k % 2]),
                    opaque: Some(ctx.raster.vis0()),
                    peel_args: (mode == RasterMode::Peel).then_some(&self.args),
                    ..Draw::new(ctx.frame, mode)
                };
                let r = &ctx.raster.rasterizer;
                let layers = ctx.settings.transparency.layers as usize;
                for k in 0..layers {
                    let current = &self.peels[k % 2];
                    self.empty.record(ctx.device, ctx.pipelines, &mut pass, current);
                    let peel = step(k, RasterMode::Peel);
                    r.draw(ctx.device, ctx.pipelines, &mut pass, ctx.scene, peel);
                    // A peel that found nothing costs its raster alone: the kernels below get
                    // no workgroups.
                    let args = Some(&self.args);
                    super::resolve::resolve_layer(ctx, &mut pass, current, &self.gbuffer, args);
                    if ctx.plan.runs(Effect::Direct) {
                        let (g, out) = (&self.gbuffer, &self.radiance);
                        let over = super::direct::Over::Groups(&self.args);
                        ctx.lighting.light(ctx, &mut pass, g, (out, None), over);
                    }
                    entries.retain(|(s, _)| *s != slot::VIS);
                    entries.push((slot::VIS, current));
                    accumulate.dispatch_indirect(ctx.device, &mut pass, &entries, &self.args, 0);
                }
                // What lies behind the last peel: counted, not drawn.
                let unpeeled = step(layers, RasterMode::Unpeeled);
                r.draw(ctx.device, ctx.pipelines, &mut pass, ctx.scene, unpeeled);
            }
            PassId::TransparencyComposite => {
                let (Some(behind), image) = ctx.image_io(id) else {
                    unreachable!("a post pass reads an image");
                };
                entries.extend([(slot::BEHIND, behind), (slot::IMAGE, image)]);
                let composite =
                    ctx.pipelines.get(ctx.device, "transparency", "composite", &defines, &[]);
                composite.dispatch_pixels(ctx.device, &mut pass, &entries, ctx.size());
            }
            other => unreachable!("{other} is not a transparency pass"),
        }
    }
}
