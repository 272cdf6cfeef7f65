//! Validates every WGSL kernel with naga, in every combination of the defines it tests, with the
//! capabilities the device is asked for (64-bit integers and their atomics only where `INT64`
//! is defined), so a shader error fails `cargo build` with its location. Also embeds the sources.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[path = "src/gpu/preprocess.rs"]
mod preprocess;

fn collect(dir: &Path, root: &Path, out: &mut BTreeMap<String, PathBuf>) {
    let mut entries: Vec<_> =
        std::fs::read_dir(dir).expect("wgsl/ is readable").flatten().collect();
    entries.sort_by_key(|e| e.path());
    for e in entries {
        let p = e.path();
        if p.is_dir() {
            collect(&p, root, out);
        } else if p.extension().is_some_and(|x| x == "wgsl") {
            let rel = p.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/");
            out.insert(rel, p);
        }
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl");
    println!("cargo:rerun-if-changed=wgsl");
    println!("cargo:rerun-if-changed=src/gpu/preprocess.rs");
    let mut files = BTreeMap::new();
    collect(&root, &root, &mut files);
    let texts: BTreeMap<String, String> = files
        .iter()
        .map(|(k, p)| (k.clone(), std::fs::read_to_string(p).expect("readable")))
        .collect();
    let lookup = |name: &str| texts.get(name).map(String::as_str);

    let mut failures = String::new();
    for (name, text) in texts.iter().filter(|(k, _)| !k.starts_with("shared/")) {
        let names = preprocess::declared_defines(text);
        for mask in 0u32..(1 << names.len()) {
            let defines: Vec<&str> = names
                .iter()
                .enumerate()
                .filter(|(i, _)| mask & (1 << i) != 0)
                .map(|(_, n)| *n)
                .collect();
            let source = match preprocess::preprocess(name, text, &defines, &lookup) {
                Ok(s) => s,
                Err(e) => {
                    let _ = writeln!(failures, "{e}");
                    continue;
                }
            };
            let mut caps = naga::valid::Capabilities::empty();
            if defines.contains(&"INT64") {
                caps |= naga::valid::Capabilities::SHADER_INT64
                    | naga::valid::Capabilities::SHADER_INT64_ATOMIC_MIN_MAX;
            }
            let label = format!("wgsl/{name} with [{}]", defines.join(", "));
            let module = match naga::front::wgsl::parse_str(&source) {
                Ok(m) => m,
                Err(e) => {
                    let _ = writeln!(
                        failures,
                        "{label}:\n{}",
                        e.emit_to_string_with_path(&source, &label)
                    );
                    continue;
                }
            };
            if let Err(e) = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
                .validate(&module)
            {
                let _ =
                    writeln!(failures, "{label}:\n{}", e.emit_to_string_with_path(&source, &label));
            }
        }
    }
    if !failures.is_empty() {
        panic!("WGSL validation failed:\n{failures}");
    }

    let mut generated = String::from(
        "/// Every file under `wgsl/`, by path relative to it.\npub const SOURCES: &[(&str, &str)] = &[\n",
    );
    for (name, path) in &files {
        let _ = writeln!(generated, "    ({name:?}, include_str!({:?})),", path.to_string_lossy());
    }
    generated.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("shaders.rs");
    std::fs::write(out, generated).expect("OUT_DIR is writable");
}
