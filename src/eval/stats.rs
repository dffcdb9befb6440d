//! The statistics every metric here needs: the median (NumPy's: the mean of the two
//! middle values of an even count) and the mean over images of per-image values.

/// The median of `values` (reordered); None for none.
pub(super) fn median(values: &mut [f64]) -> Option<f64> {
    let n = values.len();
    if n == 0 {
        return None;
    }
    let (_, &mut upper, _) = values.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        return Some(upper);
    }
    // The largest of the lower half, which select_nth left unordered below n / 2.
    let lower = values[..n / 2]
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    Some((lower + upper) / 2.0)
}

/// The mean of `values`, summed in their order; None for none.
pub(super) fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(sum, n), v| (sum + v, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// Per-image values summed in image order, so the mean has the same bits however the images
/// were computed in parallel.
#[derive(Clone, Debug)]
pub(super) struct Mean<const N: usize> {
    sums: [f64; N],
    count: usize,
}

impl<const N: usize> Default for Mean<N> {
    fn default() -> Self {
        Mean {
            sums: [0.0; N],
            count: 0,
        }
    }
}

impl<const N: usize> Mean<N> {
    pub(super) fn add(&mut self, values: [f64; N]) {
        for (s, v) in self.sums.iter_mut().zip(values) {
            *s += v;
        }
        self.count += 1;
    }

    /// The means; None before any image.
    pub(super) fn get(&self) -> Option<[f64; N]> {
        (self.count > 0).then(|| self.sums.map(|s| s / self.count as f64))
    }

    /// How many images were added.
    pub(super) fn count(&self) -> usize {
        self.count
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(&mut []), None);
        let mut m = Mean::<2>::default();
        m.add([1.0, 10.0]);
        m.add([3.0, 20.0]);
        assert_eq!((m.get(), m.count()), (Some([2.0, 15.0]), 2));
    }
}
