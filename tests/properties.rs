//! Property tests: random triangle sets through the rasterizer against the CPU reference, random
//! scenes and cameras through the whole pipeline, and loaders fed arbitrary or mutated bytes.

mod common;

use common::{fixture, gpu, render, soup};
use deep_gbuffer::cpu::raster::{self as cpu, RasterInput, double_sided_triangles};
use deep_gbuffer::{Camera, Scene, Settings};
use glam::Vec3;
use proptest::prelude::*;

fn point(extent: f32) -> impl Strategy<Value = Vec3> {
    (-extent..extent, -extent..extent, -extent..extent).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn triangles(count: std::ops::Range<usize>) -> impl Strategy<Value = Vec<[Vec3; 3]>> {
    prop::collection::vec([point(2.0), point(2.0), point(2.0)], count)
}

fn settings() -> Settings {
    let shadows = deep_gbuffer::ShadowSettings { resolution: 64, ..Default::default() };
    Settings { timings: false, shadows, layers: 2, ..Settings::with_size(24, 16) }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Any triangle set (through the near plane, behind the camera, degenerate) rasterizes to
    /// exactly the CPU reference's visibility words, on both layers.
    #[test]
    fn random_triangles_match_the_cpu_rasterizer(tris in triangles(1..40), double_sided: bool) {
        let scene = soup(&tris, double_sided);
        let camera = Camera::perspective(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, 60.0, 0.1);
        let r = render(&scene, &camera, Settings { effects: deep_gbuffer::Effects::parse("direct").unwrap(), ..settings() });
        let ds = double_sided_triangles(&scene);
        let input = RasterInput::new(&scene, &ds);
        let cpu0 = cpu::raster_layer0(&r.frame, &input);
        prop_assert_eq!(&r.vis0, &cpu0);
    }

    /// Random scenes seen from random cameras: every output finite, AV in [0, 1], nothing
    /// negative.
    #[test]
    fn random_scenes_and_cameras_give_finite_frames(
        tris in triangles(1..30),
        eye in point(4.0),
        target in point(1.0),
        fov in 10.0f32..150.0,
        reflective in 0.0f32..1.0,
    ) {
        prop_assume!((eye - target).length() > 1e-3);
        let mut scene = soup(&tris, true);
        scene.materials[0].reflectivity = reflective;
        scene.ensure_lights();
        let camera = Camera::perspective(eye, target, fov, 0.05);
        let r = render(&scene, &camera, settings());
        let g = gpu();
        let hdr = r.renderer.read_rgb(&g.device, &g.queue, r.renderer.hdr_buffer()).unwrap();
        prop_assert!(hdr.iter().all(|c| c.is_finite() && c.min_element() >= 0.0));
        if let Some(av) = r.renderer.ao_buffer() {
            let av = r.renderer.read_f32(&g.device, &g.queue, av).unwrap();
            prop_assert!(av.iter().take(24 * 16).all(|v| (0.0..=1.0).contains(v)));
        }
        if let Some(b) = r.renderer.radiosity_buffers() {
            let e = r.renderer.read_f32(&g.device, &g.queue, b.irradiance).unwrap();
            prop_assert!(e.iter().all(|v| v.is_finite() && *v >= 0.0));
        }
    }
}

/// Writes `bytes` as `input.EXT` beside a copy of Suzanne's buffer (so a mutated Suzanne still
/// finds its geometry; its textures are left out, which the loader must report) and loads it.
fn load_bytes(ext: &str, bytes: &[u8]) -> deep_gbuffer::Result<Scene> {
    let dir = std::env::temp_dir().join(format!("deep-gbuffer-prop-{}", std::process::id()));
    if !dir.join("Suzanne.bin").exists() {
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::copy(fixture("suzanne/Suzanne.bin"), dir.join("Suzanne.bin")).unwrap();
    }
    let path = dir.join(format!("input.{ext}"));
    std::fs::write(&path, bytes).unwrap();
    Scene::load(&path)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Arbitrary bytes are an error or a scene, never a panic.
    #[test]
    fn loaders_never_panic_on_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        for ext in ["obj", "gltf", "glb"] {
            let _ = load_bytes(ext, &bytes);
        }
        let mut glb = b"glTF".to_vec();
        glb.extend(&bytes);
        let _ = load_bytes("glb", &glb);
    }

    /// The shipped fixtures with bytes overwritten: an error or a scene, never a panic, and a
    /// scene that loads is a valid one.
    #[test]
    fn mutated_fixtures_never_panic(edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8)) {
        for (file, ext) in [("cornell/CornellBox-Original.obj", "obj"), ("suzanne/Suzanne.gltf", "gltf")] {
            let mut bytes = std::fs::read(fixture(file)).unwrap();
            for (at, value) in &edits {
                let i = at.index(bytes.len());
                bytes[i] = *value;
            }
            if let Ok(scene) = load_bytes(ext, &bytes) {
                prop_assert!(scene.validate().is_ok() || scene.triangles.is_empty());
            }
        }
    }
}
