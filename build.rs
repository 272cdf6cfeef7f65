//! Validates every WGSL kernel with naga, in every combination of the defines it tests, with the
//! capabilities the device is asked for (64-bit integers and their atomics only where `INT64`
//! is defined), so a shader error fails `cargo build` with its location. Also embeds the sources
//! and reflects each kernel's bindings:
//!
//! - `bindings::<kernel>::<NAME>`: one constant per `@group(0) @binding(n) var name`, so Rust
//!   binds a buffer by the shader's name and a renamed or removed binding fails the build;
//! - `ENTRY_LAYOUTS`: per compute entry point and combination of defines, the bindings that entry
//!   uses and their types, from which the pipelines' bind group layouts are made.

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
    // Per kernel: binding name -> number (the same under every define).
    let mut slots: BTreeMap<String, BTreeMap<String, u32>> = BTreeMap::new();
    let mut layouts = String::new();
    for (name, text) in texts.iter().filter(|(k, _)| !k.starts_with("shared/")) {
        let kernel = name.trim_end_matches(".wgsl").to_string();
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
            let (module, info) = match compile(&source, caps, &label) {
                Ok(compiled) => compiled,
                Err(e) => {
                    let _ = writeln!(failures, "{label}:\n{e}");
                    continue;
                }
            };
            let kernel_slots = slots.entry(kernel.clone()).or_default();
            for (_, var) in module.global_variables.iter() {
                let (Some(b), Some(var_name)) = (&var.binding, &var.name) else { continue };
                if b.group != 0 {
                    let _ = writeln!(failures, "{label}: `{var_name}` is not in group 0");
                }
                match kernel_slots.insert(var_name.clone(), b.binding) {
                    Some(old) if old != b.binding => {
                        let _ = writeln!(
                            failures,
                            "{label}: `{var_name}` is binding {} here and {old} elsewhere",
                            b.binding
                        );
                    }
                    _ => {}
                }
            }
            for (i, entry) in module.entry_points.iter().enumerate() {
                if entry.stage != naga::ShaderStage::Compute {
                    continue;
                }
                let uses = info.get_entry_point(i);
                let mut entries = String::new();
                for (handle, var) in module.global_variables.iter() {
                    let Some(b) = &var.binding else { continue };
                    if uses[handle].is_empty() {
                        continue;
                    }
                    match binding_type(&module, var) {
                        Ok(ty) => {
                            let _ = write!(entries, "({}, {ty}), ", b.binding);
                        }
                        Err(e) => {
                            let _ = writeln!(failures, "{label}: {e}");
                        }
                    }
                }
                let _ =
                    writeln!(layouts, "    ({kernel:?}, {:?}, {mask}, &[{entries}]),", entry.name);
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

    let mut bindings = String::from(
        "/// A compute entry point's kernel, name, mask of its declared defines, and the bindings it\n\
         /// uses with their types.\n\
         pub type EntryLayout = (&'static str, &'static str, u32, &'static [(u32, wgpu::BindingType)]);\n\n\
         /// Per compute entry point (kernel, entry, mask of its declared defines): the bindings it\n\
         /// uses and their types.\n\
         pub const ENTRY_LAYOUTS: &[EntryLayout] = &[\n",
    );
    bindings.push_str(&layouts);
    bindings
        .push_str("];\n\n/// Every kernel's bindings by the shader's names.\npub mod slots {\n");
    for (kernel, names) in &slots {
        let _ = writeln!(
            bindings,
            "    /// The bindings of `wgsl/{kernel}.wgsl`.\n    pub mod {kernel} {{"
        );
        let _ = writeln!(bindings, "        use crate::gpu::Slot;");
        for (var, binding) in names {
            let _ = writeln!(
                bindings,
                "        /// `{var}` (`@binding({binding})`).\n        pub const {}: Slot = Slot {{ kernel: {kernel:?}, name: {var:?}, binding: {binding} }};",
                var.to_uppercase()
            );
        }
        bindings.push_str("    }\n");
    }
    bindings.push_str("}\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("bindings.rs");
    std::fs::write(out, bindings).expect("OUT_DIR is writable");
}

/// Parses and validates `source` with `caps`; an error is the message naming `label`.
fn compile(
    source: &str,
    caps: naga::valid::Capabilities,
    label: &str,
) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| e.emit_to_string_with_path(source, label))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
        .validate(&module)
        .map_err(|e| e.emit_to_string_with_path(source, label))?;
    Ok((module, info))
}

/// The `wgpu::BindingType` (as Rust source) of a bound global.
fn binding_type(module: &naga::Module, var: &naga::GlobalVariable) -> Result<String, String> {
    let buffer = |ty: &str| {
        format!(
            "wgpu::BindingType::Buffer {{ ty: {ty}, has_dynamic_offset: false, min_binding_size: None }}"
        )
    };
    match var.space {
        naga::AddressSpace::Uniform => Ok(buffer("wgpu::BufferBindingType::Uniform")),
        naga::AddressSpace::Storage { access } => Ok(buffer(&format!(
            "wgpu::BufferBindingType::Storage {{ read_only: {} }}",
            !access.contains(naga::StorageAccess::STORE)
        ))),
        naga::AddressSpace::Handle => match &module.types[var.ty].inner {
            naga::TypeInner::Image {
                dim: naga::ImageDimension::D2,
                arrayed: false,
                class: naga::ImageClass::Storage { format, access },
            } => {
                let format = match format {
                    naga::StorageFormat::Rgba16Float => "Rgba16Float",
                    naga::StorageFormat::Rgba32Float => "Rgba32Float",
                    other => return Err(format!("storage format {other:?} has no mapping here")),
                };
                let access = if access.contains(naga::StorageAccess::LOAD) {
                    "ReadWrite"
                } else {
                    "WriteOnly"
                };
                Ok(format!(
                    "wgpu::BindingType::StorageTexture {{ access: wgpu::StorageTextureAccess::{access}, format: wgpu::TextureFormat::{format}, view_dimension: wgpu::TextureViewDimension::D2 }}"
                ))
            }
            other => Err(format!("binding of type {other:?} has no mapping here")),
        },
        other => Err(format!("a binding in address space {other:?}")),
    }
}
