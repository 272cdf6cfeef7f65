//! glTF 2.0 (`.gltf` and `.glb`, via the `gltf` crate): node transforms, every mesh and
//! primitive, the metallic-roughness material in full (base colour, metallic-roughness,
//! emissive, normal and occlusion textures, each with its sampler's wrap modes and
//! magnification filter, its coordinate set 0 or 1 and `KHR_texture_transform`), tangents (the
//! file's, or MikkTSpace's where a normal texture needs them), `KHR_lights_punctual`,
//! `KHR_materials_emissive_strength`, the alpha mode (`alphaMode`, `alphaCutoff`) and the first
//! camera. Coordinate sets above 1 and other extensions are named in one warning.
//!
//! Mirror reflectivity, which glTF does not have, is derived as `metallic * (1 - roughness)`.

use std::path::Path;

use glam::{Affine2, Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::khr_lights_punctual::Kind;
use gltf::mesh::Mode;

use super::{
    AlphaMode, Camera, Filter, Light, LightKind, Limits, MAX_TEXTURE_SIDE, Material, MeshData,
    Projection, Scene, Texture, TextureRef, Wrap,
};
use crate::{Error, Result};

thread_local! {
    /// Set while this thread runs [`catch_quietly`]'s closure.
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f`, catching a panic as an error value without the panic hook printing it. The hook
/// is wrapped once per process: the wrapper stays silent on a thread inside `catch_quietly` and
/// hands every other panic to the hook that was installed before it.
fn catch_quietly<R>(f: impl FnOnce() -> R) -> std::thread::Result<R> {
    static WRAP: std::sync::Once = std::sync::Once::new();
    WRAP.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(std::cell::Cell::get) {
                previous(info);
            }
        }));
    });
    // Nested catches leave the outer one quiet.
    let outer = QUIET.with(|q| q.replace(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(outer));
    result
}

/// The extensions the loader reads; any other the file uses is named in its warning.
const READ_EXTENSIONS: [&str; 3] =
    ["KHR_lights_punctual", "KHR_materials_emissive_strength", TRANSFORM];

const TRANSFORM: &str = "KHR_texture_transform";

/// `KHR_texture_transform` of one texture reference.
#[derive(Clone, Copy, Debug)]
struct Transform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    tex_coord: Option<u32>,
}

impl Default for Transform {
    /// No transform: the extension's defaults.
    fn default() -> Self {
        Transform { offset: [0.0; 2], rotation: 0.0, scale: [1.0; 2], tex_coord: None }
    }
}

impl Transform {
    /// From the extension's JSON (normal and occlusion references, which the `gltf` crate
    /// leaves as JSON); missing or malformed fields take their defaults.
    fn from_json(value: Option<&serde_json::Value>) -> Transform {
        let pair = |v: Option<&serde_json::Value>, default: [f32; 2]| {
            v.and_then(|v| v.as_array())
                .filter(|a| a.len() == 2)
                .and_then(|a| Some([a[0].as_f64()? as f32, a[1].as_f64()? as f32]))
                .unwrap_or(default)
        };
        let Some(v) = value else { return Transform::default() };
        Transform {
            offset: pair(v.get("offset"), [0.0; 2]),
            rotation: v.get("rotation").and_then(|r| r.as_f64()).unwrap_or(0.0) as f32,
            scale: pair(v.get("scale"), [1.0; 2]),
            tex_coord: v.get("texCoord").and_then(|t| t.as_u64()).map(|t| t.min(2) as u32),
        }
    }

    /// The affine map of the extension: translation x rotation x scale, the rotation turning
    /// coordinates counter-clockwise (its matrix's first column `(cos, sin)`).
    fn affine(&self) -> Affine2 {
        Affine2::from_scale_angle_translation(
            Vec2::from(self.scale),
            self.rotation,
            Vec2::from(self.offset),
        )
    }
}

/// A texture reference of a material: the texture, its coordinate set and transform.
struct Reference<'a> {
    texture: gltf::texture::Texture<'a>,
    tex_coord: u32,
    transform: Transform,
}

impl<'a> Reference<'a> {
    fn of(
        texture: gltf::texture::Texture<'a>,
        tex_coord: u32,
        transform: Option<&serde_json::Value>,
    ) -> Self {
        Reference { texture, tex_coord, transform: Transform::from_json(transform) }
    }

    fn of_info(info: gltf::texture::Info<'a>) -> Self {
        let transform = info.texture_transform().map_or(Transform::default(), |t| Transform {
            offset: t.offset(),
            rotation: t.rotation(),
            scale: t.scale(),
            tex_coord: t.tex_coord(),
        });
        Reference { texture: info.texture(), tex_coord: info.tex_coord(), transform }
    }

    /// The slot reading scene texture `texture` through coordinate set `tex_coord`, with the
    /// reference's sampler and transform.
    fn slot(&self, texture: u32, tex_coord: u32) -> TextureRef {
        use gltf::texture::{MagFilter, WrappingMode};
        let sampler = self.texture.sampler();
        let wrap = |w: WrappingMode| match w {
            WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
            WrappingMode::Repeat => Wrap::Repeat,
        };
        let transform = self.transform.affine();
        TextureRef {
            texture,
            wrap_s: wrap(sampler.wrap_s()),
            wrap_t: wrap(sampler.wrap_t()),
            filter: match sampler.mag_filter() {
                Some(MagFilter::Nearest) => Filter::Nearest,
                _ => Filter::Linear,
            },
            tex_coord,
            // A transform that is not finite is left out rather than refused.
            transform: if transform.is_finite() { transform } else { Affine2::IDENTITY },
        }
    }
}

/// Loads a `.gltf` or `.glb` file with its buffers and images.
pub fn load(path: &Path, limits: &Limits) -> Result<Scene> {
    // Read once: the checks and the parser see the same bytes, whatever happens to the file.
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    precheck(path, &bytes, limits)?;
    // The checks above cover what the `gltf` crate's validation and readers are known to panic
    // on; a panic left is a malformed file, not a crash.
    catch_quietly(|| read_document(path, &bytes, limits)).unwrap_or_else(|panic| {
        let message = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        Err(Error::format(path, "glTF", format!("malformed document ({message})")))
    })
}

/// Parses the checked `bytes` of the file at `path` (its folder holds the buffers and images)
/// into a scene.
fn read_document(path: &Path, bytes: &[u8], limits: &Limits) -> Result<Scene> {
    let gltf_error = |e: gltf::Error| match e {
        gltf::Error::Io(io) => Error::io(path, io),
        other => Error::format(path, "glTF", other.to_string()),
    };
    let gltf::Gltf { document: doc, blob } = gltf::Gltf::from_slice(bytes).map_err(gltf_error)?;
    let buffers = gltf::import_buffers(&doc, path.parent(), blob).map_err(gltf_error)?;
    let mut scene = Scene::default();
    // Images are decoded once each, only for materials a primitive uses, and only after their
    // header's size fits what is left of the texel budget.
    let used: std::collections::HashSet<usize> = doc
        .meshes()
        .flat_map(|m| m.primitives().filter_map(|p| p.material().index()).collect::<Vec<_>>())
        .collect();
    let mut image_textures: Vec<Option<u32>> = vec![None; doc.images().len()];
    let mut texels_left = limits.texels;
    // What the file uses that the renderer does not read, with how many materials use each.
    let mut unread: std::collections::BTreeMap<String, usize> = Default::default();
    for ext in doc.extensions_used().filter(|e| !READ_EXTENSIONS.contains(e)) {
        unread.insert(format!("the extension {ext}"), 0);
    }
    let mut coordinate_sets_above_1 = 0;
    for m in doc.materials() {
        let name =
            m.name().map_or_else(|| format!("material {}", m.index().unwrap_or(0)), str::to_owned);
        let pbr = m.pbr_metallic_roughness();
        let in_use = m.index().is_some_and(|i| used.contains(&i));
        // Each image is decoded once, whichever slots and materials use it.
        let mut slot = |reference: Option<Reference<'_>>| -> Result<Option<TextureRef>> {
            let Some(reference) = reference.filter(|_| in_use) else { return Ok(None) };
            let image = reference.texture.source();
            let i = image.index();
            if image_textures[i].is_none() {
                let at = format!("images[{i}]");
                let tex = load_image(path, &image, &buffers, &mut texels_left)
                    .map_err(|m| Error::format(path, &at, m))?;
                scene.textures.push(tex);
                image_textures[i] = Some(scene.textures.len() as u32 - 1);
            }
            let Some(texture) = image_textures[i] else { return Ok(None) };
            let mut tex_coord = reference.transform.tex_coord.unwrap_or(reference.tex_coord);
            if tex_coord > 1 {
                coordinate_sets_above_1 += 1;
                tex_coord = 0;
            }
            Ok(Some(reference.slot(texture, tex_coord)))
        };
        let base_color_texture = slot(pbr.base_color_texture().map(Reference::of_info))?;
        let emissive_texture = slot(m.emissive_texture().map(Reference::of_info))?;
        let metallic_roughness_texture =
            slot(pbr.metallic_roughness_texture().map(Reference::of_info))?;
        let normal = m.normal_texture();
        let normal_texture = slot(
            normal
                .as_ref()
                .map(|t| Reference::of(t.texture(), t.tex_coord(), t.extension_value(TRANSFORM))),
        )?;
        let occlusion = m.occlusion_texture();
        let occlusion_texture = slot(
            occlusion
                .as_ref()
                .map(|t| Reference::of(t.texture(), t.tex_coord(), t.extension_value(TRANSFORM))),
        )?;
        let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
        let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
        scene.materials.push(Material {
            name,
            base_color: Vec4::from(pbr.base_color_factor()),
            base_color_texture,
            emissive: Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0),
            emissive_texture,
            roughness,
            metallic,
            metallic_roughness_texture,
            normal_texture,
            normal_scale: normal.as_ref().map_or(1.0, |t| t.scale()),
            occlusion_texture,
            occlusion_strength: occlusion.as_ref().map_or(1.0, |t| t.strength().clamp(0.0, 1.0)),
            reflectivity: metallic * (1.0 - roughness),
            double_sided: m.double_sided(),
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => {
                    AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) }
                }
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
        });
    }
    if coordinate_sets_above_1 > 0 {
        unread.insert("texture coordinate sets above 1 (read as set 0)".into(), 0);
    }
    if !unread.is_empty() {
        let list: Vec<String> = unread
            .iter()
            .map(|(w, n)| if *n > 0 { format!("{w} ({n})") } else { w.clone() })
            .collect();
        scene.warnings.push(format!(
            "the file uses what the renderer does not read (rendered without it): {}",
            list.join(", ")
        ));
    }
    let default_material = scene.materials.len() as u32;
    let mut used_default = false;

    let Some(gscene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Err(Error::format(path, "scenes", "the file has no scene"));
    };
    let mut stack: Vec<(gltf::Node, Mat4)> = gscene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut instances = 0u64;
    while let Some((node, parent)) = stack.pop() {
        instances += 1;
        if instances > limits.instances {
            return Err(Error::format(path, "nodes", "more node instances than the limit"));
        }
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
                let uvs1: Vec<Vec2> = reader
                    .read_tex_coords(1)
                    .map(|t| t.into_f32().map(Vec2::from).collect())
                    .unwrap_or_default();
                // A mirroring transform turns the bitangent: the sign follows the determinant.
                let handedness = world.determinant().signum();
                let tangents: Vec<Vec4> = reader
                    .read_tangents()
                    .map(|it| {
                        it.map(|t| {
                            let v = (Mat3::from_mat4(world) * Vec3::new(t[0], t[1], t[2]))
                                .normalize_or_zero();
                            v.extend(if t[3] < 0.0 { -handedness } else { handedness })
                        })
                        .collect()
                    })
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
                if scene.triangle_count() as u64 + indices.len() as u64 / 3 > limits.triangles {
                    return Err(Error::format(
                        path,
                        &location,
                        format!("the scene's triangles exceed the limit of {}", limits.triangles),
                    ));
                }
                // A normal texture without tangents in the file: MikkTSpace's, from the
                // coordinate set the texture reads (else each triangle's own frame is used).
                let normal_set = scene
                    .materials
                    .get(material as usize)
                    .and_then(|m| m.normal_texture)
                    .map(|t| t.tex_coord);
                let mut v =
                    super::tangents::Vertices { positions, normals, uvs: [uvs, uvs1], tangents };
                let mut indices = indices;
                if let Some(set) = normal_set.filter(|_| v.tangents.is_empty())
                    && let Ok(Some(welded)) =
                        catch_quietly(|| super::tangents::generate(&v, &indices, set as usize))
                {
                    (v, indices) = welded;
                }
                scene
                    .push_mesh(MeshData {
                        positions: &v.positions,
                        normals: &v.normals,
                        uvs: &v.uvs[0],
                        uvs1: &v.uvs[1],
                        tangents: &v.tangents,
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
            scene.camera = Some(Camera {
                eye,
                target: eye + forward,
                up,
                projection,
                lens: Default::default(),
            });
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

/// Decodes glTF image `image` (from a buffer view, a `data:` URI or a file in the scene's
/// folder) once its header's size is checked against `MAX_TEXTURE_SIDE` and `texels_left`.
fn load_image(
    path: &Path,
    image: &gltf::Image,
    buffers: &[gltf::buffer::Data],
    texels_left: &mut u64,
) -> std::result::Result<Texture, String> {
    let bytes: std::borrow::Cow<[u8]> = match image.source() {
        gltf::image::Source::View { view, .. } => {
            let data = buffers.get(view.buffer().index()).ok_or("its buffer is missing")?;
            let range = view.offset()..view.offset().saturating_add(view.length());
            data.get(range).ok_or("its buffer view lies outside the buffer")?.into()
        }
        gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
            Some(rest) => {
                let (_, encoded) =
                    rest.split_once(";base64,").ok_or("a data: URI without base64")?;
                base64::decode(encoded).map_err(|e| format!("data: URI: {e}"))?.into()
            }
            None => {
                let folder = path.parent().unwrap_or(Path::new("."));
                let file = super::contained(folder, Path::new(&percent_decode(uri)))
                    .map_err(|m| format!("`{uri}` {m}"))?;
                std::fs::read(&file).map_err(|e| format!("{}: {e}", file.display()))?.into()
            }
        },
    };
    decode_texture(&bytes, texels_left)
}

/// Decodes an encoded image (PNG or JPEG) as an sRGB RGBA8 texture once its header's size is
/// checked against `MAX_TEXTURE_SIDE` and taken from `texels_left`.
fn decode_texture(bytes: &[u8], texels_left: &mut u64) -> std::result::Result<Texture, String> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let (w, h) = reader.into_dimensions().map_err(|e| format!("image header: {e}"))?;
    check_side(w, h)?;
    take_texels(w, h, texels_left)?;
    let decoded = image::load_from_memory(bytes).map_err(|e| e.to_string())?;
    let rgba = decoded.to_rgba8();
    Ok(Texture { width: rgba.width(), height: rgba.height(), rgba8: rgba.into_raw() })
}

/// Takes a `w` x `h` image's texels from what is left of the decoded-texel budget.
fn take_texels(w: u32, h: u32, texels_left: &mut u64) -> std::result::Result<(), String> {
    let texels = u64::from(w) * u64::from(h);
    if texels > *texels_left {
        return Err(format!(
            "{w}x{h} texels exceed what is left of the decoded-texel limit ({texels_left})"
        ));
    }
    *texels_left -= texels;
    Ok(())
}

/// Loads an image file (PNG or JPEG) as an sRGB RGBA8 texture, refusing oversized images and
/// images over what is left of the texel budget, from the header, before decoding.
pub(crate) fn load_texture_file(path: &Path, texels_left: &mut u64) -> Result<Texture> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    decode_texture(&bytes, texels_left).map_err(|m| Error::format(path, "image", m))
}

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

fn precheck(path: &Path, bytes: &[u8], limits: &Limits) -> Result<()> {
    let json_bytes: std::borrow::Cow<[u8]> = if bytes.starts_with(b"glTF") {
        match gltf::Glb::from_slice(bytes) {
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
            // The `gltf` crate unwraps an image's source: a URI, or a buffer view with its MIME
            // type (as the specification requires).
            if key == "images" {
                let has = |k: &str| item.get(k).is_some_and(|v| !v.is_null());
                let at = || format!("images[{i}]");
                if !has("uri") && !has("bufferView") {
                    return Err(Error::format(path, at(), "neither a uri nor a bufferView"));
                }
                if has("bufferView") && !has("mimeType") {
                    return Err(Error::format(path, at(), "a bufferView without its mimeType"));
                }
            }
            if let Some(uri) = item.get("uri").and_then(|u| u.as_str()) {
                let at = || format!("{key}[{i}].uri");
                check_uri(uri).map_err(|m| Error::format(path, at(), m))?;
                // Images are looked up when a used material needs them (`load_image`).
                if key == "buffers" && !uri.starts_with("data:") {
                    let folder = path.parent().unwrap_or(Path::new("."));
                    super::contained(folder, Path::new(&percent_decode(uri)))
                        .map_err(|m| Error::format(path, at(), format!("`{uri}` {m}")))?;
                }
            }
        }
    }
    check_document(&doc, limits).map_err(|(at, m)| Error::format(path, at, m))?;
    Ok(())
}

/// The JSON array `key` of `v` (empty when absent or not an array).
fn list<'a>(v: &'a serde_json::Value, key: &str) -> &'a [serde_json::Value] {
    v.get(key).and_then(|v| v.as_array()).map_or(&[], Vec::as_slice)
}

/// Bytes of one component of glTF component type `t`.
fn component_bytes(t: u64) -> Option<u64> {
    match t {
        5120 | 5121 => Some(1),
        5122 | 5123 => Some(2),
        5125 | 5126 => Some(4),
        _ => None,
    }
}

/// Components of glTF accessor type `t`.
fn type_components(t: &str) -> Option<u64> {
    Some(match t {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        "MAT4" => 16,
        _ => return None,
    })
}

/// What the loader reads of an accessor used as `semantic`: the component types and the type
/// it accepts.
fn accepted(semantic: &str) -> Option<(&'static [u64], &'static str)> {
    Some(match semantic {
        "indices" => (&[5121, 5123, 5125], "SCALAR"),
        "POSITION" | "NORMAL" => (&[5126], "VEC3"),
        "TEXCOORD_0" | "TEXCOORD_1" => (&[5126, 5121, 5123], "VEC2"),
        "TANGENT" => (&[5126], "VEC4"),
        _ => return None,
    })
}

/// Checks, before the `gltf` crate reads anything, what its readers would otherwise panic on or
/// allocate without bound: the accessors the loader reads (component type, type, normalized
/// flag, stride, that the data lies inside its buffer view, counts within `limits`), sparse
/// accessors, camera objects, and the node graph (no node reached twice on one path; instances
/// within `limits`). Errors are (where, what).
fn check_document(
    doc: &serde_json::Value,
    limits: &Limits,
) -> std::result::Result<(), (String, String)> {
    let accessors = list(doc, "accessors");
    let views = list(doc, "bufferViews");
    let uint = |v: &serde_json::Value, key: &str| v.get(key).and_then(serde_json::Value::as_u64);
    let check_accessor = |a: u64, semantic: &str| -> std::result::Result<(), String> {
        let Some(acc) = accessors.get(a as usize) else { return Ok(()) };
        let ctype = uint(acc, "componentType").unwrap_or(0);
        let ty = acc.get("type").and_then(|t| t.as_str()).unwrap_or("");
        let (Some(cbytes), Some(n)) = (component_bytes(ctype), type_components(ty)) else {
            return Err(format!("accessors[{a}]: component type {ctype} or type `{ty}` unknown"));
        };
        if let Some((types, want)) = accepted(semantic) {
            if !types.contains(&ctype) || ty != want {
                return Err(format!(
                    "accessors[{a}] ({semantic}) is {ty} of component type {ctype}; {semantic} needs {want} of {types:?}"
                ));
            }
            let normalized = acc.get("normalized").and_then(|v| v.as_bool()).unwrap_or(false);
            if semantic.starts_with("TEXCOORD") && ctype != 5126 && !normalized {
                return Err(format!("accessors[{a}] ({semantic}) of integers must be normalized"));
            }
        }
        let count = uint(acc, "count").unwrap_or(0);
        let most = if semantic == "indices" { limits.triangles * 3 } else { limits.vertices };
        if count > most {
            return Err(format!("accessors[{a}] has {count} elements, over the limit of {most}"));
        }
        let element = cbytes * n;
        if let Some(v) = uint(acc, "bufferView") {
            let Some(view) = views.get(v as usize) else {
                return Err(format!("accessors[{a}]: bufferView {v} does not exist"));
            };
            let stride = uint(view, "byteStride").unwrap_or(element);
            if stride < element {
                return Err(format!(
                    "bufferViews[{v}]: byteStride {stride} is smaller than an element of accessors[{a}] ({element} bytes)"
                ));
            }
            let offset = uint(acc, "byteOffset").unwrap_or(0);
            let length = uint(view, "byteLength").unwrap_or(0);
            let end = count.checked_sub(1).map_or(Some(0), |last| {
                last.checked_mul(stride)?.checked_add(offset)?.checked_add(element)
            });
            if end.is_none_or(|end| end > length) {
                return Err(format!(
                    "accessors[{a}]: {count} elements of {element} bytes (stride {stride}, offset {offset}) do not fit bufferViews[{v}] ({length} bytes)"
                ));
            }
        }
        if let Some(sparse) = acc.get("sparse") {
            let n = uint(sparse, "count").unwrap_or(0);
            if n > count {
                return Err(format!("accessors[{a}]: sparse count {n} exceeds count {count}"));
            }
        }
        Ok(())
    };
    let materials = list(doc, "materials").len() as u64;
    for (m, mesh) in list(doc, "meshes").iter().enumerate() {
        for (p, prim) in list(mesh, "primitives").iter().enumerate() {
            let at = format!("meshes[{m}].primitives[{p}]");
            // (semantic, the index, how many there are): attributes and indices name
            // accessors, checked as the loader reads them; the material only by range.
            let mut refs: Vec<(String, &serde_json::Value, u64)> = Vec::new();
            if let Some(attrs) = prim.get("attributes").and_then(|a| a.as_object()) {
                refs.extend(attrs.iter().map(|(k, v)| (k.clone(), v, accessors.len() as u64)));
            }
            if let Some(v) = prim.get("indices") {
                refs.push(("indices".into(), v, accessors.len() as u64));
            }
            if let Some(v) = prim.get("material") {
                refs.push(("material".into(), v, materials));
            }
            for (semantic, value, len) in refs {
                let field = if matches!(semantic.as_str(), "indices" | "material") {
                    semantic.clone()
                } else {
                    format!("attributes.{semantic}")
                };
                let index = value.as_u64().filter(|i| *i < len).ok_or_else(|| {
                    (
                        format!("{at}.{field}"),
                        format!("index {value} out of range (there are {len})"),
                    )
                })?;
                if semantic != "material" {
                    check_accessor(index, &semantic).map_err(|e| (at.clone(), e))?;
                }
            }
        }
    }
    for (c, cam) in list(doc, "cameras").iter().enumerate() {
        let ty = cam.get("type").and_then(|t| t.as_str()).unwrap_or("");
        if !matches!(ty, "perspective" | "orthographic") || cam.get(ty).is_none() {
            return Err((
                format!("cameras[{c}]"),
                format!("type `{ty}` without its `{ty}` object (perspective or orthographic)"),
            ));
        }
    }
    check_nodes(doc, limits)
}

/// The node graph: every node reached from a scene is reached on no path twice (no cycle), and
/// the instances (one per path from a scene root) stay within `limits`.
fn check_nodes(
    doc: &serde_json::Value,
    limits: &Limits,
) -> std::result::Result<(), (String, String)> {
    let nodes = list(doc, "nodes");
    let children: Vec<Vec<usize>> = nodes
        .iter()
        .map(|n| {
            list(n, "children")
                .iter()
                .filter_map(serde_json::Value::as_u64)
                .map(|c| c as usize)
                .filter(|c| *c < nodes.len())
                .collect()
        })
        .collect();
    // Instances below each node (itself included), saturating; a node met again while its own
    // subtree is open closes a cycle.
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        New,
        Open,
        Done(u64),
    }
    let mut state = vec![State::New; nodes.len()];
    let mut stack: Vec<(usize, usize)> = Vec::new();
    for root in 0..nodes.len() {
        if state[root] != State::New {
            continue;
        }
        state[root] = State::Open;
        stack.push((root, 0));
        while let Some(&mut (node, ref mut next)) = stack.last_mut() {
            if let Some(&child) = children[node].get(*next) {
                *next += 1;
                match state[child] {
                    State::Open => {
                        return Err((
                            format!("nodes[{child}]"),
                            "is its own ancestor (the node graph has a cycle)".into(),
                        ));
                    }
                    State::New => {
                        state[child] = State::Open;
                        stack.push((child, 0));
                    }
                    State::Done(_) => {}
                }
            } else {
                let below = children[node].iter().fold(1u64, |sum, c| match state[*c] {
                    State::Done(n) => sum.saturating_add(n),
                    _ => sum,
                });
                state[node] = State::Done(below);
                stack.pop();
            }
        }
    }
    let scenes = list(doc, "scenes");
    for (s, scene) in scenes.iter().enumerate() {
        let total = list(scene, "nodes")
            .iter()
            .filter_map(serde_json::Value::as_u64)
            .filter_map(|n| match state.get(n as usize) {
                Some(State::Done(k)) => Some(*k),
                _ => None,
            })
            .fold(0u64, u64::saturating_add);
        if total > limits.instances {
            return Err((
                format!("scenes[{s}]"),
                format!("instances {total} nodes, over the limit of {}", limits.instances),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    /// Run in a child process of the test binary (the panic hook is process-wide): a panic
    /// caught by `catch_quietly` prints nothing (also after a nested catch has ended), and a
    /// later uncaught panic on another thread still reaches the hook that was installed before.
    #[test]
    fn a_caught_panic_is_not_printed() {
        const CHILD: &str = "DEEP_GBUFFER_QUIET_PANIC_CHILD";
        if std::env::var_os(CHILD).is_some() {
            let caught = super::catch_quietly(|| panic!("caught quietly"));
            assert!(caught.is_err());
            let nested = super::catch_quietly(|| {
                assert!(super::catch_quietly(|| panic!("caught quietly, inner")).is_err());
                panic!("caught quietly, outer")
            });
            assert!(nested.is_err());
            let loud = std::thread::spawn(|| panic!("printed as usual")).join();
            assert!(loud.is_err());
            return;
        }
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--exact", "scene::gltf::tests::a_caught_panic_is_not_printed", "--nocapture"])
            .env(CHILD, "1")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        assert!(!stderr.contains("caught quietly"), "{stderr}");
        assert!(stderr.contains("printed as usual"), "{stderr}");
    }
}
