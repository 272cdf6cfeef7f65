//! The `#[repr(C)]` structs shared with WGSL have the sizes and member offsets naga computes for
//! the WGSL structs they mirror.

use deep_gbuffer::GpuMaterial;
use deep_gbuffer::gpu::FrameUniform;
use deep_gbuffer::passes::ao::AoUniform;

fn wgsl_layout(file: &str, name: &str) -> (u32, Vec<(String, u32)>) {
    let source = deep_gbuffer::gpu::shader_source(file, &[]);
    let module = naga::front::wgsl::parse_str(&source).unwrap();
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let (handle, ty) = module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).unwrap();
    let naga::TypeInner::Struct { members, span } = &ty.inner else { panic!("{name} is a struct") };
    let _ = handle;
    (*span, members.iter().map(|m| (m.name.clone().unwrap(), m.offset)).collect())
}

macro_rules! check {
    ($ty:ty, $file:expr, $name:expr, [$($field:ident),* $(,)?]) => {{
        let (size, members) = wgsl_layout($file, $name);
        assert_eq!(size as usize, std::mem::size_of::<$ty>(), "size of {}", $name);
        $(
            let offset = members.iter().find(|(n, _)| n == stringify!($field)).map(|(_, o)| *o).unwrap();
            assert_eq!(offset as usize, std::mem::offset_of!($ty, $field), "{}.{}", $name, stringify!($field));
        )*
    }};
}

#[test]
fn frame_uniform_matches_wgsl() {
    check!(
        FrameUniform,
        "shared/frame.wgsl",
        "Frame",
        [
            view,
            proj,
            inv_view,
            prev_view,
            prev_view_proj,
            width,
            height,
            near,
            far,
            guard_x,
            guard_y,
            dz,
            ortho,
            triangle_count,
            material_count,
            vertex_count
        ]
    );
}

#[test]
fn material_matches_wgsl() {
    // GpuMaterial's `_pad: [u32; 2]` is `_pad0, _pad1` in WGSL.
    check!(
        GpuMaterial,
        "shared/material.wgsl",
        "Material",
        [
            base_color,
            emissive,
            roughness,
            metallic,
            reflectivity,
            flags,
            texture_offset,
            texture_width,
            texture_height
        ]
    );
}

#[test]
fn ao_uniform_matches_wgsl() {
    check!(AoUniform, "ao.wgsl", "Ao", [radius, bias, intensity, samples, levels, offsets]);
}
