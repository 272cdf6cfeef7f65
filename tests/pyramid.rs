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

/// Each texel of the nearest-depth pyramid (the reflections' march) is the nearest depth of the
/// pixels it covers, `[x, x + 1) x [y, y + 1)` times `2^level`, empty (0) ones not counted, and 0
/// only where all of them are empty: the bound that lets the march skip a cell.
#[test]
fn nearest_pyramid_bounds_every_pixel_it_covers() {
    let (w, h) = (37u32, 23u32); // odd sizes: the last texels cover fewer pixels
    let depth: Vec<f32> = (0..w * h)
        .map(|i| {
            let hash = i.wrapping_mul(2654435761) >> 7;
            // A fifth of the pixels empty, the rest at depths in [1, 2).
            if hash % 5 == 0 { 0.0 } else { 1.0 + (hash % 1000) as f32 / 1000.0 }
        })
        .collect();
    let layout = PyramidLayout::new(w, h);
    let nearest = cpu::nearest(&depth, &layout);
    for (l, level) in layout.levels.iter().enumerate() {
        for ty in 0..level.height {
            for tx in 0..level.width {
                let covered = (ty << l..((ty + 1) << l).min(h))
                    .flat_map(|y| (tx << l..((tx + 1) << l).min(w)).map(move |x| (x, y)))
                    .map(|(x, y)| depth[(y * w + x) as usize])
                    .filter(|&d| d > 0.0)
                    .fold(f32::INFINITY, f32::min);
                let texel = nearest[(level.offset + ty * level.width + tx) as usize];
                let expected = if covered.is_finite() { covered } else { 0.0 };
                assert_eq!(texel, expected, "level {l} texel ({tx}, {ty})");
            }
        }
    }
}
