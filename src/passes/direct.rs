//! `wgsl/direct.wgsl`: deferred direct light, with or without shadow maps, of layer 0 and of
//! layer 1 where a later pass reads it.

use super::{FrameContext, Recorder, Stage};
use crate::SceneBuffers;
use crate::frame::DirectUniform;
use crate::gpu::{self, slots::direct as slot};
use crate::plan::{Effect, PassId, Plan};
use crate::settings::Settings;

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

/// Direct radiance of both layers (`vec4<f32>` per pixel), its Lambertian part (what the
/// radiosity passes on) and the kernel's constants.
pub(crate) struct DirectStage {
    uniform: wgpu::Buffer,
    radiance: [wgpu::Buffer; 2],
    diffuse: [wgpu::Buffer; 2],
}

impl DirectStage {
    /// Targets for a `pixels`-pixel image.
    pub(crate) fn new(device: &wgpu::Device, pixels: u64) -> Self {
        let buffer =
            |label| gpu::storage_buffer(device, label, pixels * 16, wgpu::BufferUsages::empty());
        DirectStage {
            uniform: gpu::uniform_buffer_for::<DirectUniform>(device, "deep-gbuffer.direct"),
            diffuse: [
                buffer("deep-gbuffer.direct.diffuse"),
                buffer("deep-gbuffer.direct.diffuse1"),
            ],
            radiance: [
                buffer("deep-gbuffer.direct.radiance"),
                buffer("deep-gbuffer.direct.radiance1"),
            ],
        }
    }

    /// Writes the frame's constants.
    pub(crate) fn prepare(
        &self,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        s: &Settings,
        plan: &Plan,
    ) {
        let pcf = if plan.runs(Effect::Shadows) { s.shadows.pcf } else { 0 };
        let light_count = scene.info().lights.len() as u32;
        let uniform = DirectUniform { light_count, pcf, _pad: [0; 2] };
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }

    /// The direct radiance of `layer` (zero where no light runs).
    pub(crate) fn radiance(&self, layer: usize) -> &wgpu::Buffer {
        &self.radiance[layer.min(1)]
    }

    /// The Lambertian part of the direct radiance of `layer` (written when the radiosity runs;
    /// zero where no light runs).
    pub(crate) fn diffuse(&self, layer: usize) -> &wgpu::Buffer {
        &self.diffuse[layer.min(1)]
    }
}

impl Stage for DirectStage {
    fn begin(&self, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        if !ctx.plan.runs(Effect::Direct) {
            for radiance in self.radiance.iter().chain(&self.diffuse) {
                rec.encoder().clear_buffer(radiance, 0, None);
            }
        }
    }

    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        debug_assert_eq!(*id, PassId::Direct);
        let mut pass = rec.pass(id);
        let plan = ctx.plan;
        let dof_layer1 = (plan.runs(Effect::Dof) && ctx.settings.dof.two_layers)
            || (plan.runs(Effect::MotionBlur) && ctx.settings.motion_blur.two_layers);
        // The reflections light the surfaces their rays hit themselves.
        let layers = if plan.runs(Effect::Radiosity) || dof_layer1 { 2 } else { 1 };
        let diffuse = plan.runs(Effect::Radiosity);
        for layer in 0..layers {
            let targets = (&self.radiance[layer], diffuse.then_some(&self.diffuse[layer]));
            self.light(ctx, &mut pass, ctx.gbuffer[layer], targets, None);
        }
    }
}

impl DirectStage {
    /// Records the direct light of G-buffer layer `gbuffer` into `radiance` (and its
    /// Lambertian part into `diffuse`, when given), over the whole image or with the workgroups
    /// `args` holds (8x8 pixels each).
    pub(crate) fn light(
        &self,
        ctx: &FrameContext<'_>,
        pass: &mut wgpu::ComputePass<'_>,
        gbuffer: &wgpu::Buffer,
        (radiance, diffuse): (&wgpu::Buffer, Option<&wgpu::Buffer>),
        args: Option<&wgpu::Buffer>,
    ) {
        let mut defines = ctx.settings.precision.defines();
        if ctx.shadows.is_some() {
            defines.push("SHADOWS");
        }
        if diffuse.is_some() {
            defines.push("DIFFUSE");
        }
        let pipeline = ctx.pipelines.get(ctx.device, "direct", "direct_main", &defines, &[]);
        let mut entries = vec![
            (slot::FRAME, ctx.frame),
            (slot::DIRECT, &self.uniform),
            (slot::GBUFFER, gbuffer),
            (slot::LIGHTS, ctx.scene.light_buffer()),
            (slot::RADIANCE, radiance),
        ];
        if let Some(diffuse) = diffuse {
            entries.push((slot::DIFFUSE, diffuse));
        }
        if let Some(s) = &ctx.shadows {
            entries.extend([
                (slot::FACES, s.faces),
                (slot::LIGHT_FACES, s.light_faces),
                (slot::ATLAS, s.atlas),
            ]);
        }
        match args {
            Some(args) => pipeline.dispatch_indirect(ctx.device, pass, &entries, args, 0),
            None => pipeline.dispatch_pixels(ctx.device, pass, &entries, ctx.size()),
        }
    }
}
