//! Settings of a [`Renderer`](crate::Renderer).

use crate::gpu::frame::MAX_IMAGE_SIDE;
use crate::{Error, Result};

/// How layer 1 (the nearest surface at least Δz behind layer 0) is rasterized.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum, serde::Serialize)]
pub enum Layer1Variant {
    /// Exact: a second raster pass against this frame's final layer 0.
    #[default]
    TwoPass,
    /// One pass for both layers, layer 1 against the previous frame's layer 0 at the same pixel.
    Previous,
    /// One pass, layer 1 against the previous frame's layer 0 at the fragment's reprojected
    /// position (as in the paper).
    Reproject,
}

/// How the G-buffer stores its attributes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum, serde::Serialize)]
pub enum Precision {
    /// f32 everything: 64 bytes per pixel per layer.
    #[default]
    Full,
    /// Octahedral 16-bit normals, 8-bit colours, 16-bit floats: 32 bytes per pixel per layer.
    /// Depth stays f32.
    Packed,
}

/// Which atomics the rasterizer uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum, serde::Serialize)]
pub enum AtomicPath {
    /// 64-bit atomics when the device has them, else 32-bit.
    #[default]
    Auto,
    /// One 64-bit `atomicMin` per fragment (needs `SHADER_INT64_ATOMIC_MIN_MAX`).
    Int64,
    /// Two passes of 32-bit atomics (depth, then id); runs everywhere.
    Int32,
}

/// Settings of a [`Renderer`](crate::Renderer).
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// 1 or 2 G-buffer layers.
    pub layers: u32,
    /// Minimum separation Δz of layer 1 behind layer 0, in scene units (0: second-nearest).
    pub dz: f32,
    /// Layer-1 variant.
    pub layer1: Layer1Variant,
    /// G-buffer precision.
    pub precision: Precision,
    /// Atomic path.
    pub atomics: AtomicPath,
    /// Record GPU timestamps per pass (when the device has `TIMESTAMP_QUERY`).
    pub timings: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            width: 640,
            height: 480,
            layers: 2,
            dz: 0.05,
            layer1: Layer1Variant::TwoPass,
            precision: Precision::Full,
            atomics: AtomicPath::Auto,
            timings: true,
        }
    }
}

impl Settings {
    /// Settings for a `width` x `height` image, the rest default.
    pub fn with_size(width: u32, height: u32) -> Self {
        Settings { width, height, ..Settings::default() }
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::setting(
                "size",
                format!("{}x{} has no pixels", self.width, self.height),
            ));
        }
        if self.width > MAX_IMAGE_SIDE || self.height > MAX_IMAGE_SIDE {
            return Err(Error::setting(
                "size",
                format!("{}x{} exceeds {MAX_IMAGE_SIDE} pixels on a side", self.width, self.height),
            ));
        }
        if !(1..=2).contains(&self.layers) {
            return Err(Error::setting("layers", format!("{} (must be 1 or 2)", self.layers)));
        }
        if !(self.dz >= 0.0 && self.dz.is_finite()) {
            return Err(Error::setting("dz", format!("{} (must be finite and >= 0)", self.dz)));
        }
        Ok(())
    }
}
