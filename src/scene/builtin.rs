//! Built-in scenes, by name: `cornell` (the public-domain Cornell box from `fixtures/cornell`,
//! compiled into the binary), `cornell-glass` (the same with two overlapping tinted glass panes,
//! blended) and `grid` / `grid-<triangles>` (a procedural field of tessellated
//! spheres on a ground plane, for scaling to millions of triangles).

use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};

use super::{Camera, Light, LightKind, Material, MeshData, Projection, Scene};
use crate::{Error, Result};

/// The built-in scene names (`grid-<N>` takes any triangle count N).
pub const NAMES: &[&str] = &["cornell", "cornell-glass", "grid", "grid-<triangles>"];

const CORNELL_OBJ: &str = include_str!("../../fixtures/cornell/CornellBox-Original.obj");
const CORNELL_MTL: &str = include_str!("../../fixtures/cornell/CornellBox-Original.mtl");

/// Triangles of `builtin:grid` without a count.
pub const GRID_DEFAULT_TRIANGLES: u32 = 100_000;

/// A built-in scene by name, refused (before a grid is built) when its triangles exceed
/// `limits`.
pub fn by_name(name: &str, limits: &super::Limits) -> Result<Scene> {
    let over = |n: u64| {
        Err(Error::InvalidScene(format!(
            "`{name}`: {n} triangles exceed the limit of {}",
            limits.triangles
        )))
    };
    let grid_size = match name {
        "cornell" | "cornell-glass" => {
            let scene = if name == "cornell" { cornell()? } else { cornell_glass()? };
            let n = scene.triangle_count() as u64;
            return if n > limits.triangles { over(n) } else { Ok(scene) };
        }
        "grid" => GRID_DEFAULT_TRIANGLES,
        _ => match name.strip_prefix("grid-").map(str::parse::<u32>) {
            Some(Ok(n)) if n > 0 => n,
            _ => return Err(Error::UnknownBuiltin(name.to_string())),
        },
    };
    if u64::from(grid_size) > limits.triangles {
        return over(u64::from(grid_size));
    }
    Ok(grid(grid_size))
}

/// The Cornell box (Cardenas and McGuire, 2011, public domain) with its classic camera and a
/// point light just below its emissive ceiling panel.
pub fn cornell() -> Result<Scene> {
    let path = Path::new("builtin:cornell/CornellBox-Original.obj");
    let mut scene = super::obj::parse(CORNELL_OBJ, path, Path::new(""), |_| {
        Ok((CORNELL_MTL.to_string(), PathBuf::from("builtin:cornell/CornellBox-Original.mtl")))
    })?;
    scene.camera = Some(Camera {
        eye: Vec3::new(0.0, 1.0, 3.8),
        target: Vec3::new(0.0, 1.0, 0.0),
        up: Vec3::Y,
        projection: Projection::Perspective {
            fov_y_deg: 39.3,
            near: 0.1,
            far: None,
            reverse_z: false,
        },
        lens: Default::default(),
    });
    // Sky light entering through the open front, for the ambient term.
    scene.ambient = Vec3::splat(0.08);
    scene.lights.push(Light {
        name: "ceiling".into(),
        kind: LightKind::Point { position: Vec3::new(0.0, 1.9, 0.0), range: None },
        color: Vec3::new(1.0, 0.85, 0.6),
        intensity: 4.0,
        casts_shadows: true,
    });
    Ok(scene)
}

/// The Cornell box with two blended glass panes leaning back between the camera and the boxes: a pale blue one (opacity 0.35) and, behind it and overlapping it, an orange one
/// (opacity 0.5), so that some pixels see through two blended surfaces.
pub fn cornell_glass() -> Result<Scene> {
    let mut scene = cornell()?;
    let panes = [
        ("glass.blue", Vec4::new(0.3, 0.6, 1.0, 0.35), 0.5, (-0.8, 0.1), (0.1, 1.3)),
        ("glass.orange", Vec4::new(1.0, 0.45, 0.15, 0.5), 0.2, (-0.3, 0.7), (0.3, 1.1)),
    ];
    for (name, base_color, z, (x0, x1), (y0, y1)) in panes {
        scene.materials.push(Material {
            name: name.into(),
            base_color,
            roughness: 0.3,
            double_sided: true,
            alpha_mode: super::AlphaMode::Blend,
            ..Material::default()
        });
        let material = scene.materials.len() as u32 - 1;
        // Leaning back by 40 degrees, towards the light.
        let back = (y1 - y0) * 0.84;
        let corners = [
            Vec3::new(x0, y0, z),
            Vec3::new(x1, y0, z),
            Vec3::new(x1, y1, z - back),
            Vec3::new(x0, y1, z - back),
        ];
        let n = Vec3::new(0.0, back, y1 - y0).normalize();
        push(&mut scene, &corners, &[n; 4], &[0, 1, 2, 0, 2, 3], material);
    }
    Ok(scene)
}

/// A k x k field of UV spheres on a tessellated ground plane with about `triangles` triangles.
pub fn grid(triangles: u32) -> Scene {
    let target = triangles.max(64) as f32;
    let k = ((target / 2000.0).sqrt().round() as u32).clamp(1, 64);
    let ground_cells = 8u32;
    let per_sphere =
        ((target - (2 * ground_cells * ground_cells) as f32) / (k * k) as f32).max(24.0);
    // A sphere with r rings and 2r segments has 4r(r - 1) triangles.
    let rings = ((1.0 + (1.0 + per_sphere).sqrt()) / 2.0).round().max(3.0) as u32;
    let segments = 2 * rings;

    let mut scene = Scene::default();
    let colors = [
        Vec3::new(0.8, 0.2, 0.2),
        Vec3::new(0.2, 0.7, 0.3),
        Vec3::new(0.25, 0.35, 0.85),
        Vec3::new(0.85, 0.8, 0.3),
    ];
    for (i, c) in colors.iter().enumerate() {
        scene.materials.push(Material {
            name: format!("sphere{i}"),
            base_color: c.extend(1.0),
            roughness: if i == 3 { 0.15 } else { 0.6 },
            metallic: if i == 3 { 1.0 } else { 0.0 },
            reflectivity: if i == 3 { 0.8 } else { 0.0 },
            ..Material::default()
        });
    }
    scene.materials.push(Material {
        name: "ground".into(),
        base_color: Vec4::new(0.7, 0.7, 0.7, 1.0),
        ..Material::default()
    });

    let spacing = 2.5f32;
    let extent = spacing * k as f32;
    // Ground: a tessellated square under the spheres.
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    for j in 0..=ground_cells {
        for i in 0..=ground_cells {
            let u = i as f32 / ground_cells as f32 - 0.5;
            let v = j as f32 / ground_cells as f32 - 0.5;
            positions.push(Vec3::new(u * extent * 1.2, 0.0, v * extent * 1.2));
            normals.push(Vec3::Y);
        }
    }
    let row = ground_cells + 1;
    for j in 0..ground_cells {
        for i in 0..ground_cells {
            let a = j * row + i;
            indices.extend_from_slice(&[a, a + row, a + 1, a + 1, a + row, a + row + 1]);
        }
    }
    push(&mut scene, &positions, &normals, &indices, 4);

    // One unit sphere, instanced k x k times.
    let (mut sp, mut sn, mut si) = (Vec::new(), Vec::new(), Vec::new());
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * PI * s as f32 / segments as f32;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            sp.push(n);
            sn.push(n);
        }
    }
    let srow = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let a = r * srow + s;
            if r != 0 {
                si.extend_from_slice(&[a, a + 1, a + srow]);
            }
            if r != rings - 1 {
                si.extend_from_slice(&[a + 1, a + srow + 1, a + srow]);
            }
        }
    }
    for z in 0..k {
        for x in 0..k {
            let center = Vec3::new(
                (x as f32 + 0.5) * spacing - extent * 0.5,
                1.0,
                (z as f32 + 0.5) * spacing - extent * 0.5,
            );
            let moved: Vec<Vec3> = sp.iter().map(|p| *p + center).collect();
            push(&mut scene, &moved, &sn, &si, (x + z) % 4);
        }
    }
    let eye = Vec3::new(0.0, extent * 0.45 + 2.0, extent * 0.75 + 3.0);
    scene.camera = Some(Camera::perspective(eye, Vec3::new(0.0, 0.5, 0.0), 50.0, 0.1));
    scene.ensure_lights();
    scene
}

fn push(scene: &mut Scene, positions: &[Vec3], normals: &[Vec3], indices: &[u32], material: u32) {
    let uvs: Vec<Vec2> = Vec::new();
    scene
        .push_mesh(MeshData {
            positions,
            normals,
            uvs: &uvs,
            indices,
            material,
            ..MeshData::default()
        })
        .expect("generated indices are in range");
}
