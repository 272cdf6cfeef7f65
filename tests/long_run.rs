//! The long run: 10,000 frames with a moving camera. Run it on purpose (it takes minutes on a
//! software driver): `cargo test --test long_run -- --ignored --nocapture`.
//!
//! It checks that per-frame time and the process's resident memory (on a software driver the
//! GPU's memory is the process's) stay flat, that no NaN appears in the image or the history,
//! and that a second run with the same inputs gives a bit-identical image.

mod common;

use common::gpu;
use deep_gbuffer::{Camera, Renderer, Scene, SceneBuffers, Settings};
use glam::{Quat, Vec3};

/// Frames per run: 10,000, or `DEEP_GBUFFER_LONG_RUN_FRAMES`.
fn frames() -> u32 {
    std::env::var("DEEP_GBUFFER_LONG_RUN_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000)
}

const WINDOW: u32 = 500;

fn resident_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096)
}

/// Renders frames() orbiting the Cornell box; returns the last image's bits, the mean
/// milliseconds per frame of each WINDOW, and the resident memory after each WINDOW.
fn run() -> (Vec<u32>, Vec<f64>, Vec<u64>) {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let start = scene.camera_or_default();
    let buffers = SceneBuffers::upload(&g.device, &scene).unwrap();
    let shadows = deep_gbuffer::ShadowSettings { resolution: 64, ..Default::default() };
    let settings = Settings { timings: false, shadows, ..Settings::with_size(32, 24) };
    let mut renderer = Renderer::new(&g.device, &g.queue, settings).unwrap();
    let (mut times, mut memory) = (Vec::new(), Vec::new());
    let mut window = std::time::Instant::now();
    for i in 0..frames() {
        // A slow orbit, back and forth: 0.5 degrees a frame.
        let angle = (0.5 * i as f32).to_radians().sin() * 0.6;
        let camera = Camera {
            eye: start.target + Quat::from_axis_angle(Vec3::Y, angle) * (start.eye - start.target),
            ..start.clone()
        };
        renderer.render(&g.device, &g.queue, &buffers, &camera).unwrap();
        if (i + 1) % WINDOW == 0 {
            let hdr = renderer.read_rgb(&g.device, &g.queue, renderer.hdr_buffer()).unwrap();
            assert!(hdr.iter().all(|c| c.is_finite()), "frame {i}: a non-finite pixel");
            let history = renderer
                .read_f32(&g.device, &g.queue, renderer.radiosity_buffers().unwrap().filtered)
                .unwrap();
            assert!(history.iter().all(|v| v.is_finite()), "frame {i}: a non-finite history");
            times.push(window.elapsed().as_secs_f64() * 1e3 / f64::from(WINDOW));
            memory.push(resident_bytes().unwrap_or(0));
            window = std::time::Instant::now();
        }
    }
    let hdr = renderer.read_rgb(&g.device, &g.queue, renderer.hdr_buffer()).unwrap();
    (hdr.iter().flat_map(|c| c.to_array().map(f32::to_bits)).collect(), times, memory)
}

#[test]
#[ignore = "minutes long; run on purpose"]
fn ten_thousand_frames_stay_flat_finite_and_reproducible() {
    let (image_a, times, memory) = run();
    eprintln!("ms per frame, per {WINDOW} frames: {times:.2?}");
    eprintln!(
        "resident MiB after each {WINDOW}: {:?}",
        memory.iter().map(|b| b / (1 << 20)).collect::<Vec<_>>()
    );
    // Flat: the last window is no slower than the second by more than half (the first warms up;
    // a shared machine adds noise), and memory grows by less than 16 MiB after the first window.
    assert!(times[times.len() - 1] < times[1] * 1.5, "per-frame time grew: {times:?}");
    let growth = memory[memory.len() - 1].saturating_sub(memory[0]);
    assert!(growth < 16 << 20, "resident memory grew by {growth} bytes");
    let (image_b, _, _) = run();
    assert!(image_a == image_b, "two runs with the same inputs differ");
}
