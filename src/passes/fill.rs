//! `wgsl/fill.wgsl`: fills u32 buffers with a value (empties visibility buffers), or copies
//! them.

use crate::frame::FillParams;
use crate::gpu::{self, Pipelines, slots::fill as slot};

/// A fill of every buffer of one size with one value: the uniform that says so.
pub(crate) struct Fill {
    uniform: wgpu::Buffer,
    count: u32,
}

impl Fill {
    /// The fill of buffers of `bytes` bytes with `value`.
    pub(crate) fn new(device: &wgpu::Device, bytes: u64, value: u32) -> Self {
        let count = (bytes / 4) as u32;
        let uniform = gpu::uniform_buffer(
            device,
            "deep-gbuffer.fill.params",
            bytemuck::bytes_of(&FillParams { value, count, _pad: [0; 2] }),
        );
        Fill { uniform, count }
    }

    /// The bytes the fill covers (the `bytes` it was made for, in whole words).
    pub(crate) fn bytes(&self) -> u64 {
        u64::from(self.count) * 4
    }

    /// Records the fill of `buffer` (of the size this fill was made for).
    pub(crate) fn record(
        &self,
        device: &wgpu::Device,
        pipelines: &Pipelines,
        pass: &mut wgpu::ComputePass<'_>,
        buffer: &wgpu::Buffer,
    ) {
        debug_assert_eq!(buffer.size() / 4, u64::from(self.count), "a fill of another size");
        let pipeline = pipelines.get(device, "fill", "fill", &[], &[]);
        let entries = [(slot::PARAMS, &self.uniform), (slot::DATA, buffer)];
        pipeline.dispatch(device, pass, &entries, gpu::dispatch_size(self.count.div_ceil(256)));
    }

    /// Records the copy of this fill's words from `source` into `buffer` (the value is unused).
    pub(crate) fn record_copy(
        &self,
        device: &wgpu::Device,
        pipelines: &Pipelines,
        pass: &mut wgpu::ComputePass<'_>,
        source: &wgpu::Buffer,
        buffer: &wgpu::Buffer,
    ) {
        self.record_from(device, pipelines, pass, "copy", [source, source], buffer);
    }

    /// Records `buffer = 2 source - earlier` over this fill's words, as f32s (the value is
    /// unused).
    pub(crate) fn record_extrapolate(
        &self,
        device: &wgpu::Device,
        pipelines: &Pipelines,
        pass: &mut wgpu::ComputePass<'_>,
        [source, earlier]: [&wgpu::Buffer; 2],
        buffer: &wgpu::Buffer,
    ) {
        self.record_from(device, pipelines, pass, "extrapolate", [source, earlier], buffer);
    }

    fn record_from(
        &self,
        device: &wgpu::Device,
        pipelines: &Pipelines,
        pass: &mut wgpu::ComputePass<'_>,
        entry: &'static str,
        [source, earlier]: [&wgpu::Buffer; 2],
        buffer: &wgpu::Buffer,
    ) {
        let words = u64::from(self.count);
        debug_assert!(source.size() / 4 >= words && earlier.size() / 4 >= words, "short input");
        debug_assert!(buffer.size() / 4 >= words, "a short output");
        let pipeline = pipelines.get(device, "fill", entry, &[], &[]);
        let entries = [
            (slot::PARAMS, &self.uniform),
            (slot::DATA, buffer),
            (slot::SOURCE, source),
            (slot::EARLIER, earlier),
        ];
        pipeline.dispatch(device, pass, &entries, gpu::dispatch_size(self.count.div_ceil(256)));
    }
}
