// Layer 1's radiance at pixel q, shaded as the composite shades a surface with nothing but its
// direct light, emission and the `ambient` term (layer 1 has no obscurance, radiosity or
// reflections of its own): what a pass that looks behind layer 0 (depth of field, motion blur)
// shows there. Reads the bindings named `gbuffer1` and `direct1` the including kernel declares.
// Needs shared/gbuffer.wgsl and shared/shade.wgsl.

fn layer1_radiance(q: u32, ambient: vec3<f32>) -> vec4<f32> {
#if PACKED
    let s = gbuffer_decode(gbuffer1[q * G_WORDS], gbuffer1[q * G_WORDS + 1u]);
#else
    let s = gbuffer_decode(gbuffer1[q * G_WORDS], gbuffer1[q * G_WORDS + 1u], gbuffer1[q * G_WORDS + 2u], gbuffer1[q * G_WORDS + 3u]);
#endif
    return vec4<f32>(shaded(s, direct1[q].rgb, 1.0, vec4<f32>(0.0), ambient), 1.0);
}
