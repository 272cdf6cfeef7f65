//! GPU helpers: device acquisition (for the command line and tests; the library itself only
//! borrows a device), shader loading, GPU timestamps and buffer read-back.

pub mod frame;
pub mod preprocess;
pub mod timestamps;

mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

use wgpu::util::DeviceExt;

use crate::{Error, Result};

pub use frame::{FRAME_DIAGNOSTICS, FrameUniform};
pub use timestamps::{PassTiming, Timestamps};

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

/// Creates a compute pipeline for `entry` of `wgsl/<kernel>.wgsl` with `defines`, its bind group
/// layout derived from the bindings that entry uses.
pub fn compute_pipeline(
    device: &wgpu::Device,
    kernel: &str,
    entry: &str,
    defines: &[&str],
) -> wgpu::ComputePipeline {
    compute_pipeline_with(device, kernel, entry, defines, &[])
}

/// [`compute_pipeline`] with values for the shader's `override` constants.
pub fn compute_pipeline_with(
    device: &wgpu::Device,
    kernel: &str,
    entry: &str,
    defines: &[&str],
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    let label = format!("deep-gbuffer.{kernel}");
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(&label),
        source: wgpu::ShaderSource::Wgsl(shader_source(&format!("{kernel}.wgsl"), defines).into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(&format!("{label}.{entry}")),
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions { constants, ..Default::default() },
        cache: None,
    })
}

/// A bind group for group 0 of `pipeline` from `(binding, buffer)` pairs.
pub fn bind_group(
    device: &wgpu::Device,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    entries: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = entries
        .iter()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
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

/// Binds `entries` to `pipeline` and dispatches one 8x8 workgroup per 8x8 pixels of `size`
/// (every per-pixel kernel uses `@workgroup_size(8, 8)`).
pub fn dispatch_pixels(
    device: &wgpu::Device,
    pass: &mut wgpu::ComputePass<'_>,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    entries: &[(u32, &wgpu::Buffer)],
    size: (u32, u32),
) {
    let group = bind_group(device, label, pipeline, entries);
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &group, &[]);
    pass.dispatch_workgroups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
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

/// Which adapter to open, for [`Gpu::new`].
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Open the first adapter whose name contains this (case-insensitive); `None`: the best one
    /// (64-bit atomics first, then a real GPU before a software one). The environment variable
    /// `DEEP_GBUFFER_ADAPTER` sets it too.
    pub adapter: Option<String>,
}

/// An instance, adapter, device and queue opened for deep-gbuffer: a convenience for the command
/// line, tests and benchmarks. A host engine opens its own device instead, with
/// [`Renderer::required_features`](crate::Renderer::required_features) and
/// [`Renderer::required_limits`](crate::Renderer::required_limits).
pub struct Gpu {
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

impl Gpu {
    /// Opens the best (or the named) adapter with every optional feature deep-gbuffer can use.
    pub fn new(options: &GpuOptions) -> Result<Gpu> {
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
                        f.contains(crate::Renderer::int64_features()),
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
        let features = crate::Renderer::required_features()
            | (available & crate::Renderer::optional_features());
        let limits = crate::Renderer::required_limits().using_resolution(adapter.limits());
        let mut limits = limits;
        let adapter_limits = adapter.limits();
        limits.max_storage_buffer_binding_size = adapter_limits.max_storage_buffer_binding_size;
        limits.max_buffer_size = adapter_limits.max_buffer_size;
        limits.max_storage_buffers_per_shader_stage =
            adapter_limits.max_storage_buffers_per_shader_stage;
        if !limits.check_limits(&adapter_limits)
            || !available.contains(crate::Renderer::required_features())
        {
            return Err(Error::RequestDevice(format!(
                "adapter `{}` does not meet deep-gbuffer's required limits (at least {} storage buffers per stage)",
                adapter.get_info().name,
                crate::Renderer::required_limits().max_storage_buffers_per_shader_stage
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
