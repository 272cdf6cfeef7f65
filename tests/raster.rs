//! The compute rasterizer against its CPU reference, watertightness, layer separation, the
//! layer-1 variants, the 32-bit path and hard cases.

mod common;

use common::{fixture, gpu, mesh, render, render_frames, soup};
use deep_gbuffer::PassId;
use deep_gbuffer::cpu::raster::{self as cpu, RasterInput, double_sided_triangles};
use deep_gbuffer::frame::FrameUniform;
use deep_gbuffer::gbuffer::{VIS_EMPTY, vis_depth, vis_id};
use deep_gbuffer::scene::{Camera, Projection};
use deep_gbuffer::{AtomicPath, Layer1Variant, RasterWork, Scene, SceneBuffers, Settings};
use glam::Vec3;
use rand::{Rng, SeedableRng};

/// Raster tests need no obscurance passes.
fn settings(width: u32, height: u32) -> Settings {
    let ao = deep_gbuffer::AoSettings { enabled: false, ..Default::default() };
    Settings { timings: false, ao, layers: 2, ..Settings::with_size(width, height) }
}

/// Pixels where the GPU word differs from the CPU's, with how many of them hold another
/// triangle (or none where the other has one), the largest depth difference in ulp among the
/// rest, and a description of the first few: on a device that rounds otherwise than IEEE
/// operation by operation (README, *Tests*), what differs and by how much.
fn mismatches(gpu: &[u64], cpu: &[u64], width: u32) -> (usize, String) {
    let mut n = 0;
    let (mut ids, mut ulps) = (0usize, 0u32);
    let mut report = String::new();
    for (p, (g, c)) in gpu.iter().zip(cpu).enumerate() {
        if g != c {
            n += 1;
            match (vis_depth(*g), vis_depth(*c)) {
                (Some(a), Some(b)) if vis_id(*g) == vis_id(*c) => {
                    ulps = ulps.max(a.to_bits().abs_diff(b.to_bits()));
                }
                _ => ids += 1,
            }
            if n <= 5 {
                report += &format!(
                    "\n  pixel ({}, {}): gpu id {:?} depth {:?}, cpu id {:?} depth {:?}",
                    p as u32 % width,
                    p as u32 / width,
                    vis_id(*g),
                    vis_depth(*g),
                    vis_id(*c),
                    vis_depth(*c)
                );
            }
        }
    }
    if n > 0 {
        report = format!(
            " {ids} with another triangle or none, the rest a depth at most {ulps} ulp away;{report}"
        );
    }
    (n, report)
}

/// Both layers of `scene` from `camera`: the GPU's must equal the CPU reference's bit for bit,
/// with the work shared out both ways (`RasterWork::Gpu`, whose small-triangle size, slices,
/// tile test and early depth test a GPU gets, and `RasterWork::Cpu`, a CPU driver's, without the
/// early test), whatever the device.
fn assert_matches_cpu(scene: &Scene, camera: &Camera, settings: Settings) {
    let width = settings.width;
    let ds = double_sided_triangles(scene);
    let input = RasterInput::new(scene, &ds);
    for raster_work in [RasterWork::Gpu, RasterWork::Cpu] {
        let r = render(scene, camera, Settings { raster_work, ..settings.clone() });
        let cpu0 = cpu::raster_layer0(&r.frame, &input);
        let cpu1 = cpu::raster_layer1(&r.frame, &input, &cpu0, false);
        let (n0, report0) = mismatches(&r.vis0, &cpu0, width);
        let (n1, report1) = mismatches(&r.vis1, &cpu1, width);
        assert!(cpu0.iter().any(|&w| w != VIS_EMPTY), "the view is not empty");
        assert_eq!(n0, 0, "{raster_work:?}: layer 0 differs from the CPU at {n0} pixels:{report0}");
        assert_eq!(n1, 0, "{raster_work:?}: layer 1 differs from the CPU at {n1} pixels:{report1}");
    }
}

fn cornell() -> (Scene, Camera) {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    (scene, camera)
}

#[test]
fn cornell_matches_cpu_reference() {
    let (scene, camera) = cornell();
    assert_matches_cpu(&scene, &camera, settings(96, 72));
}

#[test]
fn dense_gltf_matches_cpu_reference() {
    let scene = Scene::load(&fixture("suzanne/Suzanne.gltf")).unwrap();
    let camera = scene.camera_or_default();
    assert_matches_cpu(&scene, &camera, Settings { dz: 0.01, ..settings(128, 96) });
    // 121,496 triangles of a CAD model: many thin, many smaller than a pixel.
    let engine = Scene::load(&fixture("engine/2CylinderEngine.gltf")).unwrap();
    let camera = engine.camera_or_default();
    assert_matches_cpu(&engine, &camera, Settings { dz: 1.0, ..settings(96, 72) });
}

/// Tall, narrow triangles: their bounds are 1 to 5 of the 16x16 tiles across and about 15 down,
/// so with a GPU's 8 tiles a workgroup each workgroup's walk steps past a whole row of tiles at
/// once (slices at least the tiles across) and wraps on every step; the walk must land on the
/// same pixels and edge values as evaluating each afresh.
#[test]
fn tall_triangles_walked_past_whole_rows_match_cpu_reference() {
    let triangles: Vec<[Vec3; 3]> = [0.02f32, 0.1, 0.25]
        .iter()
        .enumerate()
        .map(|(i, &w)| {
            let x = -0.45 + 0.45 * i as f32;
            [Vec3::new(x - w, -1.1, 0.0), Vec3::new(x + w, -1.0, 0.1), Vec3::new(x, 1.1, -0.1)]
        })
        .collect();
    let scene = soup(&triangles, true);
    let camera = Camera::perspective(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 60.0, 0.05);
    assert_matches_cpu(&scene, &camera, settings(160, 256));
}

fn random_soup(seed: u64, count: usize, extent: f32) -> Vec<[Vec3; 3]> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let v = |r: &mut rand_chacha::ChaCha8Rng| {
        Vec3::new(
            r.random_range(-extent..extent),
            r.random_range(-extent..extent),
            r.random_range(-extent..extent),
        )
    };
    (0..count)
        .map(|_| {
            let a = v(&mut rng);
            // Mostly small triangles near a random centre, some large ones.
            let size = if rng.random_bool(0.2) { 2.0 } else { 0.15 };
            let b = a + (v(&mut rng) / extent) * size;
            let c = a + (v(&mut rng) / extent) * size;
            [a, b, c]
        })
        .collect()
}

#[test]
fn random_soups_match_cpu_reference() {
    for seed in 0..4 {
        for double_sided in [false, true] {
            let scene = soup(&random_soup(seed, 400, 1.5), double_sided);
            // The camera sits inside the soup's bounds, so many triangles cross the near plane.
            let camera = Camera::perspective(Vec3::new(0.1, 0.2, 1.2), Vec3::ZERO, 60.0, 0.05);
            assert_matches_cpu(&scene, &camera, Settings { dz: 0.02, ..settings(80, 60) });
        }
    }
}

/// Triangles larger than the work items can split: 600 screen-covering triangles at 512x384
/// (768 tiles: 12 workgroups each at 64 tiles a workgroup, 96 at 8) ask for at least 6600
/// work items, more than the 4696 there is room for, so many are drawn by one workgroup each.
/// The result must not change.
#[test]
fn screen_covering_layers_past_the_work_items_match_cpu_reference() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let triangles: Vec<[Vec3; 3]> = (0..600)
        .map(|_| {
            let z = rng.random_range(-2.0..0.0);
            let tilt = rng.random_range(-0.3..0.3);
            [
                Vec3::new(-8.0, -6.0, z),
                Vec3::new(8.0, -6.0, z + tilt),
                Vec3::new(0.0, 9.0, z - tilt),
            ]
        })
        .collect();
    let camera = Camera::perspective(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 60.0, 0.05);
    let scene = soup(&triangles, false);
    let settings = Settings { dz: 0.01, ..settings(512, 384) };
    assert_matches_cpu(&scene, &camera, settings.clone());
    let r = render(&scene, &camera, settings);
    let d = r.renderer.diagnostics(&gpu().device, &gpu().queue).unwrap();
    assert!(d.large_triangles >= 600, "{d:?}");
    assert_eq!(d.dropped_triangles, 0);
}

/// A w x h grid of quads on the plane z = `z`, spanning [lo, hi] in x and y.
fn grid(n: usize, lo: f32, hi: f32, z: f32, jitter: f32, seed: u64) -> Scene {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let edge = i == 0 || j == 0 || i == n || j == n;
            let d = if edge { 0.0 } else { jitter };
            let s = (hi - lo) / n as f32;
            positions.push(Vec3::new(
                lo + i as f32 * s + rng.random_range(-d..=d) * s,
                lo + j as f32 * s + rng.random_range(-d..=d) * s,
                z,
            ));
        }
    }
    let mut indices = Vec::new();
    let row = (n + 1) as u32;
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * row + i;
            indices.extend_from_slice(&[a, a + 1, a + row, a + 1, a + row + 1, a + row]);
        }
    }
    mesh(&positions, &indices, false)
}

fn coverage(scene: &Scene, frame: &FrameUniform) -> Vec<u32> {
    coverage_shared_out(scene, frame, RasterWork::Auto)
}

fn coverage_shared_out(scene: &Scene, frame: &FrameUniform, work: RasterWork) -> Vec<u32> {
    let g = gpu();
    let buffers = SceneBuffers::upload(&g.device, scene).unwrap();
    deep_gbuffer::testing::coverage_counts(&g.device, &g.queue, &buffers, frame, work).unwrap()
}

fn frame_for(scene: &Scene, camera: &Camera, width: u32, height: u32) -> FrameUniform {
    render(scene, camera, settings(width, height)).frame
}

fn ortho(height: f32) -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.0, 5.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        projection: Projection::Orthographic { height, near: 0.1, far: 10.0 },
        lens: Default::default(),
    }
}

#[test]
fn screen_filling_grids_cover_every_pixel_exactly_once() {
    // Vertices exactly on pixel centres and edges (an orthographic grid aligned to the pixels,
    // where the top-left rule decides every edge), then jittered vertices (less than a quarter cell, so no quad folds), then a finer grid.
    let (w, h) = (64u32, 64u32);
    let camera = ortho(2.0);
    for (n, jitter, seed) in [(16, 0.0, 0), (16, 0.35, 1), (64, 0.24, 2), (7, 0.3, 3)] {
        let scene = grid(n, -1.25, 1.25, 0.0, jitter, seed);
        let frame = frame_for(&scene, &camera, w, h);
        let counts = coverage(&scene, &frame);
        let bad: Vec<(usize, u32)> =
            counts.iter().copied().enumerate().filter(|&(_, c)| c != 1).take(5).collect();
        assert!(
            bad.is_empty(),
            "grid {n} jitter {jitter}: (pixel, count) not covered exactly once: {bad:?}"
        );
        let ds = double_sided_triangles(&scene);
        assert_eq!(counts, cpu::coverage_counts(&frame, &RasterInput::new(&scene, &ds)));
    }
}

#[test]
fn floor_through_the_near_plane_covers_every_pixel_below_the_horizon_once() {
    // A floor that extends behind the camera: many triangles are clipped by the near plane and
    // their clipped edges must still meet without cracks.
    let scene = {
        let mut s = grid(24, -30.0, 30.0, 0.0, 0.3, 7);
        for p in &mut s.positions {
            *p = Vec3::new(p.x, -1.0, p.y); // the xz plane at y = -1, facing up
        }
        for t in &mut s.triangles {
            t.swap(1, 2);
        }
        s
    };
    let camera = Camera::perspective(Vec3::ZERO, Vec3::new(0.0, -0.6, -1.0), 70.0, 0.1);
    let (w, h) = (80, 60);
    let frame = frame_for(&scene, &camera, w, h);
    let counts = coverage(&scene, &frame);
    let covered = counts.iter().filter(|&&c| c == 1).count();
    assert!(counts.iter().all(|&c| c <= 1), "a pixel was covered twice");
    // Every covered column is covered from some row to the bottom, without holes.
    for x in 0..w {
        let column: Vec<u32> = (0..h).map(|y| counts[(y * w + x) as usize]).collect();
        let first = column.iter().position(|&c| c == 1).expect("the floor reaches every column");
        assert!(column[first..].iter().all(|&c| c == 1), "crack in column {x}: {column:?}");
    }
    assert!(covered > (w * h / 2) as usize);
}

/// A closed double-sided sphere: every pixel is covered by exactly 0 or 2 fragments (front and
/// back); a crack anywhere shows up as 1 or 3.
#[test]
fn closed_mesh_is_watertight() {
    // builtin:grid with few triangles is one unit sphere at (0, 1, 0) on a ground square.
    let grid = Scene::from_spec("builtin:grid-600").unwrap();
    let ground = grid.triangle_materials.iter().copied().max().unwrap();
    let tris: Vec<[Vec3; 3]> = (0..grid.triangles.len())
        .filter(|&t| grid.triangle_materials[t] != ground)
        .map(|t| grid.triangles[t].map(|i| grid.positions[i as usize]))
        .collect();
    assert!(tris.len() > 400);
    let scene = soup(&tris, true);
    let center = Vec3::new(0.0, 1.0, 0.0);
    let camera = Camera::perspective(center + Vec3::new(0.3, 0.5, 3.0), center, 40.0, 0.1);
    let frame = frame_for(&scene, &camera, 96, 96);
    let counts = coverage(&scene, &frame);
    let bad: Vec<(usize, u32)> =
        counts.iter().copied().enumerate().filter(|&(_, c)| c != 0 && c != 2).take(5).collect();
    assert!(bad.is_empty(), "(pixel, count) with a crack or an overlap: {bad:?}");
    assert!(
        counts.iter().filter(|&&c| c == 2).count() > 2000,
        "the sphere covers a good part of the view"
    );
}

#[test]
fn layer1_is_the_nearest_surface_beyond_dz() {
    let (scene, camera) = cornell();
    for dz in [0.0f32, 0.05, 0.5] {
        let r = render(&scene, &camera, Settings { dz, ..settings(64, 48) });
        let ds = double_sided_triangles(&scene);
        let mut fragments: Vec<Vec<f32>> = vec![Vec::new(); r.vis0.len()];
        cpu::rasterize(&r.frame, &RasterInput::new(&scene, &ds), |x, y, d, _| {
            fragments[(y * 64 + x) as usize].push(d)
        });
        let mut layer1_pixels = 0;
        for (p, frags) in fragments.iter().enumerate() {
            let z0 = vis_depth(r.vis0[p]);
            assert_eq!(z0, frags.iter().copied().reduce(f32::min), "layer 0 is the nearest at {p}");
            let expected =
                z0.and_then(|z0| frags.iter().copied().filter(|&d| d > z0 + dz).reduce(f32::min));
            let z1 = vis_depth(r.vis1[p]);
            assert_eq!(z1, expected, "layer 1 at pixel {p} with dz {dz}");
            if let (Some(z0), Some(z1)) = (z0, z1) {
                assert!(z1 > z0 + dz, "separation invariant at {p}");
                layer1_pixels += 1;
            }
        }
        assert!(
            layer1_pixels > 200,
            "dz {dz}: the boxes give a second layer where they hide the walls ({layer1_pixels})"
        );
        if dz == 0.0 {
            // Δz = 0 is the second-nearest surface (a 2-layer k-buffer).
            for (p, frags) in fragments.iter().enumerate() {
                let mut sorted = frags.clone();
                sorted.sort_by(f32::total_cmp);
                sorted.dedup();
                assert_eq!(vis_depth(r.vis1[p]), sorted.get(1).copied(), "second nearest at {p}");
            }
        }
    }
}

#[test]
fn one_pass_variants_equal_two_pass_on_a_static_camera() {
    let (scene, camera) = cornell();
    let base = Settings { dz: 0.05, ..settings(96, 72) };
    let exact = render(&scene, &camera, base.clone());
    for layer1 in [
        Layer1Variant::Previous,
        Layer1Variant::Reproject,
        Layer1Variant::Predict,
        Layer1Variant::Delay,
    ] {
        let r = render_frames(
            &scene,
            &[camera.clone(), camera.clone()],
            Settings { layer1, ..base.clone() },
        );
        let next = matches!(layer1, Layer1Variant::Predict | Layer1Variant::Delay);
        let raster: Vec<&PassId> =
            r.renderer.passes().iter().take_while(|p| **p != PassId::Resolve).collect();
        let expected = if next {
            vec![&PassId::RasterClear, &PassId::RasterLayers, &PassId::RasterNext]
        } else {
            vec![&PassId::RasterClear, &PassId::RasterLayers]
        };
        assert_eq!(raster, expected, "{layer1:?}");
        assert_eq!(r.vis0, exact.vis0, "{layer1:?} layer 0");
        let (n, report) = mismatches(&r.vis1, &exact.vis1, 96);
        assert_eq!(n, 0, "{layer1:?} layer 1 differs from TwoPass at {n} pixels:{report}");
    }
}

/// Under camera motion the one-pass Reproject variant's layer 1 equals the CPU reference's bit for
/// bit: each fragment reprojected into the previous frame (`FrameUniform::reproject`) and tested
/// against the previous frame's layer 0 there.
#[test]
fn reprojected_layer1_under_motion_matches_cpu_reference() {
    let (scene, camera) = cornell();
    let mut moved = camera.clone();
    let turn = glam::Quat::from_rotation_y(3f32.to_radians());
    moved.eye = moved.target + turn * (moved.eye - moved.target) + Vec3::new(0.0, 0.05, 0.0);
    let settings = Settings { layer1: Layer1Variant::Reproject, dz: 0.05, ..settings(96, 72) };
    let r = render_frames(&scene, &[camera.clone(), moved], settings.clone());
    assert_eq!(r.renderer.passes()[1], PassId::RasterLayers);
    let ds = double_sided_triangles(&scene);
    let input = RasterInput::new(&scene, &ds);
    let first = render(&scene, &camera, settings);
    let previous = cpu::raster_layer0(&first.frame, &input);
    assert_eq!(first.vis0, previous, "the previous frame's layer 0");
    let cpu1 = cpu::raster_layer1(&r.frame, &input, &previous, true);
    assert!(cpu1.iter().any(|&w| w != VIS_EMPTY), "layer 1 is not empty");
    let (n, report) = mismatches(&r.vis1, &cpu1, 96);
    assert_eq!(n, 0, "reprojected layer 1 differs from the CPU reference at {n} pixels:{report}");
}

#[test]
fn first_frame_of_a_one_pass_variant_is_two_pass() {
    let (scene, camera) = cornell();
    let r =
        render(&scene, &camera, Settings { layer1: Layer1Variant::Reproject, ..settings(32, 24) });
    assert_eq!(
        r.renderer.passes()[..4],
        [PassId::RasterClear, PassId::RasterLayer0, PassId::RasterLayer1, PassId::Resolve]
    );
}

#[test]
fn int32_path_gives_identical_visibility_buffers() {
    let (scene, camera) = cornell();
    let soup_scene = soup(&random_soup(9, 300, 1.5), true);
    let soup_camera = Camera::perspective(Vec3::new(0.1, 0.2, 1.2), Vec3::ZERO, 60.0, 0.05);
    if !gpu().device.features().contains(deep_gbuffer::Renderer::int64_features()) {
        panic!(
            "this test compares the two paths and needs a device with 64-bit atomics (lavapipe has them)"
        );
    }
    // Each path with and without its early depth test (a GPU's work has it, a CPU driver's not).
    for raster_work in [RasterWork::Gpu, RasterWork::Cpu] {
        for (scene, camera) in [(&scene, &camera), (&soup_scene, &soup_camera)] {
            let at = |atomics| Settings { atomics, raster_work, ..settings(80, 60) };
            let a = render(scene, camera, at(AtomicPath::Int64));
            let b = render(scene, camera, at(AtomicPath::Int32));
            assert_eq!(a.renderer.raster_path(), "int64");
            assert_eq!(b.renderer.raster_path(), "int32");
            assert_eq!(a.vis0, b.vis0, "{raster_work:?}");
            assert_eq!(a.vis1, b.vis1, "{raster_work:?}");
        }
    }
}

#[test]
fn triangle_straddling_the_near_plane_leaves_no_stray_pixel() {
    // One big triangle from behind the camera to far in front, and its CPU reference.
    let tri = [Vec3::new(-2.0, -0.5, 3.0), Vec3::new(2.0, -0.5, 3.0), Vec3::new(0.0, -0.5, -20.0)];
    let scene = soup(&[tri], true);
    let camera = Camera::perspective(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 60.0, 0.1);
    let r = render(&scene, &camera, settings(64, 48));
    let ds = double_sided_triangles(&scene);
    let cpu0 = cpu::raster_layer0(&r.frame, &RasterInput::new(&scene, &ds));
    assert_eq!(r.vis0, cpu0);
    // The plane y = -0.5 is only below the horizon: no pixel in the upper half.
    for y in 0..24 {
        for x in 0..64 {
            assert_eq!(r.vis0[(y * 64 + x) as usize], VIS_EMPTY, "stray pixel ({x}, {y})");
        }
    }
    for w in &r.vis0 {
        if let Some(d) = vis_depth(*w) {
            assert!(d.is_finite() && d >= 0.1 * 0.999, "depth {d} in front of the near plane");
        }
    }
    assert!(r.vis0.iter().filter(|&&w| w != VIS_EMPTY).count() > 64 * 10);
}

#[test]
fn vertices_far_off_screen_cover_exactly_the_right_pixels() {
    // Orthographic, 64 pixels = 2 units: 1e5 pixels is 3125 units.
    let far = 1e5 / 32.0;
    let camera = ortho(2.0);
    let tris = [
        [Vec3::new(-far, -far, 0.0), Vec3::new(far, -far, 0.0), Vec3::new(0.0, far, 0.0)],
        // A thin wedge reaching far off to the side, crossing the view.
        [Vec3::new(-far, 0.01, 0.5), Vec3::new(far, -0.02, 0.5), Vec3::new(far, 0.03, 0.5)],
    ];
    let scene = soup(&tris, true);
    let r = render(&scene, &camera, settings(64, 64));
    let ds = double_sided_triangles(&scene);
    let input = RasterInput::new(&scene, &ds);
    assert_eq!(r.vis0, cpu::raster_layer0(&r.frame, &input));
    assert!(r.vis0.iter().all(|&w| w != VIS_EMPTY), "the huge triangle covers the whole view");
    let counts = coverage(&scene, &r.frame);
    assert_eq!(counts, cpu::coverage_counts(&r.frame, &input));
}

#[test]
fn triangles_past_the_work_items_room_take_the_slices_left_and_lose_nothing() {
    // 80 triangles that each cover the whole 512x512 view (1024 tiles): shared out as on a GPU
    // (a slice per 8 tiles) each asks for 127 work items past its first slice, 10160 in all,
    // and the rasterizer holds 80 + 4096 for the triangles and 4096 for the target's tiles
    // (`bin_sizes`), 8272. The triangles binned last get the items left or none, so their
    // workgroups walk more tiles; every pixel must still be counted once per triangle, as the
    // CPU counts it.
    let n = 80;
    let tris: Vec<[Vec3; 3]> = (0..n)
        .map(|i| {
            let z = -1.0 + 0.02 * i as f32;
            [Vec3::new(-4.0, -4.0, z), Vec3::new(4.0, -4.0, z), Vec3::new(0.0, 4.0, z)]
        })
        .collect();
    let scene = soup(&tris, true);
    let camera = ortho(2.0);
    let frame = frame_for(&scene, &camera, 512, 512);
    let counts = coverage_shared_out(&scene, &frame, RasterWork::Gpu);
    assert!(counts.iter().all(|&c| c == n), "every pixel covered {n} times");
    let ds = double_sided_triangles(&scene);
    assert_eq!(counts, cpu::coverage_counts(&frame, &RasterInput::new(&scene, &ds)));
}

#[test]
fn zero_area_and_sliver_triangles() {
    let camera = ortho(2.0);
    let p = Vec3::new(0.1, 0.1, 0.0);
    let tris = [
        [p, p, p],                                                          // a point
        [Vec3::new(-0.9, -0.9, 0.0), Vec3::ZERO, Vec3::new(0.9, 0.9, 0.0)], // collinear
        [Vec3::new(-0.9, 0.5, 0.0), Vec3::new(0.9, 0.5, 0.0), Vec3::new(0.9, 0.5001, 0.0)], // sliver
        [Vec3::new(-0.9, -0.5, 0.0), Vec3::new(0.9, -0.52, 0.0), Vec3::new(0.9, -0.47, 0.0)], // thin
    ];
    let scene = soup(&tris, true);
    let r = render(&scene, &camera, settings(64, 64));
    let ds = double_sided_triangles(&scene);
    let input = RasterInput::new(&scene, &ds);
    assert_eq!(r.vis0, cpu::raster_layer0(&r.frame, &input));
    let ids: std::collections::BTreeSet<u32> = r.vis0.iter().filter_map(|&w| vis_id(w)).collect();
    assert!(!ids.contains(&0) && !ids.contains(&1), "zero-area triangles cover nothing: {ids:?}");
    assert!(ids.contains(&3), "the thin triangle covers pixels");
    let g = r.renderer.read_gbuffer(&gpu().device, &gpu().queue, 0).unwrap();
    assert!(
        g.samples
            .iter()
            .all(|s| s.depth.is_finite() && s.normal.is_finite() && s.motion.is_finite())
    );
}

#[test]
fn equal_depth_ties_go_to_the_smaller_id_every_run() {
    // Three identical coplanar triangles: every covered pixel must name triangle 0, every run.
    let tri = [Vec3::new(-0.8, -0.8, 0.0), Vec3::new(0.8, -0.8, 0.0), Vec3::new(0.0, 0.8, 0.0)];
    let mut tris = vec![tri; 3];
    tris.extend(random_soup(3, 50, 1.0));
    let scene = soup(&tris, true);
    let camera = ortho(2.0);
    let first = render(&scene, &camera, settings(48, 48));
    for w in &first.vis0 {
        if let Some(id) = vis_id(*w) {
            assert!(id == 0 || id >= 3, "triangle {id} won a tie against triangle 0");
        }
    }
    for _ in 0..3 {
        let again = render(&scene, &camera, settings(48, 48));
        assert_eq!(again.vis0, first.vis0);
        assert_eq!(again.vis1, first.vis1);
    }
}

#[test]
fn sizes_beyond_the_device_are_refused_with_the_limit() {
    let g = gpu();
    let limit = g.device.limits().max_storage_buffer_binding_size;
    // A square whose full-precision layer (64 bytes a pixel) just exceeds the binding limit.
    let side = ((limit / 64) as f64).sqrt() as u32 + 2;
    if side <= deep_gbuffer::frame::MAX_IMAGE_SIDE {
        match deep_gbuffer::Renderer::new(&g.device, &g.queue, settings(side, side)) {
            Err(deep_gbuffer::Error::ExceedsLimit { needed, limit: l, .. }) => assert!(needed > l),
            Err(e) => panic!("unexpected error {e}"),
            Ok(_) => panic!("a {side}x{side} G-buffer exceeds {limit} bytes"),
        }
    }
    assert!(matches!(
        deep_gbuffer::Renderer::new(&g.device, &g.queue, settings(0, 10)),
        Err(deep_gbuffer::Error::InvalidSetting { name: "size", .. })
    ));
}

#[test]
fn imported_buffers_are_checked_against_their_counts() {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let uploaded = SceneBuffers::upload(&g.device, &scene).unwrap();
    let mut b = uploaded.buffers().clone();
    SceneBuffers::import(&g.device, b.clone(), Default::default())
        .expect("the uploaded buffers import as they are");
    b.triangle_count += 1;
    let e = SceneBuffers::import(&g.device, b.clone(), Default::default()).unwrap_err().to_string();
    assert!(e.contains("indices") && e.contains("bytes"), "{e}");
    // The optional attributes are checked too: a tangent buffer of one vector for every vertex.
    let mut with_tangents = uploaded.buffers().clone();
    with_tangents.tangents = Some(with_tangents.normals.clone());
    let e =
        SceneBuffers::import(&g.device, with_tangents, Default::default()).unwrap_err().to_string();
    assert!(e.contains("tangents") && e.contains("bytes"), "{e}");
    b.triangle_count = 0;
    assert!(SceneBuffers::import(&g.device, b, Default::default()).is_err());
}

/// Under motion the one-pass variants test layer 1 against the previous frame's layer 0, so they
/// differ from the exact two-pass layer 1 where the view changed. Measured at three orbit speeds
/// (printed); slow motion must stay close to two-pass, and reprojecting must never be worse than
/// reusing the same pixel. A steady orbit is what `Predict` extrapolates exactly (to the
/// rounding of its matrices), and `Delay`, which shows the camera before the last, is the
/// two-pass layer 1 of that camera bit for bit.
#[test]
fn one_pass_variants_under_motion() {
    let (scene, start) = cornell();
    let base = Settings { dz: 0.05, ..settings(96, 72) };
    for step in [0.5f32, 2.0, 5.0] {
        let cameras: Vec<Camera> = (0..6)
            .map(|i| {
                let angle = (step * i as f32).to_radians();
                Camera {
                    eye: start.target
                        + glam::Quat::from_rotation_y(angle) * (start.eye - start.target),
                    ..start.clone()
                }
            })
            .collect();
        let exact = render(&scene, cameras.last().unwrap(), base.clone());
        let mut fractions = Vec::new();
        for layer1 in [Layer1Variant::Previous, Layer1Variant::Reproject, Layer1Variant::Predict] {
            let r = render_frames(&scene, &cameras, Settings { layer1, ..base.clone() });
            assert_eq!(r.vis0, exact.vis0, "layer 0 does not depend on the variant");
            let (n, _) = mismatches(&r.vis1, &exact.vis1, 96);
            let fraction = n as f64 / r.vis1.len() as f64;
            eprintln!(
                "{step} degrees a frame: {layer1:?} layer 1 differs from two-pass at {:.2}% of pixels",
                fraction * 100.0
            );
            fractions.push(fraction);
        }
        if step <= 0.5 {
            assert!(fractions.iter().all(|&f| f < 0.01), "slow motion: {fractions:?}");
        }
        assert!(
            fractions[1] <= fractions[0],
            "{step} degrees: reproject {} vs previous {}",
            fractions[1],
            fractions[0]
        );
        assert!(fractions[2] < 0.001, "{step} degrees: predict {}", fractions[2]);
        let delayed = render_frames(
            &scene,
            &cameras,
            Settings { layer1: Layer1Variant::Delay, ..base.clone() },
        );
        let shown = &cameras[cameras.len() - 2];
        assert_eq!(delayed.renderer.image_camera(), Some(shown), "one frame late");
        let exact = render(&scene, shown, base.clone());
        assert_eq!(delayed.vis0, exact.vis0, "{step} degrees: the delayed layer 0");
        assert_eq!(delayed.vis1, exact.vis1, "{step} degrees: the delayed layer 1 is exact");
        let plan = delayed.renderer.last_plan().unwrap();
        assert!(plan.contains(&PassId::RasterLayers) && plan.contains(&PassId::RasterNext));
    }
}

/// Geometry moving steadily under a still camera: `Predict` draws the next frame's layer 0 with
/// the vertices moved on as they moved since the last frame, so its layer 1 is the two-pass one;
/// `Previous`, separated from where the box stood a frame ago, is not.
#[test]
fn predict_moves_moving_geometry_on() {
    let (scene, camera) = cornell();
    let base = Settings { dz: 0.05, ..settings(96, 72) };
    let tall = scene.material_named("tallBox").unwrap();
    let frames: Vec<Vec<Vec3>> = (0..6)
        .map(|i| scene.positions_moved(tall, Vec3::new(0.06 * i as f32, 0.0, 0.0)).unwrap())
        .collect();
    let last = Scene { positions: frames[5].clone(), ..scene.clone() };
    let exact = render(&last, &camera, base.clone());
    let mut fractions = Vec::new();
    for layer1 in [Layer1Variant::Previous, Layer1Variant::Predict] {
        let r =
            common::render_moving(&scene, &frames, &camera, Settings { layer1, ..base.clone() });
        assert_eq!(r.vis0, exact.vis0, "layer 0 does not depend on the variant");
        let (n, _) = mismatches(&r.vis1, &exact.vis1, 96);
        let fraction = n as f64 / r.vis1.len() as f64;
        eprintln!(
            "a moving box: {layer1:?} layer 1 differs from two-pass at {:.2}%",
            fraction * 100.0
        );
        fractions.push(fraction);
    }
    assert!(fractions[0] > 0.001, "the box's motion shows in Previous: {fractions:?}");
    assert!(fractions[1] < 0.001, "Predict follows the box: {fractions:?}");
}
