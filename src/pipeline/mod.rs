//! Running a recipe into a dataset folder: validation, sharding, threads, resume, progress,
//! and the typed records written beside every view.
//!
//! Owns: the order of work and its bookkeeping — recipe → scene → `build` → `render` →
//! `output` writers — and the records (`run.json`, each view's JSON). Must not touch: how
//! scenes are described, meshed, traced or encoded (it calls those modules). The result never
//! depends on the thread count, the shard split or interruptions: every sample is a pure
//! function of (recipe, seed, sample index) and is committed atomically.

mod finite;
mod progress;
mod record;
mod sample;
mod view;

pub use record::{RunRecord, ViewRecord, json_bytes, run_json, run_schema, view_schema};
pub use sample::{prepare, write_sample};
pub use view::{RenderedView, SampleRenderer, view_camera};

use crate::output::DatasetFolder;
use crate::recipe::Recipe;
use anyhow::{Context, Result, bail};
use progress::Progress;
use rayon::prelude::*;
use std::path::PathBuf;
use std::str::FromStr;
use std::time::Instant;

/// This process renders the samples whose index ≡ `index` (mod `count`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard's index K, 0 ≤ K < N.
    pub index: u64,
    /// Number of shards N.
    pub count: u64,
}

impl Shard {
    /// The whole dataset in one shard.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Whether this shard renders sample `sample`.
    pub fn owns(&self, sample: u64) -> bool {
        sample % self.count == self.index
    }
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("--shard {s}: expected K/N with 0 ≤ K < N, e.g. 0/4");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            k.trim().parse::<u64>().map_err(|_| bad())?,
            n.trim().parse::<u64>().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// How to run a recipe: where to, on how many threads, which shard.
pub struct RunOptions {
    /// The dataset folder.
    pub out: PathBuf,
    /// Worker threads; None uses every core.
    pub threads: Option<usize>,
    /// The samples this process renders.
    pub shard: Shard,
    /// Clear a folder holding another dataset (only what shmgen wrote there) instead of
    /// refusing it.
    pub force: bool,
    /// No progress bar.
    pub quiet: bool,
}

/// What a run did.
#[derive(Debug, Default)]
pub struct RunSummary {
    /// Samples rendered by this run.
    pub rendered: u64,
    /// Samples of this shard already in the folder, skipped.
    pub skipped: u64,
    /// Views rendered (image/depth pairs).
    pub pairs: u64,
    /// Bytes of sample files written by this run.
    pub bytes: u64,
    /// Wall-clock time, seconds.
    pub seconds: f64,
    /// Whether every sample of the dataset, from every shard, is now in the folder.
    pub complete: bool,
}

/// Renders this shard's unfinished samples of `recipe` into `options.out`.
pub fn run(recipe: &Recipe, options: &RunOptions) -> Result<RunSummary> {
    let start = Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.threads.unwrap_or(0))
        .build()?;
    pool.install(|| run_in_pool(recipe, options, start))
}

fn run_in_pool(recipe: &Recipe, options: &RunOptions, start: Instant) -> Result<RunSummary> {
    let total = recipe.dataset.samples;
    let mine: Vec<u64> = (0..total).filter(|&s| options.shard.owns(s)).collect();
    validate(recipe, &mine)?;

    let folder = DatasetFolder::open(&options.out, &run_json(recipe)?, options.force)?;
    let done = folder.completed()?;
    let todo: Vec<u64> = mine.iter().copied().filter(|s| !done.contains(s)).collect();
    let progress = Progress::new(todo.len() as u64, options.quiet);
    let bytes: u64 = todo
        .par_iter()
        .map(|&index| -> Result<u64> {
            let sample = prepare(recipe, index)?;
            let mut stage = folder.stage(index)?;
            let views = write_sample(recipe, &sample, &mut stage)?;
            let bytes = stage.bytes;
            folder
                .commit(stage, views)
                .with_context(|| format!("committing sample {index}"))?;
            progress.sample_done();
            Ok(bytes)
        })
        .try_reduce(|| 0, |a, b| Ok(a + b))?;
    progress.finish();
    let complete = folder.finalize(total)?;
    let rendered = todo.len() as u64;
    Ok(RunSummary {
        rendered,
        skipped: mine.len() as u64 - rendered,
        pairs: rendered * u64::from(recipe.dataset.views),
        bytes,
        seconds: start.elapsed().as_secs_f64(),
        complete,
    })
}

/// Draws and meshes every sample of the shard before anything is written, so a recipe that
/// fails for some sample fails before it leaves partial files. Reports the lowest failing
/// sample, whatever the thread scheduling.
fn validate(recipe: &Recipe, samples: &[u64]) -> Result<()> {
    let results: Vec<Result<()>> = samples
        .par_iter()
        .map(|&s| prepare(recipe, s).map(drop))
        .collect();
    if let Some(Err(e)) = results.into_iter().find(Result::is_err) {
        return Err(e);
    }
    if samples.is_empty() {
        bail!(
            "this shard has no samples (the dataset has {} samples)",
            recipe.dataset.samples
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_parsing_and_ownership() {
        assert_eq!("1/3".parse::<Shard>(), Ok(Shard { index: 1, count: 3 }));
        for bad in ["3/3", "1", "a/2", "0/0", "-1/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        let shards: Vec<Shard> = (0..3).map(|k| Shard { index: k, count: 3 }).collect();
        for s in 0..30 {
            assert_eq!(shards.iter().filter(|sh| sh.owns(s)).count(), 1);
        }
    }
}
