// Exact 64-bit integers for the edge functions of large triangles: with INT64 (the device has
// 64-bit shader integers) native i64, otherwise two's complement as vec2<u32>(lo, hi), so that
// they are exact on every device. src/cpu/raster.rs computes the same values with i64.

#if INT64
alias Wide = i64;

fn wide_sub(a: i64, b: i64) -> i64 {
    return a - b;
}

fn wide_add(a: i64, b: i64) -> i64 {
    return a + b;
}

// The exact product of two i32 values.
fn wide_mul(a: i32, b: i32) -> i64 {
    return i64(a) * i64(b);
}

// -1, 0 or 1.
fn wide_sign(a: i64) -> i32 {
    return select(select(0, 1, a > 0li), -1, a < 0li);
}

// As the vec2<u32> form converts (high word, then low), so both give the same f32.
fn wide_to_f32(a: i64) -> f32 {
    return f32(i32(a >> 32u)) * 4294967296.0 + f32(u32(a & 0xffffffffli));
}
#else
alias Wide = vec2<u32>;

fn wide_neg(a: vec2<u32>) -> vec2<u32> {
    let lo = ~a.x + 1u;
    return vec2<u32>(lo, ~a.y + select(0u, 1u, lo == 0u));
}

fn wide_sub(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    return vec2<u32>(a.x - b.x, a.y - b.y - select(0u, 1u, a.x < b.x));
}

fn wide_add(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

// The exact product of two i32 values.
fn wide_mul(a: i32, b: i32) -> vec2<u32> {
    let ua = select(bitcast<u32>(a), 0u - bitcast<u32>(a), a < 0);
    let ub = select(bitcast<u32>(b), 0u - bitcast<u32>(b), b < 0);
    let a0 = ua & 0xffffu;
    let a1 = ua >> 16u;
    let b0 = ub & 0xffffu;
    let b1 = ub >> 16u;
    let ll = a0 * b0;
    let lh = a0 * b1;
    let hl = a1 * b0;
    let t = (ll >> 16u) + (lh & 0xffffu) + (hl & 0xffffu);
    let r = vec2<u32>((ll & 0xffffu) | (t << 16u), a1 * b1 + (lh >> 16u) + (hl >> 16u) + (t >> 16u));
    return select(r, wide_neg(r), (a < 0) != (b < 0));
}

// -1, 0 or 1.
fn wide_sign(a: vec2<u32>) -> i32 {
    if (a.y >> 31u) != 0u {
        return -1;
    }
    return select(1, 0, a.x == 0u && a.y == 0u);
}

fn wide_to_f32(a: vec2<u32>) -> f32 {
    return f32(bitcast<i32>(a.y)) * 4294967296.0 + f32(a.x);
}
#endif
