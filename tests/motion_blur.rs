//! Motion blur: the shutter pass against its CPU reference, the plan, the streak of a panned
//! edge, and what the second layer shows against the truth.

mod common;

use common::{
    PostInputs, assert_few_differ, emissive_quad, gpu, middle_rmse, post_inputs, read4,
    render_frames, render_moving,
};
use deep_gbuffer::cpu::motion_blur::MotionBlurInputs;
use deep_gbuffer::frame::MotionBlurUniform;
use deep_gbuffer::plan::{Effect, PassId, Reason};
use deep_gbuffer::truth::{Shot, Shutter, Tracer};
use deep_gbuffer::{Camera, MotionBlurSettings, Renderer, Scene, Settings};
use glam::{Vec3, Vec4};

fn settings(w: u32, h: u32, motion_blur: MotionBlurSettings) -> Settings {
    Settings { timings: false, motion_blur, ..Settings::with_size(w, h) }
}

fn open(shutter: f32) -> MotionBlurSettings {
    MotionBlurSettings { shutter, ..Default::default() }
}

/// The columns of row `y` (`w` pixels a row) that the pass changed: one instant of the 64 the
/// tests take that finds another colour changes a pixel by 1/64.
fn changed_columns(image: &[Vec4], out: &[Vec4], w: u32, y: u32) -> Vec<u32> {
    (0..w)
        .filter(|&x| {
            let p = (y * w + x) as usize;
            (out[p] - image[p]).abs().max_element() > 1e-3
        })
        .collect()
}

/// A camera at `x` on the x axis looking down -z.
fn camera_at(x: f32) -> Camera {
    Camera::perspective(Vec3::new(x, 0.0, 0.0), Vec3::new(x, 0.0, -1.0), 40.0, 0.05)
}

/// Renders `cameras` in turn and checks the last frame's motion blur against the CPU's, from
/// the GPU's own G-buffer, direct light and image before the pass. Returns that image and the
/// blurred one.
fn against_cpu(scene: &Scene, cameras: &[Camera], s: Settings) -> (Vec<Vec4>, Vec<Vec4>) {
    let r = render_frames(scene, cameras, s);
    check_against_cpu(scene, &r.renderer)
}

/// Checks `renderer`'s last frame's motion blur against the CPU's, from the GPU's own G-buffer,
/// direct light and image before the pass; returns that image and the blurred one.
fn check_against_cpu(scene: &Scene, renderer: &Renderer) -> (Vec<Vec4>, Vec<Vec4>) {
    let s = renderer.settings();
    let (w, h) = (s.width, s.height);
    let motion = s.motion_blur.clone();
    let plan = renderer.last_plan().unwrap().clone();
    assert!(plan.contains(&PassId::MotionBlur), "{plan}");
    let PostInputs { layers, direct1, sharp: image, out } = post_inputs(renderer);
    let u = MotionBlurUniform::new(&motion, scene.ambient.to_array(), w);
    let inputs = MotionBlurInputs {
        u: &u,
        frame: renderer.frame_uniform().unwrap(),
        size: (w, h),
        layers: [&layers[0], &layers[1]],
        two_layers: motion.two_layers && plan.layers == 2,
        direct1: &direct1,
        image: &image,
    };
    let expected = inputs.image();
    // A step within an ulp of a pixel border lands on the neighbour on one side and not the
    // other: such pixels stay rare; the rest agree to f32 rounding.
    let far = |a: &Vec4, e: &Vec4| (*a - *e).abs().max_element() > 1e-3 * e.max_element().max(1.0);
    assert_few_differ(&out, &expected, 0.02, far, "the shutter against the CPU's");
    (image, out)
}

#[test]
fn the_shutter_matches_cpu_reference_with_one_and_two_layers() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let cameras = [camera.orbited(-4.0), camera];
    for two_layers in [true, false] {
        let motion = MotionBlurSettings { two_layers, samples: 8, ..open(1.0) };
        let (image, out) = against_cpu(&scene, &cameras, settings(64, 48, motion));
        let changed =
            image.iter().zip(&out).filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3).count();
        assert!(changed > image.len() / 10, "the turn blurs the box ({changed} changed)");
    }
}

/// A camera that does not move, or a closed shutter, runs no motion-blur pass; the image is the
/// same as with the pass switched off.
#[test]
fn a_still_camera_runs_no_motion_pass() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let still =
        render_frames(&scene, &[camera.clone(), camera.clone()], settings(32, 24, open(1.0)));
    let plan = still.renderer.last_plan().unwrap();
    assert!(!plan.contains(&PassId::MotionBlur));
    assert_eq!(plan.reason(Effect::MotionBlur), Some(Reason::Still));
    assert!(still.renderer.sharp_buffer().is_none());
    let closed =
        render_frames(&scene, &[camera.orbited(-4.0), camera.clone()], settings(32, 24, open(0.0)));
    assert_eq!(
        closed.renderer.last_plan().unwrap().reason(Effect::MotionBlur),
        Some(Reason::NotNeeded)
    );
    let off = MotionBlurSettings { enabled: false, ..open(1.0) };
    let off = render_frames(&scene, &[camera.clone(), camera], settings(32, 24, off));
    assert_eq!(
        read4(&still.renderer, still.renderer.hdr_buffer()),
        read4(&off.renderer, off.renderer.hdr_buffer()),
        "a still camera's image is the one without the pass"
    );
}

/// A plane in two colours, the camera panning across it: the edge streaks over the distance it
/// moved while the shutter was open, on the side it came from (to a pixel or two), and nowhere
/// else.
#[test]
fn a_panned_edge_streaks_over_its_motion() {
    let z = 4.0;
    let mut scene = Scene::default();
    emissive_quad(&mut scene, z, (-20.0, 0.0), Vec3::new(1.0, 0.0, 0.0));
    emissive_quad(&mut scene, z, (0.0, 20.0), Vec3::new(0.0, 1.0, 0.0));
    let (w, h, shutter, step) = (96, 64, 0.75, 0.3);
    let cameras = [camera_at(-step), camera_at(0.0)];
    let motion = MotionBlurSettings { samples: 64, ..open(shutter) };
    let (image, out) = against_cpu(&scene, &cameras, settings(w, h, motion));
    // The camera moved `step` right: the plane moved left by step * pixels per unit at z.
    let per_unit = cameras[1].pixels_of(1.0, z, h);
    let streak = shutter * step * per_unit;
    assert!(streak > 4.0 && streak < 20.0, "a measurable streak: {streak}");
    let changed = changed_columns(&image, &out, w, h / 2);
    let (first, last) = (*changed.first().unwrap() as f32, *changed.last().unwrap() as f32 + 1.0);
    let edge = w as f32 / 2.0;
    eprintln!("streak {streak} px; changed columns {first} to {last} around {edge}");
    // The plane moved left: what a pixel left of the edge showed earlier lay left of it (the
    // same red); a pixel right of the edge within the streak showed red.
    assert!((first - edge).abs() <= 1.0, "nothing changes left of the edge ({first})");
    assert!(
        (last - edge - streak).abs() <= 2.0,
        "the streak reaches {} against {streak}",
        last - edge
    );
}

/// A thin emissive bar in front of an emissive wall, the camera moving sideways (the bar, near,
/// moves faster than the wall: parallax), against the truth over the shutter (emission only:
/// the error is the blur's alone). Where the bar has moved on, the pixels showed the wall behind
/// it, which only the second layer holds: with it the error there falls.
#[test]
fn the_second_layer_lowers_the_error_behind_a_moving_bar() {
    let (near, far) = (2.0, 6.0);
    let mut scene = Scene::default();
    emissive_quad(&mut scene, far, (-20.0, 20.0), Vec3::new(0.1, 0.9, 0.2));
    emissive_quad(&mut scene, near, (-0.3, 0.3), Vec3::new(1.0, 0.2, 0.1));
    let (w, h, shutter) = (96, 64, 1.0);
    let cameras = [camera_at(-0.25), camera_at(0.0)];
    let tracer = Tracer::new(&scene).unwrap();
    let shot = Shot { camera: &cameras[1], size: (w, h), spp: 512, seed: 7 };
    let truth = tracer
        .full_in_motion(
            &scene,
            &shot,
            Some(&Shutter::camera(&cameras[0], shutter)),
            None,
            0,
            &|| {},
        )
        .unwrap();
    let mut errors = Vec::new();
    for two_layers in [false, true] {
        let motion = MotionBlurSettings { two_layers, samples: 64, ..open(shutter) };
        let r = render_frames(&scene, &cameras, settings(w, h, motion));
        let out = read4(&r.renderer, r.renderer.hdr_buffer());
        errors.push(middle_rmse(&out, &truth, w, 30.0));
    }
    eprintln!("RMSE around the bar: one layer {:.4}, two layers {:.4}", errors[0], errors[1]);
    assert!(errors[1] < 0.8 * errors[0], "two layers {} against one {}", errors[1], errors[0]);
}

/// Shutters and streaks outside their ranges are typed errors naming the setting.
#[test]
fn bad_shutters_are_refused() {
    for (m, name) in [
        (open(-0.1), "motion_blur.shutter"),
        (open(1.5), "motion_blur.shutter"),
        (open(f32::NAN), "motion_blur.shutter"),
        (MotionBlurSettings { samples: 0, ..open(0.5) }, "motion_blur.samples"),
        (MotionBlurSettings { max_blur: f32::INFINITY, ..open(0.5) }, "motion_blur.max_blur"),
    ] {
        let s = Settings { motion_blur: m, ..Settings::default() };
        match s.validate() {
            Err(deep_gbuffer::Error::InvalidSetting { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {other:?}"),
        }
    }
}

/// Depth of field and motion blur in one frame: the composite's image goes through the lens,
/// then over the shutter, as the two CPU references chained give it.
#[test]
fn the_lens_then_the_shutter() {
    use deep_gbuffer::cpu::dof::DofInputs;
    use deep_gbuffer::frame::DofUniform;
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let mut camera = scene.camera_or_default();
    camera.lens = deep_gbuffer::Lens { radius: 0.3, focus: 3.2 };
    let cameras = [camera.orbited(-4.0), camera.clone()];
    let (w, h) = (48, 36);
    let dof = deep_gbuffer::DofSettings { samples: 8, ..Default::default() };
    let motion = MotionBlurSettings { samples: 8, ..open(1.0) };
    let s = Settings { dof: dof.clone(), ..settings(w, h, motion.clone()) };
    let r = render_frames(&scene, &cameras, s);
    let g = gpu();
    let plan = r.renderer.last_plan().unwrap().clone();
    let posts: Vec<&PassId> = plan.passes.iter().filter(|p| p.is_post()).collect();
    assert_eq!(posts, [&PassId::Dof, &PassId::MotionBlur]);
    let PostInputs { layers, direct1, sharp, out } = post_inputs(&r.renderer);
    let info = deep_gbuffer::SceneBuffers::upload(&g.device, &scene).unwrap().info().clone();
    let ambient = info.ambient.to_array();
    let du = DofUniform::new(&dof, &camera, h, info.bounds, ambient);
    let layers = [&layers[0][..], &layers[1][..]];
    let lens = DofInputs {
        u: &du,
        size: (w, h),
        layers,
        two_layers: true,
        direct1: &direct1,
        sharp: &sharp,
    };
    let through_lens = lens.image();
    let mu = MotionBlurUniform::new(&motion, ambient, w);
    let shutter = MotionBlurInputs {
        u: &mu,
        frame: r.renderer.frame_uniform().unwrap(),
        size: (w, h),
        layers,
        two_layers: true,
        direct1: &direct1,
        image: &through_lens,
    };
    let expected = shutter.image();
    let far = |a: &Vec4, e: &Vec4| (*a - *e).abs().max_element() > 1e-3 * e.max_element().max(1.0);
    // Each pass may move a few pixels by a step (2% each, as above); chained, twice that.
    assert_few_differ(&out, &expected, 0.04, far, "the lens then the shutter against the CPU's");
}

/// A camera that turns half around between frames (motion vectors of thousands of pixels, or
/// none where the last frame saw nothing) gives a finite image within the scene's radiance.
#[test]
fn a_camera_turning_half_around_stays_finite() {
    let mut scene = Scene::default();
    emissive_quad(&mut scene, 6.0, (-20.0, 20.0), Vec3::new(0.1, 0.9, 0.2));
    emissive_quad(&mut scene, 2.0, (-0.3, 0.3), Vec3::new(1.0, 0.2, 0.1));
    let camera = camera_at(0.0);
    for turn in [170.0, 90.0, 45.0, 1e-3] {
        let cameras = [camera.orbited(turn), camera.clone()];
        let r = render_frames(&scene, &cameras, settings(24, 16, open(1.0)));
        for v in read4(&r.renderer, r.renderer.hdr_buffer()) {
            assert!(
                v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0,
                "{turn}: {v}"
            );
        }
    }
}

/// Depth of the bar of [`bar_scene`] and of the wall behind it.
const BAR: f32 = 2.0;
const WALL: f32 = 6.0;

/// An emissive bar 0.6 wide with its left edge at `x`, at depth [`BAR`] in front of an emissive
/// wall at depth [`WALL`] (the bar's vertices come last: moving `x` moves only those).
fn bar_scene(x: f32) -> Scene {
    let mut scene = Scene::default();
    emissive_quad(&mut scene, WALL, (-20.0, 20.0), Vec3::new(0.1, 0.9, 0.2));
    emissive_quad(&mut scene, BAR, (x, x + 0.6), Vec3::new(1.0, 0.2, 0.1));
    scene
}

/// The bar moved `by` to the right between two frames of a still camera: the resolve gives its
/// pixels the bar's own screen motion (what the CPU resolve gives from the same vertex
/// positions) and the wall none; the motion blur runs though the camera stood still, and a
/// frame after, with nothing moved, it does not.
#[test]
fn moving_geometry_has_its_own_motion_vectors() {
    use deep_gbuffer::cpu::resolve::resolve_moved;
    let (w, h, by) = (96, 64, 0.2);
    let (before, after) = (bar_scene(-0.1 - by), bar_scene(-0.1));
    let camera = camera_at(0.0);
    let frames = [before.positions.clone(), after.positions.clone()];
    let mut r = render_moving(&after, &frames, &camera, settings(w, h, open(1.0)));
    assert!(r.renderer.last_plan().unwrap().contains(&PassId::MotionBlur));
    let g = gpu();
    let expected = (by * camera.pixels_of(1.0, BAR, h), 0.0);
    let cpu = resolve_moved(&r.frame, &after, Some(&before.positions), &r.vis0);
    let layer =
        |r: &common::Rendered, l| r.renderer.read_gbuffer(&g.device, &g.queue, l).unwrap().samples;
    let gpu0 = layer(&r, 0);
    let (mut bar, mut wall) = (0, 0);
    for (p, (a, e)) in gpu0.iter().zip(&cpu).enumerate() {
        assert!((a.motion - e.motion).abs().max_element() < 1e-3, "pixel {p}: {a:?} against {e:?}");
        let m = (a.motion.x, a.motion.y);
        if (a.depth - BAR).abs() < 0.01 {
            bar += 1;
            assert!((m.0 - expected.0).abs() < 0.01 && m.1.abs() < 0.01, "bar {m:?} {expected:?}");
        } else {
            wall += 1;
            assert!(a.motion.abs().max_element() < 0.01, "the wall stood still: {m:?}");
        }
    }
    assert!(bar > 500 && wall > 500, "{bar} bar and {wall} wall pixels");
    // Layer 1 behind the bar: the wall, still.
    for s in layer(&r, 1).iter().filter(|s| s.depth > 0.0) {
        assert!(s.motion.abs().max_element() < 0.01, "layer 1 {:?}", s.motion);
    }
    r.renderer.render(&g.device, &g.queue, &r.buffers, &camera).unwrap();
    let plan = r.renderer.last_plan().unwrap();
    assert_eq!(plan.reason(Effect::MotionBlur), Some(Reason::Still), "{plan}");
    let still = layer(&r, 0);
    assert!(still.iter().all(|s| s.motion.abs().max_element() < 0.01), "nothing moved since");
}

/// The bar moves right under a still camera: it streaks over the wall it left behind, over
/// the shutter's share of its motion (the wall's pixels, still themselves, follow the fastest
/// motion near them), and its leading edge shows the wall it has just covered; its middle and
/// the wall beyond the streak are unchanged. The GPU matches the CPU reference.
#[test]
fn a_moving_object_streaks_over_its_motion() {
    let (w, h, by, shutter) = (96, 64, 0.2, 0.75);
    let (before, after) = (bar_scene(-0.1 - by), bar_scene(-0.1));
    let camera = camera_at(0.0);
    let motion = MotionBlurSettings { samples: 64, ..open(shutter) };
    let frames = [before.positions.clone(), after.positions.clone()];
    let r = render_moving(&after, &frames, &camera, settings(w, h, motion));
    let (image, out) = check_against_cpu(&after, &r.renderer);
    let per_unit = camera.pixels_of(1.0, BAR, h);
    let streak = shutter * by * per_unit;
    let (left, right) = (w as f32 / 2.0 - 0.1 * per_unit, w as f32 / 2.0 + 0.5 * per_unit);
    let changed = changed_columns(&image, &out, w, h / 2);
    eprintln!("streak {streak} px; bar {left} to {right}; changed columns {changed:?}");
    let (first, last) = (*changed.first().unwrap() as f32, *changed.last().unwrap() as f32 + 1.0);
    assert!((first - (left - streak)).abs() <= 1.5, "the trail starts at {first}");
    assert!((last - right).abs() <= 1.0, "the leading edge ends at {last}");
    let middle = (left + 1.0).ceil() as u32..(right - streak - 1.0).floor() as u32;
    assert!(middle.len() > 5 && middle.clone().all(|x| !changed.contains(&x)), "{middle:?}");
    // Both streaks are about as wide as the motion over the shutter.
    let trail = changed.iter().filter(|&&x| (x as f32) < left).count() as f32;
    let lead = changed.iter().filter(|&&x| (x as f32) > left).count() as f32;
    assert!((trail - streak).abs() <= 1.5 && (lead - streak).abs() <= 1.5, "{trail} {lead}");
}

/// Against the truth over the shutter (the bar's vertices moved linearly, emission only): with
/// two layers the error around the bar falls, as its leading edge shows the wall the bar hides.
#[test]
fn the_second_layer_lowers_the_error_of_a_moving_object() {
    let (w, h, by, shutter) = (96, 64, 0.3, 1.0);
    let (before, after) = (bar_scene(-0.1 - by), bar_scene(-0.1));
    let camera = camera_at(0.0);
    let tracer = Tracer::new(&after).unwrap();
    let shot = Shot { camera: &camera, size: (w, h), spp: 512, seed: 7 };
    let open_shutter =
        Shutter { before: &camera, open: shutter, positions_before: Some(&before.positions) };
    let truth = tracer.full_in_motion(&after, &shot, Some(&open_shutter), None, 0, &|| {}).unwrap();
    let frames = [before.positions.clone(), after.positions.clone()];
    let mut errors = Vec::new();
    for two_layers in [false, true] {
        let motion = MotionBlurSettings { two_layers, samples: 64, ..open(shutter) };
        let r = render_moving(&after, &frames, &camera, settings(w, h, motion));
        let out = read4(&r.renderer, r.renderer.hdr_buffer());
        errors.push(middle_rmse(&out, &truth, w, 30.0));
    }
    eprintln!("RMSE around the moving bar: one layer {:.4}, two {:.4}", errors[0], errors[1]);
    assert!(errors[1] < 0.8 * errors[0], "two layers {} against one {}", errors[1], errors[0]);
    // Positions before the shutter that do not fit the scene are typed errors.
    let short = Shutter { positions_before: Some(&before.positions[1..]), ..open_shutter };
    let bad = tracer.full_in_motion(&after, &shot, Some(&short), None, 0, &|| {});
    assert!(matches!(bad, Err(deep_gbuffer::Error::InvalidScene(_))), "{bad:?}");
}

/// Moving geometry at its extremes: a bar that jumped thousands of pixels, one that stood where
/// it cannot be (a vertex not a number the frame before), one behind the camera the frame
/// before, and a packed G-buffer (motion in 16-bit floats, which overflow): the image stays
/// finite and within the emitters' range, and an unknown motion is never followed.
#[test]
fn moving_geometry_at_its_extremes_stays_finite() {
    let after = bar_scene(-0.1);
    let bar = after.positions.len() - 4;
    let jumped = bar_scene(-5000.0).positions;
    let mut unknown = after.positions.clone();
    unknown[bar] = Vec3::NAN;
    let mut behind = after.positions.clone();
    for p in &mut behind[bar..] {
        p.z = 3.0;
    }
    for precision in [deep_gbuffer::Precision::Full, deep_gbuffer::Precision::Packed] {
        for before in [&jumped, &unknown, &behind] {
            let frames = [before.clone(), after.positions.clone()];
            let s = Settings { precision, ..settings(24, 16, open(1.0)) };
            let r = render_moving(&after, &frames, &camera_at(0.0), s);
            for v in read4(&r.renderer, r.renderer.hdr_buffer()) {
                assert!(
                    v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0,
                    "{precision:?}: {v}"
                );
            }
            let g = gpu();
            let layer0 = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap().samples;
            assert!(layer0.iter().all(|s| !s.motion.is_nan()), "{precision:?}: a NaN motion");
        }
    }
}
