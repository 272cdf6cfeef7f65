//! The kernels' own constants, one struct per WGSL `struct` they read as a uniform, and the
//! raster's counter words.

use bytemuck::{Pod, Zeroable};

use super::{PyramidLayout, mirrored};
use crate::scene::{Camera, Projection};
use crate::settings::{
    AoSettings, DofSettings, MotionBlurSettings, Normalization, RadiosityEstimator,
    RadiositySettings, ReflectionSettings,
};

/// Mirrors `struct Ao` in `wgsl/ao.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct AoUniform {
    /// World-space radius.
    pub radius: f32,
    /// Bias β.
    pub bias: f32,
    /// Intensity.
    pub intensity: f32,
    /// Taps per pixel.
    pub samples: u32,
    /// Pyramid levels.
    pub levels: u32,
    /// [`AoSettings::mip_offset`].
    pub mip_offset: u32,
    /// [`AoSettings::slices`].
    pub slices: u32,
    /// [`AoSettings::thickness`] times the radius, in scene units; 0 for the `horizon`
    /// estimator (solid without end).
    pub thickness: f32,
    /// Frames since the temporal filter's history began (0 without it): turns the slices.
    pub turn: u32,
    /// [`AoSettings::extrapolation`].
    pub extrapolation: f32,
    pub _pad: [u32; 2],
    /// Level offsets in the packed pyramid (up to 8).
    pub offsets: [[u32; 4]; 2],
}

const _: () = assert!(std::mem::size_of::<AoUniform>() == 80);
mirrored!(
    AoUniform,
    "ao.wgsl",
    "Ao",
    [
        radius,
        bias,
        intensity,
        samples,
        levels,
        mip_offset,
        slices,
        thickness,
        turn,
        extrapolation,
        offsets
    ]
);

impl AoUniform {
    /// The constants for `settings` over a pyramid of `layout`, in a frame `turn` frames into
    /// the temporal filter's history (0: without one), with the slices and taps that frame
    /// takes ([`AoSettings::frame_taps`]).
    pub fn new(settings: &AoSettings, layout: &PyramidLayout, turn: u32) -> Self {
        let (slices, samples) = settings.frame_taps(turn > 0);
        AoUniform {
            radius: settings.radius,
            bias: settings.bias,
            intensity: settings.intensity,
            samples,
            levels: layout.levels.len().min(8) as u32,
            mip_offset: settings.mip_offset,
            slices,
            thickness: settings.solid_depth(),
            turn,
            extrapolation: settings.extrapolation,
            _pad: [0; 2],
            offsets: level_offsets(layout),
        }
    }
}

/// Mirrors `struct Temporal` in `wgsl/temporal.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct TemporalUniform {
    /// Weight of the history, in [0, 1).
    pub alpha: f32,
    /// How far the previous frame's layer 0 may lie from a point's surface (view depth, scene
    /// units) for the point to keep its history.
    pub tolerance: f32,
    /// 1 when the previous frame's filtered values may be used.
    pub history: u32,
    pub _pad: u32,
}

mirrored!(TemporalUniform, "temporal.wgsl", "Temporal", [alpha, tolerance, history]);

/// The first texel of each of `layout`'s levels (up to 8), as the kernels' `offsets` hold them.
fn level_offsets(layout: &PyramidLayout) -> [[u32; 4]; 2] {
    let mut offsets = [[0; 4]; 2];
    for (i, l) in layout.levels.iter().enumerate().take(8) {
        offsets[i / 4][i % 4] = l.offset;
    }
    offsets
}

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
    /// Slices per pixel (`slices` gather).
    pub slices: u32,
    /// [`RadiositySettings::thickness`] times the radius, in scene units.
    pub thickness: f32,
    /// 0: [`RadiosityEstimator::Spiral`], 1: [`RadiosityEstimator::Slices`] (the kernel is
    /// chosen by define; the CPU reference reads this).
    pub estimator: u32,
    /// Levels of the gather source.
    pub levels: u32,
    /// [`RadiositySettings::mip_offset`].
    pub mip_offset: u32,
    /// [`RadiositySettings::layer1_samples`].
    pub layer1_samples: u32,
    /// [`RadiositySettings::extrapolation`].
    pub extrapolation: f32,
    pub _pad: [u32; 2],
    /// Level offsets in the gather source (up to 8).
    pub offsets: [[u32; 4]; 2],
}

mirrored!(
    RadiosityUniform,
    "radiosity.wgsl",
    "Radiosity",
    [
        radius,
        samples,
        damping,
        alpha,
        tolerance,
        normal_test,
        history,
        turn,
        normalization,
        boost_unsaturated,
        boost_saturated,
        slices,
        thickness,
        estimator,
        levels,
        mip_offset,
        layer1_samples,
        extrapolation,
        offsets
    ]
);

impl RadiosityUniform {
    /// The constants for `s` over a gather source of `layout`; `history` tells whether the
    /// previous frame may be used, `still` how many frames in a row the view has stood still
    /// (0: it moved), `turn` the frame count since the history began.
    ///
    /// With the history, a `slices` gather that turns every frame gathers
    /// [`RadiositySettings::history_slices`] of its slices while the view moves (each with the
    /// same steps a side, in both gathers): the temporal filter holds the others' light from
    /// the frames before. A still view gathers them all.
    pub fn new(
        s: &RadiositySettings,
        layout: &PyramidLayout,
        (history, still): (bool, u32),
        turn: u32,
    ) -> Self {
        let (slices, samples, layer1_samples) = s.frame_taps(history, still);
        RadiosityUniform {
            radius: s.radius,
            samples,
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
            slices,
            thickness: s.thickness * s.radius,
            estimator: match s.estimator {
                RadiosityEstimator::Spiral => 0,
                RadiosityEstimator::Slices => 1,
            },
            levels: layout.levels.len().min(8) as u32,
            mip_offset: s.mip_offset,
            layer1_samples,
            extrapolation: s.extrapolation,
            _pad: [0; 2],
            offsets: level_offsets(layout),
        }
    }
}

/// Mirrors `struct Reflections` in `wgsl/reflections.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct ReflectionsUniform {
    /// The scene's ambient radiance: what a missed ray sees without an environment map, and the
    /// ambient term of the surfaces rays hit.
    pub ambient: [f32; 3],
    /// How far a ray is followed, in scene units (infinite: to the screen's edge).
    pub max_distance: f32,
    /// How far behind a surface a ray may pass and still hit it, in scene units.
    pub thickness: f32,
    /// 8x8 tiles across.
    pub tiles_x: u32,
    /// 8x8 tiles down.
    pub tiles_y: u32,
    /// Environment map width in texels (0: the constant `sky`).
    pub env_width: u32,
    /// Environment map height in texels.
    pub env_height: u32,
    /// Levels of the nearest-depth pyramid.
    pub levels: u32,
    /// 1: the frame drew layer 1 (the march looks for hits there too).
    pub two_layers: u32,
    /// [`ReflectionSettings::lobe_samples`].
    pub lobe_samples: u32,
    /// Level offsets in the packed pyramid (up to 8).
    pub offsets: [[u32; 4]; 2],
    /// Level widths in texels (up to 8).
    pub widths: [[u32; 4]; 2],
    /// Lights in the light buffer: a hit surface's direct light is re-evaluated towards the
    /// point the ray left.
    pub light_count: u32,
    /// Percentage-closer filtering radius of the shadow maps in texels (0 without them).
    pub pcf: u32,
    /// Padding.
    pub _pad: [u32; 2],
    /// The scene's bounding sphere: world centre and radius. A ray the screen does not place is
    /// followed through the shadow maps within it; radius 0: it is not.
    pub bounds: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<ReflectionsUniform>() == 144);
mirrored!(
    ReflectionsUniform,
    "reflections.wgsl",
    "Reflections",
    [
        ambient,
        max_distance,
        thickness,
        tiles_x,
        tiles_y,
        env_width,
        env_height,
        levels,
        two_layers,
        lobe_samples,
        offsets,
        widths,
        light_count,
        pcf,
        bounds
    ]
);

impl ReflectionsUniform {
    /// The constants for `settings` at `width` x `height` over a nearest-depth pyramid of
    /// `layout`, with layer 1 when `two_layers`: hit surfaces are shaded with the scene's
    /// `ambient` radiance; missed rays see it too, or the environment map of `environment`'s
    /// size.
    pub fn new(
        settings: &ReflectionSettings,
        (width, height): (u32, u32),
        layout: &PyramidLayout,
        two_layers: bool,
        ambient: [f32; 3],
        environment: Option<(u32, u32)>,
    ) -> Self {
        let (mut offsets, mut widths) = ([[0; 4]; 2], [[0; 4]; 2]);
        for (i, l) in layout.levels.iter().enumerate().take(8) {
            offsets[i / 4][i % 4] = l.offset;
            widths[i / 4][i % 4] = l.width;
        }
        let (env_width, env_height) = environment.unwrap_or((0, 0));
        ReflectionsUniform {
            ambient,
            max_distance: settings.max_distance,
            thickness: settings.thickness,
            tiles_x: width.div_ceil(8),
            tiles_y: height.div_ceil(8),
            env_width,
            env_height,
            levels: layout.levels.len().min(8) as u32,
            two_layers: u32::from(two_layers),
            lobe_samples: settings.lobe_samples,
            offsets,
            widths,
            light_count: 0,
            pcf: 0,
            _pad: [0; 2],
            bounds: [0.0; 4],
        }
    }

    /// The same constants with `light_count` lights re-lighting hit surfaces, their shadow
    /// maps filtered with radius `pcf` (0 without shadow maps).
    pub fn with_lights(self, light_count: u32, pcf: u32) -> Self {
        ReflectionsUniform { light_count, pcf, ..self }
    }

    /// The same, with the scene's axis-aligned bounds `(lo, hi)`: rays the screen does not place
    /// are followed through the shadow maps within their bounding sphere.
    pub fn with_bounds(self, bounds: Option<(glam::Vec3, glam::Vec3)>) -> Self {
        let bounds = bounds.map_or([0.0; 4], |(lo, hi)| {
            let centre = (lo + hi) * 0.5;
            // A little past the corners, so that a surface on the bounds is inside.
            let radius = (hi - lo).length() * 0.5 * 1.001 + 1e-6;
            [centre.x, centre.y, centre.z, radius]
        });
        ReflectionsUniform { bounds, ..self }
    }
}

/// Mirrors `struct Direct` in `wgsl/direct.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct DirectUniform {
    /// Lights in the light buffer.
    pub light_count: u32,
    /// Percentage-closer filtering radius in texels (0 without shadow maps).
    pub pcf: u32,
    /// Padding.
    pub _pad: [u32; 2],
}

mirrored!(DirectUniform, "direct.wgsl", "Direct", [light_count, pcf]);

/// Mirrors `struct Composite` in `wgsl/composite.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct CompositeUniform {
    /// The ambient radiance that AV scales.
    pub ambient: [f32; 3],
    /// Padding.
    pub _pad: u32,
}

mirrored!(CompositeUniform, "composite.wgsl", "Composite", [ambient]);

/// Mirrors `struct Transparency` in `wgsl/transparency.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct TransparencyUniform {
    /// The ambient radiance blended surfaces reflect (unoccluded).
    pub ambient: [f32; 3],
    /// Padding.
    pub _pad: u32,
}

mirrored!(TransparencyUniform, "transparency.wgsl", "Transparency", [ambient]);

/// Mirrors `struct MotionBlur` in `wgsl/motion_blur.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct MotionBlurUniform {
    /// The ambient radiance (layer 1 is shaded with it).
    pub ambient: [f32; 3],
    /// [`MotionBlurSettings::shutter`].
    pub shutter: f32,
    /// [`MotionBlurSettings::max_blur`].
    pub max_blur: f32,
    /// [`MotionBlurSettings::samples`].
    pub samples: u32,
    /// Tiles each side whose fastest motion a pixel follows: enough to cover `max_blur` pixels
    /// and one more ([`MOTION_TILE`] pixels per tile).
    pub tile_reach: u32,
    /// Tiles per row.
    pub tiles_x: u32,
}

/// Pixels per side of a motion-blur tile (`TILE` in `wgsl/motion_blur.wgsl`).
pub const MOTION_TILE: u32 = 16;

mirrored!(
    MotionBlurUniform,
    "motion_blur.wgsl",
    "MotionBlur",
    [ambient, shutter, max_blur, samples, tile_reach, tiles_x]
);

impl MotionBlurUniform {
    /// The constants for `s` with the scene's `ambient` radiance, for an image `width` pixels
    /// wide.
    pub fn new(s: &MotionBlurSettings, ambient: [f32; 3], width: u32) -> Self {
        MotionBlurUniform {
            ambient,
            shutter: s.shutter,
            max_blur: s.max_blur,
            samples: s.samples,
            tile_reach: (s.max_blur.clamp(0.0, 256.0).ceil() as u32 + 1).div_ceil(MOTION_TILE),
            tiles_x: width.div_ceil(MOTION_TILE),
        }
    }
}

/// Mirrors `struct Dof` in `wgsl/dof.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct DofUniform {
    /// The ambient radiance (layer 1 is shaded with it).
    pub ambient: [f32; 3],
    /// Lens radius times the pixels per scene unit at view depth 1: the circle of confusion in
    /// pixels per unit of 1/focus - 1/z.
    pub lens_px: f32,
    /// The signed circles of confusion a lens ray walks between, in pixels: those of the scene's
    /// nearest and farthest view depths, within [`DofSettings::max_coc`] either way.
    pub coc_range: [f32; 2],
    /// 1 / the focus distance.
    pub inv_focus: f32,
    /// [`DofSettings::samples`].
    pub samples: u32,
    /// [`DofSettings::thickness`].
    pub thickness: f32,
    /// Padding.
    pub _pad: [u32; 3],
}

mirrored!(
    DofUniform,
    "dof.wgsl",
    "Dof",
    [ambient, lens_px, coc_range, inv_focus, samples, thickness]
);

impl DofUniform {
    /// The constants for `s`, seen through `camera` (a perspective camera whose lens has an
    /// aperture) in an image `height` pixels tall, over a scene within `bounds` (`None`: unknown)
    /// with the `ambient` radiance.
    pub fn new(
        s: &DofSettings,
        camera: &Camera,
        height: u32,
        bounds: Option<(glam::Vec3, glam::Vec3)>,
        ambient: [f32; 3],
    ) -> Self {
        let lens_px = camera.lens.radius * camera.pixels_of(1.0, 1.0, height);
        let inv_focus = 1.0 / camera.lens.focus;
        let coc = |z: f32| lens_px * (inv_focus - 1.0 / z);
        let mut coc_range = [-s.max_coc, s.max_coc];
        if let (Some((lo, hi)), Projection::Perspective { near, .. }) = (bounds, camera.projection)
        {
            // The view depths of the bounds' corners (no nearer than the near plane).
            let view = camera.view();
            let depths = (0..8).map(|i| {
                let corner = glam::Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                (-view.transform_point3(corner).z).max(near)
            });
            let (z_min, z_max) =
                depths.fold((f32::INFINITY, 0.0f32), |(a, b), z| (a.min(z), b.max(z)));
            if z_min.is_finite() && z_max.is_finite() {
                // A pixel's step may sit up to a pixel beyond the exact range.
                coc_range = [
                    (coc(z_min) - 1.0).clamp(-s.max_coc, s.max_coc),
                    (coc(z_max) + 1.0).clamp(-s.max_coc, s.max_coc),
                ];
            }
        }
        DofUniform {
            ambient,
            lens_px,
            coc_range,
            inv_focus,
            samples: s.samples,
            thickness: s.thickness,
            _pad: [0; 3],
        }
    }
}

/// Mirrors `struct PyramidLevel` in `wgsl/pyramid.wgsl`: one level's source and destination.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct LevelUniform {
    /// First texel of the source level.
    pub src_offset: u32,
    /// Source width.
    pub src_width: u32,
    /// Source height.
    pub src_height: u32,
    /// First texel of the level written.
    pub dst_offset: u32,
    /// Width written.
    pub dst_width: u32,
    /// Height written.
    pub dst_height: u32,
    /// Padding.
    pub _pad: [u32; 2],
}

mirrored!(
    LevelUniform,
    "pyramid.wgsl",
    "PyramidLevel",
    [src_offset, src_width, src_height, dst_offset, dst_width, dst_height]
);

impl LevelUniform {
    /// The constants that build level `i` of `layout` (level 0 from the G-buffer).
    pub fn new(layout: &PyramidLayout, i: usize) -> Self {
        let dst = layout.levels[i];
        let src = layout.levels[i.saturating_sub(1)];
        LevelUniform {
            src_offset: src.offset,
            src_width: src.width,
            src_height: src.height,
            dst_offset: dst.offset,
            dst_width: dst.width,
            dst_height: dst.height,
            _pad: [0; 2],
        }
    }
}

/// Mirrors `struct FillParams` in `wgsl/fill.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct FillParams {
    /// The word written.
    pub value: u32,
    /// Words written.
    pub count: u32,
    /// Padding.
    pub _pad: [u32; 2],
}

mirrored!(FillParams, "fill.wgsl", "FillParams", [value, count]);

/// The raster's counter words (`bins` in `wgsl/raster.wgsl`, an `array<atomic<u32>>`): the
/// bins' bookkeeping, then what the diagnostics report. The `DIAG_*` constants of the WGSL
/// name the offsets of the `rejected_*` and `untextured` words; a test holds them equal.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct RasterCounters {
    /// Triangles binned since the last `bin_args`.
    pub pending_entries: u32,
    /// Large triangles dropped because the bin was full.
    pub dropped: u32,
    /// Binned triangles of the current `raster_large` dispatch.
    pub entries: u32,
    /// Triangles binned this frame, over every raster of the frame.
    pub binned: u32,
    /// Work items (slices past a binned triangle's first) since the last `bin_args`.
    pub pending_items: u32,
    /// Blended fragments in front of the opaque layer 0 behind the last transparency peel
    /// (left out of the image; `DIAG_UNPEELED`).
    pub unpeeled: u32,
    /// Work items of the current `raster_large` dispatch.
    pub items: u32,
    /// Whether the last transparency peel found a fragment (cleared by `peel_dispatch`).
    pub peeled: u32,
    /// Triangles rejected for a vertex index past the vertex count (`DIAG_INDEX`).
    pub rejected_indices: u32,
    /// Triangles rejected for a material id past the material count (`DIAG_MATERIAL`).
    pub rejected_materials: u32,
    /// Triangles rejected for a NaN or infinite position (`DIAG_POSITION`).
    pub rejected_positions: u32,
    /// Triangles drawn untextured: a texture outside the texel buffer, or any texture in a
    /// scene marked textureless (`DIAG_TEXTURE`).
    pub untextured: u32,
}

const _: () = assert!(std::mem::size_of::<RasterCounters>() == 48);
