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

/// Writes `bytes` to a file `input-N.EXT` of its own (the tests of this file run on parallel
/// threads) beside a copy of Suzanne's buffer, and returns its path.
fn temp_file(ext: &str, bytes: &[u8]) -> std::path::PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static DIR: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    static FILES: AtomicUsize = AtomicUsize::new(0);
    let dir = DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("deep-gbuffer-prop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::copy(fixture("suzanne/Suzanne.bin"), dir.join("Suzanne.bin")).unwrap();
        dir
    });
    let path = dir.join(format!("input-{}.{ext}", FILES.fetch_add(1, Ordering::Relaxed)));
    std::fs::write(&path, bytes).unwrap();
    path
}

/// Loads `bytes` as a scene file `input-N.EXT` ([`temp_file`]: a mutated Suzanne still finds
/// its geometry; its textures are left out, which the loader must report).
fn load_bytes(ext: &str, bytes: &[u8]) -> deep_gbuffer::Result<Scene> {
    let path = temp_file(ext, bytes);
    let scene = Scene::load(&path);
    std::fs::remove_file(&path).unwrap();
    scene
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

    /// The shipped EXR fixtures (a stored G-buffer, an environment) with bytes overwritten and
    /// cut short: an error or an image, never a panic, and never an allocation of whatever a
    /// mutated header declares (an abort, which ends this test's process).
    #[test]
    fn mutated_exr_files_never_panic(
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
        cut in any::<prop::sample::Index>(),
    ) {
        for file in ["gbuffer/cornell-48x36.exr", "environment/gradient.exr"] {
            let mut bytes = std::fs::read(fixture(file)).unwrap();
            // Within the headers (their first kilobyte), where a byte decides what is allocated.
            for (at, value) in &edits {
                let i = at.index(bytes.len().min(1024));
                bytes[i] = *value;
            }
            for length in [bytes.len(), cut.index(bytes.len())] {
                let path = temp_file("exr", &bytes[..length]);
                let _ = deep_gbuffer::GBufferLayer::read_exr(&path);
                let _ = deep_gbuffer::Environment::load_exr(&path);
                std::fs::remove_file(&path).unwrap();
            }
        }
    }
}

/// A glTF document drawn field by field: a node graph (children lists that may repeat or loop),
/// accessors with any component type, type, count, offset, stride and sparse part, a camera of
/// either type with or without its object.
fn structured_gltf() -> impl Strategy<Value = serde_json::Value> {
    // Mostly what the `gltf` crate's own validation accepts, so the readers behind it are reached.
    let component = prop::sample::select(vec![5120u64, 5121, 5122, 5123, 5125, 5126]);
    let ty = prop::sample::select(vec!["SCALAR", "VEC2", "VEC3", "VEC4"]);
    let count = prop_oneof![4 => 1u64..6, 1 => Just(3_000_000_000u64)];
    let accessor =
        (component, ty, count, prop::sample::select(vec![0u64, 4]), any::<bool>(), any::<bool>());
    let children = prop::collection::vec(prop::collection::vec(0u64..4, 0..3), 4);
    let stride = prop::option::of(prop::sample::select(vec![4u64, 8, 12, 16]));
    let camera = (prop::sample::select(vec!["perspective", "orthographic"]), any::<bool>());
    (accessor.clone(), accessor, children, stride, camera, any::<bool>())
        .prop_map(|(uv, index, children, stride, (cam_type, with_object), sparse_position)| {
            let bytes: Vec<u8> = (0..96u8).collect();
            let data = format!("data:application/octet-stream;base64,{}", base64::encode(&bytes));
            let drawn = |(c, t, n, offset, normalized, sparse): (u64, &str, u64, u64, bool, bool)| {
                let mut a = serde_json::json!({"bufferView": 1, "componentType": c, "type": t, "count": n, "byteOffset": offset, "normalized": normalized});
                if sparse {
                    a["sparse"] = serde_json::json!({"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 1}});
                }
                a
            };
            let mut position = serde_json::json!({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]});
            if sparse_position {
                position = serde_json::json!({"componentType": 5126, "count": 3_000_000_000u64, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1], "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 0}}});
            }
            let mut view = serde_json::json!({"buffer": 0, "byteLength": 48});
            if let Some(s) = stride {
                view["byteStride"] = s.into();
            }
            let nodes: Vec<serde_json::Value> = children
                .iter()
                .enumerate()
                .map(|(i, c)| {
                    let mut n = serde_json::json!({"children": c});
                    if i == 0 {
                        n["mesh"] = 0.into();
                        n["camera"] = 0.into();
                    }
                    n
                })
                .collect();
            let mut camera = serde_json::json!({"type": cam_type});
            if with_object {
                camera[cam_type] = serde_json::json!({"yfov": 0.8, "znear": 0.1, "xmag": 1.0, "ymag": 1.0, "zfar": 10.0});
            }
            serde_json::json!({
                "asset": {"version": "2.0"},
                "buffers": [{"uri": data, "byteLength": 96}],
                "bufferViews": [view, {"buffer": 0, "byteOffset": 48, "byteLength": 48}],
                "accessors": [position, drawn(uv), drawn(index)],
                "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
                "cameras": [camera],
                "nodes": nodes,
                "scenes": [{"nodes": [0]}]
            })
        })
}

/// Panics seen by the process since the hook below was set (a caught one too).
static PANICS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Documents drawn field by field load or fail with an error, without any panic (not even
    /// one the loader would catch) and within moments.
    #[test]
    fn structured_gltf_never_panics(doc in structured_gltf()) {
        static HOOK: std::sync::Once = std::sync::Once::new();
        HOOK.call_once(|| {
            let previous = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                PANICS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                previous(info);
            }));
        });
        let dir = std::env::temp_dir().join(format!("deep-gbuffer-prop-structured-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("structured.gltf");
        std::fs::write(&path, doc.to_string()).unwrap();
        let before = PANICS.load(std::sync::atomic::Ordering::SeqCst);
        let started = std::time::Instant::now();
        let _ = Scene::load(&path);
        prop_assert_eq!(PANICS.load(std::sync::atomic::Ordering::SeqCst), before, "{}", doc);
        prop_assert!(started.elapsed().as_secs() < 5, "{}", doc);
    }
}
