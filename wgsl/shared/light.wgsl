// Punctual lights and the surface BRDF, shared by the lighting kernels.
// Mirrors `GpuLight` in src/scene/lighting.rs; src/cpu/direct.rs has the same functions.

struct Light {
    position: vec3<f32>,
    // 0: directional, 1: point, 2: spot
    kind: u32,
    // Unit direction the light travels (directional, spot).
    direction: vec3<f32>,
    // 0: infinite
    range: f32,
    radiance: vec3<f32>,
    cos_inner: f32,
    cos_outer: f32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

const PI: f32 = 3.14159265;

// Irradiance (on a surface facing the light) that `light` delivers at `p`, and in `l` the unit
// direction towards the light. Point and spot lights fall off as 1/d^2 times the glTF window
// clamp(1 - (d/range)^4, 0, 1)^2; spot lights fade between the outer and inner cone.
fn light_at(light: Light, p: vec3<f32>, l: ptr<function, vec3<f32>>) -> vec3<f32> {
    if light.kind == 0u {
        *l = -light.direction;
        return light.radiance;
    }
    let d = light.position - p;
    let dist2 = max(dot(d, d), 1e-8);
    *l = d / sqrt(dist2);
    var attenuation = 1.0 / dist2;
    if light.range > 0.0 {
        let ratio2 = dist2 / (light.range * light.range);
        let window = clamp(1.0 - ratio2 * ratio2, 0.0, 1.0);
        attenuation *= window * window;
    }
    if light.kind == 2u {
        let cd = dot(-*l, light.direction);
        let t = clamp((cd - light.cos_outer) / max(light.cos_inner - light.cos_outer, 1e-4), 0.0, 1.0);
        attenuation *= t * t;
    }
    return light.radiance * attenuation;
}

// Lambert diffuse (scaled by 1 - metallic) plus GGX specular with Smith-Schlick visibility and
// Schlick Fresnel; alpha = roughness^2. Multiply by irradiance and n.l for outgoing radiance.
fn brdf(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, albedo: vec3<f32>, roughness: f32, metallic: f32) -> vec3<f32> {
    let h = normalize(v + l);
    let nl = max(dot(n, l), 0.0);
    let nv = max(dot(n, v), 1e-4);
    let nh = max(dot(n, h), 0.0);
    let vh = max(dot(v, h), 0.0);
    let a = max(roughness * roughness, 1e-3);
    let a2 = a * a;
    let q = nh * nh * (a2 - 1.0) + 1.0;
    let distribution = a2 / (PI * q * q);
    let k = a * 0.5;
    let visibility = 1.0 / ((nl * (1.0 - k) + k) * (nv * (1.0 - k) + k) * 4.0);
    let f0 = mix(vec3<f32>(0.04), albedo, metallic);
    let fresnel = f0 + (1.0 - f0) * pow(1.0 - vh, 5.0);
    return (1.0 - metallic) * albedo / PI + distribution * visibility * fresnel;
}
