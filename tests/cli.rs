//! The command line as a user runs it.

use std::process::Command;

fn cli() -> Command {
    Command::new(env!("CARGO_BIN_EXE_deep-gbuffer"))
}

fn fixture_path(path: &str) -> String {
    format!("{}/fixtures/{path}", env!("CARGO_MANIFEST_DIR"))
}

fn out_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("deep-gbuffer-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn render_writes_image_layers_and_timings() {
    let dir = out_dir("render");
    let status = cli()
        .args(["render", "builtin:cornell", "--size", "64x48", "--raster-work", "gpu", "--out"])
        .arg(dir.join("cornell.png"))
        .arg("--exr")
        .arg(dir.join("cornell.exr"))
        .arg("--layers")
        .arg(dir.join("layers"))
        .arg("--timings")
        .arg(dir.join("timings.json"))
        .status()
        .unwrap();
    assert!(status.success());
    let png = image::open(dir.join("cornell.png")).unwrap();
    assert_eq!((png.width(), png.height()), (64, 48));
    for layer in 0..2 {
        for what in ["depth", "normal", "basecolor"] {
            for ext in ["png", "exr"] {
                let p = dir.join("layers").join(format!("layer{layer}_{what}.{ext}"));
                assert!(p.metadata().is_ok_and(|m| m.len() > 0), "{}", p.display());
            }
        }
    }
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("timings.json")).unwrap()).unwrap();
    assert_eq!(json["width"], 64);
    assert_eq!(json["height"], 48);
    assert!(json["adapter"].as_str().is_some_and(|a| !a.is_empty()));
    // The raster's work was shared out as asked (by the device's type without the option).
    assert_eq!(json["raster_work"], "gpu");
    // The load the frame was timed under, where the system reports it (Linux does).
    if cfg!(target_os = "linux") {
        let load = json["load"].as_array().expect("a load average on Linux");
        assert!(load.len() == 3 && load.iter().all(|v| v.as_f64().is_some_and(|v| v >= 0.0)));
    }
    let names: Vec<&str> =
        json["passes"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    // The render settles the radiosity over several frames of a static scene and times the
    // last, a still frame: it gathers the radiosity's next bounce and composites, and keeps the
    // rest, the light's shadow map drawn by the first frame and the G-buffer, obscurance and
    // direct light of the frame before.
    assert_eq!(
        names,
        [
            "radiosity",
            "radiosity.offscreen",
            "radiosity.layer1",
            "radiosity.temporal",
            "radiosity.blur",
            "composite"
        ]
    );
    assert_eq!(
        json["reused"],
        serde_json::json!([
            "shadow.ceiling",
            "raster.clear",
            "raster.layer0",
            "raster.layer1",
            "resolve",
            "pyramid",
            "ao",
            "ao.blur",
            "direct"
        ])
    );
    let total: f64 =
        json["passes"].as_array().unwrap().iter().map(|p| p["ms"].as_f64().unwrap()).sum();
    assert!(total > 0.0);
    assert!((json["total_ms"].as_f64().unwrap() - total).abs() < 1e-9);
}

#[test]
fn render_with_camera_and_options() {
    let dir = out_dir("camera");
    let out = cli()
        .args([
            "render",
            "builtin:grid-2000",
            "--size",
            "40x30",
            "--camera",
            "eye=0,4,9,target=0,1,0,fov=50",
        ])
        .args([
            "--layer1",
            "reproject",
            "--precision",
            "packed",
            "--atomics",
            "int32",
            "--dz",
            "0.1",
            "--ao-estimator",
            "horizon",
            "--ao-slices",
            "3",
            "--radiosity-estimator",
            "spiral",
            "--out",
        ])
        .arg(dir.join("grid.png"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(dir.join("grid.png").exists());
}

/// Every wrong input: exit code 1, one line starting `error:` that names the cause, no panic.
#[test]
fn bad_input_gives_one_line_and_a_failure_code() {
    let dir = out_dir("bad");
    let bad_obj = dir.join("bad.obj");
    std::fs::write(&bad_obj, "v 0 0 0\nv 1 0\nf 1 2 3\n").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["render".into(), "missing.gltf".into()], "missing.gltf"),
        (vec!["render".into(), bad_obj.display().to_string()], "line 2"),
        (vec!["render".into(), "builtin:nothing".into()], "unknown built-in scene"),
        (vec!["render".into(), "--size".into(), "0x10".into()], "size"),
        (vec!["render".into(), "--size".into(), "0x0".into()], "no pixels"),
        (vec!["render".into(), "--camera".into(), "=".into()], "without its key"),
        (vec!["render".into(), "--camera".into(), "fov=40,".into()], "empty value"),
        (vec!["render".into(), "--camera".into(), "eye=1,2".into()], "camera"),
        (vec!["render".into(), "--camera".into(), "eye=0,1,0,target=0,1,0".into()], "coincide"),
        (vec!["render".into(), "--dz=-1".into()], "dz"),
        (vec!["truth".into(), "--dz".into(), "-1".into()], "dz"),
        (vec!["render".into(), "--size".into(), "20000x10".into()], "size"),
        (vec!["render".into(), "--camera".into(), "near=-1".into()], "near"),
        (vec!["render".into(), "--camera".into(), "near=2,far=1".into()], "far"),
        (vec!["render".into(), "--camera".into(), "up=0,0,0".into()], "up is zero"),
        (vec!["render".into(), "--boost".into(), "4,4".into()], "gain"),
        (vec!["render".into(), "--max-triangles".into(), "10".into()], "limit"),
        (vec!["render".into(), "--ao-slices".into(), "0".into()], "ao.slices"),
        (vec!["render".into(), "--ao-thickness=-1".into()], "ao.thickness"),
        (vec!["truth".into(), "--ao-blur-radius".into(), "33".into()], "ao.blur_radius"),
        (
            vec![
                "sweep".into(),
                "--out".into(),
                "x".into(),
                "--ao-blur-radius".into(),
                "2,40".into(),
            ],
            "ao.blur_radius",
        ),
        (vec!["render".into(), "--radiosity-slices".into(), "17".into()], "radiosity.slices"),
        (vec!["truth".into(), "--radiosity-thickness=0".into()], "radiosity.thickness"),
        (
            vec!["render".into(), "--radiosity-extrapolation".into(), "2.5".into()],
            "radiosity.extrapolation",
        ),
        (vec!["render".into(), "--radiosity-alpha".into(), "1".into()], "radiosity.alpha"),
        (vec!["truth".into(), "--radiosity-still-alpha=-0.5".into()], "radiosity.still_alpha"),
        (vec!["render".into(), "--reflection-lobe-samples".into(), "0".into()], "lobe_samples"),
        (vec!["truth".into(), "--reflection-thickness=-1".into()], "reflections.thickness"),
        (vec!["truth".into(), "--turn".into(), "NaN".into()], "turn"),
        (vec!["render".into(), "--transparency-layers".into(), "0".into()], "transparency.layers"),
        (vec!["render".into(), "--position-encoding".into(), "u8".into()], "screen-u16"),
        // Wrong arguments, as the parser finds them: one line, exit 1, like the rest.
        (vec!["render".into(), "--nope".into()], "unexpected argument '--nope'"),
        (vec!["render".into(), "--size".into(), "abc".into()], "`abc` is not WxH"),
        (vec!["render".into(), "--ao-estimator".into(), "foo".into()], "sao, horizon, bitmask"),
        (vec!["render".into(), "--plan".into(), "--out".into(), "x.png".into()], "--plan"),
        (vec!["render".into(), "--orbit".into(), "5".into()], "--frames"),
        (vec!["frobnicate".into()], "unrecognized subcommand"),
        // Outputs are checked before the scene is even loaded.
        (vec!["render".into(), "--out".into(), "/nonexistent/x.png".into()], "/nonexistent"),
        (vec!["render".into(), "--exr".into(), "/".into()], "not a regular file"),
        (vec!["truth".into(), "--out".into(), "/nonexistent/t.png".into()], "/nonexistent"),
    ];
    for (args, needle) in cases {
        let out = cli().args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let ours: Vec<&str> = stderr
            .lines()
            .filter(|l| l.starts_with("error: ") && !l.contains("XDG_RUNTIME_DIR"))
            .collect();
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(ours.len(), 1, "{args:?}: {stderr}");
        assert!(ours[0].contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

/// `--plan` prints the plan and renders nothing; a multi-frame render reports its progress on
/// stderr (plain lines when piped); with no `XDG_RUNTIME_DIR` Mesa says nothing about it.
#[test]
fn plan_alone_progress_and_a_quiet_runtime_dir() {
    let out = cli()
        .args(["render", "builtin:grid-2000", "--size", "32x24", "--plan"])
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("reflections: runs") && stdout.contains("passes:"), "{stdout}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.lines().all(|l| l.starts_with("note: ")), "only notes: {stderr}");

    // A model 743 units across: the default lengths follow its size, and the command says so.
    let engine = fixture_path("engine/2CylinderEngine.gltf");
    let out = cli().args(["render", &engine, "--size", "32x24", "--plan"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("note: default lengths x512") && stderr.contains("radius 256"),
        "{stderr}"
    );

    let dir = out_dir("progress");
    let out = cli()
        .args(["render", "builtin:cornell", "--size", "16x12", "--frames", "20", "--out"])
        .arg(dir.join("last.png"))
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 10, "a line at each tenth: {stderr}");
    assert_eq!(lines[9], "frames: 20/20", "{stderr}");
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    assert!(dir.join("last.png").exists());
}

/// Without `--frames`, a still camera renders until the radiosity settles, and says after how
/// many frames, then averages `--average` frames more (32 unless told); `--frames 1` renders
/// one; a scene without radiosity renders one.
#[test]
fn render_settles_the_radiosity_unless_told_a_frame_count() {
    let dir = out_dir("settle");
    let run = |args: &[&str]| {
        let out = cli()
            .args(["render", "--size", "24x18", "--out"])
            .arg(dir.join("settle.png"))
            .args(args)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let settled = run(&["builtin:cornell"]);
    let note = settled.lines().find(|l| l.starts_with("note: the radiosity settled after "));
    let frames: u32 = note
        .and_then(|l| l.split_whitespace().nth(5))
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{settled}"));
    assert!((8..=128).contains(&frames) && frames.is_multiple_of(4), "{settled}");
    // Then 32 frames more, each averaged in; `--average` sets how many.
    assert!(settled.contains("note: averaged 32 more frames of the settled view"), "{settled}");
    // The filter's weights are settings like the rest (tests/radiosity.rs measures them).
    let weighted =
        run(&["builtin:cornell", "--radiosity-alpha", "0.9", "--radiosity-still-alpha", "0.85"]);
    assert!(weighted.contains("note: the radiosity settled after "), "{weighted}");
    let two = run(&["builtin:cornell", "--average", "2"]);
    assert!(two.contains("note: averaged 2 more frames"), "{two}");
    // --out-seq writes the averaged frames too, numbered on from the settled ones.
    let seq = dir.join("seq");
    let out = cli()
        .args(["render", "builtin:cornell", "--size", "24x18", "--average", "2", "--out-seq"])
        .arg(&seq)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let written = std::fs::read_dir(&seq).unwrap().count() as u32;
    assert_eq!(written, frames + 2, "{}", String::from_utf8_lossy(&out.stderr));
    assert!(seq.join(format!("frame_{:04}.png", frames + 1)).exists());
    assert!(!run(&["builtin:cornell", "--average", "0"]).contains("averaged"));
    let both = cli()
        .args(["render", "builtin:cornell", "--size", "24x18", "--frames", "3", "--average", "2"])
        .output()
        .unwrap();
    assert!(!both.status.success(), "--average applies after the radiosity settles only");
    assert!(!run(&["builtin:cornell", "--frames", "1"]).contains("radiosity"));
    // Without radiosity a still camera renders the obscurance's still frames, whose mean it
    // shows, and one frame where a still view keeps its first frame's obscurance.
    let plain = run(&["builtin:cornell", "--effects", "ao,direct,shadows"]);
    assert!(!plain.contains("radiosity"), "{plain}");
    assert!(plain.contains("note: the obscurance averages 16 still frames"), "{plain}");
    assert!(plain.contains("frames: 17/17"), "{plain}");
    let single =
        run(&["builtin:cornell", "--effects", "ao,direct,shadows", "--ao-still-frames", "0"]);
    assert!(!single.contains("frames:") && !single.contains("averages"), "{single}");
}

#[test]
fn info_names_adapter_and_raster_path() {
    let out = cli().arg("info").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("adapter:")
            && text.contains("raster:")
            && text.contains("SHADER_INT64_ATOMIC_MIN_MAX"),
        "{text}"
    );
}

#[test]
fn truth_writes_its_image_and_noise_and_compares_with_the_gpu() {
    let dir = out_dir("truth");
    let output = cli()
        .args(["truth", "builtin:cornell", "--size", "24x18", "--spp", "8", "--compare", "--exr"])
        .arg(dir.join("ao.exr"))
        .arg("--estimate-exr")
        .arg(dir.join("gpu.exr"))
        .arg("--error-png")
        .arg(dir.join("error.png"))
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("mean standard error"), "{stdout}");
    assert!(stdout.contains("error map: ") && stdout.contains("0.2500"), "{stdout}");
    assert!(stdout.contains("rmse") && stdout.contains(" ms on "), "{stdout}");
    // The truth, its noise and the GPU's estimate (--estimate-exr), each an AV per pixel.
    let read = |file: &str| {
        let image = exr::prelude::read_first_rgba_layer_from_file(
            dir.join(file),
            |r, _| vec![0.0f32; r.area()],
            |v, p, (r, _g, _b, _a): (f32, f32, f32, f32)| v[p.y() * 24 + p.x()] = r,
        )
        .unwrap();
        let values = image.layer_data.channel_data.pixels;
        assert_eq!(values.len(), 24 * 18);
        assert!(values.iter().all(|v| (0.0..=1.0).contains(v)), "{file}");
        values
    };
    let (truth, _, estimate) = (read("ao.exr"), read("ao-stderr.exr"), read("gpu.exr"));
    // The GPU's own values, not the truth's, and obscured in places.
    assert_ne!(truth, estimate);
    assert!(estimate.iter().any(|v| *v > 0.0 && *v < 0.9), "{estimate:?}");
    // The error map (--error-png) shades each compared pixel by estimate - truth over 0.25:
    // white where they agree, red where the estimate is higher, blue where it is lower.
    let map = image::open(dir.join("error.png")).unwrap().to_rgb8();
    assert_eq!(map.dimensions(), (24, 18));
    let mut shaded = [0usize; 2];
    for (i, (t, e)) in truth.iter().zip(&estimate).enumerate() {
        if !(*t > 0.0 && *e > 0.0) {
            continue;
        }
        let k = ((e - t) / 0.25).clamp(-1.0, 1.0);
        let want = if k >= 0.0 { [1.0, 1.0 - k, 1.0 - k] } else { [1.0 + k, 1.0 + k, 1.0] };
        let got = map.get_pixel(i as u32 % 24, i as u32 / 24).0;
        for c in 0..3 {
            assert!((f32::from(got[c]) / 255.0 - want[c]).abs() <= 1.0 / 255.0, "{i}: {got:?}");
        }
        shaded[usize::from(k < 0.0)] += usize::from(k.abs() > 0.05);
    }
    assert!(shaded[0] + shaded[1] > 0, "no pixel differs: {shaded:?}");
    // A preset reaches the estimate (`high`: 64 taps on 4 slices), and an explicit option
    // overrides the preset's (its 64 taps back to the default's 32 on 2 slices, radius 4).
    // The GPU's estimate of one compare run, written to `file`.
    let estimate_of = |args: &[&str], file: &str| {
        let output = cli()
            .args(["truth", "builtin:cornell", "--size", "24x18", "--spp", "1", "--compare"])
            .args(args)
            .arg("--estimate-exr")
            .arg(dir.join(file))
            .output()
            .unwrap();
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    };
    let with = |args: &[&str], file: &str| {
        estimate_of(args, file);
        read(file)
    };
    assert_ne!(with(&["--preset", "high"], "high.exr"), estimate);
    let overridden = ["--preset", "high", "--ao-samples", "32", "--ao-slices", "2"];
    assert_eq!(with(&[&overridden[..], &["--ao-blur-radius", "4"]].concat(), "back.exr"), estimate);
    // --average: frames more, the radiosity's filter keeping their mean, which differs from as
    // many frames forgetting once the mean weighs the history above alpha (the 7th on).
    let indirect = |frames: &[&str], file: &str| {
        estimate_of(&[&["--effect", "indirect", "--frames"], frames].concat(), file);
        std::fs::read(dir.join(file)).unwrap()
    };
    let forgetting = indirect(&["13"], "forgetting.exr");
    assert_eq!(indirect(&["13"], "again.exr"), forgetting, "the same frames, the same bytes");
    assert_ne!(indirect(&["3", "--average", "10"], "averaged.exr"), forgetting);
    // --estimate-exr needs --compare.
    let output = cli()
        .args(["truth", "builtin:cornell", "--size", "24x18", "--spp", "1", "--estimate-exr"])
        .arg(dir.join("alone.exr"))
        .output()
        .unwrap();
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("--compare"));
    // A scale that is not a positive number is refused before anything is traced.
    for bad in ["0", "-1", "nan", "inf"] {
        let output = cli()
            .args(["truth", "builtin:cornell", "--size", "24x18", "--spp", "1", "--compare"])
            .arg("--error-png")
            .arg(dir.join("bad.png"))
            .args(["--error-scale", bad])
            .output()
            .unwrap();
        assert!(!output.status.success(), "--error-scale {bad} accepted");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains("error_scale") && !stderr.contains("panicked"), "{stderr}");
    }
    // The full image and the reflections (the sphere field has mirrors), with the GPU's error
    // and, for the image, its SSIM.
    for (effect, scene, expect) in
        [("full", "builtin:cornell", "SSIM"), ("reflections", "builtin:grid-20000", "rmse")]
    {
        let output = cli()
            .args(["truth", scene, "--effect", effect, "--size", "24x18", "--spp", "2"])
            .args(["--bounces", "2", "--compare"])
            .output()
            .unwrap();
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(stdout.contains(expect) && stdout.contains(" ms on "), "{effect}: {stdout}");
    }
    // Reflections kept on screen (no rays followed through the shadow maps).
    let output = cli()
        .args(["truth", "builtin:grid-20000", "--effect", "reflections", "--size", "24x18"])
        .args(["--spp", "2", "--reflection-screen-only", "--compare"])
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(String::from_utf8_lossy(&output.stdout).contains("rmse"));
    // Over an open shutter: the truth of a turning camera, compared with the blurred frame.
    let output = cli()
        .args(["truth", "builtin:cornell", "--effect", "full", "--size", "24x18", "--spp", "2"])
        .args(["--turn", "-4", "--shutter", "1", "--frames", "2", "--compare"])
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(String::from_utf8_lossy(&output.stdout).contains("SSIM"));
    let bad = cli().args(["truth", "--spp", "0"]).output().unwrap();
    assert_eq!(bad.status.code(), Some(1));
    assert_eq!(String::from_utf8_lossy(&bad.stderr).trim().lines().count(), 1);
}

/// Runs `sweep` of the Cornell box at 24x18 with 4 rays per pixel and `args` into `dir`; returns
/// its CSV header and rows, and its Markdown table.
fn sweep_cornell(dir: &std::path::Path, args: &[&str]) -> (Vec<String>, Vec<Vec<String>>, String) {
    let output = cli()
        .args(["sweep", "builtin:cornell", "--size", "24x18", "--spp", "4"])
        .args(args)
        .arg("--out")
        .arg(dir)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    let md = std::fs::read_to_string(dir.join("sweep.md")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap().split(',').map(str::to_string).collect();
    let rows = lines.map(|l| l.split(',').map(str::to_string).collect()).collect();
    (header, rows, md)
}

/// `sweep` on a tiny grid writes a well-formed CSV (one row per configuration, every value a
/// number, every effect's error, instability and the image's SSIM), the Markdown table and the
/// plot; re-running it gives the same errors.
#[test]
fn sweep_writes_csv_markdown_and_plot_and_repeats_its_errors() {
    let run = |name: &str| {
        let dir = out_dir(name);
        let args = ["--ao-estimator", "bitmask", "--ao-samples", "4,8", "--radiosity-samples", "5"];
        let (header, rows, md) =
            sweep_cornell(&dir, &[&args[..], &["--layers", "1,2", "--precision", "full"]].concat());
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        let png = image::open(dir.join("pareto.png")).unwrap();
        assert_eq!((png.width(), png.height()), (900, 600));
        assert_eq!(md.lines().filter(|l| l.starts_with("| ") && !l.contains("taps")).count(), 4);
        assert_eq!(rows.len(), 4, "2 tap counts x 2 layer counts");
        for column in [
            "ao_estimator",
            "ao_slices",
            "ao_blur_radius",
            "ao_rmse",
            "indirect_instability",
            "image_rmse",
            "indirect_median_rel",
            "image_ssim",
            "ms_resolve",
        ] {
            assert!(header.contains(&column), "{column} in {header:?}");
        }
        for row in &rows {
            assert_eq!(row.len(), header.len());
            for (h, v) in header.iter().zip(row) {
                let named = ["precision", "position", "layer1", "ao_estimator"];
                let switches = ["radiosity_offscreen", "reflection_shadow_maps"];
                if !named.contains(h) && !switches.contains(h) {
                    let x: f64 = v.parse().unwrap_or_else(|_| panic!("{h} = {v}"));
                    // A relative error may be negative (and is at least -1); the rest are not.
                    let least = if h.ends_with("_median_rel") { -1.0 } else { 0.0 };
                    assert!(x.is_finite() && x >= least, "{h} = {v}");
                }
            }
        }
        let errors: Vec<String> = rows
            .iter()
            .map(|r| {
                header
                    .iter()
                    .zip(r)
                    .filter(|(h, _)| {
                        ["rmse", "mae", "ssim", "instability"].iter().any(|e| h.ends_with(e))
                    })
                    .map(|(_, v)| v.clone())
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .collect();
        errors
    };
    assert_eq!(run("sweep-a"), run("sweep-b"), "the same inputs give the same errors");
}

/// `sweep --shutter 0,1`: the open shutter's row runs the motion blur (its time is in the CSV)
/// and is compared with the truth traced over that shutter (another image, so another mean),
/// the closed one runs none; the Markdown table shows the shutter.
#[test]
fn sweep_measures_the_shutter_against_the_truth_over_it() {
    let dir = out_dir("sweep-shutter");
    let args = ["--ao-estimator", "bitmask", "--ao-samples", "4", "--radiosity-samples", "5"];
    let (header, rows, md) =
        sweep_cornell(&dir, &[&args[..], &["--layers", "2", "--shutter", "0,1"]].concat());
    assert!(md.contains("| shutter |"), "{md}");
    let column = |row: &[String], name: &str| -> f64 {
        let i = header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("{name}"));
        row[i].parse().unwrap()
    };
    assert_eq!(rows.len(), 2);
    assert_eq!((column(&rows[0], "shutter"), column(&rows[1], "shutter")), (0.0, 1.0));
    assert_eq!(column(&rows[0], "ms_motion_blur"), 0.0, "a closed shutter blurs nothing");
    assert!(column(&rows[1], "ms_motion_blur") > 0.0, "the open shutter's pass is timed");
    let means = rows.iter().map(|r| column(r, "image_truth_mean")).collect::<Vec<_>>();
    assert_ne!(means[0], means[1], "each shutter has its own truth");
}

/// `--move MATERIAL:DX,DY,DZ`: `render` moves the material over its frames and `truth` traces
/// the image over the shutter as it moves (and renders the GPU's to compare); a material the
/// scene lacks and an offset that is not three finite numbers are one-line errors.
#[test]
fn move_blurs_a_moving_material_and_refuses_bad_ones() {
    let dir = out_dir("move");
    let png = dir.join("moved.png");
    let output = cli()
        .args(["render", "builtin:cornell", "--size", "32x24", "--frames", "2", "--shutter", "1"])
        .args(["--move", "shortBox:0.3,0,0", "--out"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let still = dir.join("still.png");
    let output = cli()
        .args(["render", "builtin:cornell", "--size", "32x24", "--frames", "2", "--shutter", "1"])
        .args(["--out"])
        .arg(&still)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let (a, b) = (image::open(&png).unwrap().to_rgb8(), image::open(&still).unwrap().to_rgb8());
    assert_ne!(a.as_raw(), b.as_raw(), "the moved box shows");
    let output = cli()
        .args(["truth", "builtin:cornell", "--size", "24x18", "--spp", "4", "--effect", "full"])
        .args(["--move", "1:0.2,0,0", "--shutter", "1", "--compare", "--frames", "2"])
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(String::from_utf8_lossy(&output.stdout).contains("gpu image"));
    for (spec, expect) in [("nosuch:1,0,0", "names no material"), ("shortBox:1,0", "DX,DY,DZ")] {
        let output = cli()
            .args(["render", "builtin:cornell", "--size", "16x12", "--frames", "2"])
            .args(["--move", spec])
            .output()
            .unwrap();
        assert!(!output.status.success());
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains(expect), "{spec}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    }
}
