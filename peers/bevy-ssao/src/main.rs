//! Times Bevy's screen-space ambient occlusion (its `ssao` span: depth preprocess, GTAO and
//! spatial denoise) on an OBJ scene, headless, by Bevy's own GPU timestamps, from the camera
//! deep-gbuffer's `builtin:cornell` uses (eye 0,1,3.8, target 0,1,0, vertical field of view
//! 39.3 degrees). Bevy's effect radius is fixed at 0.5 x 1.457 world units; its `High` quality
//! takes 3 slices of 3 steps a side (18 taps).
//!
//! Usage: `bevy-ssao-peer OBJ WIDTH HEIGHT FRAMES`; prints, for every GPU span Bevy measured,
//! the median over the frames it recorded (the first frames, which compile pipelines, are in
//! Bevy's history only once it has them).
use bevy::{
    app::{AppExit, ScheduleRunnerPlugin},
    asset::RenderAssetUsages,
    camera::RenderTarget,
    diagnostic::DiagnosticsStore,
    mesh::{Indices, PrimitiveTopology},
    pbr::{ScreenSpaceAmbientOcclusion, ScreenSpaceAmbientOcclusionQualityLevel},
    prelude::*,
    render::{diagnostic::RenderDiagnosticsPlugin, render_resource::TextureFormat},
    window::ExitCondition,
};
use std::time::Duration;

#[derive(Resource)]
struct Config {
    obj: String,
    width: u32,
    height: u32,
    frames: u32,
    done: u32,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 5 {
        eprintln!("usage: bevy-ssao-peer OBJ WIDTH HEIGHT FRAMES");
        std::process::exit(2);
    }
    let number = |i: usize| -> u32 {
        args[i].parse().unwrap_or_else(|_| {
            eprintln!("not a whole number: {}", args[i]);
            std::process::exit(2)
        })
    };
    let config = Config {
        obj: args[1].clone(),
        width: number(2),
        height: number(3),
        frames: number(4),
        done: 0,
    };
    App::new()
        .insert_resource(config)
        .add_plugins(DefaultPlugins.set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            ..default()
        }))
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
    config: Res<Config>,
) {
    let target = images.add(Image::new_target_texture(
        config.width,
        config.height,
        TextureFormat::Rgba8UnormSrgb,
        None,
    ));
    commands.spawn((
        Mesh3d(meshes.add(load_obj(&config.obj))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.7, 0.7, 0.7),
            cull_mode: None,
            double_sided: true,
            ..default()
        })),
    ));
    commands.insert_resource(GlobalAmbientLight { brightness: 500.0, ..default() });
    commands.spawn((
        Camera3d::default(),
        RenderTarget::Image(target.into()),
        Projection::Perspective(PerspectiveProjection {
            fov: 39.3f32.to_radians(),
            near: 0.1,
            ..default()
        }),
        Transform::from_xyz(0.0, 1.0, 3.8).looking_at(Vec3::new(0.0, 1.0, 0.0), Vec3::Y),
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
