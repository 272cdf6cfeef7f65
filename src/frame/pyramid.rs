//! Where each level of a depth pyramid lies in its packed buffer.

/// Most levels built (level 0 is full resolution).
pub const MAX_LEVELS: u32 = 6;

/// One level's place in the packed buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Level {
    /// First texel.
    pub offset: u32,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
}

/// Where each level lies in the packed f32 buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PyramidLayout {
    /// Level 0 (full resolution) first.
    pub levels: Vec<Level>,
    /// Texels in all levels.
    pub total: u32,
}

impl PyramidLayout {
    /// The levels of a `width` x `height` image: halving (rounding up) until 1x1 or
    /// [`MAX_LEVELS`].
    pub fn new(width: u32, height: u32) -> Self {
        let mut levels = Vec::new();
        let (mut w, mut h, mut offset) = (width, height, 0);
        loop {
            levels.push(Level { offset, width: w, height: h });
            offset += w * h;
            if levels.len() as u32 == MAX_LEVELS || (w == 1 && h == 1) {
                break;
            }
            w = w.div_ceil(2);
            h = h.div_ceil(2);
        }
        PyramidLayout { levels, total: offset }
    }

    /// Bytes of one layer's pyramid buffer.
    pub fn bytes(&self) -> u64 {
        u64::from(self.total) * 4
    }
}

/// The size of `level` of a `width` x `height` image's MIP chain: halved (rounding up) `level`
/// times (`mip_size` in `wgsl/shared/mip.wgsl`; within [`MAX_LEVELS`], the size of
/// [`PyramidLayout`]'s level). The shader divides by 2^level and rounds up, which is the same.
pub fn mip_size(width: u32, height: u32, level: usize) -> (u32, u32) {
    (0..level).fold((width, height), |(w, h), _| (w.div_ceil(2), h.div_ceil(2)))
}

#[cfg(test)]
mod tests {
    use super::mip_size;

    /// The shader computes a level's size in one step, the frame's size divided by 2^level and
    /// rounded up: the same as halving it (rounding up) level times.
    #[test]
    fn a_levels_size_is_the_frame_divided_by_a_power_of_two_rounded_up() {
        for width in 1..=300u32 {
            for level in 0..12usize {
                let (w, h) = mip_size(width, width * 7 + 3, level);
                assert_eq!(w, width.div_ceil(1 << level), "{width} at level {level}");
                assert_eq!(h, (width * 7 + 3).div_ceil(1 << level), "{width} at level {level}");
            }
        }
    }
}
