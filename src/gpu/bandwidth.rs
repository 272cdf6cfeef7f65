//! The device's memory bandwidth, measured (`wgsl/bandwidth.wgsl`): what a pass's byte floor
//! is computed from ([`PassTraffic`](super::PassTraffic)).

use super::{Pipelines, Timestamps, slots::bandwidth as slot, storage_buffer};
use crate::Result;

/// Bytes per second a compute kernel reads and writes on a device, the best of a few runs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Bandwidth {
    /// Reading each word of a buffer once.
    pub read_bytes_per_s: f64,
    /// Writing each word of a buffer once.
    pub write_bytes_per_s: f64,
}

impl Bandwidth {
    /// The milliseconds under which reading `read` bytes and writing `written` bytes cannot
    /// take at this bandwidth.
    pub fn floor_ms(&self, read: u64, written: u64) -> f64 {
        1e3 * (read as f64 / self.read_bytes_per_s + written as f64 / self.write_bytes_per_s)
    }
}

/// Workgroups of the probes (256 threads each, one contiguous block of the buffer each): enough
/// threads to fill a large GPU, few enough that each walks a long block (on llvmpipe, 2 cores:
/// 64 MiB read at 2.6-2.9 GB/s with 64 or 256 workgroups, 8-9 with 1024, 5-8 with 4096).
const GROUPS: u32 = 1024;
const RUNS: usize = 3;

/// Measures the bandwidth of `device` with a `bytes`-byte buffer (rounded to 16 bytes; it
/// should be well above the device's caches: 64 MiB serves a CPU driver and most GPUs), by GPU
/// timestamps; `None` when the device has no `TIMESTAMP_QUERY`.
pub fn measure_bandwidth(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    bytes: u64,
) -> Result<Option<Bandwidth>> {
    let Some(mut timestamps) = Timestamps::new(device, queue, (2 * RUNS) as u32) else {
        return Ok(None);
    };
    let bytes = bytes.max(16).next_multiple_of(16);
    let none = wgpu::BufferUsages::empty();
    let data = storage_buffer(device, "deep-gbuffer.bandwidth.data", bytes, none);
    let sums = storage_buffer(device, "deep-gbuffer.bandwidth.sums", u64::from(GROUPS) * 4, none);
    let pipelines = Pipelines::default();
    let write = pipelines.get(device, "bandwidth", "bandwidth_write", &[], &[]);
    let read = pipelines.get(device, "bandwidth", "bandwidth_read", &[], &[]);
    let entries = [(slot::WRITTEN, &data), (slot::SOURCE, &data), (slot::SUMS, &sums)];
    let mut encoder = device.create_command_encoder(&Default::default());
    for _ in 0..RUNS {
        for (name, pipeline) in [("write", &write), ("read", &read)] {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("deep-gbuffer.bandwidth"),
                timestamp_writes: timestamps.pass(name),
            });
            pipeline.dispatch(device, &mut pass, &entries, (GROUPS, 1));
        }
    }
    timestamps.resolve(&mut encoder);
    queue.submit([encoder.finish()]);
    // The passes of one name are added up: each is RUNS runs.
    let times = timestamps.read_each(device)?;
    let best = |name: &str| {
        times.iter().filter(|(n, _)| n == name).map(|(_, ms)| *ms).fold(f64::INFINITY, f64::min)
    };
    let per_s = |ms: f64| if ms > 0.0 && ms.is_finite() { bytes as f64 / (ms / 1e3) } else { 0.0 };
    Ok(Some(Bandwidth {
        read_bytes_per_s: per_s(best("read")),
        write_bytes_per_s: per_s(best("write")),
    }))
}
