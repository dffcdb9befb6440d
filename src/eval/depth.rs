//! Depth metrics of one image, after an optional per-image alignment of the prediction.
//!
//! Over the evaluated pixels E (truth > 0 and finite, inside the chosen mask, prediction
//! finite: a pixel not predicted arrives as NaN whatever the file, and takes no part in the
//! fit either), with d the aligned prediction and d* the truth, pixels where d ≤ 0 left out and
//! counted (a logarithm or a ratio of them means nothing):
//!
//! - AbsRel = mean |d − d*| / d*, SqRel = mean (d − d*)² / d*, RMSE = √mean (d − d*)²,
//!   RMSE log = √mean (ln d − ln d*)², δ_k = share of pixels with max(d/d*, d*/d) < 1.25^k
//!   (Eigen, Puhrsch and Fergus, NeurIPS 2014, §4).
//! - Alignment, fitted on E with the raw prediction p: `median`, d = p · median(d*)/median(p)
//!   (Zhou et al., CVPR 2017); `lstsq`, d = s·p with s minimising Σ(s·p − d*)²; `lstsq_shift`,
//!   d = s·p + t minimising Σ(s·p + t − d*)² (Ranftl et al., TPAMI 2020, who fit in disparity
//!   for disparity outputs; depth outputs are fitted in depth, as Marigold does).

use super::stats::median;

/// How a prediction is aligned to the truth before scoring.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// Scored as predicted (metric depth).
    None,
    /// Scaled by the ratio of medians.
    Median,
    /// Least-squares scale.
    Lstsq,
    /// Least-squares scale and shift.
    LstsqShift,
}

impl Align {
    /// The name on the command line and in the report.
    pub fn name(self) -> &'static str {
        match self {
            Align::None => "none",
            Align::Median => "median",
            Align::Lstsq => "lstsq",
            Align::LstsqShift => "lstsq_shift",
        }
    }
}

impl std::str::FromStr for Align {
    type Err = String;
    fn from_str(s: &str) -> Result<Align, String> {
        [Align::None, Align::Median, Align::Lstsq, Align::LstsqShift]
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| {
                format!("unknown alignment {s:?}: expected none, median, lstsq or lstsq_shift")
            })
    }
}

/// AbsRel, SqRel, RMSE, RMSE log, δ1, δ2, δ3, in that order.
pub(super) type Metrics = [f64; 7];

/// What one image gave.
#[derive(Clone, Debug, Default)]
pub(super) struct ImageDepth {
    /// None when no pixel was left to score, or the alignment is undefined (a constant
    /// prediction, a median of zero).
    pub(super) metrics: Option<Metrics>,
    /// Pixels scored.
    pub(super) pixels: u64,
    /// Evaluated pixels left out: not predicted (not finite), or ≤ 0 after alignment.
    pub(super) excluded: u64,
    /// The alignment's scale and shift (1 and 0 without alignment).
    pub(super) scale: f64,
    pub(super) shift: f64,
}

/// Scores `prediction` against `truth` on the pixels where `inside` holds.
pub(super) fn score(
    truth: &[f32],
    prediction: &[f64],
    inside: &[bool],
    align: Align,
) -> ImageDepth {
    let mut pairs = Vec::new();
    let mut excluded = 0;
    for ((&t, &p), &inside) in truth.iter().zip(prediction).zip(inside) {
        let t = f64::from(t);
        if !(inside && t > 0.0 && t.is_finite()) {
            continue;
        }
        if p.is_finite() {
            pairs.push((p, t));
        } else {
            excluded += 1;
        }
    }
    let Some((scale, shift)) = fit(&pairs, align) else {
        return ImageDepth {
            excluded,
            ..ImageDepth::default()
        };
    };
    let mut sums = [0.0; 7];
    let mut pixels = 0u64;
    let limit = f64::MAX / pairs.len() as f64;
    for &(p, t) in &pairs {
        let d = scale * p + shift;
        if !(d > 0.0 && d.is_finite()) {
            excluded += 1;
            continue;
        }
        let e = d - t;
        let ratio = (d / t).max(t / d);
        let log = d.ln() - t.ln();
        let values = [
            e.abs() / t,
            e * e / t,
            e * e,
            log * log,
            f64::from(u8::from(ratio < 1.25)),
            f64::from(u8::from(ratio < 1.25 * 1.25)),
            f64::from(u8::from(ratio < 1.25 * 1.25 * 1.25)),
        ];
        // A value so large its square overflows, or so large that the image's pixels
        // together would overflow the sum, would make a mean infinite: left out like a
        // non-finite one, so no metric is ever infinite.
        // NaN counts as too large (none arises from finite positive d and d*, but a NaN
        // must never reach a sum): the explicit test keeps what `!(v <= limit)` meant.
        if values.iter().any(|v| v.is_nan() || *v > limit) {
            excluded += 1;
            continue;
        }
        for (sum, v) in sums.iter_mut().zip(values) {
            *sum += v;
        }
        pixels += 1;
    }
    let metrics = (pixels > 0).then(|| {
        let n = pixels as f64;
        let m = sums.map(|s| s / n);
        [m[0], m[1], m[2].sqrt(), m[3].sqrt(), m[4], m[5], m[6]]
    });
    ImageDepth {
        metrics,
        pixels,
        excluded,
        scale,
        shift,
    }
}

/// (scale, shift) of the alignment over (prediction, truth) pairs; None when undefined.
fn fit(pairs: &[(f64, f64)], align: Align) -> Option<(f64, f64)> {
    if pairs.is_empty() {
        return None;
    }
    let n = pairs.len() as f64;
    let fitted = match align {
        Align::None => (1.0, 0.0),
        Align::Median => {
            let mut p: Vec<f64> = pairs.iter().map(|x| x.0).collect();
            let mut t: Vec<f64> = pairs.iter().map(|x| x.1).collect();
            let mp = median(&mut p)?;
            if mp <= 0.0 {
                return None;
            }
            (median(&mut t)? / mp, 0.0)
        }
        Align::Lstsq => {
            let pp: f64 = pairs.iter().map(|(p, _)| p * p).sum();
            let pt: f64 = pairs.iter().map(|(p, t)| p * t).sum();
            if pp <= 0.0 {
                return None;
            }
            (pt / pp, 0.0)
        }
        Align::LstsqShift => {
            // Centred normal equations: s = Σ(p − p̄)(t − t̄) / Σ(p − p̄)², t = t̄ − s·p̄;
            // centring keeps the sums from cancelling when depths are large and alike.
            let mean_p = pairs.iter().map(|x| x.0).sum::<f64>() / n;
            let mean_t = pairs.iter().map(|x| x.1).sum::<f64>() / n;
            let spp: f64 = pairs.iter().map(|(p, _)| (p - mean_p).powi(2)).sum();
            let spt: f64 = pairs.iter().map(|(p, t)| (p - mean_p) * (t - mean_t)).sum();
            if spp <= 0.0 {
                return None;
            }
            let s = spt / spp;
            (s, mean_t - s * mean_p)
        }
    };
    (fitted.0.is_finite() && fitted.1.is_finite()).then_some(fitted)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed_metrics_of_two_pixels() {
        // Truth 1 and 2, prediction 2 and 2: errors 1 and 0.
        let r = score(&[1.0, 2.0], &[2.0, 2.0], &[true, true], Align::None);
        let m = r.metrics.unwrap();
        let ln2 = 2f64.ln();
        let expected = [
            0.5,
            0.5,
            (0.5f64).sqrt(),
            (ln2 * ln2 / 2.0).sqrt(),
            0.5,
            0.5,
            0.5,
        ];
        for (a, b) in m.iter().zip(expected) {
            assert!((a - b).abs() < 1e-15, "{m:?}");
        }
        assert_eq!((r.pixels, r.excluded), (2, 0));
    }

    #[test]
    fn alignment_recovers_scale_and_shift() {
        let truth = [1.0f32, 2.0, 4.0, 5.0];
        let inside = [true; 4];
        let scaled: Vec<f64> = truth.iter().map(|&t| 3.0 * f64::from(t)).collect();
        for align in [Align::Median, Align::Lstsq, Align::LstsqShift] {
            let r = score(&truth, &scaled, &inside, align);
            assert!((r.scale - 1.0 / 3.0).abs() < 1e-15, "{align:?}");
            assert!(r.metrics.unwrap()[0] < 1e-15);
        }
        let affine: Vec<f64> = truth.iter().map(|&t| 0.5 * f64::from(t) - 7.0).collect();
        let r = score(&truth, &affine, &inside, Align::LstsqShift);
        assert!((r.scale - 2.0).abs() < 1e-12 && (r.shift - 14.0).abs() < 1e-12);
        // Negative values before alignment are fine for a fit with shift, and scored after.
        assert_eq!(r.pixels, 4);
        // Without alignment they are excluded and counted.
        let r = score(&truth, &affine, &inside, Align::None);
        assert_eq!((r.pixels, r.excluded, r.metrics), (0, 4, None));
    }

    #[test]
    fn pixels_outside_the_mask_or_without_truth_are_not_counted() {
        let r = score(
            &[0.0, 1.0, 1.0, f32::NAN, 1.0],
            &[5.0, 1.0, f64::NAN, 1.0, 9.0],
            &[true, true, true, true, false],
            Align::None,
        );
        assert_eq!((r.pixels, r.excluded), (1, 1));
        let huge = score(&[1.0, 1.0], &[1e200, 1.0], &[true; 2], Align::None);
        assert_eq!(
            (huge.pixels, huge.excluded),
            (1, 1),
            "(1e200)² overflows: left out"
        );
        assert_eq!(r.metrics.unwrap()[0], 0.0);
        // Each squared error (1e153)² = 1e306 is finite; 2000 of them summed are not.
        let n = 2000;
        let mut prediction = vec![1e153; n];
        prediction[0] = 2.0;
        let far = score(&vec![1.0; n], &prediction, &vec![true; n], Align::None);
        let metrics = far.metrics.unwrap();
        assert!(metrics.iter().all(|m| m.is_finite()), "{metrics:?}");
        assert_eq!((far.pixels, far.excluded), (1, n as u64 - 1));
        assert_eq!(metrics[0], 1.0, "|2 - 1| / 1 on the one pixel left");
        assert!(
            score(&[1.0, 2.0], &[3.0, 3.0], &[true; 2], Align::LstsqShift)
                .metrics
                .is_none(),
            "a constant prediction has no scale-and-shift fit"
        );
    }
}
