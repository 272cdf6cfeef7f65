//! deep-gbuffer: two-layer deep G-buffers by compute software rasterization on wgpu.
//!
//! Both layers are rasterized in compute shaders into visibility buffers (layer 0: a 64-bit
//! `atomicMin` of `(view depth << 32) | triangle id`; layer 1: the nearest surface at least Δz
//! behind layer 0), then resolved into G-buffer attributes. The [`Renderer`] borrows the
//! caller's device and records into the caller's command encoder.
//!
//! ```no_run
//! use deep_gbuffer::{gpu::{Gpu, GpuOptions}, Renderer, Scene, SceneBuffers, Settings};
//! # fn main() -> deep_gbuffer::Result<()> {
//! let gpu = Gpu::new(&GpuOptions::default())?;
//! let scene = Scene::from_spec("builtin:cornell")?;
//! let buffers = SceneBuffers::upload(&gpu.device, &scene)?;
//! let mut renderer = Renderer::new(&gpu.device, &gpu.queue, Settings::with_size(320, 240))?;
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! renderer.encode(&gpu.device, &gpu.queue, &mut encoder, &buffers, &scene.camera_or_default())?;
//! gpu.queue.submit([encoder.finish()]);
//! let layer0 = renderer.read_gbuffer(&gpu.device, &gpu.queue, 0)?;
//! # Ok(()) }
//! ```

pub mod cpu;
mod error;
pub mod gbuffer;
pub mod gpu;
pub mod output;
pub mod passes;
pub mod plan;
mod renderer;
pub mod scene;
pub mod settings;

pub use error::{Error, Result};
pub use gbuffer::{GBufferLayer, GSample};
pub use plan::{Effects, Plan};
pub use renderer::{Diagnostics, Renderer};
pub use scene::upload::{GpuMaterial, ImportedBuffers, SceneBuffers};
pub use scene::{Camera, Projection, Scene, SceneInfo};
pub use settings::{
    AoSettings, AtomicPath, Layer1Variant, Precision, RadiositySettings, ReflectionSettings,
    Settings, ShadowSettings,
};
