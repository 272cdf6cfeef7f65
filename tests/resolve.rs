//! The resolve kernel against its CPU reference, in both precisions.

mod common;

use approx::assert_abs_diff_eq;
use common::{GBUFFER_FIXTURES, fixture, gpu, render, render_frames};
use deep_gbuffer::cpu::resolve as cpu;
use deep_gbuffer::{Filter, GSample, Precision, Scene, Settings, Wrap};
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
    compare_from(scene, &scene.camera_or_default(), precision, width, height, color_tolerance);
}

fn compare_from(
    scene: &Scene,
    camera: &deep_gbuffer::Camera,
    precision: Precision,
    width: u32,
    height: u32,
    color_tolerance: f32,
) {
    let r = render(
        scene,
        camera,
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
            assert_abs_diff_eq!(a.reflectivity, b.reflectivity, epsilon = color_tolerance);
            // Relative: an emissive texture goes through the same sRGB decoding as the base
            // colour, so its tolerance is the colour's (at least 1e-3 of the value).
            let e_tol = b.emissive.max_element() * color_tolerance.max(1e-3) + 1e-6;
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
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    // Its resolve is built without the texture code (the textured tests below run with it).
    assert!(deep_gbuffer::SceneInfo::of(&scene).textureless);
    compare(&scene, Precision::Full, 80, 60, FULL_TOLERANCE);
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

/// Every texture slot (base colour, emissive, metallic-roughness, normal, occlusion), sampler
/// mode (clamp, mirrored repeat, nearest), the second coordinate set and texture transforms,
/// against the CPU resolve in both precisions, on a fixture whose textures vary across the view
/// (fixtures/textured/generate.py).
#[test]
fn every_texture_slot_matches_cpu_reference() {
    let scene = Scene::load(&fixture("textured/textured-quad.gltf")).unwrap();
    assert_eq!(scene.textures.len(), 5, "each image decoded once");
    assert!(scene.warnings.is_empty(), "everything the file uses is read: {:?}", scene.warnings);
    let m = &scene.materials[0];
    assert!(m.texture_slots().iter().all(Option::is_some));
    assert!(!deep_gbuffer::SceneInfo::of(&scene).textureless);
    let (base, emissive) = (m.base_color_texture.unwrap(), m.emissive_texture.unwrap());
    assert_eq!((base.wrap_s, base.wrap_t), (Wrap::ClampToEdge, Wrap::MirroredRepeat));
    assert_eq!((emissive.filter, emissive.tex_coord), (Filter::Nearest, 1));
    assert!((base.transform.matrix2.x_axis.x - 1.6 * 0.3f32.cos()).abs() < 1e-6);
    assert_eq!(m.occlusion_texture.unwrap().transform.translation, glam::Vec2::new(0.25, 0.0));
    assert_eq!((m.normal_scale, m.occlusion_strength), (0.8, 0.7));
    assert_eq!(scene.uvs1.len(), scene.positions.len());
    assert_eq!(scene.tangents.len(), scene.positions.len(), "MikkTSpace's, the file has none");
    let camera = deep_gbuffer::Camera::perspective(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, 60.0, 0.1);
    compare_from(&scene, &camera, Precision::Full, 64, 48, TEXTURED_TOLERANCE);
    // Packed: the 8-bit and binary16 rounding on top of the texture decoding's own error.
    compare_from(
        &scene,
        &camera,
        Precision::Packed,
        64,
        48,
        PACKED_COLOR_TOLERANCE + TEXTURED_TOLERANCE,
    );
    // The textures reach the G-buffer: emission, roughness, metal, reflectivity and occlusion
    // vary; the nearest-read checker gives its two values only.
    let r = render(&scene, &camera, Settings { timings: false, ..Settings::with_size(64, 48) });
    let g = gpu();
    let layer = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap();
    let shown: Vec<&GSample> = layer.samples.iter().filter(|s| s.depth > 0.0).collect();
    let spread = |f: &dyn Fn(&GSample) -> f32| {
        let v: Vec<f32> = shown.iter().map(|s| f(s)).collect();
        v.iter().copied().fold(f32::MIN, f32::max) - v.iter().copied().fold(f32::MAX, f32::min)
    };
    assert!(spread(&|s| s.emissive.x) > 1.0, "the emission checker");
    assert!(
        shown.iter().all(|s| s.emissive.x == 0.0 || (s.emissive.x - 2.0).abs() < 1e-5),
        "nearest texels only"
    );
    assert!(spread(&|s| s.roughness) > 0.5, "the roughness ramp");
    assert!(spread(&|s| s.metallic) > 0.9, "metal in one half");
    assert!(spread(&|s| s.reflectivity) > 0.3, "reflectivity per texel");
    assert!(spread(&|s| s.occlusion) > 0.3, "the occlusion ramp");
    assert!(shown.iter().all(|s| s.occlusion >= 0.3 - 1e-3), "strength 0.7 keeps 0.3 at least");
    // The normal texture leans the left half towards +x and the right half up the image (+y),
    // the frame of the generated tangents following glTF's convention.
    let (w, _) = (layer.width, layer.height);
    for (p, s) in layer.samples.iter().enumerate().filter(|(_, s)| s.depth > 0.0) {
        let x = (p as u32 % w) as f32 / w as f32;
        // Where bilinear filtering reads one half only (texel centres 1 and 2, 3 and 4 of 4
        // across a quad that spans 0.24 to 0.76 of the view).
        let half =
            [(0.32..=0.42, true), (0.58..=0.68, false)].into_iter().find(|(r, _)| r.contains(&x));
        if let Some((_, left)) = half {
            let (lean, other) =
                if left { (s.normal.x, s.normal.y) } else { (s.normal.y, s.normal.x) };
            assert!(lean > 0.25 && other.abs() < 0.05, "pixel {p}: normal {}", s.normal);
        }
    }
    assert!(
        r.renderer.passes().contains(&deep_gbuffer::PassId::Reflections),
        "a metal that reflects"
    );
}

/// A normal texture on a scene built in code, without tangents: each triangle's own
/// texture-space frame gives the same lean as MikkTSpace's on the same quad, and a mirrored
/// coordinate set mirrors the frame (the lean stays up the image).
#[test]
fn normal_textures_lean_the_same_way_without_tangents() {
    let quad = |mirrored: bool| {
        let mut scene = Scene::default();
        let u = |x: f32| if mirrored { 1.0 - x } else { x };
        scene
            .push_mesh(deep_gbuffer::scene::MeshData {
                positions: &[
                    Vec3::new(-1.0, -1.0, 0.0),
                    Vec3::new(1.0, -1.0, 0.0),
                    Vec3::new(1.0, 1.0, 0.0),
                    Vec3::new(-1.0, 1.0, 0.0),
                ],
                normals: &[Vec3::Z; 4],
                uvs: &[
                    glam::Vec2::new(u(0.0), 1.0),
                    glam::Vec2::new(u(1.0), 1.0),
                    glam::Vec2::new(u(1.0), 0.0),
                    glam::Vec2::new(u(0.0), 0.0),
                ],
                indices: &[0, 1, 2, 0, 2, 3],
                ..Default::default()
            })
            .unwrap();
        // One texel leaning towards +u and up the image.
        scene.textures.push(deep_gbuffer::scene::Texture {
            width: 1,
            height: 1,
            rgba8: vec![200, 200, 180, 255],
        });
        scene.materials.push(deep_gbuffer::Material {
            normal_texture: Some(deep_gbuffer::TextureRef::new(0)),
            ..Default::default()
        });
        scene.ensure_lights();
        scene
    };
    let camera = deep_gbuffer::Camera::perspective(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, 40.0, 0.1);
    let g = gpu();
    for mirrored in [false, true] {
        let scene = quad(mirrored);
        compare_from(&scene, &camera, Precision::Full, 16, 16, TEXTURED_TOLERANCE);
        let r = render(&scene, &camera, Settings { timings: false, ..Settings::with_size(16, 16) });
        let layer = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap();
        let n = layer.at(8, 8).normal;
        // +u is +x, or -x where u is mirrored; up the image is +y either way.
        let x = if mirrored { -n.x } else { n.x };
        assert!(x > 0.3 && n.y > 0.3 && n.z > 0.2, "mirrored {mirrored}: {n}");
    }
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

/// The stored G-buffers (fixtures/gbuffer/, which the other kernels' tests shade) are what the
/// rasterizer and resolve produce today for their scene, camera and size.
#[test]
fn stored_gbuffers_are_what_the_rasterizer_draws() {
    let g = gpu();
    for (file, spec) in GBUFFER_FIXTURES {
        let stored = deep_gbuffer::GBufferLayer::read_exr(&fixture(file)).unwrap();
        let mut scene = Scene::from_spec(spec).unwrap();
        scene.ensure_lights();
        let (w, h) = (stored[0].width, stored[0].height);
        let r = render(
            &scene,
            &scene.camera_or_default(),
            Settings { timings: false, layers: 2, ..Settings::with_size(w, h) },
        );
        for (layer, expected) in stored.iter().enumerate() {
            let drawn = r.renderer.read_gbuffer(&g.device, &g.queue, layer).unwrap();
            for (p, (a, b)) in drawn.samples.iter().zip(&expected.samples).enumerate() {
                let (a, b) = (a.channels(), b.channels());
                for c in 0..a.len() {
                    let tolerance = FULL_TOLERANCE * b[c].abs().max(1.0);
                    assert!(
                        (a[c] - b[c]).abs() <= tolerance,
                        "{file} layer {layer} pixel {p} {}: drawn {} stored {}",
                        deep_gbuffer::gbuffer::EXR_CHANNELS[c],
                        a[c],
                        b[c]
                    );
                }
            }
        }
    }
}

/// A G-buffer written to EXR reads back bit for bit; files that are not G-buffers are refused
/// with the file named.
#[test]
fn gbuffer_exr_round_trips_and_refuses_other_files() {
    let stored = deep_gbuffer::GBufferLayer::read_exr(&fixture(GBUFFER_FIXTURES[0].0)).unwrap();
    let path = std::env::temp_dir().join(format!("deep-gbuffer-{}-rt.exr", std::process::id()));
    deep_gbuffer::GBufferLayer::write_exr(&path, &stored).unwrap();
    let back = deep_gbuffer::GBufferLayer::read_exr(&path).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(back.len(), 2);
    for (a, b) in back.iter().zip(&stored) {
        assert_eq!((a.width, a.height), (b.width, b.height));
        let bits = |l: &deep_gbuffer::GBufferLayer| {
            l.encode_full().iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        };
        assert_eq!(bits(a), bits(b));
    }
    // An RGB image has no G-buffer channels.
    match deep_gbuffer::GBufferLayer::read_exr(&fixture("environment/gradient.exr")) {
        Err(deep_gbuffer::Error::ImageRead { message, .. }) => {
            assert!(message.contains("depth"), "{message}")
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        deep_gbuffer::GBufferLayer::read_exr(&fixture("cornell/CornellBox-Original.mtl")),
        Err(deep_gbuffer::Error::ImageRead { .. })
    ));
    // Headers whose data windows declare more than a G-buffer can be are refused from the
    // headers, before anything is allocated for them (the reader would allocate what they say:
    // 39 GB for one such file, an abort).
    let bytes = std::fs::read(fixture(GBUFFER_FIXTURES[0].0)).unwrap();
    let window = |bytes: &[u8], max: i32| {
        let mut out = bytes.to_vec();
        let key = b"dataWindow\0box2i\0";
        let mut found = 0;
        for at in 0..out.len() - key.len() {
            if &out[at..at + key.len()] == key {
                // The attribute's size (16), then xMin, yMin, xMax, yMax.
                let value = at + key.len() + 4;
                out[value + 8..value + 12].copy_from_slice(&max.to_le_bytes());
                out[value + 12..value + 16].copy_from_slice(&max.to_le_bytes());
                found += 1;
            }
        }
        assert!(found > 0);
        out
    };
    let dir = std::env::temp_dir().join(format!("deep-gbuffer-exr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (max, needle) in [(20_000, "pixels a side"), (15_999, "samples declared")] {
        let path = dir.join(format!("window-{max}.exr"));
        std::fs::write(&path, window(&bytes, max)).unwrap();
        match deep_gbuffer::GBufferLayer::read_exr(&path) {
            Err(deep_gbuffer::Error::ImageRead { message, .. }) => {
                assert!(message.contains(needle), "{max}: {message}")
            }
            other => panic!("{max}: {:?}", other.map(|l| l.len())),
        }
    }
}

/// A provided G-buffer must fit the renderer: its size, its layer count, the full encoding.
#[test]
fn a_provided_gbuffer_that_does_not_fit_is_refused() {
    let g = gpu();
    let stored = deep_gbuffer::GBufferLayer::read_exr(&fixture(GBUFFER_FIXTURES[0].0)).unwrap();
    let scene = Scene::from_spec(GBUFFER_FIXTURES[0].1).unwrap();
    let buffers = deep_gbuffer::SceneBuffers::upload(&g.device, &scene).unwrap();
    let camera = scene.camera_or_default();
    let (w, h) = (stored[0].width, stored[0].height);
    let cases = [
        (Settings::with_size(w + 1, h), 2, "gbuffer"),
        (Settings::with_size(w, h), 1, "gbuffer"),
        (Settings { precision: Precision::Packed, ..Settings::with_size(w, h) }, 2, "precision"),
    ];
    for (settings, count, name) in cases {
        let mut renderer = deep_gbuffer::Renderer::new(&g.device, &g.queue, settings).unwrap();
        match renderer.render_gbuffer(&g.device, &g.queue, &buffers, &camera, &stored[..count]) {
            Err(deep_gbuffer::Error::InvalidSetting { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {other:?}"),
        }
    }
    // NaN or infinity anywhere in a sample is refused, naming the layer and pixel.
    let mut renderer =
        deep_gbuffer::Renderer::new(&g.device, &g.queue, Settings::with_size(w, h)).unwrap();
    for poison in [f32::NAN, f32::INFINITY] {
        let mut bad = stored.clone();
        bad[1].samples[7].emissive.y = poison;
        let e = renderer.render_gbuffer(&g.device, &g.queue, &buffers, &camera, &bad).unwrap_err();
        assert!(e.to_string().contains("layer 1 pixel 7"), "{e}");
    }
}

/// Each position encoding: the G-buffer's depths are the CPU's `stored_depth` of the visibility
/// buffer's (to f32 evaluation order: the screen encoding divides through the projection), and
/// within the encoding's own bound of the exact depth: half a 16-bit step of z/w times
/// dd/d(z/w) = d^2 / |P32| for `screen-u16`, 2^-11 relative for `view-f16`.
#[test]
fn position_encodings_give_back_the_depth_they_can_hold() {
    use deep_gbuffer::PositionEncoding;
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let g = gpu();
    for position in
        [PositionEncoding::ViewDepthF32, PositionEncoding::ScreenU16, PositionEncoding::ViewF16]
    {
        let s = Settings { position, timings: false, layers: 2, ..Settings::with_size(48, 36) };
        let r = render(&scene, &camera, s);
        let p32 = r.frame.proj[3][2].abs();
        let mut worst = 0.0f32;
        for (layer, vis) in [(0, &r.vis0), (1, &r.vis1)] {
            let got = r.renderer.read_gbuffer(&g.device, &g.queue, layer).unwrap();
            for (p, (a, &word)) in got.samples.iter().zip(vis.iter()).enumerate() {
                let Some(exact) = deep_gbuffer::gbuffer::vis_depth(word) else { continue };
                let expected = cpu::stored_depth(&r.frame, exact);
                assert!(
                    (a.depth - expected).abs() <= 4.0 * f32::EPSILON * expected,
                    "{position:?} layer {layer} pixel {p}: {} against {expected}",
                    a.depth
                );
                let bound = match position {
                    PositionEncoding::ViewDepthF32 => 0.0,
                    PositionEncoding::ScreenU16 => {
                        0.5 / 65535.0 * exact * exact / p32 * 1.01 + 8.0 * f32::EPSILON * exact
                    }
                    PositionEncoding::ViewF16 => exact / 2048.0,
                };
                let error = (a.depth - exact).abs();
                assert!(error <= bound, "{position:?}: depth {exact} held as {}", a.depth);
                worst = worst.max(error / exact);
            }
        }
        eprintln!("{position:?}: largest relative depth error {worst:.2e}");
        if position != PositionEncoding::ViewDepthF32 {
            assert!(worst > 0.0, "{position:?} quantizes");
        }
    }
}

/// The depth each encoding gives back over the depth range, for a camera with its near plane at
/// 0.1 and its far plane at 1000 or at infinity, depth running forward or reversed (printed: the
/// README's table). 16-bit z/w spaces its steps evenly in 1/d whichever way depth runs, so its
/// error grows as d^2 / near in every case (reverse-Z helps floats, not fixed point); binary16
/// keeps 2^-11 of the depth everywhere.
#[test]
fn position_error_over_the_depth_range() {
    use deep_gbuffer::frame::{
        CameraMatrices, FRAME_POSITION_SCREEN_U16, FRAME_POSITION_VIEW_F16, FrameUniform,
    };
    use deep_gbuffer::scene::{Camera, Projection};
    let depths = [0.53f32, 1.37, 3.71, 17.3, 61.9, 251.3, 913.7];
    eprintln!("| projection | encoding | {} |", depths.map(|d| format!("d = {d}")).join(" | "));
    for (far, reverse_z) in [(Some(1000.0), false), (Some(1000.0), true), (None, true)] {
        let mut camera = Camera::perspective(Vec3::ZERO, Vec3::NEG_Z, 60.0, 0.1);
        camera.projection = Projection::Perspective { fov_y_deg: 60.0, near: 0.1, far, reverse_z };
        let m = CameraMatrices::new(&camera, 64, 64);
        let frame = FrameUniform::new(&camera, m, m, 64, 64, 0.0, (0, 0, 0));
        for (name, flags) in
            [("screen-u16", FRAME_POSITION_SCREEN_U16), ("view-f16", FRAME_POSITION_VIEW_F16)]
        {
            let f = FrameUniform { flags, ..frame };
            let errors: Vec<f32> =
                depths.iter().map(|&d| (cpu::stored_depth(&f, d) - d).abs()).collect();
            eprintln!(
                "| far {far:?}, reverse {reverse_z} | {name} | {} |",
                errors.iter().map(|e| format!("{e:.2e}")).collect::<Vec<_>>().join(" | ")
            );
            for (&d, &e) in depths.iter().zip(&errors) {
                let bound = if flags == FRAME_POSITION_VIEW_F16 {
                    d / 2048.0
                } else {
                    0.5 / 65535.0 * d * d / 0.1 * 1.05 + 1e-6 * d
                };
                assert!(e <= bound, "{name}, far {far:?}, reverse {reverse_z}: {d} off by {e}");
            }
            if flags == FRAME_POSITION_SCREEN_U16 {
                // Far away the 16-bit steps are wider than binary16's relative ones.
                assert!(errors[6] > depths[6] / 2048.0, "{errors:?}");
            }
        }
    }
}

/// A frame's own resolve runs over the 8x8 tiles that hold a surface and writes the empty record
/// over the others: after the camera turns until background shows where the box was, every
/// pixel of either layer without a surface holds the empty record again, not the frame before's,
/// on an image whose sides are not multiples of 8 (tiles cut by both edges).
#[test]
fn pixels_left_without_a_surface_hold_the_empty_record() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let turned = camera.orbited(75.0);
    let settings = Settings { timings: false, layers: 2, ..Settings::with_size(37, 29) };
    let g = gpu();
    let before = render(&scene, &camera, settings.clone());
    let after = render_frames(&scene, &[camera, turned], settings);
    let mut uncovered = 0;
    for layer in 0..2 {
        let was = before.renderer.read_gbuffer(&g.device, &g.queue, layer).unwrap();
        let now = after.renderer.read_gbuffer(&g.device, &g.queue, layer).unwrap();
        let vis = if layer == 0 { &after.vis0 } else { &after.vis1 };
        let reference = cpu::resolve(&after.frame, &scene, vis);
        for (p, ((a, b), w)) in now.samples.iter().zip(&reference).zip(&was.samples).enumerate() {
            if b.depth == 0.0 {
                assert_eq!(a, b, "layer {layer} pixel {p}: the empty record");
                uncovered += usize::from(w.depth > 0.0);
            }
        }
    }
    assert!(uncovered > 20, "the turn uncovers pixels that held a surface ({uncovered})");
}
