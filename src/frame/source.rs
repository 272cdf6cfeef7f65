//! The radiosity's gather source: one 16-byte texel per pixel (and per texel of its MIP levels)
//! holding what a gather tap reads, both layers' view depths and outgoing radiance B, the
//! radiance in RGB9E5 (`wgsl/shared/rgb9e5.wgsl`).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Largest value RGB9E5 holds: (511 / 512) 2^16.
pub const RGB9E5_MAX: f32 = 65408.0;

/// 2^k for k in [-126, 127], exactly.
fn pow2(k: i32) -> f32 {
    f32::from_bits(((127 + k) as u32) << 23)
}

/// RGB9E5 of `c`, as `pack_rgb9e5`: three 9-bit mantissas sharing a 5-bit exponent (bias 15),
/// each channel within 2^-9 of the largest; NaN and negative channels 0, larger ones
/// [`RGB9E5_MAX`]. Every step is exact, so the GPU and this agree to the bit.
pub fn pack_rgb9e5(c: Vec3) -> u32 {
    let v = c.to_array().map(|x| if x > 0.0 { x.min(RGB9E5_MAX) } else { 0.0 });
    let m = v[0].max(v[1]).max(v[2]);
    let mut e = (((m.to_bits() >> 23) & 0xff) as i32 - 127).max(-16) + 16;
    if (m * pow2(24 - e) + 0.5).floor() >= 512.0 {
        e += 1;
    }
    let s = v.map(|x| (x * pow2(24 - e) + 0.5).floor() as u32);
    s[0] | (s[1] << 9) | (s[2] << 18) | ((e as u32) << 27)
}

/// The radiance `w` holds (`unpack_rgb9e5`).
pub fn unpack_rgb9e5(w: u32) -> Vec3 {
    let scale = pow2((w >> 27) as i32 - 24);
    Vec3::new((w & 0x1ff) as f32, ((w >> 9) & 0x1ff) as f32, ((w >> 18) & 0x1ff) as f32) * scale
}

/// One texel of the gather source, as `radiosity_feedback` writes it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct SourceTexel {
    /// View depth of layer 0 and layer 1 as f32 bits (0: no surface).
    pub depth: [u32; 2],
    /// B of layer 0 and layer 1 in RGB9E5.
    pub radiance: [u32; 2],
}

impl SourceTexel {
    /// The texel of a pixel whose layers lie at view depths `depth` and send `radiance`.
    pub fn new(depth: [f32; 2], radiance: [Vec3; 2]) -> Self {
        SourceTexel { depth: depth.map(f32::to_bits), radiance: radiance.map(pack_rgb9e5) }
    }

    /// View depth of `layer`.
    pub fn depth(&self, layer: usize) -> f32 {
        f32::from_bits(self.depth[layer])
    }

    /// B of `layer`.
    pub fn radiance(&self, layer: usize) -> Vec3 {
        unpack_rgb9e5(self.radiance[layer])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb9e5_round_trips_within_its_precision() {
        for c in [
            Vec3::ZERO,
            Vec3::new(1.0, 0.5, 0.25),
            Vec3::new(17.0, 12.0, 4.0),
            Vec3::new(1e-3, 2e-6, 0.0),
            Vec3::new(65000.0, 1.0, 0.0),
            Vec3::splat(0.999_99),
            Vec3::splat(511.9),
        ] {
            let back = unpack_rgb9e5(pack_rgb9e5(c));
            let tolerance = c.max_element() / 512.0 + 1e-9;
            assert!((back - c).abs().max_element() <= tolerance, "{c} -> {back}");
        }
    }

    #[test]
    fn rgb9e5_holds_exact_values_exactly_and_clamps_the_rest() {
        for c in [Vec3::new(1.0, 0.5, 0.0), Vec3::new(256.0, 3.0, 1.0), Vec3::splat(RGB9E5_MAX)] {
            assert_eq!(unpack_rgb9e5(pack_rgb9e5(c)), c);
        }
        assert_eq!(
            unpack_rgb9e5(pack_rgb9e5(Vec3::new(f32::NAN, -1.0, 2.0))),
            Vec3::new(0.0, 0.0, 2.0)
        );
        assert_eq!(
            unpack_rgb9e5(pack_rgb9e5(Vec3::new(f32::INFINITY, 1e9, 0.0))),
            Vec3::new(RGB9E5_MAX, RGB9E5_MAX, 0.0)
        );
        // Rounding up to the next power of two moves to the next exponent.
        assert_eq!(unpack_rgb9e5(pack_rgb9e5(Vec3::splat(1.9995))), Vec3::splat(2.0));
    }
}
