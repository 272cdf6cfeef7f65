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
    /// The median of the per-pixel relative error `estimate / truth - 1` (channel means) over
    /// the pixels whose truth exceeds a tenth of `truth_mean`: how far a typical lit pixel is
    /// off, which the means hide where a few bright pixels carry the light (the upper median
    /// for an even count; NaN where no pixel qualifies).
    pub median_relative: f32,
}

/// Compares `estimate` (one value per pixel, rgb) with `truth` over the pixels where the truth
/// sees a surface and `mask` (the estimate's layer 0 sees one too) holds.
pub fn compare(estimate: &[Vec3], mask: &[bool], truth: &TruthImage) -> ErrorStats {
    let (mut sq, mut abs, mut se, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    let (mut tm, mut em) = (0.0f64, 0.0f64);
    // Each compared pixel's (estimate, truth) channel means, for the median.
    let mut pairs = Vec::new();
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
        let truth_mean = f64::from(t.element_sum()) / 3.0;
        let estimate_mean = f64::from(e.element_sum()) / 3.0;
        tm += truth_mean;
        em += estimate_mean;
        pairs.push((estimate_mean, truth_mean));
        n += 1;
    }
    if n == 0 {
        return ErrorStats { median_relative: f32::NAN, ..ErrorStats::default() };
    }
    let n_f = n as f64;
    let floor = 0.1 * tm / n_f;
    let mut relative: Vec<f64> =
        pairs.iter().filter(|(_, t)| *t > floor).map(|(e, t)| e / t - 1.0).collect();
    let median_relative = if relative.is_empty() {
        f32::NAN
    } else {
        let middle = relative.len() / 2;
        *relative.select_nth_unstable_by(middle, f64::total_cmp).1 as f32
    };
    ErrorStats {
        rmse: (sq / n_f).sqrt() as f32,
        mae: (abs / n_f) as f32,
        pixels: n,
        truth_stderr: (se / n_f) as f32,
        truth_mean: (tm / n_f) as f32,
        estimate_mean: (em / n_f) as f32,
        median_relative,
    }
}

/// Structural similarity (SSIM) of two images as a viewer sees them: both tone-mapped with
/// `exposure` ([`crate::output::tonemap`]), their luminance (Rec. 709 weights) quantised to
/// 8 bits, then the mean SSIM over 8x8 windows of the `image-compare` crate (1: identical).
/// Pixels where `mask` is false are black in both.
pub fn ssim(
    estimate: &[Vec3],
    truth: &[Vec3],
    mask: &[bool],
    (width, height): (u32, u32),
    exposure: f32,
) -> f32 {
    let grey = |image: &[Vec3]| {
        let mapped = crate::output::tonemap(image, exposure);
        let bytes: Vec<u8> = mapped
            .iter()
            .zip(mask)
            .map(|(c, m)| {
                let y = if *m { c.dot(Vec3::new(0.2126, 0.7152, 0.0722)) } else { 0.0 };
                (y.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
            })
            .collect();
        image::GrayImage::from_raw(width, height, bytes).expect("one byte per pixel")
    };
    let (a, b) = (grey(estimate), grey(truth));
    image_compare::gray_similarity_structure(&image_compare::Algorithm::MSSIMSimple, &a, &b)
        .map_or(0.0, |s| s.score as f32)
}

/// Where an estimate errs, as a picture: per pixel the signed error `estimate - truth` (channel
/// means) over `scale`, on a diverging scale in display space (for
/// [`crate::output::write_png_display`]): white where the two agree, shading to red where the
/// estimate is `scale` or more too high and to blue where it is `scale` or more too low; dark
/// grey where either sees no surface (outside the comparison), black where the error is not a
/// number (a NaN or an infinity in the estimate).
pub fn error_map(estimate: &[Vec3], mask: &[bool], truth: &TruthImage, scale: f32) -> Vec<Vec3> {
    let outside = Vec3::splat(0.25);
    estimate
        .iter()
        .zip(mask)
        .zip(truth.value.iter().zip(&truth.visible))
        .map(|((e, m), (t, v))| {
            if !(*m && *v) {
                return outside;
            }
            let d = (e.element_sum() - t.element_sum()) / (3.0 * scale);
            if !d.is_finite() {
                return Vec3::ZERO;
            }
            let k = d.clamp(-1.0, 1.0);
            if k >= 0.0 {
                Vec3::new(1.0, 1.0 - k, 1.0 - k)
            } else {
                Vec3::new(1.0 + k, 1.0 + k, 1.0)
            }
        })
        .collect()
}

/// Temporal instability of a quantity that belongs to the surface, not the view (obscurance,
/// irradiance): the mean absolute frame-to-frame change at the same surface point. Each pixel of
/// `current` is compared with `previous` at the position its point had in the previous frame
/// (its layer-0 motion vector, bilinear between the four pixels around it), where all four show
/// the same material with normals within 25 degrees of the pixel's; other pixels (newly
/// visible, at silhouettes) are left out. Returns the mean change (over channels) and the pixels
/// compared.
pub fn temporal_change(
    previous: &[Vec3],
    current: &[Vec3],
    previous_layer0: &crate::GBufferLayer,
    layer0: &crate::GBufferLayer,
) -> (f32, usize) {
    let (w, h) = (layer0.width as i64, layer0.height as i64);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (p, s) in layer0.samples.iter().enumerate() {
        if s.depth.is_nan() || s.depth <= 0.0 {
            continue;
        }
        let (x, y) = ((p as i64 % w) as f32 + 0.5, (p as i64 / w) as f32 + 0.5);
        // The previous pixel-centre coordinates, then the four centres around them.
        let (px, py) = (x - s.motion.x - 0.5, y - s.motion.y - 0.5);
        let (x0, y0) = (px.floor() as i64, py.floor() as i64);
        let (fx, fy) = (px - x0 as f32, py - y0 as f32);
        let mut value = Vec3::ZERO;
        let mut same = true;
        for (dx, dy, weight) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            if weight == 0.0 {
                continue;
            }
            let (qx, qy) = (x0 + dx, y0 + dy);
            if qx < 0 || qy < 0 || qx >= w || qy >= h {
                same = false;
                break;
            }
            let q = (qy * w + qx) as usize;
            let t = &previous_layer0.samples[q];
            if t.depth.is_nan()
                || t.depth <= 0.0
                || t.material != s.material
                || t.normal.dot(s.normal) < 0.9
            {
                same = false;
                break;
            }
            value += previous[q] * weight;
        }
        if same {
            sum += f64::from((current[p] - value).abs().element_sum()) / 3.0;
            n += 1;
        }
    }
    if n == 0 { (0.0, 0) } else { ((sum / n as f64) as f32, n) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The error map: white where the estimate meets the truth, full red and blue at `scale`
    /// too high and too low (and past it), half-way colours at half of it, dark grey outside
    /// the comparison, black for a NaN.
    #[test]
    fn the_error_map_shades_the_signed_error() {
        let truth = TruthImage {
            width: 7,
            height: 1,
            value: vec![Vec3::splat(0.5); 7],
            stderr: vec![Vec3::ZERO; 7],
            visible: vec![true, true, true, true, true, true, false],
        };
        let estimate: Vec<Vec3> =
            [0.5, 0.75, 0.25, 0.625, 1.5, f32::NAN, 0.5].map(Vec3::splat).to_vec();
        let mut mask = vec![true; 7];
        let map = error_map(&estimate, &mask, &truth, 0.25);
        assert_eq!(map[0], Vec3::ONE);
        assert_eq!(map[1], Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(map[2], Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(map[3], Vec3::new(1.0, 0.5, 0.5));
        assert_eq!(map[4], Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(map[5], Vec3::ZERO);
        assert_eq!(map[6], Vec3::splat(0.25));
        mask[0] = false;
        assert_eq!(error_map(&estimate, &mask, &truth, 0.25)[0], Vec3::splat(0.25));
    }

    /// The median relative error skips the pixels under a tenth of the truth's mean (here the
    /// last, which the estimate overshoots fivefold) and the ones the masks leave out.
    #[test]
    fn the_median_relative_error_counts_the_lit_pixels() {
        let truth = TruthImage {
            width: 6,
            height: 1,
            value: [1.0, 2.0, 1.0, 1.0, 1.0, 0.01].map(Vec3::splat).to_vec(),
            stderr: vec![Vec3::ZERO; 6],
            visible: vec![true, true, true, true, false, true],
        };
        let estimate = [1.1, 1.6, 1.0, 9.0, 9.0, 0.05].map(Vec3::splat).to_vec();
        let mask = [true, true, true, false, true, true];
        let stats = compare(&estimate, &mask, &truth);
        assert_eq!(stats.pixels, 4);
        // Relative errors +0.1, -0.2, 0 (the fourth and fifth pixels masked, the sixth dim).
        assert!(stats.median_relative.abs() < 1e-6, "{}", stats.median_relative);
        assert!((stats.truth_mean - 1.0025).abs() < 1e-5);
        let dark = TruthImage { value: vec![Vec3::ZERO; 6], ..truth.clone() };
        assert!(compare(&estimate, &mask, &dark).median_relative.is_nan());
        let none = compare(&estimate, &[false; 6], &truth);
        assert_eq!(none.pixels, 0);
        assert!(none.median_relative.is_nan());
    }
}
