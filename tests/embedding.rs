//! deep-gbuffer as one stage of a host's frame: the host owns the device, its geometry buffers
//! and its command encoder, and reads the composite back from its own buffer.

use deep_gbuffer::scene::upload::{MATERIAL_DOUBLE_SIDED, SLOT_BASE_COLOR};
use deep_gbuffer::scene::{Light, LightKind};
use deep_gbuffer::{
    Camera, GpuMaterial, ImportedBuffers, Renderer, SceneBuffers, SceneInfo, Settings,
};
use glam::Vec3;
use wgpu::util::DeviceExt;

/// The host's own device, opened with what deep-gbuffer publishes it needs.
fn host_device() -> (wgpu::Device, wgpu::Queue) {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
            .expect("an adapter (lavapipe: apt-get install -y mesa-vulkan-drivers)");
    device_on(&adapter)
}

/// A device on `adapter` with what deep-gbuffer publishes it needs.
fn device_on(adapter: &wgpu::Adapter) -> (wgpu::Device, wgpu::Queue) {
    let features =
        Renderer::required_features() | (adapter.features() & Renderer::optional_features());
    let limits = Renderer::required_limits().using_resolution(adapter.limits());
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("host"),
        required_features: features,
        required_limits: limits,
        ..Default::default()
    }))
    .expect("device")
}

fn storage(device: &wgpu::Device, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::INDEX,
    })
}

#[test]
fn host_frame_with_deep_gbuffer_as_one_stage() {
    let (device, queue) = host_device();

    // The host's geometry: one quad facing +z, in its own buffers.
    let positions: [f32; 12] = [-1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0];
    let normals: [f32; 12] = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
    let uvs = [0.0f32; 8];
    let indices: [u32; 6] = [0, 1, 2, 0, 2, 3];
    let material = GpuMaterial {
        base_color: [0.5, 0.5, 0.5, 1.0],
        roughness: 1.0,
        flags: MATERIAL_DOUBLE_SIDED,
        ..Default::default()
    };
    let buffers = ImportedBuffers {
        positions: storage(&device, "host.positions", bytemuck::cast_slice(&positions)),
        normals: storage(&device, "host.normals", bytemuck::cast_slice(&normals)),
        uvs: storage(&device, "host.uvs", bytemuck::cast_slice(&uvs)),
        indices: storage(&device, "host.indices", bytemuck::cast_slice(&indices)),
        triangle_materials: storage(
            &device,
            "host.materials_of_triangles",
            bytemuck::cast_slice(&[0u32, 0]),
        ),
        materials: storage(&device, "host.materials", bytemuck::bytes_of(&material)),
        texels: storage(&device, "host.texels", &[0u8; 16]),
        uvs1: None,
        tangents: None,
        vertex_count: 4,
        triangle_count: 2,
        material_count: 1,
    };
    let info = SceneInfo {
        lights: vec![Light {
            name: "key".into(),
            kind: LightKind::Directional { direction: Vec3::NEG_Z },
            color: Vec3::ONE,
            intensity: 2.0,
            casts_shadows: false,
        }],
        ambient: Vec3::new(0.1, 0.2, 0.3),
        reflective: false,
        emissive: false,
        blended: false,
        masked: false,
        textureless: true,
        bounds: Some((Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0))),
    };
    let scene = SceneBuffers::import(&device, buffers, info).unwrap();
    let (w, h) = (32u32, 32u32);
    let mut renderer = Renderer::new(&device, &queue, Settings::with_size(w, h)).unwrap();
    let camera = Camera::perspective(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 40.0, 0.1);

    // The host's frame: its own work, then deep-gbuffer, then its own copy to read back.
    let bytes = u64::from(w * h * 16);
    let target = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("host.target"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("host.readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("host.frame") });
    encoder.clear_buffer(&target, 0, None);
    renderer.encode_to(&device, &queue, &mut encoder, &scene, &camera, &target).unwrap();
    encoder.copy_buffer_to_buffer(&target, 0, &readback, 0, bytes);
    queue.submit([encoder.finish()]);

    let pixels = deep_gbuffer::gpu::map_read(&device, &readback).unwrap();
    let pixels: &[[f32; 4]] = bytemuck::cast_slice(&pixels);
    let center = pixels[(h / 2 * w + w / 2) as usize];
    let corner = pixels[0];
    // The quad, lit head-on: albedo / pi * E (+ a little specular) + ambient * albedo.
    let expected = 0.5 / std::f32::consts::PI * 2.0 + 0.5 * 0.1;
    assert!(
        center[3] == 1.0 && (center[0] - expected).abs() < 0.02,
        "quad pixel {center:?}, expected about {expected}"
    );
    // The corner sees the sky.
    assert_eq!(corner, [0.1, 0.2, 0.3, 0.0]);

    // A target too small is a typed error, not a GPU validation failure.
    let small = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("host.small"),
        size: 64,
        usage: wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    assert!(renderer.encode_to(&device, &queue, &mut encoder, &scene, &camera, &small).is_err());
}

/// The same stage writing into the host's rgba16float storage texture.
#[test]
fn composite_into_the_hosts_storage_texture() {
    let (device, queue) = host_device();
    let scene = deep_gbuffer::Scene::from_spec("builtin:cornell").unwrap();
    let buffers = SceneBuffers::upload(&device, &scene).unwrap();
    let (w, h) = (32u32, 24u32);
    let mut renderer = Renderer::new(&device, &queue, Settings::with_size(w, h)).unwrap();
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("host.texture"),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("host.readback"),
        size: u64::from(256 * h),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    renderer
        .encode_to_texture(
            &device,
            &queue,
            &mut encoder,
            &buffers,
            &scene.camera_or_default(),
            &texture,
        )
        .unwrap();
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(256),
                rows_per_image: None,
            },
        },
        wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
    );
    queue.submit([encoder.finish()]);
    let bytes = deep_gbuffer::gpu::map_read(&device, &readback).unwrap();
    let hdr = renderer.read_rgb(&device, &queue, renderer.hdr_buffer()).unwrap();
    let half = |b: &[u8]| {
        let h = u16::from_le_bytes([b[0], b[1]]);
        let (sign, exp, frac) =
            (if h & 0x8000 != 0 { -1.0f32 } else { 1.0 }, (h >> 10) & 0x1f, f32::from(h & 0x3ff));
        if exp == 0 {
            sign * frac * 2f32.powi(-24)
        } else {
            sign * (1.0 + frac / 1024.0) * 2f32.powi(i32::from(exp) - 15)
        }
    };
    for y in 0..h {
        for x in 0..w {
            let texel = &bytes[(y * 256 + x * 8) as usize..][..8];
            let expected = hdr[(y * w + x) as usize];
            for (c, e) in [half(&texel[0..2]), half(&texel[2..4]), half(&texel[4..6])]
                .into_iter()
                .zip(expected.to_array())
            {
                // binary16 keeps 11 significant bits.
                assert!((c - e).abs() <= e.abs() / 1024.0 + 1e-6, "({x}, {y}): {c} vs {e}");
            }
        }
    }
    // A texture of the wrong format is a typed error.
    let wrong = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("host.wrong"),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    let camera = scene.camera_or_default();
    assert!(
        renderer
            .encode_to_texture(&device, &queue, &mut encoder, &buffers, &camera, &wrong)
            .is_err()
    );
}

/// Which of the scene's features [`import_strip`]'s [`SceneInfo`] declares.
#[derive(Clone, Copy, Default)]
struct Declared {
    masked: bool,
    blended: bool,
    textureless: bool,
}

/// A material of grey `base` with `flags`, its base-colour slot naming the 2x2 texture at
/// `texture_offset` of [`import_strip`]'s texels (read only where `flags` has the slot's bit).
fn strip_material(base: f32, alpha: f32, flags: u32, texture_offset: u32) -> GpuMaterial {
    let mut m = GpuMaterial {
        base_color: [base, base, base, alpha],
        roughness: 1.0,
        flags,
        ..Default::default()
    };
    m.slots[SLOT_BASE_COLOR] = deep_gbuffer::GpuTextureSlot::new(
        &deep_gbuffer::TextureRef::new(0),
        (texture_offset, 2, 2),
        1.0,
    );
    m
}

/// The host's buffers for `triangles` (indices, material id) over eight vertices: 0-3 a quad
/// facing +z, 4 NaN, 5-7 a small triangle left of the quad; the texels hold a grey opaque 2x2
/// texture at offset 0 and a grey transparent one at offset 4 (a 2x2 texture at offset 7 does
/// not fit). Lit by a shadow-casting sun.
fn import_strip(
    device: &wgpu::Device,
    triangles: &[([u32; 3], u32)],
    materials: &[GpuMaterial],
    declared: Declared,
) -> SceneBuffers {
    let nan = f32::NAN;
    let positions: [f32; 24] = [
        -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0, nan, 0.0, 0.0, -1.8, -0.3,
        0.0, -1.2, -0.3, 0.0, -1.5, 0.3, 0.0,
    ];
    let normals: Vec<f32> = (0..8).flat_map(|_| [0.0, 0.0, 1.0]).collect();
    let uvs = [0.25f32; 16];
    let indices: Vec<u32> = triangles.iter().flat_map(|(t, _)| *t).collect();
    let ids: Vec<u32> = triangles.iter().map(|(_, m)| *m).collect();
    let texels = [[128u8, 128, 128, 255].repeat(4), [128u8, 128, 128, 0].repeat(4)].concat();
    let buffers = ImportedBuffers {
        positions: storage(device, "host.positions", bytemuck::cast_slice(&positions)),
        normals: storage(device, "host.normals", bytemuck::cast_slice(&normals)),
        uvs: storage(device, "host.uvs", bytemuck::cast_slice(&uvs)),
        indices: storage(device, "host.indices", bytemuck::cast_slice(&indices)),
        triangle_materials: storage(device, "host.ids", bytemuck::cast_slice(&ids)),
        materials: storage(device, "host.materials", bytemuck::cast_slice(materials)),
        texels: storage(device, "host.texels", &texels),
        uvs1: None,
        tangents: None,
        vertex_count: 8,
        triangle_count: triangles.len() as u32,
        material_count: materials.len() as u32,
    };
    let info = SceneInfo {
        lights: vec![Light {
            name: "key".into(),
            kind: LightKind::Directional { direction: Vec3::new(0.3, -0.2, -1.0) },
            color: Vec3::ONE,
            intensity: 2.0,
            casts_shadows: true,
        }],
        ambient: Vec3::splat(0.2),
        reflective: false,
        emissive: false,
        blended: declared.blended,
        masked: declared.masked,
        textureless: declared.textureless,
        bounds: Some((Vec3::new(-2.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0))),
    };
    SceneBuffers::import(device, buffers, info).unwrap()
}

/// Two 40x24 frames of an [`import_strip`] scene: the second's composite and both frames'
/// diagnostics.
fn render_strip(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &SceneBuffers,
) -> (Vec<Vec3>, Vec<deep_gbuffer::Diagnostics>) {
    let camera =
        Camera::perspective(Vec3::new(-0.3, 0.0, 3.0), Vec3::new(-0.3, 0.0, 0.0), 50.0, 0.1);
    let mut renderer = Renderer::new(device, queue, Settings::with_size(40, 24)).unwrap();
    let mut counts = Vec::new();
    for _ in 0..2 {
        renderer.render(device, queue, scene, &camera).unwrap();
        counts.push(renderer.diagnostics(device, queue).unwrap());
    }
    let hdr = renderer.read_rgb(device, queue, renderer.hdr_buffer()).unwrap();
    (hdr, counts)
}

/// The strip's two triangles of the quad, and the small triangle with material 1.
const STRIP: [([u32; 3], u32); 3] = [([0, 1, 2], 0), ([0, 2, 3], 0), ([5, 6, 7], 1)];

fn assert_same_image(image: &[Vec3], expected: &[Vec3]) {
    assert_eq!(image.len(), expected.len());
    for (i, (a, b)) in image.iter().zip(expected).enumerate() {
        assert_eq!(a.to_array(), b.to_array(), "pixel {i}");
    }
}

/// The host's buffers as the CPU never sees them: bad indices, a bad material id, a NaN
/// position and a texture past the texel buffer. Each bad triangle is rejected on the GPU (the
/// image is bit for bit that of the good triangles alone) and counted once a frame. A texture
/// that fits, in a scene marked textureless, is left out and counted the same way.
#[test]
fn bad_imported_triangles_are_rejected_and_counted() {
    let (device, queue) = host_device();
    let textured = deep_gbuffer::scene::upload::slot_flag(SLOT_BASE_COLOR);
    let bad = [
        ([0, 1, 2], 0),
        ([0, 1, u32::MAX], 0),
        ([0, 2, 8], 0),
        ([0, 2, 3], 0),
        ([1, 2, 3], u32::MAX),
        ([1, 2, 3], 2),
        ([0, 4, 2], 0),
        ([5, 6, 7], 1),
    ];
    // The bad scene's material 1 names a texture past the texels; it is drawn untextured,
    // exactly as the good scene's untextured material 1.
    let untextured = [strip_material(0.5, 1.0, 0, 0), strip_material(0.8, 1.0, 0, 0)];
    let past = [strip_material(0.5, 1.0, 0, 0), strip_material(0.8, 1.0, textured, 7)];
    let reference = import_strip(&device, &STRIP, &untextured, Declared::default());
    let scene = import_strip(&device, &bad, &past, Declared::default());

    let (expected, clean) = render_strip(&device, &queue, &reference);
    let (image, counts) = render_strip(&device, &queue, &scene);
    assert!(clean.iter().all(|d| !d.has_bad_input()), "{clean:?}");
    for d in &counts {
        // Counted once a frame (the shadow map's raster reads the same triangles, uncounted).
        assert_eq!(
            (
                d.rejected_indices,
                d.rejected_materials,
                d.rejected_positions,
                d.untextured_triangles
            ),
            (2, 2, 1, 1),
            "{d:?}"
        );
        assert_eq!(d.rejected_triangles(), 5);
        assert_eq!(d.warnings().len(), 4, "{:?}", d.warnings());
    }
    assert!(image.iter().all(|p| p.is_finite()));
    let lit = expected.iter().filter(|p| p.x > 0.3).count();
    assert!(lit > 200, "the quad and the triangle are in view ({lit} pixels)");
    assert_same_image(&image, &expected);

    // Material 1's texture fits: sampled, it darkens the triangle; in a scene marked textureless
    // the triangle has its factors alone, as the reference, and is counted.
    let named = [strip_material(0.5, 1.0, 0, 0), strip_material(0.8, 1.0, textured, 0)];
    let (sampled, sampled_counts) =
        render_strip(&device, &queue, &import_strip(&device, &STRIP, &named, Declared::default()));
    let marked = Declared { textureless: true, ..Declared::default() };
    let (marked, marked_counts) =
        render_strip(&device, &queue, &import_strip(&device, &STRIP, &named, marked));
    assert!(sampled_counts.iter().all(|d| !d.has_bad_input()), "{sampled_counts:?}");
    let darker = sampled.iter().zip(&expected).filter(|(a, b)| a.x < 0.9 * b.x).count();
    assert!(darker > 10, "the grey texture shows on the small triangle ({darker} pixels darker)");
    for d in &marked_counts {
        assert_eq!((d.rejected_triangles(), d.untextured_triangles), (0, 1), "{d:?}");
    }
    assert_same_image(&marked, &expected);
}

/// A masked and a blended material whose texture is transparent: where textures are sampled
/// the texture's alpha cuts the triangle away (the image is the quad's alone); in a scene
/// marked textureless the material's factors alone decide its coverage and opacity, as the same
/// material without the texture (bit for bit), and the triangle is counted.
#[test]
fn textureless_scenes_cut_and_blend_by_factors_alone() {
    let (device, queue) = host_device();
    let textured = deep_gbuffer::scene::upload::slot_flag(SLOT_BASE_COLOR);
    let mask = deep_gbuffer::scene::upload::MATERIAL_MASK;
    let blend = deep_gbuffer::scene::upload::MATERIAL_BLEND;
    let quad = render_strip(
        &device,
        &queue,
        &import_strip(&device, &STRIP[..2], &[strip_material(0.5, 1.0, 0, 0)], Declared::default()),
    )
    .0;
    let cases = [
        ("masked", mask, 1.0, Declared { masked: true, ..Declared::default() }),
        ("blended", blend, 0.6, Declared { blended: true, ..Declared::default() }),
    ];
    for (name, flags, alpha, declared) in cases {
        let base = strip_material(0.5, 1.0, 0, 0);
        let material = |flags, offset| GpuMaterial {
            alpha_cutoff: 0.5,
            ..strip_material(0.8, alpha, flags, offset)
        };
        let with_texture = |offset| [base, material(flags | textured, offset)];
        let factors = [base, material(flags, 0)];
        let (expected, _) =
            render_strip(&device, &queue, &import_strip(&device, &STRIP, &factors, declared));
        let differs = expected.iter().zip(&quad).filter(|(a, b)| a != b).count();
        assert!(differs > 10, "{name}: the untextured triangle shows ({differs} pixels)");

        // Sampled, the transparent texture takes the triangle away; the opaque one keeps it.
        let (cut, counts) = render_strip(
            &device,
            &queue,
            &import_strip(&device, &STRIP, &with_texture(4), declared),
        );
        assert!(counts.iter().all(|d| !d.has_bad_input()), "{name}: {counts:?}");
        for (i, (a, b)) in cut.iter().zip(&quad).enumerate() {
            assert!((*a - *b).abs().max_element() < 1e-5, "{name}: pixel {i}: {a} against {b}");
        }
        let (kept, _) = render_strip(
            &device,
            &queue,
            &import_strip(&device, &STRIP, &with_texture(0), declared),
        );
        let shown = kept.iter().zip(&quad).filter(|(a, b)| a != b).count();
        assert!(shown > 10, "{name}: the opaque texture keeps the triangle ({shown} pixels)");

        // Marked textureless, the transparent texture is not read: the factors decide.
        let marked = Declared { textureless: true, ..declared };
        let (image, counts) =
            render_strip(&device, &queue, &import_strip(&device, &STRIP, &with_texture(4), marked));
        for d in &counts {
            assert_eq!((d.rejected_triangles(), d.untextured_triangles), (0, 1), "{name}: {d:?}");
        }
        assert_same_image(&image, &expected);
    }
}

/// Resources of another device (of the same instance) are typed errors, not panics in wgpu's
/// error handler.
#[test]
fn another_devices_resources_are_errors() {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
            .expect("an adapter");
    let (device, queue) = device_on(&adapter);
    let (other, _other_queue) = device_on(&adapter);
    let scene = deep_gbuffer::Scene::from_spec("builtin:cornell").unwrap();
    let camera = scene.camera_or_default();
    let foreign = SceneBuffers::upload(&other, &scene).unwrap();
    let mut renderer = Renderer::new(&device, &queue, Settings::with_size(16, 12)).unwrap();
    let mut encoder = device.create_command_encoder(&Default::default());
    let e = renderer.encode(&device, &queue, &mut encoder, &foreign, &camera).unwrap_err();
    assert!(matches!(e, deep_gbuffer::Error::Gpu { .. }), "{e}");
    let e = renderer.render(&device, &queue, &foreign, &camera).unwrap_err();
    assert!(matches!(e, deep_gbuffer::Error::Gpu { .. }), "{e}");
    // Its own scene still renders, and a texture of another device is refused.
    let own = SceneBuffers::upload(&device, &scene).unwrap();
    renderer.render(&device, &queue, &own, &camera).unwrap();
    let texture = other.create_texture(&wgpu::TextureDescriptor {
        label: Some("foreign"),
        size: wgpu::Extent3d { width: 16, height: 12, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    let e = renderer
        .encode_to_texture(&device, &queue, &mut encoder, &own, &camera, &texture)
        .unwrap_err();
    assert!(matches!(e, deep_gbuffer::Error::Gpu { .. }), "{e}");
}
