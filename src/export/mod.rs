//! `shmgen export`: a finished dataset converted, without rendering anything again, into the
//! layouts other tools read: nerfstudio scenes, COLMAP text models, WebDataset tar shards,
//! 16-bit millimetre depth PNGs and optical flow as KITTI PNGs and Middlebury `.flo` files.
//!
//! Owns: the exported folder and its bytes (`export.json` says what it holds). Must not touch:
//! the source dataset (it is only read; images are hard-linked, which shares their bytes and
//! never changes them), rendering, recipes or how datasets are written. Output appears all at
//! once: everything goes into a hidden sibling folder renamed to `--out` at the end
//! (`staging`), so a killed export never leaves a half-written `--out`.
//!
//! `merge` writes a dataset rather than another layout: the finished samples of folders that
//! shards wrote on different nodes, gathered into one with the same bytes as a single run,
//! placed as the exports' files are (hard link or checked copy).

mod colmap;
mod depth_mm;
mod flow;
mod merge;
mod nerfstudio;
mod png16;
mod staging;
mod tracks;
mod webdataset;

pub use merge::{MergeSummary, merge};

use crate::dataset::{Dataset, Sample, View};
use anyhow::{Result, bail};
use serde_json::{Value, json};
use staging::{Placer, Staging};
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// A layout to export to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// One nerfstudio scene (`transforms.json`) per sample.
    Nerfstudio,
    /// One COLMAP text model (`sparse/0/*.txt`) per sample.
    Colmap,
    /// WebDataset tar shards, one key per view.
    Webdataset,
    /// Depth as 16-bit PNG in millimetres, mirroring `samples/`.
    Png16,
    /// Optical flow as KITTI 16-bit PNG and Middlebury `.flo`, mirroring `samples/`.
    Flow,
}

impl Format {
    /// The name on the command line and in `export.json`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Nerfstudio => "nerfstudio",
            Format::Colmap => "colmap",
            Format::Webdataset => "webdataset",
            Format::Png16 => "png16",
            Format::Flow => "flow",
        }
    }
}

impl FromStr for Format {
    type Err = String;
    fn from_str(s: &str) -> Result<Format, String> {
        [
            Format::Nerfstudio,
            Format::Colmap,
            Format::Webdataset,
            Format::Png16,
            Format::Flow,
        ]
        .into_iter()
        .find(|f| f.name() == s)
        .ok_or_else(|| {
            format!("unknown export format {s:?}: expected nerfstudio, colmap, webdataset, png16 or flow")
        })
    }
}

/// How to export.
#[derive(Clone, Debug)]
pub struct ExportOptions {
    /// The layout.
    pub format: Format,
    /// The folder to create; it must not exist.
    pub out: PathBuf,
    /// Views per WebDataset shard; None: near-equal shards, at least 16 (see `webdataset`).
    pub shard_size: Option<usize>,
    /// Copy images instead of hard-linking them.
    pub copy: bool,
    /// nerfstudio and COLMAP: include augmented copies of views as frames of their own (each
    /// has exact K and pose, but photometric operations make them inconsistent with the
    /// clean views, which multi-view methods assume).
    pub with_copies: bool,
}

/// What an export did.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    /// Views exported.
    pub views: usize,
    /// Files hard-linked to the dataset's.
    pub linked: usize,
    /// Files copied (a link was refused, e.g. across filesystems, or `copy` was asked for).
    pub copied: usize,
    /// Files written anew (converted depth, camera files, shards).
    pub written: usize,
    /// Depth pixels beyond 65.535 m, written as 65535 mm.
    pub saturated: u64,
    /// Depth pixels closer than 0.5 mm, written as 1 mm so they do not read as "no surface".
    pub raised: u64,
    /// Valid flow vectors beyond KITTI's ±512 px, written invalid in its PNGs.
    pub flow_out_of_range: u64,
}

/// What each format's writer works with: the dataset, the folder being written, the options,
/// and the counts of what was done.
struct Job<'a> {
    dataset: &'a Dataset,
    out: &'a Path,
    options: &'a ExportOptions,
    placer: Placer,
    summary: Summary,
}

/// Exports the finished dataset at `source` as `options` say.
pub fn export(source: &Path, options: &ExportOptions) -> Result<Summary> {
    let dataset = Dataset::open(source)?;
    if options.shard_size == Some(0) {
        bail!("--shard-size 0: a shard holds at least one view");
    }
    let staging = Staging::create(&options.out, dataset.root())?;
    let mut job = Job {
        dataset: &dataset,
        out: staging.path(),
        options,
        placer: Placer::new(options.copy),
        summary: Summary::default(),
    };
    let extra = match options.format {
        Format::Nerfstudio => nerfstudio::write(&mut job)?,
        Format::Colmap => colmap::write(&mut job)?,
        Format::Webdataset => webdataset::write(&mut job)?,
        Format::Png16 => png16::write(&mut job)?,
        Format::Flow => flow::write(&mut job)?,
    };
    let Job {
        mut placer,
        mut summary,
        ..
    } = job;
    let mut record = json!({
        "schema": "shmgen.export/1",
        "format": options.format.name(),
        "tool": { "name": "shmgen", "version": env!("CARGO_PKG_VERSION") },
        "dataset": dataset.identity(),
        "views": summary.views,
    });
    if let (Value::Object(record), Value::Object(extra)) = (&mut record, extra) {
        record.extend(extra);
    }
    let mut bytes = serde_json::to_vec_pretty(&record)?;
    bytes.push(b'\n');
    placer.write(&staging.path().join("export.json"), &bytes)?;
    summary.linked = placer.linked;
    summary.copied = placer.copied;
    summary.written = placer.written;
    staging.commit()?;
    Ok(summary)
}

/// The views of a sample that multi-view formats (nerfstudio, COLMAP) make frames of: the
/// clean views, and the augmented copies too with `with_copies`.
fn frames<'a>(
    dataset: &'a Dataset,
    options: &ExportOptions,
) -> Result<Vec<(&'a Sample, Vec<&'a View>)>> {
    let mut out = Vec::new();
    for sample in &dataset.samples {
        let views: Vec<&View> = sample
            .views
            .iter()
            .filter(|v| options.with_copies || v.copy.is_none())
            .collect();
        if views.is_empty() {
            bail!(
                "sample {} has no clean view (the recipe's augment has keep_clean: false); pass --with-copies to export its augmented copies",
                sample.index
            );
        }
        out.push((sample, views));
    }
    Ok(out)
}

/// The file of `kind` of `view`, or an error naming the output the dataset lacks.
fn needed<'a>(view: &'a View, kind: &str, why: &str) -> Result<&'a str> {
    match view.file(kind) {
        Some(f) => Ok(f),
        None => bail!(
            "view {} has no {kind} file; {why} needs the dataset's \"{}\" output",
            view.stem,
            kind.split('.').next().unwrap_or(kind)
        ),
    }
}

/// K's entries (fx, fy, cx, cy), refusing a skewed K that the formats cannot express.
fn intrinsics(k: &[[f64; 3]; 3], view: &View) -> Result<[f64; 4]> {
    if k[0][1] != 0.0 {
        bail!(
            "view {}: K has skew {}; nerfstudio and COLMAP camera models have none",
            view.stem,
            k[0][1]
        );
    }
    Ok([k[0][0], k[1][1], k[0][2], k[1][2]])
}
