//! Files under PREDICTIONS that look like predictions but that no view or sample of the
//! dataset reads (a wrong stem, a wrong folder, a kind or format eval does not know), each
//! reported with the nearest name eval would read, so that a misnamed prediction is not
//! ignored without a word.
//!
//! Owns: what counts as a would-be prediction. A file does when its name ends in one of
//! [`PREDICTION_EXTENSIONS`] and it is not hidden (`.name`); PREDICTIONS is walked without
//! following links. Not reported: the files eval reads, and copies of the dataset's own files
//! at their mirrored place (`0000/000000_00.rgb.png`: an input kept beside its prediction).

use super::predictions::{Quantity, candidates, mirrored, surface_candidates};
use crate::dataset::Dataset;
use crate::words::edit_distance;
use anyhow::{Context, Result};
use serde::Serialize;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// The formats eval reads, and those depth, flow and surfaces are often saved in that it does
/// not read (so that such a file is reported rather than passed over).
const PREDICTION_EXTENSIONS: &[&str] = &[
    "exr", "npy", "png", "ply", "obj", "npz", "pfm", "tif", "tiff", "flo",
];

/// How many misnamed files a message lists by name.
const LISTED: usize = 5;

/// The files that look like predictions but match no view or sample.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Misnamed {
    /// PREDICTIONS as given; the names below are relative to it.
    pub folder: String,
    /// How many files match nothing.
    pub count: usize,
    /// The first few, in path order, each with the nearest name eval reads.
    pub first: Vec<Suggestion>,
}

/// One misnamed file and the nearest name eval reads.
#[derive(Clone, Debug, Serialize)]
pub struct Suggestion {
    /// Relative to PREDICTIONS, `/`-separated.
    pub file: String,
    /// None for a dataset without views.
    pub nearest: Option<String>,
}

/// The misnamed files under `predictions`, whose views' predictions eval looks for under
/// `samples` (`predictions` or its `samples/`).
pub(super) fn misnamed(predictions: &Path, samples: &Path, dataset: &Dataset) -> Result<Misnamed> {
    let relative = |path: &Path| relative_name(predictions, path);
    let expected: Vec<String> = expected_files(samples, dataset)
        .iter()
        .map(|path| relative(path))
        .collect();
    let copies = dataset
        .samples
        .iter()
        .flat_map(|s| s.files.iter().chain(s.views.iter().flat_map(|v| &v.files)))
        .map(|file| relative(&mirrored(samples, file)));
    let known: HashSet<String> = expected.iter().cloned().chain(copies).collect();
    let mut unmatched: Vec<String> = Vec::new();
    walk(predictions, predictions, &mut unmatched)?;
    unmatched.retain(|file| looks_like_prediction(file) && !known.contains(file));
    unmatched.sort();
    Ok(Misnamed {
        folder: predictions.display().to_string(),
        count: unmatched.len(),
        first: unmatched
            .into_iter()
            .take(LISTED)
            .map(|file| Suggestion {
                nearest: nearest(&file, &expected).map(str::to_string),
                file,
            })
            .collect(),
    })
}

impl Misnamed {
    /// The message for a person; None when every would-be prediction was read.
    pub fn describe(&self) -> Option<String> {
        if self.count == 0 {
            return None;
        }
        let (files, look) = match self.count {
            1 => ("file", "looks"),
            _ => ("files", "look"),
        };
        let mut out = format!(
            "{} {files} under {} {look} like predictions but match no view or sample, and {} not read (with the nearest name eval reads; see docs/metrics.md):",
            self.count,
            self.folder,
            if self.count == 1 { "was" } else { "were" }
        );
        for s in &self.first {
            let nearest = s.nearest.as_deref().unwrap_or("(the dataset has no view)");
            out += &format!("\n  {} → {nearest}", s.file);
        }
        if self.count > self.first.len() {
            out += &format!("\n  … and {} more", self.count - self.first.len());
        }
        Some(out)
    }
}

/// Every file eval looks for: each view's candidates of each quantity, each sample's surface.
fn expected_files(samples: &Path, dataset: &Dataset) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for sample in &dataset.samples {
        for view in &sample.views {
            for quantity in Quantity::ALL {
                out.extend(candidates(samples, view, quantity));
            }
        }
        if let Some(first) = sample.views.first() {
            out.extend(surface_candidates(samples, first.folder(), sample.index));
        }
        out.extend(super::tracks::candidates(samples, sample));
    }
    out
}

/// `path` relative to `root`, `/`-separated.
fn relative_name(root: &Path, path: &Path) -> String {
    let relative = path.strip_prefix(root).unwrap_or(path);
    let parts: Vec<String> = relative
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    parts.join("/")
}

/// Adds the relative name of every file under `folder` that is not hidden, without following
/// links (a link to a folder is listed as a file and not entered, so no loop is walked).
fn walk(root: &Path, folder: &Path, out: &mut Vec<String>) -> Result<()> {
    let listing = || format!("{}: cannot list the folder", folder.display());
    for entry in std::fs::read_dir(folder).with_context(listing)? {
        let entry = entry.with_context(listing)?;
        if entry.file_name().to_string_lossy().starts_with('.') {
            continue;
        }
        let path = entry.path();
        if entry.file_type().with_context(listing)?.is_dir() {
            walk(root, &path, out)?;
        } else {
            out.push(relative_name(root, &path));
        }
    }
    Ok(())
}

fn looks_like_prediction(file: &str) -> bool {
    file.rsplit_once('.').is_some_and(|(_, extension)| {
        PREDICTION_EXTENSIONS.contains(&extension.to_ascii_lowercase().as_str())
    })
}

/// The expected name nearest to `file`: the closest file name first (a stem or kind mistyped),
/// then the closest folder (a file put in the wrong one).
fn nearest<'a>(file: &str, expected: &'a [String]) -> Option<&'a str> {
    let split = |path: &'a str| path.rsplit_once('/').unwrap_or(("", path));
    let (folder, name) = file.rsplit_once('/').unwrap_or(("", file));
    expected
        .iter()
        .min_by_key(|e| {
            let (f, n) = split(e);
            (edit_distance(name, n), edit_distance(folder, f))
        })
        .map(String::as_str)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_name_prefers_the_file_name_then_the_folder() {
        let expected = [
            "0000/000000_00.depth.exr",
            "0000/000000_01.depth.exr",
            "0001/001000_00.depth.exr",
            "0000/000000_00.depth.npy",
        ]
        .map(String::from);
        let near = |file| nearest(file, &expected);
        assert_eq!(
            near("000000_00.depth.exr"),
            Some("0000/000000_00.depth.exr")
        );
        assert_eq!(
            near("0001/000000_01.depth.exr"),
            Some("0000/000000_01.depth.exr"),
            "the same name in another folder beats a name one character off here"
        );
        assert_eq!(
            near("0000/000000_00.dpth.npy"),
            Some("0000/000000_00.depth.npy")
        );
        assert_eq!(nearest("x.exr", &[][..]), None);
        assert!(looks_like_prediction("0000/a.depth.TIFF") && !looks_like_prediction("README.md"));
    }
}
