//! `wgsl/ao.wgsl`: two-layer ambient obscurance, with its depth pyramids and blur.

use super::blur::Blur;
use super::pyramid::{Pyramid, PyramidKind};
use super::{FrameContext, Recorder, Stage};
use crate::frame::AoUniform;
use crate::gpu::{self, slots::ao as slot};
use crate::plan::PassId;
use crate::settings::{AoEstimator, Settings};

/// The obscurance: depth pyramids of the layers it reads, its constants, raw AV, the blur's
/// intermediate and blurred AV (f32 per pixel).
pub(crate) struct AoStage {
    two_layers: bool,
    pyramid: Pyramid,
    pyramids: [wgpu::Buffer; 2],
    uniform: wgpu::Buffer,
    raw: wgpu::Buffer,
    scratch: wgpu::Buffer,
    blurred: wgpu::Buffer,
}

impl AoStage {
    /// The stage for `s`, reading both layers when `two_layers`.
    pub(crate) fn new(device: &wgpu::Device, s: &Settings, two_layers: bool) -> Self {
        let pyramid = Pyramid::new(device, s.width, s.height);
        let buffer =
            |label, size| gpu::storage_buffer(device, label, size, wgpu::BufferUsages::empty());
        let bytes = pyramid.layout().bytes();
        let pixels = u64::from(s.width) * u64::from(s.height) * 4;
        AoStage {
            two_layers,
            pyramids: [
                buffer("deep-gbuffer.pyramid.layer0", bytes),
                buffer("deep-gbuffer.pyramid.layer1", bytes),
            ],
            uniform: gpu::uniform_buffer(
                device,
                "deep-gbuffer.ao",
                bytemuck::bytes_of(&AoUniform::new(&s.ao, pyramid.layout())),
            ),
            raw: buffer("deep-gbuffer.ao.raw", pixels),
            scratch: buffer("deep-gbuffer.ao.blur", pixels),
            blurred: buffer("deep-gbuffer.ao.av", pixels),
            pyramid,
        }
    }

    /// Whether it reads both layers.
    pub(crate) fn two_layers(&self) -> bool {
        self.two_layers
    }

    /// AV as the composite reads it (blurred unless the blur radius is 0).
    pub(crate) fn av(&self, s: &Settings) -> &wgpu::Buffer {
        if s.ao.blur_radius > 0 { &self.blurred } else { &self.raw }
    }

    /// AV before the blur.
    pub(crate) fn raw(&self) -> &wgpu::Buffer {
        &self.raw
    }

    /// The depth pyramid of `layer`.
    pub(crate) fn pyramid(&self, layer: usize) -> &wgpu::Buffer {
        &self.pyramids[layer.min(1)]
    }
}

impl Stage for AoStage {
    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        let mut pass = rec.pass(id);
        match id {
            PassId::Pyramid => {
                let layers = 1 + usize::from(self.two_layers);
                for layer in 0..layers {
                    let (gbuffer, target) = (ctx.gbuffer[layer], &self.pyramids[layer]);
                    self.pyramid.record(ctx, &mut pass, PyramidKind::RotatedGrid, gbuffer, target);
                }
            }
            PassId::Ao => {
                let mut defines = ctx.settings.precision.defines();
                if self.two_layers {
                    defines.push("TWO_LAYERS");
                }
                if ctx.settings.ao.estimator != AoEstimator::Sao {
                    defines.push("SLICES");
                }
                let pipeline = ctx.pipelines.get(ctx.device, "ao", "ao_main", &defines, &[]);
                let entries = [
                    (slot::FRAME, ctx.frame),
                    (slot::AO, &self.uniform),
                    (slot::GBUFFER, ctx.gbuffer[0]),
                    (slot::PYRAMID0, &self.pyramids[0]),
                    (slot::PYRAMID1, &self.pyramids[1]),
                    (slot::AV, &self.raw),
                ];
                pipeline.dispatch_pixels(ctx.device, &mut pass, &entries, ctx.size());
            }
            PassId::AoBlur => {
                let blur = Blur { radius: ctx.settings.ao.blur_radius, vec4: false };
                blur.record(ctx, &mut pass, [&self.raw, &self.scratch, &self.blurred]);
            }
            other => unreachable!("{other} is not an obscurance pass"),
        }
    }
}
