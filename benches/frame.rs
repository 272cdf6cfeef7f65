//! Whole frames timed with GPU timestamp queries (criterion `iter_custom`: the time criterion
//! reports is the frame's GPU time, the sum of its passes), in three groups:
//!
//! - `passes`: every pass of the full GI frame, of the direct-only frame (the same direct
//!   light and shadows, no obscurance, radiosity or reflections), of the GI frame through a
//!   lens (depth of field) and of the GI frame with the shutter open while the camera turns
//!   (motion blur) on the Cornell box and a dense scene at 256x256 and 1920x1080; the ratio of
//!   the first two is what the GI costs. Each GI frame's passes are also set against their byte
//!   floor: the bytes each binds (`PassTiming::read_bytes`, `written_bytes`) at the bandwidth
//!   measured at the start of the run (`gpu::measure_bandwidth`).
//! - `triangles`: the two-layer raster (two-pass) and the resolve of `grid-N` for N from 1K to
//!   5M triangles at 640x360; the slope is milliseconds per million triangles.
//! - `resolution`: every pass of the Cornell frame from 256x256 to 3840x2160; the slope of each
//!   per-pixel pass is milliseconds per megapixel (the shadow maps do not depend on it). A size
//!   the device cannot hold is listed with the error it gets.
//! - `transparency`: the GI frame of `builtin:cornell-glass` (two blended panes) peeled 1 and 4
//!   layers deep at the `passes` sizes: what the transparency passes cost.
//!
//! Environment: `DEEP_GBUFFER_BENCH_GROUPS` (default `passes,triangles,resolution,transparency`),
//! `DEEP_GBUFFER_BENCH_SCENES` (default `cornell,grid-100000`), `DEEP_GBUFFER_BENCH_SIZES`
//! (default `256x256,1920x1080`), `DEEP_GBUFFER_BENCH_TRIANGLES` (default
//! `1000,10000,100000,1000000,5000000`), `DEEP_GBUFFER_BENCH_RESOLUTIONS` (default
//! `256x256,640x480,1280x720,1920x1080,2560x1440,3840x2160`). The summary is printed at the end
//! and written to `target/frame-bench.md`.

mod common;

use std::fmt::Write as _;
use std::time::Duration;

use common::PassTotals;
use criterion::{Criterion, SamplingMode};
use deep_gbuffer::gpu::{Bandwidth, Gpu, GpuOptions};
use deep_gbuffer::{Effects, Renderer, SceneBuffers, Settings};

/// One criterion function timing whole frames of `settings`; the per-pass means come back.
fn bench_frames(
    c: &mut Criterion,
    gpu: &Gpu,
    group: &str,
    name: &str,
    scene: &SceneBuffers,
    cameras: &[deep_gbuffer::Camera],
    settings: Settings,
) -> Result<PassTotals, deep_gbuffer::Error> {
    let mut renderer = Renderer::new(&gpu.device, &gpu.queue, settings)?;
    // Pipelines are built on first use; the first frame (and the one-pass variants' two-pass
    // first frame) stays out of the figures.
    for camera in cameras.iter().cycle().take(2) {
        renderer.render(&gpu.device, &gpu.queue, scene, camera)?;
    }
    let mut totals = PassTotals::default();
    let mut g = c.benchmark_group(group);
    g.sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(200))
        .measurement_time(Duration::from_secs(2));
    g.bench_function(name, |b| {
        b.iter_custom(|iters| {
            let ms = common::timed_frames(gpu, &mut renderer, scene, cameras, iters, &mut totals);
            Duration::from_secs_f64(ms / 1e3)
        })
    });
    g.finish();
    Ok(totals)
}

/// One camera, as `bench_frames` takes them.
fn one(camera: &deep_gbuffer::Camera) -> &[deep_gbuffer::Camera] {
    std::slice::from_ref(camera)
}

fn direct_only() -> Effects {
    Effects { ao: false, radiosity: false, reflections: false, ..Effects::default() }
}

/// Each pass of `t` against its byte floor: the bytes it binds at `bandwidth`.
fn floor_table(out: &mut String, t: &PassTotals, bandwidth: &Bandwidth) {
    let _ = writeln!(
        out,
        "| pass (GI frame) | ms | MB read | MB written | byte floor ms | ms / floor |\n|---|---:|---:|---:|---:|---:|"
    );
    for (pass, &(read, written)) in &t.bytes {
        let floor = bandwidth.floor_ms(read, written);
        let ms = t.mean(pass);
        let _ = writeln!(
            out,
            "| `{pass}` | {ms:.2} | {:.1} | {:.1} | {floor:.3} | {:.1} |",
            read as f64 / 1e6,
            written as f64 / 1e6,
            ms / floor
        );
    }
    out.push('\n');
}

fn passes(c: &mut Criterion, gpu: &Gpu, out: &mut String, bandwidth: Option<&Bandwidth>) {
    let scenes = common::list("DEEP_GBUFFER_BENCH_SCENES", "cornell,grid-100000");
    let sizes = common::sizes("DEEP_GBUFFER_BENCH_SIZES", "256x256,1920x1080");
    let _ =
        writeln!(out, "## Every pass: full GI frame, direct-only frame, GI frame through a lens\n");
    let mut ratios = String::from(
        "| scene | size | GI frame ms | direct-only frame ms | GI / direct-only |\n|---|---|---:|---:|---:|\n",
    );
    for name in &scenes {
        let scene = common::load(name);
        let camera = scene.camera_or_default();
        let buffers = SceneBuffers::upload(&gpu.device, &scene).unwrap();
        for &(w, h) in &sizes {
            let group = format!("frame/{name}/{w}x{h}");
            let full = bench_frames(
                c,
                gpu,
                &group,
                "gi",
                &buffers,
                one(&camera),
                Settings::with_size(w, h),
            );
            let settings = Settings { effects: direct_only(), ..Settings::with_size(w, h) };
            let direct =
                bench_frames(c, gpu, &group, "direct-only", &buffers, one(&camera), settings);
            // The GI frame through a lens focused on the camera's target, its aperture a fiftieth
            // of that distance: what the depth of field adds.
            let mut lens_camera = camera.clone();
            let focus = (camera.target - camera.eye).length();
            lens_camera.lens = deep_gbuffer::Lens { radius: focus / 50.0, focus };
            let settings = Settings::with_size(w, h);
            let lens =
                bench_frames(c, gpu, &group, "gi-lens", &buffers, one(&lens_camera), settings);
            // The GI frame with the shutter open, the camera turning back and forth by two
            // degrees a frame: what the motion blur adds.
            let mut settings = Settings::with_size(w, h);
            settings.motion_blur.shutter = 1.0;
            let turning = [camera.clone(), camera.orbited(2.0)];
            let shutter = bench_frames(c, gpu, &group, "gi-shutter", &buffers, &turning, settings);
            let frames = [full, direct, lens, shutter];
            if let Some(Err(e)) = frames.iter().find(|f| f.is_err()) {
                let _ = writeln!(out, "{name} {w}x{h}: {e}\n");
                continue;
            }
            let [full, direct, lens, shutter] = frames.map(|f| f.unwrap_or_default());
            if [&full, &direct, &lens, &shutter].iter().any(|t| t.frames == 0) {
                continue; // filtered out on the command line
            }
            let _ = writeln!(
                out,
                "{name} ({} triangles) {w}x{h}\n\n| pass | GI frame ms | direct-only ms | GI through a lens ms | GI, shutter open ms |\n|---|---:|---:|---:|---:|",
                scene.triangle_count()
            );
            let column = |t: &PassTotals, pass: &str| {
                if t.ms.contains_key(pass) { format!("{:.2}", t.mean(pass)) } else { "-".into() }
            };
            let mut names: Vec<&String> = lens.ms.keys().chain(shutter.ms.keys()).collect();
            names.sort();
            names.dedup();
            for pass in names {
                let (f, d) = (column(&full, pass), column(&direct, pass));
                let (l, m) = (column(&lens, pass), column(&shutter, pass));
                let _ = writeln!(out, "| `{pass}` | {f} | {d} | {l} | {m} |");
            }
            let (f, d, l, m) = (full.frame(), direct.frame(), lens.frame(), shutter.frame());
            let _ = writeln!(out, "| total | {f:.2} | {d:.2} | {l:.2} | {m:.2} |\n");
            if let Some(bandwidth) = bandwidth {
                floor_table(out, &full, bandwidth);
            }
            let _ = writeln!(
                ratios,
                "| {name} | {w}x{h} | {:.2} | {:.2} | {:.2} |",
                full.frame(),
                direct.frame(),
                full.frame() / direct.frame()
            );
        }
    }
    out.push_str(&ratios);
    out.push('\n');
}

fn triangles(c: &mut Criterion, gpu: &Gpu, out: &mut String) {
    let counts = common::list("DEEP_GBUFFER_BENCH_TRIANGLES", "1000,10000,100000,1000000,5000000");
    let (w, h) = (640, 360);
    let _ = writeln!(
        out,
        "## Scaling with triangles (`grid-N`, {w}x{h}, two layers, two-pass)\n\n| triangles | `raster.layer0` ms | `raster.layer1` ms | `resolve` ms |\n|---:|---:|---:|---:|"
    );
    let mut points: [Vec<(f64, f64)>; 3] = Default::default();
    for n in counts {
        let scene = common::load(&format!("grid-{n}"));
        let camera = scene.camera_or_default();
        let buffers = SceneBuffers::upload(&gpu.device, &scene).unwrap();
        // The raster and the resolve alone: no lighting pass, two layers forced.
        let effects = Effects { direct: false, shadows: false, ..direct_only() };
        let settings = Settings { layers: 2, effects, ..Settings::with_size(w, h) };
        let t = match bench_frames(
            c,
            gpu,
            "triangles",
            &format!("grid-{n}"),
            &buffers,
            one(&camera),
            settings,
        ) {
            Ok(t) if t.frames > 0 => t,
            Ok(_) => continue,
            Err(e) => {
                let _ = writeln!(out, "| {} | {e} | | |", scene.triangle_count());
                continue;
            }
        };
        let m = scene.triangle_count() as f64 / 1e6;
        let row = ["raster.layer0", "raster.layer1", "resolve"].map(|p| t.mean(p));
        for (points, ms) in points.iter_mut().zip(row) {
            points.push((m, ms));
        }
        let _ = writeln!(
            out,
            "| {} | {:.2} | {:.2} | {:.2} |",
            scene.triangle_count(),
            row[0],
            row[1],
            row[2]
        );
    }
    let slopes = points.each_ref().map(|p| common::fit(p).0);
    let _ = writeln!(
        out,
        "| slope, ms per million triangles | {:.1} | {:.1} | {:.1} |\n",
        slopes[0], slopes[1], slopes[2]
    );
}

fn resolution(c: &mut Criterion, gpu: &Gpu, out: &mut String) {
    let sizes = common::sizes(
        "DEEP_GBUFFER_BENCH_RESOLUTIONS",
        "256x256,640x480,1280x720,1920x1080,2560x1440,3840x2160",
    );
    let scene = common::load("cornell");
    let camera = scene.camera_or_default();
    let buffers = SceneBuffers::upload(&gpu.device, &scene).unwrap();
    let mut rows: Vec<((u32, u32), PassTotals)> = Vec::new();
    let _ = writeln!(out, "## Scaling with resolution (Cornell box, full GI frame)\n");
    for (w, h) in sizes {
        match bench_frames(
            c,
            gpu,
            "resolution",
            &format!("{w}x{h}"),
            &buffers,
            one(&camera),
            Settings::with_size(w, h),
        ) {
            Ok(t) if t.frames > 0 => rows.push(((w, h), t)),
            Ok(_) => {}
            Err(e) => {
                let _ = writeln!(out, "{w}x{h}: {e}\n");
            }
        }
    }
    let mut names: Vec<&String> = rows.iter().flat_map(|(_, t)| t.ms.keys()).collect();
    names.sort();
    names.dedup();
    let _ = write!(out, "| pass |");
    for ((w, h), _) in &rows {
        let _ = write!(out, " {w}x{h} |");
    }
    let _ = writeln!(out, " ms per megapixel |\n|---|{}---:|", "---:|".repeat(rows.len()));
    let per_pixel = |n: &str| !n.starts_with("shadow.");
    for name in names.iter().map(|n| n.as_str()).chain(["per-pixel passes"]) {
        let _ = write!(out, "| `{name}` |");
        let mut points = Vec::new();
        for ((w, h), t) in &rows {
            let ms = if name == "per-pixel passes" { t.mean_of(per_pixel) } else { t.mean(name) };
            points.push((f64::from(w * h) / 1e6, ms));
            let _ = write!(out, " {ms:.2} |");
        }
        let slope =
            if per_pixel(name) { format!("{:.1}", common::fit(&points).0) } else { "-".into() };
        let _ = writeln!(out, " {slope} |");
    }
    out.push('\n');
}

fn transparency(c: &mut Criterion, gpu: &Gpu, out: &mut String) {
    let sizes = common::sizes("DEEP_GBUFFER_BENCH_SIZES", "256x256,1920x1080");
    let scene = common::load("cornell-glass");
    let camera = scene.camera_or_default();
    let buffers = SceneBuffers::upload(&gpu.device, &scene).unwrap();
    let _ = writeln!(out, "## Transparency (Cornell box with two blended panes, full GI frame)\n");
    let _ = writeln!(
        out,
        "| size | layers (k) | `transparency.peel` ms | `transparency.composite` ms | frame ms |\n|---|---:|---:|---:|---:|"
    );
    for &(w, h) in &sizes {
        for layers in [1, 4] {
            let mut settings = Settings::with_size(w, h);
            settings.transparency.layers = layers;
            let group = format!("transparency/{w}x{h}");
            match bench_frames(
                c,
                gpu,
                &group,
                &format!("k{layers}"),
                &buffers,
                one(&camera),
                settings,
            ) {
                Ok(t) if t.frames > 0 => {
                    let _ = writeln!(
                        out,
                        "| {w}x{h} | {layers} | {:.2} | {:.2} | {:.2} |",
                        t.mean("transparency.peel"),
                        t.mean("transparency.composite"),
                        t.frame()
                    );
                }
                Ok(_) => {}
                Err(e) => {
                    let _ = writeln!(out, "| {w}x{h} | {layers} | {e} | | |");
                }
            }
        }
    }
    out.push('\n');
}

fn main() {
    let gpu = Gpu::new(&GpuOptions::default(), &deep_gbuffer::Renderer::requirements())
        .expect("a GPU adapter (or lavapipe) for the benchmarks");
    let groups =
        common::list("DEEP_GBUFFER_BENCH_GROUPS", "passes,triangles,resolution,transparency");
    let mut c = Criterion::default().configure_from_args();
    let mut out = format!(
        "Device: {}\nAt the start: {}\n",
        gpu.describe(),
        deep_gbuffer::gpu::describe_load()
    );
    // The byte floors' bandwidth, measured in this run (64 MiB read and written, best of three).
    let bandwidth = deep_gbuffer::gpu::measure_bandwidth(&gpu.device, &gpu.queue, 64 << 20)
        .expect("the bandwidth probe runs");
    match &bandwidth {
        Some(b) => {
            let _ = writeln!(
                out,
                "Bandwidth: read {:.1} GB/s, write {:.1} GB/s\n",
                b.read_bytes_per_s / 1e9,
                b.write_bytes_per_s / 1e9
            );
        }
        None => out.push_str("Bandwidth: not measured (no timestamps)\n\n"),
    }
    for group in &groups {
        match group.as_str() {
            "passes" => passes(&mut c, &gpu, &mut out, bandwidth.as_ref()),
            "triangles" => triangles(&mut c, &gpu, &mut out),
            "resolution" => resolution(&mut c, &gpu, &mut out),
            "transparency" => transparency(&mut c, &gpu, &mut out),
            other => panic!("DEEP_GBUFFER_BENCH_GROUPS: unknown group {other}"),
        }
    }
    c.final_summary();
    out += &format!("At the end: {}\n", deep_gbuffer::gpu::describe_load());
    common::write_summary("frame-bench.md", &out);
}
