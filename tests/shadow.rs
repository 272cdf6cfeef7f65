//! Shadow maps: drawn by the compute rasterizer, looked up with PCF; a directional light's shadow
//! edge falls where the geometry puts it.

mod common;

use common::{gpu, render, soup};
use deep_gbuffer::scene::{Light, LightKind, Projection};
use deep_gbuffer::{Camera, PassId, Renderer, Scene, SceneBuffers, Settings, ShadowSettings};
use glam::Vec3;

/// A ground square and a horizontal square occluder one unit above it, lit by a directional
/// light travelling along (1, -1, 0)/sqrt(2): the occluder over x in [-0.5, 0.5] (moved by
/// `shift` along x) shadows the ground over x in [0.5, 1.5] (z in [-0.5, 0.5]). Seen from
/// straight above, orthographic, 16 pixels per unit, x from -2 to 2.
fn occluder_scene(shift: f32) -> (Scene, Camera) {
    let quad = |y: f32, lo: f32, hi: f32, dx: f32| {
        [
            [Vec3::new(lo + dx, y, lo), Vec3::new(lo + dx, y, hi), Vec3::new(hi + dx, y, hi)],
            [Vec3::new(lo + dx, y, lo), Vec3::new(hi + dx, y, hi), Vec3::new(hi + dx, y, lo)],
        ]
    };
    let mut tris = quad(0.0, -3.0, 3.0, 0.0).to_vec();
    tris.extend(quad(1.0, -0.5, 0.5, shift));
    let mut scene = soup(&tris, true);
    scene.lights.push(Light {
        name: "sun".into(),
        kind: LightKind::Directional { direction: Vec3::new(1.0, -1.0, 0.0).normalize() },
        color: Vec3::ONE,
        intensity: 1.0,
        casts_shadows: true,
    });
    let camera = Camera {
        eye: Vec3::new(0.0, 5.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::NEG_Z,
        projection: Projection::Orthographic { height: 4.0, near: 0.1, far: 10.0 },
        lens: Default::default(),
    };
    (scene, camera)
}

#[test]
fn directional_shadow_edge_falls_where_the_geometry_puts_it() {
    let (scene, camera) = occluder_scene(0.0);
    let (w, h) = (64u32, 64u32);
    for pcf in [0, 1] {
        let shadows = ShadowSettings { pcf, ..Default::default() };
        let r = render(
            &scene,
            &camera,
            Settings { timings: false, shadows, ..Settings::with_size(w, h) },
        );
        assert!(r.renderer.passes().iter().any(|p| p.name() == "shadow.sun"));
        let g = gpu();
        let direct = r.renderer.read_rgb(&g.device, &g.queue, r.renderer.direct_buffer()).unwrap();
        let lit = |x: f32| {
            // Pixel centre on the row through z = 0 (image y grows with +z here).
            let px = ((x + 2.0) * 16.0) as u32;
            direct[((h / 2) * w + px) as usize].x
        };
        let full = lit(-1.5);
        assert!(full > 0.1, "open ground is lit ({full})");
        // Well inside the shadow: dark; well outside: fully lit.
        for x in [0.7, 1.0, 1.3] {
            assert!(lit(x) < 0.02 * full, "x = {x} should be in shadow: {} vs {full}", lit(x));
        }
        for x in [1.7, 1.9, -1.0] {
            assert!(
                (lit(x) - full).abs() < 0.02 * full,
                "x = {x} should be lit: {} vs {full}",
                lit(x)
            );
        }
        // The edge: the last shadowed and first lit pixel along the row straddle x = 1.5,
        // within the PCF footprint plus bias (two pixels).
        let row: Vec<f32> = (0..w).map(|x| direct[((h / 2) * w + x) as usize].x).collect();
        let edge = (40..w as usize).find(|&x| row[x] > 0.5 * full).expect("the shadow ends") as f32;
        let expected = (1.5 + 2.0) * 16.0;
        assert!(
            (edge - expected).abs() <= 2.0,
            "pcf {pcf}: edge at pixel {edge}, geometry puts it at {expected}"
        );
    }
}

#[test]
fn lights_without_shadows_get_no_shadow_map() {
    let mut scene = deep_gbuffer::Scene::from_spec("builtin:cornell").unwrap();
    scene.lights[0].casts_shadows = false;
    let r = render(
        &scene,
        &scene.camera_or_default(),
        Settings { timings: false, ..Settings::with_size(16, 16) },
    );
    assert!(!r.renderer.passes().iter().any(|p| matches!(p, deep_gbuffer::PassId::Shadow { .. })));
    assert!(r.renderer.shadow_atlas_buffer().is_none());
    assert!(r.renderer.last_plan().unwrap().shadow_lights().is_empty());
}

/// A static scene draws its shadow map once: later frames, from any camera, reuse it and light
/// the scene exactly as a map drawn anew does. Geometry written in place is redrawn after
/// `geometry_changed` (and its motion read), maps asked for are redrawn after
/// `redraw_shadow_maps` (and nothing taken for moved), and a scene uploaded anew is redrawn by
/// itself.
#[test]
fn a_static_scene_draws_its_shadow_map_once() {
    let g = gpu();
    let (scene, camera) = occluder_scene(0.0);
    let buffers = SceneBuffers::upload(&g.device, &scene).unwrap();
    let settings = Settings { timings: false, ..Settings::with_size(32, 32) };
    let mut renderer = Renderer::new(&g.device, &g.queue, settings.clone()).unwrap();
    let shadow_drawn = |r: &Renderer| r.passes().iter().any(|p| matches!(p, PassId::Shadow { .. }));
    let direct = |r: &Renderer| r.read_rgb(&g.device, &g.queue, r.direct_buffer()).unwrap();
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    assert!(shadow_drawn(&renderer));
    let first = direct(&renderer);
    let aside = Camera { eye: Vec3::new(2.0, 4.0, 1.0), ..camera.clone() };
    for cam in [aside, camera.clone()] {
        renderer.render(&g.device, &g.queue, &buffers, &cam).unwrap();
        assert!(!shadow_drawn(&renderer), "the map is kept when only the camera moves");
        let plan = renderer.last_plan().unwrap();
        assert_eq!(plan.reused.len(), 1);
        assert_eq!(plan.shadow_lights(), vec![(0, "sun")]);
    }
    assert_eq!(direct(&renderer), first, "a kept map lights as the drawn one did");
    // Asked to, it redraws the map without taking the geometry for moved.
    renderer.redraw_shadow_maps();
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    assert!(shadow_drawn(&renderer), "redraw_shadow_maps redraws the map");
    let flags = renderer.frame_uniform().unwrap().flags;
    assert_eq!(flags & deep_gbuffer::frame::FRAME_OBJECT_MOTION, 0, "nothing moved");
    assert_eq!(direct(&renderer), first);

    // The occluder moves by half a unit, written into the scene's own buffer.
    let (moved, _) = occluder_scene(0.5);
    buffers.write_positions(&g.queue, &moved.positions).unwrap();
    let short = buffers.write_positions(&g.queue, &moved.positions[1..]);
    assert!(matches!(short, Err(deep_gbuffer::Error::InvalidScene(_))), "{short:?}");
    renderer.geometry_changed();
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    assert!(shadow_drawn(&renderer), "geometry_changed redraws the map");
    let flags = renderer.frame_uniform().unwrap().flags;
    assert_ne!(flags & deep_gbuffer::frame::FRAME_OBJECT_MOTION, 0, "the occluder moved");
    let redrawn = direct(&renderer);
    assert_ne!(redrawn, first, "the shadow moved");
    let fresh = render(&moved, &camera, settings.clone());
    assert_eq!(redrawn, direct(&fresh.renderer), "as a renderer that never saw the old scene");

    // A scene uploaded anew has new buffers: its map is drawn without being told.
    let back = SceneBuffers::upload(&g.device, &scene).unwrap();
    renderer.render(&g.device, &g.queue, &back, &camera).unwrap();
    assert!(shadow_drawn(&renderer));
    assert_eq!(direct(&renderer), first);
}
