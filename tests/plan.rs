//! The plan runs only what a scene and the settings call for, and the renderer issues exactly
//! the planned passes (a skipped pass has no GPU work and no timing).

mod common;

use common::{gpu, render, render_frames};
use deep_gbuffer::{
    AoSettings, Effect, Effects, Layer1Variant, PassId, Plan, Reason, Scene, SceneInfo, Settings,
};
use glam::Vec3;

fn no_radiosity() -> deep_gbuffer::RadiositySettings {
    deep_gbuffer::RadiositySettings { enabled: false, ..Default::default() }
}

#[test]
fn radiosity_reads_layer_1_and_needs_light() {
    let plan =
        Plan::new(&SceneInfo { ambient: Vec3::ZERO, ..cornell_info() }, &Settings::default());
    assert_eq!((plan.layers, plan.reason(Effect::Radiosity)), (2, None));
    let dark = SceneInfo { lights: Vec::new(), emissive: false, ..cornell_info() };
    assert_eq!(
        Plan::new(&dark, &Settings::default()).reason(Effect::Radiosity),
        Some(Reason::NotNeeded)
    );
    let glowing = SceneInfo { lights: Vec::new(), ..cornell_info() };
    assert!(
        Plan::new(&glowing, &Settings::default()).runs(Effect::Radiosity),
        "emission alone lights the scene"
    );
}

/// The layer-1 gather runs where the radiosity does and layer 1 is drawn, unless its taps are 0.
#[test]
fn the_layer1_gather_follows_the_radiosity_and_layer_1() {
    let gathers = |settings: &Settings| {
        Plan::new(&cornell_info(), settings).contains(&PassId::RadiosityLayer1)
    };
    assert!(gathers(&Settings::default()));
    let printed = Plan::new(&cornell_info(), &Settings::default()).to_string();
    assert!(
        printed
            .contains("radiosity: runs, layer 1 gathers, off-screen light from the shadow maps\n"),
        "{printed}"
    );
    assert!(!gathers(&Settings { layers: 1, ..Settings::default() }), "no layer 1 drawn");
    let off = deep_gbuffer::RadiositySettings { layer1_samples: 0, ..Default::default() };
    let plan = Plan::new(&cornell_info(), &Settings { radiosity: off, ..Settings::default() });
    assert!(!plan.contains(&PassId::RadiosityLayer1));
    assert_eq!(plan.layers, 2, "the gather still reads layer 1");
    assert!(
        plan.to_string().contains("radiosity: runs, off-screen light from the shadow maps\n"),
        "{plan}"
    );
    assert!(!gathers(&Settings { radiosity: no_radiosity(), ..Settings::default() }));
    let too_many = deep_gbuffer::RadiositySettings { layer1_samples: 257, ..Default::default() };
    let e = too_many.validate().unwrap_err().to_string();
    assert!(e.contains("radiosity.layer1_samples"), "{e}");
}

/// The off-screen light runs with the radiosity where some light casts a shadow map to draw its
/// reflective shadow map from, and not when it is turned off.
#[test]
fn the_offscreen_light_follows_the_shadow_maps() {
    let runs = |info: &SceneInfo, settings: &Settings| {
        Plan::new(info, settings).contains(&PassId::RadiosityOffscreen)
    };
    let info = cornell_info();
    assert!(runs(&info, &Settings::default()));
    let mut off = Settings::default();
    off.radiosity.offscreen = false;
    assert!(!runs(&info, &off), "turned off");
    assert!(!Plan::new(&info, &off).to_string().contains("off-screen"));
    let mut no_shadows = Settings::default();
    no_shadows.shadows.enabled = false;
    assert!(!runs(&info, &no_shadows), "no shadow map to draw it from");
    let mut unshadowed = cornell_info();
    unshadowed.lights.iter_mut().for_each(|l| l.casts_shadows = false);
    assert!(!runs(&unshadowed, &Settings::default()), "no light casts a shadow");
    let glowing = SceneInfo { lights: Vec::new(), ..cornell_info() };
    assert!(!runs(&glowing, &Settings::default()), "emission alone");
    assert!(!runs(&info, &Settings { radiosity: no_radiosity(), ..Settings::default() }));
}

fn cornell_info() -> SceneInfo {
    SceneInfo::of(&Scene::from_spec("builtin:cornell").unwrap())
}

#[test]
fn cornell_runs_everything_it_has() {
    let plan = Plan::new(&cornell_info(), &Settings::default());
    assert_eq!(plan.layers, 2);
    assert_eq!(
        plan.left_out,
        [
            (Effect::Reflections, Reason::NotNeeded),
            (Effect::Dof, Reason::NotNeeded),
            (Effect::MotionBlur, Reason::NotNeeded),
            (Effect::Transparency, Reason::NotNeeded)
        ],
        "no mirror or glass in the box, its camera is a pinhole, and the shutter is closed"
    );
    assert_eq!(
        plan.passes,
        [
            PassId::RasterClear,
            PassId::RasterLayer0,
            PassId::RasterLayer1,
            PassId::Resolve,
            PassId::Pyramid,
            PassId::Ao,
            PassId::AoBlur,
            ceiling_shadow(),
            PassId::Direct,
            PassId::Radiosity,
            PassId::RadiosityOffscreen,
            PassId::RadiosityLayer1,
            PassId::RadiosityTemporal,
            PassId::RadiosityBlur,
            PassId::Composite
        ]
    );
    assert_eq!(plan.names()[7], "shadow.ceiling");
}

fn ceiling_shadow() -> PassId {
    PassId::Shadow { light: 0, name: "ceiling".into() }
}

#[test]
fn no_ambient_means_no_obscurance_and_no_second_layer() {
    let info = SceneInfo { ambient: Vec3::ZERO, ..cornell_info() };
    // Radiosity reads layer 1 too: with it off, nothing does.
    let plan = Plan::new(&info, &Settings { radiosity: no_radiosity(), ..Settings::default() });
    assert_eq!((plan.layers, plan.reason(Effect::Ao)), (1, Some(Reason::NotNeeded)));
    assert_eq!(
        plan.passes,
        [
            PassId::RasterClear,
            PassId::RasterLayer0,
            PassId::Resolve,
            ceiling_shadow(),
            PassId::Direct,
            PassId::Composite
        ]
    );
}

#[test]
fn no_light_means_no_direct_pass() {
    let info = SceneInfo { lights: Vec::new(), ..cornell_info() };
    let plan = Plan::new(&info, &Settings::default());
    assert_eq!(plan.reason(Effect::Direct), Some(Reason::NotNeeded));
    assert_eq!(plan.reason(Effect::Shadows), Some(Reason::NotNeeded));
    assert!(!plan.passes.iter().any(|p| matches!(p, PassId::Direct | PassId::Shadow { .. })));
}

#[test]
fn switched_off_effects_cost_nothing() {
    let info = cornell_info();
    let only_direct =
        Settings { effects: Effects::parse("direct").unwrap(), ..Settings::default() };
    let plan = Plan::new(&info, &only_direct);
    assert_eq!((plan.layers, plan.reason(Effect::Ao)), (1, Some(Reason::Disabled)));
    let one_layer_ao = Settings {
        ao: AoSettings { two_layers: false, ..Default::default() },
        radiosity: no_radiosity(),
        ..Settings::default()
    };
    let plan = Plan::new(&info, &one_layer_ao);
    assert_eq!((plan.layers, plan.runs(Effect::Ao), plan.ao_two_layers), (1, true, false));
    let no_blur =
        Settings { ao: AoSettings { blur_radius: 0, ..Default::default() }, ..Settings::default() };
    assert!(!Plan::new(&info, &no_blur).contains(&PassId::AoBlur));
    let forced =
        Settings { layers: 2, effects: Effects::parse("direct").unwrap(), ..Settings::default() };
    assert_eq!(Plan::new(&info, &forced).layers, 2, "a host can ask for layer 1 itself");
    let no_shadows =
        Settings { effects: Effects::parse("ao,direct").unwrap(), ..Settings::default() };
    let plan = Plan::new(&info, &no_shadows);
    assert_eq!(plan.reason(Effect::Shadows), Some(Reason::Disabled));
    assert!(plan.shadow_lights().is_empty());
    assert!(Effects::parse("ao,bogus").unwrap_err().to_string().contains("bogus"));
    assert_eq!(Effects::parse("auto").unwrap(), Effects::default());
}

#[test]
fn one_pass_variants_plan_raster_layers() {
    let settings = Settings { layer1: Layer1Variant::Reproject, ..Settings::default() };
    let plan = Plan::new(&cornell_info(), &settings);
    assert_eq!(&plan.passes[..3], [PassId::RasterClear, PassId::RasterLayers, PassId::Resolve]);
}

/// The passes recorded, and the passes timed, are exactly the plan's.
#[test]
fn the_renderer_runs_and_times_exactly_the_plan() {
    let g = gpu();
    assert!(
        g.device.features().contains(wgpu::Features::TIMESTAMP_QUERY),
        "lavapipe has timestamp queries"
    );
    let mut scene = Scene::from_spec("builtin:cornell").unwrap();
    for (ambient, variant) in [
        (Vec3::splat(0.1), Layer1Variant::TwoPass),
        (Vec3::ZERO, Layer1Variant::TwoPass),
        (Vec3::splat(0.1), Layer1Variant::Previous),
    ] {
        scene.ambient = ambient;
        let camera = scene.camera_or_default();
        let settings = Settings { layer1: variant, ..Settings::with_size(32, 24) };
        // From the third frame of a still camera on, every variant keeps the same passes.
        let r = render_frames(&scene, &[camera.clone(), camera.clone(), camera.clone()], settings);
        let plan = r.renderer.last_plan().unwrap().clone();
        let planned = r.renderer.plan(&r.buffers, &camera);
        assert_eq!(plan, planned, "the plan is stable from frame to frame");
        assert_eq!(r.renderer.passes(), &plan.passes[..]);
        let timed: Vec<String> =
            r.renderer.timings(&g.device).unwrap().into_iter().map(|t| t.name).collect();
        assert_eq!(timed, plan.names(), "ambient {ambient} {variant:?}");
    }
}

/// A preset sets the accuracy knobs; a two-layer preset still lets the plan drop layer 1 where
/// no effect reads it.
#[test]
fn presets_set_the_knobs_and_keep_the_plan_in_charge_of_layers() {
    use deep_gbuffer::Preset;
    let mut low = Settings::default();
    Preset::Low.apply(&mut low);
    assert_eq!((low.ao.samples, low.ao.slices, low.radiosity.samples, low.layers), (32, 2, 32, 1));
    assert_eq!((low.ao.downsample, low.radiosity.downsample), (2, 2));
    assert_eq!(low.ao.estimator, deep_gbuffer::AoEstimator::Bitmask);
    assert_eq!(low.precision, deep_gbuffer::Precision::Full);
    assert!(!low.reflections.shadow_maps, "low keeps reflections on screen");
    let mut ultra = Settings::default();
    Preset::Ultra.apply(&mut ultra);
    assert_eq!(
        (ultra.ao.samples, ultra.ao.slices, ultra.ao.blur_radius, ultra.radiosity.samples),
        (64, 4, 3, 64)
    );
    assert_eq!(ultra.layers, 0);
    // The quality presets gather every radiosity slice on every frame, under the filter they
    // were measured with; the others one slice a moving frame, as the defaults.
    assert_eq!((ultra.radiosity.history_slices, ultra.radiosity.alpha), (0, 0.85));
    let defaults = deep_gbuffer::RadiositySettings::default();
    assert_eq!((low.radiosity.history_slices, low.radiosity.alpha), (1, defaults.alpha));
    assert_eq!(low.ao.blur_radius, Settings::default().ao.blur_radius);
    assert!(ultra.ao.two_layers);
    assert!(ultra.reflections.shadow_maps);
    for preset in [Preset::Low, Preset::Balanced, Preset::High, Preset::Ultra] {
        let mut s = Settings::default();
        preset.apply(&mut s);
        s.validate().unwrap();
    }
}

/// A layer the last frame did not draw is a typed error, not an empty or a stale layer: before
/// any frame, layer 1 of a one-layer frame, and a layer past the two.
#[test]
fn reading_a_layer_the_frame_did_not_draw_is_refused() {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let buffers = deep_gbuffer::SceneBuffers::upload(&g.device, &scene).unwrap();
    let settings = Settings { layers: 1, timings: false, ..Settings::with_size(16, 12) };
    let mut renderer = deep_gbuffer::Renderer::new(&g.device, &g.queue, settings).unwrap();
    let refused = |r: &deep_gbuffer::Renderer, layer: usize, drawn: usize| {
        match r.read_gbuffer(&g.device, &g.queue, layer) {
            Err(deep_gbuffer::Error::LayerNotDrawn { layer: l, drawn: d }) => {
                assert_eq!((l, d), (layer, drawn))
            }
            other => panic!("layer {layer}: {:?}", other.map(|_| ())),
        }
        assert!(matches!(
            r.read_visibility(&g.device, &g.queue, layer),
            Err(deep_gbuffer::Error::LayerNotDrawn { .. })
        ));
    };
    refused(&renderer, 0, 0);
    renderer.render(&g.device, &g.queue, &buffers, &scene.camera_or_default()).unwrap();
    assert_eq!(renderer.last_plan().unwrap().layers, 1);
    assert!(renderer.read_gbuffer(&g.device, &g.queue, 0).is_ok());
    refused(&renderer, 1, 1);
    refused(&renderer, 7, 1);
}

/// The default lengths suit a scene about 2 units across; `scale_for` gives the power of two
/// nearest to a scene's size over that, and `scaled` multiplies every length by it, nothing
/// else.
#[test]
fn default_lengths_follow_the_scene_size_in_powers_of_two() {
    let cornell = Scene::from_spec("builtin:cornell").unwrap();
    assert_eq!(Settings::scale_for(cornell.extent()), 1.0, "the Cornell box keeps the defaults");
    let grid = Scene::from_spec("builtin:grid-20000").unwrap();
    assert_eq!(Settings::scale_for(grid.extent()), 4.0, "9 units across");
    for (extent, scale) in [(743.4, 512.0), (0.3, 0.125), (2.9, 2.0), (2.8, 1.0)] {
        assert_eq!(Settings::scale_for(extent), scale, "{extent}");
    }
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert_eq!(Settings::scale_for(bad), 1.0, "{bad}");
    }
    let (d, s) = (Settings::default(), Settings::default().scaled(4.0));
    assert_eq!(
        [s.ao.radius, s.ao.bias, s.radiosity.radius, s.radiosity.history_tolerance, s.dz],
        [d.ao.radius, d.ao.bias, d.radiosity.radius, d.radiosity.history_tolerance, d.dz]
            .map(|v| 4.0 * v)
    );
    assert_eq!(s.reflections.thickness, 4.0 * d.reflections.thickness);
    assert_eq!(s.reflections.max_distance, f32::INFINITY);
    let counts = |x: &Settings| (x.ao.samples, x.ao.slices, x.ao.thickness, x.radiosity.samples);
    assert_eq!(counts(&s), counts(&d), "counts and fractions stay");
    s.validate().unwrap();
}

/// The default shadow-map resolution follows how many pixels the scene spans: the Cornell box
/// filling a 640x480 view (about 440 pixels tall) keeps 512, the same view at 1920x1080 (about
/// 1000 pixels) gets 1024, a far camera or a
/// small image 512, a camera inside the scene the image's side (at most 4096), at any scale.
#[test]
fn default_shadow_resolution_follows_the_pixels_the_scene_spans() {
    use deep_gbuffer::ShadowSettings;
    let cornell = Scene::from_spec("builtin:cornell").unwrap();
    let bounds = cornell.bounds();
    let fitted = cornell.fit_camera(&cornell.camera_or_default(), 640.0 / 480.0);
    assert_eq!(ShadowSettings::resolution_for(640, 480, &fitted, bounds), 512);
    let wide = cornell.fit_camera(&cornell.camera_or_default(), 1920.0 / 1080.0);
    assert_eq!(ShadowSettings::resolution_for(1920, 1080, &wide, bounds), 1024);
    let mut far = fitted.clone();
    far.eye = far.target + (far.eye - far.target) * 10.0;
    assert_eq!(ShadowSettings::resolution_for(640, 480, &far, bounds), 512);
    let mut inside = fitted.clone();
    inside.eye = glam::Vec3::ZERO;
    assert_eq!(ShadowSettings::resolution_for(1920, 1080, &inside, bounds), 2048);
    assert_eq!(ShadowSettings::resolution_for(8000, 8000, &inside, bounds), 4096);
    assert_eq!(ShadowSettings::resolution_for(640, 480, &fitted, None), 512);
    // The same view of the same box 1000 times larger: the same resolution.
    let big = |v: glam::Vec3| v * 1000.0;
    let mut scaled = fitted.clone();
    (scaled.eye, scaled.target) = (big(fitted.eye), big(fitted.target));
    let bounds = bounds.map(|(a, b)| (big(a), big(b)));
    assert_eq!(ShadowSettings::resolution_for(1920, 1080, &scaled, bounds), 1024);
}

/// An obscurance or radiosity radius that spans less than a pixel even at the scene's nearest
/// point leaves its effect out and says why; the same settings from the scene's own camera run
/// it, and a frame from far away records no obscurance or radiosity pass.
#[test]
fn a_radius_under_a_pixel_leaves_its_effect_out() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let info = SceneInfo::of(&scene);
    let near = scene.camera_or_default();
    let settings = Settings::with_size(64, 48);
    let plan = Plan::for_view(&info, &settings, &near);
    assert!(plan.runs(Effect::Ao) && plan.runs(Effect::Radiosity));
    // 10,000 units away the box is a speck: a radius of 0.5 spans a thousandth of a pixel.
    let mut far = near.clone();
    far.eye = far.target + (far.eye - far.target).normalize() * 1e4;
    let span = deep_gbuffer::plan::pixels_spanned(&far, 48, info.bounds, settings.ao.radius);
    assert!(span > 0.0 && span < 0.01, "{span}");
    let plan = Plan::for_view(&info, &settings, &far);
    assert_eq!(plan.reason(Effect::Ao), Some(Reason::UnderAPixel));
    assert_eq!(plan.reason(Effect::Radiosity), Some(Reason::UnderAPixel));
    assert!(plan.runs(Effect::Direct));
    assert!(plan.to_string().contains("less than a pixel"), "{plan}");
    // A radius that reaches a pixel again runs, as does an unknown extent.
    let wide =
        Settings { ao: AoSettings { radius: 5000.0, ..AoSettings::default() }, ..settings.clone() };
    assert!(Plan::for_view(&info, &wide, &far).runs(Effect::Ao));
    let unknown = SceneInfo { bounds: None, ..info.clone() };
    assert!(Plan::for_view(&unknown, &settings, &far).runs(Effect::Ao));
    // The renderer plans with its camera: the far frame records neither pass.
    let r = render_frames(&scene, &[far], settings);
    let passes = r.renderer.passes();
    assert!(!passes.contains(&PassId::Ao) && !passes.contains(&PassId::Radiosity), "{passes:?}");
}

/// Each pass's bytes: every storage buffer it binds, once, at its size. The direct pass of the
/// Cornell box (radiosity on, so both layers and their Lambertian parts) writes exactly four
/// images of `vec4<f32>` and layer 1's list, and reads at least both G-buffer layers; every
/// pass that ran has its bytes; the device's bandwidth probe measures positive, finite rates.
#[test]
fn passes_report_the_bytes_they_bind() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let (w, h) = (48u32, 36u32);
    let r = render(&scene, &scene.camera_or_default(), Settings::with_size(w, h));
    let g = gpu();
    let pixels = u64::from(w * h);
    let timings = r.renderer.timings(&g.device).unwrap();
    let direct = timings.iter().find(|t| t.name == "direct").expect("the direct pass ran");
    // Layer 1 is lit at its listed pixels: the list (a count, an index a pixel) and its
    // dispatch arguments (three words in a buffer of the 16 bytes `gpu::storage_buffer` makes at
    // least) are written too.
    let list = (1 + pixels) * 4 + 16;
    assert_eq!(
        direct.written_bytes,
        4 * pixels * 16 + list,
        "radiance and diffuse of both layers, the list"
    );
    let gbuffers = r.renderer.gbuffer_buffer(0).size() + r.renderer.gbuffer_buffer(1).size();
    assert!(direct.read_bytes >= gbuffers, "{} < {gbuffers}", direct.read_bytes);
    for t in &timings {
        assert!(t.read_bytes + t.written_bytes > 0, "{} binds nothing", t.name);
    }
    let traffic = r.renderer.traffic();
    assert_eq!(
        traffic.iter().map(|t| t.name.as_str()).collect::<Vec<_>>(),
        timings.iter().map(|t| t.name.as_str()).collect::<Vec<_>>()
    );
    let bandwidth = deep_gbuffer::gpu::measure_bandwidth(&g.device, &g.queue, 16 << 20)
        .unwrap()
        .expect("the test device has timestamps");
    assert!(bandwidth.read_bytes_per_s > 1e8 && bandwidth.read_bytes_per_s.is_finite());
    assert!(bandwidth.write_bytes_per_s > 1e8 && bandwidth.write_bytes_per_s.is_finite());
}

/// A still frame keeps what the frame before wrote and it would write again (the G-buffer, the
/// obscurance, the direct light) and gathers the radiosity's next bounce on it: its terms are,
/// bit for bit, those of a renderer that runs every pass. A frame is still when its camera and
/// the last frame's are those of the frame before (the G-buffer's motion is then the same);
/// a moved camera, moved geometry, `redraw` or `reset_history` run every pass again.
#[test]
fn a_still_frame_keeps_what_it_would_write_again() {
    let g = gpu();
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    let buffers = deep_gbuffer::SceneBuffers::upload(&g.device, &scene).unwrap();
    let a = scene.camera_or_default();
    let b = deep_gbuffer::Camera { eye: a.eye + Vec3::new(0.3, 0.1, 0.0), ..a.clone() };
    // A still view that averages its obscurance over frames computes it again (tested in
    // tests/ao.rs); here it is kept at once, as everything else a still frame would write.
    let ao = deep_gbuffer::AoSettings { still_frames: 0, ..Default::default() };
    let settings = Settings { timings: false, ao, ..Settings::with_size(40, 30) };
    let mut kept = deep_gbuffer::Renderer::new(&g.device, &g.queue, settings.clone()).unwrap();
    let mut full = deep_gbuffer::Renderer::new(&g.device, &g.queue, settings).unwrap();
    // (camera, what happens before the frame, whether the frame is still)
    let frames = [
        (&a, "", false),
        // The first frame's G-buffer has no motion: the second keeps it.
        (&a, "", true),
        (&a, "", true),
        (&b, "", false),
        // The last frame moved: its G-buffer's motion is not this frame's.
        (&b, "", false),
        (&b, "", true),
        (&a, "", false),
        (&a, "", false),
        (&a, "geometry_changed", false),
        (&a, "", false),
        (&a, "", true),
        (&a, "redraw", false),
        (&a, "", true),
        (&a, "reset_history", false),
        (&a, "", true),
    ];
    let mut large = 0;
    for (i, (camera, event, still)) in frames.into_iter().enumerate() {
        match event {
            "geometry_changed" => {
                kept.geometry_changed();
                full.geometry_changed();
            }
            "redraw" => kept.redraw(),
            "reset_history" => {
                kept.reset_history();
                full.reset_history();
            }
            _ => {}
        }
        full.redraw();
        for r in [&mut kept, &mut full] {
            r.render(&g.device, &g.queue, &buffers, camera).unwrap();
        }
        let plan = kept.last_plan().unwrap();
        let same: Vec<&PassId> = plan.passes.iter().filter(|p| p.same_when_still()).collect();
        let reused: Vec<&PassId> = plan.reused.iter().filter(|p| p.same_when_still()).collect();
        if still {
            assert!(same.is_empty(), "frame {i} ({event}) keeps {reused:?}, runs {same:?}");
            for pass in [PassId::Resolve, PassId::Pyramid, PassId::Ao, PassId::Direct] {
                assert!(plan.reused.contains(&pass), "frame {i} keeps {pass}");
            }
            assert!(plan.contains(&PassId::Radiosity) && plan.contains(&PassId::Composite));
            assert!(plan.to_string().contains("kept from the last frame (still): raster.clear"));
        } else {
            assert!(reused.is_empty(), "frame {i} ({event}) runs every pass, keeps {reused:?}");
        }
        assert_eq!(kept.passes(), &plan.passes[..]);
        let full_plan = full.last_plan().unwrap();
        assert!(full_plan.reused.is_empty(), "redraw keeps nothing: {:?}", full_plan.reused);
        let (x, y) = (
            kept.read_terms(&g.device, &g.queue).unwrap(),
            full.read_terms(&g.device, &g.queue).unwrap(),
        );
        assert_eq!(x.av, y.av, "frame {i}: obscurance");
        assert_eq!(x.direct, y.direct, "frame {i}: direct light");
        assert_eq!(x.indirect, y.indirect, "frame {i}: gathered light");
        assert_eq!(x.hdr, y.hdr, "frame {i}: image");
        // A still frame draws nothing: the counters are those of the frame before (here the
        // shadow maps' large triangles, counted in the frames that draw them).
        let counted = kept.diagnostics(&g.device, &g.queue).unwrap().large_triangles;
        if still {
            assert_eq!(counted, large, "frame {i}");
        }
        large = counted;
    }
}
