//! The CPU scene model: one flattened triangle list with per-triangle materials, lights and a
//! camera. Loaders ([`gltf`], [`obj`]) and built-in scenes ([`builtin`]) produce it; [`upload`]
//! turns it into [`SceneBuffers`](crate::SceneBuffers) on the GPU.

pub mod builtin;
pub mod camera;
pub mod gltf;
pub mod lighting;
pub mod obj;
mod tangents;
pub mod upload;

use std::path::{Path, PathBuf};

use glam::{Affine2, Vec2, Vec3, Vec4};

pub use camera::{Camera, Lens, Projection};
pub use lighting::{GpuLight, SceneInfo};

use crate::{Error, Result};

/// Largest texture side accepted from a scene file.
pub const MAX_TEXTURE_SIDE: u32 = 8192;

/// How a texture's coordinates outside [0, 1] are read, per axis (glTF's sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// The texture tiles.
    #[default]
    Repeat,
    /// The edge texel continues.
    ClampToEdge,
    /// The texture tiles, every other tile mirrored.
    MirroredRepeat,
}

/// How texels are filtered: glTF's magnification filter (the renderer keeps no mip levels, so
/// a minifying read filters the same way).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    /// Bilinear between the four nearest texels.
    #[default]
    Linear,
    /// The nearest texel.
    Nearest,
}

/// How a material reads one of its textures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`Scene::textures`].
    pub texture: u32,
    /// Wrap mode across u (`s`).
    pub wrap_s: Wrap,
    /// Wrap mode across v (`t`).
    pub wrap_t: Wrap,
    /// Texel filter.
    pub filter: Filter,
    /// Which texture coordinate set: 0 ([`Scene::uvs`]) or 1 ([`Scene::uvs1`]).
    pub tex_coord: u32,
    /// Applied to the coordinates before the lookup (`KHR_texture_transform`: translation x
    /// rotation x scale); identity by default.
    pub transform: Affine2,
}

impl TextureRef {
    /// Texture `texture` read repeating and bilinear through coordinate set 0, untransformed.
    pub fn new(texture: u32) -> TextureRef {
        TextureRef {
            texture,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            filter: Filter::Linear,
            tex_coord: 0,
            transform: Affine2::IDENTITY,
        }
    }
}

/// How a material's opacity (base colour alpha times the base-colour texture's alpha) is used:
/// glTF's `alphaMode`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Opacity ignored: the surface is solid.
    #[default]
    Opaque,
    /// Alpha test: where the opacity is below `cutoff` the surface is a hole (in both G-buffer
    /// layers, the shadow maps and the ground truth); elsewhere it is solid.
    Mask {
        /// The opacity below which the surface is cut away (glTF `alphaCutoff`, default 0.5).
        cutoff: f32,
    },
    /// Blended: the surface stays out of the opaque layers and the shadow maps; the nearest
    /// [`TransparencySettings::layers`](crate::TransparencySettings) blended surfaces in front of
    /// the opaque ones are peeled, shaded and composited over them (`C = a C_surface + (1 - a)
    /// C_behind`).
    Blend,
}

/// A surface material (the glTF 2.0 metallic-roughness model).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name from the file, for messages.
    pub name: String,
    /// Linear base colour (rgb) and opacity (a).
    pub base_color: Vec4,
    /// The base-colour texture (sRGB encoded; multiplies `base_color`), if any.
    pub base_color_texture: Option<TextureRef>,
    /// Emitted radiance, linear rgb.
    pub emissive: Vec3,
    /// The emissive texture (sRGB encoded; multiplies `emissive`), if any.
    pub emissive_texture: Option<TextureRef>,
    /// The metallic-roughness texture (linear; green multiplies `roughness`, blue `metallic`),
    /// if any. With one, the reflectivity is taken per texel as metallic x (1 - roughness), the
    /// rule glTF materials follow.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// The tangent-space normal texture (linear, `2 c - 1` per channel), if any. It turns the
    /// interpolated normal in the frame of the vertex tangents ([`Scene::tangents`]; where a
    /// vertex has none, the triangle's own texture-space frame).
    pub normal_texture: Option<TextureRef>,
    /// Scales the normal texture's x and y (glTF `normalTexture.scale`).
    pub normal_scale: f32,
    /// The occlusion texture (linear, red channel), if any: it multiplies the light a surface
    /// reflects diffusely from indirect light (the gathered radiosity and the ambient term,
    /// which the ambient obscurance darkens too) by `1 + strength (red - 1)`, as glTF asks;
    /// direct light is left as it is. The ground truth applies it to its indirect bounce.
    pub occlusion_texture: Option<TextureRef>,
    /// How strongly the occlusion texture applies, in [0, 1] (glTF `occlusionTexture.strength`).
    pub occlusion_strength: f32,
    /// Perceptual roughness in [0, 1].
    pub roughness: f32,
    /// Metalness in [0, 1].
    pub metallic: f32,
    /// Mirror reflectivity in [0, 1] (how much a screen-space reflection contributes; a metal
    /// tints what it reflects by its base colour as far as it is metallic).
    pub reflectivity: f32,
    /// Both faces are visible; otherwise back faces are culled.
    pub double_sided: bool,
    /// How the opacity (`base_color.w` times the base-colour texture's alpha) is used.
    pub alpha_mode: AlphaMode,
}

impl Material {
    /// The texture slots in the order the GPU material holds them (base colour, emissive,
    /// metallic-roughness, normal, occlusion).
    pub fn texture_slots(&self) -> [Option<TextureRef>; 5] {
        [
            self.base_color_texture,
            self.emissive_texture,
            self.metallic_roughness_texture,
            self.normal_texture,
            self.occlusion_texture,
        ]
    }
}

/// `name` (a path a scene file gives, relative to its `folder`) as a file that may be read: it
/// must be relative, stay inside `folder` once every link is followed, and be a regular file (not
/// a folder, device or pipe). The error says why, for a message after the name.
pub(crate) fn contained(folder: &Path, name: &Path) -> std::result::Result<PathBuf, String> {
    if name.is_absolute() || name.has_root() {
        return Err("is an absolute path: only files inside the scene's folder are read".into());
    }
    // A scene given as a bare file name lies in the working folder.
    let folder = if folder.as_os_str().is_empty() { Path::new(".") } else { folder };
    let root = folder
        .canonicalize()
        .map_err(|e| format!("cannot be looked up: the scene's folder: {e}"))?;
    let file = root.join(name).canonicalize().map_err(|e| format!("cannot be opened: {e}"))?;
    if !file.starts_with(&root) {
        return Err("leads outside the scene's folder (through `..` or a link): refused".into());
    }
    let meta = std::fs::metadata(&file).map_err(|e| format!("cannot be opened: {e}"))?;
    if !meta.is_file() {
        return Err("is not a regular file (a folder, device or pipe): refused".into());
    }
    Ok(file)
}

/// What a scene file may make the loaders allocate. Counts read from a file are checked against
/// these before anything of that size is allocated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Vertices (and index-buffer elements / 3 as triangles) an accessor may declare.
    pub vertices: u64,
    /// Triangles over the whole scene, every instance counted.
    pub triangles: u64,
    /// Node instances: a node counts once per path from a scene root to it.
    pub instances: u64,
    /// Texels decoded over all textures, counted from each image's header before decoding.
    pub texels: u64,
}

impl Default for Limits {
    /// 50 million vertices and triangles, a million node instances, 2^28 texels (1 GiB as RGBA8).
    fn default() -> Self {
        Limits {
            vertices: 50_000_000,
            triangles: 50_000_000,
            instances: 1_000_000,
            texels: 1 << 28,
        }
    }
}

/// The largest radiance a light (colour x intensity), an emissive material or the ambient term
/// may have. A point light's intensity grows with the square of the scene's scale (the hard-case
/// suite draws the Cornell box at 1e5 with 4e10); every product a frame forms from these (the
/// inverse-square falloff, the largest GGX lobe, sums over lights, the radiosity's bounded
/// feedback) then stays inside f32's 3.4e38, so every buffer stays finite.
pub const MAX_RADIANCE: f32 = 1e20;

impl Material {
    /// Checks the factors: colour, roughness, metallic, reflectivity and occlusion strength
    /// finite in [0, 1], emission finite, >= 0 and at most [`MAX_RADIANCE`], a finite normal
    /// scale; texture slots read coordinate set 0 or 1 through finite transforms.
    pub fn validate(&self) -> Result<()> {
        let bad =
            |what: &str| Err(Error::InvalidScene(format!("material `{}`: {what}", self.name)));
        let unit = |v: f32| (0.0..=1.0).contains(&v);
        if !self.base_color.to_array().into_iter().all(unit) {
            return bad(&format!("base colour {} must lie in [0, 1]", self.base_color));
        }
        for (name, v) in [
            ("roughness", self.roughness),
            ("metallic", self.metallic),
            ("reflectivity", self.reflectivity),
            ("occlusion strength", self.occlusion_strength),
        ] {
            if !unit(v) {
                return bad(&format!("{name} {v} must lie in [0, 1]"));
            }
        }
        if !self.emissive.to_array().into_iter().all(|v| (0.0..=MAX_RADIANCE).contains(&v)) {
            return bad(&format!(
                "emission {} must be finite, >= 0 and at most {MAX_RADIANCE:e}",
                self.emissive
            ));
        }
        if let AlphaMode::Mask { cutoff } = self.alpha_mode
            && !(cutoff.is_finite() && cutoff >= 0.0)
        {
            return bad(&format!("alpha cutoff {cutoff} must be finite and >= 0"));
        }
        if !self.normal_scale.is_finite() {
            return bad(&format!("normal scale {} must be finite", self.normal_scale));
        }
        for slot in self.texture_slots().into_iter().flatten() {
            if slot.tex_coord > 1 {
                return bad(&format!(
                    "texture coordinate set {} (sets 0 and 1 are read)",
                    slot.tex_coord
                ));
            }
            if !slot.transform.is_finite() {
                return bad("a texture transform that is not finite");
            }
        }
        Ok(())
    }
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
            base_color_texture: None,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            roughness: 0.8,
            metallic: 0.0,
            reflectivity: 0.0,
            double_sided: false,
            alpha_mode: AlphaMode::Opaque,
        }
    }
}

/// An RGBA8 texture, sRGB encoded, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba8: Vec<u8>,
}

/// What kind of light, with its geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Parallel light travelling along `direction`.
    Directional {
        /// Direction the light travels (from the light into the scene).
        direction: Vec3,
    },
    /// Light from a point, fading to zero at `range` (infinite when `None`).
    Point {
        /// Position.
        position: Vec3,
        /// Range.
        range: Option<f32>,
    },
    /// A cone of light.
    Spot {
        /// Position.
        position: Vec3,
        /// Direction the cone points.
        direction: Vec3,
        /// Range.
        range: Option<f32>,
        /// Inner cone angle in radians (full intensity inside).
        inner_cone: f32,
        /// Outer cone angle in radians (zero outside).
        outer_cone: f32,
    },
}

/// A punctual light.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Name, for timings (`shadow.<name>`) and messages.
    pub name: String,
    /// Kind and geometry.
    pub kind: LightKind,
    /// Linear colour.
    pub color: Vec3,
    /// Intensity (lux for directional, candela for point and spot, as in glTF).
    pub intensity: f32,
    /// Whether the light casts shadows (gets a shadow map).
    pub casts_shadows: bool,
}

/// A whole scene: triangles, materials, textures, lights and an optional camera.
///
/// Vertex attributes are parallel arrays (`normals` and `uvs` have one entry per position; a
/// zero normal means "use the face normal"). Triangles index them; each triangle has a material.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// Object-space = world-space vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex normals (zero where the file has none).
    pub normals: Vec<Vec3>,
    /// Texture coordinates (zero where the file has none).
    pub uvs: Vec<Vec2>,
    /// The second texture coordinate set: empty when no vertex has one, else one per position
    /// (zero where the file has none).
    pub uvs1: Vec<Vec2>,
    /// Tangents (xyz) with the bitangent's sign (w), for normal textures: empty when no vertex
    /// has one, else one per position (zero where there is none: the triangle's own
    /// texture-space frame is used there).
    pub tangents: Vec<Vec4>,
    /// Triangles, three vertex indices each.
    pub triangles: Vec<[u32; 3]>,
    /// Material index of each triangle.
    pub triangle_materials: Vec<u32>,
    /// Materials.
    pub materials: Vec<Material>,
    /// Textures referenced by materials.
    pub textures: Vec<Texture>,
    /// Lights.
    pub lights: Vec<Light>,
    /// Sky / ambient radiance, linear rgb.
    pub ambient: Vec3,
    /// The scene's own camera, if it has one.
    pub camera: Option<Camera>,
    /// What a loader skipped (for example a line primitive), for the user to see.
    pub warnings: Vec<String>,
}

/// One mesh to append with [`Scene::push_mesh`].
#[derive(Default)]
pub struct MeshData<'a> {
    /// Positions (already in world space).
    pub positions: &'a [Vec3],
    /// Normals, empty or one per position.
    pub normals: &'a [Vec3],
    /// Texture coordinates, empty or one per position.
    pub uvs: &'a [Vec2],
    /// The second texture coordinate set, empty or one per position.
    pub uvs1: &'a [Vec2],
    /// Tangents with the bitangent's sign, empty or one per position.
    pub tangents: &'a [Vec4],
    /// Triangle indices into this mesh's own vertices.
    pub indices: &'a [u32],
    /// Material of every triangle.
    pub material: u32,
}

impl Scene {
    /// Loads a scene file by extension (`.gltf`, `.glb`, `.obj`).
    pub fn load(path: &Path) -> Result<Scene> {
        Scene::load_with(path, &Limits::default())
    }

    /// [`load`](Scene::load) within `limits` instead of the default ones.
    pub fn load_with(path: &Path, limits: &Limits) -> Result<Scene> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("gltf" | "glb") => gltf::load(path, limits),
            Some("obj") => obj::load(path, limits),
            _ => Err(Error::format(
                path,
                "file name",
                "unknown scene format (expected .gltf, .glb or .obj)",
            )),
        }
    }

    /// Loads `builtin:NAME` or a file path.
    pub fn from_spec(spec: &str) -> Result<Scene> {
        Scene::from_spec_with(spec, &Limits::default())
    }

    /// [`from_spec`](Scene::from_spec) within `limits` instead of the default ones.
    pub fn from_spec_with(spec: &str, limits: &Limits) -> Result<Scene> {
        match spec.strip_prefix("builtin:") {
            Some(name) => builtin::by_name(name, limits),
            None => Scene::load_with(Path::new(spec), limits),
        }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Appends a mesh; missing normals, coordinates and tangents become zero.
    pub fn push_mesh(&mut self, mesh: MeshData<'_>) -> Result<()> {
        let base = u32::try_from(self.positions.len())
            .map_err(|_| Error::InvalidScene("more than 2^32 vertices".into()))?;
        let n = mesh.positions.len();
        if !mesh.indices.len().is_multiple_of(3) {
            return Err(Error::InvalidScene(format!(
                "index count {} is not a multiple of 3",
                mesh.indices.len()
            )));
        }
        if let Some(bad) = mesh.indices.iter().find(|&&i| i as usize >= n) {
            return Err(Error::InvalidScene(format!(
                "index {bad} out of range for a mesh of {n} vertices"
            )));
        }
        self.positions.extend_from_slice(mesh.positions);
        if mesh.normals.len() == n {
            self.normals.extend_from_slice(mesh.normals);
        } else {
            self.normals.extend(std::iter::repeat_n(Vec3::ZERO, n));
        }
        if mesh.uvs.len() == n {
            self.uvs.extend_from_slice(mesh.uvs);
        } else {
            self.uvs.extend(std::iter::repeat_n(Vec2::ZERO, n));
        }
        let before = base as usize;
        extend_optional(&mut self.uvs1, mesh.uvs1, before, n);
        extend_optional(&mut self.tangents, mesh.tangents, before, n);
        for t in mesh.indices.chunks_exact(3) {
            self.triangles.push([t[0] + base, t[1] + base, t[2] + base]);
            self.triangle_materials.push(mesh.material);
        }
        Ok(())
    }

    /// Axis-aligned bounds of all positions (`None` for an empty scene).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.positions.iter().filter(|p| p.is_finite());
        let first = *it.next()?;
        Some(it.fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
    }

    /// The largest side of the scene's bounds, in scene units (0 for an empty scene).
    pub fn extent(&self) -> f32 {
        self.bounds().map_or(0.0, |(lo, hi)| (hi - lo).max_element())
    }

    /// A camera looking at the scene's bounds from the front (+z), slightly above, with a 45
    /// degree field of view, fitted to them ([`fit_camera`](Scene::fit_camera)).
    pub fn framing_camera(&self) -> Camera {
        let dir = Vec3::new(0.0, 0.35, 1.0).normalize();
        self.fit_camera(&Camera::perspective(dir, Vec3::ZERO, 45.0, 0.1), 1.0)
    }

    /// A near plane for a camera at `eye` that cuts nothing of the scene: half the distance from
    /// `eye` to the scene's bounds, and a ten-thousandth of their size when `eye` is inside them
    /// (the G-buffer keeps linear view depth, so a small near plane costs no precision).
    pub fn near_plane_from(&self, eye: Vec3) -> f32 {
        let (lo, hi) = self.bounds().unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
        let floor = ((hi - lo).length() * 1e-4).max(1e-6);
        let outside = (lo - eye).max(eye - hi).max(Vec3::ZERO).length();
        (outside * 0.5).max(floor)
    }

    /// `camera` moved along its line of sight so that the scene's bounding sphere fits the view
    /// at `aspect` (width / height) in both directions, looking at the sphere's centre, with a
    /// near plane that cuts nothing; its direction, up and field of view stay (an orthographic
    /// camera widens its view instead of moving).
    pub fn fit_camera(&self, camera: &Camera, aspect: f32) -> Camera {
        let (lo, hi) = self.bounds().unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        let forward = (camera.target - camera.eye).try_normalize().unwrap_or(Vec3::NEG_Z);
        let mut fitted = camera.clone();
        match &mut fitted.projection {
            Projection::Perspective { fov_y_deg, near, .. } => {
                let half_y = (fov_y_deg.to_radians() * 0.5).clamp(1e-3, 1.5);
                let half_x = (half_y.tan() * aspect.max(1e-3)).atan();
                let dist = radius / half_y.min(half_x).sin();
                fitted.eye = center - forward * dist;
                fitted.target = center;
                *near = (dist - radius).max(dist * 1e-3) * 0.5;
            }
            Projection::Orthographic { height, near, far } => {
                *height = 2.0 * radius / aspect.clamp(1e-3, 1.0);
                fitted.eye = center - forward * (2.0 * radius);
                fitted.target = center;
                *near = near.min(radius * 0.5);
                *far = far.max(4.0 * radius);
            }
        }
        fitted
    }

    /// The material named `name`, or numbered `name` (its index).
    pub fn material_named(&self, name: &str) -> Result<u32> {
        let found = self.materials.iter().position(|m| m.name == name).map(|i| i as u32);
        let numbered = name.parse::<u32>().ok().filter(|&i| (i as usize) < self.materials.len());
        found.or(numbered).ok_or_else(|| {
            let names: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
            Error::setting(
                "material",
                format!("`{name}` names no material (the scene's: {})", names.join(", ")),
            )
        })
    }

    /// The vertex positions with every vertex of the triangles of `material` moved by `by`
    /// (a vertex shared with triangles of other materials moves too): what a host writes into
    /// the scene's position buffer to move that object (then
    /// [`Renderer::geometry_changed`](crate::Renderer::geometry_changed)).
    pub fn positions_moved(&self, material: u32, by: Vec3) -> Result<Vec<Vec3>> {
        if !by.is_finite() {
            return Err(Error::setting("move", format!("{by} (must be finite)")));
        }
        let mut moves = vec![false; self.positions.len()];
        for (t, m) in self.triangles.iter().zip(&self.triangle_materials) {
            if *m == material {
                for &i in t {
                    if let Some(v) = moves.get_mut(i as usize) {
                        *v = true;
                    }
                }
            }
        }
        Ok(self.positions.iter().zip(moves).map(|(p, m)| if m { *p + by } else { *p }).collect())
    }

    /// The scene's camera, or one that frames its bounds.
    pub fn camera_or_default(&self) -> Camera {
        self.camera.clone().unwrap_or_else(|| self.framing_camera())
    }

    /// The scene lit by the default lighting (a sun that casts shadows and a sky ambient) when
    /// it has no light of its own, else as it is ([`ensure_lights`](Scene::ensure_lights)).
    /// Loading never adds lights: a file without lights renders dark unless the host asks.
    pub fn with_default_lights(mut self) -> Self {
        self.ensure_lights();
        self
    }

    /// Adds the default lighting (a sun and a sky ambient) when the scene has no light; whether
    /// it did.
    pub fn ensure_lights(&mut self) -> bool {
        let unlit = self.lights.is_empty();
        if unlit {
            self.lights.push(Light {
                name: "sun".into(),
                kind: LightKind::Directional { direction: Vec3::new(-0.4, -1.0, -0.3).normalize() },
                color: Vec3::ONE,
                intensity: 3.0,
                casts_shadows: true,
            });
            if self.ambient == Vec3::ZERO {
                self.ambient = Vec3::new(0.25, 0.3, 0.4);
            }
        }
        unlit
    }

    /// Checks what the GPU passes rely on: a non-empty scene, indices and material ids in range,
    /// finite positions, texture references in range and texture sizes that match their data.
    pub fn validate(&self) -> Result<()> {
        if self.triangles.is_empty() {
            return Err(Error::InvalidScene("the scene has no triangles".into()));
        }
        let n = self.positions.len();
        if self.normals.len() != n || self.uvs.len() != n {
            return Err(Error::InvalidScene(format!(
                "{n} positions but {} normals and {} uvs",
                self.normals.len(),
                self.uvs.len()
            )));
        }
        for (name, len) in [("second uvs", self.uvs1.len()), ("tangents", self.tangents.len())] {
            if len != 0 && len != n {
                return Err(Error::InvalidScene(format!(
                    "{n} positions but {len} {name} (none or one per position)"
                )));
            }
        }
        if self.triangle_materials.len() != self.triangles.len() {
            return Err(Error::InvalidScene(format!(
                "{} triangles but {} triangle materials",
                self.triangles.len(),
                self.triangle_materials.len()
            )));
        }
        if let Some((i, p)) = self.positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(Error::InvalidScene(format!("position {i} is not finite: {p}")));
        }
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(Error::InvalidScene(format!(
                    "triangle {t} uses vertex {bad} but there are {n} vertices"
                )));
            }
        }
        if let Some((t, &m)) = self
            .triangle_materials
            .iter()
            .enumerate()
            .find(|(_, m)| **m as usize >= self.materials.len())
        {
            return Err(Error::InvalidScene(format!(
                "triangle {t} uses material {m} but there are {} materials",
                self.materials.len()
            )));
        }
        for m in &self.materials {
            m.validate()?;
            if let Some(t) = m
                .texture_slots()
                .into_iter()
                .flatten()
                .map(|slot| slot.texture)
                .find(|&t| t as usize >= self.textures.len())
            {
                return Err(Error::InvalidScene(format!(
                    "material `{}` uses texture {t} but there are {} textures",
                    m.name,
                    self.textures.len()
                )));
            }
        }
        for (i, t) in self.textures.iter().enumerate() {
            if t.width == 0 || t.height == 0 || t.rgba8.len() != (t.width * t.height * 4) as usize {
                return Err(Error::InvalidScene(format!(
                    "texture {i} is {}x{} with {} bytes",
                    t.width,
                    t.height,
                    t.rgba8.len()
                )));
            }
        }
        Ok(())
    }
}

/// Appends `n` values of an attribute that only some meshes have: `data` when it has one per
/// vertex, else zeros; zeros first for the `before` vertices of earlier meshes when this is the
/// first mesh to have it, and nothing at all while no mesh has had it.
fn extend_optional<T: Copy + Default>(all: &mut Vec<T>, data: &[T], before: usize, n: usize) {
    if data.len() == n && n > 0 {
        all.resize(before, T::default());
        all.extend_from_slice(data);
    } else if !all.is_empty() {
        all.resize(before + n, T::default());
    }
}
