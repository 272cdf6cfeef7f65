// The radiosity's per-pixel value: irradiance (rgb, >= 0) and coverage (a, in [0, 1]), as the
// temporal filter keeps it, and `bounded` to that range (shared/value.wgsl says why).

alias Value = vec4<f32>;

fn bounded(v: Value) -> Value {
    return vec4<f32>(max(v.rgb, vec3<f32>(0.0)), clamp(v.a, 0.0, 1.0));
}
