//! The radiosity's gather source: one 32-byte texel per pixel (and per texel of its MIP levels)
//! holding what a gather tap reads: both layers' view depths, outgoing radiance B, view-space
//! normals and the radiance H of each surface's far side, the radiances in RGB9E5
//! (`wgsl/shared/rgb9e5.wgsl`), the normals octahedral in 2x16 snorm.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use crate::gbuffer::{oct_decode, unpack2x16snorm};

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

/// The octahedral encoding of `wgsl/shared/gbuffer.wgsl` (`oct_encode`) of a non-zero `n`.
fn oct_encode(n: Vec3) -> Vec2 {
    let p = Vec2::new(n.x, n.y) / (n.x.abs() + n.y.abs() + n.z.abs());
    if n.z >= 0.0 {
        return p;
    }
    let sign = Vec2::new(if p.x >= 0.0 { 1.0 } else { -1.0 }, if p.y >= 0.0 { 1.0 } else { -1.0 });
    (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * sign
}

/// WGSL's `pack2x16snorm`.
fn pack2x16snorm(v: Vec2) -> u32 {
    let c = |x: f32| u32::from((x.clamp(-1.0, 1.0) * 32767.0).round_ties_even() as i16 as u16);
    c(v.x) | (c(v.y) << 16)
}

/// A normal as the gather source holds it (`pack_normal`; 0, which reads as +z,
/// for the zero vector: a texel's depth says whether it holds a surface).
pub fn pack_normal(n: Vec3) -> u32 {
    if n.length_squared() > 0.0 { pack2x16snorm(oct_encode(n)) } else { 0 }
}

/// One texel of the gather source, as `radiosity_feedback` writes it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct SourceTexel {
    /// View depth of layer 0 and layer 1 as f32 bits (0: no surface).
    pub depth: [u32; 2],
    /// B of layer 0 and layer 1 in RGB9E5.
    pub radiance: [u32; 2],
    /// View-space normal of layer 0 and layer 1 ([`pack_normal`]; 0 where there is no surface).
    pub normal: [u32; 2],
    /// H of layer 0 and layer 1 in RGB9E5: what the surface's far side sends, the part of B
    /// that does not depend on which way the surface faces (its emission and the indirect light
    /// it reflects).
    pub hidden: [u32; 2],
}

crate::frame::mirrored!(
    SourceTexel,
    "radiosity.wgsl",
    "SourceTexel",
    [depth, radiance, normal, hidden]
);

impl SourceTexel {
    /// The texel of a pixel whose layers lie at view depths `depth`, face along the view-space
    /// `normal`s and send `radiance` (their far sides `hidden`).
    pub fn new(depth: [f32; 2], normal: [Vec3; 2], radiance: [Vec3; 2], hidden: [Vec3; 2]) -> Self {
        SourceTexel {
            depth: depth.map(f32::to_bits),
            radiance: radiance.map(pack_rgb9e5),
            normal: normal.map(pack_normal),
            hidden: hidden.map(pack_rgb9e5),
        }
    }

    /// The view-space normal of `layer` (meaningless where its depth is 0).
    pub fn normal(&self, layer: usize) -> Vec3 {
        oct_decode(unpack2x16snorm(self.normal[layer]))
    }

    /// H of `layer`.
    pub fn hidden(&self, layer: usize) -> Vec3 {
        unpack_rgb9e5(self.hidden[layer])
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
