//! The depth pyramid against its CPU reference.

mod common;

use common::{GBUFFER_FIXTURES, gpu, render, shade_fixture};
use deep_gbuffer::cpu::pyramid as cpu;
use deep_gbuffer::frame::PyramidLayout;
use deep_gbuffer::{Scene, Settings};

#[test]
fn pyramid_matches_cpu_reference_and_holds_real_depths() {
    let scene = Scene::from_spec("builtin:cornell").unwrap();
    for precision in [deep_gbuffer::Precision::Full, deep_gbuffer::Precision::Packed] {
        let (w, h) = (75, 53); // odd sizes: levels round up
        let r = render(
            &scene,
            &scene.camera_or_default(),
            Settings { precision, timings: false, layers: 2, ..Settings::with_size(w, h) },
        );
        let g = gpu();
        let layout = PyramidLayout::new(w, h);
        assert!(layout.levels.len() >= 5, "at least 5 levels: {layout:?}");
        assert_eq!(layout.levels[1].width, 38);
        for layer in 0..2 {
            let gbuffer = r.renderer.read_gbuffer(&g.device, &g.queue, layer).unwrap();
            let depth: Vec<f32> = gbuffer.samples.iter().map(|s| s.depth).collect();
            let expected = cpu::pyramid(&depth, &layout);
            let actual = r
                .renderer
                .read_f32(&g.device, &g.queue, r.renderer.pyramid_buffer(layer).unwrap())
                .unwrap();
            assert_eq!(&actual[..expected.len()], &expected[..], "layer {layer} {precision:?}");
            // Every texel of every level is a depth of level 0 (no averaging across edges).
            let mut sorted = depth.clone();
            sorted.sort_by(f32::total_cmp);
            for v in &actual[..expected.len()] {
                assert!(
                    sorted.binary_search_by(|d| d.total_cmp(v)).is_ok(),
                    "{v} is not a level-0 depth"
                );
            }
        }
    }
}

/// The stored G-buffers (fixtures/gbuffer/), independent of the rasterizer: exact.
#[test]
fn pyramid_of_stored_gbuffers_matches_cpu_reference() {
    for (i, (file, _)) in GBUFFER_FIXTURES.iter().enumerate() {
        let f = shade_fixture(i, Settings { timings: false, layers: 2, ..Settings::default() });
        let g = gpu();
        let layout = PyramidLayout::new(f.layers[0].width, f.layers[0].height);
        for layer in 0..2 {
            let depth: Vec<f32> = f.layers[layer].samples.iter().map(|s| s.depth).collect();
            let expected = cpu::pyramid(&depth, &layout);
            let buffer = f.renderer.pyramid_buffer(layer).expect("obscurance runs");
            let actual = f.renderer.read_f32(&g.device, &g.queue, buffer).unwrap();
            assert_eq!(&actual[..expected.len()], &expected[..], "{} layer {layer}", file);
        }
    }
}
