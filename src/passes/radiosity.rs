//! `wgsl/radiosity.wgsl`: screen-space radiosity with temporal multi-bounce.

use super::blur::Blur;
use super::offscreen::Offscreen;
use super::pyramid::Pyramid;
use super::temporal::Temporal;
use super::upsample::Upsample;
use super::{FrameContext, PointList, Recorder, Stage};
use crate::frame::{RadiosityUniform, SourceTexel, mip_size};
use crate::gpu::{self, slots::radiosity as slot};
use crate::plan::{PassId, Plan};
use crate::settings::{RadiosityEstimator, Settings, downsample_level};

/// The radiosity's buffers, as
/// [`Renderer::radiosity_buffers`](crate::Renderer::radiosity_buffers) names them: the gather
/// source, then `vec4<f32>` per pixel.
#[derive(Clone, Copy, Debug)]
pub struct RadiosityBuffers<'a> {
    /// The gather source: a [`SourceTexel`](crate::frame::SourceTexel) per pixel (view depths,
    /// normals and outgoing radiance B of both layers: direct + emission + damped indirect
    /// light, and H, what each surface's far side sends), then
    /// its MIP levels (as [`PyramidLayout`](crate::frame::PyramidLayout) places them).
    pub source: &'a wgpu::Buffer,
    /// The gather at 1 / [`RadiositySettings::downsample`](crate::RadiositySettings) of the
    /// image's width and height (a texel of that level of the rotated grid each, before the
    /// upsample into `gathered`); `None` at full resolution.
    pub low: Option<&'a wgpu::Buffer>,
    /// The gather's irradiance (rgb) and confidence (a).
    pub gathered: &'a wgpu::Buffer,
    /// The temporally filtered irradiance and confidence.
    pub filtered: &'a wgpu::Buffer,
    /// The irradiance and confidence the composite reads (blurred unless the radius is 0).
    pub irradiance: &'a wgpu::Buffer,
    /// The layer-1 gather (`radiosity.layer1`) at the texels of the gather's level: E / c of
    /// each layer-1 point (the irradiance found, spread over the hemisphere) and its view depth
    /// (0: none), `vec4<f32>` each; `None` until a frame ran it.
    pub layer1: Option<&'a wgpu::Buffer>,
}

impl<'a> RadiosityBuffers<'a> {
    /// The `vec4<f32>` buffers with their names: `gathered`, `filtered`, `irradiance`.
    pub fn named(&self) -> [(&'static str, &'a wgpu::Buffer); 3] {
        [("gathered", self.gathered), ("filtered", self.filtered), ("irradiance", self.irradiance)]
    }
}

/// The layer-1 gather's buffers: its records (E / c and view depth per texel) and the list of the
/// texels it runs at (those that hold a layer-1 point).
struct Layer1Gather {
    records: wgpu::Buffer,
    listed: PointList,
}

/// The radiosity: its constants, the gather source and its levels' constants, the gathered
/// irradiance, the filtered irradiance of the last and this frame (ping-pong), and the blur's
/// intermediate and result.
pub(crate) struct RadiosityStage {
    uniform: wgpu::Buffer,
    source: wgpu::Buffer,
    levels: Pyramid,
    /// The level of the rotated grid the gather computes, and its buffer when that is not 0.
    level: u32,
    low: Option<wgpu::Buffer>,
    gathered: wgpu::Buffer,
    history: [wgpu::Buffer; 2],
    /// Which `history` this (or, between frames, the last) frame filters into.
    current: usize,
    /// Frames since the history began.
    turn: u32,
    /// The temporal filter's constants.
    temporal: Temporal,
    scratch: wgpu::Buffer,
    blurred: wgpu::Buffer,
    /// The layer-1 gather's buffers, made by the first frame that runs it.
    layer1: Option<Layer1Gather>,
    /// Whether the last frame ran the layer-1 gather (the next one's feedback reads it).
    layer1_written: bool,
    /// Whether this frame's feedback reads the last frame's layer-1 gather.
    layer1_bounce: bool,
    /// The off-screen light's constants and clusters (made by the first frame that adds it).
    offscreen: Option<Offscreen>,
}

impl RadiosityStage {
    /// Targets for `s`'s image size.
    pub(crate) fn new(device: &wgpu::Device, s: &Settings) -> Self {
        let pixels = u64::from(s.width) * u64::from(s.height);
        let storage =
            |label, bytes| gpu::storage_buffer(device, label, bytes, wgpu::BufferUsages::empty());
        let buffer = |label| storage(label, pixels * 16);
        let levels = Pyramid::new(device, s.width, s.height);
        let texels = u64::from(levels.layout().total);
        let level = downsample_level(s.radiosity.downsample);
        let (w, h) = mip_size(s.width, s.height, level as usize);
        let low = (level > 0)
            .then(|| storage("deep-gbuffer.radiosity.low", u64::from(w) * u64::from(h) * 16));
        RadiosityStage {
            level,
            low,
            uniform: gpu::uniform_buffer_for::<RadiosityUniform>(device, "deep-gbuffer.radiosity"),
            source: storage(
                "deep-gbuffer.radiosity.source",
                texels * std::mem::size_of::<SourceTexel>() as u64,
            ),
            levels,
            gathered: buffer("deep-gbuffer.radiosity.raw"),
            history: [
                buffer("deep-gbuffer.radiosity.history.a"),
                buffer("deep-gbuffer.radiosity.history.b"),
            ],
            current: 0,
            turn: 0,
            temporal: Temporal::new(device, "deep-gbuffer.radiosity.temporal", true),
            scratch: buffer("deep-gbuffer.radiosity.blur"),
            blurred: buffer("deep-gbuffer.radiosity.blurred"),
            layer1: None,
            layer1_written: false,
            layer1_bounce: false,
            offscreen: None,
        }
    }

    /// Starts a frame: filters into the other history buffer and writes the constants;
    /// `history` tells whether the last frame's irradiance may be used, `still` how many frames
    /// in a row the view has stood still (the filter's weight, `history_weight`); `plan` whether this
    /// frame runs the layer-1 gather, and the off-screen light over `offscreen` reflective
    /// shadow map faces.
    pub(crate) fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        s: &Settings,
        (history, still): (bool, u32),
        plan: &Plan,
        offscreen: u32,
    ) {
        let layer1 = plan.contains(&PassId::RadiosityLayer1);
        self.layer1_bounce = history && self.layer1_written;
        self.layer1_written = layer1;
        if layer1 && self.layer1.is_none() {
            let (w, h) = mip_size(s.width, s.height, self.level as usize);
            let texels = u64::from(w) * u64::from(h);
            self.layer1 = Some(Layer1Gather {
                records: gpu::storage_buffer(
                    device,
                    "deep-gbuffer.radiosity.layer1",
                    texels * 16,
                    wgpu::BufferUsages::empty(),
                ),
                listed: PointList::new(device, "deep-gbuffer.radiosity.layer1_list", texels),
            });
        }
        self.current = 1 - self.current;
        self.turn = if history && s.radiosity.jitter { self.turn.wrapping_add(1) } else { 0 };
        let uniform = RadiosityUniform {
            alpha: s.radiosity.history_weight(still),
            ..RadiosityUniform::new(&s.radiosity, self.levels.layout(), (history, still), self.turn)
        };
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        self.temporal.prepare(queue, uniform.alpha, uniform.tolerance, history);
        if plan.contains(&PassId::RadiosityOffscreen) {
            let o = Offscreen::for_faces(self.offscreen.take(), device, offscreen);
            o.prepare(queue, self.turn, plan.layers);
            self.offscreen = Some(o);
        }
    }

    /// The off-screen light's clusters, once a frame has added it.
    pub(crate) fn clusters(&self) -> Option<&wgpu::Buffer> {
        self.offscreen.as_ref().map(Offscreen::clusters)
    }

    /// This frame's buffers (the last frame's, between frames).
    pub(crate) fn buffers(&self, s: &Settings) -> RadiosityBuffers<'_> {
        let filtered = &self.history[self.current];
        RadiosityBuffers {
            source: &self.source,
            low: self.low.as_ref(),
            gathered: &self.gathered,
            filtered,
            irradiance: if s.radiosity.blur_radius > 0 { &self.blurred } else { filtered },
            layer1: self.layer1.as_ref().map(|l| &l.records).filter(|_| self.layer1_written),
        }
    }
}

impl Stage for RadiosityStage {
    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        // The layer-1 gather's list starts empty, and its records at 0 where no point is listed
        // (the next frame's feedback must find nothing where a point was lost). This frame's
        // feedback, which reads the last frame's records, was recorded before.
        if let (PassId::RadiosityLayer1, Some(l)) = (id, &self.layer1) {
            l.listed.clear(rec.encoder());
            rec.encoder().clear_buffer(&l.records, 0, None);
        }
        let mut pass = rec.pass(id);
        let (history_in, history_out) =
            (&self.history[1 - self.current], &self.history[self.current]);
        let entries = [
            (slot::FRAME, ctx.frame),
            (slot::PARAMS, &self.uniform),
            (slot::GBUFFER0, ctx.gbuffer[0]),
            (slot::GBUFFER1, ctx.gbuffer[1]),
            (slot::DIFFUSE0, ctx.diffuse[0]),
            (slot::DIFFUSE1, ctx.diffuse[1]),
            (slot::SOURCE, &self.source),
            (slot::RAW, &self.gathered),
            (slot::HISTORY_IN, history_in),
            (slot::PREV_VIS0, ctx.raster.previous_vis0()),
            // Only the passes that use the layer-1 gather read or write it; the blur's
            // scratch (unused here) stands in for it elsewhere.
            (slot::LAYER1_GATHERED, self.layer1.as_ref().map_or(&self.scratch, |l| &l.records)),
            (slot::LIST, self.layer1.as_ref().map_or(&self.scratch, |l| &l.listed.list)),
            (slot::LIST_ARGS, self.layer1.as_ref().map_or(&self.scratch, |l| &l.listed.args)),
        ];
        let mut defines = ctx.settings.precision.defines();
        if ctx.settings.radiosity.estimator == RadiosityEstimator::Slices {
            defines.push("SLICES");
        }
        // One entry point of wgsl/radiosity.wgsl over `size` texels.
        let dispatch = |pass: &mut wgpu::ComputePass<'_>,
                        entry,
                        entries: &[_],
                        constants: &[(&'static str, f64)],
                        size| {
            let pipeline = ctx.pipelines.get(ctx.device, "radiosity", entry, &defines, constants);
            pipeline.dispatch_pixels(ctx.device, pass, entries, size);
        };
        let level = ("LEVEL", f64::from(self.level));
        let gather_size = mip_size(ctx.settings.width, ctx.settings.height, self.level as usize);
        // The gather at the points of layer `receiver`, at the texels of the gather's level.
        let gather = |pass: &mut wgpu::ComputePass<'_>, entries: &[_], receiver: u8| {
            let constants = [level, ("RECEIVER", f64::from(receiver))];
            dispatch(pass, "radiosity_gather", entries, &constants, gather_size);
        };
        match id {
            PassId::Radiosity => {
                let bounce = ("LAYER1_BOUNCE", f64::from(u8::from(self.layer1_bounce)));
                dispatch(&mut pass, "radiosity_feedback", &entries, &[level, bounce], ctx.size());
                let pipeline =
                    ctx.pipelines.get(ctx.device, "radiosity", "radiosity_source_level", &[], &[]);
                for (i, level) in self.levels.layout().levels.iter().enumerate().skip(1) {
                    let entries =
                        [(slot::SOURCE, &self.source), (slot::LEVEL, self.levels.level(i))];
                    pipeline.dispatch_pixels(
                        ctx.device,
                        &mut pass,
                        &entries,
                        (level.width, level.height),
                    );
                }
                // At a lower resolution the gather writes its own buffer, upsampled into `raw`.
                let target = self.low.as_ref().unwrap_or(&self.gathered);
                gather(
                    &mut pass,
                    &entries.map(|(s, b)| (s, if s == slot::RAW { target } else { b })),
                    0,
                );
                if let Some(low) = &self.low {
                    let upsample = Upsample { level: self.level, vec4: true, empty: 0.0 };
                    upsample.record(ctx, &mut pass, [low, &self.gathered]);
                }
            }
            PassId::RadiosityLayer1 => {
                // The gather runs at the texels that hold a layer-1 point only, listed first.
                let args = &self.layer1.as_ref().expect("made with the layer-1 gather").listed.args;
                dispatch(&mut pass, "radiosity_layer1_list", &entries, &[level], gather_size);
                ctx.pipelines
                    .get(ctx.device, "radiosity", "radiosity_layer1_dispatch", &[], &[])
                    .dispatch(ctx.device, &mut pass, &entries, (1, 1));
                let constants = [level, ("RECEIVER", 1.0)];
                ctx.pipelines
                    .get(ctx.device, "radiosity", "radiosity_gather_listed", &defines, &constants)
                    .dispatch_indirect(ctx.device, &mut pass, &entries, args, 0);
            }
            PassId::RadiosityOffscreen => {
                let offscreen =
                    self.offscreen.as_ref().expect("prepared with the off-screen light");
                offscreen.record(ctx, &mut pass, &self.gathered);
            }
            PassId::RadiosityTemporal => {
                self.temporal.record(ctx, &mut pass, [&self.gathered, history_in, history_out]);
            }
            PassId::RadiosityBlur => {
                let blur =
                    Blur { radius: ctx.settings.radiosity.blur_radius, vec4: true, plane: false };
                blur.record(ctx, &mut pass, [history_out, &self.scratch, &self.blurred]);
            }
            other => unreachable!("{other} is not a radiosity pass"),
        }
    }
}
