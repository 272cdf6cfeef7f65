//! Wavefront OBJ with MTL materials (via `tobj`). `Kd` is the base colour, `map_Kd` its texture,
//! `Ke` the emission, `Ns` the glossiness (turned into roughness) and `Ks` the mirror reflectivity.

use std::io::BufReader;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};

use super::{AlphaMode, Material, MeshData, Scene, Texture};
use crate::{Error, Result};

/// Loads an OBJ file and the MTL libraries it names (paths relative to the OBJ's folder),
/// within `limits`.
pub fn load(path: &Path, limits: &super::Limits) -> Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    // A byte-order mark would glue itself to the first keyword (and drop that line).
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mtl_dir = dir.clone();
    let scene = parse_within(text, path, &dir, limits, move |mtl: &Path| {
        let full = super::contained(&mtl_dir, mtl)
            .map_err(|m| Error::format(path, "mtllib", format!("`{}` {m}", mtl.display())))?;
        let text = std::fs::read_to_string(&full).map_err(|e| Error::io(&full, e))?;
        Ok((text.strip_prefix('\u{feff}').unwrap_or(&text).to_string(), full))
    })?;
    if scene.triangle_count() as u64 > limits.triangles {
        return Err(Error::format(
            path,
            "f",
            format!(
                "{} triangles exceed the limit of {}",
                scene.triangle_count(),
                limits.triangles
            ),
        ));
    }
    Ok(scene)
}

/// Parses OBJ text; `load_mtl` returns an MTL library's text and the path used in messages.
pub(crate) fn parse(
    text: &str,
    path: &Path,
    dir: &Path,
    load_mtl: impl Fn(&Path) -> Result<(String, PathBuf)>,
) -> Result<Scene> {
    parse_within(text, path, dir, &super::Limits::default(), load_mtl)
}

/// [`parse`] with `limits` on the textures' decoded texels.
fn parse_within(
    text: &str,
    path: &Path,
    dir: &Path,
    limits: &super::Limits,
    load_mtl: impl Fn(&Path) -> Result<(String, PathBuf)>,
) -> Result<Scene> {
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let mtl_error: std::cell::RefCell<Option<Error>> = std::cell::RefCell::new(None);
    let loaded = tobj::load_obj_buf(&mut BufReader::new(text.as_bytes()), &options, |mtl| {
        let (mtl_text, mtl_path) = match load_mtl(mtl) {
            Ok(found) => found,
            Err(e) => {
                *mtl_error.borrow_mut() = Some(e);
                return Err(tobj::LoadError::OpenFileFailed);
            }
        };
        let parsed = tobj::load_mtl_buf(&mut BufReader::new(mtl_text.as_bytes()));
        if let Err(e) = &parsed {
            let line = locate_error(&mtl_text, e);
            *mtl_error.borrow_mut() = Some(Error::format(&mtl_path, line, e.to_string()));
        }
        parsed
    });
    let (models, materials) = match loaded {
        Ok(found) => found,
        Err(e) => {
            return Err(mtl_error
                .take()
                .unwrap_or_else(|| Error::format(path, locate_error(text, &e), e.to_string())));
        }
    };
    if let Some(e) = mtl_error.take() {
        return Err(e);
    }
    let materials = materials.map_err(|e| Error::format(path, "mtllib", e.to_string()))?;

    let mut scene = Scene::default();
    let mut images = Images { loaded: Vec::new(), texels_left: limits.texels };
    for m in &materials {
        scene.materials.push(convert_material(m, dir, &mut scene.textures, &mut images)?);
    }
    let default_material = scene.materials.len() as u32;
    let mut used_default = false;
    for model in &models {
        let mesh = &model.mesh;
        let positions: Vec<Vec3> =
            mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let normals: Vec<Vec3> =
            mesh.normals.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let uvs: Vec<Vec2> =
            mesh.texcoords.chunks_exact(2).map(|p| Vec2::new(p[0], 1.0 - p[1])).collect();
        let material = match mesh.material_id {
            Some(id) if id < materials.len() => id as u32,
            _ => {
                used_default = true;
                default_material
            }
        };
        scene
            .push_mesh(MeshData {
                positions: &positions,
                normals: &normals,
                uvs: &uvs,
                indices: &mesh.indices,
                material,
                ..MeshData::default()
            })
            .map_err(|e| Error::format(path, format!("object `{}`", model.name), e.to_string()))?;
    }
    if used_default {
        scene.materials.push(Material::default());
    }
    Ok(scene)
}

/// The image files loaded so far (each decoded once) and the texels left in the budget.
struct Images {
    loaded: Vec<(PathBuf, u32)>,
    texels_left: u64,
}

fn convert_material(
    m: &tobj::Material,
    dir: &Path,
    textures: &mut Vec<Texture>,
    images: &mut Images,
) -> Result<Material> {
    let kd = m.diffuse.unwrap_or([0.8; 3]);
    let ks = m.specular.unwrap_or([0.0; 3]);
    let ke = m.emissive.unwrap_or([0.0; 3]);
    // Blinn-Phong exponent to perceptual roughness: alpha = sqrt(2 / (Ns + 2)), roughness = sqrt(alpha).
    let roughness = m.shininess.map_or(0.8, |ns| (2.0 / (ns.max(0.0) + 2.0)).sqrt().sqrt());
    let base_color_texture = match &m.diffuse_texture {
        Some(name) => {
            let file = super::contained(dir, Path::new(name)).map_err(|why| {
                Error::format(dir.join(name), format!("material `{}` map_Kd", m.name), why)
            })?;
            match images.loaded.iter().find(|(p, _)| *p == file) {
                Some((_, index)) => Some(*index),
                None => {
                    textures.push(super::gltf::load_texture_file(&file, &mut images.texels_left)?);
                    let index = textures.len() as u32 - 1;
                    images.loaded.push((file, index));
                    Some(index)
                }
            }
        }
        None => None,
    };
    // Opacity: `d`, or else `1 - Tr`; a material that lets light through is blended.
    let opacity = match (m.dissolve, m.unknown_param.get("Tr")) {
        (Some(d), _) => d,
        (None, Some(tr)) => {
            let tr = tr.split_whitespace().next().and_then(|t| t.parse::<f32>().ok());
            let Some(tr) = tr else {
                return Err(Error::InvalidScene(format!(
                    "material `{}`: Tr must be a number",
                    m.name
                )));
            };
            1.0 - tr
        }
        (None, None) => 1.0,
    };
    Ok(Material {
        name: m.name.clone(),
        base_color: Vec4::new(kd[0], kd[1], kd[2], opacity),
        alpha_mode: if opacity < 1.0 { AlphaMode::Blend } else { AlphaMode::Opaque },
        base_color_texture: base_color_texture.map(super::TextureRef::new),
        emissive: Vec3::from(ke),
        roughness,
        metallic: 0.0,
        reflectivity: ks[0].max(ks[1]).max(ks[2]).clamp(0.0, 1.0),
        double_sided: true,
        ..Material::default()
    })
}

/// Finds the line that `tobj` refused, so the message can name it (`line N`).
fn locate_error(text: &str, err: &tobj::LoadError) -> String {
    use tobj::LoadError as E;
    let floats = |rest: &str, min: usize| {
        let parts: Vec<&str> = rest.split_whitespace().collect();
        parts.len() >= min && parts.iter().all(|p| p.parse::<f32>().is_ok())
    };
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        let (key, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let bad = match (key, err) {
            ("v", E::PositionParseError) => !floats(rest, 3),
            ("vn", E::NormalParseError) => !floats(rest, 3),
            ("vt", E::TexcoordParseError) => !floats(rest, 1),
            ("Kd" | "Ka" | "Ks" | "Ke" | "Ns" | "d" | "Ni", E::MaterialParseError) => {
                !floats(rest, 1)
            }
            ("f", E::FaceParseError | E::InvalidPolygon) => {
                rest.split_whitespace().count() < 3
                    || rest
                        .split_whitespace()
                        .any(|v| v.split('/').next().is_none_or(|i| i.parse::<i64>().is_err()))
            }
            (
                "f",
                E::FaceVertexOutOfBounds | E::FaceTexCoordOutOfBounds | E::FaceNormalOutOfBounds,
            ) => rest.split_whitespace().any(|v| {
                v.split('/').zip([nv, nt, nn]).any(|(s, n)| match s.parse::<i64>() {
                    Ok(k) if k > 0 => k > n,
                    Ok(k) if k < 0 => -k > n,
                    Ok(_) => true,
                    Err(_) => false,
                })
            }),
            _ => false,
        };
        if bad {
            return format!("line {}", i + 1);
        }
        match key {
            "v" => nv += 1,
            "vt" => nt += 1,
            "vn" => nn += 1,
            _ => {}
        }
    }
    "file".into()
}
