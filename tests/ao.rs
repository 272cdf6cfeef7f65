//! Two-layer ambient obscurance and its blur, against the CPU references and simple geometry.

mod common;

use common::{
    GBUFFER_FIXTURES, assert_few_differ, corner, corner_surface, gpu, render, shade_fixture, soup,
};
use deep_gbuffer::cpu::{
    ao as cpu_ao, blur as cpu_blur, pyramid as cpu_pyramid, upsample as cpu_upsample,
};
use deep_gbuffer::frame::PyramidLayout;
use deep_gbuffer::plan::PassId;
use deep_gbuffer::settings::downsample_level;
use deep_gbuffer::{AoEstimator, AoSettings, Camera, Scene, Settings};
use glam::Vec3;

/// A tap's pixel comes from floor(position + r cos/sin); the GPU's cos, sin and log2 differ from
/// Rust's in the last bits, so a tap lying within an ulp of a pixel border can land on the
/// neighbouring pixel and change that pixel's AV by up to 2 * intensity / N. The slice
/// estimators' acos, atan2 and arc weights differ the same way, so a direction within an ulp of
/// a sector's centre can fall in the next sector (one sector of 32, at its falloff). Such pixels
/// must stay rare; every other pixel agrees to f32 rounding.
const AO_TOLERANCE: f32 = 1e-4;
const AO_FLIPPED_FRACTION: f64 = 0.01;

const ESTIMATORS: [AoEstimator; 3] = [AoEstimator::Sao, AoEstimator::Horizon, AoEstimator::Bitmask];

fn settings(w: u32, h: u32, ao: AoSettings) -> Settings {
    Settings { timings: false, ao, ..Settings::with_size(w, h) }
}

fn compare_with_cpu(scene: &Scene, camera: &Camera, s: Settings) -> Vec<f32> {
    let (w, h) = (s.width, s.height);
    let ao = s.ao.clone();
    let r = render(scene, camera, s);
    let g = gpu();
    let layout = PyramidLayout::new(w, h);
    let layers = [0, 1].map(|l| r.renderer.read_gbuffer(&g.device, &g.queue, l).unwrap());
    let pyramids = [0, 1].map(|l| {
        let depth: Vec<f32> = layers[l].samples.iter().map(|s| s.depth).collect();
        cpu_pyramid::pyramid(&depth, &layout)
    });
    let p1 = ao.two_layers.then_some(&pyramids[1][..]);
    let expected = cpu_ao::ao(&r.frame, &ao, &layers[0].samples, &layout, &pyramids[0], p1);
    let raw =
        r.renderer.read_f32(&g.device, &g.queue, r.renderer.ao_raw_buffer().unwrap()).unwrap();
    // At a lower resolution, the texels computed against the CPU's, then the upsample of the
    // GPU's own texels against the CPU's.
    let level = downsample_level(ao.downsample) as usize;
    let computed = match r.renderer.ao_low_buffer() {
        Some(low) => r.renderer.read_f32(&g.device, &g.queue, low).unwrap(),
        None => raw.clone(),
    };
    assert_eq!(level > 0, r.renderer.ao_low_buffer().is_some());
    let far = |a: &f32, b: &f32| (a - b).abs() > AO_TOLERANCE;
    let computed = &computed[..expected.len()];
    assert_few_differ(
        computed,
        &expected,
        AO_FLIPPED_FRACTION,
        far,
        "AV against the CPU reference",
    );
    assert!(raw.iter().all(|v| (0.0..=1.0).contains(v)), "AV in [0, 1]");
    if level > 0 {
        let up = cpu_upsample::upsample(w, h, level, 1.0, &layers[0].samples, computed);
        for (p, (a, b)) in raw.iter().zip(&up).enumerate() {
            // Weighted sums of the same four values: f32 rounding only.
            assert!((a - b).abs() <= 1e-5, "upsample at pixel {p}: gpu {a} cpu {b}");
        }
    }

    // The blur, from the GPU's own raw AV, against the CPU blur.
    let actual = r.renderer.read_f32(&g.device, &g.queue, r.renderer.ao_buffer().unwrap()).unwrap();
    let (samples, source) = (&layers[0].samples, &raw[..(w * h) as usize]);
    assert_blurred(&r.frame, samples, ao.blur_radius, source, &actual, "blur");
    actual[..(w * h) as usize].to_vec()
}

/// Asserts that `actual` is the CPU's blur of `source` at `radius` (both directions, the
/// obscurance's plane weight), guided by layer 0's `samples` of `frame`.
fn assert_blurred(
    frame: &deep_gbuffer::frame::FrameUniform,
    samples: &[deep_gbuffer::GSample],
    radius: u32,
    source: &[f32],
    actual: &[f32],
    what: &str,
) {
    let (size, plane) = ((frame.width, frame.height), Some(frame));
    let horizontal = cpu_blur::blur(size, radius, false, plane, samples, source);
    let blurred = cpu_blur::blur(size, radius, true, plane, samples, &horizontal);
    for (p, (a, b)) in actual.iter().zip(&blurred).enumerate() {
        // exp() and the weighted sum differ by f32 rounding only.
        assert!((a - b).abs() <= 1e-4, "{what} at pixel {p}: gpu {a} cpu {b}");
    }
}

/// At half and quarter resolution each computed texel is the full-resolution estimate at the
/// pixel it stands for, and the upsample fills in the rest as the CPU's does.
#[test]
fn lower_resolutions_match_cpu_reference() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    for estimator in [AoEstimator::Sao, AoEstimator::Bitmask] {
        for downsample in [2, 4] {
            let ao = AoSettings {
                estimator,
                downsample,
                radius: 0.4,
                samples: 12,
                ..Default::default()
            };
            // Creases cover fewer texels at a lower resolution: the mean rises a little.
            let av = compare_with_cpu(&scene, &camera, settings(80, 60, ao));
            let mean = av.iter().sum::<f32>() / av.len() as f32;
            assert!(mean < 0.99 && mean > 0.3, "{estimator:?} at 1/{downsample}: {mean}");
        }
    }
}

#[test]
fn cornell_matches_cpu_reference() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    for estimator in ESTIMATORS {
        for two_layers in [true, false] {
            let ao = AoSettings {
                estimator,
                two_layers,
                radius: 0.4,
                samples: 12,
                ..Default::default()
            };
            let av = compare_with_cpu(&scene, &camera, settings(80, 60, ao));
            let mean = av.iter().sum::<f32>() / av.len() as f32;
            assert!(
                mean < 0.98 && mean > 0.3,
                "{estimator:?}: the box is partly obscured ({mean})"
            );
        }
    }
}

#[test]
fn packed_gbuffer_gives_the_same_obscurance() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let ao = AoSettings { radius: 0.4, ..Default::default() };
    let packed = Settings { precision: deep_gbuffer::Precision::Packed, ..settings(64, 48, ao) };
    compare_with_cpu(&scene, &camera, packed);
}

#[test]
fn an_open_flat_plane_is_not_obscured() {
    let plane = [
        [Vec3::new(-50.0, 0.0, -50.0), Vec3::new(-50.0, 0.0, 50.0), Vec3::new(50.0, 0.0, 50.0)],
        [Vec3::new(-50.0, 0.0, -50.0), Vec3::new(50.0, 0.0, 50.0), Vec3::new(50.0, 0.0, -50.0)],
    ];
    let mut scene = soup(&plane, false);
    scene.ambient = Vec3::splat(0.2);
    let camera =
        Camera::perspective(Vec3::new(0.0, 2.0, 4.0), Vec3::new(0.0, 0.0, -2.0), 60.0, 0.1);
    for estimator in ESTIMATORS {
        let ao = AoSettings { estimator, radius: 1.0, ..Default::default() };
        let av = compare_with_cpu(&scene, &camera, settings(64, 48, ao));
        let min = av.iter().copied().fold(1.0, f32::min);
        assert!(av.iter().all(|&v| v == 1.0), "{estimator:?}: min AV {min}");
    }
}

#[test]
fn the_second_layer_adds_the_occlusion_hidden_behind_objects() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let base = AoSettings {
        estimator: AoEstimator::Sao,
        radius: 0.5,
        blur_radius: 0,
        ..Default::default()
    };
    let one = compare_with_cpu(
        &scene,
        &camera,
        settings(80, 60, AoSettings { two_layers: false, ..base.clone() }),
    );
    let two = compare_with_cpu(&scene, &camera, settings(80, 60, base));
    // The two-layer estimator takes the larger contribution per tap: never less occlusion.
    assert!(one.iter().zip(&two).all(|(a, b)| b <= a));
    let changed = one.iter().zip(&two).filter(|(a, b)| **a - **b > 0.02).count();
    assert!(changed > 20, "layer 1 (the boxes' hidden sides) darkens some pixels: {changed}");
}

#[test]
fn invalid_obscurance_settings_are_refused() {
    let g = gpu();
    for (ao, name) in [
        (AoSettings { radius: -1.0, ..Default::default() }, "ao.radius"),
        (AoSettings { samples: 0, ..Default::default() }, "ao.samples"),
        (AoSettings { intensity: f32::NAN, ..Default::default() }, "ao.intensity"),
        (AoSettings { downsample: 3, ..Default::default() }, "ao.downsample"),
        (AoSettings { downsample: 0, ..Default::default() }, "ao.downsample"),
        (AoSettings { extrapolation: -0.5, ..Default::default() }, "ao.extrapolation"),
        (AoSettings { extrapolation: f32::INFINITY, ..Default::default() }, "ao.extrapolation"),
        (AoSettings { blur_radius: 33, ..Default::default() }, "ao.blur_radius"),
        (AoSettings { alpha: 1.0, ..Default::default() }, "ao.alpha"),
        (AoSettings { alpha: f32::NAN, ..Default::default() }, "ao.alpha"),
        (AoSettings { history_slices: 17, ..Default::default() }, "ao.history_slices"),
        (AoSettings { history_tolerance: -1.0, ..Default::default() }, "ao.history_tolerance"),
    ] {
        match deep_gbuffer::Renderer::new(&g.device, &g.queue, settings(8, 8, ao)) {
            Err(deep_gbuffer::Error::InvalidSetting { name: n, .. }) => assert_eq!(n, name),
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("{name} accepted"),
        }
    }
}

/// A right-angle corner (a floor y = 0 meeting a wall x = 0) evaluated in closed form: every
/// pixel's point and normal come from intersecting its camera ray with the two planes, and the
/// estimator is evaluated on that exact geometry (the depth pyramid built from the exact depths).
/// The GPU, from its rasterized G-buffer, must give the same AV; pixels farther than the radius
/// from the wall see only their own plane and stay exactly unobscured, pixels at the crease are
/// obscured.
#[test]
fn a_right_angle_corner_matches_the_closed_form() {
    let size = 4.0;
    let scene = corner(size);
    let camera = Camera::perspective(Vec3::new(2.5, 1.5, 3.5), Vec3::new(0.0, 0.2, 1.5), 60.0, 0.1);
    let ao = AoSettings {
        estimator: AoEstimator::Sao,
        radius: 0.6,
        samples: 16,
        two_layers: false,
        ..Default::default()
    };
    let (w, h) = (64, 48);
    let r = render(&scene, &camera, settings(w, h, ao.clone()));
    let g = gpu();
    let f = &r.frame;

    // The exact surface at every pixel centre.
    let exact: Vec<deep_gbuffer::GSample> =
        corner_surface(f, size).into_iter().map(|(s, _)| s).collect();
    let layout = PyramidLayout::new(w, h);
    let depth: Vec<f32> = exact.iter().map(|s| s.depth).collect();
    let expected =
        cpu_ao::ao(f, &ao, &exact, &layout, &cpu_pyramid::pyramid(&depth, &layout), None);

    let raw =
        r.renderer.read_f32(&g.device, &g.queue, r.renderer.ao_raw_buffer().unwrap()).unwrap();
    // Rasterized depths are interpolated in f32 and differ from the exact ones in the last bits;
    // O is continuous in the tap point, so AV moves by far less than this.
    const EXACT_TOLERANCE: f32 = 1e-3;
    let far = |a: &f32, b: &f32| (a - b).abs() > EXACT_TOLERANCE;
    assert_few_differ(&raw, &expected, AO_FLIPPED_FRACTION, far, "AV against the closed form");
    let mut far = 0;
    let mut crease = Vec::new();
    for (p, s) in exact.iter().enumerate() {
        let world = s.depth > 0.0;
        // Distance to the other plane: the floor point's x, the wall point's y.
        let px = glam::Vec2::new((p as u32 % w) as f32 + 0.5, (p as u32 / w) as f32 + 0.5);
        let at = glam::Mat4::from_cols_array_2d(&f.inv_view)
            .transform_point3(cpu_ao::view_position(f, px, s.depth));
        let gap = if s.normal == Vec3::Y { at.x } else { at.y };
        if world && gap > ao.radius * 1.01 {
            assert_eq!(expected[p], 1.0, "pixel {p}, {gap} from the crease");
            far += 1;
        }
        if world && gap < 0.05 {
            crease.push(expected[p]);
        }
    }
    let crease_mean = crease.iter().sum::<f32>() / crease.len() as f32;
    eprintln!("{far} open pixels, {} at the crease with mean AV {crease_mean}", crease.len());
    assert!(far > 100 && crease.len() > 10);
    assert!(crease_mean < 0.8, "the crease is obscured: mean AV {crease_mean}");
}

/// The stored G-buffers (fixtures/gbuffer/), independent of the rasterizer, with both layers and
/// with layer 0 alone.
#[test]
fn obscurance_of_stored_gbuffers_matches_cpu_reference() {
    for (i, (file, _)) in GBUFFER_FIXTURES.iter().enumerate() {
        for (estimator, two_layers) in ESTIMATORS.into_iter().flat_map(|e| [(e, true), (e, false)])
        {
            // A radius of a few pixels' worth of each scene's scale.
            let radius = [0.4, 1.5][i];
            let ao = AoSettings { estimator, two_layers, radius, ..Default::default() };
            let f = shade_fixture(
                i,
                Settings { timings: false, ao: ao.clone(), ..Settings::default() },
            );
            let g = gpu();
            let layout = PyramidLayout::new(f.layers[0].width, f.layers[0].height);
            let pyramids = [0, 1].map(|l| {
                let depth: Vec<f32> = f.layers[l].samples.iter().map(|s| s.depth).collect();
                cpu_pyramid::pyramid(&depth, &layout)
            });
            let p1 = two_layers.then_some(&pyramids[1][..]);
            let expected =
                cpu_ao::ao(&f.frame, &ao, &f.layers[0].samples, &layout, &pyramids[0], p1);
            let raw = f
                .renderer
                .read_f32(&g.device, &g.queue, f.renderer.ao_raw_buffer().unwrap())
                .unwrap();
            let far = |a: &f32, b: &f32| (a - b).abs() > AO_TOLERANCE;
            assert_few_differ(&raw, &expected, AO_FLIPPED_FRACTION, far, file);
            let min = expected.iter().copied().fold(1.0, f32::min);
            assert!(min < 0.9, "{}: the view holds obscured pixels ({min})", file);
        }
    }
}

/// The slice estimators against the integral itself, in a right-angle corner whose obscurance
/// has a closed form (`common::corner_obscurance`): over the pixels farther than r from the
/// corner's ends, the mean absolute error falls as the taps grow and ends near the blur's and
/// the noise's floor, without a bias. (`sao` is biased here whatever its taps: its 2/N
/// normalisation does not estimate this integral.)
#[test]
fn slice_estimators_converge_to_the_corner_closed_form() {
    let size = 4.0;
    let scene = corner(size);
    let camera = Camera::perspective(Vec3::new(2.5, 1.5, 3.5), Vec3::new(0.0, 0.2, 1.5), 60.0, 0.1);
    let (w, h, r) = (96, 72, 0.6);
    let g = gpu();
    for estimator in [AoEstimator::Horizon, AoEstimator::Bitmask] {
        // From 8 taps on one slice the error already lies at the floor of the blur and the noise
        // (about 0.0035; each step's share takes the falloff between it and the step before, and
        // the steps crowd towards the point), so the coarse end is 4 taps (0.0083 for `horizon`,
        // 0.0086 for `bitmask`, against 0.020 at 2).
        let errors: Vec<(f32, f32)> = [(4, 1), (128, 4)]
            .into_iter()
            .map(|(samples, slices)| {
                let ao = AoSettings { estimator, radius: r, samples, slices, ..Default::default() };
                let rendered = render(&scene, &camera, settings(w, h, ao));
                let av = rendered
                    .renderer
                    .read_f32(&g.device, &g.queue, rendered.renderer.ao_buffer().unwrap())
                    .unwrap();
                let (mut abs, mut bias, mut n) = (0.0, 0.0, 0);
                for (p, (s, point)) in corner_surface(&rendered.frame, size).iter().enumerate() {
                    if s.depth <= 0.0 || !(r..=size - r).contains(&point.z) {
                        continue;
                    }
                    let x = if s.normal == Vec3::Y { point.x } else { point.y };
                    let e = av[p] - (1.0 - common::corner_obscurance(x, r));
                    (abs, bias, n) = (abs + e.abs(), bias + e, n + 1);
                }
                assert!(n > 2000, "{n} pixels");
                (abs / n as f32, bias / n as f32)
            })
            .collect();
        eprintln!("{estimator:?}: (mean |error|, mean error) at 4 and 128 taps: {errors:?}");
        let ((coarse, _), (fine, bias)) = (errors[0], errors[1]);
        assert!(fine < coarse, "{estimator:?}: the error falls as taps grow ({errors:?})");
        assert!(fine <= 0.01 && bias.abs() <= 0.005, "{estimator:?}: {errors:?}");
    }
}

/// The still views' image size.
const STILL_SIZE: (u32, u32) = (48, 36);

/// The Cornell box from its camera at `STILL_SIZE` under `ao`: the device, the camera, the
/// scene's buffers and a renderer that has drawn nothing yet.
fn still_view(
    ao: &AoSettings,
) -> (&'static deep_gbuffer::gpu::Gpu, Camera, deep_gbuffer::SceneBuffers, deep_gbuffer::Renderer) {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let buffers = deep_gbuffer::SceneBuffers::upload(&g.device, &scene).unwrap();
    let (w, h) = STILL_SIZE;
    let renderer =
        deep_gbuffer::Renderer::new(&g.device, &g.queue, settings(w, h, ao.clone())).unwrap();
    (g, scene.camera_or_default(), buffers, renderer)
}

/// One of the renderer's per-pixel f32 buffers at `STILL_SIZE`.
fn read_av(r: &deep_gbuffer::Renderer, b: Option<&deep_gbuffer::wgpu::Buffer>) -> Vec<f32> {
    let g = gpu();
    let (w, h) = STILL_SIZE;
    r.read_f32(&g.device, &g.queue, b.unwrap()).unwrap()[..(w * h) as usize].to_vec()
}

/// One slice of `bitmask` whose turns a still view averages, on the Cornell box.
fn turning_slices() -> AoSettings {
    AoSettings {
        estimator: AoEstimator::Bitmask,
        slices: 1,
        samples: 16,
        radius: 0.4,
        ..Default::default()
    }
}

/// The CPU reference of a still view's turned slices: layer 0 and both layers' depth pyramids
/// as the renderer's last frame drew them.
struct TurnedReference {
    layout: PyramidLayout,
    samples: Vec<deep_gbuffer::GSample>,
    pyramids: [Vec<f32>; 2],
}

impl TurnedReference {
    fn new(renderer: &deep_gbuffer::Renderer) -> TurnedReference {
        let g = gpu();
        let (w, h) = STILL_SIZE;
        let layout = PyramidLayout::new(w, h);
        let layers = [0, 1].map(|l| renderer.read_gbuffer(&g.device, &g.queue, l).unwrap());
        let pyramids = [0, 1].map(|l| {
            let depth: Vec<f32> = layers[l].samples.iter().map(|s| s.depth).collect();
            cpu_pyramid::pyramid(&depth, &layout)
        });
        let [layer0, _] = layers;
        TurnedReference { layout, samples: layer0.samples, pyramids }
    }

    /// Asserts that `raw`, the renderer's AV at `turn`, is the CPU's turned estimate, and that
    /// it differs from `unturned` (the first frame's) on more than a quarter of the pixels.
    fn assert_turned(
        &self,
        renderer: &deep_gbuffer::Renderer,
        ao: &AoSettings,
        turn: u32,
        raw: &[f32],
        unturned: &[f32],
    ) {
        let frame = *renderer.frame_uniform().unwrap();
        let (p0, p1) = (&self.pyramids[0], Some(&self.pyramids[1][..]));
        let expected = cpu_ao::ao_at_turn(&frame, ao, turn, &self.samples, &self.layout, p0, p1);
        let far = |a: &f32, b: &f32| (a - b).abs() > AO_TOLERANCE;
        assert_few_differ(raw, &expected, AO_FLIPPED_FRACTION, far, "turned slices");
        let turned = raw.iter().zip(unturned).filter(|(a, b)| far(a, b)).count();
        assert!(turned * 4 > raw.len(), "the slices turned: {turned} pixels changed");
    }
}

/// The temporal filter (`ao.alpha`): each frame with a history turns the slices (the CPU
/// reference of that turn agrees) and blends its AV with the last frame's filtered AV at the same
/// point; a still view goes on averaging for `still_frames` frames, each weighed as one of the
/// mean once that weighs less than alpha, and then keeps the result; a cut starts afresh.
#[test]
fn the_temporal_filter_averages_turned_slices_until_a_still_view_settles() {
    let ao = AoSettings { alpha: 0.85, still_frames: 16, ..turning_slices() };
    let (g, camera, buffers, mut renderer) = still_view(&ao);
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    let plan = renderer.last_plan().unwrap();
    assert!(plan.contains(&PassId::AoTemporal), "the filter runs with alpha above 0");
    let first_raw = read_av(&renderer, renderer.ao_raw_buffer());
    let mut filtered = read_av(&renderer, renderer.ao_filtered_buffer());
    assert_eq!(filtered, first_raw, "a first frame has no history: its own AV");

    // The frames of a still view: the slices turn, the CPU's turned estimator agrees, and each
    // frame's filtered AV is the mean of the frames so far (the first frame's counting as one).
    let reference = TurnedReference::new(&renderer);
    let mut changes = Vec::new();
    for still in 1..=ao.still_frames {
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        let plan = renderer.last_plan().unwrap();
        assert!(plan.contains(&PassId::Ao), "still frame {still} computes the obscurance");
        assert!(plan.reused.contains(&PassId::Resolve), "still frame {still} keeps its G-buffer");
        let raw = read_av(&renderer, renderer.ao_raw_buffer());
        if still == 1 {
            reference.assert_turned(&renderer, &ao, still, &raw, &first_raw);
        }
        let next = read_av(&renderer, renderer.ao_filtered_buffer());
        let weight = ao.alpha.max(1.0 - 1.0 / (still as f32 + 1.0));
        for p in 0..raw.len() {
            let expected = raw[p] * (1.0 - weight) + filtered[p] * weight;
            assert!((next[p] - expected).abs() < 1e-6, "pixel {p}: {} against {expected}", next[p]);
        }
        changes.push(next.iter().zip(&filtered).map(|(a, b)| (a - b).abs()).sum::<f32>());
        filtered = next;
    }
    eprintln!("summed change of the filtered AV, frame by frame: {changes:?}");
    // The weight rises from alpha (0.85) past the 6th still frame to 1 - 1/17 at the 16th: a
    // frame then moves the mean by 2.5 times less.
    let (early, late) =
        (changes[..4].iter().sum::<f32>() / 4.0, changes[12..].iter().sum::<f32>() / 4.0);
    assert!(late < 0.6 * early, "a still view settles: {changes:?}");

    // Past still_frames the view keeps its obscurance: the filtered AV stays the last one.
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    let plan = renderer.last_plan().unwrap();
    assert!(plan.reused.contains(&PassId::Ao) && !plan.contains(&PassId::AoTemporal));
    assert_eq!(read_av(&renderer, renderer.ao_filtered_buffer()), filtered, "the kept AV");

    // A cut: the next frame is a first frame again.
    renderer.reset_history();
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    assert_eq!(
        read_av(&renderer, renderer.ao_filtered_buffer()),
        first_raw,
        "the history is dropped"
    );
}

/// Without the temporal filter (the default) each frame of a moving view stands alone, and a
/// still view averages its obscurance: every still frame turns the slices, the AV the blur reads
/// is the mean of the still frames so far, and the blur narrows as the mean grows
/// (`AoSettings::blur_radius_for`); after `still_frames` frames the view keeps it.
#[test]
fn a_still_view_averages_its_obscurance_without_the_filter() {
    let ao = AoSettings { still_frames: 8, ..turning_slices() };
    assert_eq!(ao.alpha, 0.0, "the default has no temporal filter");
    let (g, camera, buffers, mut renderer) = still_view(&ao);
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    let plan = renderer.last_plan().unwrap();
    assert!(!plan.contains(&PassId::AoTemporal), "a first frame stands alone");
    assert!(renderer.ao_filtered_buffer().is_none());
    let first_raw = read_av(&renderer, renderer.ao_raw_buffer());

    let reference = TurnedReference::new(&renderer);
    let mut sum = vec![0.0f64; first_raw.len()];
    let mut mean = Vec::new();
    for still in 1..=ao.still_frames {
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        let plan = renderer.last_plan().unwrap();
        assert!(plan.contains(&PassId::Ao), "still frame {still} computes the obscurance");
        assert!(plan.contains(&PassId::AoTemporal), "still frame {still} averages it");
        assert!(plan.reused.contains(&PassId::Resolve), "still frame {still} keeps its G-buffer");
        let raw = read_av(&renderer, renderer.ao_raw_buffer());
        reference.assert_turned(&renderer, &ao, still, &raw, &first_raw);
        for (s, v) in sum.iter_mut().zip(&raw) {
            *s += f64::from(*v);
        }
        mean = read_av(&renderer, renderer.ao_filtered_buffer());
        for (p, (m, s)) in mean.iter().zip(&sum).enumerate() {
            let expected = s / f64::from(still);
            // A running mean in f32, one rounding a frame.
            assert!((f64::from(*m) - expected).abs() < 1e-5, "frame {still}, pixel {p}: {m}");
        }
    }
    // The blur over the mean of 8 frames: radius 4 / sqrt(8), rounded, 1.
    let radius = ao.blur_radius_for(ao.still_frames as f32);
    assert_eq!(radius, 1);
    let frame = *renderer.frame_uniform().unwrap();
    let actual = read_av(&renderer, renderer.ao_buffer());
    assert_blurred(&frame, &reference.samples, radius, &mean, &actual, "narrowed blur");

    // Past still_frames the view keeps its obscurance.
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    let plan = renderer.last_plan().unwrap();
    assert!(plan.reused.contains(&PassId::Ao) && !plan.contains(&PassId::AoTemporal));
    assert_eq!(read_av(&renderer, renderer.ao_buffer()), actual, "the kept AV");

    // A moved camera: a frame alone again, its AV the raw one under the whole blur.
    let moved = Camera { eye: camera.eye + Vec3::new(0.2, 0.0, 0.0), ..camera };
    renderer.render(&g.device, &g.queue, &buffers, &moved).unwrap();
    let plan = renderer.last_plan().unwrap();
    assert!(plan.contains(&PassId::Ao) && !plan.contains(&PassId::AoTemporal));
    assert!(renderer.ao_filtered_buffer().is_none(), "a moving frame keeps no history");
    let raw = read_av(&renderer, renderer.ao_raw_buffer());
    let frame = *renderer.frame_uniform().unwrap();
    let samples = &TurnedReference::new(&renderer).samples;
    let actual = read_av(&renderer, renderer.ao_buffer());
    assert_blurred(&frame, samples, ao.blur_radius, &raw, &actual, "moved, blur");
}
