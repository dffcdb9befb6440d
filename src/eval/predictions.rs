//! Finding and reading predictions. PREDICTIONS mirrors the dataset's `samples/` folder (it may
//! be that folder's parent or the folder itself), with the dataset's file stems:
//!
//! - depth: `{stem}.depth.exr` (channel `Y`, or a file's only channel), `{stem}.depth.npy`
//!   (float32 or float64, shape H×W or H×W×1), `{stem}.depth.png` or `{stem}.depth_mm.png`
//!   (16-bit grey, millimetres, 0 = no prediction: what `shmgen export --format png16` writes);
//! - flow: `{stem}.flow.exr` (channels `R`, `G` = u, v) or `{stem}.flow.npy` (H×W×2), pixels;
//! - displacement: `{stem}.displacement.exr` (`R`, `G`, `B` = x, y, z) or `.npy` (H×W×3),
//!   world metres;
//!
//! EXR predictions are read as the dataset's own files are (the names of `shmgen.view/1`
//! datasets, `Z`, `U V`, `X Y Z`, are accepted too), so a dataset's file is a valid prediction.
//! - surfaces: `{sample:06}.ply` (a mesh, or a point cloud when it has no faces) or
//!   `{sample:06}.obj` (a mesh).
//!
//! Two files for the same thing are an error (which one was meant is not ours to guess). The
//! names listed here are the only ones read; `misnamed` reports the files that miss them.
//!
//! "No prediction" for a pixel is NaN (or ±inf) in an EXR or a `.npy` file, and 0 in a
//! millimetre PNG, which has no NaN. `read` turns each format's mark into the one value
//! [`NO_PREDICTION`], so every metric, and every alignment's fit before it, leaves such a pixel
//! out the same way whatever the file (a 0 taken as a 0 m prediction dragged the median and
//! the fit with shift toward 0).

use super::npy;
use crate::dataset::files::{Bound, image_bound, open_regular, read_bounded};
use crate::dataset::{View, decode_exr, decode_grey_png};
use crate::output::{ExrChannels, FLOW_CHANNELS, SCALAR_CHANNELS, VECTOR_CHANNELS};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};

/// The folder holding predictions in the dataset's `NNNN/` sub-folders.
pub(super) fn samples_folder(predictions: &Path) -> Result<PathBuf> {
    if !predictions.is_dir() {
        bail!("{}: no such folder of predictions", predictions.display());
    }
    let inner = predictions.join("samples");
    Ok(if inner.is_dir() {
        inner
    } else {
        predictions.to_path_buf()
    })
}

/// What is predicted per view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Quantity {
    Depth,
    Flow,
    Displacement,
}

impl Quantity {
    /// Every quantity predicted per view.
    pub(super) const ALL: [Quantity; 3] = [Quantity::Depth, Quantity::Flow, Quantity::Displacement];

    /// The EXR channels, one per component (the .npy's last axis).
    pub(super) fn channels(self) -> ExrChannels {
        match self {
            Quantity::Depth => SCALAR_CHANNELS,
            Quantity::Flow => FLOW_CHANNELS,
            Quantity::Displacement => VECTOR_CHANNELS,
        }
    }

    /// The kinds of file that may hold it.
    fn kinds(self) -> &'static [&'static str] {
        match self {
            Quantity::Depth => &["depth.exr", "depth.npy", "depth.png", "depth_mm.png"],
            Quantity::Flow => &["flow.exr", "flow.npy"],
            Quantity::Displacement => &["displacement.exr", "displacement.npy"],
        }
    }
}

/// Every file that may predict `quantity` for `view`, in the order of its kinds.
pub(super) fn candidates(samples: &Path, view: &View, quantity: Quantity) -> Vec<PathBuf> {
    let folder = mirrored(samples, view.folder());
    quantity
        .kinds()
        .iter()
        .map(|kind| folder.join(format!("{}.{kind}", view.stem)))
        .collect()
}

/// The one file predicting `quantity` for `view`, if any.
pub(super) fn find(samples: &Path, view: &View, quantity: Quantity) -> Result<Option<PathBuf>> {
    one_of(candidates(samples, view, quantity))
}

/// Every file that may predict the surface of `sample`, whose files are in the dataset's
/// folder `folder` (`samples/NNNN`).
pub(super) fn surface_candidates(samples: &Path, folder: &str, sample: u64) -> [PathBuf; 2] {
    let folder = mirrored(samples, folder);
    ["ply", "obj"].map(|ext| folder.join(format!("{sample:06}.{ext}")))
}

/// The one prediction of the surface of `sample` (see [`surface_candidates`]).
pub(super) fn find_surface(samples: &Path, folder: &str, sample: u64) -> Result<Option<PathBuf>> {
    one_of(surface_candidates(samples, folder, sample))
}

/// The predictions' counterpart of the dataset's folder or file `samples/…`.
pub(super) fn mirrored(samples: &Path, relative: &str) -> PathBuf {
    samples.join(relative.strip_prefix("samples/").unwrap_or(relative))
}

/// The files eval reads for the dataset's first view and sample, for a message when it found
/// none: the first of each set in full, the others by their kind, e.g.
/// `P/0000/000000_00.depth.exr (or .depth.npy, …)`.
pub(super) fn example_names(samples: &Path, view: &View, sample: u64) -> String {
    let per_view = Quantity::ALL.map(|q| alternatives(&candidates(samples, view, q)));
    let surface = alternatives(&surface_candidates(samples, view.folder(), sample));
    format!(
        "{} for a view, {surface} for a sample's surface",
        per_view.join(", ")
    )
}

/// `first (or .kind, .kind)` of a set of files one of which predicts one thing.
fn alternatives(paths: &[PathBuf]) -> String {
    let kinds: Vec<String> = paths[1..]
        .iter()
        .filter_map(|p| p.file_name()?.to_str()?.split_once('.'))
        .map(|(_, kind)| format!(".{kind}"))
        .collect();
    format!("{} (or {})", paths[0].display(), kinds.join(", "))
}

fn one_of(candidates: impl IntoIterator<Item = PathBuf>) -> Result<Option<PathBuf>> {
    let found: Vec<PathBuf> = candidates.into_iter().filter(|p| p.is_file()).collect();
    match found.as_slice() {
        [] => Ok(None),
        [one] => Ok(Some(one.clone())),
        [a, b, ..] => bail!(
            "both {} and {} predict the same thing; keep one",
            a.display(),
            b.display()
        ),
    }
}

/// A pixel the file says it does not predict: not finite, so the metrics leave it out of the
/// fits and the scores and count it.
pub(super) const NO_PREDICTION: f64 = f64::NAN;

/// A millimetre PNG's sample in metres; 0 is the format's "no prediction".
fn millimetres_to_metres(mm: u16) -> f64 {
    if mm == 0 {
        NO_PREDICTION
    } else {
        f64::from(mm) / 1000.0
    }
}

/// The planes of a prediction file, each `width × height`, as f64, with [`NO_PREDICTION`]
/// wherever the file marks a pixel as not predicted. The file is read up to
/// the size such an image may have (float64 samples, twice over, plus headers) and its header
/// is checked against the view's size before anything is decoded.
pub(super) fn read(
    path: &Path,
    quantity: Quantity,
    width: usize,
    height: usize,
) -> Result<Vec<Vec<f64>>> {
    let channels = quantity.channels();
    let components = channels.names.len();
    let name = path.to_string_lossy();
    let size = (width as u32, height as u32);
    let bound = Bound {
        what: "a prediction of the view's size",
        bytes: image_bound(size.0, size.1, components as u64, 8),
    };
    let bytes = read_bounded(open_regular(path)?, &name, bound)?;
    let (w, h, planes) = if name.ends_with(".exr") {
        let layer = decode_exr(&bytes, &name, &channels.sets(), size)?;
        let planes = layer
            .channels
            .into_iter()
            .map(|c| c.into_iter().map(f64::from).collect())
            .collect();
        (layer.width, layer.height, planes)
    } else if name.ends_with(".npy") {
        let array = npy::parse(&bytes).with_context(|| format!("{}", path.display()))?;
        let c = components;
        let (h, w) = match (array.shape.as_slice(), c) {
            ([h, w], 1) => (*h, *w),
            ([h, w, k], _) if *k == c => (*h, *w),
            (shape, _) => bail!(
                "{}: shape {shape:?}; expected (H, W{}) for {quantity:?}",
                path.display(),
                if c == 1 {
                    String::new()
                } else {
                    format!(", {c}")
                }
            ),
        };
        let planes = (0..c)
            .map(|k| array.values.iter().skip(k).step_by(c).copied().collect())
            .collect();
        (w, h, planes)
    } else {
        let png = decode_grey_png(&bytes, &name, size)?;
        if png.bits != 16 {
            bail!(
                "{}: an 8-bit PNG cannot hold millimetres; write 16-bit grey",
                path.display()
            );
        }
        let metres = png
            .values
            .iter()
            .map(|&mm| millimetres_to_metres(mm))
            .collect();
        (png.width, png.height, vec![metres])
    };
    if (w, h) != (width, height) {
        bail!(
            "{}: {w}×{h} pixels, the view has {width}×{height}",
            path.display()
        );
    }
    Ok(planes)
}
