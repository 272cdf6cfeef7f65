//! The scene on the GPU: [`SceneBuffers`], uploaded from a [`Scene`] or imported from a host
//! engine's own buffers without a copy.
//!
//! Byte layouts (all little-endian, tightly packed, storage-buffer usage):
//!
//! | buffer | layout |
//! |---|---|
//! | positions | `f32 x 3` per vertex |
//! | normals | `f32 x 3` per vertex (zero: use the face normal) |
//! | uvs | `f32 x 2` per vertex |
//! | uvs1 (optional) | `f32 x 2` per vertex: the second coordinate set |
//! | tangents (optional) | `f32 x 4` per vertex: tangent xyz, bitangent sign w (zero: none) |
//! | indices | `u32 x 3` per triangle |
//! | triangle_materials | `u32` per triangle |
//! | materials | [`GpuMaterial`] (288 bytes) per material |
//! | texels | `u32` RGBA8 (sRGB, red in the low byte) per texel, all textures back to back |

use bytemuck::{Pod, Zeroable};

use super::{AlphaMode, Filter, GpuLight, Material, Scene, SceneInfo, TextureRef, Wrap};
use crate::gpu::storage_buffer_init;
use crate::{Error, Result};

/// How a material reads one texture. Mirrors `struct TextureSlot` in
/// `wgsl/shared/material.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuTextureSlot {
    /// First texel in the texel buffer.
    pub offset: u32,
    /// Width in texels (0 without a texture).
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Bits 0-1: wrap across u, bits 2-3: wrap across v (0 repeat, 1 clamp to edge, 2
    /// mirrored repeat); bit 4: nearest texel (else bilinear); bit 5: coordinate set 1.
    pub sampler: u32,
    /// The coordinate transform's first row (`u' = x u + y v + z`); w: the slot's scale (the
    /// normal scale, the occlusion strength; 1 for the other slots).
    pub transform_u: [f32; 4],
    /// The coordinate transform's second row (`v' = x u + y v + z`); w unused.
    pub transform_v: [f32; 4],
}

/// A material as the kernels read it. Mirrors `struct Material` in `wgsl/shared/material.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GpuMaterial {
    /// Linear base colour and opacity.
    pub base_color: [f32; 4],
    /// Emitted radiance.
    pub emissive: [f32; 3],
    /// Perceptual roughness.
    pub roughness: f32,
    /// Metalness.
    pub metallic: f32,
    /// Mirror reflectivity.
    pub reflectivity: f32,
    /// Bit 0: double-sided; bit `1 + k`: texture slot `k` is used (see [`SLOT_BASE_COLOR`]..);
    /// [`MATERIAL_MASK`], [`MATERIAL_BLEND`]: the alpha mode.
    pub flags: u32,
    /// The opacity below which a masked material is cut away.
    pub alpha_cutoff: f32,
    /// The texture slots: base colour (sRGB), emissive (sRGB), metallic-roughness (linear;
    /// green: roughness, blue: metallic; the reflectivity becomes metallic x (1 - roughness)
    /// per texel), normal (linear, tangent space), occlusion (linear, red).
    pub slots: [GpuTextureSlot; 5],
}

const _: () = assert!(std::mem::size_of::<GpuTextureSlot>() == 48);
const _: () = assert!(std::mem::size_of::<GpuMaterial>() == 288);

/// [`GpuMaterial::flags`] bit: both faces visible.
pub const MATERIAL_DOUBLE_SIDED: u32 = 1;
/// [`GpuMaterial::flags`] bit: alpha-tested ([`AlphaMode::Mask`]).
pub const MATERIAL_MASK: u32 = 1 << 6;
/// [`GpuMaterial::flags`] bit: blended ([`AlphaMode::Blend`]).
pub const MATERIAL_BLEND: u32 = 1 << 7;
/// Index of the base-colour texture in [`GpuMaterial::slots`].
pub const SLOT_BASE_COLOR: usize = 0;
/// Index of the emissive texture.
pub const SLOT_EMISSIVE: usize = 1;
/// Index of the metallic-roughness texture.
pub const SLOT_METALLIC_ROUGHNESS: usize = 2;
/// Index of the normal texture.
pub const SLOT_NORMAL: usize = 3;
/// Index of the occlusion texture.
pub const SLOT_OCCLUSION: usize = 4;

/// The [`GpuMaterial::flags`] bit that says texture slot `slot` is used.
pub const fn slot_flag(slot: usize) -> u32 {
    2 << slot
}

impl GpuTextureSlot {
    /// `slot` as the kernels read it, its texture placed at `(offset, width, height)`, with
    /// the slot's `scale` (normal scale, occlusion strength).
    pub fn new(slot: &TextureRef, (offset, width, height): (u32, u32, u32), scale: f32) -> Self {
        let wrap = |w: Wrap| match w {
            Wrap::Repeat => 0,
            Wrap::ClampToEdge => 1,
            Wrap::MirroredRepeat => 2,
        };
        let m = slot.transform;
        GpuTextureSlot {
            offset,
            width,
            height,
            sampler: wrap(slot.wrap_s)
                | wrap(slot.wrap_t) << 2
                | u32::from(slot.filter == Filter::Nearest) << 4
                | u32::from(slot.tex_coord == 1) << 5,
            transform_u: [m.matrix2.x_axis.x, m.matrix2.y_axis.x, m.translation.x, scale],
            transform_v: [m.matrix2.x_axis.y, m.matrix2.y_axis.y, m.translation.y, 0.0],
        }
    }
}

impl GpuMaterial {
    /// `m` as the kernels read it, its textures placed as `placed` says (offset, width and
    /// height of each of the scene's textures in the texel buffer).
    pub fn new(m: &Material, placed: &[(u32, u32, u32)]) -> GpuMaterial {
        let mut g = GpuMaterial {
            base_color: m.base_color.to_array(),
            emissive: m.emissive.to_array(),
            roughness: m.roughness,
            metallic: m.metallic,
            reflectivity: m.reflectivity,
            flags: if m.double_sided { MATERIAL_DOUBLE_SIDED } else { 0 },
            ..GpuMaterial::default()
        };
        match m.alpha_mode {
            AlphaMode::Opaque => {}
            AlphaMode::Mask { cutoff } => {
                g.flags |= MATERIAL_MASK;
                g.alpha_cutoff = cutoff;
            }
            AlphaMode::Blend => g.flags |= MATERIAL_BLEND,
        }
        for (k, slot) in m.texture_slots().iter().enumerate() {
            if let Some(slot) = slot {
                let scale = match k {
                    SLOT_NORMAL => m.normal_scale,
                    SLOT_OCCLUSION => m.occlusion_strength,
                    _ => 1.0,
                };
                g.flags |= slot_flag(k);
                g.slots[k] = GpuTextureSlot::new(slot, placed[slot.texture as usize], scale);
            }
        }
        g
    }
}

/// The host engine's own buffers, for [`SceneBuffers::import`]. Each needs `STORAGE` usage and
/// the byte layout in this module's documentation.
#[derive(Clone, Debug)]
pub struct ImportedBuffers {
    /// Positions.
    pub positions: wgpu::Buffer,
    /// Normals.
    pub normals: wgpu::Buffer,
    /// Texture coordinates.
    pub uvs: wgpu::Buffer,
    /// The second texture-coordinate set (`f32 x 2` per vertex), if any material reads it.
    pub uvs1: Option<wgpu::Buffer>,
    /// Tangents with the bitangent's sign (`f32 x 4` per vertex; zero: the triangle's own
    /// texture-space frame), for normal textures. Without it every triangle uses its own.
    pub tangents: Option<wgpu::Buffer>,
    /// Indices.
    pub indices: wgpu::Buffer,
    /// Per-triangle material ids.
    pub triangle_materials: wgpu::Buffer,
    /// Materials.
    pub materials: wgpu::Buffer,
    /// Texels (a 16-byte buffer when there are no textures).
    pub texels: wgpu::Buffer,
    /// Vertices in the buffers.
    pub vertex_count: u32,
    /// Triangles in the buffers.
    pub triangle_count: u32,
    /// Materials in the buffer.
    pub material_count: u32,
}

/// A scene's geometry and materials on the GPU.
#[derive(Clone, Debug)]
pub struct SceneBuffers {
    pub(crate) b: ImportedBuffers,
    pub(crate) info: SceneInfo,
    /// [`GpuLight`] per light (one zeroed light when there is none, so it binds).
    pub(crate) lights: wgpu::Buffer,
    /// The second coordinate set, or 16 zero bytes when the scene has none.
    pub(crate) uvs1: wgpu::Buffer,
    /// The tangents, or 16 zero bytes when the scene has none.
    pub(crate) tangents: wgpu::Buffer,
}

/// The most triangles a scene may have: the shaders address the index buffer (three u32 per
/// triangle) with 32-bit indices.
pub const MAX_TRIANGLES: u32 = 1 << 29;

impl SceneBuffers {
    /// Validates `scene` and uploads it.
    pub fn upload(device: &wgpu::Device, scene: &Scene) -> Result<SceneBuffers> {
        crate::gpu::scoped(device, "deep-gbuffer.scene", || Self::create(device, scene))
    }

    fn create(device: &wgpu::Device, scene: &Scene) -> Result<SceneBuffers> {
        scene.validate()?;
        SceneInfo::of(scene).validate()?;
        let limits = device.limits();
        // Every texture once, however many materials and slots use it.
        let mut texels: Vec<u32> = Vec::new();
        let mut placed = Vec::with_capacity(scene.textures.len());
        for tex in &scene.textures {
            placed.push((texels.len() as u32, tex.width, tex.height));
            texels.extend(
                tex.rgba8.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            );
        }
        let materials: Vec<GpuMaterial> =
            scene.materials.iter().map(|m| GpuMaterial::new(m, &placed)).collect();
        let positions: Vec<f32> = scene.positions.iter().flat_map(|p| p.to_array()).collect();
        let normals = finite_or_zero(&scene.normals, |n| n.is_finite().then(|| n.to_array()));
        let uvs = finite_or_zero(&scene.uvs, |t| t.is_finite().then(|| t.to_array()));
        let uvs1 = finite_or_zero(&scene.uvs1, |t| t.is_finite().then(|| t.to_array()));
        let tangents = finite_or_zero(&scene.tangents, |t| t.is_finite().then(|| t.to_array()));
        let indices: Vec<u32> = scene.triangles.iter().flatten().copied().collect();
        let check = |what: &str, bytes: usize| -> Result<()> {
            let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
            if bytes as u64 > limit {
                return Err(Error::ExceedsLimit {
                    what: format!("the scene's {what} buffer"),
                    needed: bytes as u64,
                    limit,
                    unit: "bytes",
                });
            }
            Ok(())
        };
        check("positions", positions.len() * 4)?;
        check("tangents", tangents.len() * 4)?;
        check("indices", indices.len() * 4)?;
        check("texels", texels.len() * 4)?;
        let count = |n: usize, what: &str| {
            u32::try_from(n)
                .ok()
                .filter(|&n| n < MAX_TRIANGLES)
                .ok_or_else(|| Error::InvalidScene(format!("too many {what}: {n}")))
        };
        let b = ImportedBuffers {
            positions: storage_buffer_init(
                device,
                "deep-gbuffer.scene.positions",
                bytemuck::cast_slice(&positions),
            ),
            normals: storage_buffer_init(
                device,
                "deep-gbuffer.scene.normals",
                bytemuck::cast_slice(&normals),
            ),
            uvs: storage_buffer_init(device, "deep-gbuffer.scene.uvs", bytemuck::cast_slice(&uvs)),
            uvs1: (!uvs1.is_empty()).then(|| {
                storage_buffer_init(device, "deep-gbuffer.scene.uvs1", bytemuck::cast_slice(&uvs1))
            }),
            tangents: (!tangents.is_empty()).then(|| {
                storage_buffer_init(
                    device,
                    "deep-gbuffer.scene.tangents",
                    bytemuck::cast_slice(&tangents),
                )
            }),
            indices: storage_buffer_init(
                device,
                "deep-gbuffer.scene.indices",
                bytemuck::cast_slice(&indices),
            ),
            triangle_materials: storage_buffer_init(
                device,
                "deep-gbuffer.scene.triangle_materials",
                bytemuck::cast_slice(&scene.triangle_materials),
            ),
            materials: storage_buffer_init(
                device,
                "deep-gbuffer.scene.materials",
                bytemuck::cast_slice(&materials),
            ),
            texels: storage_buffer_init(
                device,
                "deep-gbuffer.scene.texels",
                bytemuck::cast_slice(&texels),
            ),
            vertex_count: count(scene.positions.len(), "vertices")?,
            triangle_count: count(scene.triangles.len(), "triangles")?,
            material_count: count(scene.materials.len(), "materials")?,
        };
        let info = SceneInfo::of(scene);
        Ok(SceneBuffers::new(device, b, info))
    }

    /// Uses a host engine's buffers as they are (no copy), after checking their sizes and usage
    /// against the counts. Index, material-id, position and texture values are not read back
    /// here: the rasterizer rejects each triangle whose indices or material id are out of range
    /// or whose positions are not finite, draws a material whose texture lies outside `texels`
    /// with its base colour, and counts both in [`Diagnostics`](crate::Diagnostics).
    pub fn import(
        device: &wgpu::Device,
        buffers: ImportedBuffers,
        info: SceneInfo,
    ) -> Result<SceneBuffers> {
        info.validate()?;
        let b = &buffers;
        if b.triangle_count == 0 {
            return Err(Error::InvalidScene("the scene has no triangles".into()));
        }
        if b.triangle_count >= MAX_TRIANGLES {
            return Err(Error::InvalidScene(format!("too many triangles: {}", b.triangle_count)));
        }
        let v = u64::from(b.vertex_count);
        let t = u64::from(b.triangle_count);
        let m = u64::from(b.material_count);
        let required = [
            ("positions", &b.positions, v * 12),
            ("normals", &b.normals, v * 12),
            ("uvs", &b.uvs, v * 8),
            ("indices", &b.indices, t * 12),
            ("triangle_materials", &b.triangle_materials, t * 4),
            ("materials", &b.materials, m * std::mem::size_of::<GpuMaterial>() as u64),
            ("texels", &b.texels, 4),
        ]
        .map(|(name, buffer, needed)| (name, Some(buffer), needed));
        let optional =
            [("uvs1", b.uvs1.as_ref(), v * 8), ("tangents", b.tangents.as_ref(), v * 16)];
        for (name, buffer, needed) in required.into_iter().chain(optional) {
            let Some(buffer) = buffer else { continue };
            if buffer.size() < needed {
                return Err(Error::ImportedBuffer {
                    name,
                    message: format!("{} bytes, but the counts need {needed}", buffer.size()),
                });
            }
            if !buffer.usage().contains(wgpu::BufferUsages::STORAGE) {
                return Err(Error::ImportedBuffer { name, message: "lacks STORAGE usage".into() });
            }
        }
        Ok(SceneBuffers::new(device, buffers, info))
    }

    fn new(device: &wgpu::Device, b: ImportedBuffers, info: SceneInfo) -> SceneBuffers {
        // An attribute no vertex has binds as one zero element, which the resolve reads as none.
        let or_empty = |buffer: &Option<wgpu::Buffer>, label: &str| {
            buffer.clone().unwrap_or_else(|| storage_buffer_init(device, label, &[0u8; 16]))
        };
        SceneBuffers {
            lights: light_buffer(device, &info),
            uvs1: or_empty(&b.uvs1, "deep-gbuffer.scene.no-uvs1"),
            tangents: or_empty(&b.tangents, "deep-gbuffer.scene.no-tangents"),
            b,
            info,
        }
    }

    /// Lights, ambient and material facts.
    pub fn info(&self) -> &SceneInfo {
        &self.info
    }

    /// The lights as [`GpuLight`]s.
    pub fn light_buffer(&self) -> &wgpu::Buffer {
        &self.lights
    }

    /// The underlying buffers.
    pub fn buffers(&self) -> &ImportedBuffers {
        &self.b
    }

    /// Writes new vertex positions into the scene's position buffer, as a host moves objects
    /// (then [`Renderer::geometry_changed`](crate::Renderer::geometry_changed)); one per vertex.
    pub fn write_positions(&self, queue: &wgpu::Queue, positions: &[glam::Vec3]) -> Result<()> {
        if positions.len() != self.b.vertex_count as usize {
            return Err(Error::InvalidScene(format!(
                "{} positions for {} vertices",
                positions.len(),
                self.b.vertex_count
            )));
        }
        let words: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
        queue.write_buffer(&self.b.positions, 0, bytemuck::cast_slice(&words));
        Ok(())
    }

    /// Triangles.
    pub fn triangle_count(&self) -> u32 {
        self.b.triangle_count
    }

    /// The buffers whose contents a frame's raster, resolve and lights read (positions,
    /// indices, triangle materials, materials, texels, lights), as handles: a scene uploaded or
    /// imported anew has new ones, which is how kept results (shadow maps, a still frame's
    /// G-buffer) know the scene changed.
    pub(crate) fn identity(&self) -> [wgpu::Buffer; 6] {
        let b = &self.b;
        [&b.positions, &b.indices, &b.triangle_materials, &b.materials, &b.texels, &self.lights]
            .map(wgpu::Buffer::clone)
    }

    /// (triangles, materials, vertices): the counts a raster's frame uniform carries.
    pub(crate) fn counts(&self) -> (u32, u32, u32) {
        (self.b.triangle_count, self.b.material_count, self.b.vertex_count)
    }

    /// The bytes the vertex positions take (`f32 x 3` per vertex).
    pub(crate) fn position_bytes(&self) -> u64 {
        u64::from(self.b.vertex_count) * 12
    }
}

fn light_buffer(device: &wgpu::Device, info: &SceneInfo) -> wgpu::Buffer {
    let mut lights: Vec<GpuLight> = info.lights.iter().map(GpuLight::new).collect();
    // A kernel binds at least one light (the light count says none are read).
    if lights.is_empty() {
        lights.push(GpuLight::zeroed());
    }
    storage_buffer_init(device, "deep-gbuffer.scene.lights", bytemuck::cast_slice(&lights))
}

/// `values` flattened to floats, a value `f` gives none for (not finite) as zeros.
fn finite_or_zero<T, const N: usize>(values: &[T], f: impl Fn(&T) -> Option<[f32; N]>) -> Vec<f32> {
    values.iter().flat_map(|v| f(v).unwrap_or([0.0; N])).collect()
}
