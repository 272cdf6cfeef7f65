//! Screen-space radiosity: the first frame against the CPU reference, temporal convergence on a
//! static camera, a camera cut that resets the history, and non-finite input that never enters
//! the history.

mod common;

use common::{GBUFFER_FIXTURES, assert_few_differ, gpu, read4, render_frames, shade_fixture};
use deep_gbuffer::cpu::radiosity as cpu;
use deep_gbuffer::frame::{PyramidLayout, RadiosityUniform, SourceTexel, pack_rgb9e5};
use deep_gbuffer::settings::downsample_level;
use deep_gbuffer::{
    Boost, Camera, Normalization, RadiosityEstimator, RadiositySettings, Renderer, Scene,
    SceneBuffers, Settings,
};
use glam::Vec4;

/// As for obscurance: a tap within an ulp of a pixel border may land on the neighbouring pixel on
/// one side and not the other (GPU cos/sin), changing that pixel's sum by one tap. Such pixels
/// must stay rare; the rest agree to f32 rounding of the sums.
const RADIOSITY_TOLERANCE: f32 = 1e-3;
const RADIOSITY_FLIPPED_FRACTION: f64 = 0.02;

/// The gather alone: the off-screen light, which adds to it, has its own tests
/// (`tests/offscreen.rs`).
fn settings(w: u32, h: u32) -> Settings {
    let mut s = Settings { timings: false, ..Settings::with_size(w, h) };
    s.radiosity.offscreen = false;
    s
}

#[test]
fn first_frame_matches_cpu_reference() {
    first_frame_against_cpu(RadiositySettings::default());
    first_frame_against_cpu(RadiositySettings {
        estimator: RadiosityEstimator::Spiral,
        ..Default::default()
    });
    // The slices' plain sum and the strongest extrapolation from every other step.
    for extrapolation in [0.0, 2.0] {
        first_frame_against_cpu(RadiositySettings { extrapolation, ..Default::default() });
    }
    // Every tap beyond a pixel reads a coarser level of the gather source.
    for estimator in [RadiosityEstimator::Slices, RadiosityEstimator::Spiral] {
        first_frame_against_cpu(RadiositySettings {
            estimator,
            mip_offset: 0,
            ..Default::default()
        });
    }
}

/// At half and quarter resolution each gathered texel is the full-resolution gather at the pixel
/// it stands for, and the upsample fills in the rest as the CPU's does.
#[test]
fn lower_resolutions_match_cpu_reference() {
    for estimator in [RadiosityEstimator::Slices, RadiosityEstimator::Spiral] {
        for downsample in [2, 4] {
            first_frame_against_cpu(RadiositySettings {
                estimator,
                downsample,
                ..Default::default()
            });
        }
    }
}

/// The paper's 2 pi / M normalisation and a colour boost, against the same CPU reference (with a
/// damping that keeps the feedback gain 2 x 0.2 x 2 below 1).
#[test]
fn paper_normalization_and_boost_match_cpu_reference() {
    first_frame_against_cpu(RadiositySettings {
        estimator: RadiosityEstimator::Spiral,
        normalization: Normalization::Paper,
        boost: Boost { unsaturated: 1.0, saturated: 2.0 },
        damping: 0.2,
        ..Default::default()
    });
}

/// Settings whose feedback could grow without bound are refused, naming the gain.
#[test]
fn diverging_feedback_is_refused() {
    for (normalization, damping, boost) in [
        (Normalization::Cosine, 1.0, 1.0),
        (Normalization::Cosine, 0.8, 4.0),
        (Normalization::Paper, 0.8, 1.0),
        (Normalization::Paper, 0.3, 2.0),
    ] {
        let s = RadiositySettings {
            estimator: RadiosityEstimator::Spiral,
            normalization,
            damping,
            boost: Boost { unsaturated: boost, saturated: boost },
            ..Default::default()
        };
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("gain"), "{normalization:?} {damping} {boost}: {e}");
    }
    let bounded = RadiositySettings {
        estimator: RadiosityEstimator::Spiral,
        normalization: Normalization::Paper,
        damping: 0.45,
        ..Default::default()
    };
    bounded.validate().unwrap();
}

/// Either filter weight outside [0, 1) is refused, naming its field.
#[test]
fn filter_weights_outside_the_unit_interval_are_refused() {
    for (s, name) in [
        (RadiositySettings { alpha: 1.0, ..Default::default() }, "radiosity.alpha"),
        (RadiositySettings { alpha: -0.1, ..Default::default() }, "radiosity.alpha"),
        (RadiositySettings { still_alpha: 1.0, ..Default::default() }, "radiosity.still_alpha"),
        (
            RadiositySettings { still_alpha: f32::NAN, ..Default::default() },
            "radiosity.still_alpha",
        ),
    ] {
        match s.validate() {
            Err(deep_gbuffer::Error::InvalidSetting { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {other:?}"),
        }
    }
    RadiositySettings { still_alpha: 0.0, ..Default::default() }.validate().unwrap();
}

/// The gather source `buffer` (a [`SourceTexel`] per texel) read back.
fn read_source(buffer: &deep_gbuffer::wgpu::Buffer) -> Vec<SourceTexel> {
    let g = gpu();
    bytemuck::pod_collect_to_vec(
        &deep_gbuffer::gpu::read_buffer(&g.device, &g.queue, buffer).unwrap(),
    )
}

fn first_frame_against_cpu(radiosity: RadiositySettings) {
    let radiosity = RadiositySettings { offscreen: false, ..radiosity };
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let (w, h) = (64, 48);
    let settings = Settings { radiosity: radiosity.clone(), ..settings(w, h) };
    let r = render_frames(&scene, &[scene.camera_or_default()], settings);
    let g = gpu();
    let layers = [0, 1].map(|l| r.renderer.read_gbuffer(&g.device, &g.queue, l).unwrap().samples);
    let raw =
        first_frame_matches(&r.renderer, &r.frame, [&layers[0], &layers[1]], &radiosity, "cornell");
    let lit = raw.iter().filter(|e| e.truncate().max_element() > 0.01).count();
    assert!(lit > raw.len() / 2, "the box receives indirect light ({lit})");
}

/// With the history a frame whose view moved gathers `history_slices` of the slices, each with
/// the steps a side all of them take (the layer-1 gather too); a first frame, a still view,
/// slices that do not turn or the spiral take them all. A moved second frame's gather against
/// the CPU's with that frame's taps, and not with all of them.
#[test]
fn a_frame_with_history_gathers_its_history_slices() {
    // The gather alone, as `settings` sets it.
    let radiosity = RadiositySettings { history_slices: 1, offscreen: false, ..Default::default() };
    assert_eq!(radiosity.frame_taps(false, 0), (2, 32, 8), "a first frame takes every slice");
    assert_eq!(radiosity.frame_taps(true, 0), (1, 16, 4), "one slice of two, 8 and 2 steps a side");
    assert_eq!(radiosity.frame_taps(true, 1), (2, 32, 8), "a still view takes every slice");
    let fixed = RadiositySettings { jitter: false, ..radiosity.clone() };
    assert_eq!(fixed.frame_taps(true, 0), (2, 32, 8), "slices that do not turn are all taken");
    let spiral = RadiositySettings { estimator: RadiosityEstimator::Spiral, ..radiosity.clone() };
    assert_eq!(spiral.frame_taps(true, 0), (2, 32, 8), "the spiral has no slices");
    let four = RadiositySettings { slices: 4, samples: 64, history_slices: 3, ..radiosity.clone() };
    assert_eq!(four.frame_taps(true, 0), (3, 48, 6));
    for all in [0, 2, 5] {
        let r = RadiositySettings { history_slices: all, ..radiosity.clone() };
        assert_eq!(r.frame_taps(true, 0), (2, 32, 8), "{all}: every slice");
    }
    let too_many = RadiositySettings { history_slices: 17, ..radiosity.clone() };
    let e = too_many.validate().unwrap_err().to_string();
    assert!(e.contains("radiosity.history_slices"), "{e}");

    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let (w, h) = (64, 48);
    let camera = scene.camera_or_default();
    let settings = Settings { radiosity: radiosity.clone(), ..settings(w, h) };
    let r = render_frames(&scene, &[camera.clone(), camera.orbited(0.5)], settings);
    let g = gpu();
    let layers = [0, 1].map(|l| r.renderer.read_gbuffer(&g.device, &g.queue, l).unwrap().samples);
    let buffers = r.renderer.radiosity_buffers().expect("radiosity runs");
    let source = read_source(buffers.source);
    let raw = read4(&r.renderer, buffers.gathered);
    let layout = PyramidLayout::new(w, h);
    let far = |a: &Vec4, e: &Vec4| {
        (*a - *e).abs().max_element() > RADIOSITY_TOLERANCE * e.max_element().max(1.0)
    };
    // The second frame has the history (where its points were seen) and the slices' first turn.
    let gather = |settings: &RadiositySettings| {
        let uniform = RadiosityUniform::new(settings, &layout, (true, 0), 1);
        cpu::gather(&r.frame, &uniform, [&layers[0], &layers[1]], &source, &layout, (0, 0))
    };
    let expected = gather(&radiosity);
    assert_few_differ(&raw, &expected, RADIOSITY_FLIPPED_FRACTION, far, "one slice of two");
    let every = gather(&RadiositySettings { history_slices: 0, ..radiosity.clone() });
    let differ = raw.iter().zip(&every).filter(|(a, e)| far(a, e)).count();
    eprintln!("{differ} of {} pixels differ from the gather over both slices", raw.len());
    assert!(differ > raw.len() / 4, "{differ} of {} differ from both slices' gather", raw.len());
}

/// The first frame of `renderer` (no history) against the CPU reference computed on `layers`:
/// the gather source (depths, and B of layer 0 from the GPU's own direct radiance), its levels,
/// then the gather. Returns the GPU's gathered irradiance and confidence.
fn first_frame_matches(
    renderer: &Renderer,
    frame: &deep_gbuffer::frame::FrameUniform,
    layers: [&[deep_gbuffer::GSample]; 2],
    radiosity: &RadiositySettings,
    what: &str,
) -> Vec<Vec4> {
    let g = gpu();
    let deep_gbuffer::RadiosityBuffers { source, low, gathered: raw, layer1, .. } =
        renderer.radiosity_buffers().expect("radiosity runs");
    let source = read_source(source);
    let raw = read4(renderer, raw);
    let layout = PyramidLayout::new(frame.width, frame.height);
    let pixels = layers[0].len();
    // B without history is the boosted Lambertian part of the direct light + emission (layer 0's
    // checked in tests/direct.rs), held in RGB9E5: within 2^-9 of a texel's largest channel (the
    // format's rounding) besides f32 rounding.
    let uniform = RadiosityUniform::new(radiosity, &layout, (false, 0), 0);
    let diffuse0 = renderer.read_rgb(&g.device, &g.queue, renderer.diffuse_buffer(0)).unwrap();
    let expected_b0 = cpu::feedback_without_history(&uniform, layers[0], &diffuse0);
    for (p, (t, e)) in source[..pixels].iter().zip(&expected_b0).enumerate() {
        let a = t.radiance(0);
        assert!(
            (a - *e).abs().max_element()
                <= e.max_element() / 512.0 + 1e-5 * e.max_element().max(1.0),
            "{what}: B {a} vs {e}"
        );
        for (l, layer) in layers.iter().enumerate() {
            let depth = layer[p].depth;
            assert_eq!(t.depth(l).to_bits(), depth.to_bits(), "{what}: depth of layer {l}");
            // The normal in 2x16 snorm (a few 1e-5 off); the far side's light without history is
            // the emission.
            let normal = deep_gbuffer::cpu::frame::mat_mul(
                &frame.view,
                layer[p].normal.extend(0.0).to_array(),
            )
            .truncate();
            assert!(
                depth.is_nan()
                    || depth <= 0.0
                    || (t.normal(l) - normal).abs().max_element() <= 1e-3,
                "{what}: normal of layer {l}: {} vs {normal}",
                t.normal(l)
            );
            let emission = if depth > 0.0 { layer[p].emissive } else { glam::Vec3::ZERO };
            assert_eq!(t.hidden[l], pack_rgb9e5(emission), "{what}: far side of layer {l}");
        }
    }
    // The levels above pick texels of the GPU's own level 0, exactly.
    let levels = deep_gbuffer::cpu::pyramid::rotated_grid(&source[..pixels], &layout);
    assert!(levels == source, "{what}: the gather source's levels against the CPU's");
    // At a lower resolution the texels the gather computed against the CPU's, then the upsample
    // of the GPU's own texels against the CPU's.
    let level = downsample_level(radiosity.downsample) as usize;
    let expected = cpu::gather(frame, &uniform, layers, &source, &layout, (level, 0));
    let computed = match low {
        Some(low) => read4(renderer, low),
        None => raw.clone(),
    };
    assert_eq!(level > 0, low.is_some());
    let computed = &computed[..expected.len()];
    let far = |a: &Vec4, e: &Vec4| {
        (*a - *e).abs().max_element() > RADIOSITY_TOLERANCE * e.max_element().max(1.0)
    };
    let gather = format!("{what}: the gather against the CPU's");
    assert_few_differ(computed, &expected, RADIOSITY_FLIPPED_FRACTION, far, &gather);
    if level > 0 {
        let (w, h) = (frame.width, frame.height);
        let up =
            deep_gbuffer::cpu::upsample::upsample(w, h, level, Vec4::ZERO, layers[0], computed);
        for (p, (a, e)) in raw.iter().zip(&up).enumerate() {
            // Weighted sums of the same four values: f32 rounding only.
            let close = (*a - *e).abs().max_element() <= 1e-5 * e.max_element().max(1.0);
            assert!(close, "{what}: upsample at pixel {p}: gpu {a} cpu {e}");
        }
    }
    assert!(raw.iter().all(|e| e.is_finite() && e.min_element() >= 0.0 && e.w <= 1.0));

    // The layer-1 gather at the same texels, kept as E / c and the point's depth.
    let layer1 = read4(renderer, layer1.expect("the layer-1 gather runs"));
    let (w, _) = deep_gbuffer::cpu::pyramid::mip_size(frame.width, frame.height, level);
    let expected: Vec<Vec4> = cpu::gather(frame, &uniform, layers, &source, &layout, (level, 1))
        .iter()
        .enumerate()
        .map(|(t, g)| {
            let (x, y) = deep_gbuffer::cpu::pyramid::mip_origin(
                frame.width,
                frame.height,
                level,
                (t as u32 % w, t as u32 / w),
            );
            cpu::layer1_record(*g, layers[1][(y * frame.width + x) as usize].depth)
        })
        .collect();
    let computed = &layer1[..expected.len()];
    let far = |a: &Vec4, e: &Vec4| {
        a.w != e.w
            || (a.truncate() - e.truncate()).abs().max_element()
                > RADIOSITY_TOLERANCE * e.truncate().max_element().max(1.0)
    };
    let gather1 = format!("{what}: the layer-1 gather against the CPU's");
    assert_few_differ(computed, &expected, RADIOSITY_FLIPPED_FRACTION, far, &gather1);
    let found = expected.iter().filter(|e| e.w > 0.0 && e.truncate().max_element() > 0.01).count();
    assert!(found > 0, "{what}: layer 1 receives light");
    raw
}

/// The Cornell box's camera and its scene uploaded to the test device.
fn cornell_uploaded() -> (Camera, SceneBuffers) {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    (scene.camera_or_default(), SceneBuffers::upload(&gpu().device, &scene).unwrap())
}

/// The next frame's layer 1 reflects what the layer-1 gather found at its point: B1 = boost D1 +
/// boost delta (1 - metallic) rho / pi E1 + Le1 and H1 its reflected part, E1 the last frame's
/// layer-1 record where the point is the same (a static camera: everywhere). Without the layer-1
/// gather layer 1 sends its direct light and emission alone.
#[test]
fn layer1_reflects_the_last_frames_layer1_gather() {
    let g = gpu();
    let (camera, buffers) = cornell_uploaded();
    for layer1_samples in [8, 0] {
        let radiosity = RadiositySettings { layer1_samples, ..Default::default() };
        let s = Settings { radiosity: radiosity.clone(), ..settings(64, 48) };
        let mut renderer = Renderer::new(&g.device, &g.queue, s).unwrap();
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        let plan = renderer.last_plan().expect("a frame ran").clone();
        let runs = plan.contains(&deep_gbuffer::PassId::RadiosityLayer1);
        assert_eq!(runs, layer1_samples > 0, "{}", plan);
        let record = renderer.radiosity_buffers().unwrap().layer1.map(|b| read4(&renderer, b));
        assert_eq!(record.is_some(), runs);
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();

        let layer1 = renderer.read_gbuffer(&g.device, &g.queue, 1).unwrap().samples;
        let diffuse1 = renderer.read_rgb(&g.device, &g.queue, renderer.diffuse_buffer(1)).unwrap();
        let source = read_source(renderer.radiosity_buffers().unwrap().source);
        let layout = PyramidLayout::new(64, 48);
        let uniform = RadiosityUniform::new(&radiosity, &layout, (true, 0), 1);
        let (mut points, mut bounced) = (0, 0);
        for (p, s1) in layer1.iter().enumerate() {
            if s1.depth.is_nan() || s1.depth <= 0.0 {
                continue;
            }
            points += 1;
            let e = match &record {
                Some(r) if (r[p].w - s1.depth).abs() <= radiosity.history_tolerance => {
                    r[p].truncate()
                }
                _ => glam::Vec3::ZERO,
            };
            let boost = cpu::boost(&uniform, s1.base_color);
            let reflected = cpu::reflected(&uniform, s1, boost, e);
            let b = boost * diffuse1[p] + reflected;
            // RGB9E5: within 2^-9 of a texel's largest channel, besides f32 rounding.
            let close = |a: glam::Vec3, e: glam::Vec3| {
                (a - e).abs().max_element()
                    <= e.max_element() / 512.0 + 1e-5 * e.max_element().max(1.0)
            };
            let (got_b, got_h) = (source[p].radiance(1), source[p].hidden(1));
            assert!(close(got_b, b), "{layer1_samples} taps, pixel {p}: B1 {got_b} vs {b}");
            assert!(close(got_h, reflected), "pixel {p}: H1 {got_h} vs {reflected}");
            if (reflected - s1.emissive).max_element() > 0.05 * b.max_element() {
                bounced += 1;
            }
        }
        eprintln!("{layer1_samples} taps: {bounced} of {points} layer-1 points reflect a bounce");
        if layer1_samples > 0 {
            assert!(bounced > points / 4, "{bounced} of {points} layer-1 points reflect a bounce");
        } else {
            assert_eq!(bounced, 0);
        }
    }
}

/// The layer-1 gather runs at the texels that hold a layer-1 point: after the camera moves, the
/// texels whose pixel held one on the last frame and holds none now read 0 (the next frame's
/// feedback must not find the old point's light there), and every texel that holds one reads
/// its point's depth.
#[test]
fn the_layer1_gather_follows_the_points_of_layer1() {
    let g = gpu();
    let (camera, buffers) = cornell_uploaded();
    let mut renderer = Renderer::new(&g.device, &g.queue, settings(64, 48)).unwrap();
    let moved =
        deep_gbuffer::Camera { eye: camera.eye + glam::Vec3::new(0.6, -0.3, 0.4), ..camera };
    // Pixels that held a layer-1 point on the frame before and hold none now.
    let (mut before, mut emptied) = (Vec::new(), 0);
    for (frame, camera) in [camera.clone(), moved, camera].iter().enumerate() {
        renderer.render(&g.device, &g.queue, &buffers, camera).unwrap();
        let layer1 = renderer.read_gbuffer(&g.device, &g.queue, 1).unwrap().samples;
        let record = read4(&renderer, renderer.radiosity_buffers().unwrap().layer1.unwrap());
        for (p, s1) in layer1.iter().enumerate() {
            let depth = if s1.depth > 0.0 { s1.depth } else { 0.0 };
            assert_eq!(record[p].w, depth, "frame {frame}, pixel {p}: {}", record[p]);
            if depth == 0.0 {
                assert_eq!(record[p], Vec4::ZERO, "frame {frame}, pixel {p}");
            }
        }
        let held: Vec<bool> = layer1.iter().map(|s| s.depth > 0.0).collect();
        emptied += before.iter().zip(&held).filter(|&(b, h)| *b && !*h).count();
        before = held;
    }
    assert!(emptied > 0, "no pixel lost its layer-1 point between frames");
}

/// On a static camera, with the spiral held still, the multi-bounce feedback and the temporal
/// filter converge to a fixed point: the frame-to-frame change dies away.
#[test]
fn a_static_camera_converges_and_a_cut_resets() {
    let g = gpu();
    let (camera, buffers) = cornell_uploaded();
    let radiosity = deep_gbuffer::RadiositySettings { jitter: false, ..Default::default() };
    let shadows = deep_gbuffer::ShadowSettings { enabled: false, ..Default::default() };
    let mut renderer =
        Renderer::new(&g.device, &g.queue, Settings { radiosity, shadows, ..settings(32, 24) })
            .unwrap();
    let mut frames = Vec::new();
    for _ in 0..120 {
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        frames.push(read4(&renderer, renderer.radiosity_buffers().unwrap().filtered));
    }
    let change = |a: &[Vec4], b: &[Vec4]| {
        a.iter().zip(b).map(|(x, y)| (*x - *y).truncate().abs().max_element()).fold(0.0, f32::max)
    };
    let mean =
        |f: &[Vec4]| f.iter().map(|v| v.truncate().element_sum()).sum::<f32>() / f.len() as f32;
    let early = change(&frames[1], &frames[2]);
    let late = change(&frames[118], &frames[119]);
    eprintln!(
        "largest per-pixel change: {early} (frame 2), {late} (frame 120); mean {} -> {}",
        mean(&frames[0]),
        mean(&frames[119])
    );
    assert!(mean(&frames[119]) > mean(&frames[0]) * 1.05, "later bounces add light");
    assert!(late < 1e-3 * early.max(1e-6) + 1e-4, "converged: {early} early, {late} late");

    // A camera cut: the history is dropped, the next frame is a first frame again.
    renderer.reset_history();
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    let after_cut = read4(&renderer, renderer.radiosity_buffers().unwrap().filtered);
    assert_eq!(after_cut, frames[0], "after a cut the history does not leak into the frame");
}

/// A slanted surface keeps its history when the camera turns: the pixel centres around where a
/// point was lie up to a pixel and a half from it, and a surface seen at a slant runs on in
/// depth by its slope over that distance, more than the history's 1 cm at this size. (That a
/// surface uncovered beside one that moved away takes none is `temporal_cut_and_an_object_moving_away`
/// in tests/hard_cases.rs.)
#[test]
fn slanted_surfaces_keep_their_history_under_a_turn() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let turned = camera.orbited(1.0);
    let r = render_frames(&scene, &[camera, turned], settings(64, 48));
    let buffers = r.renderer.radiosity_buffers().expect("radiosity runs");
    let (raw, filtered) =
        (read4(&r.renderer, buffers.gathered), read4(&r.renderer, buffers.filtered));
    let g = gpu();
    let layer0 = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap().samples;
    let surface: Vec<usize> = (0..layer0.len()).filter(|&p| layer0[p].depth > 0.0).collect();
    // Without history the filter passes the frame's own gather on unchanged.
    let afresh = surface.iter().filter(|&&p| filtered[p] == raw[p]).count();
    eprintln!("{afresh} of {} surface pixels start afresh after a 1 degree turn", surface.len());
    // 1 of 2334 pixels here (the points beside the blocks' edges that were hidden find a pixel
    // of their own surface among the four the history is read from; 52 when it was read from
    // the nearest alone); with 1 cm from the point's own depth, 953 (the floor, the ceiling
    // and the side walls).
    assert!(afresh * 20 < surface.len(), "{afresh} of {} start afresh", surface.len());
}

/// A material with a NaN emission (possible only through imported buffers, which the CPU does not
/// check) must not poison the history: after many frames no output, history or image value is NaN.
#[test]
fn nan_input_never_enters_the_history() {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let uploaded = SceneBuffers::upload(&g.device, &scene).unwrap();
    let mut b = uploaded.buffers().clone();
    let mut materials: Vec<deep_gbuffer::GpuMaterial> = bytemuck::pod_collect_to_vec(
        &deep_gbuffer::gpu::read_buffer(&g.device, &g.queue, &b.materials).unwrap()
            [..scene.materials.len() * std::mem::size_of::<deep_gbuffer::GpuMaterial>()],
    );
    materials[0].emissive = [f32::NAN, 1.0, f32::INFINITY];
    b.materials = deep_gbuffer::gpu::storage_buffer_init(
        &g.device,
        "test.materials",
        bytemuck::cast_slice(&materials),
    );
    let buffers = SceneBuffers::import(&g.device, b, uploaded.info().clone()).unwrap();
    // Obscurance and shadows off: 1000 frames of what matters here.
    let s = Settings {
        ao: deep_gbuffer::AoSettings { enabled: false, ..Default::default() },
        shadows: deep_gbuffer::ShadowSettings { enabled: false, ..Default::default() },
        ..settings(12, 9)
    };
    let mut renderer = Renderer::new(&g.device, &g.queue, s).unwrap();
    let camera = scene.camera_or_default();
    for _ in 0..1000 {
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    }
    let deep_gbuffer::RadiosityBuffers {
        source,
        gathered: raw,
        filtered: history,
        irradiance: blurred,
        ..
    } = renderer.radiosity_buffers().unwrap();
    let source = read_source(source);
    assert!(
        source.iter().all(|t| (0..2).all(|l| t.radiance(l).is_finite() && t.depth(l).is_finite())),
        "the gather source holds a non-finite value"
    );
    for (name, buffer) in [("raw", raw), ("history", history), ("blurred", blurred)] {
        let values = read4(&renderer, buffer);
        assert!(values.iter().all(|v| v.is_finite()), "{name} holds a non-finite value");
    }
    // The resolve reads a NaN emission as 0 and an infinite one as MAX_RADIANCE: the image is
    // finite everywhere, where the material is seen too.
    let hdr = renderer.read_rgb(&g.device, &g.queue, renderer.hdr_buffer()).unwrap();
    assert!(hdr.iter().all(|c| c.is_finite()), "the image holds a non-finite value");
}

/// Energy conservation: inside a closed box whose walls all emit Le and reflect rho, the true
/// irradiance is the same everywhere, E = pi Le / (1 - delta rho) (the bounces sum to a
/// geometric series, each damped by delta). With boost = 1 the multi-bounce estimate of the
/// radiance the gather sees converges to it (the irradiance found over the share of the
/// hemisphere it covers, E / c) and no pixel ever exceeds it, in any frame, beyond the precision
/// B is stored in.
#[test]
fn a_closed_white_box_converges_to_the_closed_form_and_never_exceeds_it() {
    let g = gpu();
    let (rho, le) = (0.5, 1.0);
    let scene = common::white_box(rho, le);
    let radiosity = RadiositySettings { jitter: false, ..Default::default() };
    let closed_form = std::f32::consts::PI * le / (1.0 - radiosity.damping * rho);
    let precision = 2f32.powi(-9) / (1.0 - radiosity.damping * rho);
    let buffers = SceneBuffers::upload(&g.device, &scene).unwrap();
    let camera = deep_gbuffer::Camera::perspective(
        glam::Vec3::new(0.3, 0.2, 0.6),
        glam::Vec3::new(-1.0, -0.8, -1.0),
        70.0,
        0.01,
    );
    let mut renderer =
        Renderer::new(&g.device, &g.queue, Settings { radiosity, ..settings(32, 24) }).unwrap();
    // The fixed-point iteration contracts by alpha + (1 - alpha) delta rho = 0.91 per frame:
    // 200 frames leave a residual of 0.91^200 ~ 6e-9.
    // Float sums of equal values weighted by their cosines round to within a few ulps. The gather
    // source holds B in RGB9E5, rounded to within 2^-9 of its value (rounding to nearest: up or
    // down); each bounce rounds again, so the iteration x = round(Le + delta rho x / pi) settles
    // anywhere within 2^-9 / (1 - delta rho) of the closed form, and no closer.
    let bound = closed_form * (1.0 + 1e-5 + precision);
    let mut last = Vec::new();
    for frame in 0..200 {
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        let deep_gbuffer::RadiosityBuffers {
            gathered: raw,
            filtered: history,
            irradiance: blurred,
            ..
        } = renderer.radiosity_buffers().unwrap();
        for (name, buffer) in [("raw", raw), ("history", history), ("blurred", blurred)] {
            let values = read4(&renderer, buffer);
            // The irradiance found, and spread over the whole hemisphere (E / c, which the
            // next bounce reads).
            let max = values.iter().map(|v| v.truncate().max_element()).fold(0.0, f32::max);
            assert!(max <= bound, "frame {frame}: {name} reaches {max} > {closed_form}");
            let spread = values.iter().filter(|v| v.w > 0.0).map(|v| v.x / v.w);
            let max = spread.fold(0.0, f32::max);
            assert!(max <= bound, "frame {frame}: {name} spread reaches {max} > {closed_form}");
        }
        if frame == 199 {
            last = read4(&renderer, history);
        }
    }
    // What the gather sees, spread over the hemisphere: pi times the mean radiance it found.
    let counted: Vec<f32> = last.iter().filter(|v| v.w > 0.0).map(|v| v.x / v.w).collect();
    let within = (1e-3 + precision) * closed_form;
    let close = counted.iter().filter(|v| (*v - closed_form).abs() <= within).count();
    let mean = counted.iter().sum::<f32>() / counted.len() as f32;
    eprintln!(
        "closed form {closed_form}: {close} of {} pixels within {within}, mean {mean}",
        counted.len()
    );
    // A pixel on an open stretch of wall counts no tap (every tap lies in its own plane): it has
    // no estimate (confidence 0; the composite falls back to the ambient term there), and its B
    // carries no indirect light, so the few pixels that tap it converge a little below the
    // closed form. Neither can push a pixel above it.
    assert!(counted.len() > last.len() * 8 / 10, "most pixels count some taps");
    assert!(close * 10 >= counted.len() * 9, "nine in ten counted pixels reach the closed form");
    assert!((mean - closed_form).abs() <= 0.01 * closed_form, "mean {mean}");
}

/// The stored G-buffers (fixtures/gbuffer/), independent of the rasterizer: the first frame's
/// feedback and gather.
#[test]
fn radiosity_of_stored_gbuffers_matches_cpu_reference() {
    for (i, (file, _)) in GBUFFER_FIXTURES.iter().enumerate() {
        let f = shade_fixture(i, settings(0, 0));
        let layers = [&f.layers[0].samples[..], &f.layers[1].samples[..]];
        let raw =
            first_frame_matches(&f.renderer, &f.frame, layers, &RadiositySettings::default(), file);
        assert!(raw.iter().any(|e| e.truncate().max_element() > 0.01), "{file} is lit");
    }
}

/// A view that stands still stops flickering: once its bounces have settled
/// (`RadiositySettings::settle_frames`), the temporal filter averages the frames since
/// (`history_weight`), so the gathered light changes less and less from one frame to the next,
/// where the exponential filter keeps the turned slices' noise; a camera move starts over.
#[test]
fn a_still_view_stops_flickering() {
    let r = RadiositySettings::default();
    let settle = r.settle_frames();
    // A still view's weight 0.7 and a feedback gain of at most 0.8: 0.94 a frame, 112 frames
    // to 1e-3.
    assert_eq!(settle, 112);
    assert_eq!(r.history_weight(0), r.alpha, "a moving view");
    assert_eq!(r.history_weight(1), r.still_alpha);
    assert_eq!(r.history_weight(settle), r.still_alpha);
    assert_eq!(r.history_weight(settle + 2), r.still_alpha, "1 - 1/3 is below still_alpha");
    assert!((r.history_weight(settle + 99) - 0.99).abs() < 1e-6);
    assert!((r.history_weight(u32::MAX) - (1.0 - 1.0 / 1024.0)).abs() < 1e-6);
    let fixed = RadiositySettings { jitter: false, ..r.clone() };
    assert_eq!(fixed.history_weight(0), r.alpha);
    assert_eq!(fixed.history_weight(settle + 99), r.still_alpha, "no noise to average");
    let same = RadiositySettings { still_alpha: 0.85, ..r.clone() };
    // 0.85: 0.97 a frame, 227 frames.
    assert_eq!(same.settle_frames(), 227);

    let g = gpu();
    let (camera, buffers) = cornell_uploaded();
    let mut renderer = Renderer::new(&g.device, &g.queue, settings(32, 24)).unwrap();
    // The mean per-pixel change of the filtered irradiance from the frame before.
    let mut last: Vec<Vec4> = Vec::new();
    let mut step = |renderer: &mut Renderer, camera: &Camera| {
        renderer.render(&g.device, &g.queue, &buffers, camera).unwrap();
        let now = read4(renderer, renderer.radiosity_buffers().unwrap().filtered);
        let change = now.iter().zip(&last).map(|(a, b)| (*a - *b).truncate().abs().element_sum());
        let mean = change.sum::<f32>() / now.len() as f32;
        last = now;
        mean
    };
    let changes: Vec<f32> = (0..settle + 200).map(|_| step(&mut renderer, &camera)).collect();
    let exponential = changes[settle as usize - 20..settle as usize].iter().sum::<f32>() / 20.0;
    let averaged = changes[changes.len() - 20..].iter().sum::<f32>() / 20.0;
    eprintln!("mean change a frame: {exponential} before it settles, {averaged} 200 frames after");
    assert!(exponential > 0.0, "the turned slices change the estimate");
    assert!(averaged < 0.1 * exponential, "{averaged} against {exponential}");

    // A move starts over: until it settles again the filter forgets as fast as before.
    let moved = Camera { eye: camera.eye + glam::Vec3::new(0.05, 0.0, 0.0), ..camera.clone() };
    let again: Vec<f32> = (0..settle).map(|_| step(&mut renderer, &moved)).collect();
    let before_settling = again[settle as usize - 20..].iter().sum::<f32>() / 20.0;
    eprintln!("after a move: {before_settling}");
    assert!(before_settling > 0.5 * exponential, "{before_settling} against {exponential}");
}

/// A still view takes the still weight (`RadiositySettings::still_alpha`, 0.7): each frame
/// carries the bounces further than a heavier weight (0.85, the still view's before it) would,
/// so the light climbs to the same fixed point in fewer frames.
#[test]
fn a_still_view_reaches_its_bounces_sooner() {
    let g = gpu();
    let (camera, buffers) = cornell_uploaded();
    // The mean of the filtered irradiance after each of `n` frames.
    let means = |still_alpha: f32, n: usize| -> Vec<f32> {
        let mut s = settings(32, 24);
        s.radiosity.still_alpha = still_alpha;
        let mut renderer = Renderer::new(&g.device, &g.queue, s).unwrap();
        (0..n)
            .map(|_| {
                renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
                let now = read4(&renderer, renderer.radiosity_buffers().unwrap().filtered);
                now.iter().map(|v| v.truncate().element_sum()).sum::<f32>() / now.len() as f32
            })
            .collect()
    };
    let fast = means(RadiositySettings::default().still_alpha, 200);
    let slow = means(0.85, 300);
    // Past their settle_frames (112 and 227) both filters average: the fixed point's mean.
    let settled = |m: &[f32]| m[m.len() - 50..].iter().sum::<f32>() / 50.0;
    let (to_fast, to_slow) = (settled(&fast), settled(&slow));
    eprintln!("settled means: {to_fast} (still weight), {to_slow} (0.85)");
    assert_eq!(fast[0], slow[0], "the first frame has no history");
    assert!((to_fast - to_slow).abs() < 0.02 * to_slow, "one fixed point");
    // What each still lacks of it, summed over the first 32 frames: c^n sums to 1 / (1 - c), c =
    // a + (1 - a) g for a feedback gain g (0.8 at most: half). The image's mean at 32x24 moves
    // by several per cent from frame to frame with the turned slices, alike in both runs.
    let lacking = |m: &[f32], to: f32| m[1..32].iter().map(|x| to - x).sum::<f32>();
    let (f, s) = (lacking(&fast, to_fast), lacking(&slow, to_slow));
    eprintln!("lacking over 32 frames: {f} (still weight), {s} (0.85)");
    assert!(s > 0.1 * to_slow, "the heavier weight climbs for frames: {s}");
    assert!(f < 0.7 * s, "{f} against {s}");
}

/// A host that has measured the bounces settle (`Renderer::settle`, as `deep-gbuffer render`
/// does) lets the filter average from then on, without waiting for the bound of
/// `settle_frames`; a move forgets it.
#[test]
fn a_view_the_host_calls_settled_averages_from_then_on() {
    let g = gpu();
    let (camera, buffers) = cornell_uploaded();
    let frames = |renderer: &mut Renderer, camera: &Camera, n: usize| -> Vec<f32> {
        let mut last = read4(renderer, renderer.radiosity_buffers().unwrap().filtered);
        (0..n)
            .map(|_| {
                renderer.render(&g.device, &g.queue, &buffers, camera).unwrap();
                let now = read4(renderer, renderer.radiosity_buffers().unwrap().filtered);
                let change =
                    now.iter().zip(&last).map(|(a, b)| (*a - *b).truncate().abs().element_sum());
                let mean = change.sum::<f32>() / now.len() as f32;
                last = now;
                mean
            })
            .collect()
    };
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;

    let mut settled = Renderer::new(&g.device, &g.queue, settings(32, 24)).unwrap();
    let mut plain = Renderer::new(&g.device, &g.queue, settings(32, 24)).unwrap();
    for r in [&mut settled, &mut plain] {
        r.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    }
    let exponential = mean(&frames(&mut plain, &camera, 60)[40..]);
    frames(&mut settled, &camera, 20);
    settled.settle();
    let averaged = mean(&frames(&mut settled, &camera, 60)[50..]);
    eprintln!("mean change a frame: {exponential} forgetting, {averaged} 50 frames after settle");
    assert!(exponential > 0.0, "the turned slices change the estimate");
    assert!(averaged < 0.3 * exponential, "{averaged} against {exponential}");

    // Settled and then moved: the filter forgets as a renderer never told does, bit for bit.
    let mut told = Renderer::new(&g.device, &g.queue, settings(32, 24)).unwrap();
    let mut untold = Renderer::new(&g.device, &g.queue, settings(32, 24)).unwrap();
    for r in [&mut told, &mut untold] {
        for _ in 0..6 {
            r.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        }
    }
    told.settle();
    let moved = Camera { eye: camera.eye + glam::Vec3::new(0.05, 0.0, 0.0), ..camera.clone() };
    for r in [&mut told, &mut untold] {
        for _ in 0..6 {
            r.render(&g.device, &g.queue, &buffers, &moved).unwrap();
        }
    }
    let a = read4(&told, told.radiosity_buffers().unwrap().filtered);
    let b = read4(&untold, untold.radiosity_buffers().unwrap().filtered);
    assert!(
        a.iter()
            .zip(&b)
            .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
    );
}

/// A still view keeps its radiosity once the mean of its settled frames holds `kept_after` of
/// them (`RadiositySettings::kept_when_still`): the still frames after it run no radiosity pass
/// (the plan lists them as reused) and the irradiance stays as it was, bit for bit, until the
/// view moves; with everything else kept too they run no pass at all. With `kept_after` 0 it
/// is never kept.
#[test]
fn a_settled_still_view_keeps_its_radiosity() {
    let g = gpu();
    let (camera, buffers) = cornell_uploaded();
    let mut s = settings(32, 24);
    // A still weight of 0 settles in few frames (the feedback gain alone: 31).
    s.radiosity.still_alpha = 0.0;
    s.radiosity.kept_after = 4;
    let settle = s.radiosity.settle_frames();
    assert_eq!(settle, 31);
    assert!(!s.radiosity.kept_when_still(settle + 4));
    assert!(s.radiosity.kept_when_still(settle + 5));
    let never = RadiositySettings { kept_after: 0, ..s.radiosity.clone() };
    assert!(!never.kept_when_still(u32::MAX));

    let runs = |r: &Renderer| r.passes().contains(&deep_gbuffer::PassId::Radiosity);
    let irradiance = |r: &Renderer| {
        read4(r, r.radiosity_buffers().unwrap().irradiance)
            .iter()
            .flat_map(|v| v.to_array().map(f32::to_bits))
            .collect::<Vec<u32>>()
    };
    let mut renderer = Renderer::new(&g.device, &g.queue, s.clone()).unwrap();
    // Frame k stands still for k - 1 frames: the last to gather is the (settle + 5)-th.
    for _ in 0..settle + 5 {
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        assert!(runs(&renderer), "the radiosity gathers until its mean holds 4 frames");
    }
    let plan = renderer.plan(&buffers, &camera);
    assert!(plan.reused.contains(&deep_gbuffer::PassId::Radiosity), "{:?}", plan.reused);
    assert!(plan.runs(deep_gbuffer::Effect::Radiosity), "kept, the radiosity still lights");
    let settled = irradiance(&renderer);
    let image = |r: &Renderer| r.read_rgb(&g.device, &g.queue, r.hdr_buffer()).unwrap();
    let shown = image(&renderer);
    assert!(shown.iter().all(|c| c.is_finite()) && shown.iter().any(|c| c.max_element() > 0.0));
    for _ in 0..3 {
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        assert!(!runs(&renderer));
        assert!(irradiance(&renderer) == settled, "the kept radiosity changed");
        // The obscurance has averaged its still frames (16) too: nothing is left to run, the
        // composite included, and the image stays.
        assert!(renderer.passes().is_empty(), "{:?}", renderer.passes());
        assert!(image(&renderer) == shown, "the image changed");
    }

    // A move gathers again, from the kept history.
    let moved = Camera { eye: camera.eye + glam::Vec3::new(0.05, 0.0, 0.0), ..camera.clone() };
    renderer.render(&g.device, &g.queue, &buffers, &moved).unwrap();
    assert!(runs(&renderer));
    assert!(irradiance(&renderer) != settled);

    // A host that says the view settled, and says it again, keeps it once the mean since the
    // first time holds the frames; told past the bound, the mean goes on instead of starting
    // over.
    let mut told = Renderer::new(&g.device, &g.queue, s.clone()).unwrap();
    for frame in 1..=10u32 {
        told.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        // Frame k stands still for k - 1: told after frames 2 and 4, its mean holds 5 frames
        // at the 6th.
        assert_eq!(runs(&told), frame <= 6, "frame {frame}");
        if frame == 2 || frame == 4 {
            told.settle();
        }
    }
    let mut late = Renderer::new(&g.device, &g.queue, s.clone()).unwrap();
    for frame in 1..=settle + 7 {
        late.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        assert_eq!(runs(&late), frame <= settle + 5, "frame {frame}");
        if frame == settle + 2 {
            late.settle();
        }
    }

    let mut always =
        Renderer::new(&g.device, &g.queue, Settings { radiosity: never, ..s }).unwrap();
    for _ in 0..settle + 8 {
        always.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    }
    assert!(runs(&always), "kept_after 0 keeps nothing");
}
