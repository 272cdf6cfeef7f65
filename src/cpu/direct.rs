//! CPU reference of `wgsl/direct.wgsl` and `wgsl/shared/light.wgsl`.

use std::f32::consts::PI;

use glam::{Vec2, Vec3, Vec4Swizzles};

use crate::cpu::frame::{mat_mul, toward_camera, view_position};
use crate::cpu::shadow::{Shadows, shadow};
use crate::frame::FrameUniform;
use crate::gbuffer::GSample;
use crate::scene::GpuLight;

/// As `light_at`: irradiance at `p` and the unit direction towards the light.
pub fn light_at(light: &GpuLight, p: Vec3) -> (Vec3, Vec3) {
    let radiance = Vec3::from(light.radiance);
    let direction = Vec3::from(light.direction);
    if light.kind == 0 {
        return (radiance, -direction);
    }
    let d = Vec3::from(light.position) - p;
    let dist2 = d.dot(d).max(1e-8);
    let l = d / dist2.sqrt();
    let mut attenuation = 1.0 / dist2;
    if light.range > 0.0 {
        let ratio2 = dist2 / (light.range * light.range);
        let window = (1.0 - ratio2 * ratio2).clamp(0.0, 1.0);
        attenuation *= window * window;
    }
    if light.kind == 2 {
        let cd = (-l).dot(direction);
        let t = ((cd - light.cos_outer) / (light.cos_inner - light.cos_outer).max(1e-4))
            .clamp(0.0, 1.0);
        attenuation *= t * t;
    }
    (radiance * attenuation, l)
}

/// As `brdf`.
pub fn brdf(n: Vec3, v: Vec3, l: Vec3, albedo: Vec3, roughness: f32, metallic: f32) -> Vec3 {
    let h = (v + l).normalize();
    let nl = n.dot(l).max(0.0);
    let nv = n.dot(v).max(1e-4);
    let nh = n.dot(h).max(0.0);
    let vh = v.dot(h).max(0.0);
    let a = (roughness * roughness).max(1e-3);
    let a2 = a * a;
    let q = nh * nh * (a2 - 1.0) + 1.0;
    let distribution = a2 / (PI * q * q);
    let k = a * 0.5;
    let visibility = 1.0 / ((nl * (1.0 - k) + k) * (nv * (1.0 - k) + k) * 4.0);
    let f0 = Vec3::splat(0.04).lerp(albedo, metallic);
    let fresnel = f0 + (Vec3::ONE - f0) * (1.0 - vh).powf(5.0);
    (1.0 - metallic) * albedo / PI + distribution * visibility * fresnel
}

/// As `lit` (`wgsl/shared/lit.wgsl`): the radiance sample `s` at world point `world` sends
/// towards the unit world direction `v` (towards the viewer) by `lights` (past their shadow maps
/// when given), and the irradiance it receives.
pub fn lit(
    s: &GSample,
    world: Vec3,
    v: Vec3,
    lights: &[GpuLight],
    shadows: Option<&Shadows>,
) -> (Vec3, Vec3) {
    let (mut radiance, mut irradiance) = (Vec3::ZERO, Vec3::ZERO);
    for (i, light) in lights.iter().enumerate() {
        let (e, l) = light_at(light, world);
        let nl = s.normal.dot(l);
        if nl > 0.0 {
            let visible = shadows.map_or(1.0, |sh| shadow(sh, i, light, world, s.normal, l));
            radiance +=
                brdf(s.normal, v, l, s.base_color, s.roughness, s.metallic) * e * nl * visible;
            irradiance += e * nl * visible;
        }
    }
    (radiance, irradiance)
}

/// Outgoing direct radiance of every pixel of `layer` (zero where there is no surface).
pub fn direct(
    f: &FrameUniform,
    layer: &[GSample],
    lights: &[GpuLight],
    shadows: Option<&Shadows>,
) -> Vec<Vec3> {
    direct_and_diffuse(f, layer, lights, shadows).0
}

/// [`direct`], and the Lambertian part alone (the kernel's `DIFFUSE` output: what the radiosity
/// gather passes on).
pub fn direct_and_diffuse(
    f: &FrameUniform,
    layer: &[GSample],
    lights: &[GpuLight],
    shadows: Option<&Shadows>,
) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut out = vec![Vec3::ZERO; (f.width * f.height) as usize];
    let mut lambert = out.clone();
    for y in 0..f.height {
        for x in 0..f.width {
            let p = (y * f.width + x) as usize;
            let s = &layer[p];
            if s.depth.is_nan() || s.depth <= 0.0 {
                continue;
            }
            let vp = view_position(f, Vec2::new(x as f32, y as f32) + 0.5, s.depth);
            let world = mat_mul(&f.inv_view, vp.extend(1.0).to_array()).xyz();
            let v = toward_camera(f, world);
            let (radiance, irradiance) = lit(s, world, v, lights, shadows);
            out[p] = radiance;
            lambert[p] = (1.0 - s.metallic) * s.base_color / PI * irradiance;
        }
    }
    (out, lambert)
}
