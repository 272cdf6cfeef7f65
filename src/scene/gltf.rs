//! glTF 2.0 (`.gltf` and `.glb`, via the `gltf` crate): node transforms, every mesh and
//! primitive, metallic-roughness materials with base-colour textures, `KHR_lights_punctual`,
//! `KHR_materials_emissive_strength` and the first camera.
//!
//! Mirror reflectivity, which glTF does not have, is derived as `metallic * (1 - roughness)`.

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::khr_lights_punctual::Kind;
use gltf::mesh::Mode;

use super::{
    Camera, Light, LightKind, MAX_TEXTURE_SIDE, Material, MeshData, Projection, Scene, Texture,
};
use crate::{Error, Result};

/// Loads a `.gltf` or `.glb` file with its buffers and images.
pub fn load(path: &Path) -> Result<Scene> {
    precheck(path)?;
    // The `gltf` crate's validation can panic on some out-of-range indices; that is a malformed
    // file, not a crash.
    let imported = std::panic::catch_unwind(|| gltf::import(path)).map_err(|panic| {
        let message = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        Error::format(path, "glTF", format!("malformed document ({message})"))
    })?;
    let (doc, buffers, images) = imported.map_err(|e| match e {
        gltf::Error::Io(io) => Error::io(path, io),
        other => Error::format(path, "glTF", other.to_string()),
    })?;
    let mut scene = Scene::default();
    let mut image_textures: Vec<Option<u32>> = vec![None; images.len()];
    for m in doc.materials() {
        let name =
            m.name().map_or_else(|| format!("material {}", m.index().unwrap_or(0)), str::to_owned);
        let pbr = m.pbr_metallic_roughness();
        let base_color_texture = match pbr.base_color_texture() {
            Some(info) => {
                let image = info.texture().source().index();
                let data = images.get(image).ok_or_else(|| {
                    Error::format(
                        path,
                        format!("materials[`{name}`]"),
                        format!("image {image} missing"),
                    )
                })?;
                if image_textures[image].is_none() {
                    let tex = convert_image(data)
                        .map_err(|m| Error::format(path, format!("images[{image}]"), m))?;
                    scene.textures.push(tex);
                    image_textures[image] = Some(scene.textures.len() as u32 - 1);
                }
                image_textures[image]
            }
            None => None,
        };
        let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
        let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
        scene.materials.push(Material {
            name,
            base_color: Vec4::from(pbr.base_color_factor()),
            base_color_texture,
            emissive: Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0),
            roughness,
            metallic,
            reflectivity: metallic * (1.0 - roughness),
            double_sided: m.double_sided(),
        });
    }
    let default_material = scene.materials.len() as u32;
    let mut used_default = false;

    let Some(gscene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Err(Error::format(path, "scenes", "the file has no scene"));
    };
    let mut stack: Vec<(gltf::Node, Mat4)> = gscene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        stack.extend(node.children().map(|c| (c, world)));
        if let Some(mesh) = node.mesh() {
            let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
            for prim in mesh.primitives() {
                let location = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let positions: Vec<Vec3> = reader
                    .read_positions()
                    .ok_or_else(|| Error::format(path, &location, "no POSITION attribute"))?
                    .map(|p| world.transform_point3(Vec3::from(p)))
                    .collect();
                let normals: Vec<Vec3> = reader
                    .read_normals()
                    .map(|it| {
                        it.map(|n| (normal_matrix * Vec3::from(n)).normalize_or_zero()).collect()
                    })
                    .unwrap_or_default();
                let uvs: Vec<Vec2> = reader
                    .read_tex_coords(0)
                    .map(|t| t.into_f32().map(Vec2::from).collect())
                    .unwrap_or_default();
                let raw: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..positions.len() as u32).collect(),
                };
                let indices = match prim.mode() {
                    Mode::Triangles => raw,
                    Mode::TriangleStrip => (2..raw.len())
                        .flat_map(|i| {
                            if i % 2 == 0 {
                                [raw[i - 2], raw[i - 1], raw[i]]
                            } else {
                                [raw[i - 1], raw[i - 2], raw[i]]
                            }
                        })
                        .collect(),
                    Mode::TriangleFan => {
                        (2..raw.len()).flat_map(|i| [raw[0], raw[i - 1], raw[i]]).collect()
                    }
                    other => {
                        scene.warnings.push(format!(
                            "{location}: {other:?} primitive skipped (not triangles)"
                        ));
                        continue;
                    }
                };
                let material = match prim.material().index() {
                    Some(i) => i as u32,
                    None => {
                        used_default = true;
                        default_material
                    }
                };
                // A mirroring transform flips the winding.
                let indices = if world.determinant() < 0.0 {
                    indices.chunks_exact(3).flat_map(|t| [t[0], t[2], t[1]]).collect()
                } else {
                    indices
                };
                scene
                    .push_mesh(MeshData {
                        positions: &positions,
                        normals: &normals,
                        uvs: &uvs,
                        indices: &indices,
                        material,
                    })
                    .map_err(|e| Error::format(path, &location, e.to_string()))?;
            }
        }
        if let Some(light) = node.light() {
            let position = world.transform_point3(Vec3::ZERO);
            let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
            let kind = match light.kind() {
                Kind::Directional => LightKind::Directional { direction },
                Kind::Point => LightKind::Point { position, range: light.range() },
                Kind::Spot { inner_cone_angle, outer_cone_angle } => LightKind::Spot {
                    position,
                    direction,
                    range: light.range(),
                    inner_cone: inner_cone_angle,
                    outer_cone: outer_cone_angle,
                },
            };
            scene.lights.push(Light {
                name: light.name().map_or_else(|| format!("light{}", light.index()), str::to_owned),
                kind,
                color: Vec3::from(light.color()),
                intensity: light.intensity(),
                casts_shadows: true,
            });
        }
        if let (Some(cam), None) = (node.camera(), &scene.camera) {
            let eye = world.transform_point3(Vec3::ZERO);
            let forward = world.transform_vector3(Vec3::NEG_Z);
            let up = world.transform_vector3(Vec3::Y);
            let projection = match cam.projection() {
                gltf::camera::Projection::Perspective(p) => Projection::Perspective {
                    fov_y_deg: p.yfov().to_degrees(),
                    near: p.znear(),
                    far: p.zfar(),
                    reverse_z: false,
                },
                gltf::camera::Projection::Orthographic(o) => Projection::Orthographic {
                    height: 2.0 * o.ymag(),
                    near: o.znear(),
                    far: o.zfar(),
                },
            };
            scene.camera = Some(Camera { eye, target: eye + forward, up, projection });
        }
    }
    if used_default {
        scene.materials.push(Material::default());
    }
    Ok(scene)
}

fn check_side(width: u32, height: u32) -> std::result::Result<(), String> {
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(format!(
            "texture is {width}x{height}, larger than the {MAX_TEXTURE_SIDE} texel limit"
        ));
    }
    if width == 0 || height == 0 {
        return Err("texture has zero size".into());
    }
    Ok(())
}

fn convert_image(data: &gltf::image::Data) -> std::result::Result<Texture, String> {
    use gltf::image::Format as F;
    check_side(data.width, data.height)?;
    let p = &data.pixels;
    let u16s = |i: usize| (u16::from_le_bytes([p[2 * i], p[2 * i + 1]]) >> 8) as u8;
    let f32s = |i: usize| {
        let v = f32::from_le_bytes([p[4 * i], p[4 * i + 1], p[4 * i + 2], p[4 * i + 3]]);
        (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
    };
    let n = (data.width * data.height) as usize;
    let (channels, get): (usize, &dyn Fn(usize) -> u8) = match data.format {
        F::R8 => (1, &|i| p[i]),
        F::R8G8 => (2, &|i| p[i]),
        F::R8G8B8 => (3, &|i| p[i]),
        F::R8G8B8A8 => (4, &|i| p[i]),
        F::R16 => (1, &u16s),
        F::R16G16 => (2, &u16s),
        F::R16G16B16 => (3, &u16s),
        F::R16G16B16A16 => (4, &u16s),
        F::R32G32B32FLOAT => (3, &f32s),
        F::R32G32B32A32FLOAT => (4, &f32s),
    };
    let bytes_per = p.len() / n.max(1) / channels;
    if p.len() < n * channels * bytes_per || bytes_per == 0 {
        return Err(format!(
            "image data holds {} bytes, too few for {}x{}",
            p.len(),
            data.width,
            data.height
        ));
    }
    let mut rgba8 = Vec::with_capacity(n * 4);
    for i in 0..n {
        let c = |k: usize| get(i * channels + k);
        rgba8.extend_from_slice(&match channels {
            1 => [c(0), c(0), c(0), 255],
            2 => [c(0), c(0), c(0), c(1)],
            3 => [c(0), c(1), c(2), 255],
            _ => [c(0), c(1), c(2), c(3)],
        });
    }
    Ok(Texture { width: data.width, height: data.height, rgba8 })
}

/// Loads an image file (PNG or JPEG) as an sRGB RGBA8 texture, refusing oversized images.
pub(crate) fn load_texture_file(path: &Path) -> Result<Texture> {
    let reader = image::ImageReader::open(path).map_err(|e| Error::io(path, e))?;
    let reader = reader.with_guessed_format().map_err(|e| Error::io(path, e))?;
    let (w, h) =
        reader.into_dimensions().map_err(|e| Error::format(path, "image header", e.to_string()))?;
    check_side(w, h).map_err(|m| Error::format(path, "image", m))?;
    let img = image::open(path).map_err(|e| Error::format(path, "image", e.to_string()))?;
    let rgba = img.to_rgba8();
    Ok(Texture { width: rgba.width(), height: rgba.height(), rgba8: rgba.into_raw() })
}

/// Checks the mesh references the `gltf` crate's validation may index without checking
/// (attribute, index and material ids), so the error names the exact place.
/// A glTF URI is followed only if it is embedded data (`data:`) or a relative path that stays
/// inside the scene's folder: network addresses, other schemes, absolute paths and paths that
/// climb out with `..` (also percent-encoded) are refused before anything is read.
fn check_uri(uri: &str) -> std::result::Result<(), String> {
    if uri.starts_with("data:") {
        return Ok(());
    }
    let decoded = percent_decode(uri);
    let scheme = decoded.split_once(':').map(|(s, _)| s);
    if let Some(s) = scheme
        && s.len() > 1
        && s.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    {
        return Err(format!(
            "`{uri}`: a `{s}:` address is refused (only relative files and data: URIs)"
        ));
    }
    let windows_drive = decoded.len() >= 2 && decoded.as_bytes()[1] == b':';
    if decoded.starts_with('/') || decoded.starts_with('\\') || windows_drive {
        return Err(format!(
            "`{uri}`: an absolute path is refused (only paths inside the scene's folder)"
        ));
    }
    let mut depth = 0i32;
    for part in decoded.split(['/', '\\']) {
        match part {
            "" | "." => {}
            ".." => {
                depth -= 1;
                if depth < 0 {
                    return Err(format!("`{uri}` points outside the scene's folder: refused"));
                }
            }
            _ => depth += 1,
        }
    }
    Ok(())
}

/// `%XX` escapes decoded (invalid escapes kept as they are).
fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
        if bytes[i] == b'%'
            && let Some(v) = hex.and_then(|h| u8::from_str_radix(h, 16).ok())
        {
            out.push(v);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn precheck(path: &Path) -> Result<()> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let json_bytes: std::borrow::Cow<[u8]> = if bytes.starts_with(b"glTF") {
        match gltf::Glb::from_slice(&bytes) {
            Ok(glb) => glb.json.into_owned().into(),
            Err(e) => return Err(Error::format(path, "GLB header", e.to_string())),
        }
    } else {
        bytes.into()
    };
    // Syntax errors are left to the real parser, which names line and column.
    let Ok(doc) = serde_json::from_slice::<serde_json::Value>(&json_bytes) else { return Ok(()) };
    for key in ["buffers", "images"] {
        let list = doc.get(key).and_then(|v| v.as_array()).cloned().unwrap_or_default();
        for (i, item) in list.iter().enumerate() {
            if let Some(uri) = item.get("uri").and_then(|u| u.as_str()) {
                let at = || format!("{key}[{i}].uri");
                check_uri(uri).map_err(|m| Error::format(path, at(), m))?;
                if !uri.starts_with("data:") {
                    let folder = path.parent().unwrap_or(Path::new("."));
                    super::contained(folder, Path::new(&percent_decode(uri)))
                        .map_err(|m| Error::format(path, at(), format!("`{uri}` {m}")))?;
                }
            }
        }
    }
    let count = |key: &str| doc.get(key).and_then(|v| v.as_array()).map_or(0, Vec::len) as u64;
    let (accessors, materials) = (count("accessors"), count("materials"));
    let meshes = doc.get("meshes").and_then(|m| m.as_array()).cloned().unwrap_or_default();
    for (m, mesh) in meshes.iter().enumerate() {
        let prims = mesh.get("primitives").and_then(|p| p.as_array()).cloned().unwrap_or_default();
        for (p, prim) in prims.iter().enumerate() {
            let at = |what: &str| format!("meshes[{m}].primitives[{p}].{what}");
            let mut refs: Vec<(String, &serde_json::Value, u64)> = Vec::new();
            if let Some(attrs) = prim.get("attributes").and_then(|a| a.as_object()) {
                refs.extend(
                    attrs.iter().map(|(k, v)| (at(&format!("attributes.{k}")), v, accessors)),
                );
            }
            if let Some(v) = prim.get("indices") {
                refs.push((at("indices"), v, accessors));
            }
            if let Some(v) = prim.get("material") {
                refs.push((at("material"), v, materials));
            }
            for (location, value, len) in refs {
                match value.as_u64() {
                    Some(i) if i < len => {}
                    _ => {
                        return Err(Error::format(
                            path,
                            location,
                            format!("index {value} out of range (there are {len})"),
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}
