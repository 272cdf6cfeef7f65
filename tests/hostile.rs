//! The crafted inputs of `fixtures/hostile/` through the command line, each under a memory and
//! a time limit: the outcome its README's table gives, one error line, never a panic.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::fixture;

/// Address space a run may use (`ulimit -v`, KiB): 4 GiB.
const MEMORY_KIB: u64 = 4 << 20;
/// Wall-clock time a run may take.
const TIME_LIMIT: Duration = Duration::from_secs(60);

/// Runs `render FILE` (one frame) in `dir` under the limits; returns the exit code and stderr.
fn render_limited(dir: &Path, file: &str, out: &Path) -> (Option<i32>, String) {
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {MEMORY_KIB}; exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_deep-gbuffer"))
        .args(["render", file, "--size", "16x12", "--frames", "1", "--out"])
        .arg(out)
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > TIME_LIMIT {
            child.kill().unwrap();
            panic!("{file}: still running after {TIME_LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    (status.code(), stderr)
}

fn check(dir: &Path, file: &str, exit: i32, needle: &str, out: &Path) {
    let (code, stderr) = render_limited(dir, file, out);
    assert!(!stderr.contains("panicked"), "{file}: {stderr}");
    assert_eq!(code, Some(exit), "{file}: {stderr}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("error: ") && !l.contains("XDG_RUNTIME_DIR"))
        .collect();
    if exit == 0 {
        assert!(errors.is_empty(), "{file}: {stderr}");
    } else {
        assert_eq!(errors.len(), 1, "{file}: {stderr}");
        assert!(errors[0].contains(needle), "{file}: expected `{needle}`: {stderr}");
    }
}

fn out_dir(name: &str) -> std::path::PathBuf {
    let dir =
        std::env::temp_dir().join(format!("deep-gbuffer-hostile-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn every_crafted_input_gets_its_outcome_within_the_limits() {
    let dir = fixture("hostile");
    let table = std::fs::read_to_string(dir.join("README.md")).unwrap();
    let rows: Vec<Vec<&str>> = table
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| file"))
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect();
    let out = out_dir("table");
    let mut listed = Vec::new();
    for row in &rows {
        let [file, exit, needle] = row[..] else { panic!("row {row:?}") };
        check(&dir, file, exit.parse().unwrap(), needle, &out.join("image.png"));
        listed.push(file.to_string());
    }
    // Every scene file of the folder is in the table.
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".gltf") || name.ends_with(".obj") {
            assert!(listed.contains(&name), "{name} is not in the table");
        }
    }
}

/// Buffer URIs that are links out of the folder or to a device, and a FIFO that would block a
/// read forever.
#[test]
fn links_and_pipes_are_refused_within_the_limits() {
    let dir = out_dir("links");
    let base = std::fs::read_to_string(fixture("hostile/indices-float.gltf")).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&base).unwrap();
    doc["accessors"][1]["componentType"] = 5123.into();
    let outside = out_dir("links-outside");
    std::fs::write(outside.join("secret.bin"), [0u8; 42]).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.bin")).unwrap();
    std::os::unix::fs::symlink(outside.join("secret.bin"), dir.join("secret.bin")).unwrap();
    let fifo = dir.join("pipe.bin");
    let mut cases = vec![("zero.bin", "leads outside"), ("secret.bin", "leads outside")];
    if Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
        cases.push(("pipe.bin", "not a regular file"));
    }
    for (uri, needle) in cases {
        doc["buffers"][0]["uri"] = uri.into();
        let file = format!("{uri}.gltf");
        std::fs::write(dir.join(&file), doc.to_string()).unwrap();
        check(&dir, &file, 1, needle, &dir.join("image.png"));
    }
}
