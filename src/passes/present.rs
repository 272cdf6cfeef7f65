//! `wgsl/present.wgsl`: the HDR composite into a caller's storage texture.

use crate::gpu::{Pipelines, slots::present as slot};

/// The caller's texture last presented to, and its view (kept while the texture is the same,
/// so its bind group is too).
pub(crate) struct Present {
    target: Option<(wgpu::Texture, wgpu::TextureView)>,
}

impl Present {
    pub(crate) fn new() -> Self {
        Present { target: None }
    }

    /// Records the copy of `hdr` into `texture` (rgba16float or rgba32float, the frame's size).
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        pipelines: &Pipelines,
        encoder: &mut wgpu::CommandEncoder,
        frame: &wgpu::Buffer,
        hdr: &wgpu::Buffer,
        texture: &wgpu::Texture,
    ) {
        let size = (texture.width(), texture.height());
        if self.target.as_ref().is_none_or(|(t, _)| t != texture) {
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            self.target = Some((texture.clone(), view));
        }
        let (_, view) = self.target.as_ref().expect("set above");
        let f16 = texture.format() == wgpu::TextureFormat::Rgba16Float;
        let defines: &[&str] = if f16 { &["F16"] } else { &[] };
        let pipeline = pipelines.get(device, "present", "present_main", defines, &[]);
        let group = pipeline.bind_with_view(
            device,
            &[(slot::FRAME, frame), (slot::HDR, hdr)],
            (slot::OUTPUT, view),
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("deep-gbuffer.present"),
            timestamp_writes: None,
        });
        pipeline.dispatch_group(&mut pass, &group, (size.0.div_ceil(8), size.1.div_ceil(8)));
    }
}
