//! `wgsl/radiosity.wgsl`: screen-space radiosity with temporal multi-bounce.

use bytemuck::{Pod, Zeroable};

use crate::gpu;
use crate::settings::{Normalization, Precision, RadiositySettings};

/// Mirrors `struct Radiosity` in `wgsl/radiosity.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct RadiosityUniform {
    /// World-space gather radius.
    pub radius: f32,
    /// Taps per pixel.
    pub samples: u32,
    /// Damping delta of the fed-back indirect light.
    pub damping: f32,
    /// Weight of the history in the temporal filter.
    pub alpha: f32,
    /// History kept where the reprojected point is within this view depth of the previous layer 0.
    pub tolerance: f32,
    /// 1: a tap counts only if it faces the gathering point.
    pub normal_test: u32,
    /// 1: the previous frame's history may be used.
    pub history: u32,
    /// Frame count since the history began (turns the spiral).
    pub turn: u32,
    /// 0: [`Normalization::Cosine`], 1: [`Normalization::Paper`].
    pub normalization: u32,
    /// [`Boost::unsaturated`](crate::settings::Boost).
    pub boost_unsaturated: f32,
    /// [`Boost::saturated`](crate::settings::Boost).
    pub boost_saturated: f32,
    /// Padding to 16 bytes.
    pub pad: u32,
}

impl RadiosityUniform {
    /// The constants for `s`; `history` tells whether the previous frame may be used, `turn` the
    /// frame count since the history began.
    pub fn new(s: &RadiositySettings, history: bool, turn: u32) -> Self {
        RadiosityUniform {
            radius: s.radius,
            samples: s.samples,
            damping: s.damping,
            alpha: s.alpha,
            tolerance: s.history_tolerance,
            normal_test: u32::from(s.normal_test),
            history: u32::from(history),
            turn,
            normalization: match s.normalization {
                Normalization::Cosine => 0,
                Normalization::Paper => 1,
            },
            boost_unsaturated: s.boost.unsaturated,
            boost_saturated: s.boost.saturated,
            pad: 0,
        }
    }
}

/// The buffers of one radiosity frame.
pub struct RadiosityTargets<'a> {
    /// Frame constants.
    pub frame: &'a wgpu::Buffer,
    /// [`RadiosityUniform`].
    pub uniform: &'a wgpu::Buffer,
    /// G-buffer layers.
    pub gbuffer: [&'a wgpu::Buffer; 2],
    /// Direct radiance of each layer.
    pub direct: [&'a wgpu::Buffer; 2],
    /// Outgoing radiance B of each layer (written by the feedback step).
    pub b: [&'a wgpu::Buffer; 2],
    /// The gather's irradiance and confidence.
    pub raw: &'a wgpu::Buffer,
    /// Last frame's filtered irradiance, and this frame's.
    pub history: [&'a wgpu::Buffer; 2],
    /// Last frame's layer-0 visibility buffer (depth for the history test).
    pub prev_vis0: &'a wgpu::Buffer,
}

/// The three radiosity kernels.
pub struct RadiosityPass {
    feedback: wgpu::ComputePipeline,
    gather: wgpu::ComputePipeline,
    temporal: wgpu::ComputePipeline,
}

impl RadiosityPass {
    /// Builds the pipelines for `precision` G-buffers.
    pub fn new(device: &wgpu::Device, precision: Precision) -> Self {
        let defines = &precision.defines()[..];
        RadiosityPass {
            feedback: gpu::compute_pipeline(device, "radiosity", "radiosity_feedback", defines),
            gather: gpu::compute_pipeline(device, "radiosity", "radiosity_gather", defines),
            temporal: gpu::compute_pipeline(device, "radiosity", "radiosity_temporal", defines),
        }
    }

    /// Records feedback and gather (the `radiosity` pass).
    pub fn encode_gather(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        t: &RadiosityTargets<'_>,
        size: (u32, u32),
    ) {
        let feedback = [
            (0, t.frame),
            (1, t.uniform),
            (2, t.gbuffer[0]),
            (3, t.gbuffer[1]),
            (4, t.direct[0]),
            (5, t.direct[1]),
            (6, t.b[0]),
            (7, t.b[1]),
            (9, t.history[0]),
            (11, t.prev_vis0),
        ];
        let gather = [
            (0, t.frame),
            (1, t.uniform),
            (2, t.gbuffer[0]),
            (3, t.gbuffer[1]),
            (6, t.b[0]),
            (7, t.b[1]),
            (8, t.raw),
        ];
        for (pipeline, entries) in [(&self.feedback, &feedback[..]), (&self.gather, &gather[..])] {
            gpu::dispatch_pixels(device, pass, "deep-gbuffer.radiosity", pipeline, entries, size);
        }
    }

    /// Records the temporal filter (the `radiosity.temporal` pass).
    pub fn encode_temporal(
        &self,
        device: &wgpu::Device,
        pass: &mut wgpu::ComputePass<'_>,
        t: &RadiosityTargets<'_>,
        size: (u32, u32),
    ) {
        let entries = [
            (0, t.frame),
            (1, t.uniform),
            (2, t.gbuffer[0]),
            (8, t.raw),
            (9, t.history[0]),
            (10, t.history[1]),
            (11, t.prev_vis0),
        ];
        gpu::dispatch_pixels(
            device,
            pass,
            "deep-gbuffer.radiosity.temporal",
            &self.temporal,
            &entries,
            size,
        );
    }
}
