//! Times Bevy's screen-space ambient occlusion (its `ssao` span: depth preprocess, GTAO and
//! spatial denoise) on an OBJ or glTF scene, headless, by Bevy's own GPU timestamps. Bevy's
//! effect radius is fixed at 0.5 x 1.457 world units; its `High` quality takes 3 slices of 3
//! steps a side (18 taps).
//!
//! Usage: `bevy-ssao-peer SCENE WIDTH HEIGHT FRAMES [EYE TARGET UP FOV_DEG SCALE]`, the vectors
//! as `x,y,z`. The camera defaults to the one deep-gbuffer's `builtin:cornell` uses (eye
//! 0,1,3.8, target 0,1,0, up +y, 39.3 degrees vertically); SCALE multiplies the scene and the
//! camera's position (Bevy's radius is fixed, so a scene is scaled to it instead). A glTF's own
//! cameras and lights are not loaded. Prints, for every GPU span Bevy measured, the median over
//! the frames it recorded.
use bevy::{
    app::{AppExit, ScheduleRunnerPlugin},
    asset::RenderAssetUsages,
    camera::RenderTarget,
    diagnostic::DiagnosticsStore,
    gltf::GltfLoaderSettings,
    mesh::{Indices, PrimitiveTopology},
    pbr::{ScreenSpaceAmbientOcclusion, ScreenSpaceAmbientOcclusionQualityLevel},
    prelude::*,
    render::{diagnostic::RenderDiagnosticsPlugin, render_resource::TextureFormat},
    window::ExitCondition,
};
use std::time::Duration;

#[derive(Resource)]
struct Config {
    scene: String,
    eye: Vec3,
    target: Vec3,
    up: Vec3,
    fov_deg: f32,
    scale: f32,
    width: u32,
    height: u32,
    frames: u32,
    done: u32,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 5 && args.len() != 10 {
        eprintln!("usage: bevy-ssao-peer SCENE WIDTH HEIGHT FRAMES [EYE TARGET UP FOV_DEG SCALE]");
        std::process::exit(2);
    }
    let real = |i: usize| -> f32 {
        args[i].parse().unwrap_or_else(|_| {
            eprintln!("not a number: {}", args[i]);
            std::process::exit(2)
        })
    };
    let vector = |i: usize| -> Vec3 {
        let v: Vec<f32> = args[i].split(',').filter_map(|x| x.parse().ok()).collect();
        match v[..] {
            [x, y, z] => Vec3::new(x, y, z),
            _ => {
                eprintln!("not x,y,z: {}", args[i]);
                std::process::exit(2)
            }
        }
    };
    let given = args.len() == 10;
    let number = |i: usize| -> u32 {
        args[i].parse().unwrap_or_else(|_| {
            eprintln!("not a whole number: {}", args[i]);
            std::process::exit(2)
        })
    };
    let config = Config {
        scene: args[1].clone(),
        eye: if given { vector(5) } else { Vec3::new(0.0, 1.0, 3.8) },
        target: if given { vector(6) } else { Vec3::new(0.0, 1.0, 0.0) },
        up: if given { vector(7) } else { Vec3::Y },
        fov_deg: if given { real(8) } else { 39.3 },
        scale: if given { real(9) } else { 1.0 },
        width: number(2),
        height: number(3),
        frames: number(4),
        done: 0,
    };
    // Assets load from the scene's folder.
    let folder = std::fs::canonicalize(&config.scene)
        .unwrap_or_else(|e| {
            eprintln!("{}: {e}", config.scene);
            std::process::exit(2)
        })
        .parent()
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    App::new()
        .insert_resource(config)
        .add_plugins(
            DefaultPlugins
                .set(WindowPlugin {
                    primary_window: None,
                    exit_condition: ExitCondition::DontExit,
                    ..default()
                })
                .set(AssetPlugin { file_path: folder, ..default() }),
        )
        .add_plugins(RenderDiagnosticsPlugin)
        .add_plugins(ScheduleRunnerPlugin::run_loop(Duration::ZERO))
        .add_systems(Startup, setup)
        .add_systems(Update, report)
        .run();
}

/// The OBJ's faces as flat-shaded triangles (positions only; negative indices count back).
fn load_obj(path: &str) -> Mesh {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| {
        eprintln!("{path}: {e}");
        std::process::exit(2)
    });
    let mut vertices: Vec<Vec3> = Vec::new();
    let (mut positions, mut normals) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let p: Vec<f32> = words.take(3).filter_map(|x| x.parse().ok()).collect();
                if let [x, y, z] = p[..] {
                    vertices.push(Vec3::new(x, y, z));
                }
            }
            Some("f") => {
                let corners: Vec<usize> = words
                    .filter_map(|t| t.split('/').next()?.parse::<i64>().ok())
                    .map(|i| if i < 0 { vertices.len() as i64 + i } else { i - 1 } as usize)
                    .collect();
                for k in 1..corners.len().saturating_sub(1) {
                    let [a, b, c] = [corners[0], corners[k], corners[k + 1]].map(|i| vertices[i]);
                    let n = (b - a).cross(c - a).normalize_or_zero();
                    for p in [a, b, c] {
                        positions.push(p.to_array());
                        normals.push(n.to_array());
                    }
                }
            }
            _ => {}
        }
    }
    let count = positions.len() as u32;
    Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
        .with_inserted_indices(Indices::U32((0..count).collect()))
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut images: ResMut<Assets<Image>>,
    assets: Res<AssetServer>,
    config: Res<Config>,
) {
    let target = images.add(Image::new_target_texture(
        config.width,
        config.height,
        TextureFormat::Rgba8UnormSrgb,
        None,
    ));
    let scaled = Transform::from_scale(Vec3::splat(config.scale));
    if config.scene.ends_with(".gltf") || config.scene.ends_with(".glb") {
        let file = std::path::Path::new(&config.scene).file_name().unwrap().to_string_lossy();
        let scene = assets
            .load_builder()
            .with_settings(|s: &mut GltfLoaderSettings| {
                s.load_cameras = false;
                s.load_lights = false;
            })
            .load(GltfAssetLabel::Scene(0).from_asset(file.to_string()));
        commands.spawn((WorldAssetRoot(scene), scaled));
    } else {
        commands.spawn((
            Mesh3d(meshes.add(load_obj(&config.scene))),
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: Color::srgb(0.7, 0.7, 0.7),
                cull_mode: None,
                double_sided: true,
                ..default()
            })),
            scaled,
        ));
    }
    commands.insert_resource(GlobalAmbientLight { brightness: 500.0, ..default() });
    commands.spawn((
        Camera3d::default(),
        RenderTarget::Image(target.into()),
        Projection::Perspective(PerspectiveProjection {
            fov: config.fov_deg.to_radians(),
            near: 0.1 * config.scale.min(1.0),
            ..default()
        }),
        Transform::from_translation(config.eye * config.scale)
            .looking_at(config.target * config.scale, config.up),
        Msaa::Off,
        ScreenSpaceAmbientOcclusion {
            quality_level: ScreenSpaceAmbientOcclusionQualityLevel::High,
            ..default()
        },
    ));
}

fn report(
    mut config: ResMut<Config>,
    diagnostics: Res<DiagnosticsStore>,
    mut exit: MessageWriter<AppExit>,
) {
    config.done += 1;
    if config.done < config.frames {
        return;
    }
    for d in diagnostics.iter() {
        let path = d.path().as_str();
        if path.ends_with("elapsed_gpu") {
            let mut values: Vec<f64> = d.values().copied().collect();
            values.sort_by(f64::total_cmp);
            let median = values.get(values.len() / 2).copied().unwrap_or(f64::NAN);
            println!("{path}: median {median:.3} ms over {} frames", values.len());
        }
    }
    exit.write(AppExit::Success);
}
