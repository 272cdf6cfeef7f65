//! `wgsl/blur.wgsl`: the separable bilateral blur (horizontal, then vertical).

use super::FrameContext;
use crate::gpu::slots::blur as slot;

/// One blur: its radius in pixels (a pipeline constant), whether it blurs `vec4<f32>` images
/// (radiosity) or f32 images (obscurance), and whether a tap is weighed by its distance from the
/// centre's tangent plane too (`plane_weight`: the obscurance, which varies at the scale of a
/// pixel where the geometry does; the gathered irradiance varies at the scale of its radius).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Blur {
    pub radius: u32,
    pub vec4: bool,
    pub plane: bool,
}

impl Blur {
    /// Records `source` -> `scratch` (horizontal) -> `target` (vertical), weighted by layer 0.
    pub(crate) fn record(
        &self,
        ctx: &FrameContext<'_>,
        pass: &mut wgpu::ComputePass<'_>,
        [source, scratch, target]: [&wgpu::Buffer; 3],
    ) {
        let mut defines = ctx.settings.precision.defines();
        if self.vec4 {
            defines.push("VEC4");
        }
        if self.plane {
            defines.push("PLANE");
        }
        let radius = [("RADIUS", f64::from(self.radius))];
        for (vertical, (from, to)) in [(false, (source, scratch)), (true, (scratch, target))] {
            let mut defines = defines.clone();
            if vertical {
                defines.push("VERTICAL");
            }
            let pipeline = ctx.pipelines.get(ctx.device, "blur", "blur_main", &defines, &radius);
            let entries = [
                (slot::FRAME, ctx.frame),
                (slot::GBUFFER, ctx.gbuffer[0]),
                (slot::SOURCE, from),
                (slot::BLURRED, to),
            ];
            pipeline.dispatch_pixels(ctx.device, pass, &entries, ctx.size());
        }
    }
}
