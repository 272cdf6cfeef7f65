// The radiosity's per-pixel value, as the temporal filter keeps it: irradiance (rgb, >= 0) and
// the share of the hemisphere it covers (a, in [0, 1]); `bounded` keeps a mean of such values in
// that range (shared/mean.wgsl, included here, says why), `usable` tells whether a stored one
// may enter a frame.

alias Value = vec4<f32>;

fn bounded(v: Value) -> Value {
    return vec4<f32>(max(v.rgb, vec3<f32>(0.0)), clamp(v.a, 0.0, 1.0));
}

fn usable(v: Value) -> bool {
    return all(abs(v.rgb) <= vec3<f32>(3.0e38)) && v.a >= 0.0 && v.a <= 1.0;
}

#include "shared/mean.wgsl"
