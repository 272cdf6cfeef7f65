//! The hardware-raster baseline of the benchmarks draws the same picture as layer 0, so the
//! time ratio compares like with like.

mod common;

use common::{gpu, render};
use deep_gbuffer::gbuffer::vis_id;
use deep_gbuffer::testing::BaselinePass;
use deep_gbuffer::{Scene, Settings};

#[test]
fn baseline_draws_the_same_triangles_as_layer0() {
    let g = gpu();
    let scene = Scene::from_spec("builtin:grid-20000").unwrap();
    let (w, h) = (96, 72);
    let r = render(
        &scene,
        &scene.camera_or_default(),
        Settings { timings: false, ..Settings::with_size(w, h) },
    );
    let baseline = BaselinePass::new(&g.device, w, h, true);
    let mut encoder = g.device.create_command_encoder(&Default::default());
    baseline.encode(&g.device, &mut encoder, &r.buffers, r.renderer.frame_buffer(), None);
    g.queue.submit([encoder.finish()]);
    let ids = baseline.read_ids(&g.device, &g.queue).unwrap();
    let same =
        ids.iter().zip(&r.vis0).filter(|(hw, w)| vis_id(**w).unwrap_or(u32::MAX) == **hw).count();
    // The two fill rules sample the same pixel centres; they differ only where the hardware's
    // own snapping or depth precision breaks a near-tie along an edge.
    let agreement = same as f64 / ids.len() as f64;
    assert!(agreement > 0.99, "hardware and compute agree on {:.2}% of pixels", agreement * 100.0);
}
