//! GPU helpers: device acquisition (for the command line and tests; the library itself only
//! borrows a device), shader loading, pipelines whose bindings are reflected from the shaders,
//! GPU timestamps and buffer read-back.

mod bandwidth;
mod pipeline;
pub(crate) mod preprocess;
mod timestamps;
pub(crate) mod traffic;

mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

use wgpu::util::DeviceExt;

use crate::{Error, Result};

pub use bandwidth::{Bandwidth, measure_bandwidth};
pub(crate) use pipeline::{Pipeline, Pipelines, Slot, slots};
pub use timestamps::PassTiming;
pub use timestamps::Timestamps;
pub use traffic::PassTraffic;

/// The WGSL text of `wgsl/<name>` with `defines`, includes expanded.
pub fn shader_source(name: &str, defines: &[&str]) -> String {
    let lookup = |n: &str| shaders::SOURCES.iter().find(|(k, _)| *k == n).map(|(_, v)| *v);
    let source = lookup(name).unwrap_or_else(|| panic!("wgsl/{name} is embedded by build.rs"));
    let declared = preprocess::declared_defines(source);
    assert!(
        defines.iter().all(|d| declared.contains(d)),
        "wgsl/{name} does not declare all of {defines:?}"
    );
    // build.rs has preprocessed and validated every kernel in every combination of defines.
    preprocess::preprocess(name, source, defines, &lookup).expect("validated by build.rs")
}

/// Runs `f` inside validation and out-of-memory error scopes, so a GPU error becomes
/// [`Error::Gpu`] naming `label` instead of reaching the device's uncaptured-error handler.
pub fn scoped<T>(device: &wgpu::Device, label: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let value = f();
    let errors = [pollster::block_on(memory.pop()), pollster::block_on(validation.pop())];
    let value = value?;
    match errors.into_iter().flatten().next() {
        Some(e) => Err(Error::Gpu {
            label: label.to_string(),
            message: e.to_string().lines().collect::<Vec<_>>().join(" "),
        }),
        None => Ok(value),
    }
}

/// Workgroup counts for `groups` one-dimensional workgroups, folded into y past the 65535 limit.
pub fn dispatch_size(groups: u32) -> (u32, u32) {
    let x = groups.clamp(1, 65535);
    (x, groups.div_ceil(x).max(1))
}

/// A uniform buffer holding `contents`.
pub fn uniform_buffer(device: &wgpu::Device, label: &str, contents: &[u8]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents,
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// A uniform buffer for one `T`, rewritten with `Queue::write_buffer`.
pub(crate) fn uniform_buffer_for<T>(device: &wgpu::Device, label: &str) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: std::mem::size_of::<T>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A storage buffer of `size` bytes.
pub fn storage_buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16).next_multiple_of(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST
            | extra,
        mapped_at_creation: false,
    })
}

/// A storage buffer holding `data` (at least 16 bytes, so empty arrays still bind).
pub fn storage_buffer_init(device: &wgpu::Device, label: &str, data: &[u8]) -> wgpu::Buffer {
    let mut bytes = data.to_vec();
    bytes.resize(data.len().max(16).next_multiple_of(4), 0);
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: &bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
    })
}

/// Copies `buffer` to the CPU (submits its own copy and waits).
pub fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u8>> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("deep-gbuffer.readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("deep-gbuffer.readback"),
    });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    queue.submit([encoder.finish()]);
    map_read(device, &staging)
}

/// Maps a MAP_READ buffer, waits, and returns its bytes.
pub fn map_read(device: &wgpu::Device, staging: &wgpu::Buffer) -> Result<Vec<u8>> {
    let failed = || Error::Readback(format!("{staging:?}"));
    let slice = staging.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|_| failed())?;
    rx.recv().map_err(|_| failed())?.map_err(|_| failed())?;
    let bytes = slice.get_mapped_range().map_err(|_| failed())?.to_vec();
    staging.unmap();
    Ok(bytes)
}

/// What a device must have and what it should have if the adapter offers it, for [`Gpu::new`]
/// ([`Renderer::requirements`](crate::Renderer::requirements) gives deep-gbuffer's).
#[derive(Clone, Debug, Default)]
pub struct Requirements {
    /// Features the device must have.
    pub features: wgpu::Features,
    /// Features requested where the adapter has them.
    pub optional_features: wgpu::Features,
    /// Among several adapters, those with all of these are preferred.
    pub preferred_features: wgpu::Features,
    /// Limits the device must have (storage buffer sizes are raised to the adapter's).
    pub limits: wgpu::Limits,
}

/// Which adapter to open, for [`Gpu::new`].
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Open the first adapter whose name contains this (case-insensitive); `None`: the best one
    /// (64-bit atomics first, then a real GPU before a software one). The environment variable
    /// `DEEP_GBUFFER_ADAPTER` sets it too.
    pub adapter: Option<String>,
}

/// An instance, adapter, device and queue: a convenience for the command line, tests and
/// benchmarks. A host engine opens its own device instead, with
/// [`Renderer::requirements`](crate::Renderer::requirements).
pub struct Gpu {
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

impl Gpu {
    /// Opens the best (or the named) adapter with the `requirements`' features and limits and
    /// every optional feature it has.
    pub fn new(options: &GpuOptions, requirements: &Requirements) -> Result<Gpu> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        if adapters.is_empty() {
            return Err(Error::NoAdapter(
                "no Vulkan, Metal, DX12 or GL adapter; on Debian install the software Vulkan driver with `apt-get install -y mesa-vulkan-drivers`".into(),
            ));
        }
        let wanted = options.adapter.clone().or_else(|| std::env::var("DEEP_GBUFFER_ADAPTER").ok());
        let adapter = match &wanted {
            Some(name) => {
                let lower = name.to_lowercase();
                let found =
                    adapters.iter().find(|a| a.get_info().name.to_lowercase().contains(&lower));
                found.cloned().ok_or_else(|| {
                    let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
                    Error::NoAdapter(format!(
                        "no adapter named like `{name}` (found: {})",
                        names.join(", ")
                    ))
                })?
            }
            None => adapters
                .iter()
                .max_by_key(|a| {
                    let f = a.features();
                    let info = a.get_info();
                    (
                        f.contains(requirements.preferred_features),
                        info.backend == wgpu::Backend::Vulkan
                            || info.backend == wgpu::Backend::Metal
                            || info.backend == wgpu::Backend::Dx12,
                        info.device_type != wgpu::DeviceType::Cpu,
                    )
                })
                .cloned()
                .expect("not empty"),
        };
        let available = adapter.features();
        let features = requirements.features | (available & requirements.optional_features);
        let limits = requirements.limits.clone().using_resolution(adapter.limits());
        let mut limits = limits;
        let adapter_limits = adapter.limits();
        limits.max_storage_buffer_binding_size = adapter_limits.max_storage_buffer_binding_size;
        limits.max_buffer_size = adapter_limits.max_buffer_size;
        limits.max_storage_buffers_per_shader_stage =
            adapter_limits.max_storage_buffers_per_shader_stage;
        if !limits.check_limits(&adapter_limits) || !available.contains(requirements.features) {
            return Err(Error::RequestDevice(format!(
                "adapter `{}` does not meet the required features {:?} and limits (at least {} storage buffers per stage)",
                adapter.get_info().name,
                requirements.features,
                requirements.limits.max_storage_buffers_per_shader_stage
            )));
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("deep-gbuffer"),
            required_features: features,
            required_limits: limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| Error::RequestDevice(e.to_string()))?;
        Ok(Gpu { adapter, device, queue })
    }

    /// One line describing the adapter: name, backend, driver.
    pub fn describe(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {} {})", i.name, i.backend, i.driver, i.driver_info)
    }
}

/// The machine's load average over 1, 5 and 15 minutes (`/proc/loadavg`), where the system
/// reports one: a timing taken on a busy machine is slower than the device allows, and a
/// software driver shares the CPUs with everything else.
pub fn load_average() -> Option<[f32; 3]> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut it = text.split_whitespace().map(|v| v.parse::<f32>().ok());
    Some([it.next()??, it.next()??, it.next()??])
}

/// [`load_average`] as one line ("load 1.52 1.40 1.38 (1, 5, 15 min)", or that it is unknown).
pub fn describe_load() -> String {
    match load_average() {
        Some([a, b, c]) => format!("load {a:.2} {b:.2} {c:.2} (1, 5, 15 min)"),
        None => "load unknown".into(),
    }
}
