//! Loaders and scene validation: the fixtures load, malformed files give errors that name the
//! problem and where it is.

mod common;

use common::fixture;
use deep_gbuffer::scene::LightKind;
use deep_gbuffer::{Error, Scene};
use glam::Vec3;

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("deep-gbuffer-test-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn cornell_fixture_loads_with_its_materials() {
    let scene = Scene::load(&fixture("cornell/CornellBox-Original.obj")).unwrap();
    assert_eq!(scene.triangle_count(), 36);
    assert_eq!(scene.materials.len(), 8);
    let light = scene.materials.iter().find(|m| m.name == "light").unwrap();
    assert_eq!(light.emissive, Vec3::new(17.0, 12.0, 4.0));
    let left = scene.materials.iter().find(|m| m.name == "leftWall").unwrap();
    assert_eq!(left.base_color.truncate(), Vec3::new(0.63, 0.065, 0.05));
    scene.validate().unwrap();
    // The built-in copy is the same geometry, with a camera and a light.
    let builtin = Scene::from_spec("builtin:cornell").unwrap();
    assert_eq!(builtin.positions, scene.positions);
    assert!(builtin.camera.is_some() && !builtin.lights.is_empty());
}

#[test]
fn gltf_fixtures_load() {
    let suzanne = Scene::load(&fixture("suzanne/Suzanne.gltf")).unwrap();
    assert!(suzanne.triangle_count() > 3000);
    assert_eq!(suzanne.textures.len(), 2, "the base-colour and metallic-roughness textures");
    let m = &suzanne.materials[0];
    let texture = |t: Option<deep_gbuffer::TextureRef>| t.map(|t| t.texture);
    assert_eq!(
        (
            texture(m.base_color_texture),
            texture(m.metallic_roughness_texture),
            texture(m.emissive_texture)
        ),
        (Some(0), Some(1), None)
    );
    assert!(suzanne.uvs.iter().any(|uv| *uv != glam::Vec2::ZERO));
    suzanne.validate().unwrap();
    let engine = Scene::load(&fixture("engine/2CylinderEngine.gltf")).unwrap();
    assert!(engine.triangle_count() > 50_000, "{}", engine.triangle_count());
    engine.validate().unwrap();
}

#[test]
fn gltf_lights_camera_and_transforms() {
    let dir = temp_dir("gltf-lights");
    // One triangle under a translated, scaled node; a spot light and a camera on nodes.
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let bytes: Vec<u8> = positions.iter().flat_map(|f| f.to_le_bytes()).collect();
    std::fs::write(dir.join("tri.bin"), &bytes).unwrap();
    let gltf = r#"{
      "asset": {"version": "2.0"},
      "extensionsUsed": ["KHR_lights_punctual"],
      "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "spot", "color": [1, 0.5, 0.25], "intensity": 20, "range": 9, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}, "name": "lamp"}
      ]}},
      "buffers": [{"uri": "tri.bin", "byteLength": 36}],
      "bufferViews": [{"buffer": 0, "byteLength": 36}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
      "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}}],
      "nodes": [
        {"mesh": 0, "translation": [10, 0, 0], "scale": [2, 2, 2]},
        {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 5, 0]},
        {"camera": 0, "translation": [0, 0, 4]}
      ],
      "scenes": [{"nodes": [0, 1, 2]}],
      "scene": 0
    }"#;
    let scene = Scene::load(&write(&dir, "scene.gltf", gltf)).unwrap();
    assert_eq!(
        scene.positions,
        vec![Vec3::new(10.0, 0.0, 0.0), Vec3::new(12.0, 0.0, 0.0), Vec3::new(10.0, 2.0, 0.0)]
    );
    assert_eq!(scene.lights.len(), 1);
    assert_eq!(scene.lights[0].name, "lamp");
    match scene.lights[0].kind {
        LightKind::Spot { position, direction, range, inner_cone, outer_cone } => {
            assert_eq!(position, Vec3::new(0.0, 5.0, 0.0));
            assert_eq!(direction, Vec3::NEG_Z);
            assert_eq!((range, inner_cone, outer_cone), (Some(9.0), 0.2, 0.5));
        }
        other => panic!("{other:?}"),
    }
    let camera = scene.camera.unwrap();
    assert_eq!(camera.eye, Vec3::new(0.0, 0.0, 4.0));
    assert!(matches!(camera.projection, deep_gbuffer::Projection::Perspective { far: None, .. }));
    // No material: the default one is appended.
    assert_eq!(scene.materials.len(), 1);
}

/// The same document as a binary `.glb` (header, JSON chunk, BIN chunk).
#[test]
fn glb_loads() {
    let dir = temp_dir("glb");
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let bin: Vec<u8> = positions.iter().flat_map(|f| f.to_le_bytes()).collect();
    let json = r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 36}],
      "bufferViews": [{"buffer": 0, "byteLength": 36}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}],
      "materials": [{"doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1, 1], "metallicFactor": 1, "roughnessFactor": 0.25}}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}], "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}"#;
    let mut json = json.as_bytes().to_vec();
    json.resize(json.len().next_multiple_of(4), b' ');
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    let path = dir.join("tri.glb");
    std::fs::write(&path, &glb).unwrap();
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    let m = &scene.materials[0];
    assert!(m.double_sided);
    assert_eq!((m.metallic, m.roughness, m.reflectivity), (1.0, 0.25, 0.75));
    // A truncated file is an error, not a panic.
    std::fs::write(&path, &glb[..30]).unwrap();
    assert!(Scene::load(&path).is_err());
}

#[test]
fn scenes_without_camera_or_lights_get_defaults() {
    let mut scene = Scene::load(&fixture("cornell/CornellBox-Original.obj")).unwrap();
    assert!(scene.camera.is_none() && scene.lights.is_empty());
    let camera = scene.camera_or_default();
    let (lo, hi) = scene.bounds().unwrap();
    // The framing camera looks at the centre from outside the bounds.
    assert!((camera.target - (lo + hi) * 0.5).length() < 1e-5);
    assert!(camera.eye.z > hi.z);
    scene.ensure_lights();
    assert!(matches!(scene.lights[0].kind, LightKind::Directional { .. }));
    assert!(scene.ambient.max_element() > 0.0);
}

fn error_text(result: Result<Scene, Error>) -> String {
    match result {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn malformed_obj_names_file_and_line() {
    let dir = temp_dir("obj");
    let bad_vertex = write(&dir, "v.obj", "v 0 0 0\nv 1 0 0\nv 0 x 0\nf 1 2 3\n");
    let text = error_text(Scene::load(&bad_vertex));
    assert!(text.contains("v.obj") && text.contains("line 3"), "{text}");

    let out_of_range = write(&dir, "f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n# comment\nf 1 2 7\n");
    let text = error_text(Scene::load(&out_of_range));
    assert!(text.contains("f.obj") && text.contains("line 5"), "{text}");

    let missing_mtl =
        write(&dir, "m.obj", "mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let text = error_text(Scene::load(&missing_mtl));
    assert!(text.contains("nowhere.mtl"), "{text}");

    write(&dir, "bad.mtl", "newmtl a\nKd 1 1 1\nKe 1 x 1\n");
    let bad_mtl =
        write(&dir, "b.obj", "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n");
    let text = error_text(Scene::load(&bad_mtl));
    assert!(text.contains("bad.mtl") && text.contains("line 3"), "{text}");

    let text = error_text(Scene::load(&dir.join("absent.obj")));
    assert!(text.contains("absent.obj"), "{text}");
}

#[test]
fn malformed_gltf_names_the_problem() {
    let dir = temp_dir("gltf");
    let text = error_text(Scene::load(&write(
        &dir,
        "syntax.gltf",
        "{\"asset\": {\"version\": \"2.0\"},\n \"nodes\": [ }",
    )));
    assert!(text.contains("syntax.gltf") && text.contains("line 2"), "{text}");

    let missing_buffer = r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "gone.bin", "byteLength": 36}],
      "bufferViews": [{"buffer": 0, "byteLength": 36}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}"#;
    let text = error_text(Scene::load(&write(&dir, "nobuf.gltf", missing_buffer)));
    assert!(text.contains("nobuf.gltf") || text.contains("gone.bin"), "{text}");

    let bad_accessor = r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
      "bufferViews": [{"buffer": 0, "byteLength": 36}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 7}}]}], "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}"#;
    let text = error_text(Scene::load(&write(&dir, "accessor.gltf", bad_accessor)));
    assert!(text.contains("accessor.gltf") && text.contains("meshes[0]"), "{text}");

    let text = error_text(Scene::load(&write(&dir, "scene.txt", "hello")));
    assert!(text.contains("unknown scene format"), "{text}");
}

/// glTF URIs that leave the scene's folder, or the machine, are refused before anything is
/// read; relative files inside the folder and data: URIs load.
#[test]
fn gltf_uris_outside_the_folder_or_on_the_network_are_refused() {
    let dir = temp_dir("uris");
    let doc = |uri: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"uri": "{uri}", "byteLength": 36}}],
      "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
      "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}}],
      "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}], "nodes": [{{"mesh": 0}}], "scenes": [{{"nodes": [0]}}]}}"#
        )
    };
    for (uri, expect) in [
        ("../secret.bin", "outside"),
        ("a/../../secret.bin", "outside"),
        ("%2e%2e/secret.bin", "outside"),
        ("/etc/passwd", "absolute"),
        ("C:/Windows/win.ini", "absolute"),
        ("http://example.com/tri.bin", "http:"),
        ("https://example.com/tri.bin", "https:"),
        ("file:///etc/passwd", "file:"),
    ] {
        let text = error_text(Scene::load(&write(&dir, "uri.gltf", &doc(uri))));
        assert!(text.contains("buffers[0].uri") && text.contains(expect), "{uri}: {text}");
    }
    // Inside the folder: a relative file one level down loads.
    let triangle: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::create_dir_all(dir.join("bin")).unwrap();
    std::fs::write(dir.join("bin/tri.bin"), triangle).unwrap();
    let scene = Scene::load(&write(&dir, "inside.gltf", &doc("bin/../bin/tri.bin"))).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    // A name that is a link is followed, and refused where it leads out of the folder or to
    // something that is not a regular file (a device, a folder, a pipe that would hang a read).
    let outside = temp_dir("uris-outside");
    std::fs::write(outside.join("secret.bin"), [0u8; 36]).unwrap();
    let link = |name: &str, to: &std::path::Path| {
        let at = dir.join(name);
        let _ = std::fs::remove_file(&at);
        std::os::unix::fs::symlink(to, &at).unwrap();
    };
    link("escape.bin", &outside.join("secret.bin"));
    link("zero.bin", std::path::Path::new("/dev/zero"));
    link("folder.bin", &outside);
    link("inner.bin", &dir.join("bin/tri.bin"));
    let fifo = dir.join("pipe.bin");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    let mut cases = vec![
        ("escape.bin", "leads outside"),
        ("zero.bin", "leads outside"),
        ("folder.bin", "leads outside"),
        ("missing.bin", "cannot be opened"),
    ];
    if made.is_ok_and(|s| s.success()) {
        cases.push(("pipe.bin", "not a regular file"));
    }
    for (uri, expect) in cases {
        let text = error_text(Scene::load(&write(&dir, "link.gltf", &doc(uri))));
        assert!(text.contains("buffers[0].uri") && text.contains(expect), "{uri}: {text}");
    }
    let scene = Scene::load(&write(&dir, "link.gltf", &doc("inner.bin"))).unwrap();
    assert_eq!(scene.triangle_count(), 1, "a link that stays inside is followed");
}

/// OBJ `mtllib` and MTL `map_Kd` stay inside the OBJ's folder too.
#[test]
fn obj_libraries_and_maps_stay_inside_the_folder() {
    let dir = temp_dir("obj-paths");
    let outside = temp_dir("obj-paths-outside");
    std::fs::write(outside.join("m.mtl"), "newmtl a\nKd 1 0 0\n").unwrap();
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let abs = outside.join("m.mtl");
    let climb = format!("../{}/m.mtl", outside.file_name().unwrap().to_str().unwrap());
    let linked = dir.join("linked.mtl");
    let _ = std::fs::remove_file(&linked);
    std::os::unix::fs::symlink(&abs, &linked).unwrap();
    for (mtllib, expect) in [
        (abs.to_str().unwrap(), "absolute"),
        (climb.as_str(), "leads outside"),
        ("linked.mtl", "leads outside"),
    ] {
        let obj = write(&dir, "a.obj", &format!("mtllib {mtllib}\nusemtl a\n{tri}"));
        let text = error_text(Scene::load(&obj));
        assert!(text.contains("mtllib") && text.contains(expect), "{mtllib}: {text}");
    }
    write(&dir, "m.mtl", "newmtl a\nKd 1 0 0\nmap_Kd /etc/passwd\n");
    let obj = write(&dir, "b.obj", &format!("mtllib m.mtl\nusemtl a\n{tri}"));
    let text = error_text(Scene::load(&obj));
    assert!(text.contains("map_Kd") && text.contains("absolute"), "{text}");
}

#[test]
fn invalid_scenes_are_refused_with_the_cause() {
    let mut scene = Scene::from_spec("builtin:cornell").unwrap();
    scene.triangles[5][1] = 10_000;
    assert!(scene.validate().unwrap_err().to_string().contains("triangle 5 uses vertex 10000"));

    let mut scene = Scene::from_spec("builtin:cornell").unwrap();
    scene.positions[3].y = f32::NAN;
    assert!(scene.validate().unwrap_err().to_string().contains("position 3 is not finite"));

    let mut scene = Scene::from_spec("builtin:cornell").unwrap();
    scene.triangle_materials[0] = 99;
    assert!(scene.validate().unwrap_err().to_string().contains("material 99"));

    assert!(Scene::default().validate().unwrap_err().to_string().contains("no triangles"));
    assert!(matches!(Scene::from_spec("builtin:nope"), Err(Error::UnknownBuiltin(_))));
}

#[test]
fn procedural_grid_reaches_millions_of_triangles() {
    for target in [1_000u32, 100_000, 2_000_000] {
        let scene = Scene::from_spec(&format!("builtin:grid-{target}")).unwrap();
        let n = scene.triangle_count() as f64;
        assert!((n / f64::from(target) - 1.0).abs() < 0.25, "grid-{target} has {n} triangles");
        scene.validate().unwrap();
    }
}

/// Values that are finite one by one but overflow together (intensity x colour, emission x
/// strength), or are already infinite, are refused before anything reaches the GPU, naming the
/// light or material.
#[test]
fn radiance_that_overflows_is_refused() {
    let check = |scene: &Scene, what: &str| {
        let e = scene.validate().and_then(|()| deep_gbuffer::SceneInfo::of(scene).validate());
        let e = e.unwrap_err().to_string();
        assert!(e.contains(what), "{what}: {e}");
    };
    let cornell = Scene::from_spec("builtin:cornell").unwrap();
    let mut s = cornell.clone();
    s.lights[0].intensity = 3e38;
    s.lights[0].color = Vec3::splat(10.0);
    check(&s, "colour x intensity");
    let mut s = cornell.clone();
    s.materials[0].emissive = Vec3::new(1e39_f64 as f32, 0.0, 0.0);
    check(&s, "emission");
    let mut s = cornell.clone();
    s.materials[0].base_color.x = f32::NAN;
    check(&s, "base colour");
    let mut s = cornell.clone();
    s.ambient = Vec3::splat(f32::MAX);
    check(&s, "ambient");
    // The same through a file: an OBJ whose material emits infinity.
    let dir = temp_dir("overflow");
    write(&dir, "m.mtl", "newmtl hot\nKd 0.5 0.5 0.5\nKe inf 1 1\n");
    let obj =
        write(&dir, "a.obj", "mtllib m.mtl\nusemtl hot\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let scene = Scene::load(&obj);
    let text = match scene {
        Err(e) => e.to_string(),
        Ok(scene) => scene.validate().unwrap_err().to_string(),
    };
    assert!(text.contains("emission") || text.contains("Ke"), "{text}");
}

#[test]
fn a_grid_over_the_triangle_limit_is_refused_before_it_is_built() {
    let text = error_text(Scene::from_spec("builtin:grid-1000000000"));
    assert!(text.contains("limit"), "{text}");
}

/// A one-triangle glTF document with its buffer inline, for mutating into hostile variants.
fn triangle_gltf() -> serde_json::Value {
    let bytes: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .chain([0u16, 1, 2].iter().flat_map(|v| v.to_le_bytes()))
        .collect();
    let b64 = base64::encode(&bytes);
    serde_json::json!({
        "asset": {"version": "2.0"},
        "buffers": [{"uri": format!("data:application/octet-stream;base64,{b64}"), "byteLength": 42}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    })
}

/// What the `gltf` crate's readers would panic on or allocate without bound is refused first,
/// naming the place: accessor types, strides, counts, cameras and node graphs.
#[test]
fn hostile_gltf_structures_are_refused_before_reading() {
    let dir = temp_dir("hostile-gltf");
    let load = |doc: &serde_json::Value| {
        let path = write(&dir, "hostile.gltf", &doc.to_string());
        error_text(Scene::load(&path))
    };
    let base = triangle_gltf();
    let scene = Scene::load(&write(&dir, "ok.gltf", &base.to_string())).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    type Mutation = fn(&mut serde_json::Value);
    let cases: [(Mutation, &str); 11] = [
        (|d| d["accessors"][1]["componentType"] = 5126.into(), "indices needs SCALAR"),
        (|d| d["accessors"][1]["componentType"] = 5122.into(), "indices needs SCALAR"),
        (
            |d| {
                d["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 1.into();
                d["accessors"][1]["componentType"] = 5125.into();
                d["accessors"][1]["type"] = "VEC2".into();
            },
            "TEXCOORD_0 needs VEC2",
        ),
        (
            |d| d["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = 0.into(),
            "TEXCOORD_1 needs VEC2",
        ),
        (
            |d| d["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] = 0.into(),
            "TANGENT needs VEC4",
        ),
        (|d| d["bufferViews"][0]["byteStride"] = 4.into(), "byteStride 4"),
        (|d| d["accessors"][0]["count"] = 4.into(), "do not fit"),
        (
            |d| {
                d["accessors"][0] = serde_json::json!({"componentType": 5126, "count": 3_000_000_000u64, "type": "VEC3", "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 0}}});
            },
            "over the limit",
        ),
        (
            |d| {
                d["cameras"] = serde_json::json!([{"type": "perspective"}]);
                d["nodes"][0]["camera"] = 0.into();
            },
            "without its `perspective` object",
        ),
        (|d| d["nodes"][0]["children"] = serde_json::json!([0]), "cycle"),
        (
            |d| {
                d["nodes"] = serde_json::json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
            },
            "cycle",
        ),
    ];
    for (i, (mutate, expect)) in cases.iter().enumerate() {
        let mut doc = base.clone();
        mutate(&mut doc);
        let text = load(&doc);
        assert!(text.contains(expect), "case {i}: {text}");
    }
    // Each node listing the next twice: 2^25 instances from a few hundred bytes.
    let mut doc = base.clone();
    let nodes: Vec<serde_json::Value> = (0..25)
        .map(|i| serde_json::json!({"children": [i + 1, i + 1]}))
        .chain([serde_json::json!({"mesh": 0})])
        .collect();
    doc["nodes"] = nodes.into();
    let text = load(&doc);
    assert!(text.contains("instances") && text.contains("limit"), "{text}");
    // A material no primitive uses has its image never read (this one does not exist).
    let mut doc = base.clone();
    doc["images"] = serde_json::json!([{"uri": "missing.png"}]);
    doc["textures"] = serde_json::json!([{"source": 0}]);
    doc["materials"] =
        serde_json::json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    let path = write(&dir, "unused.gltf", &doc.to_string());
    assert!(Scene::load(&path).is_ok(), "an unused material's image is not decoded");
    doc["meshes"][0]["primitives"][0]["material"] = 0.into();
    let text = load(&doc);
    assert!(text.contains("images[0]") && text.contains("missing.png"), "{text}");
}

/// A UTF-8 byte-order mark does not cost the OBJ its first line.
#[test]
fn obj_with_a_byte_order_mark_keeps_its_first_vertex() {
    let dir = temp_dir("bom");
    let obj = write(&dir, "bom.obj", "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(Scene::load(&obj).unwrap().triangle_count(), 1);
}

/// Cameras that cannot make an image say why: a zero `up`, an `up` along the view, a field of
/// view below the minimum.
#[test]
fn degenerate_cameras_say_why() {
    let camera = Scene::from_spec("builtin:cornell").unwrap().camera_or_default();
    let mut zero_up = camera.clone();
    zero_up.up = Vec3::ZERO;
    let mut parallel = camera.clone();
    parallel.up = camera.target - camera.eye;
    let mut narrow = camera.clone();
    if let deep_gbuffer::Projection::Perspective { fov_y_deg, .. } = &mut narrow.projection {
        *fov_y_deg = 1e-30;
    }
    for (c, why) in [(zero_up, "up is zero"), (parallel, "parallel"), (narrow, "field of view")] {
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains(why), "{why}: {e}");
    }
    camera.validate().unwrap();
}

/// A camera moved close to (or into) the scene gets a near plane that cuts none of it.
#[test]
fn the_near_plane_follows_the_eye() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let (lo, hi) = scene.bounds().unwrap();
    let framing = scene.framing_camera();
    let deep_gbuffer::Projection::Perspective { near, .. } = framing.projection else {
        panic!("perspective")
    };
    let inside = (lo + hi) * 0.5;
    assert!(scene.near_plane_from(inside) < near * 1e-2);
    assert!(scene.near_plane_from(inside) > 0.0);
    let above = Vec3::new(inside.x, hi.y + 2.0, inside.z);
    assert!((scene.near_plane_from(above) - 1.0).abs() < 1e-5, "half the way to the bounds");
}

/// `fit_camera` keeps the camera's direction and field of view and moves it until every vertex
/// of the scene projects inside the view, for wide, square and tall images; the engine's own
/// camera (a tight 18 degrees) cuts it off before.
#[test]
fn a_fitted_camera_sees_the_whole_scene() {
    let scene = Scene::load(&fixture("engine/2CylinderEngine.gltf")).unwrap();
    let inside = |camera: &deep_gbuffer::Camera, aspect: f32| {
        let m = camera.projection(aspect) * camera.view();
        scene.positions.iter().all(|p| {
            let c = m * p.extend(1.0);
            c.w > 0.0 && (c.x / c.w).abs() <= 1.0 && (c.y / c.w).abs() <= 1.0
        })
    };
    let own = scene.camera.clone().expect("the file has a camera");
    assert!(!inside(&own, 4.0 / 3.0), "the file's camera cuts the engine off");
    for aspect in [16.0 / 9.0, 1.0, 0.5] {
        let fitted = scene.fit_camera(&own, aspect);
        assert!(inside(&fitted, aspect), "aspect {aspect}");
        let (a, b) = (own.target - own.eye, fitted.target - fitted.eye);
        assert!(a.normalize().dot(b.normalize()) > 0.9999, "the direction stays");
        let fov = |c: &deep_gbuffer::Camera| match c.projection {
            deep_gbuffer::Projection::Perspective { fov_y_deg, .. } => fov_y_deg,
            _ => unreachable!("a perspective camera"),
        };
        assert_eq!(fov(&fitted), fov(&own), "the field of view stays");
        fitted.validate().unwrap();
    }
    // An orthographic camera widens its view instead of moving.
    let ortho = deep_gbuffer::Camera {
        projection: deep_gbuffer::Projection::Orthographic { height: 1.0, near: 0.1, far: 10.0 },
        ..own.clone()
    };
    for aspect in [16.0 / 9.0, 0.5] {
        let fitted = scene.fit_camera(&ortho, aspect);
        assert!(inside(&fitted, aspect), "orthographic, aspect {aspect}");
        fitted.validate().unwrap();
    }
}

/// glTF alpha modes: MASK with its cutoff (0.5 when the file gives none), BLEND, OPAQUE; a
/// negative cutoff is refused by the validation every upload and tracer runs.
#[test]
fn gltf_alpha_modes_are_read() {
    use deep_gbuffer::scene::AlphaMode;
    let dir = temp_dir("alpha-gltf");
    let with = |material: serde_json::Value| {
        let mut doc = triangle_gltf();
        doc["materials"] = serde_json::json!([material]);
        doc["meshes"][0]["primitives"][0]["material"] = 0.into();
        Scene::load(&write(&dir, "alpha.gltf", &doc.to_string()))
    };
    let mode = |m: serde_json::Value| with(m).unwrap().materials[0].alpha_mode;
    assert_eq!(
        mode(serde_json::json!({"alphaMode": "MASK", "alphaCutoff": 0.25})),
        AlphaMode::Mask { cutoff: 0.25 }
    );
    assert_eq!(mode(serde_json::json!({"alphaMode": "MASK"})), AlphaMode::Mask { cutoff: 0.5 });
    assert_eq!(mode(serde_json::json!({"alphaMode": "BLEND"})), AlphaMode::Blend);
    assert_eq!(mode(serde_json::json!({})), AlphaMode::Opaque);
    let loaded = with(serde_json::json!({"alphaMode": "BLEND"})).unwrap();
    assert!(loaded.warnings.iter().all(|w| !w.contains("alpha")), "{:?}", loaded.warnings);
    let negative = with(serde_json::json!({"alphaMode": "MASK", "alphaCutoff": -1.0})).unwrap();
    let refused = error_text(negative.validate().map(|()| negative.clone()));
    assert!(refused.contains("alpha cutoff"), "{refused}");
}
