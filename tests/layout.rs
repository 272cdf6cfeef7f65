//! Every `#[repr(C)]` struct shared with WGSL ([`deep_gbuffer::frame::MIRRORED`]) has the size
//! and member offsets naga computes for the WGSL struct it mirrors, and the raster's counter
//! words sit where the shader's `DIAG_*` constants say.

use deep_gbuffer::frame::{MIRRORED, MirrorLayout, RasterCounters};
use deep_gbuffer::testing::shader_source;

fn module(file: &str) -> naga::Module {
    naga::front::wgsl::parse_str(&shader_source(file, &[])).unwrap()
}

/// Padding members (`_pad`, `_pad0`, `pad`) are not compared by name.
fn is_padding(name: &str) -> bool {
    name.starts_with('_') || name == "pad"
}

fn check(m: &MirrorLayout) -> Result<(), String> {
    let module = module(m.file);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let ty = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(m.wgsl))
        .ok_or_else(|| format!("wgsl/{} has no struct {}", m.file, m.wgsl))?
        .1;
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        return Err(format!("{} is not a struct", m.wgsl));
    };
    if *span as usize != m.size {
        return Err(format!("{}: {} bytes, WGSL {} has {span}", m.rust, m.size, m.wgsl));
    }
    for member in members {
        let name = member.name.as_deref().unwrap_or_default();
        if is_padding(name) {
            continue;
        }
        match m.fields.iter().find(|(n, _)| *n == name) {
            Some((_, offset)) if *offset == member.offset as usize => {}
            Some((_, offset)) => {
                return Err(format!(
                    "{}.{name} at {offset}, WGSL {}.{name} at {}",
                    m.rust, m.wgsl, member.offset
                ));
            }
            None => return Err(format!("{} has no field for WGSL {}.{name}", m.rust, m.wgsl)),
        }
    }
    for (name, _) in m.fields {
        if !members.iter().any(|x| x.name.as_deref() == Some(name)) {
            return Err(format!("WGSL {} has no member for {}.{name}", m.wgsl, m.rust));
        }
    }
    Ok(())
}

#[test]
fn every_mirrored_struct_matches_its_wgsl_twin() {
    let failures: Vec<String> = MIRRORED.iter().filter_map(|m| check(m).err()).collect();
    assert!(failures.is_empty(), "{failures:#?}");
    assert!(MIRRORED.len() >= 11, "the list holds every mirrored struct");
}

/// The check itself notices a wrong offset, a missing member and a wrong size.
#[test]
fn the_check_finds_mismatches() {
    let frame = MIRRORED.iter().find(|m| m.wgsl == "Frame").unwrap();
    let mut shifted: Vec<(&'static str, usize)> = frame.fields.to_vec();
    shifted[5].1 += 4;
    let shifted = MirrorLayout { fields: Box::leak(shifted.into_boxed_slice()), ..*frame };
    assert!(check(&shifted).unwrap_err().contains("at"));
    let missing = MirrorLayout { fields: &frame.fields[1..], ..*frame };
    assert!(check(&missing).unwrap_err().contains("no field"));
    let larger = MirrorLayout { size: frame.size + 16, ..*frame };
    assert!(check(&larger).unwrap_err().contains("bytes"));
}

/// The value of the WGSL constant `name` in `module`.
fn constant(module: &naga::Module, name: &str) -> naga::Literal {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no constant {name}"));
    match module.global_expressions[c.init] {
        naga::Expression::Literal(literal) => literal,
        ref other => panic!("{name} = {other:?}"),
    }
}

#[test]
fn raster_counter_words_match_the_shader() {
    let module = module("raster.wgsl");
    let word = |name: &str| match constant(&module, name) {
        naga::Literal::U32(v) => v as usize,
        other => panic!("{name} = {other:?}"),
    };
    let at = |offset: usize| offset / 4;
    assert_eq!(at(std::mem::offset_of!(RasterCounters, rejected_indices)), word("DIAG_INDEX"));
    assert_eq!(at(std::mem::offset_of!(RasterCounters, rejected_materials)), word("DIAG_MATERIAL"));
    assert_eq!(at(std::mem::offset_of!(RasterCounters, rejected_positions)), word("DIAG_POSITION"));
    assert_eq!(at(std::mem::offset_of!(RasterCounters, untextured)), word("DIAG_TEXTURE"));
}

/// The resolve bounds the host's (unchecked) emission by the limit the CPU checks scenes against.
#[test]
fn radiance_bound_matches_the_shader() {
    let module = module("resolve.wgsl");
    assert_eq!(
        constant(&module, "MAX_RADIANCE"),
        naga::Literal::F32(deep_gbuffer::scene::MAX_RADIANCE)
    );
}
