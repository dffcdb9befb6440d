//! What every augmentation spec shares: ranges of drawn values, the probability of applying
//! an operation, and the checks that name a bad parameter and its value.
//!
//! Every field of a spec consumes exactly one draw whether its range is a span or a single
//! number, and the probability test is always the first draw of an operation, so widening
//! one range never shifts the values drawn for the fields after it.

use crate::seeds::Stream;
use serde::{Deserialize, Serialize};

/// A range a value is drawn from uniformly: `[lo, hi]`, or one number for a fixed value.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum Range {
    /// A fixed value.
    Fixed(f64),
    /// `[lo, hi]` with lo ≤ hi, drawn uniformly.
    Span([f64; 2]),
}

impl Range {
    /// The lower and upper bound (equal for a fixed value).
    pub fn bounds(&self) -> (f64, f64) {
        match *self {
            Range::Fixed(x) => (x, x),
            Range::Span([lo, hi]) => (lo, hi),
        }
    }

    /// A value uniform in [lo, hi) (exactly lo when fixed); always one draw.
    pub fn draw(&self, stream: &mut Stream) -> f64 {
        let (lo, hi) = self.bounds();
        stream.uniform(lo, hi)
    }

    /// A value whose logarithm is uniform between the logarithms of the bounds (bounds > 0).
    pub fn draw_log(&self, stream: &mut Stream) -> f64 {
        let (lo, hi) = self.bounds();
        libm::exp(stream.uniform(libm::log(lo), libm::log(hi)))
    }

    /// An integer uniform over the integers in [lo, hi] (bounds rounded inwards; specs check
    /// with [`check_integers`] that there is one); always one draw.
    pub fn draw_integer(&self, stream: &mut Stream) -> i64 {
        let (lo, hi) = self.bounds();
        let (lo, hi) = (lo.ceil() as i64, hi.floor() as i64);
        stream.integer(lo, hi.max(lo))
    }
}

/// Implements `validate` and `draw` for the spec of an operation with one drawn parameter:
/// `spec`'s `field` is a [`Range`] within `bounds`, its draw becomes `params`' `field`.
macro_rules! one_parameter_spec {
    ($spec:ident, $params:ident { $field:ident }, $bounds:expr) => {
        impl $spec {
            /// Checks the range and probability; the error names the parameter by its path
            /// under `at` (the operation's place in the recipe) and shows its value.
            pub fn validate(&self, at: &str) -> Result<(), String> {
                let field = stringify!($field);
                super::draw::check_one(at, field, &self.$field, $bounds, self.probability)
            }

            /// Draws one view's parameters, or `None` when the probability says skip.
            pub fn draw(&self, stream: &mut Stream) -> Option<$params> {
                happens(stream, self.probability).then(|| $params {
                    $field: self.$field.draw(stream),
                })
            }
        }
    };
}
pub(super) use one_parameter_spec;

/// Whether an operation applied with `probability` happens this time: one draw, true with
/// that probability (always for 1, never for 0).
pub fn happens(stream: &mut Stream, probability: f64) -> bool {
    stream.unit() < probability
}

impl std::fmt::Display for Range {
    /// As a recipe writes it: one number, or `[lo, hi]`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Range::Fixed(x) => write!(f, "{x}"),
            Range::Span([lo, hi]) => write!(f, "[{lo}, {hi}]"),
        }
    }
}

/// Checks that `range` is ordered, finite and within [min, max] (an infinite or ±f64::MAX
/// bound is no bound); the error names `name` and shows the range as written.
pub fn check_range(name: &str, range: &Range, min: f64, max: f64) -> Result<(), String> {
    let (lo, hi) = range.bounds();
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(format!("{name} = {range} must be finite"));
    }
    if lo > hi {
        return Err(format!(
            "{name} = {range}: the low end exceeds the high end"
        ));
    }
    let (bounded_below, bounded_above) = (min > -f64::MAX, max < f64::MAX);
    if lo >= min && hi <= max {
        return Ok(());
    }
    Err(match (bounded_below, bounded_above) {
        (true, true) => format!("{name} = {range} must lie within [{min}, {max}]"),
        (true, false) => format!("{name} = {range} must be ≥ {min}"),
        _ => format!("{name} = {range} must be ≤ {max}"),
    })
}

/// Checks that a range drawn as an integer holds at least one whole number: rounding its
/// bounds inwards must not cross (otherwise every draw would be one made-up value).
pub fn check_integers(name: &str, range: &Range) -> Result<(), String> {
    let (lo, hi) = range.bounds();
    if lo.ceil() <= hi.floor() {
        Ok(())
    } else {
        Err(format!(
            "{name} = {range} holds no whole number; give whole bounds such as [{}, {}]",
            lo.floor(),
            hi.ceil()
        ))
    }
}

/// Checks the spec of a one-parameter operation at `at`: its range `field` within `bounds`
/// and the probability of the operation.
pub fn check_one(
    at: &str,
    field: &str,
    range: &Range,
    bounds: [f64; 2],
    probability: f64,
) -> Result<(), String> {
    check_range(&format!("{at}.{field}"), range, bounds[0], bounds[1])?;
    check_probability(at, probability)
}

/// Checks that the probability of the operation at `at` lies in [0, 1].
pub fn check_probability(at: &str, probability: f64) -> Result<(), String> {
    if (0.0..=1.0).contains(&probability) {
        Ok(())
    } else {
        Err(format!(
            "{at}.probability = {probability} must lie within [0, 1]"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::test_stream;

    fn moments(values: &[f64]) -> (f64, f64) {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        (mean, var)
    }

    #[test]
    fn uniform_draws_have_the_bounds_mean_and_variance_of_their_range() {
        let mut s = test_stream("range");
        let r = Range::Span([0.8, 1.2]);
        let values: Vec<f64> = (0..20_000).map(|_| r.draw(&mut s)).collect();
        assert!(values.iter().all(|v| (0.8..1.2).contains(v)));
        let (mean, var) = moments(&values);
        assert!((mean - 1.0).abs() < 0.003, "{mean}");
        // Variance of U(a, b) is (b − a)²/12.
        assert!((var / (0.16 / 12.0) - 1.0).abs() < 0.03, "{var}");
        assert_eq!(Range::Fixed(2.5).draw(&mut s), 2.5);
    }

    #[test]
    fn log_uniform_draws_have_a_uniform_logarithm() {
        let mut s = test_stream("log");
        let r = Range::Span([0.08, 0.3]);
        let logs: Vec<f64> = (0..20_000).map(|_| r.draw_log(&mut s).ln()).collect();
        let (mean, var) = moments(&logs);
        let (a, b) = (0.08f64.ln(), 0.3f64.ln());
        assert!((mean - 0.5 * (a + b)).abs() < 0.01, "{mean}");
        assert!((var / ((b - a).powi(2) / 12.0) - 1.0).abs() < 0.03, "{var}");
    }

    #[test]
    fn integer_draws_cover_the_inclusive_range() {
        let mut s = test_stream("int");
        let mut seen = [0u32; 3];
        for _ in 0..3000 {
            seen[(Range::Span([1.0, 3.0]).draw_integer(&mut s) - 1) as usize] += 1;
        }
        assert!(seen.iter().all(|&c| (900..1100).contains(&c)), "{seen:?}");
        assert_eq!(Range::Fixed(70.0).draw_integer(&mut s), 70);
    }

    #[test]
    fn probability_sets_the_frequency() {
        let mut s = test_stream("p");
        for p in [0.0, 0.3, 1.0] {
            let hits = (0..20_000).filter(|_| happens(&mut s, p)).count() as f64;
            // Binomial standard deviation at p = 0.3 is about 0.0032 of the draws.
            assert!((hits / 20_000.0 - p).abs() < 0.013, "p = {p}: {hits}");
        }
    }

    #[test]
    fn checks_name_the_parameter_and_value() {
        let err = check_range("blur.sigma", &Range::Span([2.0, 1.0]), 0.0, 10.0).unwrap_err();
        assert!(err.contains("blur.sigma") && err.contains('2'), "{err}");
        assert!(check_range("x", &Range::Fixed(11.0), 0.0, 10.0).is_err());
        assert!(check_range("x", &Range::Fixed(f64::NAN), 0.0, 10.0).is_err());
        assert!(check_probability("jpeg", 1.5).unwrap_err().contains("1.5"));
        assert!(check_probability("jpeg", 0.5).is_ok());
        // A fixed value is shown as written, one-sided bounds as one-sided.
        let one = check_range("gamma", &Range::Fixed(-1.0), 0.0, f64::MAX).unwrap_err();
        assert_eq!(one, "gamma = -1 must be ≥ 0");
    }

    #[test]
    fn an_integer_range_must_hold_a_whole_number() {
        let err = check_integers("erase.count", &Range::Span([0.2, 0.8])).unwrap_err();
        assert!(err.contains("[0.2, 0.8] holds no whole number"), "{err}");
        for fine in [
            Range::Span([0.2, 1.0]),
            Range::Fixed(3.0),
            Range::Span([1.5, 2.5]),
        ] {
            assert!(check_integers("n", &fine).is_ok(), "{fine}");
        }
    }

    #[test]
    fn ranges_read_from_one_number_or_a_pair() {
        let fixed: Range = serde_json::from_str("3").unwrap();
        let span: Range = serde_json::from_str("[1, 2]").unwrap();
        assert_eq!(fixed, Range::Fixed(3.0));
        assert_eq!(span, Range::Span([1.0, 2.0]));
    }
}
