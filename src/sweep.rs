//! What accuracy costs in time: render a grid of configurations of one scene and camera, time
//! every pass with GPU timestamps, and measure each effect's error against ground truth
//! ([`crate::truth`]).
//!
//! The effects measured are the ambient visibility (against world-space obscurance with the same
//! radius and falloff) and the radiosity irradiance of a first frame as the composite weighs it,
//! confidence times E (against one-bounce
//! diffuse indirect irradiance: a first frame gathers B = direct + emission, one bounce). Each
//! configuration renders a first frame (which warms caches and pipelines), then three more, each from an empty history, and keeps the
//! median time of each pass; the estimate is the same every time.

use std::io::Write;
use std::path::Path;

use glam::Vec3;

use crate::scene::{Camera, Scene};
use crate::settings::{AoSettings, Precision, RadiositySettings, Settings};
use crate::truth::metrics::{self, ErrorStats};
use crate::truth::{Tracer, TruthImage};
use crate::{Error, Renderer, Result, SceneBuffers};

/// One configuration of the accuracy knobs.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Knobs {
    /// Obscurance taps per pixel.
    pub ao_samples: u32,
    /// Radiosity taps per pixel.
    pub radiosity_samples: u32,
    /// G-buffer layers (1: layer 0 only, for both effects; 2: the deep G-buffer).
    pub layers: u32,
    /// G-buffer encoding.
    pub precision: Precision,
}

impl Knobs {
    /// The renderer settings of this configuration at `width` x `height`.
    pub fn settings(&self, width: u32, height: u32) -> Settings {
        Settings {
            layers: self.layers,
            precision: self.precision,
            ao: AoSettings {
                samples: self.ao_samples,
                two_layers: self.layers == 2,
                ..AoSettings::default()
            },
            radiosity: RadiositySettings {
                samples: self.radiosity_samples,
                ..RadiositySettings::default()
            },
            timings: true,
            ..Settings::with_size(width, height)
        }
    }
}

/// The grid a sweep renders: every combination of these values.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Obscurance taps.
    pub ao_samples: Vec<u32>,
    /// Radiosity taps.
    pub radiosity_samples: Vec<u32>,
    /// Layer counts.
    pub layers: Vec<u32>,
    /// Encodings.
    pub precision: Vec<Precision>,
}

impl Default for Grid {
    fn default() -> Self {
        Grid {
            ao_samples: vec![4, 8, 11, 16, 24, 32],
            radiosity_samples: vec![5, 9, 13, 19, 27],
            layers: vec![1, 2],
            precision: vec![Precision::Full, Precision::Packed],
        }
    }
}

impl Grid {
    /// Every configuration, in a fixed order.
    pub fn configurations(&self) -> Vec<Knobs> {
        let mut out = Vec::new();
        for &precision in &self.precision {
            for &layers in &self.layers {
                for &ao_samples in &self.ao_samples {
                    for &radiosity_samples in &self.radiosity_samples {
                        out.push(Knobs { ao_samples, radiosity_samples, layers, precision });
                    }
                }
            }
        }
        out
    }
}

/// The ground truth a sweep compares with.
pub struct Truth {
    /// World-space obscurance (the default radius and falloff).
    pub ao: TruthImage,
    /// One-bounce diffuse indirect irradiance.
    pub indirect: TruthImage,
}

impl Truth {
    /// Traces both truths of `scene` from `camera` at `width` x `height` with `spp` rays per
    /// pixel (`progress` is called once per finished row of each).
    pub fn trace(
        scene: &Scene,
        camera: &Camera,
        (width, height): (u32, u32),
        spp: u32,
        progress: &(dyn Fn() + Sync),
    ) -> Result<Truth> {
        let tracer = Tracer::new(scene)?;
        let ao = AoSettings::default();
        Ok(Truth {
            ao: tracer.ambient_obscurance(scene, camera, width, height, &ao, spp, 1, progress)?,
            indirect: tracer.indirect(scene, camera, width, height, 1, spp, 2, progress)?,
        })
    }
}

/// One measured configuration.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// The knobs.
    pub knobs: Knobs,
    /// GPU milliseconds per pass (stable names), in order.
    pub passes: Vec<(String, f64)>,
    /// Sum of all passes.
    pub total_ms: f64,
    /// Obscurance error (AV after the blur).
    pub ao: ErrorStats,
    /// Radiosity error (the irradiance the composite takes from it: confidence times E).
    pub indirect: ErrorStats,
}

impl Row {
    /// Milliseconds of the passes named.
    pub fn ms_of(&self, names: &[&str]) -> f64 {
        self.passes.iter().filter(|(n, _)| names.contains(&n.as_str())).map(|(_, ms)| ms).sum()
    }
}

/// Renders and measures one configuration.
pub fn measure(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &SceneBuffers,
    camera: &Camera,
    truth: &Truth,
    knobs: &Knobs,
) -> Result<Row> {
    let (w, h) = (truth.ao.width, truth.ao.height);
    let mut renderer = Renderer::new(device, queue, knobs.settings(w, h))?;
    // A first frame warms pipelines and caches; then TIMED_FRAMES first frames (the history
    // reset before each), and per pass the median of their times.
    renderer.render(device, queue, scene, camera)?;
    let mut runs: Vec<Vec<crate::gpu::PassTiming>> = Vec::new();
    for _ in 0..TIMED_FRAMES {
        renderer.reset_history();
        renderer.render(device, queue, scene, camera)?;
        runs.push(renderer.timings(device)?);
    }
    let timings: Vec<(String, f64)> = runs[0]
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let mut ms: Vec<f64> = runs.iter().filter_map(|r| r.get(i).map(|t| t.ms)).collect();
            ms.sort_by(f64::total_cmp);
            (t.name.clone(), ms[ms.len() / 2])
        })
        .collect();
    let layer0 = renderer.read_gbuffer(device, queue, 0)?;
    let mask: Vec<bool> = layer0.samples.iter().map(|s| s.depth > 0.0).collect();
    let n = (w * h) as usize;
    let missing = |what: &str| Error::InvalidSetting {
        name: "sweep",
        message: format!("the scene's plan runs no {what}: nothing to measure"),
    };
    let av = renderer.read_f32(
        device,
        queue,
        renderer.ao_buffer().ok_or_else(|| missing("obscurance"))?,
    )?;
    let av: Vec<Vec3> = av.iter().take(n).map(|v| Vec3::splat(*v)).collect();
    let radiosity = renderer.radiosity_buffers().ok_or_else(|| missing("radiosity"))?;
    let e = renderer.read_f32(device, queue, radiosity[4])?;
    let e = crate::truth::metrics::weighted_irradiance(&e, n);
    let passes = timings;
    Ok(Row {
        knobs: knobs.clone(),
        total_ms: passes.iter().map(|(_, ms)| ms).sum(),
        passes,
        ao: metrics::compare(&av, &mask, &truth.ao),
        indirect: metrics::compare(&e, &mask, &truth.indirect),
    })
}

/// Timed frames per configuration (the median of their times is kept).
pub const TIMED_FRAMES: usize = 3;

/// The passes whose time an effect costs.
pub const AO_PASSES: [&str; 3] = ["pyramid", "ao", "ao.blur"];
/// The passes whose time the radiosity term costs.
pub const RADIOSITY_PASSES: [&str; 3] = ["radiosity", "radiosity.temporal", "radiosity.blur"];

/// Indices of `points` (ms, error) on the Pareto front (no other point is both faster and more
/// accurate), sorted by time.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        points[a].0.total_cmp(&points[b].0).then(points[a].1.total_cmp(&points[b].1))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// Writes `rows` as CSV: the knobs, every pass's ms (one column per pass name), the total, and
/// each effect's RMSE, MAE and the truth's noise floor.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        for (n, _) in &r.passes {
            if !names.contains(&n.as_str()) {
                names.push(n);
            }
        }
    }
    let mut out = String::from("ao_samples,radiosity_samples,layers,precision");
    for n in &names {
        out += &format!(",ms_{n}");
    }
    out += ",total_ms,ao_ms,radiosity_ms,ao_rmse,ao_mae,ao_truth_stderr,indirect_rmse,indirect_mae,indirect_truth_stderr\n";
    for r in rows {
        let k = &r.knobs;
        out += &format!("{},{},{},{:?}", k.ao_samples, k.radiosity_samples, k.layers, k.precision);
        for n in &names {
            let ms = r.passes.iter().find(|(p, _)| p == n).map_or(0.0, |(_, ms)| *ms);
            out += &format!(",{ms:.4}");
        }
        out += &format!(
            ",{:.4},{:.4},{:.4},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5}\n",
            r.total_ms,
            r.ms_of(&AO_PASSES),
            r.ms_of(&RADIOSITY_PASSES),
            r.ao.rmse,
            r.ao.mae,
            r.ao.truth_stderr,
            r.indirect.rmse,
            r.indirect.mae,
            r.indirect.truth_stderr
        );
    }
    std::fs::write(path, out).map_err(|e| Error::io(path, e))
}

/// Writes `rows` as a Markdown table (the CSV's main columns; Pareto-optimal rows per effect
/// marked), headed by what was measured where.
pub fn write_markdown(path: &Path, rows: &[Row], heading: &str) -> Result<()> {
    let ao_front = pareto_front(
        &rows.iter().map(|r| (r.ms_of(&AO_PASSES), f64::from(r.ao.rmse))).collect::<Vec<_>>(),
    );
    let rad_front = pareto_front(
        &rows
            .iter()
            .map(|r| (r.ms_of(&RADIOSITY_PASSES), f64::from(r.indirect.rmse)))
            .collect::<Vec<_>>(),
    );
    let mut f = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    let mut out = format!("{heading}\n\n");
    out += "| AO taps | radiosity taps | layers | precision | AO ms | AO RMSE | radiosity ms | indirect RMSE | frame ms |\n";
    out += "|---:|---:|---:|---|---:|---:|---:|---:|---:|\n";
    for (i, r) in rows.iter().enumerate() {
        let k = &r.knobs;
        let mark = |front: &[usize]| if front.contains(&i) { " *" } else { "" };
        out += &format!(
            "| {} | {} | {} | {:?} | {:.2} | {:.4}{} | {:.2} | {:.4}{} | {:.2} |\n",
            k.ao_samples,
            k.radiosity_samples,
            k.layers,
            k.precision,
            r.ms_of(&AO_PASSES),
            r.ao.rmse,
            mark(&ao_front),
            r.ms_of(&RADIOSITY_PASSES),
            r.indirect.rmse,
            mark(&rad_front),
            r.total_ms
        );
    }
    out += "\n`*`: on the Pareto front of that effect (no configuration is both faster and more accurate).\n";
    f.write_all(out.as_bytes()).map_err(|e| Error::io(path, e))
}

/// The font of the plots (DejaVu Sans, assets/fonts/, under its own free licence).
static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Draws `pareto.png`: for each effect, every configuration's relative error (RMSE over the
/// truth's mean) against the GPU milliseconds of that effect's passes, and its Pareto front as a
/// line.
pub fn plot_pareto(path: &Path, rows: &[Row], title: &str) -> Result<()> {
    use plotters::prelude::*;
    let fail =
        |e: &dyn std::fmt::Display| Error::ImageWrite { path: path.into(), message: e.to_string() };
    // Registering twice is harmless; the first registration stays.
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    type Series = (&'static str, RGBColor, Vec<(f64, f64)>);
    let series: [Series; 2] = [
        (
            "ambient obscurance",
            RGBColor(31, 119, 180),
            rows.iter()
                .map(|r| (r.ms_of(&AO_PASSES), f64::from(r.ao.rmse / r.ao.truth_mean.max(1e-9))))
                .collect(),
        ),
        (
            "radiosity (one bounce)",
            RGBColor(214, 39, 40),
            rows.iter()
                .map(|r| {
                    (
                        r.ms_of(&RADIOSITY_PASSES),
                        f64::from(r.indirect.rmse / r.indirect.truth_mean.max(1e-9)),
                    )
                })
                .collect(),
        ),
    ];
    let all = series.iter().flat_map(|s| s.2.iter());
    let (x_max, y_min, y_max) = all
        .fold((0.0f64, f64::MAX, 0.0f64), |(x, lo, hi), p| (x.max(p.0), lo.min(p.1), hi.max(p.1)));
    // A log axis: the effects' relative errors differ by orders of magnitude.
    let y_min = (y_min * 0.8).max(1e-6);
    let y_max = (y_max * 1.25).max(y_min * 10.0);
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(64)
        .build_cartesian_2d(0.0..x_max * 1.08 + 1e-3, (y_min..y_max).log_scale())
        .map_err(|e| fail(&e))?;
    chart
        .configure_mesh()
        .x_desc("GPU time of the effect's passes (ms)")
        .y_desc("RMSE / mean of the truth (log)")
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(|e| fail(&e))?;
    for (name, colour, points) in &series {
        let colour = *colour;
        chart
            .draw_series(points.iter().map(|p| Circle::new(*p, 4, colour.mix(0.5).filled())))
            .map_err(|e| fail(&e))?;
        let front: Vec<(f64, f64)> = pareto_front(points).into_iter().map(|i| points[i]).collect();
        chart
            .draw_series(front.iter().map(|p| Circle::new(*p, 6, colour.stroke_width(2))))
            .map_err(|e| fail(&e))?;
        chart
            .draw_series(LineSeries::new(front, colour.stroke_width(2)))
            .map_err(|e| fail(&e))?
            .label(format!("{name} (ringed and joined: Pareto front)"))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()
        .map_err(|e| fail(&e))?;
    root.present().map_err(|e| fail(&e))
}
