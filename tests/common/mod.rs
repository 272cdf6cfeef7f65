//! Shared by the integration tests: one device per test binary, and helpers that render a scene
//! and return what the CPU references need.
#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::sync::OnceLock;

use deep_gbuffer::frame::FrameUniform;
use deep_gbuffer::gpu::{Gpu, GpuOptions};
use deep_gbuffer::{Camera, Renderer, Scene, SceneBuffers, Settings};
use glam::Vec3;

/// The test device. A machine without an adapter fails the tests: they never skip silently.
pub fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| {
        match Gpu::new(&GpuOptions::default(), &deep_gbuffer::Renderer::requirements()) {
            Ok(gpu) => {
                eprintln!("test adapter: {}", gpu.describe());
                gpu
            }
            Err(e) => panic!(
                "{e} (install the software Vulkan driver: apt-get install -y mesa-vulkan-drivers)"
            ),
        }
    })
}

/// One frame's visibility buffers, G-buffer settings and the uniform the GPU used.
pub struct Rendered {
    pub vis0: Vec<u64>,
    pub vis1: Vec<u64>,
    pub frame: FrameUniform,
    pub renderer: Renderer,
    pub buffers: SceneBuffers,
}

/// Renders `frames` frames of `scene` from `cameras` (one per frame) and returns the last.
pub fn render_frames(scene: &Scene, cameras: &[Camera], settings: Settings) -> Rendered {
    let g = gpu();
    let buffers = SceneBuffers::upload(&g.device, scene).expect("upload");
    let mut renderer = Renderer::new(&g.device, &g.queue, settings).expect("renderer");
    for camera in cameras {
        renderer.render(&g.device, &g.queue, &buffers, camera).expect("render");
    }
    rendered(renderer, buffers)
}

/// Renders `scene` through `camera` while its geometry moves: a frame with each of `positions`
/// in turn, as a host moves objects (writes the scene's position buffer, then calls
/// `geometry_changed`); returns the last.
pub fn render_moving(
    scene: &Scene,
    positions: &[Vec<Vec3>],
    camera: &Camera,
    settings: Settings,
) -> Rendered {
    let g = gpu();
    let buffers = SceneBuffers::upload(&g.device, scene).expect("upload");
    let mut renderer = Renderer::new(&g.device, &g.queue, settings).expect("renderer");
    for (i, frame) in positions.iter().enumerate() {
        buffers.write_positions(&g.queue, frame).expect("one position per vertex");
        if i > 0 {
            renderer.geometry_changed();
        }
        renderer.render(&g.device, &g.queue, &buffers, camera).expect("render");
    }
    rendered(renderer, buffers)
}

/// What `renderer` drew in its last frame of the scene in `buffers`.
fn rendered(renderer: Renderer, buffers: SceneBuffers) -> Rendered {
    let g = gpu();
    let vis0 = renderer.read_visibility(&g.device, &g.queue, 0).expect("read vis0");
    let vis1 = if renderer.last_plan().is_some_and(|p| p.layers == 2) {
        renderer.read_visibility(&g.device, &g.queue, 1).expect("read vis1")
    } else {
        Vec::new()
    };
    let frame = *renderer.frame_uniform().expect("a frame was encoded");
    Rendered { vis0, vis1, frame, renderer, buffers }
}

/// Renders one frame.
pub fn render(scene: &Scene, camera: &Camera, settings: Settings) -> Rendered {
    render_frames(scene, std::slice::from_ref(camera), settings)
}

/// The fixtures folder.
pub fn fixture(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures").join(path)
}

/// A scene of one indexed mesh with one default material (double-sided or not).
pub fn mesh(positions: &[Vec3], indices: &[u32], double_sided: bool) -> Scene {
    let mut scene = Scene::default();
    scene.materials.push(deep_gbuffer::scene::Material { double_sided, ..Default::default() });
    let data = deep_gbuffer::scene::MeshData { positions, indices, ..Default::default() };
    scene.push_mesh(data).expect("indices in range");
    scene
}

/// A scene of the given triangles (one material, optionally double-sided).
pub fn soup(triangles: &[[Vec3; 3]], double_sided: bool) -> Scene {
    let positions: Vec<Vec3> = triangles.iter().flatten().copied().collect();
    let indices: Vec<u32> = (0..positions.len() as u32).collect();
    mesh(&positions, &indices, double_sided)
}

/// The stored deep G-buffers in fixtures/gbuffer/: (file, the scene it shows with the scene's own
/// camera). Kernels shade them through `Renderer::render_gbuffer`, independent of the rasterizer.
pub const GBUFFER_FIXTURES: [(&str, &str); 2] = [
    ("gbuffer/cornell-48x36.exr", "builtin:cornell"),
    ("gbuffer/grid-20000-64x48.exr", "builtin:grid-20000"),
];

/// A stored G-buffer shaded by the GPU passes.
pub struct Shaded {
    /// The scene (lights, materials, shadow casters), with its default lights added.
    pub scene: Scene,
    /// The stored layers.
    pub layers: Vec<deep_gbuffer::GBufferLayer>,
    pub frame: FrameUniform,
    pub renderer: Renderer,
}

/// Loads fixture `index` of [`GBUFFER_FIXTURES`] and shades it with `settings` (its size set to
/// the fixture's).
pub fn shade_fixture(index: usize, settings: Settings) -> Shaded {
    let (file, spec) = GBUFFER_FIXTURES[index];
    let layers = deep_gbuffer::GBufferLayer::read_exr(&fixture(file)).expect("fixture G-buffer");
    assert_eq!(layers.len(), 2, "{file} holds both layers");
    let mut scene = Scene::from_spec(spec).expect("scene");
    scene.ensure_lights();
    let g = gpu();
    let buffers = SceneBuffers::upload(&g.device, &scene).expect("upload");
    let settings = Settings { width: layers[0].width, height: layers[0].height, ..settings };
    let mut renderer = Renderer::new(&g.device, &g.queue, settings).expect("renderer");
    let camera = scene.camera_or_default();
    renderer.render_gbuffer(&g.device, &g.queue, &buffers, &camera, &layers).expect("shade");
    let frame = *renderer.frame_uniform().expect("a frame was encoded");
    Shaded { scene, layers, frame, renderer }
}

/// The inside of the cube [-1, 1]^3, every face wound to face inward, with albedo `rho` and
/// emission `le` on every face and no light.
pub fn white_box(rho: f32, le: f32) -> Scene {
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let (u, v) = (glam::Vec3::AXES[(axis + 1) % 3], glam::Vec3::AXES[(axis + 2) % 3]);
            let c = glam::Vec3::AXES[axis] * sign;
            let corners = [c - u - v, c + u - v, c + u + v, c - u + v];
            for t in [[0, 1, 2], [0, 2, 3]] {
                let mut tri = t.map(|i| corners[i]);
                // Wound counter-clockwise seen from inside: the normal points to the centre.
                if (tri[1] - tri[0]).cross(tri[2] - tri[0]).dot(-c) < 0.0 {
                    tri.swap(1, 2);
                }
                triangles.push(tri);
            }
        }
    }
    let mut scene = soup(&triangles, false);
    scene.materials[0].base_color = glam::Vec4::new(rho, rho, rho, 1.0);
    scene.materials[0].emissive = glam::Vec3::splat(le);
    scene
}

/// A `vec4<f32>` per-pixel buffer of `r`'s size, read back.
pub fn read4(r: &Renderer, buffer: &wgpu::Buffer) -> Vec<glam::Vec4> {
    let g = gpu();
    r.read_vec4(&g.device, &g.queue, buffer).unwrap()
}

/// Asserts that `differs` holds for at most `fraction` of the pairs of `actual` and `expected`
/// (kernels whose f32 evaluation order differs from the CPU's flip a few pixels across a
/// threshold; such pixels must stay rare).
pub fn assert_few_differ<T>(
    actual: &[T],
    expected: &[T],
    fraction: f64,
    differs: impl Fn(&T, &T) -> bool,
    what: &str,
) {
    assert_eq!(actual.len(), expected.len(), "{what}: sizes");
    let n = actual.iter().zip(expected).filter(|(a, e)| differs(a, e)).count();
    assert!(
        (n as f64) <= fraction * actual.len() as f64,
        "{what}: {n} of {} pixels differ (at most {:.1}% may)",
        actual.len(),
        fraction * 100.0
    );
}

/// A right-angle corner: a floor y = 0 and a wall x = 0, each `size` a side, meeting along the
/// z axis from z = 0 to z = size.
pub fn corner(size: f32) -> Scene {
    let floor = [Vec3::ZERO, Vec3::new(0.0, 0.0, size), Vec3::new(size, 0.0, size)];
    let floor2 = [Vec3::ZERO, Vec3::new(size, 0.0, size), Vec3::new(size, 0.0, 0.0)];
    let wall = [Vec3::ZERO, Vec3::new(0.0, size, 0.0), Vec3::new(0.0, size, size)];
    let wall2 = [Vec3::ZERO, Vec3::new(0.0, size, size), Vec3::new(0.0, 0.0, size)];
    let mut scene = soup(&[floor, floor2, wall, wall2], true);
    scene.ambient = Vec3::splat(0.2);
    scene
}

/// The exact surface of [`corner`] at every pixel centre of frame `f`: view depth and normal
/// (from intersecting the pixel's ray with the two planes), and the world point; depth 0 where
/// the ray misses.
pub fn corner_surface(f: &FrameUniform, size: f32) -> Vec<(deep_gbuffer::GSample, Vec3)> {
    let to_world = |v: Vec3| glam::Mat4::from_cols_array_2d(&f.inv_view).transform_point3(v);
    (0..f.width * f.height)
        .map(|p| {
            let px = glam::Vec2::new((p % f.width) as f32 + 0.5, (p / f.width) as f32 + 0.5);
            let eye = to_world(Vec3::ZERO);
            // The point at view depth 1 on this pixel's ray: a point at depth d is eye + d dir.
            let dir = to_world(deep_gbuffer::cpu::ao::view_position(f, px, 1.0)) - eye;
            let mut best = (deep_gbuffer::GSample::default(), Vec3::ZERO);
            for (axis, normal) in [(1, Vec3::Y), (0, Vec3::X)] {
                let d = -eye[axis] / dir[axis];
                let hit = eye + d * dir;
                let inside = (0..3).all(|a| a == axis || (0.0..=size).contains(&hit[a]));
                if d > 0.0 && inside && (best.0.depth == 0.0 || d < best.0.depth) {
                    best = (deep_gbuffer::GSample { depth: d, normal, ..Default::default() }, hit);
                }
            }
            best
        })
        .collect()
}

/// Obscurance `(1/pi) integral max(1 - d^2/r^2, 0) cos(theta) dw` of a point at distance `x`
/// from an infinite wall perpendicular to its own (infinite) plane, for radius `r`. With the
/// polar axis towards the wall, a = cos(alpha), the wall is hit at d = x / a, and the cosine to
/// the normal integrates over the half circle to 2 sin(alpha), so with u = x / r and
/// A = acos(u):
///     O = (2/pi) integral_0^A sin^2(alpha) (1 - u^2 / cos^2(alpha)) d alpha
///       = (2/pi) (A/2 - sin(2A)/4 - u^2 (tan A - A)).
/// At the crease (u = 0) it is 1/2: the wall fills half the hemisphere at distance 0.
pub fn corner_obscurance(x: f32, r: f32) -> f32 {
    let u = (x / r) as f64;
    if u >= 1.0 {
        return 0.0;
    }
    let a = u.acos();
    let o = std::f64::consts::FRAC_2_PI * (a / 2.0 - (2.0 * a).sin() / 4.0 - u * u * (a.tan() - a));
    o as f32
}

/// Adds an emissive quad (nothing else: base colour 0) facing a camera that looks down -z, at
/// view depth `z`, spanning x in `xs` and y in [-5, 5].
pub fn emissive_quad(scene: &mut Scene, z: f32, xs: (f32, f32), emissive: Vec3) {
    let material = scene.materials.len() as u32;
    scene.materials.push(deep_gbuffer::scene::Material {
        emissive,
        base_color: glam::Vec4::ZERO,
        ..Default::default()
    });
    let positions = [
        Vec3::new(xs.0, -5.0, -z),
        Vec3::new(xs.1, -5.0, -z),
        Vec3::new(xs.1, 5.0, -z),
        Vec3::new(xs.0, 5.0, -z),
    ];
    let indices = [0, 1, 2, 0, 2, 3];
    let mesh = deep_gbuffer::scene::MeshData {
        positions: &positions,
        indices: &indices,
        material,
        ..Default::default()
    };
    scene.push_mesh(mesh).expect("indices in range");
}

/// The RMSE of `image` against `truth` over the visible pixels of the columns within
/// `half_width` of the middle (`width` pixels a row).
#[cfg(feature = "truth")]
pub fn middle_rmse(
    image: &[glam::Vec4],
    truth: &deep_gbuffer::truth::TruthImage,
    width: u32,
    half_width: f32,
) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (p, (o, t)) in image.iter().zip(&truth.value).enumerate() {
        let x = (p as u32 % width) as f32;
        if truth.visible[p] && (x - width as f32 / 2.0).abs() < half_width {
            sum += f64::from((o.truncate() - *t).length_squared());
            n += 1;
        }
    }
    (sum / n as f64).sqrt()
}

/// What a pass after the composite reads, from a renderer's last frame: both layers' samples
/// (layer 1 empty when it was not drawn), layer 1's direct radiance, the composite's image and
/// the final one.
pub struct PostInputs {
    pub layers: [Vec<deep_gbuffer::GSample>; 2],
    pub direct1: Vec<Vec3>,
    pub sharp: Vec<glam::Vec4>,
    pub out: Vec<glam::Vec4>,
}

/// Reads [`PostInputs`] from `r` (a post pass ran in its last frame).
pub fn post_inputs(r: &Renderer) -> PostInputs {
    let g = gpu();
    let plan = r.last_plan().expect("a frame was rendered");
    let pixels = r.settings().width as usize * r.settings().height as usize;
    let layers = [0, 1].map(|l| {
        if l < plan.layers as usize {
            r.read_gbuffer(&g.device, &g.queue, l).expect("read layer").samples
        } else {
            vec![Default::default(); pixels]
        }
    });
    PostInputs {
        layers,
        direct1: r.read_rgb(&g.device, &g.queue, r.direct1_buffer()).expect("read direct"),
        sharp: read4(r, r.sharp_buffer().expect("a post pass ran")),
        out: read4(r, r.hdr_buffer()),
    }
}

/// A black, double-sided mirror: reflectivity 1, roughness 0.
pub fn mirror() -> deep_gbuffer::scene::Material {
    deep_gbuffer::scene::Material {
        name: "mirror".into(),
        base_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
        reflectivity: 1.0,
        roughness: 0.0,
        double_sided: true,
        ..Default::default()
    }
}

/// A mirror floor (material 0: reflectivity 1, black) and a wall of material `wall` standing on
/// it at `wall_z`, `half_width` either side of x = 0 and `height` tall.
pub fn mirror_before_a_wall(
    wall: deep_gbuffer::scene::Material,
    wall_z: f32,
    half_width: f32,
    height: f32,
) -> Scene {
    let mut scene = Scene::default();
    scene.materials.push(mirror());
    scene.materials.push(deep_gbuffer::scene::Material { double_sided: true, ..wall });
    let side = 4.0 * half_width.max(-wall_z);
    let floor = [
        Vec3::new(-side, 0.0, -side),
        Vec3::new(side, 0.0, -side),
        Vec3::new(side, 0.0, side),
        Vec3::new(-side, 0.0, side),
    ];
    let quad = [
        Vec3::new(-half_width, 0.0, wall_z),
        Vec3::new(half_width, 0.0, wall_z),
        Vec3::new(half_width, height, wall_z),
        Vec3::new(-half_width, height, wall_z),
    ];
    for (quad, material) in [(floor, 0), (quad, 1)] {
        scene
            .push_mesh(deep_gbuffer::scene::MeshData {
                positions: &quad,
                normals: &[],
                uvs: &[],
                indices: &[0, 1, 2, 0, 2, 3],
                material,
                ..deep_gbuffer::scene::MeshData::default()
            })
            .unwrap();
    }
    scene
}
