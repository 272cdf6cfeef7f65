//! The environment a reflection ray sees when it leaves the screen: an equirectangular
//! (latitude-longitude) radiance map, read from an EXR file, sampled bilinearly.
//!
//! Direction `d` (world space, unit) maps to `u = 0.5 + atan2(d.x, -d.z) / 2pi` across (so the
//! centre column looks down -z and u wraps around) and `v = acos(d.y) / pi` down (row 0 is
//! straight up). `wgsl/reflections.wgsl` samples it the same way.

use std::path::Path;

use glam::Vec3;

use crate::{Error, Result};

/// An equirectangular radiance map (linear rgb, scene-referred).
#[derive(Clone, PartialEq)]
pub struct Environment {
    width: u32,
    height: u32,
    /// Row-major rgb with an unused fourth lane, as the GPU reads it.
    texels: Vec<[f32; 4]>,
}

impl std::fmt::Debug for Environment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Environment({}x{})", self.width, self.height)
    }
}

impl Environment {
    /// The largest side accepted (a 8192 x 4096 map is 512 MiB on the GPU).
    pub const MAX_SIDE: u32 = 8192;

    /// A map of `width` x `height` texels, row major from the top. Every value must be finite
    /// and non-negative.
    pub fn new(width: u32, height: u32, rgb: Vec<[f32; 3]>) -> Result<Environment> {
        Self::check_size(width, height).map_err(|m| Error::setting("environment", m))?;
        if rgb.len() as u64 != u64::from(width) * u64::from(height) {
            return Err(Error::setting(
                "environment",
                format!("{} texels for a {width}x{height} map", rgb.len()),
            ));
        }
        if let Some(i) = rgb.iter().position(|c| c.iter().any(|v| !(v.is_finite() && *v >= 0.0))) {
            return Err(Error::setting(
                "environment",
                format!(
                    "texel ({}, {}) is {:?} (radiance must be finite and >= 0)",
                    i as u32 % width,
                    i as u32 / width,
                    rgb[i]
                ),
            ));
        }
        let texels = rgb.into_iter().map(|[r, g, b]| [r, g, b, 0.0]).collect();
        Ok(Environment { width, height, texels })
    }

    fn check_size(width: u32, height: u32) -> std::result::Result<(), String> {
        if width == 0 || height == 0 || width > Self::MAX_SIDE || height > Self::MAX_SIDE {
            return Err(format!(
                "a {width}x{height} map (each side must be 1 to {})",
                Self::MAX_SIDE
            ));
        }
        Ok(())
    }

    /// Reads the first RGB(A) layer of an EXR file (alpha is ignored).
    pub fn load_exr(path: &Path) -> Result<Environment> {
        let read_error = |e: exr::error::Error| match e {
            exr::error::Error::Io(source) => Error::io(path, source),
            e => Error::ImageRead { path: path.into(), message: e.to_string() },
        };
        // Refuse an oversized image from its header, before anything is allocated for it.
        let meta = exr::meta::MetaData::read_from_file(path, false).map_err(read_error)?;
        if meta.headers.is_empty() {
            return Err(Error::ImageRead { path: path.into(), message: "no image layer".into() });
        }
        // Every part: the layer read below is the first with RGBA channels, not always the first.
        for header in meta.headers.iter() {
            let size = header.layer_size;
            let side = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
            Self::check_size(side(size.0), side(size.1)).map_err(|m| Error::ImageRead {
                path: path.into(),
                message: format!("{m}, refused"),
            })?;
        }
        let image = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |resolution, _| (resolution.width(), vec![[0.0f32; 3]; resolution.area()]),
            |(width, texels), position, (r, g, b, _a): (f32, f32, f32, f32)| {
                texels[position.y() * *width + position.x()] = [r, g, b];
            },
        )
        .map_err(read_error)?;
        let size = image.layer_data.size;
        let (_, texels) = image.layer_data.channel_data.pixels;
        Environment::new(size.0 as u32, size.1 as u32, texels)
            .map_err(|e| Error::ImageRead { path: path.into(), message: e.to_string() })
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texels as the GPU reads them (rgb and an unused lane, row major).
    pub fn texels(&self) -> &[[f32; 4]] {
        &self.texels
    }

    /// The radiance seen along world-space unit direction `d` (as `environment` in the WGSL).
    pub fn sample(&self, d: Vec3) -> Vec3 {
        let (w, h) = (self.width as i32, self.height as i32);
        let u = 0.5 + d.x.atan2(-d.z) / std::f32::consts::TAU;
        let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        let x = u * w as f32 - 0.5;
        let y = (v * h as f32 - 0.5).clamp(0.0, (h - 1) as f32);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let x0 = (x0 as i32).rem_euclid(w);
        let x1 = (x0 + 1) % w;
        let y0 = y0 as i32;
        let y1 = (y0 + 1).min(h - 1);
        let at = |x: i32, y: i32| Vec3::from_slice(&self.texels[(y * w + x) as usize][..3]);
        let top = at(x0, y0).lerp(at(x1, y0), fx);
        let bottom = at(x0, y1).lerp(at(x1, y1), fx);
        top.lerp(bottom, fy)
    }
}
