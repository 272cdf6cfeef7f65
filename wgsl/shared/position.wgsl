// The G-buffer's position encodings (`PositionEncoding` in src/settings.rs): the view depth a
// layer gives back under each. Kernels rebuild positions from the pixel centre and this depth.
// `stored_depth` in src/cpu/resolve.rs is the same on the CPU.

#include "shared/frame.wgsl"
#include "shared/gbuffer.wgsl"

// The encoding's frame flags (`PositionEncoding::frame_flags`), a pipeline constant rather than
// the frame's own bits, so that the encodings not in use are compiled out (a SIMD driver that
// runs both sides of every branch would run all three for every pixel).
override POSITION_FLAGS: u32 = 0u;

// The view depth d as the frame's encoding holds it.
fn stored_depth(f: Frame, d: f32) -> f32 {
    if (POSITION_FLAGS & FRAME_POSITION_VIEW_F16) != 0u {
        return f16_value(f16_bits(min(d, F16_MAX)));
    }
    if (POSITION_FLAGS & FRAME_POSITION_SCREEN_U16) != 0u {
        // z/w of the view point at depth d, in 16 bits over [0, 1], and back through the
        // projection: z_clip = P22 (-d) + P32, w_clip = P23 (-d) + P33.
        let c = mat_mul(f.proj, vec4<f32>(0.0, 0.0, -d, 1.0));
        let q = round(clamp(c.z / c.w, 0.0, 1.0) * 65535.0) / 65535.0;
        let back = (q * f.proj[3].w - f.proj[3].z) / (q * f.proj[2].w - f.proj[2].z);
        // The far end of an infinite projection: the largest finite depth.
        return select(3.0e38, back, back > 0.0 && back <= 3.0e38);
    }
    return d;
}
