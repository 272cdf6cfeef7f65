//! The off-screen light (`wgsl/offscreen.wgsl`): the reflective shadow maps' clusters and their
//! light added to the radiosity's gather, against the CPU reference (`cpu::offscreen`). Its
//! plan is tested in `tests/plan.rs`, its bounds and many lights in `tests/hard_cases.rs`.

mod common;

use common::{assert_few_differ, gpu, read4, render_frames};
use deep_gbuffer::cpu::offscreen as reference;
use deep_gbuffer::frame::{Cluster, OffscreenUniform, RSM_RESOLUTION, ShadowFace};
use deep_gbuffer::scene::GpuLight;
use deep_gbuffer::{Camera, Renderer, Scene, Settings};
use glam::Vec4;

/// Settings with the off-screen light `on` or off.
fn settings(w: u32, h: u32, on: bool) -> Settings {
    let mut s = Settings { timings: false, ..Settings::with_size(w, h) };
    s.radiosity.offscreen = on;
    s
}

/// The Cornell box from level with its light (the ceiling around the light lies above the
/// screen): the reflective shadow maps' clusters against the CPU's, computed from the GPU's own
/// maps, and the gather with the clusters' light added against the gather of the same frame
/// rendered without it plus the CPU's sum.
#[test]
fn offscreen_light_matches_cpu_reference() {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = Camera {
        eye: glam::Vec3::new(0.0, 1.8, 3.8),
        target: glam::Vec3::new(0.0, 0.7, 0.0),
        ..scene.camera_or_default()
    };
    let (w, h) = (64, 48);
    let without = render_frames(&scene, std::slice::from_ref(&camera), settings(w, h, false));
    let on = settings(w, h, true);
    let with = render_frames(&scene, &[camera], on.clone());
    assert!(without.renderer.offscreen_buffers().is_none(), "off, it does not run");
    let o = with.renderer.offscreen_buffers().expect("the off-screen light runs");
    let read = |b: &deep_gbuffer::wgpu::Buffer| {
        deep_gbuffer::gpu::read_buffer(&g.device, &g.queue, b).unwrap()
    };
    let faces: Vec<ShadowFace> = bytemuck::pod_collect_to_vec(&read(o.faces));
    let face_lights: Vec<u32> = bytemuck::pod_collect_to_vec(&read(o.face_lights));
    let vis: Vec<u64> = bytemuck::pod_collect_to_vec(&read(o.vis));
    let records = deep_gbuffer::GBufferLayer::decode(
        &read(o.records),
        RSM_RESOLUTION,
        RSM_RESOLUTION * o.face_count,
        on.precision,
    )
    .unwrap()
    .samples;
    let clusters: Vec<Cluster> = bytemuck::pod_collect_to_vec(&read(o.clusters));
    assert_eq!(o.face_count, 6, "the point light's six faces");
    let layers = [0, 1].map(|l| with.renderer.read_visibility(&g.device, &g.queue, l).unwrap());
    let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::new).collect();
    let params = OffscreenUniform::new(o.face_count, 0, 2);
    let rsm = reference::Rsm {
        frame: &with.frame,
        params: &params,
        lights: &lights,
        faces: &faces,
        face_lights: &face_lights,
        vis: &vis,
        records: &records,
        layers: [&layers[0], &layers[1]],
    };
    let expected = rsm.clusters();
    assert_eq!(clusters.len(), expected.len());
    // Sums of the same texels in another order (a tree against a loop): f32 rounding, and a
    // texel whose projection lands within an ulp of a pixel's edge may be held on one side only.
    let far = |a: &Cluster, e: &Cluster| {
        let close = |a: [f32; 3], e: [f32; 3], scale: f32| {
            glam::Vec3::from(a).distance(glam::Vec3::from(e)) <= 1e-3 * scale.max(1e-6)
        };
        (a.area - e.area).abs() > 1e-3 * e.area.max(1e-6)
            || !close(a.flux, e.flux, glam::Vec3::from(e.flux).max_element())
            || !close(a.position, e.position, 1.0)
            || !close(a.normal, e.normal, 1.0)
    };
    assert_few_differ(&clusters, &expected, 0.02, far, "the clusters against the CPU's");
    let lit = clusters.iter().filter(|c| c.area > 0.0 && c.flux[0] > 0.0).count();
    assert!(lit >= 32, "the ceiling above the screen sends light ({lit} clusters)");

    let gathered = |r: &Renderer| read4(r, r.radiosity_buffers().unwrap().gathered);
    let (before, after) = (gathered(&without.renderer), gathered(&with.renderer));
    let layer0 = with.renderer.read_gbuffer(&g.device, &g.queue, 0).unwrap().samples;
    let expected = reference::add(&with.frame, &params, &clusters, &layer0, &before);
    let far = |a: &Vec4, e: &Vec4| (*a - *e).abs().max_element() > 1e-4 * e.max_element().max(1.0);
    assert_few_differ(&after, &expected, 0.0, far, "the gather with the clusters' light");
    let mean =
        |v: &[Vec4]| v.iter().map(|e| e.truncate().element_sum()).sum::<f32>() / v.len() as f32;
    assert!(
        mean(&after) > 1.5 * mean(&before),
        "the light from above the screen counts: {} against {}",
        mean(&after),
        mean(&before)
    );
}
