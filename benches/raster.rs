//! Raster and resolve timed with GPU timestamp queries (criterion `iter_custom`: the reported
//! time is GPU time of the named pass, not wall clock), with the hardware-raster baseline drawing
//! the same triangles on the same adapter in the same run.
//!
//! The baseline runs on a second logical device of the same adapter: on lavapipe, once a render
//! pass has executed on a device, the timestamps of that device's later compute passes stop
//! adding up to the wall-clock time of the frame (measured: a resolve of 32 ms read as 0.05 ms),
//! while a separate device keeps them right.
//!
//! `DEEP_GBUFFER_BENCH_SIZES` (default `256x256,1920x1080`) and `DEEP_GBUFFER_BENCH_SCENES`
//! (default `cornell,engine`) narrow the run. A summary table (mean ms per pass, and the
//! compute/hardware ratio) is printed at the end and written to `target/raster-bench.md`, with
//! the ratios the goals name measured again frame by frame in turns (compute / hardware layer
//! 0, `Previous` and `Reproject` both layers / two-pass layer 0; `DEEP_GBUFFER_BENCH_ROUNDS`
//! rounds, default 24, 0 to leave them out), which hold on a busy machine.

mod common;

use std::sync::Mutex;
use std::time::Duration;

use criterion::Criterion;
use deep_gbuffer::gpu::{Gpu, GpuOptions, Timestamps};
use deep_gbuffer::testing::BaselinePass;
use deep_gbuffer::{Camera, Layer1Variant, Precision, Renderer, SceneBuffers, Settings};
use wgpu::util::DeviceExt;

static SUMMARY: Mutex<Vec<(String, String, f64)>> = Mutex::new(Vec::new());
static PACKED_ERRORS: Mutex<Vec<String>> = Mutex::new(Vec::new());
/// Per scene and size, per pair, the ratio of each round's two times.
static RATIOS: Mutex<Vec<(String, String, Vec<f64>)>> = Mutex::new(Vec::new());

/// Times `a` and `b` (each returns one frame's GPU milliseconds) one after the other in each
/// of `common::rounds()` rounds (after one round unrecorded), the order swapped each round, and
/// keeps each round's ratio a / b: the two run under the same load, so the ratio holds on a
/// busy machine where the means of two benchmarks taken a minute apart do not.
fn alternate(group: &str, name: &str, mut a: impl FnMut() -> f64, mut b: impl FnMut() -> f64) {
    let rounds = common::rounds();
    if rounds == 0 {
        return;
    }
    let ratios: Vec<f64> = (0..=rounds)
        .map(|i| {
            if i % 2 == 0 {
                let ta = a();
                ta / b()
            } else {
                let tb = b();
                a() / tb
            }
        })
        .skip(1)
        .collect();
    eprintln!("{group}: {name}: {:?}", spread(&ratios));
    RATIOS.lock().unwrap().push((group.to_string(), name.to_string(), ratios));
}

/// The median, the lowest and the highest of `ratios`.
fn spread(ratios: &[f64]) -> (f64, f64, f64) {
    let mut sorted = ratios.to_vec();
    sorted.sort_by(f64::total_cmp);
    (sorted[sorted.len() / 2], sorted[0], sorted[sorted.len() - 1])
}

/// The error of the packed G-buffer against the full one, over the surface pixels of both layers:
/// normal angle (max and mean, radians), base colour (max absolute), emission (max relative).
fn packed_error(gpu: &Gpu, buffers: &SceneBuffers, camera: &Camera, w: u32, h: u32) -> String {
    let layers = |precision| {
        let mut r = Renderer::new(
            &gpu.device,
            &gpu.queue,
            Settings { precision, layers: 2, timings: false, ..Settings::with_size(w, h) },
        )
        .unwrap();
        r.render(&gpu.device, &gpu.queue, buffers, camera).unwrap();
        [0, 1].map(|l| r.read_gbuffer(&gpu.device, &gpu.queue, l).unwrap())
    };
    let (full, packed) = (layers(Precision::Full), layers(Precision::Packed));
    let (mut max_angle, mut sum_angle, mut max_color, mut max_emission, mut n) =
        (0.0f32, 0.0f64, 0.0f32, 0.0f32, 0u64);
    for (f, p) in full.iter().zip(&packed) {
        for (a, b) in f.samples.iter().zip(&p.samples).filter(|(a, _)| a.depth > 0.0) {
            let angle = a.normal.dot(b.normal).clamp(-1.0, 1.0).acos();
            max_angle = max_angle.max(angle);
            sum_angle += f64::from(angle);
            max_color = max_color.max((a.base_color - b.base_color).abs().max_element());
            let e = a.emissive.max_element();
            if e > 0.0 {
                max_emission = max_emission.max((a.emissive - b.emissive).abs().max_element() / e);
            }
            n += 1;
        }
    }
    format!(
        "{:.2e} | {:.2e} | {:.2e} | {:.2e}",
        max_angle,
        sum_angle / n.max(1) as f64,
        max_color,
        max_emission
    )
}

/// Summed GPU milliseconds of `pass` over `iters` frames of `renderer`.
fn frames(
    gpu: &Gpu,
    renderer: &mut Renderer,
    scene: &SceneBuffers,
    camera: &Camera,
    pass: &str,
    iters: u64,
) -> f64 {
    let mut totals = common::PassTotals::default();
    common::timed_frames(gpu, renderer, scene, std::slice::from_ref(camera), iters, &mut totals);
    *totals.ms.get(pass).unwrap_or_else(|| panic!("no pass {pass}: {:?}", totals.ms.keys()))
}

fn record(group: &str, name: &str, sum: f64, count: u64) {
    if count == 0 {
        return; // filtered out on the command line
    }
    let ms = sum / count as f64;
    SUMMARY.lock().unwrap().push((group.to_string(), name.to_string(), ms));
}

fn bench_scene(c: &mut Criterion, gpu: &Gpu, hw: &Gpu, scene_name: &str, (w, h): (u32, u32)) {
    let scene = common::load(scene_name);
    let camera = scene.camera_or_default();
    let buffers = SceneBuffers::upload(&gpu.device, &scene).unwrap();
    let group_name = format!("{scene_name} ({} triangles) {w}x{h}", scene.triangle_count());
    if Renderer::new(&gpu.device, &gpu.queue, Settings::with_size(w, h)).is_ok() {
        let errors = packed_error(gpu, &buffers, &camera, w, h);
        PACKED_ERRORS.lock().unwrap().push(format!("| {group_name} | {errors} |"));
    }
    let mut group = c.benchmark_group(format!("raster/{scene_name}/{w}x{h}"));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));

    let variants: [(&str, Layer1Variant, Precision, &str); 9] = [
        ("raster.layer0", Layer1Variant::TwoPass, Precision::Full, "raster.layer0"),
        ("raster.layer1 two-pass", Layer1Variant::TwoPass, Precision::Full, "raster.layer1"),
        ("raster.layers previous", Layer1Variant::Previous, Precision::Full, "raster.layers"),
        ("raster.layers reproject", Layer1Variant::Reproject, Precision::Full, "raster.layers"),
        // Predict and Delay: one pass for both layers, plus the next frame's layer 0.
        ("raster.layers predict", Layer1Variant::Predict, Precision::Full, "raster.layers"),
        ("raster.next predict", Layer1Variant::Predict, Precision::Full, "raster.next"),
        ("resolve full", Layer1Variant::TwoPass, Precision::Full, "resolve"),
        ("resolve packed", Layer1Variant::TwoPass, Precision::Packed, "resolve"),
        ("raster.clear", Layer1Variant::TwoPass, Precision::Full, "raster.clear"),
    ];
    // The renderers of the variants the alternated pairs below time again.
    let mut kept: std::collections::HashMap<&str, Renderer> = Default::default();
    for (name, layer1, precision, pass) in variants {
        // Only the raster and resolve passes: obscurance has its own benchmark.
        let ao = deep_gbuffer::AoSettings { enabled: false, ..Default::default() };
        // Both layers whatever the scene calls for (a scene without lights needs one).
        let settings = Settings { layer1, precision, ao, layers: 2, ..Settings::with_size(w, h) };
        let mut renderer = match Renderer::new(&gpu.device, &gpu.queue, settings) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("skipping {name} at {w}x{h}: {e}");
                continue;
            }
        };
        // The first frame of a one-pass variant is two-pass; later frames have history.
        renderer.render(&gpu.device, &gpu.queue, &buffers, &camera).unwrap();
        let mut sum = 0.0;
        let mut count = 0u64;
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let ms = frames(gpu, &mut renderer, &buffers, &camera, pass, iters);
                sum += ms;
                count += iters;
                Duration::from_secs_f64(ms / 1e3)
            })
        });
        record(&group_name, name, sum, count);
        if matches!(name, "raster.layer0" | "raster.layers previous" | "raster.layers reproject") {
            kept.insert(name, renderer);
        }
    }

    // The same triangles through the hardware rasterizer, on a second device of the adapter,
    // with the camera constants the compute frames used.
    let mut renderer = Renderer::new(&gpu.device, &gpu.queue, Settings::with_size(w, h)).unwrap();
    renderer.render(&gpu.device, &gpu.queue, &buffers, &camera).unwrap();
    let frame = hw.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("deep-gbuffer.baseline.frame"),
        contents: bytemuck::bytes_of(renderer.frame_uniform().unwrap()),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let hw_buffers = SceneBuffers::upload(&hw.device, &scene).unwrap();
    let all_double_sided = scene.materials.iter().all(|m| m.double_sided);
    let baseline = BaselinePass::new(&hw.device, w, h, !all_double_sided);
    let mut timestamps = Timestamps::new(&hw.device, &hw.queue, 1).expect("timestamp queries");
    let mut hardware_frame = || {
        timestamps.reset();
        let mut encoder = hw.device.create_command_encoder(&Default::default());
        let writes = timestamps.render_pass("hardware.layer0");
        baseline.encode(&hw.device, &mut encoder, &hw_buffers, &frame, writes);
        timestamps.resolve(&mut encoder);
        hw.queue.submit([encoder.finish()]);
        timestamps.read(&hw.device).unwrap()[0].ms
    };
    let (mut sum, mut count) = (0.0, 0u64);
    group.bench_function("hardware.layer0", |b| {
        b.iter_custom(|iters| {
            let ms: f64 = (0..iters).map(|_| hardware_frame()).sum();
            sum += ms;
            count += iters;
            Duration::from_secs_f64(ms / 1e3)
        })
    });
    record(&group_name, "hardware.layer0", sum, count);

    // The ratios the goals name, each pair alternated frame by frame.
    if let Some(mut layer0) = kept.remove("raster.layer0") {
        let compute = |r: &mut Renderer, pass| frames(gpu, r, &buffers, &camera, pass, 1);
        alternate(
            &group_name,
            "compute / hardware layer 0",
            || compute(&mut layer0, "raster.layer0"),
            &mut hardware_frame,
        );
        for (variant, name) in [
            ("raster.layers previous", "previous both layers / layer 0"),
            ("raster.layers reproject", "reproject both layers / layer 0"),
        ] {
            let Some(mut one_pass) = kept.remove(variant) else { continue };
            alternate(
                &group_name,
                name,
                || compute(&mut one_pass, "raster.layers"),
                || compute(&mut layer0, "raster.layer0"),
            );
        }
    }
    group.finish();
}

fn main() {
    let gpu = Gpu::new(&GpuOptions::default(), &deep_gbuffer::Renderer::requirements())
        .expect("a GPU adapter (or lavapipe) for the benchmarks");
    let hw = Gpu::new(&GpuOptions::default(), &deep_gbuffer::Renderer::requirements())
        .expect("a second device for the hardware baseline");
    let load_at_start = deep_gbuffer::gpu::describe_load();
    let sizes = common::sizes("DEEP_GBUFFER_BENCH_SIZES", "256x256,1920x1080");
    let scenes = common::list("DEEP_GBUFFER_BENCH_SCENES", "cornell,engine");
    let mut c = Criterion::default().configure_from_args();
    for scene in &scenes {
        for &size in &sizes {
            bench_scene(&mut c, &gpu, &hw, scene, size);
        }
    }
    c.final_summary();

    let mut table = format!(
        "Device: {}\nAt the start: {}; at the end: {}\n\n| scene | pass | GPU ms |\n|---|---|---:|\n",
        gpu.describe(),
        load_at_start,
        deep_gbuffer::gpu::describe_load()
    );
    let summary = SUMMARY.lock().unwrap();
    for (group, name, ms) in summary.iter() {
        table += &format!("| {group} | {name} | {ms:.3} |\n");
    }
    table += "\n| scene | compute layer 0 / hardware layer 0 | layer 1 (two-pass) / layer 0 |\n|---|---:|---:|\n";
    let find =
        |g: &str, n: &str| summary.iter().find(|(gg, nn, _)| gg == g && nn == n).map(|x| x.2);
    let mut groups: Vec<&String> = summary.iter().map(|(g, _, _)| g).collect();
    groups.dedup();
    for g in groups {
        if let (Some(l0), Some(hw), Some(l1)) = (
            find(g, "raster.layer0"),
            find(g, "hardware.layer0"),
            find(g, "raster.layer1 two-pass"),
        ) {
            table += &format!("| {g} | {:.1} | {:.2} |\n", l0 / hw, l1 / l0);
        }
    }
    table += "\nEach pair timed frame by frame in turns (the same load for both; the median, lowest and highest of the rounds' ratios):\n\n| scene | pair | median | range | rounds |\n|---|---|---:|---:|---:|\n";
    for (g, name, ratios) in RATIOS.lock().unwrap().iter() {
        let (median, low, high) = spread(ratios);
        table +=
            &format!("| {g} | {name} | {median:.2} | {low:.2}-{high:.2} | {} |\n", ratios.len());
    }
    table += "\n| scene | normal angle max (rad) | normal angle mean (rad) | base colour max abs | emission max rel |\n|---|---:|---:|---:|---:|\n";
    for row in PACKED_ERRORS.lock().unwrap().iter() {
        table += row;
        table += "\n";
    }
    common::write_summary("raster-bench.md", &table);
}
