// The radiance the image shows at a surface, reflections left out: its direct radiance, its
// emission, and the diffuse albedo (1 - metallic) * base colour / pi times the irradiance
//     occlusion * (E + min(1 - conf, AV) * pi * ambient),
// where E is the irradiance the radiosity gather found and conf the share of the hemisphere it
// covers (both 0 without radiosity): the ambient term fills the rest, the open sky, as much of
// it as the ambient visibility AV leaves (1 without obscurance; AV alone without radiosity, the
// deep G-buffer paper's AV * ambient). 1 - conf and AV both estimate the open share and both
// over-estimate it (neither sees past its radius; AV counts a near surface at its falloff), and
// they see the same surfaces: the smaller is the better estimate, where their product darkened
// every crease twice (README, "The ambient term"). The material's occlusion texture (1 without
// one) dims both, as glTF asks of indirect light. The composite shows it at every pixel; a
// reflection shows it where its ray hits. src/cpu/composite.rs (`shaded`) is the same on the
// CPU.

fn shaded(s: GSample, direct: vec3<f32>, visibility: f32, irradiance: vec4<f32>, ambient: vec3<f32>) -> vec3<f32> {
    let confidence = clamp(irradiance.a, 0.0, 1.0);
    let albedo = (1.0 - s.metallic) * s.base_color;
    let reflected = albedo * s.occlusion * (irradiance.rgb / 3.14159265 + min(1.0 - confidence, visibility) * ambient);
    return direct + reflected + s.emissive;
}
