//! Transparency: the peels and their blend against the CPU reference, the closed-form blend of
//! parallel planes, k = 1, triangle order, the plan, alpha-tested holes, the loaders' alpha
//! modes and the stochastic truth.

mod common;

use common::{gpu, read4, render};
use deep_gbuffer::cpu::raster::{self as cpu, RasterInput, double_sided_triangles};
use deep_gbuffer::cpu::transparency::TransparencyInputs;
use deep_gbuffer::plan::{Effect, PassId, Reason};
use deep_gbuffer::scene::{AlphaMode, Material, MeshData, Texture, TextureRef};
use deep_gbuffer::truth::{Shot, Tracer};
use deep_gbuffer::{Camera, Effects, Scene, Settings, TransparencySettings};
use glam::{Vec2, Vec3, Vec4};

fn settings(w: u32, h: u32, layers: u32) -> Settings {
    let mut s = Settings { timings: false, ..Settings::with_size(w, h) };
    s.transparency = TransparencySettings { layers, ..Default::default() };
    s.shadows.enabled = false;
    s
}

/// A camera at the origin looking down -z.
fn camera() -> Camera {
    Camera::perspective(Vec3::ZERO, Vec3::NEG_Z, 40.0, 0.05)
}

/// Adds a quad facing the camera at view depth `z` over x and y in [-half, half] with `material`.
fn quad(scene: &mut Scene, z: f32, half: f32, material: Material) {
    let index = scene.materials.len() as u32;
    scene.materials.push(material);
    let positions = [
        Vec3::new(-half, -half, -z),
        Vec3::new(half, -half, -z),
        Vec3::new(half, half, -z),
        Vec3::new(-half, half, -z),
    ];
    let uvs = [Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)];
    let indices = [0, 1, 2, 0, 2, 3];
    let mesh = MeshData {
        positions: &positions,
        uvs: &uvs,
        indices: &indices,
        material: index,
        ..Default::default()
    };
    scene.push_mesh(mesh).expect("indices in range");
}

/// An emissive surface (base colour 0: it reflects nothing), blended with `opacity` or opaque.
fn emitter(emissive: Vec3, opacity: Option<f32>) -> Material {
    Material {
        base_color: Vec4::new(0.0, 0.0, 0.0, opacity.unwrap_or(1.0)),
        emissive,
        double_sided: true,
        alpha_mode: if opacity.is_some() { AlphaMode::Blend } else { AlphaMode::Opaque },
        ..Default::default()
    }
}

/// An opaque emissive wall at depth 6 and blended emissive planes at depths 2 and 4 (opacity
/// 0.3 and 0.6), nearer ones smaller so that every combination shows.
fn planes() -> (Scene, [(Vec3, f32); 2], Vec3) {
    let back = Vec3::new(0.1, 0.2, 0.9);
    let glass = [(Vec3::new(2.0, 0.5, 0.1), 0.3), (Vec3::new(0.2, 1.5, 0.3), 0.6)];
    let mut scene = Scene::default();
    quad(&mut scene, 6.0, 10.0, emitter(back, None));
    quad(&mut scene, 2.0, 0.4, emitter(glass[0].0, Some(glass[0].1)));
    quad(&mut scene, 4.0, 1.2, emitter(glass[1].0, Some(glass[1].1)));
    (scene, glass, back)
}

/// What the CPU reference reads of the frame `r` drew (no shadows: the tests switch them off).
fn cpu_inputs<'a>(
    r: &'a common::Rendered,
    scene: &'a Scene,
    layers: u32,
    behind: &'a [Vec4],
) -> TransparencyInputs<'a> {
    TransparencyInputs { frame: &r.frame, scene, opaque: &r.vis0, layers, shadows: None, behind }
}

fn centre(image: &[Vec4], w: u32, h: u32) -> Vec3 {
    image[((h / 2) * w + w / 2) as usize].truncate()
}

#[test]
fn parallel_planes_blend_in_closed_form() {
    let (scene, [(e1, a1), (e2, a2)], back) = planes();
    let (w, h) = (32, 24);
    let r = render(&scene, &camera(), settings(w, h, 4));
    let plan = r.renderer.last_plan().unwrap();
    assert!(
        plan.contains(&PassId::TransparencyPeel) && plan.contains(&PassId::TransparencyComposite),
        "{plan}"
    );
    let image = read4(&r.renderer, r.renderer.hdr_buffer());
    let expected = a1 * e1 + (1.0 - a1) * (a2 * e2 + (1.0 - a2) * back);
    let got = centre(&image, w, h);
    // The closed form to f32 rounding (a few products and sums of values near 1).
    assert!(
        (got - expected).abs().max_element() < 1e-5 * expected.max_element(),
        "{got} against {expected}"
    );
    // A pixel outside the near plane sees the far blended plane over the wall.
    let p = (h / 2 * w + w / 2 + 8) as usize;
    let expected = a2 * e2 + (1.0 - a2) * back;
    assert!(
        (image[p].truncate() - expected).abs().max_element() < 1e-5,
        "{} against {expected}",
        image[p]
    );
    // k = 1 keeps the nearest blended surface only: what lies behind it shows through.
    let r = render(&scene, &camera(), settings(w, h, 1));
    let got = centre(&read4(&r.renderer, r.renderer.hdr_buffer()), w, h);
    let expected = a1 * e1 + (1.0 - a1) * back;
    assert!((got - expected).abs().max_element() < 1e-5, "k = 1: {got} against {expected}");
}

#[test]
fn peels_match_cpu_reference_on_the_glass_box() {
    let scene = Scene::from_spec("builtin:cornell-glass").unwrap();
    let camera = scene.camera_or_default();
    for layers in [1, 4] {
        let (w, h) = (64, 48);
        let r = render(&scene, &camera, settings(w, h, layers));
        let behind = read4(&r.renderer, r.renderer.sharp_buffer().expect("a post pass ran"));
        let out = read4(&r.renderer, r.renderer.hdr_buffer());
        let inputs = cpu_inputs(&r, &scene, layers, &behind);
        let peels = inputs.peels();
        let covered = peels[0].iter().filter(|&&w| w != u64::MAX).count();
        assert!(covered > (w * h / 10) as usize, "the panes cover the image ({covered})");
        if layers == 4 {
            let two = peels[1].iter().filter(|&&w| w != u64::MAX).count();
            assert!(two > 0 && two < covered, "some pixels see both panes ({two})");
            assert!(peels[2].iter().all(|&w| w == u64::MAX), "no third pane");
        }
        let expected = inputs.image();
        let mut changed = 0;
        for (p, (a, e)) in out.iter().zip(&expected).enumerate() {
            // f32 sums in another order.
            let tol = 1e-4 * e.max_element().max(1.0);
            assert!((*a - *e).abs().max_element() <= tol, "pixel {p}: {a} against {e}");
            changed += usize::from((*a - behind[p]).abs().max_element() > 1e-3);
        }
        assert!(changed > covered / 2, "the panes change what they cover ({changed})");
    }
}

/// The image depends on the triangles, not on their order (ties between fragments at one depth
/// go to the smaller id: only what lies at the same depth could tell).
#[test]
fn shuffled_triangles_leave_the_image_unchanged() {
    let (scene, ..) = planes();
    let mut shuffled = scene.clone();
    shuffled.triangles.reverse();
    shuffled.triangle_materials.reverse();
    let (w, h) = (32, 24);
    let a = render(&scene, &camera(), settings(w, h, 4));
    let b = render(&shuffled, &camera(), settings(w, h, 4));
    let image = read4(&a.renderer, a.renderer.hdr_buffer());
    assert_eq!(image, read4(&b.renderer, b.renderer.hdr_buffer()));
    // The panes were peeled and blended: the centre is not the wall behind them.
    let wall = read4(&a.renderer, a.renderer.sharp_buffer().expect("the blend ran"));
    assert!((centre(&image, w, h) - centre(&wall, w, h)).length() > 0.1);
}

#[test]
fn a_scene_without_blended_materials_runs_no_transparency_pass() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let s = settings(16, 12, 4);
    let plan = deep_gbuffer::Plan::new(&deep_gbuffer::SceneInfo::of(&scene), &s);
    assert_eq!(plan.reason(Effect::Transparency), Some(Reason::NotNeeded));
    assert!(!plan.names().iter().any(|n| n.starts_with("transparency")), "{plan}");
    let glass = Scene::from_spec("builtin:cornell-glass").unwrap();
    let info = deep_gbuffer::SceneInfo::of(&glass);
    let plan = deep_gbuffer::Plan::new(&info, &s);
    assert!(plan.runs(Effect::Transparency));
    assert!(plan.names().contains(&"transparency.peel".to_string()));
    let off =
        Settings { effects: Effects { transparency: false, ..Effects::default() }, ..s.clone() };
    assert_eq!(
        deep_gbuffer::Plan::new(&info, &off).reason(Effect::Transparency),
        Some(Reason::Disabled)
    );
    // Out-of-range peel counts are refused.
    for layers in [0, 17] {
        let mut bad = s.clone();
        bad.transparency.layers = layers;
        assert!(bad.validate().is_err(), "{layers} peels");
    }
}

/// A masked quad with a checkered alpha texture in front of a wall: the GPU rasterizer cuts the
/// same holes as the CPU's (bit for bit), through both layers; the same quad with a factor under
/// the cutoff and no texture is not drawn at all.
#[test]
fn masked_surfaces_are_holes_where_their_opacity_is_under_the_cutoff() {
    let (w, h) = (48, 32);
    let mut scene = Scene::default();
    quad(&mut scene, 6.0, 10.0, emitter(Vec3::ONE, None));
    let mut rgba8 = Vec::new();
    for y in 0..4u32 {
        for x in 0..4u32 {
            rgba8.extend_from_slice(&[255, 255, 255, if (x + y) % 2 == 0 { 255 } else { 0 }]);
        }
    }
    scene.textures.push(Texture { width: 4, height: 4, rgba8 });
    let mut masked = emitter(Vec3::new(1.0, 0.0, 0.0), None);
    masked.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    masked.base_color_texture =
        Some(TextureRef { filter: deep_gbuffer::Filter::Nearest, ..TextureRef::new(0) });
    quad(&mut scene, 3.0, 1.0, masked);
    let mut s = settings(w, h, 4);
    s.layers = 2;
    let r = render(&scene, &camera(), s.clone());
    let ds = double_sided_triangles(&scene);
    let input = RasterInput::new(&scene, &ds);
    let cpu0 = cpu::raster_layer0(&r.frame, &input);
    assert_eq!(r.vis0, cpu0, "layer 0 against the CPU's");
    assert_eq!(
        r.vis1,
        cpu::raster_layer1(&r.frame, &input, &cpu0, false),
        "layer 1 against the CPU's"
    );
    // At this size the quad's triangles take the rasterizer's one-thread path (at most 16
    // pixels across); at three times it they are binned, and the tiles' loop cuts the holes.
    let mut large = settings(3 * w, 3 * h, 4);
    large.layers = 2;
    let rl = render(&scene, &camera(), large);
    assert_eq!(rl.vis0, cpu::raster_layer0(&rl.frame, &input), "binned triangles, layer 0");
    let quad_ids = |vis: &[u64]| vis.iter().filter(|&&v| v != u64::MAX && (v as u32) >= 2).count();
    let on_quad = quad_ids(&r.vis0);
    assert!(quad_ids(&rl.vis0) > 8 * on_quad, "the large quad covers 9 times the pixels");
    // The quad spans about 2 / (2 * 3 * tan 20) of the height: some 29% of 48 x 32 in a square.
    let square = {
        let side = 2.0 / (2.0 * 3.0 * 20f32.to_radians().tan()) * h as f32;
        (side * side) as usize
    };
    assert!(
        on_quad > square * 2 / 5 && on_quad < square * 3 / 5,
        "half the quad is solid: {on_quad} of {square}"
    );
    // A factor under the cutoff without a texture: no fragment at all.
    let mut faded = scene.clone();
    faded.materials[1].base_color_texture = None;
    faded.materials[1].base_color.w = 0.4;
    let r = render(&faded, &camera(), s);
    assert_eq!(quad_ids(&r.vis0), 0);
    assert_eq!(quad_ids(&r.vis1), 0);
}

/// The truth traces blended surfaces stochastically: its mean converges to the closed-form
/// blend of the parallel planes.
#[test]
fn the_truth_blends_stochastically() {
    let (scene, [(e1, a1), (e2, a2)], back) = planes();
    let (w, h) = (8, 6);
    let tracer = Tracer::new(&scene).unwrap();
    let cam = camera();
    let shot = Shot { camera: &cam, size: (w, h), spp: 4096, seed: 1 };
    let truth = tracer.full(&scene, &shot, None, 0, &|| {}).unwrap();
    let p = ((h / 2) * w + w / 2) as usize;
    let expected = a1 * e1 + (1.0 - a1) * (a2 * e2 + (1.0 - a2) * back);
    let err = (truth.value[p] - expected).abs();
    assert!(
        err.max_element() < 4.0 * truth.stderr[p].max_element() + 1e-4,
        "{} ± {} against {expected}",
        truth.value[p],
        truth.stderr[p]
    );
    assert!(truth.stderr[p].max_element() > 0.0, "the estimate varies: it samples the blend");
}

/// OBJ materials: `d` below 1 (or `Tr` above 0) makes a blended material; a fully opaque one
/// stays opaque.
#[test]
fn obj_dissolve_and_transmission_make_blended_materials() {
    let dir = std::env::temp_dir().join(format!("deep-gbuffer-alpha-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("a.mtl"),
        "newmtl d\nKd 1 1 1\nd 0.25\nnewmtl tr\nKd 1 1 1\nTr 0.75\nnewmtl solid\nKd 1 1 1\n",
    )
    .unwrap();
    let obj = "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl d\nf 1 2 3\nusemtl tr\nf 1 2 3\nusemtl solid\nf 1 2 3\n";
    std::fs::write(dir.join("a.obj"), obj).unwrap();
    let scene = Scene::load(&dir.join("a.obj")).unwrap();
    let by_name = |n: &str| scene.materials.iter().find(|m| m.name == n).unwrap();
    assert_eq!(by_name("d").alpha_mode, AlphaMode::Blend);
    assert_eq!(by_name("d").base_color.w, 0.25);
    assert_eq!(by_name("tr").alpha_mode, AlphaMode::Blend);
    assert_eq!(by_name("tr").base_color.w, 0.25);
    assert_eq!(by_name("solid").alpha_mode, AlphaMode::Opaque);
    std::fs::write(dir.join("a.mtl"), "newmtl d\nKd 1 1 1\nTr x\n").unwrap();
    assert!(Scene::load(&dir.join("a.obj")).is_err(), "a Tr that is not a number is refused");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn negative_or_nan_alpha_cutoffs_are_refused() {
    for (cutoff, refused) in [(-1.0, true), (f32::NAN, true), (f32::INFINITY, true), (0.0, false)] {
        let mut scene = Scene::default();
        let mut m = emitter(Vec3::ONE, None);
        m.alpha_mode = AlphaMode::Mask { cutoff };
        quad(&mut scene, 2.0, 1.0, m);
        assert_eq!(scene.validate().is_err(), refused, "cutoff {cutoff}");
    }
}

/// Blended fragments behind the k-th peel are counted in the diagnostics (as many as the CPU
/// finds), and none are once k covers every surface.
#[test]
fn fragments_beyond_the_last_peel_are_reported() {
    let (scene, ..) = planes();
    let (w, h) = (32, 24);
    let g = gpu();
    for (layers, some) in [(1, true), (2, false), (8, false)] {
        let r = render(&scene, &camera(), settings(w, h, layers));
        let d = r.renderer.diagnostics(&g.device, &g.queue).unwrap();
        let ds = double_sided_triangles(&scene);
        let input = RasterInput::new(&scene, &ds);
        let behind = read4(&r.renderer, r.renderer.sharp_buffer().unwrap());
        let inputs = cpu_inputs(&r, &scene, layers, &behind);
        let peels = inputs.peels();
        let expected = cpu::unpeeled_fragments(&r.frame, &input, peels.last().unwrap(), &r.vis0);
        assert_eq!(d.unpeeled_fragments, expected, "k = {layers}");
        assert_eq!(expected > 0, some, "k = {layers}: {expected}");
        assert_eq!(d.warnings().is_empty(), !some, "{:?}", d.warnings());
    }
}
