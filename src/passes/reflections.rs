//! `wgsl/reflections.wgsl`: screen-space reflections against both layers, in reflective tiles
//! only.

use super::pyramid::{Pyramid, PyramidKind};
use super::{FrameContext, PointList, Recorder, Stage};
use crate::SceneBuffers;
use crate::frame::ReflectionsUniform;
use crate::gpu::{self, slots::reflections as slot};
use crate::plan::{Effect, PassId, Plan};
use crate::settings::Settings;

/// The reflections: constants, layer 0's nearest-depth pyramid, the reflective tiles and their
/// indirect arguments, and the reflected radiance (rgb, times the reflectivity) and confidence
/// (a) per pixel.
pub(crate) struct ReflectionsStage {
    uniform: wgpu::Buffer,
    pyramid: Pyramid,
    nearest: wgpu::Buffer,
    tiles: PointList,
    output: wgpu::Buffer,
    /// The rays followed through the shadow maps (a count, then pixel and distance per ray) and
    /// the indirect arguments of the kernel that follows them.
    followed: wgpu::Buffer,
    hidden_args: wgpu::Buffer,
    /// Bound in place of an environment map when there is none.
    no_environment: wgpu::Buffer,
    tiles_x: u32,
    tiles_y: u32,
}

impl ReflectionsStage {
    /// Targets for `s`'s image size.
    pub(crate) fn new(device: &wgpu::Device, s: &Settings) -> Self {
        let (tiles_x, tiles_y) = (s.width.div_ceil(8), s.height.div_ceil(8));
        let pixels = u64::from(s.width) * u64::from(s.height);
        let storage = |label, size, usage| gpu::storage_buffer(device, label, size, usage);
        let none = wgpu::BufferUsages::empty();
        let pyramid = Pyramid::new(device, s.width, s.height);
        ReflectionsStage {
            nearest: storage("deep-gbuffer.reflections.nearest", pyramid.layout().bytes(), none),
            pyramid,
            uniform: gpu::uniform_buffer_for::<ReflectionsUniform>(
                device,
                "deep-gbuffer.reflections",
            ),
            tiles: PointList::new(
                device,
                "deep-gbuffer.reflections.tiles",
                u64::from(tiles_x * tiles_y),
            ),
            output: storage("deep-gbuffer.reflections.output", pixels * 16, none),
            followed: storage("deep-gbuffer.reflections.followed", pixels * 8 + 4, none),
            hidden_args: storage(
                "deep-gbuffer.reflections.hidden_args",
                16,
                wgpu::BufferUsages::INDIRECT,
            ),
            no_environment: storage("deep-gbuffer.reflections.no_environment", 16, none),
            tiles_x,
            tiles_y,
        }
    }

    /// Writes the frame's constants for `plan` (whether it draws layer 1 and the shadow maps);
    /// `environment`: the map's size (`None`: the scene's ambient sky).
    pub(crate) fn prepare(
        &self,
        queue: &wgpu::Queue,
        s: &Settings,
        scene: &SceneBuffers,
        plan: &Plan,
        environment: Option<(u32, u32)>,
    ) {
        let pcf = if plan.runs(Effect::Shadows) { s.shadows.pcf } else { 0 };
        let uniform = ReflectionsUniform::new(
            &s.reflections,
            (s.width, s.height),
            self.pyramid.layout(),
            plan.layers == 2,
            scene.info().ambient.to_array(),
            environment,
        )
        .with_lights(scene.info().lights.len() as u32, pcf)
        .with_bounds(scene.info().bounds);
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }

    /// The reflected radiance and confidence.
    pub(crate) fn output(&self) -> &wgpu::Buffer {
        &self.output
    }
}

impl Stage for ReflectionsStage {
    fn record(&self, id: &PassId, ctx: &FrameContext<'_>, rec: &mut Recorder<'_>) {
        debug_assert_eq!(*id, PassId::Reflections);
        // Rays the screen cannot place follow the shadow maps, where there are some.
        let follow = ctx.shadows.is_some() && ctx.settings.reflections.shadow_maps;
        self.tiles.clear(rec.encoder());
        rec.encoder().clear_buffer(&self.output, 0, None);
        if follow {
            rec.encoder().clear_buffer(&self.followed, 0, Some(4));
        }
        let mut pass = rec.pass(id);
        self.pyramid.record(ctx, &mut pass, PyramidKind::Nearest, ctx.gbuffer[0], &self.nearest);
        let mut entries = vec![
            (slot::FRAME, ctx.frame),
            (slot::PARAMS, &self.uniform),
            (slot::GBUFFER, ctx.gbuffer[0]),
            (slot::GBUFFER1, ctx.gbuffer[1]),
            (slot::LIGHTS, ctx.scene.light_buffer()),
            (slot::LIST, &self.tiles.list),
            (slot::LIST_ARGS, &self.tiles.args),
            (slot::REFLECTIONS, &self.output),
            (slot::ENVIRONMENT_MAP, ctx.environment.unwrap_or(&self.no_environment)),
            (slot::NEAREST, &self.nearest),
        ];
        // A hit surface is shaded as the composite shades it, with the terms the frame has, and
        // lit towards the point its ray left.
        let mut defines = ctx.settings.precision.defines();
        if let Some(s) = &ctx.shadows {
            defines.push("SHADOWS");
            entries.extend([
                (slot::FACES, s.faces),
                (slot::LIGHT_FACES, s.light_faces),
                (slot::ATLAS, s.atlas),
            ]);
        }
        if follow {
            defines.push("FOLLOW");
            entries.extend(super::surface_entries!(slot, ctx.scene));
            entries
                .extend([(slot::FOLLOWED, &self.followed), (slot::HIDDEN_ARGS, &self.hidden_args)]);
        }
        for (define, s, buffer) in
            [("AO", slot::AV, ctx.av), ("RADIOSITY", slot::IRRADIANCE, ctx.irradiance)]
        {
            if let Some(buffer) = buffer {
                defines.push(define);
                entries.push((s, buffer));
            }
        }
        // The surface code's texture switch exists with the followed rays' kernel only.
        let textures = [super::textures_constant(ctx.scene)];
        let constants: &[(&str, f64)] = if follow { &textures } else { &[] };
        let get = |entry| ctx.pipelines.get(ctx.device, "reflections", entry, &defines, constants);
        let groups = gpu::dispatch_size((self.tiles_x * self.tiles_y).div_ceil(64));
        get("reflections_classify").dispatch(ctx.device, &mut pass, &entries, groups);
        get("reflections_args").dispatch(ctx.device, &mut pass, &entries, (1, 1));
        get("reflections_march").dispatch_indirect(
            ctx.device,
            &mut pass,
            &entries,
            &self.tiles.args,
            0,
        );
        if follow {
            get("reflections_hidden_args").dispatch(ctx.device, &mut pass, &entries, (1, 1));
            let args = &self.hidden_args;
            get("reflections_hidden").dispatch_indirect(ctx.device, &mut pass, &entries, args, 0);
        }
    }
}
