//! `shmgen eval`: metrics of predictions against a finished dataset — depth (Eigen et al.
//! 2014, with optional per-image alignment), surfaces (Chamfer distance, F-score), flow and
//! displacement (end-point error), sensor histories and point tracks (TAP-Vid's metrics).
//! Every formula, with its source, is in `docs/metrics.md`.
//!
//! Owns: finding and reading predictions (and reporting the misnamed ones), the metrics and
//! the report. Must not touch: the dataset or the predictions (it only reads), rendering,
//! recipes. Aggregation: every metric is computed per image (per sample for surfaces), then
//! averaged over images with equal weight, as Marigold and Depth Anything evaluate; images are
//! scored in parallel and summed in dataset order, so the report has the same bytes on any
//! number of threads.
//!
//! What is scored: the views chosen by `--where` (all by default, see `select`), and for each
//! quantity predicted anywhere, every chosen view (sample) that has a prediction and the truth
//! to score it against. What is not (no prediction, no truth, nothing to score) is counted and
//! named in text and JSON (`outcome`); the report says whether the evaluation is complete, and
//! `shmgen eval` exits [`EXIT_PARTIAL`] when it is not. Per-image (per-sample) values are in the
//! JSON beside the means.

mod depth;
mod epe;
mod history;
mod misnamed;
mod nearest;
mod npy;
mod outcome;
mod predictions;
mod select;
mod stats;
mod surface;
mod tracks;

pub use depth::Align;
pub use misnamed::{Misnamed, Suggestion};
pub use outcome::Unscored;
pub use select::Condition;

/// The exit code of `shmgen eval` when something asked for was not scored (see [`outcome`]);
/// 0 is complete, 1 an error.
pub const EXIT_PARTIAL: u8 = 2;

use crate::dataset::{Dataset, View};
use crate::geometry::import::{import_mesh, import_surface};
use crate::output::refuse_data_target;
use crate::output::write_atomic;
use anyhow::{Context, Result, bail};
use outcome::{Outcome, Tallied, tally};
use predictions::Quantity;
use rayon::prelude::*;
use serde::Serialize;
use serde_json::Value;
use stats::Mean;
use std::path::{Path, PathBuf};

/// Which pixels depth is scored on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mask {
    /// The structure: mask > 0 (where the view has a mask) and depth > 0.
    Structure,
    /// Every pixel with valid truth: depth > 0, and valid > 0 where the view has a validity
    /// image (augmented copies warped in image space).
    Valid,
}

impl Mask {
    /// The name on the command line and in the report.
    pub fn name(self) -> &'static str {
        match self {
            Mask::Structure => "structure",
            Mask::Valid => "valid",
        }
    }
}

impl std::str::FromStr for Mask {
    type Err = String;
    fn from_str(s: &str) -> Result<Mask, String> {
        [Mask::Structure, Mask::Valid]
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown mask {s:?}: expected structure or valid"))
    }
}

/// How to evaluate.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Per-image alignment of depth predictions.
    pub align: Align,
    /// The pixels depth is scored on.
    pub mask: Mask,
    /// F-score threshold τ, metres.
    pub fscore_threshold: f64,
    /// Points sampled on each mesh for Chamfer distance and F-score.
    pub surface_samples: usize,
    /// Where the report's JSON will be written, if anywhere: refused before scoring, which
    /// may take minutes, if it is or lies inside a dataset or an export.
    pub json: Option<PathBuf>,
    /// `--where` conditions: only the views for which all hold are scored.
    pub selection: Vec<Condition>,
}

/// The report, as `--json` writes it.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    schema: &'static str,
    dataset: Value,
    settings: Settings,
    /// The views scored: all, or those `--where` chose.
    pub selection: Selection,
    /// Whether every selected view (sample) had a prediction of each quantity predicted
    /// anywhere, and each was scored (`unscored` is empty).
    pub complete: bool,
    /// What was not scored and why, by quantity and reason.
    pub unscored: Vec<Unscored>,
    /// Depth: the mean over images of each image's metrics.
    #[serde(flatten)]
    pub depth: DepthMetrics,
    /// The mean over images of the alignment's scale (None without alignment).
    pub align_scale: Option<f64>,
    /// The mean over images of the alignment's shift, metres (`lstsq_shift` only).
    pub align_shift: Option<f64>,
    /// Depth: images scored, missing, skipped, and pixels.
    pub depth_counts: Counts,
    /// Chamfer distance and F-score, when surfaces were predicted.
    pub surface: Option<SurfaceReport>,
    /// Optical flow EPE (pixels), when flow was predicted.
    pub flow: Option<EpeReport>,
    /// Displacement EPE (metres), when displacement was predicted.
    pub displacement: Option<EpeReport>,
    /// Sensor histories (`{sample:06}.sensors_{rate}hz.csv`), when any was predicted.
    pub histories: Option<history::HistoryReport>,
    /// Point tracks (`{sample:06}_{view:02}.tracks.npy`), when any was predicted.
    pub tracks: Option<tracks::TracksReport>,
    /// Files under PREDICTIONS that look like predictions but that no view or sample reads.
    pub misnamed_files: Misnamed,
    /// Each scored view's values, in dataset order.
    pub images: Vec<ImageResult>,
    /// Each scored sample's surface values, in dataset order.
    pub samples: Vec<SampleResult>,
}

/// Which views were scored.
#[derive(Clone, Debug, Serialize)]
pub struct Selection {
    /// The `--where` conditions, as given (FIELD=VALUE).
    pub conditions: Vec<String>,
    /// Views chosen, of the dataset's.
    pub views: usize,
    /// Views of the dataset.
    pub dataset_views: usize,
    /// Samples with a chosen view, of the dataset's.
    pub samples: usize,
    /// Samples of the dataset.
    pub dataset_samples: usize,
}

/// One view's values (None: that quantity was not scored for it).
#[derive(Clone, Debug, Serialize)]
pub struct ImageResult {
    /// The view's file stem (`000003_01`, or `000003_01a0` for an augmented copy).
    pub stem: String,
    /// The sample index.
    pub sample: u64,
    /// The view index.
    pub view: u32,
    /// The augmented copy's index (None for a clean view).
    pub copy: Option<u32>,
    /// Depth metrics.
    pub depth: Option<DepthResult>,
    /// Optical flow EPE, pixels.
    pub flow: Option<EpeResult>,
    /// Displacement EPE, metres.
    pub displacement: Option<EpeResult>,
}

/// The depth metrics of one image, or their means over images (None where nothing was
/// scored).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct DepthMetrics {
    /// Mean |d − d*| / d*.
    pub abs_rel: Option<f64>,
    /// Mean (d − d*)² / d*.
    pub sq_rel: Option<f64>,
    /// √mean (d − d*)², metres.
    pub rmse: Option<f64>,
    /// √mean (ln d − ln d*)².
    pub rmse_log: Option<f64>,
    /// δ < 1.25.
    pub delta1: Option<f64>,
    /// δ < 1.25².
    pub delta2: Option<f64>,
    /// δ < 1.25³.
    pub delta3: Option<f64>,
}

impl DepthMetrics {
    /// The first seven of `values` (AbsRel, SqRel, RMSE, RMSE log, δ1, δ2, δ3), if any.
    fn from_values(values: Option<&[f64]>) -> DepthMetrics {
        let m = |i: usize| values.map(|v| v[i]);
        DepthMetrics {
            abs_rel: m(0),
            sq_rel: m(1),
            rmse: m(2),
            rmse_log: m(3),
            delta1: m(4),
            delta2: m(5),
            delta3: m(6),
        }
    }
}

/// One image's depth metrics (None where it had nothing to score).
#[derive(Clone, Debug, Serialize)]
pub struct DepthResult {
    /// Its metrics.
    #[serde(flatten)]
    pub metrics: DepthMetrics,
    /// Pixels scored.
    pub pixels: u64,
    /// Pixels left out (see `settings.excluded`).
    pub excluded_pixels: u64,
    /// The alignment's scale (1 without alignment; None when undefined).
    pub scale: Option<f64>,
    /// The alignment's shift, metres (0 without a fitted shift; None when undefined).
    pub shift: Option<f64>,
}

/// One image's end-point error.
#[derive(Clone, Debug, Serialize)]
pub struct EpeResult {
    /// The image's mean end-point error.
    pub epe_mean: Option<f64>,
    /// The image's median end-point error.
    pub epe_median: Option<f64>,
    /// Pixels scored.
    pub pixels: u64,
    /// Pixels left out (not predicted).
    pub excluded_pixels: u64,
}

/// One sample's surface metrics.
#[derive(Clone, Debug, Serialize)]
pub struct SampleResult {
    /// The sample's index.
    pub sample: u64,
    /// Its metrics.
    #[serde(flatten)]
    pub metrics: SurfaceMetrics,
}

/// Surface metrics of one sample, or their means over samples.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SurfaceMetrics {
    /// ½ (accuracy + completeness), metres.
    pub chamfer_l1: f64,
    /// Mean squared accuracy + mean squared completeness, m².
    pub chamfer_l2: f64,
    /// Mean distance of predicted points to the true surface, metres.
    pub accuracy: f64,
    /// Mean distance of true surface points to the prediction, metres.
    pub completeness: f64,
    /// Share of predicted points within τ of the truth.
    pub precision: f64,
    /// Share of true points within τ of the prediction.
    pub recall: f64,
    /// 2PR / (P + R) (per sample, then averaged).
    pub fscore: f64,
}

impl SurfaceMetrics {
    /// The metrics from the values [`SurfaceMetrics::values`] gives, or their means.
    fn from_values(m: [f64; 7]) -> SurfaceMetrics {
        SurfaceMetrics {
            chamfer_l1: m[0],
            chamfer_l2: m[1],
            accuracy: m[2],
            completeness: m[3],
            precision: m[4],
            recall: m[5],
            fscore: m[6],
        }
    }

    /// A sample's metrics as values to average.
    fn values(s: &surface::SurfaceScore) -> [f64; 7] {
        [
            s.chamfer_l1(),
            s.chamfer_l2(),
            s.accuracy,
            s.completeness,
            s.precision,
            s.recall,
            s.fscore(),
        ]
    }
}

#[derive(Clone, Debug, Serialize)]
struct Settings {
    align: &'static str,
    mask: &'static str,
    aggregate: &'static str,
    fscore_threshold: f64,
    surface_samples: usize,
    excluded: &'static str,
}

/// How many images (or samples) and pixels (or points) a metric saw.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Counts {
    /// Images with a prediction and at least one scored pixel.
    pub images: usize,
    /// Views of the dataset with no prediction (while others have one).
    pub missing: usize,
    /// Views with a prediction whose truth the dataset lacks (listed in `unscored`).
    pub no_truth: usize,
    /// Images with a prediction but nothing to score (no pixel left, alignment undefined).
    pub skipped: usize,
    /// Pixels scored, over all images.
    pub pixels: u64,
    /// Pixels left out: not predicted (NaN or ±inf, 0 in a millimetre PNG) or (depth) not
    /// positive after alignment.
    pub excluded_pixels: u64,
}

/// Surface metrics, means over samples.
#[derive(Clone, Debug, Serialize)]
pub struct SurfaceReport {
    /// Means over the samples scored.
    #[serde(flatten)]
    pub metrics: SurfaceMetrics,
    /// Samples scored and missing.
    pub samples: usize,
    /// Samples of the dataset with no predicted surface.
    pub missing: usize,
    /// Samples with a predicted surface but no true mesh (listed in `unscored`).
    pub no_truth: usize,
}

/// End-point error, means over images of each image's mean and median.
#[derive(Clone, Debug, Serialize)]
pub struct EpeReport {
    /// Mean over images of the image's mean EPE.
    pub epe_mean: Option<f64>,
    /// Mean over images of the image's median EPE.
    pub epe_median: Option<f64>,
    /// Images and pixels.
    pub counts: Counts,
}

/// What one view's predictions gave.
struct ViewScores {
    depth: Outcome<depth::ImageDepth>,
    flow: Outcome<epe::ImageEpe>,
    displacement: Outcome<epe::ImageEpe>,
}

impl Tallied for depth::ImageDepth {
    fn has_metrics(&self) -> bool {
        self.metrics.is_some()
    }
    fn pixels(&self) -> (u64, u64) {
        (self.pixels, self.excluded)
    }
}

impl Tallied for epe::ImageEpe {
    fn has_metrics(&self) -> bool {
        self.mean_median.is_some()
    }
    fn pixels(&self) -> (u64, u64) {
        (self.pixels, self.excluded)
    }
}

impl Tallied for surface::SurfaceScore {
    fn has_metrics(&self) -> bool {
        true
    }
    fn pixels(&self) -> (u64, u64) {
        (0, 0)
    }
}

/// Evaluates the predictions in `predictions` against the finished dataset at `root`.
pub fn evaluate(root: &Path, predictions: &Path, options: &EvalOptions) -> Result<Report> {
    if !(options.fscore_threshold > 0.0 && options.fscore_threshold.is_finite()) {
        bail!(
            "--fscore-threshold {}: expected a positive distance in metres",
            options.fscore_threshold
        );
    }
    if options.surface_samples == 0 {
        bail!("--surface-samples 0: at least one point per surface is needed");
    }
    if let Some(json) = &options.json {
        refuse_data_target(json, "--json", Some(root), false)?;
    }
    let dataset = Dataset::open(root)?;
    let samples = predictions::samples_folder(predictions)?;
    let views = select::select(&dataset, &options.selection)?;
    if views.is_empty() {
        bail!(
            "--where {}: no view of the dataset matches",
            conditions_shown(&options.selection).join(" --where ")
        );
    }
    let scores = views
        .par_iter()
        .map(|view| score_view(&dataset, &samples, view, options))
        .collect::<Result<Vec<_>>>()?;
    let chosen_samples: Vec<&crate::dataset::Sample> = dataset
        .samples
        .iter()
        .filter(|s| views.iter().any(|v| v.sample == s.index))
        .collect();
    let surfaces = chosen_samples
        .iter()
        .map(|sample| score_surface(&dataset, &samples, sample, options))
        .collect::<Result<Vec<_>>>()?;
    let histories = chosen_samples
        .iter()
        .map(|sample| history::score_sample(&dataset, &samples, sample))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect::<Vec<_>>();
    let track_scores = chosen_samples
        .iter()
        .map(|sample| tracks::score_sample(&dataset, &samples, sample))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect::<Vec<_>>();
    let misnamed_files = misnamed::misnamed(predictions, &samples, &dataset)?;

    let (depth_counts, mut unscored) = tally("depth", &named(&views, &scores, |s| &s.depth));
    let (flow, flow_unscored) = epe_report("flow", &named(&views, &scores, |s| &s.flow));
    let (displacement, displacement_unscored) =
        epe_report("displacement", &named(&views, &scores, |s| &s.displacement));
    let sample_items: Vec<(String, &Outcome<surface::SurfaceScore>)> = chosen_samples
        .iter()
        .zip(&surfaces)
        .map(|(s, o)| (format!("sample {}", s.index), o))
        .collect();
    let (surface_counts, surface_unscored) = tally("surface", &sample_items);
    unscored.extend(flow_unscored);
    unscored.extend(displacement_unscored);
    unscored.extend(surface_unscored);
    let history_items: Vec<(String, &Outcome<Vec<history::ColumnScore>>)> =
        histories.iter().map(|(n, o)| (n.clone(), o)).collect();
    let (history_counts, history_unscored) = tally("history", &history_items);
    unscored.extend(history_unscored);
    let track_items: Vec<(String, &Outcome<tracks::TrackScore>)> =
        track_scores.iter().map(|(n, o)| (n.clone(), o)).collect();
    let (track_counts, track_unscored) = tally("tracks", &track_items);
    unscored.extend(track_unscored);
    let surface = surface_report(&surfaces, &surface_counts);

    let anything_predicted = scores
        .iter()
        .any(|s| s.depth.predicted() || s.flow.predicted() || s.displacement.predicted())
        || surfaces.iter().any(Outcome::predicted)
        || histories.iter().any(|(_, o)| o.predicted())
        || track_scores.iter().any(|(_, o)| o.predicted());
    if !anything_predicted {
        let expected = views.first().map_or(String::new(), |v| {
            format!(
                "; eval reads {}",
                predictions::example_names(&samples, v, v.sample)
            )
        });
        let misnamed = misnamed_files
            .describe()
            .map_or(String::new(), |m| format!("\n{m}"));
        bail!(
            "{}: no prediction found{expected}{misnamed}",
            predictions.display()
        );
    }
    let mut depth_mean = Mean::<9>::default();
    for d in scores.iter().filter_map(|s| s.depth.scored()) {
        if let Some(m) = d.metrics {
            depth_mean.add([m[0], m[1], m[2], m[3], m[4], m[5], m[6], d.scale, d.shift]);
        }
    }
    let m = depth_mean.get();
    let pick = |i: usize| m.map(|m| m[i]);
    Ok(Report {
        schema: "shmgen.eval/2",
        dataset: dataset.identity(),
        settings: Settings {
            align: options.align.name(),
            mask: options.mask.name(),
            aggregate: "per image (per sample for surfaces), then the mean over images",
            fscore_threshold: options.fscore_threshold,
            surface_samples: options.surface_samples,
            excluded: "pixels not predicted (NaN or ±inf; 0 in a millimetre PNG), or (depth) not positive after alignment, are left out of the fit and the metrics, and counted",
        },
        selection: Selection {
            conditions: conditions_shown(&options.selection),
            views: views.len(),
            dataset_views: dataset.views().count(),
            samples: chosen_samples.len(),
            dataset_samples: dataset.samples.len(),
        },
        complete: unscored.is_empty(),
        unscored,
        depth: DepthMetrics::from_values(m.as_ref().map(|m| &m[..])),
        align_scale: pick(7).filter(|_| options.align != Align::None),
        align_shift: pick(8).filter(|_| options.align == Align::LstsqShift),
        depth_counts,
        surface,
        flow,
        displacement,
        histories: history::report(&histories, history_counts),
        tracks: tracks::report(&track_scores, track_counts),
        misnamed_files,
        images: image_results(&views, &scores, options.align),
        samples: chosen_samples
            .iter()
            .zip(&surfaces)
            .filter_map(|(sample, o)| o.scored().map(|s| sample_result(sample.index, s)))
            .collect(),
    })
}

/// One quantity's outcome per view, named by the view's stem.
fn named<'a, T>(
    views: &[&View],
    scores: &'a [ViewScores],
    pick: fn(&ViewScores) -> &Outcome<T>,
) -> Vec<(String, &'a Outcome<T>)> {
    views
        .iter()
        .zip(scores)
        .map(|(v, s)| (v.stem.clone(), pick(s)))
        .collect()
}

fn conditions_shown(conditions: &[Condition]) -> Vec<String> {
    conditions.iter().map(Condition::to_string).collect()
}

/// The per-image values of the views that had anything scored.
fn image_results(views: &[&View], scores: &[ViewScores], align: Align) -> Vec<ImageResult> {
    let epe = |e: &epe::ImageEpe| EpeResult {
        epe_mean: e.mean_median.map(|m| m.0),
        epe_median: e.mean_median.map(|m| m.1),
        pixels: e.pixels,
        excluded_pixels: e.excluded,
    };
    views
        .iter()
        .zip(scores)
        .filter(|(_, s)| {
            s.depth.scored().is_some()
                || s.flow.scored().is_some()
                || s.displacement.scored().is_some()
        })
        .map(|(v, s)| ImageResult {
            stem: v.stem.clone(),
            sample: v.sample,
            view: v.view,
            copy: v.copy,
            depth: s.depth.scored().map(|d| depth_result(d, align)),
            flow: s.flow.scored().map(epe),
            displacement: s.displacement.scored().map(epe),
        })
        .collect()
}

fn depth_result(d: &depth::ImageDepth, align: Align) -> DepthResult {
    let fitted = d.metrics.is_some() || align == Align::None;
    DepthResult {
        metrics: DepthMetrics::from_values(d.metrics.as_ref().map(|m| &m[..])),
        pixels: d.pixels,
        excluded_pixels: d.excluded,
        scale: fitted.then_some(if align == Align::None { 1.0 } else { d.scale }),
        shift: fitted.then_some(if align == Align::None { 0.0 } else { d.shift }),
    }
}

fn sample_result(sample: u64, s: &surface::SurfaceScore) -> SampleResult {
    SampleResult {
        sample,
        metrics: SurfaceMetrics::from_values(SurfaceMetrics::values(s)),
    }
}

fn score_view(
    dataset: &Dataset,
    samples: &Path,
    view: &View,
    options: &EvalOptions,
) -> Result<ViewScores> {
    let depth_file = predictions::find(samples, view, Quantity::Depth)?;
    let flow_file = predictions::find(samples, view, Quantity::Flow)?;
    let displacement_file = predictions::find(samples, view, Quantity::Displacement)?;
    let mut out = ViewScores {
        depth: Outcome::Missing,
        flow: Outcome::Missing,
        displacement: Outcome::Missing,
    };
    if depth_file.is_none() && flow_file.is_none() && displacement_file.is_none() {
        return Ok(out);
    }
    // Every quantity is scored where the view sees a surface or inside its masks: the true
    // depth is read once, if the dataset has it.
    let depth_layer = match view.file("depth.exr") {
        Some(_) => Some(dataset.layer(view, "depth.exr", &Quantity::Depth.channels().sets())?),
        None => None,
    };
    if let Some(path) = depth_file {
        out.depth = match &depth_layer {
            Some(layer) => Outcome::Scored(score_depth(dataset, view, layer, &path, options)?),
            None => Outcome::NoTruth(lacks(view, &[("depth.exr", "depth")]).unwrap_or_default()),
        };
    }
    if let Some(path) = flow_file {
        out.flow = match lacks(view, &[("flow.exr", "flow"), ("flow_valid.png", "flow")]) {
            Some(reason) => Outcome::NoTruth(reason),
            None => {
                let truth = dataset.layer(view, "flow.exr", &Quantity::Flow.channels().sets())?;
                let valid = positive(dataset, view, "flow_valid.png")?;
                let predicted =
                    predictions::read(&path, Quantity::Flow, truth.width, truth.height)?;
                Outcome::Scored(epe::score(&truth.channels, &predicted, &valid))
            }
        };
    }
    if let Some(path) = displacement_file {
        let needed = [("displacement.exr", "displacement"), ("depth.exr", "depth")];
        out.displacement = match (&depth_layer, lacks(view, &needed)) {
            (Some(layer), None) => {
                let truth = dataset.layer(
                    view,
                    "displacement.exr",
                    &Quantity::Displacement.channels().sets(),
                )?;
                // Displacement is that of the surface point the pixel sees: defined where it
                // sees one.
                let valid: Vec<bool> = layer.channels[0].iter().map(|&d| d > 0.0).collect();
                let predicted =
                    predictions::read(&path, Quantity::Displacement, layer.width, layer.height)?;
                Outcome::Scored(epe::score(&truth.channels, &predicted, &valid))
            }
            (_, reason) => Outcome::NoTruth(reason.unwrap_or_default()),
        };
    }
    Ok(out)
}

/// The depth metrics of the prediction at `path` against the view's true depth `layer`.
fn score_depth(
    dataset: &Dataset,
    view: &View,
    layer: &crate::dataset::Layer,
    path: &Path,
    options: &EvalOptions,
) -> Result<depth::ImageDepth> {
    let (w, h) = (layer.width, layer.height);
    let predicted = predictions::read(path, Quantity::Depth, w, h)?;
    let kind = match options.mask {
        Mask::Structure => "mask.png",
        Mask::Valid => "valid.png",
    };
    let inside = match view.file(kind) {
        Some(_) => positive(dataset, view, kind)?,
        None => vec![true; w * h],
    };
    Ok(depth::score(
        &layer.channels[0],
        &predicted[0],
        &inside,
        options.align,
    ))
}

/// Why a prediction of the view cannot be scored: the first of the dataset files `needed`
/// (kind, the output that writes it) the view lacks; None when it has them all.
fn lacks(view: &View, needed: &[(&str, &str)]) -> Option<String> {
    needed.iter().find(|(kind, _)| view.file(kind).is_none()).map(|(kind, output)| {
        format!("the dataset has no {kind} to score it against (add \"{output}\" to the recipe's outputs)")
    })
}

/// Where the view's grey image of `kind` is above 0.
fn positive(dataset: &Dataset, view: &View, kind: &str) -> Result<Vec<bool>> {
    let image = dataset.grey(view, kind)?;
    Ok(image.values.iter().map(|&v| v > 0).collect())
}

/// The EPE report of one vector quantity over the selected views (None where predicted
/// nowhere), and what of it was not scored.
fn epe_report(
    quantity: &'static str,
    items: &[(String, &Outcome<epe::ImageEpe>)],
) -> (Option<EpeReport>, Vec<Unscored>) {
    let (counts, unscored) = tally(quantity, items);
    let mut mean = Mean::<2>::default();
    for e in items.iter().filter_map(|(_, o)| o.scored()) {
        if let Some((a, b)) = e.mean_median {
            mean.add([a, b]);
        }
    }
    if counts.images + counts.skipped + counts.no_truth == 0 {
        return (None, unscored);
    }
    let m = mean.get();
    let report = EpeReport {
        epe_mean: m.map(|m| m[0]),
        epe_median: m.map(|m| m[1]),
        counts,
    };
    (Some(report), unscored)
}

/// The surface of one sample: scored against its true mesh, or why not.
fn score_surface(
    dataset: &Dataset,
    samples: &Path,
    sample: &crate::dataset::Sample,
    options: &EvalOptions,
) -> Result<Outcome<surface::SurfaceScore>> {
    let Some(first) = sample.views.first() else {
        return Ok(Outcome::Missing);
    };
    let Some(path) = predictions::find_surface(samples, first.folder(), sample.index)? else {
        return Ok(Outcome::Missing);
    };
    let Some(truth_file) = sample.file("mesh.ply") else {
        return Ok(Outcome::NoTruth(format!(
            "the dataset has no {:06}.mesh.ply to score {} against (add \"mesh\" to the recipe's outputs)",
            sample.index,
            path.file_name().unwrap_or_default().to_string_lossy()
        )));
    };
    // Checked as every file of an untrusted dataset is (no link, regular, its recorded
    // size and hash) before the importer reads it.
    dataset.verify_file(truth_file)?;
    let truth = import_mesh(&dataset.path(truth_file), Default::default())
        .map_err(anyhow::Error::msg)?
        .mesh;
    let predicted = import_surface(&path).map_err(anyhow::Error::msg)?;
    let score = surface::score(
        &predicted,
        &truth,
        options.surface_samples,
        options.fscore_threshold,
    )
    .with_context(|| format!("{}", path.display()))?;
    Ok(Outcome::Scored(score))
}

/// Surface metrics, means over the samples scored; None when none was.
fn surface_report(
    surfaces: &[Outcome<surface::SurfaceScore>],
    counts: &Counts,
) -> Option<SurfaceReport> {
    let mut mean = Mean::<7>::default();
    for s in surfaces.iter().filter_map(Outcome::scored) {
        mean.add(SurfaceMetrics::values(s));
    }
    mean.get().map(|m| SurfaceReport {
        metrics: SurfaceMetrics::from_values(m),
        samples: mean.count(),
        missing: counts.missing,
        no_truth: counts.no_truth,
    })
}

impl Report {
    /// Writes the report as pretty JSON to `path`, atomically; never onto a dataset or an
    /// export.
    pub fn write_json(&self, path: &Path) -> Result<()> {
        refuse_data_target(path, "--json", None, false)?;
        let mut bytes = serde_json::to_vec_pretty(self)?;
        bytes.push(b'\n');
        write_atomic(path, &bytes)
    }

    /// The report for a person: one block per kind of prediction found.
    pub fn text(&self) -> String {
        let mut out = String::new();
        let c = &self.depth_counts;
        let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
        if c.images + c.skipped > 0 {
            out += &format!(
                "depth: {} images, {} pixels (align {}, mask {}, mean over images)\n",
                c.images, c.pixels, self.settings.align, self.settings.mask
            );
            out += "  AbsRel   SqRel    RMSE     RMSE log δ<1.25   δ<1.25²  δ<1.25³\n";
            out += &format!(
                "  {:<8} {:<8} {:<8} {:<8} {:<8} {:<8} {}\n",
                f(self.depth.abs_rel),
                f(self.depth.sq_rel),
                f(self.depth.rmse),
                f(self.depth.rmse_log),
                f(self.depth.delta1),
                f(self.depth.delta2),
                f(self.depth.delta3)
            );
        }
        if let Some(s) = &self.surface {
            out += &format!(
                "surface: {} samples, {} points per sampled surface, τ = {} m\n  Chamfer-L1 {:.6} m (accuracy {:.6}, completeness {:.6}), Chamfer-L2 {:.3e} m², F-score {:.4} (precision {:.4}, recall {:.4})\n",
                s.samples,
                self.settings.surface_samples,
                self.settings.fscore_threshold,
                s.metrics.chamfer_l1,
                s.metrics.accuracy,
                s.metrics.completeness,
                s.metrics.chamfer_l2,
                s.metrics.fscore,
                s.metrics.precision,
                s.metrics.recall
            );
        }
        for (name, unit, report) in [
            ("flow", "px", &self.flow),
            ("displacement", "m", &self.displacement),
        ] {
            if let Some(r) = report {
                out += &format!(
                    "{name}: {} images, {} pixels\n  EPE mean {} {unit}, median {} {unit}\n",
                    r.counts.images,
                    r.counts.pixels,
                    f(r.epe_mean),
                    f(r.epe_median)
                );
            }
        }
        if let Some(h) = &self.histories {
            out += &h.text();
        }
        if let Some(t) = &self.tracks {
            out += &t.text();
        }
        out
    }

    /// What a person should know about what was not scored: each group of views (samples)
    /// not scored with its reason and first names, pixels left out, misnamed files.
    pub fn warnings(&self) -> Vec<String> {
        let mut out: Vec<String> = self.unscored.iter().map(Unscored::describe).collect();
        let mut excluded = |what: &str, c: &Counts, left_out: &str| {
            if c.excluded_pixels > 0 {
                out.push(format!(
                    "{what}: {} pixels left out ({left_out})",
                    c.excluded_pixels
                ));
            }
        };
        excluded(
            "depth",
            &self.depth_counts,
            "not predicted: NaN or ±inf, or 0 in a millimetre PNG; or not positive after alignment",
        );
        let vectors = "not predicted: NaN or ±inf";
        if let Some(r) = &self.flow {
            excluded("flow", &r.counts, vectors);
        }
        if let Some(r) = &self.displacement {
            excluded("displacement", &r.counts, vectors);
        }
        out.extend(self.misnamed_files.describe());
        out
    }

    /// One line saying whether everything asked for was scored, and what was chosen.
    pub fn summary(&self) -> String {
        let s = &self.selection;
        let chosen = if s.conditions.is_empty() {
            format!("all {} views", s.views)
        } else {
            format!(
                "{} of {} views, {} of {} samples (--where {})",
                s.views,
                s.dataset_views,
                s.samples,
                s.dataset_samples,
                s.conditions.join(" --where ")
            )
        };
        if self.complete {
            format!("complete: every prediction asked for was scored; {chosen}")
        } else {
            let not: usize = self.unscored.iter().map(|u| u.count).sum();
            format!(
                "partial: {not} views or samples not scored (listed above; exit code {EXIT_PARTIAL}); {chosen}"
            )
        }
    }
}
