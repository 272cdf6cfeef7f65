//! CPU reference of `wgsl/shared/mean.wgsl`: a weighted mean taken about its first term, so that
//! where every term equals the first the mean is exactly it. The kernels also clamp the mean to
//! the range of what they carry; the values here need not keep one.

use std::ops::{Add, Div, Mul, Sub};

/// As `Mean` and `mean_add`, `mean_value`.
#[derive(Clone, Copy, Debug)]
pub struct Mean<T> {
    reference: T,
    sum: T,
    weight: f32,
}

impl<T> Mean<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<f32, Output = T> + Div<f32, Output = T>,
{
    /// No terms yet; `zero` is the value type's zero.
    pub fn new(zero: T) -> Self {
        Mean { reference: zero, sum: zero, weight: 0.0 }
    }

    /// Adds `v` with weight `w` (>= 0); a term before any weight has been added becomes the
    /// reference.
    pub fn add(&mut self, v: T, w: f32) {
        if self.weight <= 0.0 {
            self.reference = v;
        }
        self.sum = self.sum + (v - self.reference) * w;
        self.weight += w;
    }

    /// The mean, where some weight was added.
    pub fn value(&self) -> Option<T> {
        (self.weight > 0.0).then(|| self.reference + self.sum / self.weight)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_terms_give_exactly_the_term_and_others_their_weighted_mean() {
        let (v, weights) = (0.987_654_3f32, [0.1f32, 0.7, 0.3, 0.9, 0.13]);
        // The plain sum w v / sum w misses v here (0.98765427).
        let plain = weights.iter().map(|w| w * v).sum::<f32>() / weights.iter().sum::<f32>();
        assert_ne!(plain, v);
        let mut m = Mean::new(0.0f32);
        assert_eq!(m.value(), None);
        for w in weights {
            m.add(v, w);
        }
        assert_eq!(m.value(), Some(v));
        // A term of weight 0 added first is not kept as the reference (taken about 0.25, the
        // same terms' mean reads 0.98765427): the mean of the weighted terms is still exact.
        let mut m = Mean::new(0.0f32);
        m.add(0.25, 0.0);
        for w in weights {
            m.add(v, w);
        }
        assert_eq!(m.value(), Some(v));
        let mut m = Mean::new(0.0f32);
        m.add(1.0, 1.0);
        m.add(3.0, 3.0);
        assert_eq!(m.value(), Some(2.5));
    }
}
