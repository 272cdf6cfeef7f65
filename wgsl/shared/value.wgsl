// What the blur, the upsample and the temporal filter carry: with VEC4 the radiosity's irradiance
// and coverage (shared/irradiance.wgsl), else the obscurance's visibility, in [0, 1]. `bounded`
// keeps a mean of such values in their range (shared/mean.wgsl, included here), `usable` tells
// whether a stored one may enter a frame.
#if VEC4
#include "shared/irradiance.wgsl"
#else
alias Value = f32;

fn bounded(v: Value) -> Value {
    return clamp(v, 0.0, 1.0);
}

fn usable(v: Value) -> bool {
    return v >= 0.0 && v <= 1.0;
}
#endif
#include "shared/mean.wgsl"
