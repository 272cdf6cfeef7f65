//! Depth of field: the lens pass against its CPU reference, the plan, the focus plane, and the
//! width of a blurred edge.

mod common;

use common::{
    PostInputs, assert_few_differ, emissive_quad, gpu, middle_rmse, post_inputs, read4, render,
};
use deep_gbuffer::cpu::dof::DofInputs;
use deep_gbuffer::frame::DofUniform;
use deep_gbuffer::plan::{Effect, PassId};
use deep_gbuffer::truth::{Shot, Tracer};
use deep_gbuffer::{Camera, DofSettings, Lens, Scene, Settings};
use glam::{Vec3, Vec4};

fn settings(w: u32, h: u32, dof: DofSettings) -> Settings {
    Settings { timings: false, dof, ..Settings::with_size(w, h) }
}

/// A camera at the origin looking down -z, its lens open to `radius`, focused at `focus`.
fn lens_camera(radius: f32, focus: f32) -> Camera {
    let mut camera = Camera::perspective(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 40.0, 0.05);
    camera.lens = Lens { radius, focus };
    camera
}

/// Reads the final and the sharp image and computes the CPU reference from the GPU's own
/// G-buffer, direct light and sharp image.
fn against_cpu(scene: &Scene, camera: &Camera, s: Settings) -> (Vec<Vec4>, Vec<Vec4>) {
    let (w, h) = (s.width, s.height);
    let dof = s.dof.clone();
    let r = render(scene, camera, s);
    let g = gpu();
    let plan = r.renderer.last_plan().unwrap().clone();
    assert!(plan.contains(&PassId::Dof), "{plan}");
    let PostInputs { layers, direct1, sharp, out } = post_inputs(&r.renderer);
    let info = deep_gbuffer::SceneBuffers::upload(&g.device, scene).unwrap().info().clone();
    let u = DofUniform::new(&dof, camera, h, info.bounds, info.ambient.to_array());
    let inputs = DofInputs {
        u: &u,
        size: (w, h),
        layers: [&layers[0], &layers[1]],
        two_layers: dof.two_layers && plan.layers == 2,
        direct1: &direct1,
        sharp: &sharp,
    };
    let expected = inputs.image();
    // A step within an ulp of a pixel border lands on the neighbour on one side and not the
    // other (GPU cos and sin): such pixels stay rare; the rest agree to f32 rounding.
    let far = |a: &Vec4, e: &Vec4| (*a - *e).abs().max_element() > 1e-3 * e.max_element().max(1.0);
    assert_few_differ(&out, &expected, 0.02, far, "the lens against the CPU's");
    (sharp, out)
}

#[test]
fn the_lens_matches_cpu_reference_with_one_and_two_layers() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let mut camera = scene.camera_or_default();
    camera.lens = Lens { radius: 0.4, focus: 3.2 };
    for two_layers in [true, false] {
        let dof = DofSettings { two_layers, samples: 8, ..Default::default() };
        let (sharp, out) = against_cpu(&scene, &camera, settings(64, 48, dof));
        let changed =
            sharp.iter().zip(&out).filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3).count();
        assert!(changed > sharp.len() / 4, "the back wall is out of focus ({changed} changed)");
    }
}

#[test]
fn a_pinhole_runs_no_lens_pass() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let s = settings(32, 24, DofSettings::default());
    let r = render(&scene, &camera, s.clone());
    let plan = r.renderer.last_plan().unwrap();
    assert!(!plan.contains(&PassId::Dof));
    assert_eq!(plan.reason(Effect::Dof), Some(deep_gbuffer::plan::Reason::NotNeeded));
    assert!(r.renderer.sharp_buffer().is_none());
    // Switched off, an open lens runs none either.
    let mut open = camera.clone();
    open.lens = Lens { radius: 0.1, focus: 3.0 };
    let off = Settings { dof: DofSettings { enabled: false, ..Default::default() }, ..s };
    let r = render(&scene, &open, off);
    assert_eq!(
        r.renderer.last_plan().unwrap().reason(Effect::Dof),
        Some(deep_gbuffer::plan::Reason::Disabled)
    );
}

/// A wall in the focus plane with nothing in front: every lens ray meets the wall at its own
/// pixel, so the image is the sharp one.
#[test]
fn the_focus_plane_stays_sharp() {
    let mut scene = Scene::default();
    emissive_quad(&mut scene, 4.0, (-5.0, 5.0), Vec3::new(0.2, 0.7, 0.3));
    let (sharp, out) =
        against_cpu(&scene, &lens_camera(0.2, 4.0), settings(48, 32, DofSettings::default()));
    for (p, (a, b)) in sharp.iter().zip(&out).enumerate() {
        assert!(
            (*a - *b).abs().max_element() <= 1e-6 * a.max_element().max(1.0),
            "pixel {p}: {a} -> {b}"
        );
    }
}

/// A near plane covering the left half, out of focus, in front of a wall in focus: the image
/// changes only within the near plane's circle of confusion of the edge, and across all of it
/// (to a pixel, and a little less where only the lens's outermost rays reach).
#[test]
fn a_blurred_edge_spreads_over_its_circle_of_confusion() {
    let (near, focus) = (2.0, 6.0);
    let mut scene = Scene::default();
    emissive_quad(&mut scene, focus, (-20.0, 20.0), Vec3::new(0.0, 1.0, 0.0));
    emissive_quad(&mut scene, near, (-10.0, 0.0), Vec3::new(1.0, 0.0, 0.0));
    let (w, h) = (96, 64);
    let camera = lens_camera(0.5, focus);
    let s = settings(w, h, DofSettings { samples: 64, ..Default::default() });
    let (sharp, out) = against_cpu(&scene, &camera, s);
    let u = DofUniform::new(&DofSettings::default(), &camera, h, None, [0.0; 3]);
    let coc = (u.lens_px * (u.inv_focus - 1.0 / near)).abs();
    assert!(coc > 4.0 && coc < 20.0, "a measurable circle: {coc}");
    let edge = w as f32 / 2.0;
    let y = h / 2;
    let changed: Vec<u32> = (0..w)
        .filter(|&x| {
            let p = (y * w + x) as usize;
            // One lens ray of the 64 that finds the other plane changes a pixel by 1/64.
            (out[p] - sharp[p]).abs().max_element() > 1e-3
        })
        .collect();
    let (first, last) = (*changed.first().unwrap() as f32, *changed.last().unwrap() as f32);
    eprintln!("circle of confusion {coc} px; changed columns {first} to {last} around {edge}");
    assert!((edge - first - coc).abs() <= 2.0, "left reach {} against {coc}", edge - first);
    assert!(
        (last + 1.0 - edge - coc).abs() <= 2.0,
        "right reach {} against {coc}",
        last + 1.0 - edge
    );
}

/// A thin emissive bar far out of focus in front of an emissive wall in focus, against the
/// thin-lens truth (emission only: the image is what the lens sees, nothing else). Around the
/// bar, the lens sees the wall behind it; only the second layer holds that wall: with it the
/// error there falls.
#[test]
fn the_second_layer_lowers_the_error_around_a_blurred_foreground() {
    let (near, focus) = (2.0, 6.0);
    let mut scene = Scene::default();
    emissive_quad(&mut scene, focus, (-20.0, 20.0), Vec3::new(0.1, 0.9, 0.2));
    emissive_quad(&mut scene, near, (-0.3, 0.3), Vec3::new(1.0, 0.2, 0.1));
    let (w, h) = (96, 64);
    let camera = lens_camera(0.5, focus);
    let tracer = Tracer::new(&scene).unwrap();
    let shot = Shot { camera: &camera, size: (w, h), spp: 512, seed: 7 };
    let truth = tracer.full(&scene, &shot, None, 0, &|| {}).unwrap();
    let mut errors = Vec::new();
    for two_layers in [false, true] {
        let dof = DofSettings { two_layers, samples: 64, ..Default::default() };
        let r = render(&scene, &camera, settings(w, h, dof));
        let out = read4(&r.renderer, r.renderer.hdr_buffer());
        // The columns within the bar's circle of confusion of either edge.
        errors.push(middle_rmse(&out, &truth, w, 32.0));
    }
    eprintln!("RMSE around the bar: one layer {:.4}, two layers {:.4}", errors[0], errors[1]);
    assert!(errors[1] < 0.8 * errors[0], "two layers {} against one {}", errors[1], errors[0]);
}

/// Lenses at their limits (an aperture far wider than the scene, a hair's width, a focus at the
/// near plane or far beyond the scene) give finite images within the radiance the scene emits.
#[test]
fn lenses_at_their_limits_stay_finite() {
    let mut scene = Scene::default();
    emissive_quad(&mut scene, 6.0, (-20.0, 20.0), Vec3::new(0.1, 0.9, 0.2));
    emissive_quad(&mut scene, 2.0, (-0.3, 0.3), Vec3::new(1.0, 0.2, 0.1));
    for (radius, focus) in [(1000.0, 6.0), (1e-6, 6.0), (0.5, 0.05), (0.5, 1e9), (3.0, 1e-3)] {
        let r =
            render(&scene, &lens_camera(radius, focus), settings(24, 16, DofSettings::default()));
        let out = read4(&r.renderer, r.renderer.hdr_buffer());
        for v in &out {
            assert!(
                v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0,
                "lens {radius} at {focus}: {v}"
            );
        }
    }
}

/// A lens that cannot be is refused with a typed error naming the camera.
#[test]
fn impossible_lenses_are_refused() {
    let mut ortho = lens_camera(0.1, 3.0);
    ortho.projection = deep_gbuffer::Projection::Orthographic { height: 2.0, near: 0.1, far: 10.0 };
    for camera in [
        lens_camera(-0.1, 3.0),
        lens_camera(f32::NAN, 3.0),
        lens_camera(f32::INFINITY, 3.0),
        lens_camera(0.1, 0.0),
        lens_camera(0.1, f32::NAN),
        ortho,
    ] {
        match camera.validate() {
            Err(deep_gbuffer::Error::InvalidSetting { name: "camera", .. }) => {}
            other => panic!("{:?} accepted: {other:?}", camera.lens),
        }
    }
    // A pinhole needs no focus.
    lens_camera(0.0, 0.0).validate().unwrap();
}
