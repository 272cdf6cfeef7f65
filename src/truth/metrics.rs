//! Error of an estimate against ground truth, over the pixels where both see a surface.

use glam::Vec3;

use super::TruthImage;

/// Error statistics of one effect.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ErrorStats {
    /// Root-mean-square error (over pixels and channels).
    pub rmse: f32,
    /// Mean absolute error.
    pub mae: f32,
    /// Pixels compared.
    pub pixels: usize,
    /// The truth's own mean standard error over those pixels: differences below it are noise.
    pub truth_stderr: f32,
    /// Mean of the truth over those pixels (for scale).
    pub truth_mean: f32,
    /// Mean of the estimate over those pixels (its bias shows against `truth_mean`).
    pub estimate_mean: f32,
}

/// Compares `estimate` (one value per pixel, rgb) with `truth` over the pixels where the truth
/// sees a surface and `mask` (the estimate's layer 0 sees one too) holds.
pub fn compare(estimate: &[Vec3], mask: &[bool], truth: &TruthImage) -> ErrorStats {
    let (mut sq, mut abs, mut se, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    let (mut tm, mut em) = (0.0f64, 0.0f64);
    for (((e, m), (t, s)), v) in
        estimate.iter().zip(mask).zip(truth.value.iter().zip(&truth.stderr)).zip(&truth.visible)
    {
        if !(*m && *v) {
            continue;
        }
        let d = (*e - *t).as_dvec3();
        sq += d.length_squared() / 3.0;
        abs += d.abs().element_sum() / 3.0;
        se += f64::from(s.element_sum()) / 3.0;
        tm += f64::from(t.element_sum()) / 3.0;
        em += f64::from(e.element_sum()) / 3.0;
        n += 1;
    }
    if n == 0 {
        return ErrorStats::default();
    }
    let n_f = n as f64;
    ErrorStats {
        rmse: (sq / n_f).sqrt() as f32,
        mae: (abs / n_f) as f32,
        pixels: n,
        truth_stderr: (se / n_f) as f32,
        truth_mean: (tm / n_f) as f32,
        estimate_mean: (em / n_f) as f32,
    }
}

/// The irradiance the composite takes from the radiosity pass: confidence (alpha) times E (rgb),
/// of the first `n` pixels of its `vec4` buffer. The rest of the hemisphere, which no tap
/// covered, is the ambient term's; the ground truth of diffuse indirect light leaves the sky out
/// in the same way.
pub fn weighted_irradiance(values: &[f32], n: usize) -> Vec<Vec3> {
    values.chunks_exact(4).take(n).map(|c| Vec3::new(c[0], c[1], c[2]) * c[3]).collect()
}
