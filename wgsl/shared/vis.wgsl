// The visibility buffer: per pixel one 64-bit word `(depth bits << 32) | triangle id`, stored as
// two u32 words (id at 2p, depth at 2p + 1, the little-endian layout of a u64). Depth is the
// f32 view depth, positive, so its bits order like the value; the empty pixel is all ones.
// With INT64 the word is updated by one 64-bit atomicMin; without it by two passes over 32-bit
// atomics: DEPTH_PHASE takes the minimum depth, then the id phase the minimum id at that depth.
// Both give the same words. With EARLY_TEST each write first reads the word and leaves when it
// cannot lower it (the early depth test; the id phase always reads the depth it matches): words
// only decrease, so skipping the atomic changes nothing. WGSL cannot pass storage pointers to
// functions, so the writes name the bindings `vis0` and `vis1` (declared under WRITE_L0 and
// WRITE_L1 by the including kernel), and each has its own copy.

const VIS_EMPTY: u32 = 0xffffffffu;

#if INT64
alias VisWord = atomic<u64>;

fn vis_pack(depth: f32, id: u32) -> u64 {
    return (u64(bitcast<u32>(depth)) << 32u) | u64(id);
}
#if WRITE_L0
fn vis0_write(p: u32, depth: f32, id: u32) {
    let word = vis_pack(depth, id);
#if EARLY_TEST
    if atomicLoad(&vis0[p]) <= word {
        return;
    }
#endif
    atomicMin(&vis0[p], word);
}
#endif
#if WRITE_L1
fn vis1_write(p: u32, depth: f32, id: u32) {
    let word = vis_pack(depth, id);
#if EARLY_TEST
    if atomicLoad(&vis1[p]) <= word {
        return;
    }
#endif
    atomicMin(&vis1[p], word);
}
#endif
#else
alias VisWord = atomic<u32>;

#if WRITE_L0
fn vis0_write(p: u32, depth: f32, id: u32) {
#if DEPTH_PHASE
#if EARLY_TEST
    if atomicLoad(&vis0[2u * p + 1u]) <= bitcast<u32>(depth) {
        return;
    }
#endif
    atomicMin(&vis0[2u * p + 1u], bitcast<u32>(depth));
#else
    if atomicLoad(&vis0[2u * p + 1u]) == bitcast<u32>(depth) {
        atomicMin(&vis0[2u * p], id);
    }
#endif
}
#endif
#if WRITE_L1
fn vis1_write(p: u32, depth: f32, id: u32) {
#if DEPTH_PHASE
#if EARLY_TEST
    if atomicLoad(&vis1[2u * p + 1u]) <= bitcast<u32>(depth) {
        return;
    }
#endif
    atomicMin(&vis1[2u * p + 1u], bitcast<u32>(depth));
#else
    if atomicLoad(&vis1[2u * p + 1u]) == bitcast<u32>(depth) {
        atomicMin(&vis1[2u * p], id);
    }
#endif
}
#endif
#endif
