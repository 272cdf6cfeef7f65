//! `wgsl/ao.wgsl`: two-layer ambient obscurance, with its depth pyramids and blur.

use super::blur::Blur;
use super::pyramid::{Pyramid, PyramidKind};
use super::upsample::Upsample;
use super::{FrameContext, Recorder, Stage};
use crate::frame::{AoUniform, mip_size};
use crate::gpu::{self, slots::ao as slot};
use crate::plan::PassId;
use crate::settings::{AoEstimator, Settings, downsample_level};

/// The obscurance: depth pyramids of the layers it reads, its constants, AV at the resolution it
/// is computed at (when that is not the image's), raw AV, the blur's intermediate and blurred AV
/// (f32 per pixel).
pub(crate) struct AoStage {
    two_layers: bool,
    pyramid: Pyramid,
    pyramids: [wgpu::Buffer; 2],
    uniform: wgpu::Buffer,
    /// The level of the rotated grid AV is computed at, and its buffer when that is not 0.
    level: u32,
    low: Option<wgpu::Buffer>,
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
        let level = downsample_level(s.ao.downsample);
        let (w, h) = mip_size(s.width, s.height, level as usize);
        let low =
            (level > 0).then(|| buffer("deep-gbuffer.ao.low", u64::from(w) * u64::from(h) * 4));
        AoStage {
            level,
            low,
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

    /// AV at the resolution it is computed at, when that is not the image's.
    pub(crate) fn low(&self) -> Option<&wgpu::Buffer> {
        self.low.as_ref()
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
                let level = [("LEVEL", f64::from(self.level))];
                let pipeline = ctx.pipelines.get(ctx.device, "ao", "ao_main", &defines, &level);
                let target = self.low.as_ref().unwrap_or(&self.raw);
                let entries = [
                    (slot::FRAME, ctx.frame),
                    (slot::AO, &self.uniform),
                    (slot::GBUFFER, ctx.gbuffer[0]),
                    (slot::PYRAMID0, &self.pyramids[0]),
                    (slot::PYRAMID1, &self.pyramids[1]),
                    (slot::AV, target),
                ];
                let size = mip_size(ctx.settings.width, ctx.settings.height, self.level as usize);
                pipeline.dispatch_pixels(ctx.device, &mut pass, &entries, size);
                if let Some(low) = &self.low {
                    let upsample = Upsample { level: self.level, vec4: false, empty: 1.0 };
                    upsample.record(ctx, &mut pass, [low, &self.raw]);
                }
            }
            PassId::AoBlur => {
                let blur = Blur { radius: ctx.settings.ao.blur_radius, vec4: false };
                blur.record(ctx, &mut pass, [&self.raw, &self.scratch, &self.blurred]);
            }
            other => unreachable!("{other} is not an obscurance pass"),
        }
    }
}
