//! What the benchmarks share: scenes by name, sizes from the environment, frames timed by GPU
//! timestamp queries, least-squares slopes and the summary file.

#![allow(dead_code)] // each benchmark uses its own part

use std::collections::BTreeMap;

use deep_gbuffer::gpu::Gpu;
use deep_gbuffer::{Camera, Renderer, Scene, SceneBuffers};

/// A scene by benchmark name: `engine` (the 2CylinderEngine fixture) or any `builtin:` name.
pub fn load(name: &str) -> Scene {
    match name {
        "engine" => Scene::load(&repo_path("fixtures/engine/2CylinderEngine.gltf")),
        other => Scene::from_spec(&format!("builtin:{other}")),
    }
    .unwrap_or_else(|e| panic!("scene {name}: {e}"))
}

/// `relative` inside the crate's folder where the benchmark was built, or inside the working
/// directory where that folder is gone: a bench binary carried to a machine without the sources'
/// path (a GPU machine without Rust, `scripts/gpu-report.sh`) runs from a copy of the repository.
pub fn repo_path(relative: &str) -> std::path::PathBuf {
    let built = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    if built.is_dir() { built.join(relative) } else { std::path::PathBuf::from(relative) }
}

/// The comma-separated list in environment variable `var`, or `default`.
pub fn list(var: &str, default: &str) -> Vec<String> {
    std::env::var(var)
        .unwrap_or_else(|_| default.into())
        .split(',')
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .collect()
}

/// Image sizes (`WxH,WxH`) from environment variable `var`, or `default`.
pub fn sizes(var: &str, default: &str) -> Vec<(u32, u32)> {
    list(var, default)
        .iter()
        .map(|s| {
            let (w, h) = s.split_once('x').unwrap_or_else(|| panic!("{var}: {s} is not WxH"));
            (w.parse().expect("width"), h.parse().expect("height"))
        })
        .collect()
}

/// Rounds of the alternated ratios: `DEEP_GBUFFER_BENCH_ROUNDS`, default 24 (0: none).
pub fn rounds() -> usize {
    std::env::var("DEEP_GBUFFER_BENCH_ROUNDS")
        .map_or(24, |v| v.parse().expect("DEEP_GBUFFER_BENCH_ROUNDS: a number of rounds"))
}

/// GPU milliseconds per pass, summed over frames.
#[derive(Default)]
pub struct PassTotals {
    /// Pass name to summed milliseconds.
    pub ms: BTreeMap<String, f64>,
    /// Frames summed.
    pub frames: u64,
    /// Pass name to the bytes it binds for reading and for writing (the last frame's).
    pub bytes: BTreeMap<String, (u64, u64)>,
}

impl PassTotals {
    /// Mean milliseconds of `pass` (0 when it never ran).
    pub fn mean(&self, pass: &str) -> f64 {
        self.ms.get(pass).map_or(0.0, |ms| ms / self.frames.max(1) as f64)
    }

    /// Mean milliseconds of the passes `which` accepts.
    pub fn mean_of(&self, which: impl Fn(&str) -> bool) -> f64 {
        self.ms.iter().filter(|(n, _)| which(n)).map(|(_, ms)| ms).sum::<f64>()
            / self.frames.max(1) as f64
    }

    /// Mean milliseconds of a whole frame.
    pub fn frame(&self) -> f64 {
        self.mean_of(|_| true)
    }
}

/// Renders `iters` frames, through `cameras` in turn, and adds each pass's GPU time to
/// `totals`; returns the frames' summed GPU milliseconds (every pass), which is what criterion
/// is given. Each frame runs every pass, as a frame of a scene whose geometry moves does (a
/// static scene keeps its shadow maps, and a still camera its G-buffer, obscurance and direct
/// light: see `Renderer::redraw`), so that their cost shows.
pub fn timed_frames(
    gpu: &Gpu,
    renderer: &mut Renderer,
    scene: &SceneBuffers,
    cameras: &[Camera],
    iters: u64,
    totals: &mut PassTotals,
) -> f64 {
    let mut sum = 0.0;
    for _ in 0..iters {
        renderer.redraw();
        let camera = &cameras[totals.frames as usize % cameras.len()];
        renderer.render(&gpu.device, &gpu.queue, scene, camera).unwrap();
        for t in renderer.timings(&gpu.device).unwrap() {
            totals.bytes.insert(t.name.clone(), (t.read_bytes, t.written_bytes));
            *totals.ms.entry(t.name).or_default() += t.ms;
            sum += t.ms;
        }
        totals.frames += 1;
    }
    sum
}

/// The least-squares line through `points` (x, y): (slope, intercept).
pub fn fit(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (sx, sy) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (slope, my - slope * mx)
}

/// Prints `table` and writes it to `target/<file>`.
pub fn write_summary(file: &str, table: &str) {
    println!("\n{table}");
    let out = repo_path("target").join(file);
    if let Some(dir) = out.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    if let Err(e) = std::fs::write(&out, table) {
        eprintln!("could not write {}: {e}", out.display());
    }
}
