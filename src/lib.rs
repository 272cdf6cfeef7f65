//! deep-gbuffer: two-layer deep G-buffers by compute software rasterization on wgpu, and global
//! illumination from them.
//!
//! Both layers are rasterized in compute shaders into visibility buffers (layer 0: a 64-bit
//! `atomicMin` of `(view depth << 32) | triangle id`; layer 1: the nearest surface at least Δz
//! behind layer 0), then resolved into G-buffer attributes, from which compute kernels derive
//! `DIRECT + AV * AMBIENT + RADIOSITY + REFLECTIONS`, running only the passes the scene calls for
//! (the [`Plan`]). The [`Renderer`] borrows the caller's device and records into the caller's
//! command encoder.
//!
//! ```no_run
//! use deep_gbuffer::{gpu::{Gpu, GpuOptions}, Renderer, Scene, SceneBuffers, Settings};
//! # fn main() -> deep_gbuffer::Result<()> {
//! // A host engine opens its own device with `Renderer::requirements()`; this helper does too.
//! let gpu = Gpu::new(&GpuOptions::default(), &Renderer::requirements())?;
//! let scene = Scene::from_spec("builtin:cornell")?;
//! let buffers = SceneBuffers::upload(&gpu.device, &scene)?;
//! let mut renderer = Renderer::new(&gpu.device, &gpu.queue, Settings::with_size(320, 240))?;
//! // The host's own target: the composite lands here, vec4<f32> per pixel.
//! let target = gpu.device.create_buffer(&wgpu::BufferDescriptor {
//!     label: Some("host.target"),
//!     size: 320 * 240 * 16,
//!     usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
//!     mapped_at_creation: false,
//! });
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! // ... the host's passes before ...
//! renderer.encode_to(&gpu.device, &gpu.queue, &mut encoder, &buffers, &scene.camera_or_default(), &target)?;
//! // ... the host's passes after, reading `target` or `renderer.gbuffer_buffer(0)` ...
//! gpu.queue.submit([encoder.finish()]);
//! let layer0 = renderer.read_gbuffer(&gpu.device, &gpu.queue, 0)?;
//! # Ok(()) }
//! ```

/// The README's code runs as a test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod cpu;
pub mod environment;
mod error;
mod files;
pub mod frame;
pub mod gbuffer;
pub mod gpu;
pub mod output;
mod passes;
pub mod plan;
mod renderer;
pub mod scene;
pub mod settings;
#[cfg(feature = "sweep")]
pub mod sweep;
#[doc(hidden)]
pub mod testing;
#[cfg(feature = "truth")]
pub mod truth;

/// The vector and matrix types of the public API.
pub use glam;
/// The wgpu this crate is built on (version 30): a host shares its device and buffers with the
/// renderer, so it uses this one.
pub use wgpu;

pub use environment::Environment;
pub use error::{Error, Result};
pub use gbuffer::{GBufferLayer, GSample};
pub use passes::offscreen::OffscreenBuffers;
pub use passes::radiosity::RadiosityBuffers;
pub use plan::{Effect, PassId, Plan, Reason};
pub use renderer::{Diagnostics, Renderer, Terms};
pub use scene::upload::{GpuMaterial, GpuTextureSlot, ImportedBuffers, SceneBuffers};
pub use scene::{
    AlphaMode, Camera, Filter, Lens, Material, Projection, Scene, SceneInfo, TextureRef, Wrap,
};
pub use settings::{
    AoEstimator, AoSettings, AtomicPath, Boost, DofSettings, Effects, Layer1Variant,
    MotionBlurSettings, Normalization, PositionEncoding, Precision, Preset, RadiosityEstimator,
    RadiositySettings, RasterWork, ReflectionSettings, Settings, ShadowSettings,
    TransparencySettings,
};
