//! Screen-space reflections: against the CPU reference, a mirror that shows an object where the
//! mirrored rays meet it, and no pass where nothing reflects.

mod common;

use common::{
    GBUFFER_FIXTURES, assert_few_differ, gpu, mirror, mirror_before_a_wall, read4, render,
    shade_fixture,
};
use deep_gbuffer::cpu::{reflections as cpu, shadow as cpu_shadow};
use deep_gbuffer::frame::ReflectionsUniform;
use deep_gbuffer::scene::{GpuLight, Material, MeshData};
use deep_gbuffer::{Camera, Environment, Error, Renderer, Scene, SceneBuffers, Settings};
use glam::{Vec3, Vec4};

/// A step's pixel comes from a projection the GPU rounds slightly differently (fused
/// multiply-adds), so a ray that grazes a surface within an ulp of the thickness, or of a pixel
/// border, can hit one step apart on the two sides. Such pixels must stay rare.
const FLIPPED_FRACTION: f64 = 0.02;

#[test]
fn reflective_spheres_match_cpu_reference() {
    let scene = Scene::from_spec("builtin:grid-20000").unwrap();
    let s = Settings { timings: false, ..Settings::with_size(80, 60) };
    let r = render(&scene, &scene.camera_or_default(), s);
    assert!(r.renderer.passes().contains(&deep_gbuffer::PassId::Reflections));
    let g = gpu();
    let [layer0, layer1] =
        [0, 1].map(|l| r.renderer.read_gbuffer(&g.device, &g.queue, l).unwrap().samples);
    let reflective = layer0.iter().filter(|s| s.depth > 0.0 && s.reflectivity > 0.0).count();
    assert!(reflective > 50, "the view shows reflective spheres ({reflective})");
    march_matches(&r.renderer, &r.frame, [&layer0, &layer1], &scene, "grid");
}

/// The GPU march of `renderer`'s last frame of `scene` against the CPU march on both layers,
/// hit surfaces shaded with the scene's lights (re-lit towards the ray's origin), the frame's
/// obscurance and gathered irradiance, and the scene's constant ambient; returns the CPU's.
fn march_matches(
    renderer: &Renderer,
    frame: &deep_gbuffer::frame::FrameUniform,
    layers: [&[deep_gbuffer::GSample]; 2],
    scene: &Scene,
    what: &str,
) -> Vec<Vec4> {
    let ambient = scene.ambient;
    let g = gpu();
    let av = renderer.read_f32(&g.device, &g.queue, renderer.ao_buffer().unwrap()).unwrap();
    let irradiance = read4(renderer, renderer.radiosity_buffers().unwrap().irradiance);
    // Hit surfaces are re-lit by the scene's lights past the CPU's own shadow maps.
    let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::new).collect();
    let (faces, light_faces, atlas) =
        cpu_shadow::maps(scene, renderer.settings().shadows.resolution);
    let shadows = cpu_shadow::Shadows {
        faces: &faces,
        light_faces: &light_faces,
        atlas: &atlas,
        pcf: renderer.settings().shadows.pcf,
    };
    let shading = cpu::HitShading {
        lights: &lights,
        shadows: Some(&shadows),
        av: Some(&av),
        irradiance: Some(&irradiance),
        // The rays the screen cannot place followed through the same shadow maps.
        follow: renderer.settings().reflections.shadow_maps.then_some(scene),
    };
    let s = &renderer.settings().reflections;
    let layout = deep_gbuffer::frame::PyramidLayout::new(frame.width, frame.height);
    let size = (frame.width, frame.height);
    let uniform = ReflectionsUniform::new(s, size, &layout, true, ambient.to_array(), None)
        .with_bounds(scene.bounds());
    let expected = cpu::reflections(frame, &uniform, layers, &shading, None);
    let actual = read4(renderer, renderer.reflections_buffer().unwrap());
    let far = |a: &Vec4, e: &Vec4| (*a - *e).abs().max_element() > 1e-3 * e.max_element().max(1.0);
    let what = format!("{what}: the march against the CPU's");
    assert_few_differ(&actual, &expected, FLIPPED_FRACTION, far, &what);
    assert!(actual.iter().all(|v| v.is_finite()));
    let hits = expected.iter().filter(|v| v.w > 0.5).count();
    assert!(hits > 10, "{what}: some rays hit neighbouring spheres or the ground ({hits})");
    expected
}

/// A mirror pixel's view ray, mirrored in the floor, worked out in closed form.
struct MirroredRay {
    /// The pixel.
    p: usize,
    /// The mirrored ray's direction (world space).
    m: Vec3,
    /// Where it meets the wall's plane.
    q: Vec3,
    /// The ray meets the wall away from its border by a margin for pixel steps, where the
    /// screen shows it clear of the edge fade.
    hits: bool,
    /// The ray clearly misses the wall.
    misses: bool,
}

/// The mirrored view ray of every floor pixel of `r` (rendered through `camera`) against the
/// wall of [`mirror_before_a_wall`].
fn mirrored_rays(
    r: &common::Rendered,
    camera: &Camera,
    (wall_z, half_width, height): (f32, f32, f32),
) -> Vec<MirroredRay> {
    let g = gpu();
    let (w, h) = (r.frame.width, r.frame.height);
    let layer0 = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap().samples;
    let inv_view = camera.view().inverse();
    let view_proj = camera.projection(w as f32 / h as f32) * camera.view();
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let p = (y * w + x) as usize;
            let s = &layer0[p];
            if !(s.depth > 0.0 && s.material == 0) {
                continue;
            }
            // The floor point, its mirrored view ray, and where that ray meets the wall's plane.
            let vp = deep_gbuffer::cpu::frame::view_position(
                &r.frame,
                glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
                s.depth,
            );
            let point = inv_view.transform_point3(vp);
            let d = (point - camera.eye).normalize();
            let m = Vec3::new(d.x, -d.y, d.z);
            let t = (wall_z - point.z) / m.z;
            let q = point + m * t;
            // Where the screen shows q, in [0, 1]^2 (the march sees only what is on screen).
            let c = view_proj * q.extend(1.0);
            let uv = glam::Vec2::new(c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5);
            let hits = t > 0.0
                && q.x.abs() < 0.8 * half_width
                && q.y > 0.15 * height
                && q.y < 0.85 * height
                && c.w > 0.0
                && uv.min_element() > 0.15
                && uv.max_element() < 0.85;
            let misses = t <= 0.0 || q.x.abs() > 1.3 * half_width || q.y > 1.3 * height;
            out.push(MirroredRay { p, m, q, hits, misses });
        }
    }
    out
}

/// A mirror floor and a glowing red wall standing on it at `wall_z`, seen by `camera`, with the
/// default settings: a floor pixel shows the wall's red exactly when its mirrored view ray meets
/// the wall (worked out here in closed form) where the screen shows the wall, the sky when the
/// ray misses the wall.
fn a_mirror_shows_the_wall_where_mirrored_rays_meet_it(
    camera: Camera,
    wall_z: f32,
    half_width: f32,
    height: f32,
) {
    let glow = Material {
        name: "glow".into(),
        base_color: Vec4::ZERO.with_w(1.0),
        emissive: Vec3::new(1.0, 0.0, 0.0),
        ..Default::default()
    };
    let mut scene = mirror_before_a_wall(glow, wall_z, half_width, height);
    scene.ambient = Vec3::new(0.0, 0.0, 0.5);
    let (w, h) = (64u32, 48u32);
    let r = render(&scene, &camera, Settings { timings: false, ..Settings::with_size(w, h) });
    let refl = read4(&r.renderer, r.renderer.reflections_buffer().unwrap());
    let (mut agree, mut checked, mut hits) = (0, 0, 0);
    for ray in mirrored_rays(&r, &camera, (wall_z, half_width, height)) {
        let v = refl[ray.p];
        let red = v.x > 0.5 && v.z < 0.2;
        // The sky is blue; a black pixel would be the mirror hitting itself.
        let sky = v.x < 0.1 && v.z > 0.4;
        hits += usize::from(ray.hits && red);
        if ray.hits || ray.misses {
            checked += 1;
            if (ray.hits && red) || (ray.misses && sky) {
                agree += 1;
            }
        }
    }
    assert!(checked > 200, "enough mirror pixels to judge ({checked})");
    assert!(hits > 50, "wall at z = {wall_z}: enough rays meet it on screen ({hits})");
    assert!(
        agree as f64 >= 0.97 * checked as f64,
        "wall at z = {wall_z}: {agree} of {checked} mirror pixels show what the geometry puts there"
    );
}

/// A gold metal mirror (base colour (0.9, 0.6, 0.2), metallic 1, reflectivity 1) before a
/// white glowing wall under a grey sky: what it reflects is tinted by its base colour, the F0
/// of its specular BRDF, the wall's white shown as gold and the sky's grey as a darker gold.
#[test]
fn a_metal_mirror_tints_what_it_reflects() {
    let glow = Material {
        name: "glow".into(),
        base_color: Vec4::ZERO.with_w(1.0),
        emissive: Vec3::ONE,
        ..Default::default()
    };
    let wall = (-1.0f32, 1.0f32, 1.0f32);
    let mut scene = mirror_before_a_wall(glow, wall.0, wall.1, wall.2);
    let gold = Vec3::new(0.9, 0.6, 0.2);
    scene.materials[0].base_color = gold.extend(1.0);
    scene.materials[0].metallic = 1.0;
    scene.ambient = Vec3::splat(0.5);
    let camera =
        Camera::perspective(Vec3::new(0.0, 1.5, 3.0), Vec3::new(0.0, 0.0, -0.5), 50.0, 0.1);
    let r = render(&scene, &camera, Settings { timings: false, ..Settings::with_size(64, 48) });
    let refl = read4(&r.renderer, r.renderer.reflections_buffer().unwrap());
    let (mut hits, mut misses) = (0, 0);
    for ray in mirrored_rays(&r, &camera, wall) {
        let v = refl[ray.p].truncate();
        let expected = if ray.hits {
            hits += 1;
            gold
        } else if ray.misses {
            misses += 1;
            0.5 * gold
        } else {
            continue;
        };
        // At the default precision the G-buffer holds the base colour in f32 and the
        // reflectivity of 1 exactly (12 bits), and the wall's emission and the sky are
        // constants: only f32 rounding separates the two.
        assert!((v - expected).abs().max_element() < 1e-3, "pixel {}: {v} vs {expected}", ray.p);
    }
    assert!(hits > 50 && misses > 50, "rays meet the wall ({hits}) and the sky ({misses})");
}

#[test]
fn a_mirror_shows_a_near_wall_where_mirrored_rays_meet_it() {
    let camera =
        Camera::perspective(Vec3::new(0.0, 1.5, 3.0), Vec3::new(0.0, 0.0, -0.5), 50.0, 0.1);
    a_mirror_shows_the_wall_where_mirrored_rays_meet_it(camera, -1.0, 1.0, 1.0);
}

/// The hierarchical march follows a ray across the screen, however far it goes in the scene.
#[test]
fn a_mirror_shows_a_far_wall_where_mirrored_rays_meet_it() {
    let camera =
        Camera::perspective(Vec3::new(0.0, 1.5, 3.0), Vec3::new(0.0, 0.8, -10.0), 50.0, 0.1);
    a_mirror_shows_the_wall_where_mirrored_rays_meet_it(camera, -30.0, 20.0, 3.0);
}

/// A hit surface is lit towards the point its ray left, not towards the camera: a mirror floor
/// before a rough metal wall under a directional light shows, where its mirrored view ray meets
/// the wall, the wall's radiance along that ray (the BRDF in closed form: a metal's light is all
/// specular, so it depends on the direction it leaves in), which differs from what the camera
/// sees of the same wall.
#[test]
fn a_mirror_shows_a_metal_wall_lit_towards_the_mirror() {
    let (albedo, roughness) = (Vec3::new(0.9, 0.8, 0.7), 0.3);
    let metal = Material {
        name: "metal".into(),
        base_color: albedo.extend(1.0),
        metallic: 1.0,
        roughness,
        ..Default::default()
    };
    let wall = (-1.0f32, 1.0f32, 1.0f32);
    let mut scene = mirror_before_a_wall(metal, wall.0, wall.1, wall.2);
    let travel = Vec3::new(0.0, -0.45, -1.0).normalize();
    let light = deep_gbuffer::scene::Light {
        name: "sun".into(),
        kind: deep_gbuffer::scene::LightKind::Directional { direction: travel },
        color: Vec3::ONE,
        intensity: 3.0,
        casts_shadows: true,
    };
    let radiance = Vec3::from(GpuLight::new(&light).radiance);
    scene.lights.push(light);
    let camera =
        Camera::perspective(Vec3::new(0.0, 1.5, 3.0), Vec3::new(0.0, 0.0, -0.5), 50.0, 0.1);
    let (w, h) = (64u32, 48u32);
    let r = render(&scene, &camera, Settings { timings: false, ..Settings::with_size(w, h) });
    let refl = read4(&r.renderer, r.renderer.reflections_buffer().unwrap());
    // The wall faces +z; its radiance towards unit v.
    let (n, to_light) = (Vec3::Z, -travel);
    let lit = |v: Vec3| {
        deep_gbuffer::cpu::direct::brdf(n, v, to_light, albedo, roughness, 1.0)
            * radiance
            * n.dot(to_light)
    };
    let (mut checked, mut apart) = (0, 0);
    for ray in mirrored_rays(&r, &camera, wall).into_iter().filter(|ray| ray.hits) {
        let towards_mirror = lit(-ray.m);
        let towards_camera = lit((camera.eye - ray.q).normalize());
        let off = |e: Vec3, by: Vec3, within: f32| (e - by).abs().max_element() > within;
        checked += 1;
        // The same BRDF in f32 on both sides, differently rounded (up to 6e-5 of the value
        // measured); the wall is lit whole, so the shadow lookup adds nothing.
        let tolerance = 1e-3 * towards_mirror.max_element();
        let a = refl[ray.p].truncate();
        assert!(!off(a, towards_mirror, tolerance), "pixel {}: {a} vs {towards_mirror}", ray.p);
        apart +=
            usize::from(off(towards_camera, towards_mirror, 0.1 * towards_mirror.max_element()));
    }
    assert!(checked > 50, "enough mirror pixels see the wall ({checked})");
    assert!(apart * 2 > checked, "the camera sees the wall differently ({apart} of {checked})");
}

/// A convex mirror cannot see itself: every ray it reflects leaves it, so the march must find
/// neither its own front (layer 0) nor the back it hides (layer 1), and each pixel shows the sky.
#[test]
fn a_convex_mirror_never_sees_itself() {
    let (rings, segments) = (24u32, 48u32);
    let mut positions = Vec::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            positions.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ));
        }
    }
    let mut indices = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let a = i * (segments + 1) + j;
            let b = a + segments + 1;
            indices.extend_from_slice(&[a, a + 1, b, a + 1, b + 1, b]);
        }
    }
    let mut scene = Scene::default();
    scene.materials.push(Material {
        name: "chrome".into(),
        base_color: Vec4::new(0.5, 0.5, 0.5, 1.0),
        reflectivity: 1.0,
        roughness: 0.0,
        emissive: Vec3::splat(0.5),
        ..Default::default()
    });
    // Smooth normals: a sphere's are its positions.
    let mesh = MeshData {
        positions: &positions,
        normals: &positions,
        uvs: &[],
        indices: &indices,
        material: 0,
        ..MeshData::default()
    };
    scene.push_mesh(mesh).unwrap();
    scene.ambient = Vec3::new(0.0, 0.0, 0.5);
    let camera = Camera::perspective(Vec3::new(0.4, 0.8, 3.0), Vec3::ZERO, 45.0, 0.1);
    let r = render(&scene, &camera, Settings { timings: false, ..Settings::with_size(64, 48) });
    assert_eq!(r.renderer.last_plan().unwrap().layers, 2, "layer 1 holds the sphere's back");
    let g = gpu();
    let layer0 = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap().samples;
    let refl = read4(&r.renderer, r.renderer.reflections_buffer().unwrap());
    let shown: Vec<_> = refl.iter().zip(&layer0).filter(|(_, s)| s.depth > 0.0).collect();
    assert!(shown.len() > 400, "the sphere fills the view ({})", shown.len());
    let seen_itself = shown.iter().filter(|(v, _)| v.w > 0.0).count();
    assert_eq!(seen_itself, 0, "of {} mirror pixels, {seen_itself} see the sphere", shown.len());
    assert!(shown.iter().all(|(v, _)| (v.truncate() - scene.ambient).abs().max_element() < 1e-6));
}

#[test]
fn nothing_reflective_runs_no_reflection_pass() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let r = render(
        &scene,
        &scene.camera_or_default(),
        Settings { timings: false, ..Settings::with_size(16, 12) },
    );
    assert!(!r.renderer.passes().contains(&deep_gbuffer::PassId::Reflections));
    assert!(r.renderer.reflections_buffer().is_none());
}

fn gradient() -> Environment {
    Environment::load_exr(&common::fixture("environment/gradient.exr")).unwrap()
}

/// The fixture holds r = (x + 0.5) / 64, g = (y + 0.5) / 32, b = 0.25 (fixtures/README.md); the
/// mapping puts straight up on row 0 and -z on the middle column.
#[test]
fn the_environment_map_loads_and_maps_directions() {
    let env = gradient();
    assert_eq!((env.width(), env.height()), (64, 32));
    for (i, t) in env.texels().iter().enumerate() {
        let (x, y) = ((i % 64) as f32, (i / 64) as f32);
        assert_eq!(t[..3], [(x + 0.5) / 64.0, (y + 0.5) / 32.0, 0.25], "texel {i}");
    }
    let up = env.sample(Vec3::Y);
    assert!((up.y - 0.5 / 32.0).abs() < 1e-6, "up reads row 0: {up}");
    let forward = env.sample(Vec3::NEG_Z);
    assert!((forward.x - 0.5).abs() < 1e-6 && (forward.y - 0.5).abs() < 1e-6, "{forward}");
    let right = env.sample(Vec3::X);
    assert!((right.x - 0.75).abs() < 1e-6, "+x is a quarter turn from -z: {right}");
}

#[test]
fn bad_environment_maps_get_typed_errors() {
    match Environment::load_exr(&common::fixture("cornell/CornellBox-Original.obj")) {
        Err(Error::ImageRead { path, .. }) => assert!(path.ends_with("CornellBox-Original.obj")),
        other => panic!("not an EXR: {other:?}"),
    }
    match Environment::load_exr(&common::fixture("environment/missing.exr")) {
        Err(Error::Io { .. }) => {}
        other => panic!("a missing file: {other:?}"),
    }
    for rgb in [vec![[f32::NAN, 0.0, 0.0]], vec![[-1.0, 0.0, 0.0]], vec![]] {
        assert!(matches!(
            Environment::new(1, 1, rgb),
            Err(Error::InvalidSetting { name: "environment", .. })
        ));
    }
    assert!(Environment::new(0, 1, vec![]).is_err());
    assert!(Environment::new(Environment::MAX_SIDE + 1, 1, vec![[0.0; 3]; 8193]).is_err());
}

/// A mirror floor alone under an environment map: every reflected ray leaves the screen, and each
/// floor pixel shows the map along the floor's closed-form mirrored view ray.
#[test]
fn missed_rays_see_the_environment_map() {
    let g = gpu();
    let mut scene = Scene::default();
    scene.materials.push(Material {
        name: "mirror".into(),
        base_color: Vec4::new(0.0, 0.0, 0.0, 1.0),
        reflectivity: 1.0,
        roughness: 0.0,
        ..Default::default()
    });
    let floor = [
        Vec3::new(-4.0, 0.0, -4.0),
        Vec3::new(-4.0, 0.0, 4.0),
        Vec3::new(4.0, 0.0, 4.0),
        Vec3::new(4.0, 0.0, -4.0),
    ];
    let mesh = MeshData {
        positions: &floor,
        normals: &[],
        uvs: &[],
        indices: &[0, 1, 2, 0, 2, 3],
        material: 0,
        ..MeshData::default()
    };
    scene.push_mesh(mesh).unwrap();
    scene.ambient = Vec3::splat(0.1);
    let camera =
        Camera::perspective(Vec3::new(0.3, 1.2, 2.0), Vec3::new(-0.2, 0.0, -1.0), 60.0, 0.1);
    let (w, h) = (48u32, 32u32);
    let buffers = SceneBuffers::upload(&g.device, &scene).unwrap();
    let mut renderer = Renderer::new(
        &g.device,
        &g.queue,
        Settings { timings: false, ..Settings::with_size(w, h) },
    )
    .unwrap();
    let env = gradient();
    renderer.set_environment(&g.device, Some(&env)).unwrap();
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    let layer0 = renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap().samples;
    let refl = read4(&renderer, renderer.reflections_buffer().unwrap());
    let frame = renderer.frame_uniform().unwrap();
    let inv_view = camera.view().inverse();
    let mut checked = 0;
    for (p, s) in layer0.iter().enumerate() {
        if s.depth.is_nan() || s.depth <= 0.0 {
            continue;
        }
        let px = glam::Vec2::new((p as u32 % w) as f32 + 0.5, (p as u32 / w) as f32 + 0.5);
        let point =
            inv_view.transform_point3(deep_gbuffer::cpu::frame::view_position(frame, px, s.depth));
        let d = (point - camera.eye).normalize();
        let expected = env.sample(Vec3::new(d.x, -d.y, d.z));
        // Directions through the f32 G-buffer round-trip differ in the last bits; the map is
        // smooth (a texel step changes a channel by 1/64), so colours agree far closer than this.
        assert!(
            (refl[p].truncate() - expected).abs().max_element() < 2e-3,
            "pixel {p}: {} vs {expected}",
            refl[p]
        );
        assert_eq!(refl[p].w, 0.0, "a missed ray has no confidence");
        checked += 1;
    }
    assert!(checked > (w * h / 2) as usize, "the floor fills the view ({checked})");

    // Back to the constant sky.
    renderer.set_environment(&g.device, None).unwrap();
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    let refl = read4(&renderer, renderer.reflections_buffer().unwrap());
    let sky = refl.iter().zip(&layer0).filter(|(_, s)| s.depth > 0.0);
    assert!(sky.clone().all(|(v, _)| (v.truncate() - scene.ambient).abs().max_element() < 1e-6));
}

/// The stored G-buffer of the reflective spheres (fixtures/gbuffer/), independent of the
/// rasterizer.
#[test]
fn reflections_of_a_stored_gbuffer_match_cpu_reference() {
    let f = shade_fixture(1, Settings { timings: false, ..Settings::default() });
    assert_eq!(GBUFFER_FIXTURES[1].1, "builtin:grid-20000");
    march_matches(
        &f.renderer,
        &f.frame,
        [&f.layers[0].samples, &f.layers[1].samples],
        &f.scene,
        GBUFFER_FIXTURES[1].0,
    );
}

/// The ray's length, the shell's thickness and the lobe's directions: a bad value is a typed
/// error naming the setting;
/// an infinite length (the default) follows rays to the screen's edge.
#[test]
fn invalid_reflection_settings_are_refused() {
    let g = gpu();
    let with = |reflections| Settings { reflections, ..Settings::with_size(8, 8) };
    for (max_distance, thickness, lobe_samples, name) in [
        (0.0, 0.1, 8, "reflections.max_distance"),
        (-1.0, 0.1, 8, "reflections.max_distance"),
        (f32::NAN, 0.1, 8, "reflections.max_distance"),
        (f32::INFINITY, 0.0, 8, "reflections.thickness"),
        (f32::INFINITY, f32::INFINITY, 8, "reflections.thickness"),
        (f32::INFINITY, 0.1, 0, "reflections.lobe_samples"),
        (f32::INFINITY, 0.1, 65, "reflections.lobe_samples"),
    ] {
        let s = deep_gbuffer::ReflectionSettings {
            max_distance,
            thickness,
            lobe_samples,
            enabled: true,
            shadow_maps: true,
        };
        match Renderer::new(&g.device, &g.queue, with(s)) {
            Err(Error::InvalidSetting { name: n, .. }) => assert_eq!(n, name),
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("{name} = {max_distance}, {thickness}, {lobe_samples} accepted"),
        }
    }
    let unbounded = deep_gbuffer::ReflectionSettings::default();
    assert_eq!(unbounded.max_distance, f32::INFINITY);
    assert!(Renderer::new(&g.device, &g.queue, with(unbounded)).is_ok());
}

/// A mirror wall at z = -2 behind a box whose face towards the mirror the camera does not see;
/// a sun behind the mirror, high enough to clear its top edge, lights that face. The box's faces
/// are single-sided quads (outward normals, counter-clockwise seen from outside), material 1.
fn a_box_before_a_mirror() -> Scene {
    let mut scene = Scene::default();
    scene.materials.push(mirror());
    scene.materials.push(Material {
        name: "box".into(),
        base_color: Vec4::new(0.8, 0.5, 0.2, 1.0),
        roughness: 1.0,
        ..Default::default()
    });
    let mirror = [[-4.0, -1.0, -2.0], [4.0, -1.0, -2.0], [4.0, 2.5, -2.0], [-4.0, 2.5, -2.0]];
    let mut quads = vec![(mirror.map(Vec3::from), Vec3::Z, 0)];
    // The unit cube about (0, 1, 0): each face's corners counter-clockwise about its normal.
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|i| if i == axis { sign } else { 0.0 }));
            let (u, v) = (n.any_orthonormal_vector(), n.cross(n.any_orthonormal_vector()));
            let c = Vec3::new(0.0, 1.0, 0.0) + 0.5 * n;
            let corners = [
                c - 0.5 * u - 0.5 * v,
                c + 0.5 * u - 0.5 * v,
                c + 0.5 * u + 0.5 * v,
                c - 0.5 * u + 0.5 * v,
            ];
            quads.push((corners, n, 1));
        }
    }
    for (corners, n, material) in quads {
        scene
            .push_mesh(MeshData {
                positions: &corners,
                normals: &[n; 4],
                uvs: &[],
                indices: &[0, 1, 2, 0, 2, 3],
                material,
                ..MeshData::default()
            })
            .unwrap();
    }
    scene.lights.push(deep_gbuffer::scene::Light {
        name: "sun".into(),
        kind: deep_gbuffer::scene::LightKind::Directional {
            direction: Vec3::new(0.0, -2.0, 1.0).normalize(),
        },
        color: Vec3::ONE,
        intensity: 3.0,
        casts_shadows: true,
    });
    scene.ambient = Vec3::new(0.0, 0.0, 0.5);
    scene
}

/// The mirror shows the box's face that the camera does not see, lit by the sun, where the
/// mirrored view rays meet it (worked out in closed form): the screen holds no such face, the
/// sun's shadow map does. Screen-only reflections show the sky there. And the GPU agrees with
/// the CPU reference.
#[test]
fn a_mirror_shows_the_lit_side_of_a_box_the_camera_does_not_see() {
    let scene = a_box_before_a_mirror();
    let camera =
        Camera::perspective(Vec3::new(2.5, 2.5, 4.0), Vec3::new(0.0, 1.0, -1.0), 45.0, 0.1);
    let size = Settings::with_size(96, 72);
    let followed = render(&scene, &camera, Settings { timings: false, ..size.clone() });
    let mut screen_only = Settings { timings: false, ..size };
    screen_only.reflections.shadow_maps = false;
    let unfollowed = render(&scene, &camera, screen_only);
    let g = gpu();
    let layer0 = followed.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap().samples;
    let centre = (36 * 96 + 48) as usize;
    assert_eq!(layer0[centre].material, 1, "the camera sees the box");
    let [with, without] = [&followed, &unfollowed]
        .map(|r| read4(&r.renderer, r.renderer.reflections_buffer().unwrap()));
    // The back face's radiance, red and green (the ambient sky is blue only): Lambertian
    // (roughness 1, no metal), lit at n.l = 1/sqrt(5) with irradiance 3: base / pi * 3 /
    // sqrt(5). Within 5%: the BRDF's specular lobe at roughness 1 adds 2-3% (measured: red
    // 0.348 against 0.342, green 0.220 against 0.214).
    let lit = Vec3::new(0.8, 0.5, 0.2) / std::f32::consts::PI * 3.0 / 5f32.sqrt();
    let inv_view = camera.view().inverse();
    let layer1 = followed.renderer.read_gbuffer(&g.device, &g.queue, 1).unwrap().samples;
    let cpu = march_matches(&followed.renderer, &followed.frame, [&layer0, &layer1], &scene, "box");
    let (mut shown, mut counted) = (0, 0);
    for (p, s) in layer0.iter().enumerate() {
        if !(s.depth > 0.0 && s.material == 0) {
            continue;
        }
        let (x, y) = ((p % 96) as f32 + 0.5, (p / 96) as f32 + 0.5);
        let vp = deep_gbuffer::cpu::frame::view_position(
            &followed.frame,
            glam::Vec2::new(x, y),
            s.depth,
        );
        let point = inv_view.transform_point3(vp);
        let d = (point - camera.eye).normalize();
        let m = Vec3::new(d.x, d.y, -d.z);
        // Where the mirrored ray meets the plane of the back face, z = -0.5, well inside it.
        let t = (-0.5 - point.z) / m.z;
        let q = point + m * t;
        if !(t > 0.0 && q.x.abs() < 0.35 && (q.y - 1.0).abs() < 0.35) {
            continue;
        }
        counted += 1;
        // The GPU and the CPU reference alike.
        let near =
            |v: Vec4| (v.x - lit.x).abs() < 0.05 * lit.x && (v.y - lit.y).abs() < 0.05 * lit.y;
        if near(with[p]) && near(cpu[p]) {
            shown += 1;
        }
        assert!(
            without[p].truncate().distance(Vec3::new(0.0, 0.0, 0.5)) < 1e-3,
            "screen-only: the sky at {p}, {:?}",
            without[p]
        );
    }
    assert!(counted > 20, "mirrored rays meet the hidden face ({counted})");
    assert_eq!(shown, counted, "mirror pixels that show the lit face");
}

/// A still view keeps its reflections when nothing they read changes (the obscurance kept, the
/// radiosity off or kept): its still frames run no reflections pass, and its reflected light and
/// image stay, bit for bit, those of a renderer that runs every pass.
#[test]
fn a_still_view_keeps_its_reflections() {
    let g = common::gpu();
    let scene = Scene::from_spec("builtin:grid-20000").unwrap();
    let buffers = SceneBuffers::upload(&g.device, &scene).unwrap();
    let camera = scene.camera_or_default();
    let mut s = Settings { timings: false, ..Settings::with_size(48, 36) };
    // The obscurance kept from the first still frame on (a still view that averages it runs
    // the reflections while it does); no radiosity.
    s.ao.still_frames = 0;
    s.radiosity.enabled = false;
    let mut kept = Renderer::new(&g.device, &g.queue, s.clone()).unwrap();
    let mut full = Renderer::new(&g.device, &g.queue, s).unwrap();
    // Renders a frame with both (the full renderer running every pass): whether `kept` ran the
    // reflections, its reflected light and image checked against the full renderer's.
    let step = |kept: &mut Renderer, full: &mut Renderer, frame: &str| {
        full.redraw();
        for r in [&mut *kept, &mut *full] {
            r.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        }
        let reflects = |r: &Renderer| r.passes().contains(&deep_gbuffer::PassId::Reflections);
        assert!(reflects(full));
        let (x, y) = (
            kept.read_terms(&g.device, &g.queue).unwrap(),
            full.read_terms(&g.device, &g.queue).unwrap(),
        );
        assert!(x.reflections.as_ref().is_some_and(|r| r.iter().any(|c| c.max_element() > 0.0)));
        assert!(x.reflections == y.reflections, "{frame}: reflections differ");
        assert!(x.hdr == y.hdr, "{frame}: the image differs");
        reflects(kept)
    };
    for frame in 0..4 {
        let label = format!("frame {frame}");
        assert_eq!(step(&mut kept, &mut full, &label), frame == 0, "{label}");
    }
    // A new environment is seen at once: the next frame runs them, the one after keeps them.
    let sky = gradient();
    for r in [&mut kept, &mut full] {
        r.set_environment(&g.device, Some(&sky)).unwrap();
    }
    for frame in 0..2 {
        let label = format!("frame {frame} after the new environment");
        assert_eq!(step(&mut kept, &mut full, &label), frame == 0, "{label}");
    }
}
