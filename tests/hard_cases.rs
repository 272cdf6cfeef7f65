//! Hard cases through the whole pipeline: every case renders frames on the test device and checks
//! that no output or history buffer holds a NaN or an infinity, that AV lies in [0, 1], and that
//! radiance and irradiance are never negative and never above what the lights deliver.

mod common;

use common::{gpu, mesh, read4, soup};
use std::f32::consts::PI;

use deep_gbuffer::cpu::frame::{mat_mul, view_position};
use deep_gbuffer::scene::{GpuLight, Projection};
use deep_gbuffer::{
    AoSettings, Camera, GSample, RadiositySettings, Renderer, Scene, SceneBuffers, SceneInfo,
    Settings,
};
use glam::{Vec2, Vec3, Vec4};

/// What one checked frame showed.
struct Checked {
    /// Pixels with a layer-0 surface.
    surfaces: usize,
    renderer: Renderer,
}

/// Relative slack on the upper bounds below: the GPU and this test compute the world point and
/// the light's distance in different f32 operation orders.
const BOUND_SLACK: f32 = 1e-3;

/// An upper bound on the direct radiance leaving `s`, from what `lights` can deliver there:
/// each light's unattenuated irradiance E (radiance / d^2 for point and spot lights; the range
/// window, the cone and shadows only lower it) times the largest value of brdf * n.l. Lambert
/// gives at most albedo (1 - metallic) / pi; GGX's D is at most 1 / (pi a^2), Smith-Schlick
/// visibility times n.l at most 1 / (2a) (k = a/2), Fresnel at most 1.
fn direct_bound(s: &GSample, world: Vec3, lights: &[GpuLight]) -> Vec3 {
    let a = (s.roughness * s.roughness).max(1e-3);
    let brdf = s.base_color * (1.0 - s.metallic) / PI + Vec3::splat(1.0 / (2.0 * PI * a * a * a));
    lights
        .iter()
        .map(|l| {
            let radiance = Vec3::from(l.radiance);
            let e = if l.kind == 0 {
                radiance
            } else {
                radiance / (Vec3::from(l.position) - world).length_squared().max(1e-8)
            };
            e * brdf
        })
        .sum()
}

/// Checks every buffer the last frame of `r` wrote, drawing `scene`: finite, non-negative, AV
/// in [0, 1], direct radiance within [`direct_bound`], and the radiosity gather's irradiance
/// (pi times a cosine-weighted mean of the B it reads) within pi times the largest B.
fn check_buffers(r: &Renderer, scene: &Scene, what: &str) -> usize {
    let g = gpu();
    let n = (r.settings().width * r.settings().height) as usize;
    let lights: Vec<GpuLight> = SceneInfo::of(scene).lights.iter().map(GpuLight::new).collect();
    let f = *r.frame_uniform().expect("a frame");
    let layer0 = r.read_gbuffer(&g.device, &g.queue, 0).unwrap();
    let world = |p: usize| {
        let px = Vec2::new((p as u32 % f.width) as f32 + 0.5, (p as u32 / f.width) as f32 + 0.5);
        let v = view_position(&f, px, layer0.samples[p].depth);
        mat_mul(&f.inv_view, [v.x, v.y, v.z, 1.0]).truncate()
    };
    let finite_nonneg = |name: &str, v: &[Vec4]| {
        for (p, x) in v.iter().enumerate() {
            assert!(x.is_finite(), "{what}: {name} pixel {p} is {x}");
            assert!(x.truncate().min_element() >= 0.0, "{what}: {name} pixel {p} is {x}");
        }
    };
    let hdr = read4(r, r.hdr_buffer());
    finite_nonneg("hdr", &hdr);
    let direct = read4(r, r.direct_buffer());
    finite_nonneg("direct", &direct);
    for (p, (l, s)) in direct.iter().zip(&layer0.samples).enumerate() {
        if s.depth > 0.0 {
            let bound = direct_bound(s, world(p), &lights) * (1.0 + BOUND_SLACK);
            assert!(
                l.truncate().cmple(bound).all(),
                "{what}: direct radiance {l} at pixel {p} above what the lights deliver, {bound}"
            );
        }
    }
    if let Some(av) = r.ao_buffer() {
        let av = r.read_f32(&g.device, &g.queue, av).unwrap();
        for (p, v) in av.iter().take(n).enumerate() {
            assert!((0.0..=1.0).contains(v), "{what}: AV {v} at pixel {p}");
        }
    }
    if let Some(buffers) = r.radiosity_buffers() {
        let mut values = Vec::new();
        for (name, b) in buffers.named() {
            let v = read4(r, b);
            finite_nonneg(name, &v);
            assert!(v.iter().all(|x| x.w <= 1.0), "{what}: {name} confidence above 1");
            values.push(v);
        }
        let source: Vec<deep_gbuffer::frame::SourceTexel> = bytemuck::pod_collect_to_vec(
            &deep_gbuffer::gpu::read_buffer(&g.device, &g.queue, buffers.source).unwrap(),
        );
        let radiance = source.iter().flat_map(|t| [t.radiance(0), t.radiance(1)]);
        let b: Vec<Vec4> = radiance.map(|b| b.extend(0.0)).collect();
        finite_nonneg("B", &b);
        let mut largest_b = b.iter().fold(Vec3::ZERO, |m, b| m.max(b.truncate()));
        // The off-screen light's clusters send their texels' mean radiance, flux / area, into
        // the share of the hemisphere the gather left open: the bound takes the largest too.
        if let Some(o) = r.offscreen_buffers() {
            let clusters: Vec<deep_gbuffer::frame::Cluster> = bytemuck::pod_collect_to_vec(
                &deep_gbuffer::gpu::read_buffer(&g.device, &g.queue, o.clusters).unwrap(),
            );
            for c in clusters.iter().filter(|c| c.area > 0.0) {
                largest_b = largest_b.max(Vec3::from(c.flux) / c.area);
            }
        }
        let bound = PI * largest_b * (1.0 + BOUND_SLACK);
        for (p, e) in values[0].iter().enumerate() {
            assert!(
                e.truncate().cmple(bound).all(),
                "{what}: gathered irradiance {e} at pixel {p} above pi max radiance = {bound}"
            );
        }
        // The layer-1 gather keeps E / c, a weighted mean of what it saw: bounded alike.
        if let Some(layer1) = buffers.layer1 {
            let records = read4(r, layer1);
            finite_nonneg("layer-1 gather", &records);
            for (t, e) in records.iter().enumerate() {
                assert!(
                    e.truncate().cmple(bound).all(),
                    "{what}: layer-1 E / c {e} at texel {t} above pi max radiance = {bound}"
                );
            }
        }
    }
    if let Some(b) = r.reflections_buffer() {
        finite_nonneg("reflections", &read4(r, b));
    }
    for s in &layer0.samples {
        assert!(s.depth.is_finite() && s.depth >= 0.0, "{what}: depth {}", s.depth);
        if s.depth > 0.0 {
            assert!((s.normal.length() - 1.0).abs() < 1e-3, "{what}: normal {}", s.normal);
        }
    }
    layer0.samples.iter().filter(|s| s.depth > 0.0).count()
}

/// Renders `frames` frames of `scene` from `camera` and checks each.
fn check(scene: &Scene, camera: &Camera, settings: Settings, frames: u32, what: &str) -> Checked {
    let g = gpu();
    let buffers = SceneBuffers::upload(&g.device, scene).unwrap();
    let mut renderer = Renderer::new(&g.device, &g.queue, settings).unwrap();
    let mut surfaces = 0;
    for _ in 0..frames {
        renderer.render(&g.device, &g.queue, &buffers, camera).unwrap();
        surfaces = check_buffers(&renderer, scene, what);
    }
    Checked { surfaces, renderer }
}

/// 32x24 with 128-texel shadow faces (the Cornell box's point light draws six per frame).
fn small() -> Settings {
    let shadows = deep_gbuffer::ShadowSettings { resolution: 128, ..Default::default() };
    Settings { timings: false, shadows, ..Settings::with_size(32, 24) }
}

fn cornell() -> (Scene, Camera) {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    (scene, camera)
}

#[test]
fn projections() {
    let (scene, base) = cornell();
    let perspective = |fov_y_deg, near, far, reverse_z| Camera {
        projection: Projection::Perspective { fov_y_deg, near, far, reverse_z },
        ..base.clone()
    };
    let cases = [
        (
            "orthographic",
            Camera {
                projection: Projection::Orthographic { height: 2.5, near: 0.1, far: 20.0 },
                ..base.clone()
            },
        ),
        ("reverse-z", perspective(40.0, 0.1, Some(50.0), true)),
        ("reverse-z infinite", perspective(40.0, 0.1, None, true)),
        ("infinite far plane", perspective(40.0, 0.1, None, false)),
        ("5 degrees", perspective(5.0, 0.1, Some(50.0), false)),
        ("120 degrees", perspective(120.0, 0.1, Some(50.0), false)),
        ("far/near 1e6", perspective(40.0, 1e-4, Some(100.0), false)),
    ];
    for (what, camera) in cases {
        let c = check(&scene, &camera, small(), 2, what);
        assert!(c.surfaces > 0, "{what}: the box is in view");
    }
}

#[test]
fn cameras_inside_on_and_away_from_geometry() {
    let (scene, base) = cornell();
    // Inside the tall box (its centre is about (-0.33, 0.6, -0.29) in the Cornell box).
    let inside = Camera { eye: Vec3::new(-0.33, 0.6, -0.29), ..base.clone() };
    check(&scene, &inside, small(), 2, "inside a box");
    // Exactly on the floor (y = 0), looking along it.
    let on = Camera::perspective(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.0, 0.0, -1.0), 60.0, 0.01);
    check(&scene, &on, small(), 2, "on the floor");
    // Looking away from everything.
    let away = Camera::perspective(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 10.0), 60.0, 0.1);
    let c = check(&scene, &away, small(), 2, "an empty view");
    assert_eq!(c.surfaces, 0);
}

/// The off-screen light from a spot light's and a sun's reflective shadow maps (one face each,
/// perspective and orthographic), seen from inside the box looking away from both: bounded and
/// finite like the rest, and it adds the light of what lies behind the camera.
#[test]
fn offscreen_light_from_a_spot_and_a_sun() {
    use deep_gbuffer::scene::{Light, LightKind};
    let (mut scene, _) = cornell();
    scene.lights = vec![
        Light {
            name: "spot".into(),
            kind: LightKind::Spot {
                position: Vec3::new(0.0, 1.9, 0.0),
                direction: Vec3::new(0.2, -1.0, 0.1),
                range: None,
                inner_cone: 0.4,
                outer_cone: 0.8,
            },
            color: Vec3::ONE,
            intensity: 6.0,
            casts_shadows: true,
        },
        Light {
            name: "sun".into(),
            kind: LightKind::Directional { direction: Vec3::new(-0.3, -0.5, -1.0) },
            color: Vec3::new(1.0, 0.9, 0.8),
            intensity: 2.0,
            casts_shadows: true,
        },
    ];
    // Inside the room, looking at the floor of a corner with the light's ceiling behind.
    let camera =
        Camera::perspective(Vec3::new(0.9, 1.7, 0.9), Vec3::new(-0.9, 0.1, -0.9), 50.0, 0.05);
    let mean = |offscreen: bool| {
        let mut settings = small();
        settings.radiosity.offscreen = offscreen;
        let c = check(&scene, &camera, settings, 3, "off-screen light from a spot and a sun");
        assert_eq!(c.renderer.offscreen_buffers().map(|o| o.face_count), offscreen.then_some(2));
        let irradiance = read4(&c.renderer, c.renderer.radiosity_buffers().unwrap().gathered);
        irradiance.iter().map(|e| e.truncate().element_sum()).sum::<f32>() / irradiance.len() as f32
    };
    // Measured 0.908 against 0.805: the spot lights the floor in view, which the gather holds,
    // so what lies outside is the spill on the walls behind the camera and the sun's patch; the
    // frames are deterministic, so a 5% margin is far above rounding.
    let (without, with) = (mean(false), mean(true));
    assert!(with > without * 1.05, "the light outside the screen counts: {with} against {without}");
}

/// Twelve shadow-casting point lights: 4608 clusters, of which a pixel sums at most 32 a frame
/// (the frames cover the rest); bounded and finite like the rest.
#[test]
fn offscreen_light_from_many_lights() {
    use deep_gbuffer::scene::{Light, LightKind};
    let (mut scene, camera) = cornell();
    scene.lights = (0..12)
        .map(|i| {
            let a = i as f32 * 0.52;
            Light {
                name: format!("lamp{i}"),
                kind: LightKind::Point {
                    position: Vec3::new(0.7 * a.cos(), 0.3 + 0.12 * i as f32, 0.7 * a.sin()),
                    range: None,
                },
                color: Vec3::ONE,
                intensity: 0.5,
                casts_shadows: true,
            }
        })
        .collect();
    let c = check(&scene, &camera, small(), 3, "twelve shadow-casting lights");
    assert_eq!(c.renderer.offscreen_buffers().map(|o| o.face_count), Some(72));
}

#[test]
fn one_triangle_and_an_edge_on_triangle() {
    let tri = [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
    let mut scene = soup(&[tri], false);
    scene.ensure_lights();
    let facing = Camera::perspective(Vec3::new(0.0, 0.5, 2.0), Vec3::new(0.0, 0.5, 0.0), 60.0, 0.1);
    let c = check(&scene, &facing, small(), 2, "one triangle");
    assert!(c.surfaces > 0);
    // Seen exactly edge-on: the triangle lies in the plane z = 0 and the eye too.
    let edge_on =
        Camera::perspective(Vec3::new(3.0, 0.5, 0.0), Vec3::new(0.0, 0.5, 0.0), 60.0, 0.1);
    let c = check(&scene, &edge_on, small(), 2, "an edge-on triangle");
    assert_eq!(c.surfaces, 0, "an edge-on triangle covers no pixel centre");
}

#[test]
fn bad_normals_and_coincident_triangles() {
    let (mut scene, camera) = cornell();
    // Zero-length and NaN vertex normals: the resolve falls back to the face normal.
    let n = scene.normals.len();
    for (i, normal) in scene.normals.iter_mut().enumerate() {
        *normal = match i % 3 {
            0 => Vec3::ZERO,
            1 => Vec3::NAN,
            _ => *normal,
        };
    }
    assert_eq!(scene.normals.len(), n);
    check(&scene, &camera, small(), 2, "zero and NaN normals");

    // Two coincident coplanar quads with different materials: one wins everywhere, the same on
    // every run.
    let quad = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let mut scene = mesh(&quad, &[0, 1, 2, 0, 2, 3, 0, 1, 2, 0, 2, 3], false);
    scene.materials.push(deep_gbuffer::scene::Material {
        base_color: Vec4::new(1.0, 0.0, 0.0, 1.0),
        ..Default::default()
    });
    scene.triangle_materials[2] = 1;
    scene.triangle_materials[3] = 1;
    scene.ensure_lights();
    let camera = Camera::perspective(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 50.0, 0.1);
    let a = check(&scene, &camera, small(), 1, "coincident quads");
    let b = check(&scene, &camera, small(), 1, "coincident quads again");
    let g = gpu();
    let ha = a.renderer.read_rgb(&g.device, &g.queue, a.renderer.hdr_buffer()).unwrap();
    let hb = b.renderer.read_rgb(&g.device, &g.queue, b.renderer.hdr_buffer()).unwrap();
    assert_eq!(ha, hb, "the same winner on every run");
}

/// A thin pole two units in front of a wall, obscurance radius 0.5: no tap on the pole is within
/// the radius of the wall, so the wall shows no halo around the pole, with one layer or two.
#[test]
fn a_thin_pole_casts_no_halo_on_the_wall_behind() {
    let mut triangles = Vec::new();
    let wall = [
        [Vec3::new(-5.0, -5.0, 0.0), Vec3::new(5.0, -5.0, 0.0), Vec3::new(5.0, 5.0, 0.0)],
        [Vec3::new(-5.0, -5.0, 0.0), Vec3::new(5.0, 5.0, 0.0), Vec3::new(-5.0, 5.0, 0.0)],
    ];
    triangles.extend(wall);
    // A square pole 0.1 wide, from z = 1.95 to 2.05, standing from y = -5 to 5.
    let (a, b) = (-0.05f32, 0.05f32);
    for (x0, z0, x1, z1) in
        [(a, b + 2.0, b, b + 2.0), (b, b + 2.0, b, a + 2.0), (a, a + 2.0, a, b + 2.0)]
    {
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        triangles.push([p(x0, -5.0, z0), p(x1, -5.0, z1), p(x1, 5.0, z1)]);
        triangles.push([p(x0, -5.0, z0), p(x1, 5.0, z1), p(x0, 5.0, z0)]);
    }
    let mut scene = soup(&triangles, true);
    scene.ambient = Vec3::splat(0.3);
    let camera = Camera::perspective(Vec3::new(0.3, 0.0, 6.0), Vec3::ZERO, 40.0, 0.1);
    let g = gpu();
    for two_layers in [true, false] {
        let ao = AoSettings { radius: 0.5, two_layers, blur_radius: 0, ..Default::default() };
        let c = check(&scene, &camera, Settings { ao, ..small() }, 1, "pole");
        let layer0 = c.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap();
        let av = c.renderer.read_f32(&g.device, &g.queue, c.renderer.ao_buffer().unwrap()).unwrap();
        let wall: Vec<f32> = layer0
            .samples
            .iter()
            .zip(&av)
            .filter(|(s, _)| s.depth > 5.9)
            .map(|(_, v)| *v)
            .collect();
        assert!(wall.len() > 100);
        let min = wall.iter().copied().fold(1.0, f32::min);
        assert_eq!(min, 1.0, "two layers: {two_layers}: the wall is not obscured (min AV {min})");
    }
}

#[test]
fn mirrors_facing_the_camera_and_at_grazing_angles() {
    let mut scene = Scene::from_spec("builtin:cornell").unwrap();
    for m in &mut scene.materials {
        m.reflectivity = 1.0;
        m.roughness = 0.0;
    }
    let camera = scene.camera_or_default();
    // Every surface a mirror: rays toward the camera (the back wall), grazing (floor and walls
    // seen at an angle) and leaving the screen; each ends within its 48 steps.
    let c = check(&scene, &camera, small(), 2, "all mirrors");
    assert!(c.renderer.passes().contains(&deep_gbuffer::PassId::Reflections));
    let grazing =
        Camera::perspective(Vec3::new(0.0, 0.02, 1.5), Vec3::new(0.0, 0.0, -1.0), 60.0, 0.01);
    check(&scene, &grazing, small(), 2, "grazing mirrors");
}

#[test]
fn scene_scales_from_a_thousandth_to_a_hundred_thousand() {
    let (scene, camera) = cornell();
    for scale in [1e-3f32, 1e5] {
        let mut s = scene.clone();
        for p in &mut s.positions {
            *p *= scale;
        }
        for l in &mut s.lights {
            if let deep_gbuffer::scene::LightKind::Point { position, .. } = &mut l.kind {
                *position *= scale;
            }
            l.intensity *= scale * scale;
        }
        let mut cam = camera.clone();
        cam.eye *= scale;
        cam.target *= scale;
        if let Projection::Perspective { near, .. } = &mut cam.projection {
            *near *= scale;
        }
        let settings = Settings {
            dz: 0.05 * scale,
            ao: AoSettings { radius: 0.5 * scale, bias: 0.01 * scale, ..Default::default() },
            radiosity: RadiositySettings {
                radius: scale,
                history_tolerance: 0.01 * scale,
                ..Default::default()
            },
            ..small()
        };
        let c = check(&s, &cam, settings, 3, &format!("scale {scale}"));
        assert!(c.surfaces > 300, "scale {scale}: {} surfaces", c.surfaces);
    }
}

#[test]
fn tiny_and_odd_resolutions() {
    let (scene, camera) = cornell();
    for (w, h) in [(1, 1), (7, 5), (2, 1), (1, 9)] {
        let c = check(
            &scene,
            &camera,
            Settings { timings: false, ..Settings::with_size(w, h) },
            2,
            &format!("{w}x{h}"),
        );
        assert!(c.surfaces <= (w * h) as usize);
    }
}

/// 3840x2160 through the whole pipeline: finite everywhere where the device can hold a layer in
/// one storage binding; where it cannot (lavapipe allows 128 MiB, a full-precision layer needs
/// 506 MiB), a typed error that names the layer, what it needs and the limit.
#[test]
fn ultra_hd() {
    let (scene, camera) = cornell();
    let g = gpu();
    let (w, h) = (3840u32, 2160u32);
    let needed = u64::from(w) * u64::from(h) * 64;
    let limit = g.device.limits().max_storage_buffer_binding_size;
    let settings = Settings { timings: false, ..Settings::with_size(w, h) };
    if needed > limit {
        match Renderer::new(&g.device, &g.queue, settings) {
            Err(deep_gbuffer::Error::ExceedsLimit { what, needed: n, limit: l, unit }) => {
                assert!(what.contains("3840x2160"), "{what}");
                // It says what would fit: the packed precision, or how many pixels.
                assert!(what.contains("would fit") || what.contains("pixels fit"), "{what}");
                assert_eq!(unit, "bytes");
                assert_eq!((n, l), (needed, limit));
            }
            other => panic!("{:?}", other.map(|_| ())),
        }
    } else {
        let c = check(&scene, &camera, settings, 1, "3840x2160");
        assert!(c.surfaces > (w * h / 2) as usize);
    }
}

#[test]
fn extreme_layer_separation_and_one_sample() {
    let (scene, camera) = cornell();
    for dz in [0.0, 1e6] {
        let c =
            check(&scene, &camera, Settings { dz, layers: 2, ..small() }, 2, &format!("dz {dz}"));
        let layer1 = c.renderer.read_gbuffer(&gpu().device, &gpu().queue, 1).unwrap();
        if dz > 1e5 {
            assert!(layer1.samples.iter().all(|s| s.depth == 0.0), "nothing lies 1e6 behind");
        }
    }
    let one = Settings {
        ao: AoSettings { samples: 1, ..Default::default() },
        radiosity: RadiositySettings { samples: 1, ..Default::default() },
        ..small()
    };
    check(&scene, &camera, one, 3, "one sample");
    // A radius of zero is no setting at all: refused with its name.
    let zero = Settings { ao: AoSettings { radius: 0.0, ..Default::default() }, ..small() };
    match Renderer::new(&gpu().device, &gpu().queue, zero) {
        Err(deep_gbuffer::Error::InvalidSetting { name, .. }) => assert_eq!(name, "ao.radius"),
        other => panic!("{:?}", other.map(|_| ())),
    }
}

/// Temporal: a first frame, a camera cut, and an object that moves away and uncovers the
/// background: the history is dropped where the uncovered surface was not seen, no NaN appears,
/// and the uncovered pixels end up as a fresh render of the new scene shows them.
#[test]
fn temporal_cut_and_an_object_moving_away() {
    let g = gpu();
    let (scene, camera) = cornell();
    let buffers = SceneBuffers::upload(&g.device, &scene).unwrap();
    let radiosity = RadiositySettings { jitter: false, ..Default::default() };
    let settings = Settings { radiosity, ..small() };
    let mut r = Renderer::new(&g.device, &g.queue, settings.clone()).unwrap();
    for _ in 0..5 {
        r.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        check_buffers(&r, &scene, "before the cut");
    }
    r.reset_history();
    let far = Camera { eye: camera.eye + Vec3::new(0.5, 0.2, 1.0), ..camera.clone() };
    r.render(&g.device, &g.queue, &buffers, &far).unwrap();
    check_buffers(&r, &scene, "after the cut");

    // Move the short box (the material "shortBox") 5 units away: the floor under it appears.
    let mut moved = scene.clone();
    let short = moved.materials.iter().position(|m| m.name == "shortBox").unwrap() as u32;
    let mut vertices = std::collections::BTreeSet::new();
    for (t, m) in moved.triangles.iter().zip(&moved.triangle_materials) {
        if *m == short {
            vertices.extend(t.iter().copied());
        }
    }
    for v in vertices {
        moved.positions[v as usize].x += 5.0;
    }
    let moved_buffers = SceneBuffers::upload(&g.device, &moved).unwrap();
    // The first frame after the move: where the box was and the floor now shows, the history
    // (the box's irradiance) must be dropped, so the filtered irradiance is this frame's own.
    let before = r.read_gbuffer(&g.device, &g.queue, 0).unwrap();
    r.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    let before_cut = r.read_gbuffer(&g.device, &g.queue, 0).unwrap();
    assert_eq!(before.width, before_cut.width);
    r.render(&g.device, &g.queue, &moved_buffers, &camera).unwrap();
    check_buffers(&r, &moved, "the box moved away");
    let after = r.read_gbuffer(&g.device, &g.queue, 0).unwrap();
    let deep_gbuffer::RadiosityBuffers { gathered: raw, filtered: history, .. } =
        r.radiosity_buffers().unwrap();
    let (raw, history) = (read4(&r, raw), read4(&r, history));
    let mut uncovered = 0;
    for p in 0..after.samples.len() {
        let (was, now) = (&before_cut.samples[p], &after.samples[p]);
        // Uncovered, and farther than the history tolerance from what covered it (where the box
        // meets the floor the two surfaces are within it, and the history rightly stays).
        let tolerance = RadiositySettings::default().history_tolerance;
        let gone = was.depth > 0.0 && was.material == short;
        if gone && now.depth > 0.0 && now.material != short && now.depth - was.depth > tolerance {
            uncovered += 1;
            assert_eq!(
                history[p].truncate(),
                raw[p].truncate(),
                "pixel {p} kept the box's history"
            );
        }
    }
    assert!(uncovered > 5, "the move uncovers floor ({uncovered} pixels)");
}

/// Resizing between frames: the history restarts, so the first frame after a resize is bit for
/// bit a fresh renderer's first frame at the new size; a size the device cannot hold is an error
/// that leaves the renderer drawing at its old size.
#[test]
fn resize_between_frames() {
    let g = gpu();
    let (scene, camera) = cornell();
    let buffers = SceneBuffers::upload(&g.device, &scene).unwrap();
    let first_frame = |settings: Settings| {
        let mut fresh = Renderer::new(&g.device, &g.queue, settings).unwrap();
        fresh.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        read4(&fresh, fresh.hdr_buffer())
    };
    let mut r = Renderer::new(&g.device, &g.queue, small()).unwrap();
    for _ in 0..4 {
        r.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    }
    for (w, h) in [(20, 14), (32, 24), (7, 5)] {
        r.resize(&g.device, &g.queue, w, h).unwrap();
        r.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        check_buffers(&r, &scene, &format!("resized to {w}x{h}"));
        let image = read4(&r, r.hdr_buffer());
        assert_eq!(image.len(), (w * h) as usize);
        let expected = first_frame(Settings { width: w, height: h, ..small() });
        assert!(image == expected, "the first frame after resizing to {w}x{h} kept history");
        for _ in 0..2 {
            r.render(&g.device, &g.queue, &buffers, &camera).unwrap();
            check_buffers(&r, &scene, &format!("{w}x{h}, later frames"));
        }
    }
    for (w, h) in [(0, 5), (5, 0), (100_000, 4)] {
        let e = r.resize(&g.device, &g.queue, w, h).unwrap_err();
        assert!(matches!(e, deep_gbuffer::Error::InvalidSetting { .. }), "{w}x{h}: {e}");
    }
    assert_eq!((r.settings().width, r.settings().height), (7, 5));
    r.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    check_buffers(&r, &scene, "after refused resizes");
}

/// Transparency at its limits: up to twenty blended panes stacked in the Cornell box (two of
/// them at the same depth, opacities 0, 1, tiny and in between, one emitting brightly) peeled 1
/// and 16 (the most) layers deep: every buffer stays finite and in range, the image stays within
/// what the panes and the box can send, and the fragments past the last peel are counted (none
/// once k exceeds the panes).
#[test]
fn many_blended_layers_and_extreme_opacities() {
    let (base, camera) = cornell();
    let opacities = [0.0, 1.0, 1e-7, 0.5, 0.999_999];
    for panes in [20, 10] {
        let mut scene = base.clone();
        for i in 0..panes {
            let z = 0.9 - 0.07 * (i.min(panes - 2)) as f32;
            let material = scene.materials.len() as u32;
            scene.materials.push(deep_gbuffer::Material {
                base_color: Vec4::new(0.8, 0.4, 0.2, opacities[i % opacities.len()]),
                emissive: if i == 7 { Vec3::splat(1e4) } else { Vec3::ZERO },
                alpha_mode: deep_gbuffer::AlphaMode::Blend,
                double_sided: true,
                ..Default::default()
            });
            let s = 0.3 + 0.02 * i as f32;
            let positions = [
                Vec3::new(-s, 1.0 - s, z),
                Vec3::new(s, 1.0 - s, z),
                Vec3::new(s, 1.0 + s, z),
                Vec3::new(-s, 1.0 + s, z),
            ];
            let mesh = deep_gbuffer::scene::MeshData {
                positions: &positions,
                indices: &[0, 1, 2, 0, 2, 3],
                material,
                ..Default::default()
            };
            scene.push_mesh(mesh).unwrap();
        }
        let mut unpeeled = Vec::new();
        for layers in [1, 16] {
            let mut s = small();
            s.transparency.layers = layers;
            let what = format!("{panes} stacked blended panes, k = {layers}");
            let c = check(&scene, &camera, s, 2, &what);
            let image = read4(&c.renderer, c.renderer.hdr_buffer());
            for (p, v) in image.iter().enumerate() {
                assert!(
                    v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.1e4,
                    "{what}, pixel {p}: {v}"
                );
            }
            let g = gpu();
            unpeeled.push(c.renderer.diagnostics(&g.device, &g.queue).unwrap().unpeeled_fragments);
        }
        assert!(unpeeled[0] > unpeeled[1], "{panes} panes: {unpeeled:?}");
        assert_eq!(unpeeled[1] == 0, panes <= 16, "{panes} panes: {unpeeled:?}");
    }
}
