//! Writing images: G-buffer layers as PNG (to look at) and EXR (raw values), and a simply
//! shaded preview of layer 0.

use std::path::Path;

use glam::Vec3;

pub use crate::files::{check_writable, write_bytes, write_replacing};
use crate::gbuffer::GBufferLayer;
use crate::{Error, Result};

/// The 8-bit sRGB encoding of a linear value (clamped to [0, 1]; NaN and infinities are 0).
pub fn srgb8(c: f32) -> u8 {
    let c = if c.is_finite() { c.clamp(0.0, 1.0) } else { 0.0 };
    let s = if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Writes an 8-bit RGB PNG from linear colours (sRGB encoded on the way).
pub fn write_png_linear(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<()> {
    let bytes: Vec<u8> = pixels.iter().flat_map(|c| [srgb8(c.x), srgb8(c.y), srgb8(c.z)]).collect();
    write_png_raw(path, width, height, bytes)
}

/// Writes an 8-bit RGB PNG from values already in [0, 1] display space (no sRGB curve).
pub fn write_png_display(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<()> {
    let q = |c: f32| (if c.is_finite() { c.clamp(0.0, 1.0) } else { 0.0 } * 255.0 + 0.5) as u8;
    let bytes: Vec<u8> = pixels.iter().flat_map(|c| [q(c.x), q(c.y), q(c.z)]).collect();
    write_png_raw(path, width, height, bytes)
}

fn write_png_raw(path: &Path, width: u32, height: u32, bytes: Vec<u8>) -> Result<()> {
    let fail = |message: String| Error::ImageWrite { path: path.into(), message };
    let image = image::RgbImage::from_raw(width, height, bytes)
        .ok_or_else(|| fail(format!("{width}x{height} needs {} bytes", 3 * width * height)))?;
    write_replacing(path, |tmp| {
        image.save_with_format(tmp, image::ImageFormat::Png).map_err(|e| fail(e.to_string()))
    })
}

/// Writes a 32-bit float RGB EXR.
pub fn write_exr(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<()> {
    let w = width as usize;
    if pixels.len() < w * height as usize {
        return Err(Error::ImageWrite {
            path: path.into(),
            message: format!(
                "{width}x{height} needs {} pixels, {} given",
                w * height as usize,
                pixels.len()
            ),
        });
    }
    write_replacing(path, |tmp| {
        exr::prelude::write_rgb_file(tmp, w, height as usize, |x, y| {
            let c = pixels[y * w + x];
            (c.x, c.y, c.z)
        })
        .map_err(|e| Error::ImageWrite { path: path.into(), message: e.to_string() })
    })
}

/// Depth shown as brightness: near is white, far dark, no surface black (range over both
/// layers when given together, so they compare).
pub fn depth_display(layers: &[&GBufferLayer]) -> Vec<Vec<Vec3>> {
    let depths = layers.iter().flat_map(|l| l.samples.iter().map(|s| s.depth)).filter(|d| *d > 0.0);
    let (lo, hi) = depths.fold((f32::MAX, 0.0f32), |(lo, hi), d| (lo.min(d), hi.max(d)));
    let range = (hi - lo).max(1e-6);
    layers
        .iter()
        .map(|l| {
            l.samples
                .iter()
                .map(|s| {
                    if s.depth > 0.0 {
                        Vec3::splat(1.0 - 0.85 * (s.depth - lo) / range)
                    } else {
                        Vec3::ZERO
                    }
                })
                .collect()
        })
        .collect()
}

/// Writes `layer{i}_depth`, `layer{i}_normal` and `layer{i}_basecolor` as PNG and EXR into `dir`,
/// and every attribute of every layer, losslessly, into `gbuffer.exr`
/// ([`GBufferLayer::write_exr`]; [`GBufferLayer::read_exr`] reads it back).
pub fn write_layers(dir: &Path, layers: &[GBufferLayer]) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    GBufferLayer::write_exr(&dir.join("gbuffer.exr"), layers)?;
    let refs: Vec<&GBufferLayer> = layers.iter().collect();
    let depth_png = depth_display(&refs);
    for (i, l) in layers.iter().enumerate() {
        let (w, h) = (l.width, l.height);
        let depth: Vec<Vec3> = l.samples.iter().map(|s| Vec3::splat(s.depth)).collect();
        let normal: Vec<Vec3> = l.samples.iter().map(|s| s.normal).collect();
        let normal_png: Vec<Vec3> = l
            .samples
            .iter()
            .map(|s| if s.depth > 0.0 { s.normal * 0.5 + 0.5 } else { Vec3::ZERO })
            .collect();
        let base: Vec<Vec3> = l.samples.iter().map(|s| s.base_color).collect();
        write_png_display(&dir.join(format!("layer{i}_depth.png")), w, h, &depth_png[i])?;
        write_exr(&dir.join(format!("layer{i}_depth.exr")), w, h, &depth)?;
        write_png_display(&dir.join(format!("layer{i}_normal.png")), w, h, &normal_png)?;
        write_exr(&dir.join(format!("layer{i}_normal.exr")), w, h, &normal)?;
        write_png_linear(&dir.join(format!("layer{i}_basecolor.png")), w, h, &base)?;
        write_exr(&dir.join(format!("layer{i}_basecolor.exr")), w, h, &base)?;
    }
    Ok(())
}

/// The tone map of `--out`: exposure, then the ACES filmic curve fitted by Narkowicz (2015),
/// per channel, to [0, 1] linear (sRGB encoding follows when written).
pub fn tonemap(hdr: &[Vec3], exposure: f32) -> Vec<Vec3> {
    hdr.iter()
        .map(|c| {
            let x = (*c * exposure).max(Vec3::ZERO);
            ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(Vec3::ZERO, Vec3::ONE)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("deep-gbuffer-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// A write that fails half way leaves the file it aimed at as it was, and nothing beside it.
    #[test]
    fn a_failed_write_leaves_the_old_file() {
        let dir = folder("failed-write");
        let path = dir.join("image.exr");
        std::fs::write(&path, b"the old image").unwrap();
        let result = write_replacing(&path, |tmp| {
            std::fs::write(tmp, b"half an ima").unwrap();
            Err(Error::ImageWrite { path: path.clone(), message: "disk full".into() })
        });
        assert!(result.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"the old image");
        assert_eq!(entries(&dir), ["image.exr"]);
        // A complete write replaces it.
        write_exr(&path, 2, 1, &[Vec3::ONE, Vec3::ZERO]).unwrap();
        assert_ne!(std::fs::read(&path).unwrap(), b"the old image");
        assert_eq!(entries(&dir), ["image.exr"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// What is not a regular writable file is refused before anything is written.
    #[test]
    fn only_regular_writable_files_are_replaced() {
        use std::os::unix::fs::PermissionsExt;
        let dir = folder("refused-write");
        let read_only = dir.join("kept.png");
        std::fs::write(&read_only, b"kept").unwrap();
        std::fs::set_permissions(&read_only, std::fs::Permissions::from_mode(0o444)).unwrap();
        let folder_path = dir.join("a-folder.exr");
        std::fs::create_dir(&folder_path).unwrap();
        let link = dir.join("link.png");
        std::os::unix::fs::symlink(&read_only, &link).unwrap();
        let socket = dir.join("socket.exr");
        let _listener = std::os::unix::net::UnixListener::bind(&socket).unwrap();
        let pixels = [Vec3::ONE];
        for (path, why) in [
            (&read_only, "read-only"),
            (&folder_path, "not a regular file"),
            (&link, "not a regular file"),
            (&socket, "not a regular file"),
        ] {
            let png = write_png_linear(path, 1, 1, &pixels).unwrap_err().to_string();
            let exr = write_exr(path, 1, 1, &pixels).unwrap_err().to_string();
            assert!(png.contains(why) && exr.contains(why), "{}: {png} / {exr}", path.display());
        }
        assert_eq!(std::fs::read(&read_only).unwrap(), b"kept");
        assert!(folder_path.is_dir() && link.is_symlink() && socket.exists());
        assert_eq!(entries(&dir), ["a-folder.exr", "kept.png", "link.png", "socket.exr"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
