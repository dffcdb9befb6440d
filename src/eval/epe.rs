//! End-point error of a vector field (optical flow in pixels, displacement in metres): the
//! Euclidean norm ‖f − f*‖ per valid pixel, where the truth is valid and the prediction is
//! finite (a non-finite prediction, or one so far off that the error overflows, is left out
//! and counted); the image's mean and median.

use super::stats::median;

/// One image's end-point errors.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct ImageEpe {
    /// Mean and median EPE; None when no pixel was scored.
    pub(super) mean_median: Option<(f64, f64)>,
    pub(super) pixels: u64,
    pub(super) excluded: u64,
}

/// EPE of `prediction` against `truth` (one plane per component) where `valid` holds.
pub(super) fn score(truth: &[Vec<f32>], prediction: &[Vec<f64>], valid: &[bool]) -> ImageEpe {
    let mut errors = Vec::new();
    let mut excluded = 0;
    for (i, &v) in valid.iter().enumerate() {
        let finite_truth = truth.iter().all(|t| t[i].is_finite());
        if !v || !finite_truth {
            continue;
        }
        if prediction.iter().any(|p| !p[i].is_finite()) {
            excluded += 1;
            continue;
        }
        let squared: f64 = truth
            .iter()
            .zip(prediction)
            .map(|(t, p)| (p[i] - f64::from(t[i])).powi(2))
            .sum();
        // An error whose square overflows is left out like a non-finite prediction, so the
        // means stay finite.
        if !squared.is_finite() {
            excluded += 1;
            continue;
        }
        errors.push(squared.sqrt());
    }
    let pixels = errors.len() as u64;
    let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
    ImageEpe {
        mean_median: median(&mut errors).map(|m| (mean, m)),
        pixels,
        excluded,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_offset_has_its_norm_as_error() {
        let truth = vec![vec![1.0f32, 2.0, 3.0], vec![0.0, 0.0, 0.0]];
        let prediction = vec![vec![4.0, 5.0, f64::NAN], vec![4.0, 4.0, 4.0]];
        let r = score(&truth, &prediction, &[true, true, true]);
        assert_eq!(r.mean_median, Some((5.0, 5.0)));
        assert_eq!((r.pixels, r.excluded), (2, 1));
        assert_eq!(score(&truth, &prediction, &[false; 3]).mean_median, None);
    }
}
