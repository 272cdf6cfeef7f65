//! `wgsl/direct.wgsl`: deferred direct light, with or without shadow maps, of layer 0 and of
//! layer 1 where a later pass reads it.

use super::{FrameContext, PointList, Recorder, Stage};
use crate::SceneBuffers;
use crate::frame::DirectUniform;
use crate::gpu::{self, slots::direct as slot};
use crate::plan::{Effect, PassId, Plan};
use crate::settings::Settings;

/// Direct radiance of both layers (`vec4<f32>` per pixel), its Lambertian part (what the
/// radiosity passes on), the kernel's constants, and the list of the pixels that hold a layer-1
/// surface.
pub(crate) struct DirectStage {
    uniform: wgpu::Buffer,
    radiance: [wgpu::Buffer; 2],
    diffuse: [wgpu::Buffer; 2],
    listed: PointList,
}

/// Which pixels [`DirectStage::light`] lights.
#[derive(Clone, Copy)]
pub(crate) enum Over<'a> {
    /// The whole image.
    Image,
    /// The 8x8-pixel workgroups this indirect dispatch buffer holds.
    Groups(&'a wgpu::Buffer),
    /// The pixels that hold a surface, listed first: few pixels hold a layer-1 surface, and a
    /// workgroup of 64 listed pixels has no idle lanes. The targets must be cleared before.
    Listed,
}

impl DirectStage {
    /// Targets for a `pixels`-pixel image.
    pub(crate) fn new(device: &wgpu::Device, pixels: u64) -> Self {
        let buffer =
            |label| gpu::storage_buffer(device, label, pixels * 16, wgpu::BufferUsages::empty());
        DirectStage {
            listed: PointList::new(device, "deep-gbuffer.direct.list", pixels),
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
        let plan = ctx.plan;
        let dof_layer1 = (plan.runs(Effect::Dof) && ctx.settings.dof.two_layers)
            || (plan.runs(Effect::MotionBlur) && ctx.settings.motion_blur.two_layers);
        // The reflections light the surfaces their rays hit themselves.
        let layers = if plan.runs(Effect::Radiosity) || dof_layer1 { 2 } else { 1 };
        let diffuse = plan.runs(Effect::Radiosity);
        if layers == 2 {
            // Layer 1 is lit at its listed pixels: the rest of its targets reads 0.
            let encoder = rec.encoder();
            self.listed.clear(encoder);
            encoder.clear_buffer(&self.radiance[1], 0, None);
            if diffuse {
                encoder.clear_buffer(&self.diffuse[1], 0, None);
            }
        }
        let mut pass = rec.pass(id);
        for layer in 0..layers {
            let targets = (&self.radiance[layer], diffuse.then_some(&self.diffuse[layer]));
            let over = if layer == 0 { Over::Image } else { Over::Listed };
            self.light(ctx, &mut pass, ctx.gbuffer[layer], targets, over);
        }
    }
}

impl DirectStage {
    /// Records the direct light of G-buffer layer `gbuffer` into `radiance` (and its
    /// Lambertian part into `diffuse`, when given) at the pixels `over` names.
    pub(crate) fn light(
        &self,
        ctx: &FrameContext<'_>,
        pass: &mut wgpu::ComputePass<'_>,
        gbuffer: &wgpu::Buffer,
        (radiance, diffuse): (&wgpu::Buffer, Option<&wgpu::Buffer>),
        over: Over<'_>,
    ) {
        let mut defines = ctx.settings.precision.defines();
        if ctx.shadows.is_some() {
            defines.push("SHADOWS");
        }
        if diffuse.is_some() {
            defines.push("DIFFUSE");
        }
        if let Over::Listed = over {
            defines.push("LISTED");
        }
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
        let kernel = |entry| ctx.pipelines.get(ctx.device, "direct", entry, &defines, &[]);
        match over {
            Over::Image => {
                kernel("direct_main").dispatch_pixels(ctx.device, pass, &entries, ctx.size())
            }
            Over::Groups(args) => {
                kernel("direct_main").dispatch_indirect(ctx.device, pass, &entries, args, 0)
            }
            Over::Listed => {
                let PointList { list, args } = &self.listed;
                // Not `args`: a dispatch may not read its indirect buffer as storage.
                entries.push((slot::LIST, list));
                let listing =
                    [(slot::FRAME, ctx.frame), (slot::GBUFFER, gbuffer), (slot::LIST, list)];
                kernel("direct_list").dispatch_pixels(ctx.device, pass, &listing, ctx.size());
                let count = [(slot::LIST, list), (slot::LIST_ARGS, args)];
                kernel("direct_list_args").dispatch(ctx.device, pass, &count, (1, 1));
                kernel("direct_listed").dispatch_indirect(ctx.device, pass, &entries, args, 0);
            }
        }
    }
}
