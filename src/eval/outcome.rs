//! What became of each view (or sample) for one predicted quantity, and the account of what
//! was not scored: predictions missing, predictions whose truth the dataset lacks, images with
//! nothing to score. Each is counted and named (the first few), in text and JSON, so a partial
//! evaluation is never mistaken for a complete one.
//!
//! Owns: [`Outcome`], [`Unscored`] and the tally of outcomes into counts and unscored groups.
//! The rule of completeness (`shmgen eval` exits 2 when it does not hold): every selected view
//! (sample, for surfaces) has a prediction of each quantity predicted anywhere, and each
//! prediction was scored.

use super::Counts;
use serde::Serialize;

/// How many names an [`Unscored`] group lists.
pub(super) const LISTED: usize = 5;

/// One view's (or sample's) outcome for one quantity.
pub(super) enum Outcome<T> {
    /// No prediction file.
    Missing,
    /// A prediction, but the dataset lacks the truth it is scored against (the reason).
    NoTruth(String),
    /// Scored (the score may still have nothing in it: no pixel left).
    Scored(T),
}

impl<T> Outcome<T> {
    /// Whether there is a prediction at all.
    pub(super) fn predicted(&self) -> bool {
        !matches!(self, Outcome::Missing)
    }

    /// The score, if scored.
    pub(super) fn scored(&self) -> Option<&T> {
        match self {
            Outcome::Scored(t) => Some(t),
            _ => None,
        }
    }
}

/// A group of views or samples of one quantity not scored, for one reason.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Unscored {
    /// `depth`, `flow`, `displacement`, `surface` or `history` (files of a sample).
    pub quantity: &'static str,
    /// Why they were not scored.
    pub reason: String,
    /// How many.
    pub count: usize,
    /// The first few, by stem (views) or `sample N`, in dataset order.
    pub first: Vec<String>,
}

impl Unscored {
    /// One line for a person: `depth: 3 views not scored: no prediction (e.g. 000001_00, …)`.
    pub fn describe(&self) -> String {
        let unit = if matches!(self.quantity, "surface" | "history") {
            "samples"
        } else {
            "views"
        };
        let more = if self.count > self.first.len() {
            ", …"
        } else {
            ""
        };
        format!(
            "{}: {} {unit} not scored: {} (e.g. {}{more})",
            self.quantity,
            self.count,
            self.reason,
            self.first.join(", ")
        )
    }
}

/// What the score of one item says for the counts: whether it has metrics, the pixels (or
/// points) scored and left out.
pub(super) trait Tallied {
    fn has_metrics(&self) -> bool;
    fn pixels(&self) -> (u64, u64);
}

/// The reason given for a view without a prediction.
pub(super) const NO_PREDICTION: &str = "no prediction";

/// The reason given for a scored image with no pixel left.
const NOTHING_TO_SCORE: &str = "nothing to score (no pixel left, or the alignment is undefined)";

/// Counts and unscored groups of one quantity over `items` (name, outcome), in order. A
/// quantity predicted nowhere has no counts and no groups (it was not asked for).
pub(super) fn tally<T: Tallied>(
    quantity: &'static str,
    items: &[(String, &Outcome<T>)],
) -> (Counts, Vec<Unscored>) {
    let mut counts = Counts::default();
    if !items.iter().any(|(_, o)| o.predicted()) {
        return (counts, Vec::new());
    }
    let mut groups: Vec<Unscored> = Vec::new();
    let mut add = |reason: &str, name: &str| {
        let group = match groups.iter().position(|g| g.reason == reason) {
            Some(k) => &mut groups[k],
            None => {
                groups.push(Unscored {
                    quantity,
                    reason: reason.to_string(),
                    count: 0,
                    first: Vec::new(),
                });
                groups.last_mut().unwrap()
            }
        };
        group.count += 1;
        if group.first.len() < LISTED {
            group.first.push(name.to_string());
        }
    };
    for (name, outcome) in items {
        match outcome {
            Outcome::Missing => {
                counts.missing += 1;
                add(NO_PREDICTION, name);
            }
            Outcome::NoTruth(reason) => {
                counts.no_truth += 1;
                add(reason, name);
            }
            Outcome::Scored(score) => {
                let (pixels, excluded) = score.pixels();
                counts.pixels += pixels;
                counts.excluded_pixels += excluded;
                if score.has_metrics() {
                    counts.images += 1;
                } else {
                    counts.skipped += 1;
                    add(NOTHING_TO_SCORE, name);
                }
            }
        }
    }
    (counts, groups)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct S(bool);
    impl Tallied for S {
        fn has_metrics(&self) -> bool {
            self.0
        }
        fn pixels(&self) -> (u64, u64) {
            (10, 1)
        }
    }

    #[test]
    fn every_item_is_counted_once_and_named_by_reason() {
        let outcomes: Vec<Outcome<S>> = (0..9)
            .map(|i| match i % 3 {
                0 => Outcome::Missing,
                1 => Outcome::NoTruth("no mesh".into()),
                _ => Outcome::Scored(S(i != 2)),
            })
            .collect();
        let items: Vec<(String, &Outcome<S>)> = outcomes
            .iter()
            .enumerate()
            .map(|(i, o)| (format!("v{i}"), o))
            .collect();
        let (c, groups) = tally("depth", &items);
        assert_eq!(
            (c.images, c.missing, c.no_truth, c.skipped, c.pixels),
            (2, 3, 3, 1, 30)
        );
        let reasons: Vec<(&str, usize, Vec<String>)> = groups
            .iter()
            .map(|g| (g.reason.as_str(), g.count, g.first.clone()))
            .collect();
        assert_eq!(
            reasons[0],
            (
                NO_PREDICTION,
                3,
                vec!["v0".into(), "v3".into(), "v6".into()]
            )
        );
        assert_eq!(reasons[1].0, "no mesh");
        assert_eq!(reasons[2], (NOTHING_TO_SCORE, 1, vec!["v2".into()]));
        let none: Vec<(String, &Outcome<S>)> = Vec::new();
        assert!(tally("flow", &none).1.is_empty());
    }
}
