// A weighted mean of the values a kernel carries (`Value`, with its `bounded`: shared/value.wgsl
// or shared/irradiance.wgsl), taken about its first term: reference + sum w (v - reference) /
// sum w. Where every term equals the first the mean is exactly it (an open plane's visibility
// stays exactly 1), and `mean_value` keeps it in the value's range. A device's division need not
// be correctly rounded (Vulkan allows 2.5 ulp; on an NVIDIA H200 a plain sum w v / sum w read
// 0.9999998 on an open plane and 1.0000001 elsewhere), and a visibility an ulp past 1 is one the
// temporal filter would drop as unusable. src/cpu/mean.rs is the same on the CPU (unclamped).

struct Mean {
    reference: Value,
    sum: Value,
    weight: f32,
}

// Adds v with weight w (>= 0); a term before any weight has been added becomes the reference.
fn mean_add(m: ptr<function, Mean>, v: Value, w: f32) {
    if !((*m).weight > 0.0) {
        (*m).reference = v;
    }
    (*m).sum += w * (v - (*m).reference);
    (*m).weight += w;
}

// The mean, within the value's range; only where some weight was added.
fn mean_value(m: Mean) -> Value {
    return bounded(m.reference + m.sum / m.weight);
}
