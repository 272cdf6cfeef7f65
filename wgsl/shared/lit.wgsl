// The direct light a surface sends towards a viewer, by every light (with SHADOWS past its
// shadow map): shared by the direct kernel (towards the camera) and the reflections (towards the
// point a reflected ray left). Reads the including kernel's binding `lights` (and, with SHADOWS,
// those of shared/shadow.wgsl). src/cpu/direct.rs (`lit`) is the same on the CPU.

#include "shared/light.wgsl"
#include "shared/shadow.wgsl"

struct Lit {
    // Outgoing radiance towards the viewer.
    radiance: vec3<f32>,
    // Irradiance, the shadows applied.
    irradiance: vec3<f32>,
}

// What sample s at world point `world` receives from the first `count` lights and sends towards
// the unit world direction v (towards the viewer); `pcf`: the shadow maps' filter radius.
fn lit(s: GSample, world: vec3<f32>, v: vec3<f32>, count: u32, pcf: u32) -> Lit {
    var out = Lit(vec3<f32>(0.0), vec3<f32>(0.0));
    for (var i = 0u; i < count; i++) {
        var l: vec3<f32>;
        let e = light_at(lights[i], world, &l);
        let nl = dot(s.normal, l);
        if nl > 0.0 {
            var visible = 1.0;
#if SHADOWS
            visible = shadow(i, lights[i], world, s.normal, l, pcf);
#endif
            out.radiance += brdf(s.normal, v, l, s.base_color, s.roughness, s.metallic) * e * nl * visible;
            out.irradiance += e * nl * visible;
        }
    }
    return out;
}
