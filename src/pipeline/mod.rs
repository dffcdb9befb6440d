//! Running a recipe into a dataset folder: validation, sharding, threads, resume, progress,
//! and the typed records written beside every view.
//!
//! Owns: the order of work and its bookkeeping — recipe → scene → `build` → `render` →
//! `output` writers — and the records (`run.json`, each view's JSON). Must not touch: how
//! scenes are described, meshed, traced or encoded (it calls those modules). The result never
//! depends on the thread count, the shard split or interruptions: every sample is a pure
//! function of (recipe, seed, sample index) and is committed atomically.
//!
//! The unit of work is a sample, or with `--frames-per-unit F` a range of F frames of a
//! sequence sample (unit u = sample × units per sample + range): units are dealt to shards
//! (u ≡ K mod N), rendered, committed and resumed alone, and each frame's files have the same
//! bytes whichever unit wrote them.

mod augmented;
mod damage;
mod finite;
mod geometry;
mod heap;
mod progress;
mod record;
mod sample;
mod sensors;
mod sequence;
mod view;

/// `shmgen status`: how far the shards of a run have got (read from the folder `output` owns).
pub use crate::output::{EXIT_COMPLETE, EXIT_INCOMPLETE, EXIT_RUNNING, Status, status};
/// The damage classes by value, for readers of the damage layers.
pub use crate::render::DamageClass;
pub use geometry::SampleGeometry;
pub use record::{FrameRecord, ViewFacts};
pub use record::{RunRecord, ViewRecord, json_bytes, run_json, run_schema, view_schema};
pub use sample::{for_each_image, prepare, write_sample, write_sample_frames};
pub use sequence::{MountOffset, SampleMotion, mount_offset};
pub use view::{RenderedView, SampleRenderer, view_camera};

use crate::output::refuse_data_target;
use crate::output::{DatasetFolder, FrameUnits};
use crate::recipe::Recipe;
use crate::render::SharedTraceMeshes;
use anyhow::{Context, Result, bail};
use progress::Progress;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// This process renders the units of work (samples, or frame ranges of sequence samples)
/// whose index ≡ `index` (mod `count`).
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

    /// Whether this shard renders unit `sample` (a sample, unless frames are dealt out).
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
    /// The units this process renders.
    pub shard: Shard,
    /// Deal a sequence's frames out in units of this many frames (None: whole samples).
    pub frames_per_unit: Option<u32>,
    /// Clear a folder holding another dataset (only what shmgen wrote there) instead of
    /// refusing it.
    pub force: bool,
    /// No progress bar.
    pub quiet: bool,
}

/// What a run did.
#[derive(Debug, Default)]
pub struct RunSummary {
    /// Units (samples, or frame ranges with `frames_per_unit`) rendered by this run.
    pub rendered: u64,
    /// Units of this shard already in the folder, skipped.
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

/// Samples of the shard (the first ones it has to render) drawn and meshed before anything is
/// written: a recipe that fails for one of them leaves no files. Later samples are drawn,
/// meshed and rendered in order as the run goes.
pub const VALIDATED_FIRST: u64 = 1000;

impl Shard {
    /// Number of samples of a dataset of `total` samples this shard renders.
    pub fn len(&self, total: u64) -> u64 {
        total.saturating_sub(self.index).div_ceil(self.count)
    }

    /// Whether this shard renders no sample of a dataset of `total` samples.
    pub fn is_empty(&self, total: u64) -> bool {
        self.len(total) == 0
    }

    /// The units of a dataset of `total` units this shard renders, in order.
    fn samples(&self, total: u64) -> impl Iterator<Item = u64> + Send + use<> {
        let (index, count) = (self.index, self.count);
        (0..self.len(total)).map(move |i| index + i * count)
    }
}

/// Renders this shard's unfinished samples of `recipe` into `options.out`.
pub fn run(recipe: &Recipe, options: &RunOptions) -> Result<RunSummary> {
    let start = Instant::now();
    heap::keep_view_buffers();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.threads.unwrap_or(0))
        .build()?;
    pool.install(|| run_in_pool(recipe, options, start))
}

/// The units of work of a run: whole samples, or each sequence sample's frames in ranges.
#[derive(Clone, Copy)]
struct Units {
    samples: u64,
    frames: Option<FrameUnits>,
}

impl Units {
    /// The units of `recipe` with `frames_per_unit` frames each (None: whole samples); refused
    /// for a dataset without a sequence, or 0 frames.
    fn of(recipe: &Recipe, frames_per_unit: Option<u32>) -> Result<Units> {
        let samples = recipe.dataset.samples;
        let Some(per_unit) = frames_per_unit else {
            return Ok(Units {
                samples,
                frames: None,
            });
        };
        let Some(sequence) = &recipe.dataset.sequence else {
            bail!(
                "--frames-per-unit {per_unit}: the recipe films no sequence (no dataset.sequence); its units are whole samples, so leave the option out"
            );
        };
        if per_unit == 0 {
            bail!("--frames-per-unit 0: a unit holds at least one frame");
        }
        Ok(Units {
            samples,
            frames: Some(FrameUnits {
                frames: sequence.frames(),
                per_unit,
            }),
        })
    }

    /// Units of one sample.
    fn per_sample(&self) -> u64 {
        self.frames.map_or(1, |f| f.per_sample())
    }

    /// Units of the dataset.
    fn total(&self) -> u64 {
        self.samples.saturating_mul(self.per_sample())
    }

    /// The sample of unit `unit`.
    fn sample(&self, unit: u64) -> u64 {
        unit / self.per_sample()
    }

    /// The sample of unit `unit` and its frames (None: all of them).
    fn work(&self, unit: u64) -> (u64, Option<std::ops::Range<u32>>) {
        let per_sample = self.per_sample();
        let frames = self.frames.map(|f| f.range(unit % per_sample));
        (unit / per_sample, frames)
    }

    /// What a unit is called in messages.
    fn name(&self, unit: u64) -> String {
        match self.work(unit) {
            (sample, Some(frames)) => format!(
                "unit {unit} (frames {}–{} of sample {sample})",
                frames.start,
                frames.end.saturating_sub(1)
            ),
            (sample, None) => format!("sample {sample}"),
        }
    }
}

fn run_in_pool(recipe: &Recipe, options: &RunOptions, start: Instant) -> Result<RunSummary> {
    let units = Units::of(recipe, options.frames_per_unit)?;
    let (samples, total) = (units.samples, units.total());
    let shard = options.shard;
    let mine = shard.len(total);
    if mine == 0 {
        match units.frames {
            None => bail!("this shard has no samples (the dataset has {total} samples)"),
            Some(_) => bail!(
                "this shard has no units (the dataset has {total} units of --frames-per-unit frames)"
            ),
        }
    }
    let identity = |recorded: Option<&serde_json::Value>| run_json(recipe, recorded);
    let shard_id = (shard.index, shard.count);
    let extent = (samples, units.frames);

    // Before writing anything: the folder must be usable, and the samples of the first units
    // to render must build.
    refuse_data_target(&options.out, "--out", None, true)?;
    let done = DatasetFolder::check(&options.out, &identity, options.force, shard_id, extent)?;
    let first = shard.samples(total).filter(|u| !done.contains(*u));
    let ahead = mine.saturating_sub(done.len()).min(VALIDATED_FIRST);
    let mut last = None;
    let first_samples = (first.take(ahead as usize))
        .map(|unit| units.sample(unit))
        .filter(move |&sample| last.replace(sample) != Some(sample))
        .collect::<Vec<_>>();
    let count = first_samples.len() as u64;
    let progress = Progress::new("validating", "samples", count, options.quiet);
    in_order(first_samples.into_iter(), |index| {
        prepare(recipe, index)?;
        progress.sample_done();
        Ok(0)
    })
    .map_err(|(_, e)| e)?;
    progress.finish();

    let folder = DatasetFolder::open(&options.out, &identity, options.force, shard_id)?;
    let done = folder.completed(shard_id, extent)?;
    let todo = mine - done.len();
    let noun = units.frames.map_or("samples", |_| "units of frames");
    let progress = Progress::new("rendering", noun, todo, options.quiet);
    let (rendered, pairs) = (AtomicU64::new(0), AtomicU64::new(0));
    let shared = SharedTraceMeshes::default();
    let bytes = in_order(shard.samples(total).filter(|u| !done.contains(*u)), |unit| {
        let (index, frames) = units.work(unit);
        let sample = prepare(recipe, index)?;
        let mut stage = match (&frames, units.frames) {
            (Some(range), Some(all)) => folder.stage_frames(index, range.clone(), all)?,
            _ => folder.stage(index)?,
        };
        let views = write_sample_frames(recipe, &sample, &shared, &mut stage, frames.clone())?;
        let bytes = stage.bytes;
        folder
            .commit(stage, views)
            .with_context(|| format!("committing {}", units.name(unit)))?;
        rendered.fetch_add(1, Ordering::Relaxed);
        pairs.fetch_add(images_of(recipe, frames), Ordering::Relaxed);
        progress.sample_done();
        Ok(bytes)
    })
    .map_err(|(unit, e)| {
        e.context(format!(
            "the run stopped at {}: all the work of this shard before it is complete and listed in {}",
            units.name(unit),
            options.out.join("manifest.jsonl").display()
        ))
    })?;
    progress.finish();
    let complete = folder.finish(samples)?;
    let rendered = rendered.into_inner();
    Ok(RunSummary {
        rendered,
        skipped: done.len(),
        pairs: pairs.into_inner(),
        bytes,
        seconds: start.elapsed().as_secs_f64(),
        complete,
    })
}

/// Images (image/depth pairs) of the frames `frames` of a sample (all of them: None).
fn images_of(recipe: &Recipe, frames: Option<std::ops::Range<u32>>) -> u64 {
    let dataset = &recipe.dataset;
    match frames {
        Some(range) => {
            let per_frame =
                u64::from(dataset.cameras_per_sample()) * u64::from(dataset.augment.per_view());
            per_frame * u64::from(range.end - range.start)
        }
        None => u64::from(dataset.images_per_sample()),
    }
}

/// Runs `work` on `samples` in their order on every thread of the current pool, each thread
/// taking the next sample when it is free, with memory independent of the number of samples.
/// After a failure no further sample is started. Returns the sum of the results, or the
/// lowest failing sample with its error: every sample before it was started before it and
/// succeeded, whatever the thread count (samples after it already under way may finish too).
fn in_order(
    samples: impl Iterator<Item = u64> + Send,
    work: impl Fn(u64) -> Result<u64> + Sync,
) -> Result<u64, (u64, anyhow::Error)> {
    let next = Mutex::new(samples);
    let stop = AtomicBool::new(false);
    let failed: Mutex<Option<(u64, anyhow::Error)>> = Mutex::new(None);
    let sum = AtomicU64::new(0);
    rayon::broadcast(|_| {
        loop {
            let index = {
                let mut next = next.lock().unwrap();
                if stop.load(Ordering::SeqCst) {
                    break;
                }
                match next.next() {
                    Some(index) => index,
                    None => break,
                }
            };
            match work(index) {
                Ok(value) => {
                    sum.fetch_add(value, Ordering::Relaxed);
                }
                Err(e) => {
                    stop.store(true, Ordering::SeqCst);
                    let mut failed = failed.lock().unwrap();
                    if failed.as_ref().is_none_or(|(lowest, _)| index < *lowest) {
                        *failed = Some((index, e));
                    }
                }
            }
        }
    });
    match failed.into_inner().unwrap() {
        Some(failure) => Err(failure),
        None => Ok(sum.into_inner()),
    }
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
        for total in [0, 1, 2, 3, 4, 29, 30, 31] {
            for sh in &shards {
                let listed: Vec<u64> = sh.samples(total).collect();
                let owned: Vec<u64> = (0..total).filter(|&s| sh.owns(s)).collect();
                assert_eq!(listed, owned);
                assert_eq!(sh.len(total), owned.len() as u64);
            }
        }
        let huge = Shard { index: 3, count: 7 };
        assert_eq!(huge.len(1 << 40), ((1u64 << 40) - 3).div_ceil(7));
    }

    #[test]
    fn in_order_reports_the_lowest_failure_after_every_earlier_sample() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        let worked = Mutex::new(Vec::new());
        let result = pool.install(|| {
            in_order(0..u64::MAX, |s| {
                worked.lock().unwrap().push(s);
                match s {
                    57 | 90 => Err(anyhow::anyhow!("bad {s}")),
                    _ => Ok(1),
                }
            })
        });
        let (index, e) = result.unwrap_err();
        assert_eq!((index, e.to_string()), (57, "bad 57".to_string()));
        let worked = worked.into_inner().unwrap();
        assert!((0..57).all(|s| worked.contains(&s)));
        assert_eq!(pool.install(|| in_order(0..100, |_| Ok(2))).unwrap(), 200);
    }
}
