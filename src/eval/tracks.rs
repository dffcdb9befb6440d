//! Point tracks: a tracker's predicted tracks, in TAP-Vid's layout, against a sequence's true
//! point tracks (output `point_tracks`, docs/sequences.md). Definitions in docs/metrics.md.
//!
//! Owns: assembling a view's truth from its frames' `tracks.npy` (`[Q, 3]`: x, y, state),
//! reading a prediction (bounded, shape checked against the truth), and the metrics of one
//! view: RMSE and largest error over the truly visible points, TAP-Vid's δ_avg^x, occlusion
//! accuracy and average Jaccard when occlusion is predicted, and the error of the first
//! frequency identified (`history::identify_frequency`) from each track's vertical history.
//!
//! A prediction names the view without a frame, in the dataset's sample folder:
//! `NNNN/{sample:06}_{view:02}.tracks.npy` (`[N, T, 2]` float32 or float64, x, y in pixels,
//! the truth's pixel-centre convention) and optionally `NNNN/{sample:06}_{view:02}.occluded.npy`
//! (`[N, T]` bool, uint8 or float, nonzero = occluded). N and T must be the truth's: its query
//! points in order, its frames. NaN or ±inf in `tracks` is "no prediction" there, left out and
//! counted.

use super::Counts;
use super::history::identify_frequency;
use super::npy;
use super::outcome::{Outcome, Tallied};
use super::predictions::mirrored;
use super::stats;
use crate::dataset::files::{Bound, open_regular, read_bounded};
use crate::dataset::{Dataset, Sample, View};
use anyhow::{Context, Result, bail};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The largest tracks file read, truth or prediction: 4 GiB.
const TRACKS_FILE: Bound = Bound {
    what: "a point-tracks .npy",
    bytes: 1 << 32,
};

/// TAP-Vid's thresholds, pixels: δ_avg^x averages the share within each.
pub const THRESHOLDS: [f64; 5] = [1.0, 2.0, 4.0, 8.0, 16.0];

/// A view's true tracks over its frames, point-major: entry n·T + t is point n at frame t.
struct Truth {
    points: usize,
    frames: usize,
    xy: Vec<[f64; 2]>,
    visible: Vec<bool>,
    fps: f64,
}

/// A prediction: positions (NaN where none) and, if given, occlusion flags, point-major.
struct Prediction {
    xy: Vec<[f64; 2]>,
    occluded: Option<Vec<bool>>,
}

/// The scores of one view's predicted tracks.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct TrackScore {
    /// The view, `{sample:06}_{view:02}` (`a{copy}` for a copy).
    pub view: String,
    /// Query points, and frames.
    pub points: usize,
    /// Frames of the sequence.
    pub frames: usize,
    /// (point, frame) pairs scored: truly visible, after the query frame, predicted.
    pub scored: u64,
    /// Truly visible pairs after the query frame with no prediction (NaN or ±inf).
    pub excluded: u64,
    /// √mean |p − t|² over the pairs scored, px.
    pub rmse: Option<f64>,
    /// max |p − t| over the pairs scored, px.
    pub max_error: Option<f64>,
    /// Share of the pairs scored within each of `THRESHOLDS` (strictly).
    pub within: Option<[f64; 5]>,
    /// TAP-Vid's δ_avg^x: the mean of `within`.
    pub delta_avg: Option<f64>,
    /// Share of the pairs after the query frame whose predicted occlusion is the truth's.
    pub occlusion_accuracy: Option<f64>,
    /// TAP-Vid's average Jaccard over `THRESHOLDS`.
    pub average_jaccard: Option<f64>,
    /// Tracks whose first frequency was identified from both histories.
    pub frequency_tracks: usize,
    /// Mean |f₁ predicted − f₁ true| over those tracks, Hz.
    pub frequency_error: Option<f64>,
}

impl Tallied for TrackScore {
    fn has_metrics(&self) -> bool {
        self.scored > 0
    }
    fn pixels(&self) -> (u64, u64) {
        (self.scored, self.excluded)
    }
}

/// Point tracks in the report: counts, the means over the views scored, each view's scores.
#[derive(Clone, Debug, Serialize)]
pub struct TracksReport {
    /// Views scored (`images`), missing, and (point, frame) pairs (`pixels`) scored and left out.
    pub counts: Counts,
    /// Mean over views of each view's RMSE, px.
    pub rmse: Option<f64>,
    /// Mean over views of each view's largest error, px.
    pub max_error: Option<f64>,
    /// Mean over views of δ_avg^x.
    pub delta_avg: Option<f64>,
    /// Mean over the views predicting occlusion of their occlusion accuracy.
    pub occlusion_accuracy: Option<f64>,
    /// Mean over the views predicting occlusion of their average Jaccard.
    pub average_jaccard: Option<f64>,
    /// Mean over the views with identified frequencies of their mean |Δf₁|, Hz.
    pub frequency_error: Option<f64>,
    /// Each scored view's scores, in dataset order.
    pub views: Vec<TrackScore>,
}

/// The report of point tracks, None when none was predicted.
pub(super) fn report(
    outcomes: &[(String, Outcome<TrackScore>)],
    counts: Counts,
) -> Option<TracksReport> {
    if !outcomes.iter().any(|(_, o)| o.predicted()) {
        return None;
    }
    let views: Vec<TrackScore> = (outcomes.iter())
        .filter_map(|(_, o)| o.scored().cloned())
        .collect();
    let mean = |f: fn(&TrackScore) -> Option<f64>| stats::mean(views.iter().filter_map(f));
    Some(TracksReport {
        counts,
        rmse: mean(|s| s.rmse),
        max_error: mean(|s| s.max_error),
        delta_avg: mean(|s| s.delta_avg),
        occlusion_accuracy: mean(|s| s.occlusion_accuracy),
        average_jaccard: mean(|s| s.average_jaccard),
        frequency_error: mean(|s| s.frequency_error),
        views,
    })
}

impl TracksReport {
    /// The block of the text report.
    pub(super) fn text(&self) -> String {
        let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
        format!(
            "tracks: {} views, {} visible (point, frame) pairs (mean over views)\n  RMSE {} px, max error {} px, δ_avg {}, occlusion accuracy {}, AJ {}, |Δf₁| {} Hz\n",
            self.counts.images,
            self.counts.pixels,
            f(self.rmse),
            f(self.max_error),
            f(self.delta_avg),
            f(self.occlusion_accuracy),
            f(self.average_jaccard),
            f(self.frequency_error)
        )
    }
}

/// The views of `sample` with true tracks, each with the outcome of its prediction (named by
/// the view's stem without the frame).
pub(super) fn score_sample(
    dataset: &Dataset,
    samples: &Path,
    sample: &Sample,
) -> Result<Vec<(String, Outcome<TrackScore>)>> {
    let mut out = Vec::new();
    for frames in tracked_views(sample) {
        let (stem, path, occluded) = prediction_paths(samples, frames[0]);
        if !path.exists() {
            out.push((stem, Outcome::Missing));
            continue;
        }
        let truth = truth(dataset, &frames)?;
        let prediction = predicted(&path, occluded.exists().then_some(&occluded), &truth)?;
        let scores = score(&stem, &truth, &prediction);
        out.push((stem, Outcome::Scored(scores)));
    }
    Ok(out)
}

/// The prediction files eval reads for the tracked views of `sample` (for `misnamed`).
pub(super) fn candidates(samples: &Path, sample: &Sample) -> Vec<PathBuf> {
    tracked_views(sample)
        .iter()
        .flat_map(|frames| {
            let (_, tracks, occluded) = prediction_paths(samples, frames[0]);
            [tracks, occluded]
        })
        .collect()
}

/// The view's stem without its frame, and where its predicted tracks and occlusion are.
fn prediction_paths(samples: &Path, first: &View) -> (String, PathBuf, PathBuf) {
    let stem = first.stem.split("_f").next().unwrap_or(&first.stem);
    let at = |kind: &str| mirrored(samples, &format!("{}/{stem}.{kind}", first.folder()));
    (stem.to_string(), at("tracks.npy"), at("occluded.npy"))
}

/// The frames of each view (clean or copy) of `sample` that has true tracks, in frame order.
fn tracked_views(sample: &Sample) -> Vec<Vec<&View>> {
    let mut groups: Vec<Vec<&View>> = Vec::new();
    for view in sample
        .views
        .iter()
        .filter(|v| v.file("tracks.npy").is_some())
    {
        match groups.last_mut() {
            Some(group) if (group[0].view, group[0].copy) == (view.view, view.copy) => {
                group.push(view)
            }
            _ => groups.push(vec![view]),
        }
    }
    for group in &mut groups {
        group.sort_by_key(|v| v.frame);
    }
    groups
}

/// A view's truth from its frames' tracks files (and the frame rate from its first record).
fn truth(dataset: &Dataset, frames: &[&View]) -> Result<Truth> {
    let mut per_frame = Vec::new();
    for view in frames {
        let relative = view.file("tracks.npy").unwrap_or_default();
        let array = npy::parse(&dataset.read(relative, TRACKS_FILE)?)
            .with_context(|| format!("{relative}: the truth's tracks"))?;
        if array.shape.len() != 2 || array.shape[1] != 3 {
            bail!(
                "{relative}: shape {:?}; tracks are [queries, 3]",
                array.shape
            );
        }
        per_frame.push(array);
    }
    let points = per_frame[0].shape[0];
    if let Some(odd) = per_frame.iter().position(|a| a.shape[0] != points) {
        bail!(
            "{}: {} queries, frame 0 has {points}",
            frames[odd].stem,
            per_frame[odd].shape[0]
        );
    }
    let count = frames.len();
    let (mut xy, mut visible) = (Vec::new(), Vec::new());
    for n in 0..points {
        for frame in &per_frame {
            let row = &frame.values[3 * n..3 * n + 3];
            xy.push([row[0], row[1]]);
            visible.push(row[2] == 1.0);
        }
    }
    let record = dataset.record(frames[0])?;
    let fps = record["frame"]["fps"].as_f64().unwrap_or(0.0);
    Ok(Truth {
        points,
        frames: count,
        xy,
        visible,
        fps,
    })
}

/// Reads the prediction at `tracks` (and `occluded`), checking its shape against `truth`.
fn predicted(tracks: &Path, occluded: Option<&Path>, truth: &Truth) -> Result<Prediction> {
    let (n, t) = (truth.points, truth.frames);
    let read = |path: &Path, flags: bool| -> Result<npy::Array> {
        let name = path.display().to_string();
        let bytes = read_bounded(open_regular(path)?, &name, TRACKS_FILE)?;
        let parsed = if flags {
            npy::parse_flags(&bytes)
        } else {
            npy::parse(&bytes)
        };
        parsed.with_context(|| name.clone())
    };
    let array = read(tracks, false)?;
    if array.shape != [n, t, 2] {
        bail!(
            "{}: shape {:?}; the truth has {n} query points over {t} frames: expected [{n}, {t}, 2] (x, y)",
            tracks.display(),
            array.shape
        );
    }
    let xy = array.values.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
    let occluded = match occluded {
        None => None,
        Some(path) => {
            let flags = read(path, true)?;
            if flags.shape != [n, t] {
                bail!(
                    "{}: shape {:?}; expected [{n}, {t}] (the tracks' points and frames)",
                    path.display(),
                    flags.shape
                );
            }
            if let Some(bad) = flags.values.iter().position(|v| !v.is_finite()) {
                bail!(
                    "{}: entry {bad} is {}; occlusion flags are 0 (visible) or nonzero (occluded)",
                    path.display(),
                    flags.values[bad]
                );
            }
            Some(flags.values.iter().map(|&v| v != 0.0).collect())
        }
    };
    Ok(Prediction { xy, occluded })
}

/// The metrics of one view (docs/metrics.md): every pair after the query frame (frame 0).
fn score(view: &str, truth: &Truth, prediction: &Prediction) -> TrackScore {
    let pairs = || {
        (0..truth.points).flat_map(move |n| (1..truth.frames).map(move |t| n * truth.frames + t))
    };
    let error = |i: usize| {
        let ([px, py], [tx, ty]) = (prediction.xy[i], truth.xy[i]);
        (px.is_finite() && py.is_finite()).then(|| (px - tx).hypot(py - ty))
    };
    let (mut scored, mut excluded, mut squares, mut largest) = (0u64, 0u64, 0.0, 0.0f64);
    let mut within = [0u64; 5];
    for i in pairs().filter(|&i| truth.visible[i]) {
        let Some(e) = error(i) else {
            excluded += 1;
            continue;
        };
        scored += 1;
        squares += e * e;
        largest = largest.max(e);
        for (count, threshold) in within.iter_mut().zip(THRESHOLDS) {
            *count += u64::from(e < threshold);
        }
    }
    let share = |count: u64| count as f64 / scored as f64;
    let within = (scored > 0).then(|| within.map(share));
    let (occlusion_accuracy, average_jaccard) = match &prediction.occluded {
        Some(occluded) => {
            // Right where the flag says occluded exactly where the truth is not visible.
            let accuracy = pairs().filter(|&i| occluded[i] != truth.visible[i]).count();
            let all = pairs().count().max(1);
            let jaccard = THRESHOLDS.map(|threshold| {
                let seen_within =
                    |i: usize| !occluded[i] && error(i).is_some_and(|e| e < threshold);
                let tp = pairs()
                    .filter(|&i| truth.visible[i] && seen_within(i))
                    .count();
                let claimed = pairs().filter(|&i| !occluded[i]).count();
                let visible = pairs().filter(|&i| truth.visible[i]).count();
                // Jaccard = TP / (TP + FP + FN), FP = claimed − TP, FN = visible − TP.
                tp as f64 / (claimed + visible - tp).max(1) as f64
            });
            (
                Some(accuracy as f64 / all as f64),
                Some(jaccard.iter().sum::<f64>() / 5.0),
            )
        }
        None => (None, None),
    };
    let frequency_errors = frequency_errors(truth, prediction);
    TrackScore {
        view: view.to_string(),
        points: truth.points,
        frames: truth.frames,
        scored,
        excluded,
        rmse: (scored > 0).then(|| (squares / scored as f64).sqrt()),
        max_error: (scored > 0).then_some(largest),
        delta_avg: within.map(|w| w.iter().sum::<f64>() / 5.0),
        within,
        occlusion_accuracy,
        average_jaccard,
        frequency_tracks: frequency_errors.len(),
        frequency_error: (!frequency_errors.is_empty())
            .then(|| frequency_errors.iter().sum::<f64>() / frequency_errors.len() as f64),
    }
}

/// |f₁ predicted − f₁ true| (Hz) of each track visible in every frame and predicted in every
/// frame whose first frequency both vertical histories (y, px) show.
fn frequency_errors(truth: &Truth, prediction: &Prediction) -> Vec<f64> {
    let t = truth.frames;
    (0..truth.points)
        .filter_map(|n| {
            let span = n * t..(n + 1) * t;
            if !truth.visible[span.clone()].iter().all(|&v| v) {
                return None;
            }
            let true_y: Vec<f64> = truth.xy[span.clone()].iter().map(|p| p[1]).collect();
            let predicted_y: Vec<f64> = prediction.xy[span].iter().map(|p| p[1]).collect();
            let f_true = identify_frequency(&true_y, truth.fps)?;
            let f_predicted = identify_frequency(&predicted_y, truth.fps)?;
            Some((f_predicted - f_true).abs())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two points over four frames, moving right by 1 px a frame from (10.5, 20.5) and
    /// (30.5, 40.5); the second hidden at frame 2.
    fn truth() -> Truth {
        let mut xy = Vec::new();
        for start in [[10.5, 20.5], [30.5, 40.5]] {
            for t in 0..4 {
                xy.push([start[0] + t as f64, start[1]]);
            }
        }
        let mut visible = vec![true; 8];
        visible[6] = false;
        Truth {
            points: 2,
            frames: 4,
            xy,
            visible,
            fps: 30.0,
        }
    }

    fn shifted(dx: f64) -> Vec<[f64; 2]> {
        truth().xy.iter().map(|p| [p[0] + dx, p[1]]).collect()
    }

    #[test]
    fn a_perfect_prediction_scores_zero_and_delta_one() {
        let truth = truth();
        let occluded = Some(truth.visible.iter().map(|v| !v).collect());
        let perfect = Prediction {
            xy: truth.xy.clone(),
            occluded,
        };
        let s = score("v", &truth, &perfect);
        assert_eq!((s.scored, s.excluded), (5, 0));
        assert_eq!(
            (s.rmse, s.max_error, s.delta_avg),
            (Some(0.0), Some(0.0), Some(1.0))
        );
        assert_eq!(s.occlusion_accuracy, Some(1.0));
        assert_eq!(s.average_jaccard, Some(1.0));
    }

    #[test]
    fn a_shift_of_one_and_a_half_pixels_scores_that_rmse_and_misses_the_one_pixel_threshold() {
        let truth = truth();
        let s = score(
            "v",
            &truth,
            &Prediction {
                xy: shifted(1.5),
                occluded: None,
            },
        );
        assert_eq!(s.rmse, Some(1.5));
        assert_eq!(s.max_error, Some(1.5));
        assert_eq!(s.within, Some([0.0, 1.0, 1.0, 1.0, 1.0]));
        assert_eq!(s.delta_avg, Some(0.8));
        assert_eq!((s.occlusion_accuracy, s.average_jaccard), (None, None));
    }

    #[test]
    fn occlusion_claimed_everywhere_scores_the_visible_share_and_no_jaccard() {
        let truth = truth();
        let s = score(
            "v",
            &truth,
            &Prediction {
                xy: truth.xy.clone(),
                occluded: Some(vec![true; 8]),
            },
        );
        // Of the six pairs after the query frame, one is truly hidden.
        assert_eq!(s.occlusion_accuracy, Some(1.0 / 6.0));
        assert_eq!(s.average_jaccard, Some(0.0));
        // Positions are scored on the truly visible pairs whatever the occlusion claimed.
        assert_eq!(s.delta_avg, Some(1.0));
    }

    #[test]
    fn pairs_not_predicted_are_left_out_and_counted() {
        let truth = truth();
        let mut xy = truth.xy.clone();
        xy[1] = [f64::NAN, 0.0];
        let s = score("v", &truth, &Prediction { xy, occluded: None });
        assert_eq!((s.scored, s.excluded), (4, 1));
        assert_eq!(s.rmse, Some(0.0));
    }

    #[test]
    fn a_track_oscillating_at_two_hertz_is_identified_so() {
        let frames = 120;
        let oscillation = |amplitude: f64| -> Vec<[f64; 2]> {
            (0..frames)
                .map(|t| {
                    let time = t as f64 / 30.0;
                    [
                        5.5,
                        7.5 + amplitude * (2.0 * std::f64::consts::PI * 2.0 * time).sin(),
                    ]
                })
                .collect()
        };
        let truth = Truth {
            points: 1,
            frames,
            xy: oscillation(1.0),
            visible: vec![true; frames],
            fps: 30.0,
        };
        let prediction = Prediction {
            xy: oscillation(0.5),
            occluded: None,
        };
        let errors = frequency_errors(&truth, &prediction);
        assert_eq!(errors.len(), 1);
        assert!(errors[0] < 1e-9, "{errors:?}");
    }
}
