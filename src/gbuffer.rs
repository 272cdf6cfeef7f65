//! The G-buffer and visibility buffer as the CPU reads them back, for both encodings. Mirrors
//! `wgsl/shared/gbuffer.wgsl` and `wgsl/shared/vis.wgsl`.

use glam::{Vec2, Vec3};

use crate::settings::Precision;

/// An empty visibility-buffer word (no surface).
pub const VIS_EMPTY: u64 = u64::MAX;

/// Bytes per pixel of a G-buffer layer.
pub fn bytes_per_pixel(precision: Precision) -> u64 {
    match precision {
        Precision::Full => 64,
        Precision::Packed => 32,
    }
}

/// Packs a visibility word: `(depth bits << 32) | triangle id`.
pub fn vis_pack(depth: f32, id: u32) -> u64 {
    (u64::from(depth.to_bits()) << 32) | u64::from(id)
}

/// The triangle id of a visibility word (`None` when empty).
pub fn vis_id(word: u64) -> Option<u32> {
    (word != VIS_EMPTY).then_some(word as u32)
}

/// The view depth of a visibility word (`None` when empty).
pub fn vis_depth(word: u64) -> Option<f32> {
    (word != VIS_EMPTY).then(|| f32::from_bits((word >> 32) as u32))
}

/// One G-buffer sample. Mirrors `struct GSample` in `wgsl/shared/gbuffer.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GSample {
    /// View depth (0: no surface).
    pub depth: f32,
    /// World-space unit normal facing the camera.
    pub normal: Vec3,
    /// Linear base colour.
    pub base_color: Vec3,
    /// Perceptual roughness.
    pub roughness: f32,
    /// Emitted radiance.
    pub emissive: Vec3,
    /// Metalness.
    pub metallic: f32,
    /// Screen motion in pixels (current position minus previous position).
    pub motion: Vec2,
    /// Mirror reflectivity.
    pub reflectivity: f32,
    /// The material's ambient occlusion (its occlusion texture; 1 without one): it multiplies
    /// the ambient term.
    pub occlusion: f32,
    /// Material id.
    pub material: u32,
}

impl Default for GSample {
    /// No surface: every attribute zero, the occlusion 1.
    fn default() -> Self {
        GSample {
            depth: 0.0,
            normal: Vec3::ZERO,
            base_color: Vec3::ZERO,
            roughness: 0.0,
            emissive: Vec3::ZERO,
            metallic: 0.0,
            motion: Vec2::ZERO,
            reflectivity: 0.0,
            occlusion: 1.0,
            material: 0,
        }
    }
}

/// Reflectivity and occlusion (12 bits each) as one integer-valued f32, as
/// `pack_factors` in `wgsl/shared/gbuffer.wgsl` (the full encoding's fifteenth word).
fn pack_factors(reflectivity: f32, occlusion: f32) -> f32 {
    let r = (reflectivity.clamp(0.0, 1.0) * 4095.0).round() as u32;
    let o = (occlusion.clamp(0.0, 1.0) * 4095.0).round() as u32;
    (r + (o << 12)) as f32
}

fn unpack_factors(x: f32) -> (f32, f32) {
    let v = x as u32;
    ((v & 0xfff) as f32 / 4095.0, (v >> 12) as f32 / 4095.0)
}

/// One G-buffer layer on the CPU.
#[derive(Clone, Debug, PartialEq)]
pub struct GBufferLayer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major samples, top row first.
    pub samples: Vec<GSample>,
}

fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = (h >> 10) & 0x1f;
    let frac = f32::from(h & 0x3ff);
    match exp {
        0 => sign * frac * 2f32.powi(-24),
        31 => {
            if frac == 0.0 {
                sign * f32::INFINITY
            } else {
                f32::NAN
            }
        }
        e => sign * (1.0 + frac / 1024.0) * 2f32.powi(i32::from(e) - 15),
    }
}

fn unpack2x16float(w: u32) -> Vec2 {
    Vec2::new(f16_to_f32(w as u16), f16_to_f32((w >> 16) as u16))
}

/// WGSL's `unpack2x16snorm`.
pub(crate) fn unpack2x16snorm(w: u32) -> Vec2 {
    let c = |v: u16| (f32::from(v as i16) / 32767.0).max(-1.0);
    Vec2::new(c(w as u16), c((w >> 16) as u16))
}

/// Inverse of the octahedral encoding in `wgsl/shared/gbuffer.wgsl`.
pub fn oct_decode(e: Vec2) -> Vec3 {
    let mut n = Vec3::new(e.x, e.y, 1.0 - e.x.abs() - e.y.abs());
    let t = (-n.z).max(0.0);
    n.x += if n.x >= 0.0 { -t } else { t };
    n.y += if n.y >= 0.0 { -t } else { t };
    n.normalize()
}

impl GBufferLayer {
    /// Decodes the bytes of a `width` x `height` G-buffer layer in `precision` (any alignment;
    /// bytes past the layer are ignored). Too few bytes is an error saying how many it needs.
    pub fn decode(
        bytes: &[u8],
        width: u32,
        height: u32,
        precision: Precision,
    ) -> crate::Result<GBufferLayer> {
        let n = u64::from(width) * u64::from(height);
        let needed = n.checked_mul(bytes_per_pixel(precision)).filter(|b| *b <= bytes.len() as u64);
        let Some(needed) = needed else {
            return Err(crate::Error::setting(
                "gbuffer",
                format!(
                    "a {width}x{height} layer needs {} bytes in the {precision:?} encoding, {} given",
                    u128::from(n) * u128::from(bytes_per_pixel(precision)),
                    bytes.len()
                ),
            ));
        };
        let bytes = &bytes[..needed as usize];
        let samples = match precision {
            Precision::Full => {
                let f: Vec<f32> = bytemuck::pod_collect_to_vec(bytes);
                f.chunks_exact(16)
                    .map(|w| GSample::from_words(w.try_into().expect("16 words")))
                    .collect()
            }
            Precision::Packed => {
                let u: Vec<u32> = bytemuck::pod_collect_to_vec(bytes);
                u.chunks_exact(8)
                    .map(|w| {
                        let depth = f32::from_bits(w[0]);
                        let c = w[2].to_le_bytes().map(|b| f32::from(b) / 255.0);
                        let bm = unpack2x16float(w[4]);
                        GSample {
                            depth,
                            normal: if depth > 0.0 {
                                oct_decode(unpack2x16snorm(w[1]))
                            } else {
                                Vec3::ZERO
                            },
                            base_color: Vec3::new(c[0], c[1], c[2]),
                            roughness: c[3],
                            emissive: unpack2x16float(w[3]).extend(bm.x),
                            metallic: bm.y,
                            motion: unpack2x16float(w[5]),
                            reflectivity: f32::from(w[6] as u16) / 65535.0,
                            occlusion: f32::from(w[7] as u16) / 65535.0,
                            material: w[6] >> 16,
                        }
                    })
                    .collect()
            }
        };
        Ok(GBufferLayer { width, height, samples })
    }

    /// The sample at pixel (x, y).
    pub fn at(&self, x: u32, y: u32) -> &GSample {
        &self.samples[(y * self.width + x) as usize]
    }
}

/// The channels of a G-buffer layer in an EXR file, one per attribute.
pub const EXR_CHANNELS: [&str; 17] = [
    "depth",
    "normal.X",
    "normal.Y",
    "normal.Z",
    "albedo.R",
    "albedo.G",
    "albedo.B",
    "roughness",
    "emission.R",
    "emission.G",
    "emission.B",
    "metallic",
    "motion.X",
    "motion.Y",
    "reflectivity",
    "occlusion",
    "material",
];

impl GSample {
    /// Every attribute as a number, in [`EXR_CHANNELS`] order.
    pub fn channels(&self) -> [f32; 17] {
        let (n, c, e) = (self.normal, self.base_color, self.emissive);
        [
            self.depth,
            n.x,
            n.y,
            n.z,
            c.x,
            c.y,
            c.z,
            self.roughness,
            e.x,
            e.y,
            e.z,
            self.metallic,
            self.motion.x,
            self.motion.y,
            self.reflectivity,
            self.occlusion,
            self.material as f32,
        ]
    }

    fn from_channels(w: &[f32; 17]) -> GSample {
        GSample {
            depth: w[0],
            normal: Vec3::new(w[1], w[2], w[3]),
            base_color: Vec3::new(w[4], w[5], w[6]),
            roughness: w[7],
            emissive: Vec3::new(w[8], w[9], w[10]),
            metallic: w[11],
            motion: Vec2::new(w[12], w[13]),
            reflectivity: w[14],
            occlusion: w[15],
            material: w[16] as u32,
        }
    }

    /// The sixteen words of the full encoding (`Precision::Full`): the channels, reflectivity
    /// and occlusion packed into one word (12 bits each).
    pub fn words(&self) -> [f32; 16] {
        let c = self.channels();
        let mut w = [0.0; 16];
        w[..14].copy_from_slice(&c[..14]);
        w[14] = pack_factors(self.reflectivity, self.occlusion);
        w[15] = c[16];
        w
    }

    fn from_words(w: &[f32; 16]) -> GSample {
        let (reflectivity, occlusion) = unpack_factors(w[14]);
        let mut c = [0.0; 17];
        c[..14].copy_from_slice(&w[..14]);
        (c[14], c[15], c[16]) = (reflectivity, occlusion, w[15]);
        GSample::from_channels(&c)
    }
}

impl GBufferLayer {
    /// The most samples (pixels times channels, over every layer) [`read_exr`] reads: 2^30 (4
    /// GiB of 32-bit floats; two 3840x2160 layers of the 17 channels hold a quarter of it).
    ///
    /// [`read_exr`]: GBufferLayer::read_exr
    pub const MAX_EXR_SAMPLES: u64 = 1 << 30;

    /// The layer in the full encoding, as `wgsl/shared/gbuffer.wgsl` reads it (64 bytes a pixel).
    pub fn encode_full(&self) -> Vec<f32> {
        self.samples.iter().flat_map(GSample::words).collect()
    }

    /// Writes `layers` into one EXR file, one EXR layer (`layer0`, `layer1`) each, every
    /// attribute a 32-bit float channel named as in [`EXR_CHANNELS`] (lossless).
    pub fn write_exr(path: &std::path::Path, layers: &[GBufferLayer]) -> crate::Result<()> {
        use exr::prelude::*;
        let write_error =
            |e: Error| crate::Error::ImageWrite { path: path.into(), message: e.to_string() };
        let exr_layers: Vec<_> = layers
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let channels = EXR_CHANNELS
                    .iter()
                    .enumerate()
                    .map(|(c, name)| {
                        let values = l.samples.iter().map(|s| s.channels()[c]).collect();
                        AnyChannel::new(*name, FlatSamples::F32(values))
                    })
                    .collect();
                Layer::new(
                    (l.width as usize, l.height as usize),
                    LayerAttributes::named(format!("layer{i}").as_str()),
                    Encoding::SMALL_LOSSLESS,
                    AnyChannels::sort(channels),
                )
            })
            .collect();
        crate::files::write_replacing(path, |tmp| {
            Image::from_layers(
                ImageAttributes::new(IntegerBounds::from_dimensions(
                    exr_layers.first().map_or((0, 0), |l| l.size.into()),
                )),
                exr_layers,
            )
            .write()
            .to_file(tmp)
            .map_err(write_error)
        })
    }

    /// Reads the layers [`write_exr`](GBufferLayer::write_exr) wrote, in their order. A missing
    /// channel, a channel that is not 32-bit float, layers of different sizes, a layer over
    /// [`MAX_IMAGE_SIDE`](crate::settings::MAX_IMAGE_SIDE) a side or headers that declare more
    /// than [`MAX_EXR_SAMPLES`](GBufferLayer::MAX_EXR_SAMPLES) are errors that name the file.
    pub fn read_exr(path: &std::path::Path) -> crate::Result<Vec<GBufferLayer>> {
        use exr::prelude::*;
        let bad = |message: String| crate::Error::ImageRead { path: path.into(), message };
        let read_error = |e| match e {
            Error::Io(source) => crate::Error::io(path, source),
            e => bad(e.to_string()),
        };
        // The headers first: what they declare is allocated before a sample is read, so a size
        // past what a G-buffer can be is refused from them.
        let meta = exr::meta::MetaData::read_from_file(path, false).map_err(read_error)?;
        let mut samples = 0u64;
        for header in meta.headers.iter() {
            let (w, h) = header.layer_size.into();
            let side = crate::settings::MAX_IMAGE_SIDE as usize;
            if w > side || h > side {
                return Err(bad(format!(
                    "a {w}x{h} layer, larger than {side} pixels a side, refused"
                )));
            }
            samples += (w * h * header.channels.list.len()) as u64;
        }
        if samples > Self::MAX_EXR_SAMPLES {
            return Err(bad(format!(
                "{samples} samples declared, more than the {} a G-buffer file may hold, refused",
                Self::MAX_EXR_SAMPLES
            )));
        }
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .all_layers()
            .all_attributes()
            .from_file(path)
            .map_err(read_error)?;
        let mut layers = Vec::new();
        for (i, layer) in image.layer_data.iter().enumerate() {
            let (w, h) = (layer.size.0, layer.size.1);
            let mut columns = Vec::with_capacity(EXR_CHANNELS.len());
            for name in EXR_CHANNELS {
                let channel = layer.channel_data.list.iter().find(|c| c.name.to_string() == name);
                // Files written before the occlusion channel existed hold none: 1 throughout.
                let Some(channel) = channel else {
                    if name == "occlusion" {
                        columns.push(None);
                        continue;
                    }
                    return Err(bad(format!("layer {i} has no channel `{name}`")));
                };
                match &channel.sample_data {
                    FlatSamples::F32(v) if v.len() == w * h => columns.push(Some(v)),
                    _ => return Err(bad(format!("layer {i}: channel `{name}` is not f32"))),
                }
            }
            let samples = (0..w * h)
                .map(|p| {
                    GSample::from_channels(&std::array::from_fn(|c| {
                        columns[c].map_or(1.0, |v| v[p])
                    }))
                })
                .collect();
            let (width, height) = (w as u32, h as u32);
            layers.push(GBufferLayer { width, height, samples });
        }
        if layers.is_empty()
            || layers.iter().any(|l| (l.width, l.height) != (layers[0].width, layers[0].height))
        {
            return Err(bad("expected one or more G-buffer layers of one size".into()));
        }
        Ok(layers)
    }
}

#[cfg(test)]
mod decode_tests {
    use super::*;

    /// Too few bytes, and sizes whose byte count overflows, are errors; any alignment decodes.
    #[test]
    fn decode_checks_the_byte_count() {
        let layer = GBufferLayer {
            width: 3,
            height: 2,
            samples: (0..6)
                .map(|i| GSample { depth: i as f32 + 0.5, ..GSample::default() })
                .collect(),
        };
        let words = layer.encode_full();
        let mut bytes = vec![0u8];
        bytes.extend_from_slice(bytemuck::cast_slice(&words));
        let shifted = GBufferLayer::decode(&bytes[1..], 3, 2, Precision::Full).unwrap();
        assert_eq!(shifted.samples, layer.samples);
        for (w, h) in [(5, 5), (u32::MAX, u32::MAX), (1 << 20, 1 << 20)] {
            for precision in [Precision::Full, Precision::Packed] {
                let e = GBufferLayer::decode(&bytes[1..], w, h, precision).unwrap_err();
                assert!(e.to_string().contains("bytes"), "{e}");
            }
        }
    }
}
