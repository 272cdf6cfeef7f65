//! Ground truth by ray tracing: closed-form cases, reproducibility, and the GPU estimate's error
//! against it falling as its sample count rises.

mod common;

use common::{gpu, soup};
use deep_gbuffer::truth::{Tracer, metrics};
use deep_gbuffer::{AoSettings, Camera, Renderer, Scene, SceneBuffers, Settings};
use glam::Vec3;

fn quad(y: f32, size: f32, up: bool) -> [[Vec3; 3]; 2] {
    let c = |x: f32, z: f32| Vec3::new(x, y, z);
    let (a, b, d, e) = (c(-size, -size), c(-size, size), c(size, size), c(size, -size));
    // Counter-clockwise seen from the side the normal points to.
    if up { [[a, b, d], [a, d, e]] } else { [[a, d, b], [a, e, d]] }
}

/// A floor under a parallel ceiling at height h < r: every direction hits the ceiling at
/// d = h / cos(theta), and with cosine-distributed directions (mu = cos(theta) has density 2 mu)
///     A = integral from mu0 = h/r to 1 of (1 - h^2 / (r^2 mu^2)) 2 mu dmu
///       = 1 - mu0^2 + 2 mu0^2 ln(mu0),
/// so AV = 1 - A. Without the ceiling, AV = 1 exactly.
#[test]
fn obscurance_under_a_ceiling_has_the_closed_form() {
    let (h, r) = (0.3f32, 0.5f32);
    let mut triangles = Vec::new();
    triangles.extend(quad(0.0, 50.0, true));
    triangles.extend(quad(h, 50.0, false));
    let scene = soup(&triangles, false);
    let camera =
        Camera::perspective(Vec3::new(0.0, 0.2, 0.0), Vec3::new(0.0, 0.0, -1.0), 60.0, 0.01);
    let tracer = Tracer::new(&scene).unwrap();
    let ao = AoSettings { radius: r, ..Default::default() };
    let (w, hgt, spp) = (16, 12, 512);
    let image = tracer.ambient_obscurance(&scene, &camera, w, hgt, &ao, spp, 7, &|| ()).unwrap();
    let mu0 = h / r;
    // AV = 1 - A.
    let expected = mu0 * mu0 - 2.0 * mu0 * mu0 * mu0.ln();
    let mut floor = 0;
    for (p, v) in image.value.iter().enumerate() {
        // The view sees the floor and the ceiling's underside, which has the same answer by
        // symmetry.
        if !image.visible[p] {
            continue;
        }
        let se = image.stderr[p].x;
        assert!(
            (v.x - expected).abs() <= 5.0 * se + 1e-4,
            "pixel {p}: {} vs closed form {} (standard error {se})",
            v.x,
            expected
        );
        floor += 1;
    }
    assert_eq!(floor, (w * hgt) as usize, "floor and ceiling fill the view");

    let open = soup(&quad(0.0, 50.0, true), false);
    let camera =
        Camera::perspective(Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, -2.0), 60.0, 0.01);
    let tracer = Tracer::new(&open).unwrap();
    let image = tracer.ambient_obscurance(&open, &camera, 8, 6, &ao, 64, 7, &|| ()).unwrap();
    assert!(image.visible.iter().filter(|v| **v).count() > 10);
    let seen = image.value.iter().zip(&image.visible).filter(|(_, v)| **v);
    assert!(seen.clone().all(|(v, _)| v.x == 1.0), "an open plane is unobscured");
}

#[test]
fn the_same_seed_gives_the_same_truth_and_another_seed_another() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let tracer = Tracer::new(&scene).unwrap();
    let ao = AoSettings::default();
    let run =
        |seed| tracer.ambient_obscurance(&scene, &camera, 24, 18, &ao, 16, seed, &|| ()).unwrap();
    let (a, b, c) = (run(3), run(3), run(4));
    assert_eq!(a.value, b.value);
    assert_ne!(a.value, c.value);
}

/// The error of the GPU's obscurance against the truth falls as its tap count rises (the blur is
/// off so the taps alone decide the noise), and never below the truth's own noise floor.
#[test]
fn gpu_obscurance_error_falls_as_its_samples_rise() {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let (w, h) = (64, 48);
    let tracer = Tracer::new(&scene).unwrap();
    let base = AoSettings { blur_radius: 0, ..Default::default() };
    let truth = tracer.ambient_obscurance(&scene, &camera, w, h, &base, 256, 1, &|| ()).unwrap();
    let buffers = SceneBuffers::upload(&g.device, &scene).unwrap();
    let error = |samples| {
        let ao = AoSettings { samples, ..base.clone() };
        let settings = Settings { ao, timings: false, ..Settings::with_size(w, h) };
        let mut renderer = Renderer::new(&g.device, &g.queue, settings).unwrap();
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        let av = renderer.read_f32(&g.device, &g.queue, renderer.ao_buffer().unwrap()).unwrap();
        let layer0 = renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap();
        let estimate: Vec<Vec3> =
            av.iter().take((w * h) as usize).map(|v| Vec3::splat(*v)).collect();
        let mask: Vec<bool> = layer0.samples.iter().map(|s| s.depth > 0.0).collect();
        metrics::compare(&estimate, &mask, &truth)
    };
    let errors: Vec<_> = [2, 8, 32].map(error).into();
    eprintln!("{errors:#?}");
    // The open front of the box shows nothing in a quarter of the view.
    assert!(errors[0].pixels > (w * h) as usize / 2);
    assert!(errors[0].rmse > errors[1].rmse && errors[1].rmse > errors[2].rmse, "{errors:?}");
    assert!(errors.iter().all(|e| e.rmse > e.truth_stderr));
}

#[test]
fn invalid_truth_requests_are_refused() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let tracer = Tracer::new(&scene).unwrap();
    let ao = AoSettings::default();
    for (w, h, spp, name) in [(0, 4, 4, "size"), (4, 4, 0, "spp")] {
        match tracer.ambient_obscurance(&scene, &camera, w, h, &ao, spp, 1, &|| ()) {
            Err(deep_gbuffer::Error::InvalidSetting { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {:?}", other.map(|_| ())),
        }
    }
    assert!(Tracer::new(&Scene::default()).is_err(), "an empty scene");
}

/// Inside a closed box whose walls all emit Le and reflect rho, with no light: every path sees
/// the same radiance, so the estimate has no noise and equals the closed form,
/// E = pi Le (1 + rho + ... + rho^(bounces - 1)).
#[test]
fn indirect_light_in_a_closed_white_box_has_the_closed_form() {
    let (rho, le) = (0.5f32, 1.0f32);
    let scene = common::white_box(rho, le);
    let camera =
        Camera::perspective(Vec3::new(0.3, 0.2, 0.6), Vec3::new(-1.0, -0.8, -1.0), 70.0, 0.01);
    let tracer = Tracer::new(&scene).unwrap();
    for bounces in [1, 3] {
        let image = tracer.indirect(&scene, &camera, 12, 9, bounces, 16, 1, &|| ()).unwrap();
        let expected =
            std::f32::consts::PI * le * (0..bounces).map(|i| rho.powi(i as i32)).sum::<f32>();
        assert!(image.visible.iter().all(|v| *v), "the box fills the view");
        for (v, se) in image.value.iter().zip(&image.stderr) {
            assert!(
                (v.x - expected).abs() <= 1e-4 * expected,
                "{bounces} bounces: {v} vs {expected}"
            );
            assert!(se.x <= 1e-4 * expected, "no noise: {se}");
        }
    }
    assert!(tracer.indirect(&scene, &camera, 4, 4, 0, 4, 1, &|| ()).is_err(), "zero bounces");
}
