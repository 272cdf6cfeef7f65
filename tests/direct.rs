//! Direct light and the composite against their CPU references, and a lit plane against the
//! closed-form value of the BRDF.

mod common;

use std::f32::consts::PI;

use common::{GBUFFER_FIXTURES, gpu, render, render_frames, shade_fixture, soup};
use deep_gbuffer::cpu::{composite as cpu_composite, direct as cpu_direct, shadow as cpu_shadow};
use deep_gbuffer::scene::{GpuLight, Light, LightKind, Projection};
use deep_gbuffer::{Camera, Scene, Settings};
use glam::Vec3;

/// GPU `pow`, `sqrt` and division differ from Rust's in the last bits, and the shader compiler
/// may fuse multiply-adds: radiance agrees to a relative 1e-4 (plus an absolute floor for
/// values near zero).
fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() <= 1e-4 * b.abs().max_element() + 1e-6
}

/// Below this roughness the GGX lobe is steep: D = a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2) with
/// a = roughness^2 multiplies a rounding of n.h by about 4 / a^2 in relative terms, so a highlight
/// on a smooth sphere agrees to a relative 1e-3 (not 1e-4). Rough surfaces keep [`close`].
const SMOOTH: f32 = 0.5;

fn close_specular(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() <= 1e-3 * b.abs().max_element() + 1e-6
}

#[test]
fn cornell_direct_and_composite_match_cpu_reference() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let (w, h) = (64, 48);
    let r = render(
        &scene,
        &scene.camera_or_default(),
        Settings { timings: false, ..Settings::with_size(w, h) },
    );
    let g = gpu();
    let layer0 = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap();
    let (expected, lambert, atlas) = cpu_reference(&scene, &r, &layer0.samples);
    let gpu_atlas = r
        .renderer
        .read_f32(&g.device, &g.queue, r.renderer.shadow_atlas_buffer().unwrap())
        .unwrap();
    let gpu_atlas: Vec<u64> = bytemuck::pod_collect_to_vec(&gpu_atlas);
    assert!(gpu_atlas == atlas, "the GPU's shadow maps equal the CPU rasterizer's");
    let actual = r.renderer.read_rgb(&g.device, &g.queue, r.renderer.direct_buffer()).unwrap();
    let diffuse = r.renderer.read_rgb(&g.device, &g.queue, r.renderer.diffuse_buffer(0)).unwrap();
    let mut lit = 0;
    for (p, (a, b)) in actual.iter().zip(&expected).enumerate() {
        assert!(close(*a, *b), "direct at pixel {p}: gpu {a} cpu {b}");
        assert!(close(diffuse[p], lambert[p]), "diffuse at {p}: {} {}", diffuse[p], lambert[p]);
        assert!(lambert[p].cmple(*b + 1e-6).all(), "the Lambertian part is part of it at {p}");
        lit += usize::from(b.max_element() > 0.01);
    }
    assert!(lit > (w * h / 2) as usize, "the light reaches most of the box ({lit})");

    // The composite from the GPU's own inputs.
    let av = r.renderer.read_f32(&g.device, &g.queue, r.renderer.ao_buffer().unwrap()).unwrap();
    let irradiance = r
        .renderer
        .read_f32(&g.device, &g.queue, r.renderer.radiosity_buffers().unwrap().irradiance)
        .unwrap();
    let irradiance: Vec<glam::Vec4> = irradiance
        .chunks_exact(4)
        .take((w * h) as usize)
        .map(|c| glam::Vec4::new(c[0], c[1], c[2], c[3]))
        .collect();
    let expected = cpu_composite::composite(
        &layer0.samples,
        &actual,
        Some(&av[..(w * h) as usize]),
        Some(&irradiance),
        scene.ambient,
    );
    let hdr = r.renderer.read_rgb(&g.device, &g.queue, r.renderer.hdr_buffer()).unwrap();
    for (p, (a, b)) in hdr.iter().zip(&expected).enumerate() {
        assert!(close(*a, *b), "composite at pixel {p}: gpu {a} cpu {b}");
        assert!(a.is_finite() && a.min_element() >= 0.0);
    }
}

/// The CPU reference's direct light and Lambertian part of `samples` seen from `r`'s last
/// frame, with shadow maps the CPU draws itself (the CPU rasterizer, the default settings), and
/// those maps' visibility words.
fn cpu_reference(
    scene: &Scene,
    r: &common::Rendered,
    samples: &[deep_gbuffer::GSample],
) -> (Vec<Vec3>, Vec<Vec3>, Vec<u64>) {
    let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::new).collect();
    let defaults = Settings::default().shadows;
    let (faces, light_faces, atlas) = cpu_shadow::maps(scene, defaults.resolution);
    let shadows = cpu_shadow::Shadows {
        faces: &faces,
        light_faces: &light_faces,
        atlas: &atlas,
        pcf: defaults.pcf,
    };
    let (direct, lambert) =
        cpu_direct::direct_and_diffuse(&r.frame, samples, &lights, Some(&shadows));
    (direct, lambert, atlas)
}

/// Layer 1 is lit at the pixels that hold a layer-1 surface only: after the camera moved, its
/// direct light and Lambertian part still match the CPU reference at every pixel, 0 wherever
/// layer 1 holds nothing (nothing of the frame before is left).
#[test]
fn layer1_direct_light_matches_cpu_reference_after_the_camera_moved() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let mut moved = camera.clone();
    moved.eye += (camera.target - camera.eye) * 0.3 + Vec3::new(0.3, 0.2, 0.0);
    let (w, h) = (48, 36);
    let settings = Settings { timings: false, ..Settings::with_size(w, h) };
    let r = render_frames(&scene, &[moved, camera], settings);
    let g = gpu();
    let layer1 = r.renderer.read_gbuffer(&g.device, &g.queue, 1).unwrap();
    let (expected, lambert, _) = cpu_reference(&scene, &r, &layer1.samples);
    let actual = r.renderer.read_rgb(&g.device, &g.queue, r.renderer.direct1_buffer()).unwrap();
    let diffuse = r.renderer.read_rgb(&g.device, &g.queue, r.renderer.diffuse_buffer(1)).unwrap();
    let (mut held, mut lit) = (0, 0);
    for (p, (a, b)) in actual.iter().zip(&expected).enumerate() {
        assert!(close(*a, *b), "layer-1 direct at pixel {p}: gpu {a} cpu {b}");
        assert!(
            close(diffuse[p], lambert[p]),
            "layer-1 diffuse at {p}: {} {}",
            diffuse[p],
            lambert[p]
        );
        held += usize::from(layer1.samples[p].depth > 0.0);
        lit += usize::from(b.max_element() > 0.01);
    }
    // Some pixels hold a layer-1 surface and some of those are lit; most hold none.
    assert!(lit > 0 && held < (w * h / 2) as usize, "{held} held, {lit} lit");
}

/// A white plane lit straight from above by a directional light, seen straight from above
/// (orthographic): n = l = v, so the BRDF is albedo / pi + D F G / 4 with D = 1 / (pi a^2),
/// G = 1, F = 0.04 (a = roughness^2).
#[test]
fn a_lit_plane_has_the_closed_form_radiance() {
    let plane = [
        [Vec3::new(-2.0, 0.0, -2.0), Vec3::new(-2.0, 0.0, 2.0), Vec3::new(2.0, 0.0, 2.0)],
        [Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 0.0, 2.0), Vec3::new(2.0, 0.0, -2.0)],
    ];
    let mut scene = soup(&plane, false);
    let (albedo, roughness) = (0.6f32, 0.7f32);
    scene.materials[0].base_color = glam::Vec4::new(albedo, albedo, albedo, 1.0);
    scene.materials[0].roughness = roughness;
    scene.lights.push(Light {
        name: "sun".into(),
        kind: LightKind::Directional { direction: Vec3::NEG_Y },
        color: Vec3::ONE,
        intensity: 3.0,
        casts_shadows: false,
    });
    let camera = Camera {
        eye: Vec3::new(0.0, 5.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::NEG_Z,
        projection: Projection::Orthographic { height: 2.0, near: 0.1, far: 10.0 },
        lens: Default::default(),
    };
    let r = render(&scene, &camera, Settings { timings: false, ..Settings::with_size(16, 16) });
    let g = gpu();
    let direct = r.renderer.read_rgb(&g.device, &g.queue, r.renderer.direct_buffer()).unwrap();
    let a = roughness * roughness;
    let expected = 3.0 * (albedo / PI + 0.04 / (4.0 * PI * a * a));
    for d in &direct {
        assert!((d.x - expected).abs() <= 1e-4 * expected, "{d} vs {expected}");
    }
}

#[test]
fn a_scene_without_light_has_zero_direct_radiance() {
    let mut scene = Scene::from_spec("builtin:cornell").unwrap();
    scene.lights.clear();
    let r = render(
        &scene,
        &scene.camera_or_default(),
        Settings { timings: false, ..Settings::with_size(32, 24) },
    );
    assert!(!r.renderer.passes().contains(&deep_gbuffer::PassId::Direct));
    let g = gpu();
    let direct = r.renderer.read_rgb(&g.device, &g.queue, r.renderer.direct_buffer()).unwrap();
    assert!(direct.iter().all(|d| *d == Vec3::ZERO));
}

/// The stored G-buffers (fixtures/gbuffer/), independent of the rasterizer: every light, with
/// the CPU's own shadow maps.
#[test]
fn direct_light_of_stored_gbuffers_matches_cpu_reference() {
    for (i, (file, _)) in GBUFFER_FIXTURES.iter().enumerate() {
        let f = shade_fixture(i, Settings { timings: false, ..Settings::default() });
        let g = gpu();
        let lights: Vec<GpuLight> = f.scene.lights.iter().map(GpuLight::new).collect();
        let resolution = Settings::default().shadows.resolution;
        let (faces, light_faces, atlas) = cpu_shadow::maps(&f.scene, resolution);
        let shadows = cpu_shadow::Shadows {
            faces: &faces,
            light_faces: &light_faces,
            atlas: &atlas,
            pcf: Settings::default().shadows.pcf,
        };
        let expected = cpu_direct::direct(&f.frame, &f.layers[0].samples, &lights, Some(&shadows));
        let actual = f.renderer.read_rgb(&g.device, &g.queue, f.renderer.direct_buffer()).unwrap();
        for (p, (a, b)) in actual.iter().zip(&expected).enumerate() {
            let rough = f.layers[0].samples[p].roughness;
            let ok = if rough >= SMOOTH { close(*a, *b) } else { close_specular(*a, *b) };
            assert!(ok, "{} pixel {p} (roughness {rough}): gpu {a} cpu {b}", file);
        }
        assert!(expected.iter().any(|c| c.max_element() > 0.01), "the view is lit");
    }
}

/// The ambient term fills the share of the hemisphere the radiosity gather left open, as much of
/// it as the obscurance leaves open: the smaller of `1 - c` and AV (both estimate the open share
/// from above and see the same surfaces, so their product would darken a crease twice); without
/// the gather (`c = 0`) it is the paper's AV * ambient. (The GPU composite is held to this CPU
/// twin by `cornell_direct_and_composite_match_cpu_reference`.)
#[test]
fn the_ambient_term_takes_the_smaller_open_share() {
    let s = deep_gbuffer::gbuffer::GSample {
        depth: 1.0,
        base_color: Vec3::ONE,
        occlusion: 1.0,
        ..Default::default()
    };
    let ambient = Vec3::splat(0.5);
    let share = |av: f32, c: f32| {
        let e = glam::Vec4::new(0.0, 0.0, 0.0, c);
        cpu_composite::shaded(&s, Vec3::ZERO, av, e, ambient).x / 0.5
    };
    for (av, c, open) in [(0.3, 0.6, 0.3), (0.9, 0.2, 0.8), (0.7, 0.0, 0.7), (1.0, 1.0, 0.0)] {
        let got = share(av, c);
        assert!((got - open).abs() < 1e-6, "AV {av}, coverage {c}: {got}, not {open}");
    }
}
