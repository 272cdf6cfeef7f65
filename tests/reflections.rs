//! Screen-space reflections: against the CPU reference, a mirror that shows an object where the
//! mirrored rays meet it, and no pass where nothing reflects.

mod common;

use common::{gpu, render};
use deep_gbuffer::cpu::reflections as cpu;
use deep_gbuffer::passes::reflections::ReflectionsUniform;
use deep_gbuffer::scene::{Material, MeshData};
use deep_gbuffer::{Camera, Scene, Settings};
use glam::{Vec3, Vec4};

/// A step's pixel comes from a projection the GPU rounds slightly differently (fused
/// multiply-adds), so a ray that grazes a surface within an ulp of the thickness, or of a pixel
/// border, can hit one step apart on the two sides. Such pixels must stay rare.
const FLIPPED_FRACTION: f64 = 0.02;

fn read4(r: &deep_gbuffer::Renderer, b: &wgpu::Buffer) -> Vec<Vec4> {
    let g = gpu();
    let n = (r.settings().width * r.settings().height) as usize;
    r.read_f32(&g.device, &g.queue, b)
        .unwrap()
        .chunks_exact(4)
        .take(n)
        .map(|c| Vec4::new(c[0], c[1], c[2], c[3]))
        .collect()
}

#[test]
fn reflective_spheres_match_cpu_reference() {
    let scene = Scene::from_spec("builtin:grid-20000").unwrap();
    let s = Settings { timings: false, ..Settings::with_size(80, 60) };
    let uniform_settings = s.reflections.clone();
    let r = render(&scene, &scene.camera_or_default(), s);
    assert!(r.renderer.passes().iter().any(|p| p == "reflections"));
    let g = gpu();
    let layer0 = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap().samples;
    let radiance0 =
        r.renderer.read_rgb(&g.device, &g.queue, r.renderer.direct_buffer().unwrap()).unwrap();
    let radiance1 =
        r.renderer.read_rgb(&g.device, &g.queue, r.renderer.direct1_buffer().unwrap()).unwrap();
    let uniform = ReflectionsUniform {
        sky: scene.ambient.to_array(),
        max_distance: uniform_settings.max_distance,
        thickness: uniform_settings.thickness,
        tiles_x: 10,
        tiles_y: 8,
        _pad: 0,
    };
    let expected = cpu::reflections(&r.frame, &uniform, &layer0, &r.vis1, [&radiance0, &radiance1]);
    let actual = read4(&r.renderer, r.renderer.reflections_buffer().unwrap());
    let reflective = layer0.iter().filter(|s| s.depth > 0.0 && s.reflectivity > 0.0).count();
    assert!(reflective > 50, "the view shows reflective spheres ({reflective})");
    let differ = actual
        .iter()
        .zip(&expected)
        .filter(|(a, e)| (**a - **e).abs().max_element() > 1e-3 * e.max_element().max(1.0))
        .count();
    assert!(
        (differ as f64) <= FLIPPED_FRACTION * actual.len() as f64,
        "{differ} pixels differ from the CPU march"
    );
    assert!(actual.iter().all(|v| v.is_finite()));
    let hits = expected.iter().filter(|v| v.w > 0.5).count();
    assert!(hits > 10, "some rays hit neighbouring spheres or the ground ({hits})");
}

/// A mirror floor (reflectivity 1, black) and a glowing red wall standing on it, seen from
/// above at an angle: a floor pixel shows the wall's red exactly when its mirrored view ray meets
/// the wall (worked out here in closed form), the sky otherwise.
#[test]
fn a_mirror_shows_the_wall_where_mirrored_rays_meet_it() {
    let mut scene = Scene::default();
    scene.materials.push(Material {
        name: "mirror".into(),
        base_color: Vec4::new(0.0, 0.0, 0.0, 1.0),
        reflectivity: 1.0,
        roughness: 0.0,
        double_sided: true,
        ..Default::default()
    });
    scene.materials.push(Material {
        name: "glow".into(),
        base_color: Vec4::ZERO.with_w(1.0),
        emissive: Vec3::new(1.0, 0.0, 0.0),
        double_sided: true,
        ..Default::default()
    });
    let floor = [
        Vec3::new(-4.0, 0.0, -4.0),
        Vec3::new(4.0, 0.0, -4.0),
        Vec3::new(4.0, 0.0, 4.0),
        Vec3::new(-4.0, 0.0, 4.0),
    ];
    let wall = [
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
    ];
    for (quad, material) in [(floor, 0), (wall, 1)] {
        scene
            .push_mesh(MeshData {
                positions: &quad,
                normals: &[],
                uvs: &[],
                indices: &[0, 1, 2, 0, 2, 3],
                material,
            })
            .unwrap();
    }
    scene.ambient = Vec3::new(0.0, 0.0, 0.5);
    let camera =
        Camera::perspective(Vec3::new(0.0, 1.5, 3.0), Vec3::new(0.0, 0.0, -0.5), 50.0, 0.1);
    let (w, h) = (64u32, 48u32);
    let settings = Settings {
        timings: false,
        reflections: deep_gbuffer::ReflectionSettings {
            max_distance: 8.0,
            thickness: 0.3,
            ..Default::default()
        },
        ..Settings::with_size(w, h)
    };
    let r = render(&scene, &camera, settings);
    let g = gpu();
    let layer0 = r.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap().samples;
    let refl = read4(&r.renderer, r.renderer.reflections_buffer().unwrap());
    let inv_view = camera.view().inverse();
    let (mut agree, mut checked) = (0, 0);
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
            let t = (-1.0 - point.z) / m.z;
            let expected_hit = if t > 0.0 {
                let q = point + m * t;
                // Hit the wall, away from its border by a margin for the march's step and fade.
                q.x.abs() < 0.8 && q.y > 0.15 && q.y < 0.85 && t < 7.0
            } else {
                false
            };
            let clear_miss = t <= 0.0 || {
                let q = point + m * t;
                q.x.abs() > 1.3 || q.y > 1.3
            };
            let red = refl[p].x > 0.5 && refl[p].z < 0.2;
            let sky = refl[p].x < 0.1;
            if expected_hit || clear_miss {
                checked += 1;
                if (expected_hit && red) || (clear_miss && sky) {
                    agree += 1;
                }
            }
        }
    }
    assert!(checked > 200, "enough mirror pixels to judge ({checked})");
    assert!(
        agree as f64 >= 0.97 * checked as f64,
        "{agree} of {checked} mirror pixels show what the geometry puts there"
    );
}

#[test]
fn nothing_reflective_runs_no_reflection_pass() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let r = render(
        &scene,
        &scene.camera_or_default(),
        Settings { timings: false, ..Settings::with_size(16, 12) },
    );
    assert!(!r.renderer.passes().iter().any(|p| p == "reflections"));
    assert!(r.renderer.reflections_buffer().is_none());
}
