//! `wgsl/reflections.wgsl`: screen-space reflections against both layers, in reflective tiles
//! only.

use bytemuck::{Pod, Zeroable};

use crate::gpu;
use crate::settings::Precision;

/// Mirrors `struct Reflections` in `wgsl/reflections.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct ReflectionsUniform {
    /// Environment (sky) radiance a missed ray sees.
    pub sky: [f32; 3],
    /// How far a ray is marched, in scene units.
    pub max_distance: f32,
    /// How far behind a surface a ray may pass and still hit it, in scene units.
    pub thickness: f32,
    /// 8x8 tiles across.
    pub tiles_x: u32,
    /// 8x8 tiles down.
    pub tiles_y: u32,
    /// Environment map width in texels (0: the constant `sky`).
    pub env_width: u32,
    /// Environment map height in texels.
    pub env_height: u32,
    /// 1: the layer-0 radiance already includes emission (the radiosity pass's B).
    pub with_emission: u32,
    /// Padding.
    pub _pad: [u32; 2],
}

/// The inputs and outputs of the reflection passes.
pub struct ReflectionTargets<'a> {
    /// Frame constants.
    pub frame: &'a wgpu::Buffer,
    /// Layer-0 G-buffer.
    pub gbuffer0: &'a wgpu::Buffer,
    /// Layer-1 visibility buffer (its depth words).
    pub vis1: &'a wgpu::Buffer,
    /// Outgoing radiance of both layers (B when radiosity runs, else direct).
    pub radiance: [&'a wgpu::Buffer; 2],
    /// The environment map's texels (any buffer of at least 16 bytes without one).
    pub environment: &'a wgpu::Buffer,
    /// Tile list (count, then tile indices).
    pub tiles: &'a wgpu::Buffer,
    /// Indirect arguments (INDIRECT usage).
    pub args: &'a wgpu::Buffer,
    /// Reflected radiance (rgb) and confidence (a) per pixel.
    pub output: &'a wgpu::Buffer,
}

/// The reflection kernels.
pub struct ReflectionsPass {
    classify: wgpu::ComputePipeline,
    args: wgpu::ComputePipeline,
    march: wgpu::ComputePipeline,
}

impl ReflectionsPass {
    /// Builds the pipelines for `precision` G-buffers.
    pub fn new(device: &wgpu::Device, precision: Precision) -> Self {
        let defines = &precision.defines()[..];
        ReflectionsPass {
            classify: gpu::compute_pipeline(device, "reflections", "reflections_classify", defines),
            args: gpu::compute_pipeline(device, "reflections", "reflections_args", defines),
            march: gpu::compute_pipeline(device, "reflections", "reflections_march", defines),
        }
    }

    /// Records classify, args and march into `pass` (the tile list must be zeroed before).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        uniform: &ReflectionsUniform,
        t: &ReflectionTargets<'_>,
    ) {
        let params =
            gpu::uniform_buffer(device, "deep-gbuffer.reflections", bytemuck::bytes_of(uniform));
        let classify = gpu::bind_group(
            device,
            "deep-gbuffer.reflections.classify",
            &self.classify,
            &[(0, t.frame), (1, &params), (2, t.gbuffer0), (6, t.tiles)],
        );
        pass.set_pipeline(&self.classify);
        pass.set_bind_group(0, &classify, &[]);
        let (x, y) = gpu::dispatch_size((uniform.tiles_x * uniform.tiles_y).div_ceil(64));
        pass.dispatch_workgroups(x, y, 1);
        let args = gpu::bind_group(
            device,
            "deep-gbuffer.reflections.args",
            &self.args,
            &[(6, t.tiles), (7, t.args)],
        );
        pass.set_pipeline(&self.args);
        pass.set_bind_group(0, &args, &[]);
        pass.dispatch_workgroups(1, 1, 1);
        let entries = [
            (0, t.frame),
            (1, &params),
            (2, t.gbuffer0),
            (3, t.vis1),
            (4, t.radiance[0]),
            (5, t.radiance[1]),
            (6, t.tiles),
            (8, t.output),
            (9, t.environment),
        ];
        let march = gpu::bind_group(device, "deep-gbuffer.reflections", &self.march, &entries);
        pass.set_pipeline(&self.march);
        pass.set_bind_group(0, &march, &[]);
        pass.dispatch_workgroups_indirect(t.args, 0);
    }
}
