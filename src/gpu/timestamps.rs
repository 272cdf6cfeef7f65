//! GPU timestamps around named passes (`raster.layer0`, `resolve`, ...).

/// The GPU time of one named pass.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PassTiming {
    /// Stable pass name.
    pub name: String,
    /// Milliseconds between the pass's first and last timestamp.
    pub ms: f64,
    /// Bytes of the storage buffers the pass binds read-only (0 where not counted: see
    /// [`PassTraffic`](super::PassTraffic)).
    pub read_bytes: u64,
    /// Bytes of the storage buffers the pass binds read-write.
    pub written_bytes: u64,
}

/// A query set with room for `capacity` passes, and the names written this frame.
pub struct Timestamps {
    query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    staging: wgpu::Buffer,
    capacity: u32,
    names: Vec<String>,
    period_ns: f32,
}

impl Timestamps {
    /// `None` when the device has no `TIMESTAMP_QUERY`.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, capacity: u32) -> Option<Timestamps> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let count = capacity * 2;
        let size = u64::from(count) * 8;
        Some(Timestamps {
            query_set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("deep-gbuffer.timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("deep-gbuffer.timestamps.resolve"),
                size,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            staging: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("deep-gbuffer.timestamps.staging"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            capacity,
            names: Vec::new(),
            period_ns: queue.get_timestamp_period(),
        })
    }

    /// Forgets the previous frame's passes.
    pub fn reset(&mut self) {
        self.names.clear();
    }

    fn slot(&mut self, name: &str) -> Option<u32> {
        let i = self.names.len() as u32;
        if i >= self.capacity {
            return None;
        }
        self.names.push(name.to_string());
        Some(i)
    }

    /// Timestamp writes for a compute pass named `name` (`None` once the set is full).
    pub fn pass(&mut self, name: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let i = self.slot(name)?;
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }

    /// Timestamp writes for a render pass named `name` (`None` once the set is full).
    pub fn render_pass(&mut self, name: &str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let i = self.slot(name)?;
        Some(wgpu::RenderPassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }

    /// Records the copy of this frame's timestamps to the staging buffer.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let n = self.names.len() as u32 * 2;
        if n == 0 {
            return;
        }
        encoder.resolve_query_set(&self.query_set, 0..n, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.staging, 0, u64::from(n) * 8);
    }

    /// Reads the milliseconds of each pass of the last submitted frame, in order (waits for the
    /// GPU).
    pub fn read_each(&self, device: &wgpu::Device) -> crate::Result<Vec<(String, f64)>> {
        if self.names.is_empty() {
            return Ok(Vec::new());
        }
        let bytes = super::map_read(device, &self.staging)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        Ok(self
            .names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let (a, b) = (ticks[2 * i], ticks[2 * i + 1]);
                (name.clone(), b.saturating_sub(a) as f64 * f64::from(self.period_ns) / 1e6)
            })
            .collect())
    }

    /// Reads the timings of the last submitted frame (waits for the GPU). Passes that share a
    /// name are added up.
    pub fn read(&self, device: &wgpu::Device) -> crate::Result<Vec<PassTiming>> {
        let mut out: Vec<PassTiming> = Vec::new();
        for (name, ms) in self.read_each(device)? {
            match out.iter_mut().find(|t| t.name == name) {
                Some(t) => t.ms += ms,
                None => out.push(PassTiming { name, ms, read_bytes: 0, written_bytes: 0 }),
            }
        }
        Ok(out)
    }
}
