//! `shmgen eval`: metrics of predictions against a finished dataset — depth (Eigen et al.
//! 2014, with optional per-image alignment), surfaces (Chamfer distance, F-score), flow and
//! displacement (end-point error). Every formula, with its source, is in `docs/metrics.md`.
//!
//! Owns: finding and reading predictions (and reporting the misnamed ones), the metrics and
//! the report. Must not touch: the dataset or the predictions (it only reads), rendering,
//! recipes. Aggregation: every metric is computed per image (per sample for surfaces), then
//! averaged over images with equal weight, as Marigold and Depth Anything evaluate; images are
//! scored in parallel and summed in dataset order, so the report has the same bytes on any
//! number of threads.

mod depth;
mod epe;
mod misnamed;
mod nearest;
mod npy;
mod predictions;
mod stats;
mod surface;

pub use depth::Align;
pub use misnamed::{Misnamed, Suggestion};

use crate::dataset::{Dataset, View};
use crate::geometry::import::{import_mesh, import_surface};
use crate::output::refuse_data_target;
use crate::output::write_atomic;
use anyhow::{Context, Result, bail};
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
}

/// The report, as `--json` writes it.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    schema: &'static str,
    dataset: Value,
    settings: Settings,
    /// Depth: mean over images of each image's AbsRel.
    pub abs_rel: Option<f64>,
    /// SqRel.
    pub sq_rel: Option<f64>,
    /// RMSE, metres.
    pub rmse: Option<f64>,
    /// RMSE of ln depth.
    pub rmse_log: Option<f64>,
    /// δ < 1.25.
    pub delta1: Option<f64>,
    /// δ < 1.25².
    pub delta2: Option<f64>,
    /// δ < 1.25³.
    pub delta3: Option<f64>,
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
    /// Files under PREDICTIONS that look like predictions but that no view or sample reads.
    pub misnamed_files: Misnamed,
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
    /// 2PR / (P + R) per sample, averaged.
    pub fscore: f64,
    /// Samples scored and missing.
    pub samples: usize,
    /// Samples of the dataset with no predicted surface.
    pub missing: usize,
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

/// What one view's predictions gave (None: no prediction of that quantity).
#[derive(Default)]
struct ViewScores {
    depth: Option<depth::ImageDepth>,
    flow: Option<epe::ImageEpe>,
    displacement: Option<epe::ImageEpe>,
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
    let views: Vec<&View> = dataset.views().collect();
    let scores = views
        .par_iter()
        .map(|view| score_view(&dataset, &samples, view, options))
        .collect::<Result<Vec<_>>>()?;
    let surfaces = surfaces(&dataset, &samples, options)?;
    let misnamed_files = misnamed::misnamed(predictions, &samples, &dataset)?;

    let mut depth_mean = Mean::<9>::default();
    let mut counts = Counts::default();
    for s in &scores {
        match &s.depth {
            None => counts.missing += 1,
            Some(d) => {
                counts.pixels += d.pixels;
                counts.excluded_pixels += d.excluded;
                match d.metrics {
                    Some(m) => {
                        depth_mean.add([m[0], m[1], m[2], m[3], m[4], m[5], m[6], d.scale, d.shift])
                    }
                    None => counts.skipped += 1,
                }
            }
        }
    }
    counts.images = depth_mean.count();
    if counts.images + counts.skipped == 0 {
        counts.missing = 0;
    }
    let flow = epe_report(scores.iter().map(|s| s.flow));
    let displacement = epe_report(scores.iter().map(|s| s.displacement));
    if counts.images + counts.skipped == 0
        && surfaces.is_none()
        && flow.is_none()
        && displacement.is_none()
    {
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
    let m = depth_mean.get();
    let pick = |i: usize| m.map(|m| m[i]);
    Ok(Report {
        schema: "shmgen.eval/1",
        dataset: dataset.identity(),
        settings: Settings {
            align: options.align.name(),
            mask: options.mask.name(),
            aggregate: "per image (per sample for surfaces), then the mean over images",
            fscore_threshold: options.fscore_threshold,
            surface_samples: options.surface_samples,
            excluded: "pixels not predicted (NaN or ±inf; 0 in a millimetre PNG), or (depth) not positive after alignment, are left out of the fit and the metrics, and counted",
        },
        abs_rel: pick(0),
        sq_rel: pick(1),
        rmse: pick(2),
        rmse_log: pick(3),
        delta1: pick(4),
        delta2: pick(5),
        delta3: pick(6),
        align_scale: pick(7).filter(|_| options.align != Align::None),
        align_shift: pick(8).filter(|_| options.align == Align::LstsqShift),
        depth_counts: counts,
        surface: surfaces,
        flow,
        displacement,
        misnamed_files,
    })
}

fn score_view(
    dataset: &Dataset,
    samples: &Path,
    view: &View,
    options: &EvalOptions,
) -> Result<ViewScores> {
    let mut out = ViewScores::default();
    let depth_prediction = predictions::find(samples, view, Quantity::Depth)?;
    let flow_prediction = predictions::find(samples, view, Quantity::Flow)?;
    let displacement_prediction = predictions::find(samples, view, Quantity::Displacement)?;
    if depth_prediction.is_none() && flow_prediction.is_none() && displacement_prediction.is_none()
    {
        return Ok(out);
    }
    truth(view, "depth.exr", "depth")?;
    let depth_layer = dataset.layer(view, "depth.exr", &Quantity::Depth.channels().sets())?;
    let (w, h) = (depth_layer.width, depth_layer.height);
    let depth = &depth_layer.channels[0];
    if let Some(path) = depth_prediction {
        let predicted = predictions::read(&path, Quantity::Depth, w, h)?;
        let kind = match options.mask {
            Mask::Structure => "mask.png",
            Mask::Valid => "valid.png",
        };
        let inside = match view.file(kind) {
            Some(_) => positive(dataset, view, kind)?,
            None => vec![true; w * h],
        };
        out.depth = Some(depth::score(depth, &predicted[0], &inside, options.align));
    }
    if let Some(path) = flow_prediction {
        truth(view, "flow.exr", "flow")?;
        let truth_flow = dataset.layer(view, "flow.exr", &Quantity::Flow.channels().sets())?;
        truth(view, "flow_valid.png", "flow")?;
        let valid = positive(dataset, view, "flow_valid.png")?;
        let predicted = predictions::read(&path, Quantity::Flow, w, h)?;
        out.flow = Some(epe::score(&truth_flow.channels, &predicted, &valid));
    }
    if let Some(path) = displacement_prediction {
        truth(view, "displacement.exr", "displacement")?;
        let truth_displacement = dataset.layer(
            view,
            "displacement.exr",
            &Quantity::Displacement.channels().sets(),
        )?;
        // Displacement is that of the surface point the pixel sees: defined where it sees one.
        let valid: Vec<bool> = depth.iter().map(|&d| d > 0.0).collect();
        let predicted = predictions::read(&path, Quantity::Displacement, w, h)?;
        out.displacement = Some(epe::score(&truth_displacement.channels, &predicted, &valid));
    }
    Ok(out)
}

/// The dataset's file of `kind` for `view`, or an error naming the output it lacks.
fn truth<'a>(view: &'a View, kind: &str, output: &str) -> Result<&'a str> {
    view.file(kind).with_context(|| {
        format!(
            "view {} has a prediction but the dataset has no {kind} for it (the \"{output}\" output)",
            view.stem
        )
    })
}

/// Where the view's grey image of `kind` is above 0.
fn positive(dataset: &Dataset, view: &View, kind: &str) -> Result<Vec<bool>> {
    let image = dataset.grey(view, kind)?;
    Ok(image.values.iter().map(|&v| v > 0).collect())
}

fn epe_report(images: impl Iterator<Item = Option<epe::ImageEpe>>) -> Option<EpeReport> {
    let mut mean = Mean::<2>::default();
    let mut counts = Counts::default();
    for image in images {
        match image {
            None => counts.missing += 1,
            Some(e) => {
                counts.pixels += e.pixels;
                counts.excluded_pixels += e.excluded;
                match e.mean_median {
                    Some((a, b)) => mean.add([a, b]),
                    None => counts.skipped += 1,
                }
            }
        }
    }
    counts.images = mean.count();
    if counts.images + counts.skipped == 0 {
        return None;
    }
    let m = mean.get();
    Some(EpeReport {
        epe_mean: m.map(|m| m[0]),
        epe_median: m.map(|m| m[1]),
        counts,
    })
}

/// Surface metrics over the samples that have a predicted surface; None when none has.
fn surfaces(
    dataset: &Dataset,
    samples: &Path,
    options: &EvalOptions,
) -> Result<Option<SurfaceReport>> {
    let mut mean = Mean::<7>::default();
    let mut missing = 0;
    for sample in &dataset.samples {
        let Some(first) = sample.views.first() else {
            continue;
        };
        let Some(path) = predictions::find_surface(samples, first.folder(), sample.index)? else {
            missing += 1;
            continue;
        };
        let truth_file = sample.file("mesh.ply").with_context(|| {
            format!(
                "sample {} has a predicted surface but the dataset has no {:06}.mesh.ply",
                sample.index, sample.index
            )
        })?;
        // Checked as every file of an untrusted dataset is (no link, regular, its recorded
        // size and hash) before the importer reads it.
        dataset.verify_file(truth_file)?;
        let truth = import_mesh(&dataset.path(truth_file), Default::default())
            .map_err(anyhow::Error::msg)?
            .mesh;
        let predicted = import_surface(&path).map_err(anyhow::Error::msg)?;
        let s = surface::score(
            &predicted,
            &truth,
            options.surface_samples,
            options.fscore_threshold,
        )
        .with_context(|| format!("{}", path.display()))?;
        mean.add([
            s.chamfer_l1(),
            s.chamfer_l2(),
            s.accuracy,
            s.completeness,
            s.precision,
            s.recall,
            s.fscore(),
        ]);
    }
    Ok(mean.get().map(|m| SurfaceReport {
        chamfer_l1: m[0],
        chamfer_l2: m[1],
        accuracy: m[2],
        completeness: m[3],
        precision: m[4],
        recall: m[5],
        fscore: m[6],
        samples: mean.count(),
        missing,
    }))
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
                f(self.abs_rel),
                f(self.sq_rel),
                f(self.rmse),
                f(self.rmse_log),
                f(self.delta1),
                f(self.delta2),
                f(self.delta3)
            );
        }
        if let Some(s) = &self.surface {
            out += &format!(
                "surface: {} samples, {} points per sampled surface, τ = {} m\n  Chamfer-L1 {:.6} m (accuracy {:.6}, completeness {:.6}), Chamfer-L2 {:.3e} m², F-score {:.4} (precision {:.4}, recall {:.4})\n",
                s.samples,
                self.settings.surface_samples,
                self.settings.fscore_threshold,
                s.chamfer_l1,
                s.accuracy,
                s.completeness,
                s.chamfer_l2,
                s.fscore,
                s.precision,
                s.recall
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
        out
    }

    /// What a person should know about what was not scored.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        let mut counted = |what: &str, c: &Counts, left_out: &str| {
            if c.missing > 0 {
                out.push(format!("{what}: {} views have no prediction", c.missing));
            }
            if c.skipped > 0 {
                out.push(format!(
                    "{what}: {} images had nothing to score (no pixel left, or the alignment is undefined)",
                    c.skipped
                ));
            }
            if c.excluded_pixels > 0 {
                out.push(format!(
                    "{what}: {} pixels left out ({left_out})",
                    c.excluded_pixels
                ));
            }
        };
        counted(
            "depth",
            &self.depth_counts,
            "not predicted: NaN or ±inf, or 0 in a millimetre PNG; or not positive after alignment",
        );
        let vectors = "not predicted: NaN or ±inf";
        if let Some(r) = &self.flow {
            counted("flow", &r.counts, vectors);
        }
        if let Some(r) = &self.displacement {
            counted("displacement", &r.counts, vectors);
        }
        if let Some(s) = &self.surface
            && s.missing > 0
        {
            out.push(format!("surface: {} samples have no prediction", s.missing));
        }
        out.extend(self.misnamed_files.describe());
        out
    }
}
