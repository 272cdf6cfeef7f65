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
//! | indices | `u32 x 3` per triangle |
//! | triangle_materials | `u32` per triangle |
//! | materials | [`GpuMaterial`] (64 bytes) per material |
//! | texels | `u32` RGBA8 (sRGB, red in the low byte) per texel, all textures back to back |

use bytemuck::{Pod, Zeroable};

use super::{GpuLight, Scene, SceneInfo};
use crate::gpu::storage_buffer_init;
use crate::{Error, Result};

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
    /// Bit 0: double-sided; bit 1: base-colour texture; bit 2: emissive texture; bit 3:
    /// metallic-roughness texture.
    pub flags: u32,
    /// First texel of the base-colour texture in the texel buffer.
    pub texture_offset: u32,
    /// Texture width (0 without a texture).
    pub texture_width: u32,
    /// Texture height.
    pub texture_height: u32,
    /// First texel of the emissive texture (sRGB; multiplies `emissive`).
    pub emissive_offset: u32,
    /// Emissive texture width.
    pub emissive_width: u32,
    /// Emissive texture height.
    pub emissive_height: u32,
    /// First texel of the metallic-roughness texture (linear; green: roughness, blue:
    /// metallic; the reflectivity becomes metallic x (1 - roughness) per texel).
    pub metallic_roughness_offset: u32,
    /// Metallic-roughness texture width.
    pub metallic_roughness_width: u32,
    /// Metallic-roughness texture height.
    pub metallic_roughness_height: u32,
    /// Padding.
    pub _pad: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<GpuMaterial>() == 96);

/// [`GpuMaterial::flags`] bit: both faces visible.
pub const MATERIAL_DOUBLE_SIDED: u32 = 1;
/// [`GpuMaterial::flags`] bit: has a base-colour texture.
pub const MATERIAL_TEXTURED: u32 = 2;
/// [`GpuMaterial::flags`] bit: has an emissive texture.
pub const MATERIAL_EMISSIVE_TEXTURED: u32 = 4;
/// [`GpuMaterial::flags`] bit: has a metallic-roughness texture.
pub const MATERIAL_METALLIC_ROUGHNESS_TEXTURED: u32 = 8;

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
        let mut materials = Vec::with_capacity(scene.materials.len());
        for m in &scene.materials {
            let mut g = GpuMaterial {
                base_color: m.base_color.to_array(),
                emissive: m.emissive.to_array(),
                roughness: m.roughness,
                metallic: m.metallic,
                reflectivity: m.reflectivity,
                flags: if m.double_sided { MATERIAL_DOUBLE_SIDED } else { 0 },
                ..GpuMaterial::default()
            };
            if let Some(t) = m.base_color_texture {
                g.flags |= MATERIAL_TEXTURED;
                (g.texture_offset, g.texture_width, g.texture_height) = placed[t as usize];
            }
            if let Some(t) = m.emissive_texture {
                g.flags |= MATERIAL_EMISSIVE_TEXTURED;
                (g.emissive_offset, g.emissive_width, g.emissive_height) = placed[t as usize];
            }
            if let Some(t) = m.metallic_roughness_texture {
                g.flags |= MATERIAL_METALLIC_ROUGHNESS_TEXTURED;
                let (offset, width, height) = placed[t as usize];
                g.metallic_roughness_offset = offset;
                g.metallic_roughness_width = width;
                g.metallic_roughness_height = height;
            }
            materials.push(g);
        }
        let positions: Vec<f32> = scene.positions.iter().flat_map(|p| p.to_array()).collect();
        let normals: Vec<f32> = scene
            .normals
            .iter()
            .flat_map(|n| if n.is_finite() { n.to_array() } else { [0.0; 3] })
            .collect();
        let uvs: Vec<f32> = scene
            .uvs
            .iter()
            .flat_map(|t| if t.is_finite() { t.to_array() } else { [0.0; 2] })
            .collect();
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
        Ok(SceneBuffers { lights: light_buffer(device, &info), b, info })
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
        for (name, buffer, needed) in [
            ("positions", &b.positions, v * 12),
            ("normals", &b.normals, v * 12),
            ("uvs", &b.uvs, v * 8),
            ("indices", &b.indices, t * 12),
            ("triangle_materials", &b.triangle_materials, t * 4),
            ("materials", &b.materials, m * 64),
            ("texels", &b.texels, 4),
        ] {
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
        Ok(SceneBuffers { lights: light_buffer(device, &info), b: buffers, info })
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

    /// Triangles.
    pub fn triangle_count(&self) -> u32 {
        self.b.triangle_count
    }
}

fn light_buffer(device: &wgpu::Device, info: &SceneInfo) -> wgpu::Buffer {
    let lights: Vec<GpuLight> = info.lights.iter().map(GpuLight::new).collect();
    storage_buffer_init(device, "deep-gbuffer.scene.lights", bytemuck::cast_slice(&lights))
}
