//! The resolve kernel against its CPU reference, in both precisions.

mod common;

use approx::assert_abs_diff_eq;
use common::{fixture, gpu, render};
use deep_gbuffer::cpu::resolve as cpu;
use deep_gbuffer::{GSample, Precision, Scene, Settings};
use glam::Vec3;

/// f32 evaluation order differs between the shader compiler and Rust (fused multiply-adds,
/// vector dot products), so interpolated attributes agree to a few ulps of their magnitude.
const FULL_TOLERANCE: f32 = 2e-4;
/// Texture sampling goes through sRGB decoding with `pow`, whose GPU implementation is less
/// exact than Rust's.
const TEXTURED_TOLERANCE: f32 = 2e-3;
/// Packed: 8-bit colour (half a step of 1/255), and binary16 emission (relative 2^-11).
const PACKED_COLOR_TOLERANCE: f32 = 0.5 / 255.0 + 1e-4;
/// Packed normals: 16-bit octahedral, worst-case angular error about 2e-4 rad.
const PACKED_NORMAL_TOLERANCE: f32 = 1e-3;

fn compare(scene: &Scene, precision: Precision, width: u32, height: u32, color_tolerance: f32) {
    let r = render(
        scene,
        &scene.camera_or_default(),
        Settings { precision, timings: false, layers: 2, ..Settings::with_size(width, height) },
    );
    let g = gpu();
    for (layer, vis) in [(0, &r.vis0), (1, &r.vis1)] {
        let gpu_layer = r.renderer.read_gbuffer(&g.device, &g.queue, layer).unwrap();
        let reference = cpu::resolve(&r.frame, scene, vis);
        let mut surfaces = 0;
        for (p, (a, b)) in gpu_layer.samples.iter().zip(&reference).enumerate() {
            check_finite(a);
            assert_eq!(
                a.depth, b.depth,
                "layer {layer} pixel {p}: depth is the visibility buffer's"
            );
            if b.depth == 0.0 {
                continue;
            }
            surfaces += 1;
            let normal_tolerance = if precision == Precision::Packed {
                PACKED_NORMAL_TOLERANCE
            } else {
                FULL_TOLERANCE
            };
            assert_abs_diff_eq!(
                a.normal.to_array()[..],
                b.normal.to_array()[..],
                epsilon = normal_tolerance
            );
            assert_abs_diff_eq!(
                a.base_color.to_array()[..],
                b.base_color.to_array()[..],
                epsilon = color_tolerance
            );
            assert_abs_diff_eq!(a.roughness, b.roughness, epsilon = color_tolerance);
            assert_abs_diff_eq!(a.metallic, b.metallic, epsilon = 1e-3);
            let e_tol = b.emissive.max_element() * 1e-3 + 1e-6;
            assert_abs_diff_eq!(
                a.emissive.to_array()[..],
                b.emissive.to_array()[..],
                epsilon = e_tol
            );
            assert_abs_diff_eq!(a.motion.to_array()[..], b.motion.to_array()[..], epsilon = 1e-2);
            assert_eq!(a.material, b.material, "layer {layer} pixel {p}");
            assert_abs_diff_eq!(a.normal.length(), 1.0, epsilon = 1e-3);
        }
        if layer == 0 {
            assert!(surfaces > (width * height / 8) as usize, "the view shows the scene");
        }
    }
}

fn check_finite(s: &GSample) {
    let all = [s.depth, s.roughness, s.metallic, s.reflectivity, s.motion.x, s.motion.y];
    assert!(all.iter().all(|v| v.is_finite()), "{s:?}");
    assert!(s.normal.is_finite() && s.base_color.is_finite() && s.emissive.is_finite(), "{s:?}");
}

#[test]
fn cornell_full_precision_matches_cpu_reference() {
    compare(&Scene::from_spec("builtin:cornell").unwrap(), Precision::Full, 80, 60, FULL_TOLERANCE);
}

#[test]
fn cornell_packed_matches_cpu_reference_within_its_encoding() {
    compare(
        &Scene::from_spec("builtin:cornell").unwrap(),
        Precision::Packed,
        80,
        60,
        PACKED_COLOR_TOLERANCE,
    );
}

#[test]
fn textured_gltf_matches_cpu_reference() {
    let scene = Scene::load(&fixture("suzanne/Suzanne.gltf")).unwrap();
    assert!(!scene.textures.is_empty());
    compare(&scene, Precision::Full, 96, 72, TEXTURED_TOLERANCE);
}

#[test]
fn cornell_light_is_emissive() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let r = render(
        &scene,
        &camera,
        Settings { timings: false, layers: 2, ..Settings::with_size(64, 48) },
    );
    let g = gpu();
    let layer0 = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap();
    let light = scene.materials.iter().position(|m| m.name == "light").unwrap() as u32;
    let lit: Vec<&GSample> =
        layer0.samples.iter().filter(|s| s.material == light && s.depth > 0.0).collect();
    assert!(!lit.is_empty(), "the ceiling light is visible");
    assert!(lit.iter().all(|s| s.emissive == Vec3::new(17.0, 12.0, 4.0)));
}
