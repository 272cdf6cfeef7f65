// Reads sample p of the G-buffer binding named `gbuffer` that the including kernel declares
// (WGSL cannot pass a storage buffer to a function, so the binding's name is the contract).

fn sample_at(p: u32) -> GSample {
#if PACKED
    return gbuffer_decode(gbuffer[p * G_WORDS], gbuffer[p * G_WORDS + 1u]);
#else
    return gbuffer_decode(gbuffer[p * G_WORDS], gbuffer[p * G_WORDS + 1u], gbuffer[p * G_WORDS + 2u], gbuffer[p * G_WORDS + 3u]);
#endif
}
