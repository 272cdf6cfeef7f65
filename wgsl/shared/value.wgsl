// What the blur, the upsample and the temporal filter carry: with VEC4 the radiosity's irradiance
// (rgb, >= 0) and coverage (a, in [0, 1]), else the obscurance's visibility (in [0, 1]).
//
// Their weighted means are taken about a reference value (the pixel's own, or the first term's):
// reference + sum w (v - reference) / sum w, so that where every term equals the reference the
// mean is exactly it (an open plane's visibility stays exactly 1), and then `bounded` to the
// value's range. A device's division need not be correctly rounded (Vulkan allows 2.5 ulp; on an
// NVIDIA H200 a plain sum w v / sum w read 0.9999998 on an open plane and 1.0000001 elsewhere),
// and a visibility an ulp past 1 is one the temporal filter would drop as unusable.
// src/cpu/blur.rs and src/cpu/upsample.rs take the same means, unclamped (their values there
// need not keep a range).
#if VEC4
#include "shared/irradiance.wgsl"
#else
alias Value = f32;

fn bounded(v: Value) -> Value {
    return clamp(v, 0.0, 1.0);
}
#endif
