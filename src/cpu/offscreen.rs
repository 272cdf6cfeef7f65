//! CPU reference of `wgsl/offscreen.wgsl`: the clusters of the reflective shadow maps' texels
//! that no layer holds, and their light added to the gather.

use std::f32::consts::PI;

use glam::{Vec2, Vec3, Vec4, Vec4Swizzles};

use crate::cpu::direct::light_at;
use crate::cpu::frame::{clip_to_pixel, image_size, mat_mul, view_position};
use crate::cpu::spiral::depth_slope_span;
use crate::frame::{
    Cluster, FrameUniform, OffscreenUniform, RSM_CLUSTER_SIDE, RSM_CLUSTERS_PER_FACE,
    RSM_CLUSTERS_PER_PIXEL, RSM_HELD_MARGIN, RSM_RESOLUTION, ShadowFace,
};
use crate::gbuffer::{GSample, vis_depth};
use crate::scene::GpuLight;

/// What the cluster kernel reads: the camera's frame and constants, the lights, and the
/// reflective shadow maps.
pub struct Rsm<'a> {
    /// The camera's frame.
    pub frame: &'a FrameUniform,
    /// The kernel's constants.
    pub params: &'a OffscreenUniform,
    /// The scene's lights.
    pub lights: &'a [GpuLight],
    /// Each face's lookup constants (offsets in texels).
    pub faces: &'a [ShadowFace],
    /// The light of each face.
    pub face_lights: &'a [u32],
    /// The faces' visibility words.
    pub vis: &'a [u64],
    /// The faces' G-buffer records, decoded.
    pub records: &'a [GSample],
    /// This frame's visibility words of layer 0 and layer 1.
    pub layers: [&'a [u64]; 2],
}

impl Rsm<'_> {
    /// As `held_tolerance`.
    fn held_tolerance(&self, v: Vec3, n: Vec3, z: f32) -> f32 {
        depth_slope_span(self.frame, v, n, 2.0) + 1e-3 * z
    }

    /// As `unheld`: the share of the world point (normal `n`) the clusters carry.
    fn unheld(&self, world: Vec3, n: Vec3) -> f32 {
        let f = self.frame;
        let v = mat_mul(&f.view, world.extend(1.0).to_array());
        let c = mat_mul(&f.proj, v.to_array());
        if c.w.is_nan() || c.w <= 0.0 {
            return 1.0;
        }
        let size = image_size(f);
        let px = clip_to_pixel(c, size);
        if !(px.x >= 0.0 && px.y >= 0.0 && px.x < size.x && px.y < size.y) {
            return 1.0;
        }
        let z = -v.z;
        let q = (px.y as u32 * f.width + px.x as u32) as usize;
        let n_view = mat_mul(&f.view, n.extend(0.0).to_array()).xyz();
        let tolerance = self.held_tolerance(v.xyz(), n_view, z);
        let near = |layer: &[u64]| vis_depth(layer[q]).is_some_and(|d| (d - z).abs() <= tolerance);
        let held = near(self.layers[0]) || (self.params.layers == 2 && near(self.layers[1]));
        if !held {
            return 1.0;
        }
        let edge = px.x.min(size.x - px.x).min(px.y.min(size.y - px.y));
        (1.0 - edge / (RSM_HELD_MARGIN * size.y).max(1e-6)).clamp(0.0, 1.0)
    }

    /// One texel's share of its cluster: flux, area, area times point, area times normal.
    fn texel(&self, face: usize, (x, y): (u32, u32)) -> Option<(Vec3, f32, Vec3, Vec3)> {
        let f = &self.faces[face];
        let t = (f.offset + y * RSM_RESOLUTION + x) as usize;
        let s = &self.records[t];
        let depth = vis_depth(self.vis[t])?;
        if s.depth.is_nan() || s.depth <= 0.0 {
            return None;
        }
        let res = RSM_RESOLUTION as f32;
        let ndc = Vec2::new((x as f32 + 0.5) / res * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / res * 2.0);
        let (v, perpendicular) = if f.ortho != 0 {
            let v = Vec3::new(
                (ndc.x - f.proj[3][0]) / f.proj[0][0],
                (ndc.y - f.proj[3][1]) / f.proj[1][1],
                -depth,
            );
            (v, f.texel * f.texel)
        } else {
            let unit = Vec3::new(ndc.x / f.proj[0][0], ndc.y / f.proj[1][1], -1.0);
            (unit * depth, f.texel * f.texel * depth * depth / unit.length())
        };
        let u = v - Vec3::from_slice(&f.view[3][..3]);
        let column = |k: usize| Vec3::from_slice(&f.view[k][..3]);
        let world = Vec3::new(column(0).dot(u), column(1).dot(u), column(2).dot(u));
        let (e, l) = light_at(&self.lights[self.face_lights[face] as usize], world);
        let cos_l = s.normal.dot(l).max(0.0);
        let a = perpendicular / cos_l.max(0.1);
        let reflected = (1.0 - s.metallic) * s.occlusion * s.base_color / PI
            * e
            * perpendicular
            * (cos_l / 0.1).min(1.0);
        let sent = reflected + s.emissive * a;
        let finite = sent.abs().max_element() <= 3.0e38 && a <= 3.0e38 && world.is_finite();
        let weight = self.unheld(world, s.normal);
        (finite && weight > 0.0).then(|| {
            let area = a * weight;
            (sent * weight, area, world * area, s.normal * area)
        })
    }

    /// As `offscreen_clusters`: every face's clusters, [`RSM_CLUSTERS_PER_FACE`] each.
    pub fn clusters(&self) -> Vec<Cluster> {
        let (side, cells) = (RSM_CLUSTER_SIDE, RSM_RESOLUTION / RSM_CLUSTER_SIDE);
        let mut out = Vec::new();
        for face in 0..self.params.faces as usize {
            for cy in 0..cells {
                for cx in 0..cells {
                    let (mut flux, mut area, mut point, mut normal) =
                        (Vec3::ZERO, 0.0f32, Vec3::ZERO, Vec3::ZERO);
                    for ly in 0..side {
                        for lx in 0..side {
                            let texel = (cx * side + lx, cy * side + ly);
                            if let Some((f, a, p, n)) = self.texel(face, texel) {
                                flux += f;
                                area += a;
                                point += p;
                                normal += n;
                            }
                        }
                    }
                    let mut c = Cluster::default();
                    if area > 0.0 && area <= 3.0e38 {
                        c.position = (point / area).to_array();
                        c.area = area;
                        c.normal = (normal / area).to_array();
                        c.flux = flux.to_array();
                    }
                    out.push(c);
                }
            }
        }
        debug_assert_eq!(out.len(), (self.params.faces * RSM_CLUSTERS_PER_FACE) as usize);
        out
    }
}

/// As `stride_for`: a pixel sums one in this many of `count` clusters, at most
/// [`RSM_CLUSTERS_PER_PIXEL`] of them.
pub fn stride_for(count: usize) -> usize {
    let mut stride = 1;
    while stride * (RSM_CLUSTERS_PER_PIXEL as usize) < count {
        stride *= 2;
    }
    stride
}

/// As `stride_phase`: the residue pixel `(x, y)` sums at frame `turn`.
pub fn stride_phase((x, y): (u32, u32), stride: usize, turn: u32) -> usize {
    // u32 arithmetic that wraps, as the kernel's.
    let b = (x & 3) + 4 * (y & 3);
    let turned = if stride > 16 { turn.wrapping_mul(16) } else { turn };
    (b.wrapping_add(turned) % stride as u32) as usize
}

/// As `offscreen_compact` and `offscreen_add`: the gather's irradiance and coverage `raw` with
/// the light of the `clusters` that hold a texel added at every layer-0 point of `layer0`.
pub fn add(
    f: &FrameUniform,
    u: &OffscreenUniform,
    clusters: &[Cluster],
    layer0: &[GSample],
    raw: &[Vec4],
) -> Vec<Vec4> {
    let count = (u.faces * RSM_CLUSTERS_PER_FACE) as usize;
    let lit: Vec<&Cluster> = clusters[..count].iter().filter(|c| c.area > 0.0).collect();
    let stride = stride_for(lit.len());
    let mut out = raw.to_vec();
    for y in 0..f.height {
        for x in 0..f.width {
            let p = (y * f.width + x) as usize;
            let s = &layer0[p];
            if s.depth.is_nan() || s.depth <= 0.0 {
                continue;
            }
            let c = view_position(f, Vec2::new(x as f32, y as f32) + 0.5, s.depth);
            let at = mat_mul(&f.inv_view, c.extend(1.0).to_array()).xyz();
            let phase = stride_phase((x, y), stride, u.turn);
            let (mut e, mut covered) = (Vec3::ZERO, 0.0f32);
            for cluster in lit.iter().skip(phase).step_by(stride) {
                let d = Vec3::from(cluster.position) - at;
                let d2 = d.dot(d);
                if d2.is_nan() || d2 <= 0.0 {
                    continue;
                }
                let w = d / d2.sqrt();
                let (cos_x, cos_p) = (s.normal.dot(w), -Vec3::from(cluster.normal).dot(w));
                if cos_x <= 0.0 || cos_p <= 0.0 {
                    continue;
                }
                let g = cos_x * cos_p / (d2 + cluster.area / PI);
                e += Vec3::from(cluster.flux) * g;
                covered += cluster.area * g / PI;
            }
            let g = raw[p];
            let open = (1.0 - g.w).clamp(0.0, 1.0);
            let share = covered * stride as f32;
            let scale = if share > open { stride as f32 * open / share } else { stride as f32 };
            let sum = g.xyz() + e * scale;
            if sum.abs().max_element() <= 3.0e38 {
                out[p] = sum.extend((g.w + covered * scale).min(1.0));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{RSM_CLUSTERS_PER_PIXEL, stride_for, stride_phase};

    /// A pixel sums at most 32 clusters however many there are, the 16 pixels of a 4x4 block
    /// take different residues, and over the frames the block takes every one.
    #[test]
    fn strides_bound_the_work_and_cover_every_cluster() {
        for count in [0, 1, 31, 32, 33, 384, 512, 513, 15360, 1 << 20] {
            let stride = stride_for(count);
            let most = RSM_CLUSTERS_PER_PIXEL as usize;
            assert!(count.div_ceil(stride) <= most, "{count} clusters: stride {stride}");
            assert!(stride == 1 || count.div_ceil(stride / 2) > most, "{count}: the least stride");
            for turn in [0, 1, 7, u32::MAX] {
                let mut seen: Vec<usize> =
                    (0..16).map(|b| stride_phase((b % 4, b / 4), stride, turn)).collect();
                seen.sort_unstable();
                seen.dedup();
                assert_eq!(seen.len(), stride.min(16), "{count} clusters, turn {turn}");
            }
            // The block's pixels over stride / 16 frames (one frame up to 16) take every one.
            let frames = (stride / 16).max(1) as u32;
            let mut over_frames: Vec<usize> = (0..frames)
                .flat_map(|turn| (0..16).map(move |b| stride_phase((b % 4, b / 4), stride, turn)))
                .collect();
            over_frames.sort_unstable();
            over_frames.dedup();
            assert_eq!(over_frames.len(), stride, "{count} clusters over {frames} frames");
        }
    }
}
