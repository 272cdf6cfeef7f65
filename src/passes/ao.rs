//! `wgsl/ao.wgsl`: two-layer ambient obscurance, with its depth pyramids and blur.

use super::blur::Blur;
use super::pyramid::{Pyramid, PyramidKind};
use super::temporal::Temporal;
use super::upsample::Upsample;
use super::{FrameContext, Recorder, Stage};
use crate::frame::{AoUniform, mip_size};
use crate::gpu::{self, slots::ao as slot};
use crate::plan::PassId;
use crate::settings::{AoEstimator, Settings, downsample_level};

/// The obscurance: depth pyramids of the layers it reads, its constants, AV at the resolution it
/// is computed at (when that is not the image's), raw AV, the temporally filtered AV of the last
/// and this frame (ping-pong, with the filter or a still view's mean), the blur's intermediate
/// and blurred AV (f32 per pixel).
pub(crate) struct AoStage {
    two_layers: bool,
    pyramid: Pyramid,
    pyramids: [wgpu::Buffer; 2],
    uniform: wgpu::Buffer,
    /// The level of the rotated grid AV is computed at, and its buffer when that is not 0.
    level: u32,
    low: Option<wgpu::Buffer>,
    raw: wgpu::Buffer,
    /// The filtered AV (with the temporal filter), and which of them this (or, between frames,
    /// the last) frame filters into.
    history: Option<[wgpu::Buffer; 2]>,
    current: usize,
    /// Frames since the filter's history began (0: none), and its constants.
    turn: u32,
    temporal: Temporal,
    /// Whether the filtered AV holds the last frame that ran the obscurance (or kept it).
    continues: bool,
    /// Whether the last frame that ran the obscurance filtered it (the filter, or a still
    /// view's mean): the AV the blur and the composite read is then the filtered one.
    filtered_last: bool,
    /// The blur's radius this frame ([`AoSettings::blur_radius_for`] the frames in the mean).
    blur_radius: u32,
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
            uniform: gpu::uniform_buffer_for::<AoUniform>(device, "deep-gbuffer.ao"),
            raw: buffer("deep-gbuffer.ao.raw", pixels),
            history: (s.ao.temporal() || s.ao.still_frames > 0).then(|| {
                [
                    buffer("deep-gbuffer.ao.history.a", pixels),
                    buffer("deep-gbuffer.ao.history.b", pixels),
                ]
            }),
            current: 0,
            turn: 0,
            temporal: Temporal::new(device, "deep-gbuffer.ao.temporal", false),
            continues: false,
            filtered_last: false,
            blur_radius: s.ao.blur_radius,
            scratch: buffer("deep-gbuffer.ao.blur", pixels),
            blurred: buffer("deep-gbuffer.ao.av", pixels),
            pyramid,
        }
    }

    /// Whether it reads both layers.
    pub(crate) fn two_layers(&self) -> bool {
        self.two_layers
    }

    /// Starts a frame that runs the obscurance: filters into the other history buffer (when
    /// `filters`: the plan runs `ao.temporal`) and writes the constants; `history`: the last
    /// frame's camera is known (no cut) and its filtered AV may be used, if the last frame that
    /// ran (or kept) the obscurance was the last frame and filtered it; `still`: the frames in a
    /// row the view has stood still (the filter's weight,
    /// [`AoSettings::history_weight`](crate::AoSettings::history_weight)).
    pub(crate) fn prepare(
        &mut self,
        queue: &wgpu::Queue,
        s: &Settings,
        (history, filters): (bool, bool),
        still: u32,
    ) {
        let filters = filters && self.history.is_some();
        let history = history && self.continues && self.filtered_last && filters;
        self.current = 1 - self.current;
        // The slices turn on every frame the filter carries a history into, and on a still
        // view's first frame (its mean's first term, unlike the moving frame before it).
        self.turn = if history {
            self.turn.wrapping_add(1).max(1)
        } else if filters && still > 0 {
            still
        } else {
            0
        };
        let uniform = AoUniform::new(&s.ao, self.pyramid.layout(), self.turn);
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        let alpha = s.ao.history_weight(still);
        self.temporal.prepare(queue, alpha, s.ao.history_tolerance, history);
        // A still view's mean of n frames (history weight 1 - 1 / n) narrows the blur.
        let averaged = if filters && history && still > 0 { 1.0 / (1.0 - alpha) } else { 1.0 };
        self.blur_radius = s.ao.blur_radius_for(averaged);
        self.continues = true;
        self.filtered_last = filters;
    }

    /// Marks a frame that neither ran nor kept the obscurance: the next one starts afresh.
    pub(crate) fn skipped(&mut self) {
        self.continues = false;
    }

    /// The temporally filtered AV of this frame (the last, between frames), when it was
    /// filtered (the filter, or a still view's mean).
    pub(crate) fn filtered(&self) -> Option<&wgpu::Buffer> {
        self.history.as_ref().filter(|_| self.filtered_last).map(|h| &h[self.current])
    }

    /// AV as the blur reads it: filtered when this frame filtered it (the temporal filter or a
    /// still view's mean), else raw.
    fn unblurred(&self) -> &wgpu::Buffer {
        self.filtered().unwrap_or(&self.raw)
    }

    /// AV as the composite reads it (blurred unless the blur radius is 0).
    pub(crate) fn av(&self, s: &Settings) -> &wgpu::Buffer {
        if s.ao.blur_radius > 0 { &self.blurred } else { self.unblurred() }
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
            PassId::AoTemporal => {
                let history = self.history.as_ref().expect("made with the temporal filter");
                let (history_in, history_out) =
                    (&history[1 - self.current], &history[self.current]);
                self.temporal.record(ctx, &mut pass, [&self.raw, history_in, history_out]);
            }
            PassId::AoBlur => {
                let blur = Blur { radius: self.blur_radius, vec4: false, plane: true };
                blur.record(ctx, &mut pass, [self.unblurred(), &self.scratch, &self.blurred]);
            }
            other => unreachable!("{other} is not an obscurance pass"),
        }
    }
}
