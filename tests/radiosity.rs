//! Screen-space radiosity: the first frame against the CPU reference, temporal convergence on a
//! static camera, a camera cut that resets the history, and non-finite input that never enters
//! the history.

mod common;

use common::{gpu, render_frames};
use deep_gbuffer::cpu::radiosity as cpu;
use deep_gbuffer::passes::radiosity::RadiosityUniform;
use deep_gbuffer::{Renderer, Scene, SceneBuffers, Settings};
use glam::Vec4;

/// As for obscurance: a tap within an ulp of a pixel border may land on the neighbouring pixel on
/// one side and not the other (GPU cos/sin), changing that pixel's sum by one tap. Such pixels
/// must stay rare; the rest agree to f32 rounding of the sums.
const RADIOSITY_TOLERANCE: f32 = 1e-3;
const RADIOSITY_FLIPPED_FRACTION: f64 = 0.02;

fn read4(r: &Renderer, buffer: &wgpu::Buffer) -> Vec<Vec4> {
    let g = gpu();
    let v = r.read_f32(&g.device, &g.queue, buffer).unwrap();
    let n = (r.settings().width * r.settings().height) as usize;
    v.chunks_exact(4).take(n).map(|c| Vec4::new(c[0], c[1], c[2], c[3])).collect()
}

fn settings(w: u32, h: u32) -> Settings {
    Settings { timings: false, ..Settings::with_size(w, h) }
}

#[test]
fn first_frame_matches_cpu_reference() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let (w, h) = (64, 48);
    let r = render_frames(&scene, &[scene.camera_or_default()], settings(w, h));
    let g = gpu();
    let layers = [0, 1].map(|l| r.renderer.read_gbuffer(&g.device, &g.queue, l).unwrap().samples);
    let [b0, b1, raw, _, _] =
        r.renderer.radiosity_buffers().expect("radiosity runs on the Cornell box");
    let (b0, b1, raw) = (read4(&r.renderer, b0), read4(&r.renderer, b1), read4(&r.renderer, raw));
    let b = [
        b0.iter().map(|v| v.truncate()).collect::<Vec<_>>(),
        b1.iter().map(|v| v.truncate()).collect::<Vec<_>>(),
    ];
    // B without history is direct + emission (direct of layer 0 checked in tests/direct.rs).
    let direct0 =
        r.renderer.read_rgb(&g.device, &g.queue, r.renderer.direct_buffer().unwrap()).unwrap();
    let expected_b0 = cpu::feedback_without_history(&layers[0], &direct0);
    for (a, e) in b[0].iter().zip(&expected_b0) {
        assert!((*a - *e).abs().max_element() <= 1e-5 * e.max_element().max(1.0), "{a} vs {e}");
    }
    let uniform = RadiosityUniform::new(&Settings::default().radiosity, false, 0);
    let expected = cpu::gather(&r.frame, &uniform, [&layers[0], &layers[1]], [&b[0], &b[1]]);
    let differ = raw
        .iter()
        .zip(&expected)
        .filter(|(a, e)| {
            (**a - **e).abs().max_element() > RADIOSITY_TOLERANCE * e.max_element().max(1.0)
        })
        .count();
    assert!(
        (differ as f64) <= RADIOSITY_FLIPPED_FRACTION * raw.len() as f64,
        "{differ} of {} pixels differ from the CPU gather",
        raw.len()
    );
    let lit = raw.iter().filter(|e| e.truncate().max_element() > 0.01).count();
    assert!(lit > raw.len() / 2, "the box receives indirect light ({lit})");
    assert!(raw.iter().all(|e| e.is_finite() && e.min_element() >= 0.0 && e.w <= 1.0));
}

/// On a static camera, with the spiral held still, the multi-bounce feedback and the temporal
/// filter converge to a fixed point: the frame-to-frame change dies away.
#[test]
fn a_static_camera_converges_and_a_cut_resets() {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let buffers = SceneBuffers::upload(&g.device, &scene).unwrap();
    let radiosity = deep_gbuffer::RadiositySettings { jitter: false, ..Default::default() };
    let shadows = deep_gbuffer::ShadowSettings { enabled: false, ..Default::default() };
    let mut renderer =
        Renderer::new(&g.device, &g.queue, Settings { radiosity, shadows, ..settings(32, 24) })
            .unwrap();
    let mut frames = Vec::new();
    for _ in 0..120 {
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        frames.push(read4(&renderer, renderer.radiosity_buffers().unwrap()[3]));
    }
    let change = |a: &[Vec4], b: &[Vec4]| {
        a.iter().zip(b).map(|(x, y)| (*x - *y).truncate().abs().max_element()).fold(0.0, f32::max)
    };
    let mean =
        |f: &[Vec4]| f.iter().map(|v| v.truncate().element_sum()).sum::<f32>() / f.len() as f32;
    let early = change(&frames[1], &frames[2]);
    let late = change(&frames[118], &frames[119]);
    eprintln!(
        "largest per-pixel change: {early} (frame 2), {late} (frame 120); mean {} -> {}",
        mean(&frames[0]),
        mean(&frames[119])
    );
    assert!(mean(&frames[119]) > mean(&frames[0]) * 1.05, "later bounces add light");
    assert!(late < 1e-3 * early.max(1e-6) + 1e-4, "converged: {early} early, {late} late");

    // A camera cut: the history is dropped, the next frame is a first frame again.
    renderer.reset_history();
    renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    let after_cut = read4(&renderer, renderer.radiosity_buffers().unwrap()[3]);
    assert_eq!(after_cut, frames[0], "after a cut the history does not leak into the frame");
}

/// A material with a NaN emission (possible only through imported buffers, which the CPU does not
/// check) must not poison the history: after many frames no output or history value is NaN.
#[test]
fn nan_input_never_enters_the_history() {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let uploaded = SceneBuffers::upload(&g.device, &scene).unwrap();
    let mut b = uploaded.buffers().clone();
    let mut materials: Vec<deep_gbuffer::GpuMaterial> = bytemuck::pod_collect_to_vec(
        &deep_gbuffer::gpu::read_buffer(&g.device, &g.queue, &b.materials).unwrap()
            [..scene.materials.len() * 64],
    );
    materials[0].emissive = [f32::NAN, 1.0, f32::INFINITY];
    b.materials = deep_gbuffer::gpu::storage_buffer_init(
        &g.device,
        "test.materials",
        bytemuck::cast_slice(&materials),
    );
    let buffers = SceneBuffers::import(&g.device, b, uploaded.info().clone()).unwrap();
    // Obscurance and shadows off: 1000 frames of what matters here.
    let s = Settings {
        ao: deep_gbuffer::AoSettings { enabled: false, ..Default::default() },
        shadows: deep_gbuffer::ShadowSettings { enabled: false, ..Default::default() },
        ..settings(12, 9)
    };
    let mut renderer = Renderer::new(&g.device, &g.queue, s).unwrap();
    let camera = scene.camera_or_default();
    for _ in 0..1000 {
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
    }
    let [b0, b1, raw, history, blurred] = renderer.radiosity_buffers().unwrap();
    for (name, buffer) in
        [("b0", b0), ("b1", b1), ("raw", raw), ("history", history), ("blurred", blurred)]
    {
        let values = read4(&renderer, buffer);
        assert!(values.iter().all(|v| v.is_finite()), "{name} holds a non-finite value");
    }
    let hdr = renderer.read_rgb(&g.device, &g.queue, renderer.hdr_buffer().unwrap()).unwrap();
    let bad = hdr.iter().filter(|c| !c.is_finite()).count();
    // The NaN emission shows only where that material is seen directly (the composite adds it);
    // it spreads nowhere else.
    let direct_material_pixels = renderer
        .read_gbuffer(&g.device, &g.queue, 0)
        .unwrap()
        .samples
        .iter()
        .filter(|s| s.depth > 0.0 && s.material == 0)
        .count();
    assert!(
        bad <= direct_material_pixels,
        "{bad} non-finite pixels, {direct_material_pixels} showing the material"
    );
}
