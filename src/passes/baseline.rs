//! `wgsl/baseline.wgsl`: the hardware-raster baseline the benchmarks compare the compute
//! rasterizer with (layer 0 only: depth test and triangle id, no second layer).

use crate::SceneBuffers;
use crate::gpu::{self, slots::baseline as slot};

/// A render pipeline and its targets.
pub struct BaselinePass {
    pipeline: wgpu::RenderPipeline,
    depth: wgpu::TextureView,
    ids: wgpu::Texture,
    ids_view: wgpu::TextureView,
    width: u32,
    height: u32,
}

impl BaselinePass {
    /// Builds the pipeline and a `width` x `height` depth and id target. `cull_back` culls
    /// back faces (as the compute rasterizer does for single-sided materials).
    pub fn new(device: &wgpu::Device, width: u32, height: u32, cull_back: bool) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("deep-gbuffer.baseline"),
            source: wgpu::ShaderSource::Wgsl(gpu::shader_source("baseline.wgsl", &[]).into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("deep-gbuffer.baseline"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                front_face: wgpu::FrontFace::Ccw,
                cull_mode: cull_back.then_some(wgpu::Face::Back),
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: wgpu::TextureFormat::R32Uint,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let texture = |label: &str, format| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let depth = texture("deep-gbuffer.baseline.depth", wgpu::TextureFormat::Depth32Float)
            .create_view(&Default::default());
        let ids = texture("deep-gbuffer.baseline.ids", wgpu::TextureFormat::R32Uint);
        let ids_view = ids.create_view(&Default::default());
        BaselinePass { pipeline, depth, ids, ids_view, width, height }
    }

    /// Records the draw; `timestamp_writes` times it.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &SceneBuffers,
        frame: &wgpu::Buffer,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let b = scene.buffers();
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("deep-gbuffer.baseline"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: slot::FRAME.binding,
                    resource: frame.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: slot::POSITIONS.binding,
                    resource: b.positions.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: slot::INDICES.binding,
                    resource: b.indices.as_entire_binding(),
                },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("deep-gbuffer.baseline"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.ids_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: f64::from(u32::MAX),
                        g: 0.0,
                        b: 0.0,
                        a: 0.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..scene.triangle_count() * 3, 0..1);
    }

    /// Reads the id target back (u32::MAX where nothing was drawn; waits for the GPU).
    pub fn read_ids(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> crate::Result<Vec<u32>> {
        let row = (self.width * 4).next_multiple_of(256);
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("deep-gbuffer.baseline.readback"),
            size: u64::from(row * self.height),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            self.ids.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: None,
                },
            },
            wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
        );
        queue.submit([encoder.finish()]);
        let bytes = gpu::map_read(device, &staging)?;
        Ok((0..self.height)
            .flat_map(|y| {
                let start = (y * row) as usize;
                bytemuck::pod_collect_to_vec::<u8, u32>(
                    &bytes[start..start + (self.width * 4) as usize],
                )
            })
            .collect())
    }
}
