//! The dataset folder: run.json, manifest.jsonl, staging and commit of samples, the locks
//! that let shards share a folder, and the clean-up of what interrupted runs leave.
//!
//! Everything transient lives in `.partial/`: `folder.lock` (held while a run opens the
//! folder, replaces a dataset, or finishes, and by a merge throughout), `shard-K-of-N.lock`
//! (held by the process writing shard K/N, which records its pid there), `shard-K-of-N/`
//! (that shard's staging) and `merge/` (a merge's staging, see `merge`).
//! Temporary files of `run.json` and `manifest.jsonl` are written only under `folder.lock`,
//! so any found while holding it are stale and removed.
//!
//! A sample of a sequence may be written in units of a few frames (`FrameUnits`), each
//! committed with a unit line (`{"unit": {"sample", "frames": [start, end], "of"}, ...}`) that
//! readers of finished samples do not take for one. Once the unit lines of a sample cover all
//! its frames, the sample's own line — the one a whole-sample commit writes, byte for byte — is
//! appended ("sealed"), and the unit lines are dropped when the finished manifest is sorted.

use super::fault::{self, Fault};
use super::lock::{Lock, is_held, open_no_wait, recorded_holder};
use anyhow::{Context, Result, bail};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::fmt::Display;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufRead, BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

pub(super) const RUN_JSON: &str = "run.json";
pub(super) const MANIFEST: &str = "manifest.jsonl";
pub(super) const STAGING: &str = ".partial";
const SAMPLES: &str = "samples";
const FOLDER_LOCK: &str = "folder.lock";
/// Extension of the empty file `.partial/shard-K-of-N.done` a shard leaves when it ends
/// before the dataset is complete: the shard count in use, for `status` (removed with
/// `.partial/` once the dataset is complete, so finished folders do not depend on it).
const DONE: &str = "done";
/// Differences between two datasets listed in an error, at most.
const DIFFERENCES_SHOWN: usize = 6;

/// The `run.json` of the dataset being written, given the one already in the folder (if it
/// parses): fields that do not identify a dataset may be carried over from it.
pub type Identity<'a> = &'a dyn Fn(Option<&Value>) -> Result<Vec<u8>>;

/// A dataset's output folder, opened for one shard: `run.json`, `manifest.jsonl` and the
/// committed samples, with a staging area for the samples this process is writing.
pub struct DatasetFolder {
    pub(super) root: PathBuf,
    pub(super) shard: Option<ShardLease>,
}

/// The lock on a shard and its staging folder.
pub(super) struct ShardLease {
    lock: Lock,
    staging: PathBuf,
}

/// How each sequence sample's frames are dealt out as units of work: `per_unit` consecutive
/// frames each (the last unit of a sample takes what is left), of `frames` frames a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameUnits {
    /// Frames of a sample.
    pub frames: u32,
    /// Frames of a unit, ≥ 1.
    pub per_unit: u32,
}

impl FrameUnits {
    /// Units of one sample.
    pub fn per_sample(&self) -> u64 {
        u64::from(self.frames.div_ceil(self.per_unit.max(1)).max(1))
    }

    /// The frames of unit `unit` of a sample (0 ≤ unit < `per_sample`).
    pub fn range(&self, unit: u64) -> Range<u32> {
        let start = u32::try_from(unit)
            .unwrap_or(u32::MAX)
            .saturating_mul(self.per_unit);
        start.min(self.frames)..start.saturating_add(self.per_unit).min(self.frames)
    }

    /// Whether the frames of unit `unit` are among those a unit line `span` holds.
    pub(super) fn held_by(&self, unit: u64, span: FrameSpan) -> bool {
        let frames = self.range(unit);
        span.of == self.frames && span.start <= frames.start && frames.end <= span.end
    }
}

/// What one manifest line records: a finished sample, a unit of a sample's frames (its
/// sample, its frames [start, end) and the sample's frame count), or nothing readable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Entry {
    Sample(u64),
    Unit(u64, FrameSpan),
    Unreadable,
}

/// Frames [start, end) of a sample of `of` frames, as a unit line records them, with the
/// frames per unit of the run that wrote it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct FrameSpan {
    pub start: u32,
    pub end: u32,
    pub of: u32,
    pub per_unit: u32,
}

/// A sample being written: its files go into a private staging folder first.
pub struct SampleStage {
    sample: u64,
    /// The frames staged when this is a unit of a sequence sample (None: the whole sample).
    frames: Option<FrameSpan>,
    dir: PathBuf,
    root: PathBuf,
    files: Vec<String>,
    /// The manifest's record of each file: its size and BLAKE3, as hex.
    hashes: serde_json::Map<String, Value>,
    /// Bytes staged so far.
    pub bytes: u64,
}

/// Sample indices of one shard (those ≡ K mod N), one bit each from 0 to the highest: memory
/// grows with the samples finished, never with the dataset's size.
pub struct SampleSet {
    count: u64,
    bits: Vec<u64>,
    len: u64,
}

/// What a folder holds, in the eyes of the dataset about to be written.
enum Holds {
    /// No dataset: a missing or empty folder, or only leftovers of an interrupted start.
    Nothing,
    /// This dataset; `rewrite` when its run.json's bytes differ (another serialisation).
    Same { rewrite: bool },
    /// Another dataset (or one that cannot be identified): what differs, and how many
    /// finished samples it has.
    Other { why: String, finished: u64 },
    /// Files shmgen did not write, and no dataset.
    Foreign { names: Vec<String> },
}

impl SampleStage {
    /// Writes one file of the sample (path relative to the dataset root) into staging.
    pub fn write(&mut self, relative: String, bytes: &[u8]) -> Result<()> {
        let staged = self.dir.join(self.files.len().to_string());
        fault::write_through("stage", bytes, |b| fs::write(&staged, b))
            .map_err(|e| io_error(e, format_args!("writing {relative}"), &self.root))?;
        self.bytes += bytes.len() as u64;
        let hash = blake3::hash(bytes).to_hex();
        let record = serde_json::json!({ "bytes": bytes.len(), "blake3": hash.as_str() });
        self.hashes.insert(relative.clone(), record);
        self.files.push(relative);
        Ok(())
    }
}

impl SampleSet {
    /// An empty set of the samples of a shard of `count` shards.
    pub fn new(count: u64) -> SampleSet {
        SampleSet {
            count: count.max(1),
            bits: Vec::new(),
            len: 0,
        }
    }

    fn insert(&mut self, sample: u64) {
        let position = sample / self.count;
        let word = usize::try_from(position / 64).expect("a sample index fits in memory");
        if word >= self.bits.len() {
            self.bits.resize(word + 1, 0);
        }
        let bit = 1u64 << (position % 64);
        if self.bits[word] & bit == 0 {
            self.bits[word] |= bit;
            self.len += 1;
        }
    }

    /// Whether `sample` (a sample of the shard) is in the set.
    pub fn contains(&self, sample: u64) -> bool {
        let position = sample / self.count;
        usize::try_from(position / 64)
            .ok()
            .and_then(|word| self.bits.get(word))
            .is_some_and(|w| w & (1 << (position % 64)) != 0)
    }

    /// Number of samples in the set.
    pub fn len(&self) -> u64 {
        self.len
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl DatasetFolder {
    /// What opening `root` for shard `shard` = (K, N) of the dataset `identity` of `total`
    /// samples would find, without writing anything: the shard's samples already finished,
    /// or the error opening would give (a folder holding another dataset or foreign files,
    /// unless `force`).
    pub fn check(
        root: &Path,
        identity: Identity,
        force: bool,
        shard: (u64, u64),
        (total, units): (u64, Option<FrameUnits>),
    ) -> Result<SampleSet> {
        let (holds, _) = survey(root, identity)?;
        refuse(root, &holds, force)?;
        match holds {
            Holds::Same { .. } => completed_in(root, shard, total, units),
            _ => Ok(SampleSet::new(shard.1)),
        }
    }

    /// Opens `root` for writing shard `shard` = (K, N) of the dataset whose run.json
    /// `identity` gives. A folder holding another dataset is refused, saying what differs
    /// and how many finished samples `force` would delete; with `force` it is replaced (said
    /// first, on stderr), unless another process is writing it. Files shmgen did not write
    /// are never touched. A shard being written by another process is refused.
    pub fn open(
        root: &Path,
        identity: Identity,
        force: bool,
        shard: (u64, u64),
    ) -> Result<DatasetFolder> {
        let existed = root.exists();
        fs::create_dir_all(root).map_err(|e| io_error(e, "creating the output folder", root))?;
        let mut folder = DatasetFolder {
            root: root.to_path_buf(),
            shard: None,
        };
        let opened = folder.lock_folder().and_then(|setup| {
            let opened = folder.open_locked(identity, force, shard);
            if opened.is_err() {
                let _ = folder.release_shard();
            }
            setup.remove()?;
            opened
        });
        if opened.is_err() {
            // Leave a refused folder as it was.
            let _ = fs::remove_dir(folder.path(STAGING));
            if !existed {
                let _ = fs::remove_dir(root);
            }
        }
        opened.map(|()| folder)
    }

    fn open_locked(&mut self, identity: Identity, force: bool, shard: (u64, u64)) -> Result<()> {
        self.take_for(identity, force)?;
        self.lease_shard(shard)
    }

    /// Makes the folder (whose lock the caller holds) hold the dataset `identity`: kept if it
    /// holds it, created if it holds nothing, replaced (`force`) or refused otherwise.
    pub(super) fn take_for(&self, identity: Identity, force: bool) -> Result<()> {
        let root = &self.root;
        let (holds, run_json) = survey(root, identity)?;
        refuse(root, &holds, force)?;
        match &holds {
            Holds::Same { rewrite: false } => {}
            Holds::Same { rewrite: true } | Holds::Nothing => self.write_run_json(&run_json)?,
            Holds::Other { why, finished } => {
                self.refuse_if_being_written()?;
                eprintln!(
                    "--force: {} holds a different dataset ({why}); deleting its {finished} finished samples (manifest.jsonl, samples/, run.json)",
                    root.display()
                );
                self.clear()?;
                self.write_run_json(&run_json)?;
            }
            Holds::Foreign { names } => {
                eprintln!(
                    "--force: writing the dataset into {} beside files shmgen did not write, which are kept: {}",
                    root.display(),
                    names.join(", ")
                );
                self.write_run_json(&run_json)?;
            }
        }
        self.remove_stale_temporaries()
    }

    /// Takes the lock of shard K/N and its staging folder, refused if another process holds it
    /// or a shard of another count is being written (called under the folder lock).
    fn lease_shard(&mut self, (k, n): (u64, u64)) -> Result<()> {
        self.refuse_other_shard_counts((k, n))?;
        let root = self.root.clone();
        let name = format!("shard-{k}-of-{n}");
        let lock_path = self.path(STAGING).join(format!("{name}.lock"));
        let Some(mut lock) = Lock::acquire(&lock_path, false)
            .map_err(|e| io_error(e, "locking the shard", &root))?
        else {
            bail!(
                "shard {k}/{n} of {} is being written by another process ({}); wait for it to finish (or stop it and run again to resume)",
                root.display(),
                recorded_holder(&lock_path)
            );
        };
        lock.record_holder()
            .map_err(|e| io_error(e, "locking the shard", &root))?;
        let staging = self.path(STAGING).join(name);
        remove_all(&staging)?;
        self.shard = Some(ShardLease { lock, staging });
        self.terminate_torn_line()
    }

    fn write_run_json(&self, bytes: &[u8]) -> Result<()> {
        write_atomic_with(&self.path(RUN_JSON), |out| out.write_all(bytes))
            .map_err(|e| io_error(e, "writing run.json", &self.root))
    }

    /// Takes the folder lock, saying so when another process holds it.
    pub(super) fn lock_folder(&self) -> Result<Lock> {
        let path = self.path(STAGING).join(FOLDER_LOCK);
        let locking = |wait| {
            Lock::acquire(&path, wait).map_err(|e| io_error(e, "locking the folder", &self.root))
        };
        let mut lock = match locking(false)? {
            Some(lock) => lock,
            None => {
                eprintln!(
                    "waiting for another shmgen process ({}) to finish opening or finishing {}",
                    recorded_holder(&path),
                    self.root.display()
                );
                locking(true)?.expect("a blocking lock is taken")
            }
        };
        lock.record_holder()
            .map_err(|e| io_error(e, "locking the folder", &self.root))?;
        Ok(lock)
    }

    /// Before replacing a dataset: no other process may be writing any shard of it.
    fn refuse_if_being_written(&self) -> Result<()> {
        for (lock_path, shard) in self.shard_locks()? {
            if Lock::acquire(&lock_path, false)?.is_none() {
                bail!(
                    "{} is being written by another process (shard {shard}, {}); --force does not delete a dataset while it is written: stop that process first",
                    self.root.display(),
                    recorded_holder(&lock_path)
                );
            }
        }
        Ok(())
    }

    /// Running two shard counts at once renders every sample twice (K/N and K'/N' own
    /// overlapping samples), so a shard is refused while a shard of another count is being
    /// written. Checked under the folder lock, so two starting shards cannot both pass. Lock
    /// files of another count that no process holds are what a finished or dead run left:
    /// resuming with a new count is legitimate and skips their finished samples.
    fn refuse_other_shard_counts(&self, (k, n): (u64, u64)) -> Result<()> {
        for (lock_path, shard) in self.shard_locks()? {
            let other = parse_shard(&shard).map(|(_, count)| count);
            if other.is_none_or(|count| count == n) || !is_held_now(&lock_path)? {
                continue;
            }
            let other = other.expect("checked above");
            bail!(
                "shard {k}/{n} refused: {} is being written in {other} shards (shard {shard}, {}); running {n} and {other} shards at once would render samples twice. Wait for that run to end (`shmgen status {}` says when), or run the missing shards of {other} (--shard K/{other})",
                self.root.display(),
                recorded_holder(&lock_path),
                self.root.display()
            );
        }
        Ok(())
    }

    /// The shard lock files in staging, with the shard each names ("K/N").
    fn shard_locks(&self) -> Result<Vec<(PathBuf, String)>> {
        shard_lock_files(&self.root)
    }

    /// A crash can leave a manifest line without its newline; end it so that the next
    /// appended line stays parseable (the fragment itself is ignored).
    pub(super) fn terminate_torn_line(&self) -> Result<()> {
        let path = self.path(MANIFEST);
        if !path.exists() {
            return Ok(());
        }
        let lock = self.lock_manifest()?;
        let mut file = lock.file();
        let len = file.metadata()?.len();
        let mut last = [b'\n'];
        if len > 0 {
            let mut reader = File::open(&path)?;
            reader.seek(SeekFrom::Start(len - 1))?;
            reader.read_exact(&mut last)?;
        }
        if last[0] != b'\n' {
            file.write_all(b"\n")
                .map_err(|e| io_error(e, "ending a torn line of manifest.jsonl", &self.root))?;
        }
        Ok(())
    }

    /// The manifest, created if missing, opened for appending and locked.
    fn lock_manifest(&self) -> Result<Lock> {
        let mut options = OpenOptions::new();
        options.create(true).append(true);
        let lock = Lock::acquire_with(&self.path(MANIFEST), &options, true)
            .map_err(|e| io_error(e, "opening manifest.jsonl", &self.root))?;
        Ok(lock.expect("a blocking lock is taken"))
    }

    pub(super) fn path(&self, relative: &str) -> PathBuf {
        self.root.join(relative)
    }

    /// Deletes the dataset in the folder, manifest first: an interruption leaves samples
    /// that no manifest lists (redone or deleted later), never a manifest listing deleted
    /// samples. run.json goes last, so the folder stays recognisably shmgen's.
    fn clear(&self) -> Result<()> {
        remove_all(&self.path(MANIFEST))?;
        remove_all(&self.path(SAMPLES))?;
        for name in entries(&self.path(STAGING))? {
            if name != FOLDER_LOCK {
                remove_all(&self.path(STAGING).join(name))?;
            }
        }
        remove_all(&self.path(RUN_JSON))
    }

    /// Removes temporary files of run.json and the manifest: they are written only under
    /// the folder lock, which the caller holds, so any there are stale.
    fn remove_stale_temporaries(&self) -> Result<()> {
        for name in entries(&self.root)? {
            if is_temporary(&name) {
                remove_all(&self.path(&name))?;
            }
        }
        Ok(())
    }

    /// The units of work of shard `shard` = (K, N) below `total` samples listed in the
    /// manifest: samples, or with `units` the (sample, frame range) units numbered
    /// `sample × units per sample + unit` (a finished sample has all its units; a unit line
    /// covers the units whose frames it holds). Lines that do not parse (a torn write after a
    /// crash) are ignored: their work is simply redone.
    pub fn completed(
        &self,
        shard: (u64, u64),
        (total, units): (u64, Option<FrameUnits>),
    ) -> Result<SampleSet> {
        completed_in(&self.root, shard, total, units)
    }

    /// A fresh staging area for `sample`, discarding leftovers of an interrupted attempt.
    pub fn stage(&self, sample: u64) -> Result<SampleStage> {
        self.stage_as(sample, None)
    }

    /// A fresh staging area for frames `frames` of sample `sample`, a unit of `units`:
    /// committed, they are a unit line, and the sample is finished once its units cover it.
    pub fn stage_frames(
        &self,
        sample: u64,
        frames: Range<u32>,
        units: FrameUnits,
    ) -> Result<SampleStage> {
        let range = FrameSpan {
            start: frames.start,
            end: frames.end,
            of: units.frames,
            per_unit: units.per_unit,
        };
        self.stage_as(sample, Some(range))
    }

    fn stage_as(&self, sample: u64, frames: Option<FrameSpan>) -> Result<SampleStage> {
        let staging = &self
            .shard
            .as_ref()
            .expect("an open folder holds its shard")
            .staging;
        let name = match frames {
            Some(f) => format!("{sample:06}_f{:04}", f.start),
            None => format!("{sample:06}"),
        };
        let dir = staging.join(name);
        remove_all(&dir)?;
        fs::create_dir_all(&dir)
            .map_err(|e| io_error(e, format_args!("staging sample {sample}"), &self.root))?;
        Ok(SampleStage {
            sample,
            frames,
            dir,
            root: self.root.clone(),
            files: Vec::new(),
            hashes: serde_json::Map::new(),
            bytes: 0,
        })
    }

    /// Moves the staged files into place, then records the sample in the manifest; a unit
    /// of a sequence sample is recorded as a unit line, and the sample's own line follows it
    /// once its units cover every frame. `views`: the images of the whole sample.
    pub fn commit(&self, stage: SampleStage, views: u32) -> Result<()> {
        self.move_into_place(&stage.dir, &stage.files)?;
        fault::check("commit")?;
        let mut line = match stage.frames {
            None => sample_line(stage.sample, views, stage.files, stage.hashes)?,
            Some(frames) => unit_line(stage.sample, frames, views, stage.files, stage.hashes)?,
        };
        line.push(b'\n');
        self.append_line(&line)?;
        if stage.frames.is_some() {
            self.seal_covered(Some(stage.sample))?;
        }
        fault::check("committed")?;
        fs::remove_dir(&stage.dir)?;
        Ok(())
    }

    /// Appends the line of each sample (only `only`, if given) whose unit lines cover all its
    /// frames and that the manifest does not list yet: the line a whole-sample commit would
    /// have written, its files in frame order, each once. Under the manifest's lock, so two
    /// shards committing a sample's last units seal it once.
    pub(super) fn seal_covered(&self, only: Option<u64>) -> Result<()> {
        let lock = self.lock_manifest()?;
        let path = self.path(MANIFEST);
        let mut finished = HashSet::new();
        let mut units: BTreeMap<u64, Vec<(FrameSpan, u64, usize)>> = BTreeMap::new();
        scan_entries(&path, |entry, offset, len| match entry {
            Entry::Sample(sample) => {
                finished.insert(sample);
            }
            Entry::Unit(sample, frames) if only.is_none_or(|s| s == sample) => {
                units.entry(sample).or_default().push((frames, offset, len));
            }
            _ => {}
        })?;
        for (sample, mut lines) in units {
            if finished.contains(&sample) {
                continue;
            }
            lines.sort_by_key(|(f, _, _)| (f.start, f.end));
            if !covers(lines.iter().map(|(f, _, _)| *f)) {
                continue;
            }
            let mut line = sealed_line(&path, sample, &lines)?;
            line.push(b'\n');
            fault::write_through("append", &line, |b| lock.file().write_all(b))
                .map_err(|e| io_error(e, "appending to manifest.jsonl", &self.root))?;
        }
        Ok(())
    }

    /// Renames the files staged in `dir` (named 0, 1, … in the order of `files`) to their
    /// places `files` (relative to the root).
    pub(super) fn move_into_place(&self, dir: &Path, files: &[String]) -> Result<()> {
        for (i, relative) in files.iter().enumerate() {
            let target = self.path(relative);
            if let Some(parent) = target.parent() {
                fs::create_dir_all(parent).map_err(|e| {
                    io_error(
                        e,
                        format_args!("creating the folder of {relative}"),
                        &self.root,
                    )
                })?;
            }
            fs::rename(dir.join(i.to_string()), &target).map_err(|e| {
                io_error(e, format_args!("moving {relative} into place"), &self.root)
            })?;
        }
        Ok(())
    }

    /// Appends a whole manifest line (newline included) in one write in append mode, under
    /// the manifest's lock: concurrent shards never interleave lines, even on a shared
    /// filesystem.
    pub(super) fn append_line(&self, line: &[u8]) -> Result<()> {
        let lock = self.lock_manifest()?;
        fault::write_through("append", line, |b| lock.file().write_all(b))
            .map_err(|e| io_error(e, "appending to manifest.jsonl", &self.root))
    }

    /// Ends this process's work on the folder: releases its shard, then — once every sample
    /// of the dataset is in the manifest — rewrites the manifest in sample order so that the
    /// finished dataset has the same bytes however it was run, and removes what interrupted
    /// runs left (temporary files, staging of shards no process holds). Returns whether the
    /// dataset is complete.
    pub fn finish(mut self, total: u64) -> Result<bool> {
        let marker = self
            .shard
            .as_ref()
            .map(|lease| lease.staging.with_extension(DONE));
        self.release_shard()?;
        let setup = self.lock_folder()?;
        let complete = self.tidy(total)?;
        // Until the dataset is complete, `status` learns the shard count from these.
        if let Some(marker) = marker.filter(|_| !complete) {
            File::create(&marker)
                .map_err(|e| io_error(e, "marking the shard finished", &self.root))?;
        }
        setup.remove()?;
        let _ = fs::remove_dir(self.path(STAGING));
        Ok(complete)
    }

    /// `finish`'s work once the folder lock is held: the manifest sorted if the dataset is
    /// complete (returned), leftovers of interrupted runs and merges removed.
    pub(super) fn tidy(&self, total: u64) -> Result<bool> {
        // Units whose sample a crash left unsealed after its last unit line.
        self.seal_covered(None)?;
        let complete = self.finalize_manifest(total)?;
        self.remove_stale_temporaries()?;
        // Shards no process holds: their lock files and staging go.
        let mut held = Vec::new();
        for (path, _) in self.shard_locks()? {
            match Lock::acquire(&path, false) {
                Ok(Some(lock)) => lock.remove()?,
                _ => held.extend(path.file_stem().map(|s| s.to_string_lossy().to_string())),
            }
        }
        for name in entries(&self.path(STAGING))? {
            let stem = name.strip_suffix(".lock").unwrap_or(&name);
            let marks_a_shard = name.ends_with(&format!(".{DONE}"));
            if name != FOLDER_LOCK
                && !held.iter().any(|h| h == stem)
                && (complete || !marks_a_shard)
            {
                remove_all(&self.path(STAGING).join(&name))?;
            }
        }
        Ok(complete)
    }

    fn release_shard(&mut self) -> Result<()> {
        if let Some(ShardLease { lock, staging }) = self.shard.take() {
            remove_all(&staging)?;
            lock.remove()?;
        }
        Ok(())
    }

    /// Puts the manifest in sample order, without duplicates or torn lines, once it lists
    /// every sample below `total`. Memory: a bit per sample and, only when the manifest is
    /// out of order, 24 bytes per line.
    fn finalize_manifest(&self, total: u64) -> Result<bool> {
        let path = self.path(MANIFEST);
        let lock = self.lock_manifest()?;
        let (mut lines, mut ordered, mut last) = (0u64, true, None);
        scan_manifest(&path, |line| match line {
            Some((sample, _, _)) if sample < total => {
                lines += 1;
                ordered &= last.is_none_or(|l| l < sample);
                last = Some(sample);
            }
            _ => ordered = false,
        })?;
        if lines < total {
            return Ok(false);
        }
        if ordered && lines == total {
            return Ok(true);
        }
        let mut seen = SampleSet::new(1);
        let mut index = Vec::new();
        scan_manifest(&path, |line| {
            if let Some((sample, offset, len)) = line
                && sample < total
                && !seen.contains(sample)
            {
                seen.insert(sample);
                index.push((sample, offset, len));
            }
        })?;
        if seen.len() < total {
            return Ok(false);
        }
        index.sort_unstable();
        let mut source = File::open(&path)?;
        write_atomic_with(&path, |out| {
            let mut buffer = Vec::new();
            for &(_, offset, len) in &index {
                buffer.resize(len, 0);
                source.seek(SeekFrom::Start(offset))?;
                source.read_exact(&mut buffer)?;
                out.write_all(&buffer)?;
            }
            Ok(())
        })
        .map_err(|e| io_error(e, "sorting manifest.jsonl", &self.root))?;
        drop(lock);
        Ok(true)
    }
}

impl Drop for DatasetFolder {
    /// A run that stops on an error leaves no staging behind (its samples were not
    /// committed) and frees its shard.
    fn drop(&mut self) {
        if self.release_shard().is_ok() {
            let _ = fs::remove_dir(self.path(STAGING));
        }
    }
}

/// The most of a run.json or export.json read (ours are a few kB).
const RECORD_BYTES: u64 = 16 << 20;

/// Refuses a dataset folder with a link where shmgen reads or writes (run.json, the manifest,
/// `samples/` and its folders, `.partial/` and its locks): a dataset received from someone
/// else could otherwise point them elsewhere, and resuming it would append, rename or lock
/// files outside it. The folder itself may be a link: the user named it.
pub(super) fn refuse_links(root: &Path) -> Result<()> {
    let mut places: Vec<PathBuf> = [RUN_JSON, MANIFEST, SAMPLES, STAGING]
        .iter()
        .map(|name| root.join(name))
        .collect();
    for folder in [SAMPLES, STAGING] {
        let folder = root.join(folder);
        if fs::symlink_metadata(&folder).is_ok_and(|m| m.is_dir()) {
            places.extend(entries(&folder)?.into_iter().map(|name| folder.join(name)));
        }
    }
    for place in places {
        if fs::symlink_metadata(&place).is_ok_and(|m| m.file_type().is_symlink()) {
            bail!(
                "{}: is a symbolic link; a dataset folder holds no links (a received dataset could point them outside it), so shmgen does not write into this one: remove the link",
                place.display()
            );
        }
    }
    Ok(())
}

/// The bytes of a record shmgen writes (`run.json`, `export.json`), None if there is none;
/// refused if it is not a regular file or larger than any record shmgen writes.
pub(super) fn read_record(path: &Path) -> Result<Option<Vec<u8>>> {
    let mut options = OpenOptions::new();
    options.read(true);
    // A FIFO opens without waiting for a writer, and is then refused as not a regular file.
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
    let file = match options.open(path) {
        Ok(file) => file,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    let meta = file.metadata()?;
    let len = meta.len();
    if !meta.is_file() || len > RECORD_BYTES {
        bail!(
            "{}: not a record shmgen wrote (not a regular file, or {len} bytes)",
            path.display()
        );
    }
    let mut bytes = Vec::new();
    file.take(RECORD_BYTES)
        .read_to_end(&mut bytes)
        .with_context(|| format!("reading {}", path.display()))?;
    Ok(Some(bytes))
}

/// What `root` holds for the dataset `identity`, and this dataset's run.json bytes.
fn survey(root: &Path, identity: Identity) -> Result<(Holds, Vec<u8>)> {
    refuse_links(root)?;
    let run_json = root.join(RUN_JSON);
    let recorded = loop {
        if let Some(bytes) = read_record(&run_json)? {
            break bytes;
        }
        let ours = identity(None)?;
        if root.join(MANIFEST).exists() {
            let why = "it has a manifest.jsonl but no run.json".to_string();
            let finished = finished_samples(root)?;
            return Ok((Holds::Other { why, finished }, ours));
        }
        let names: Vec<String> = entries(root)?
            .into_iter()
            .filter(|n| n != STAGING && !is_temporary(n))
            .collect();
        // Another shard opening the folder (`check` does not take the folder lock) may have
        // renamed run.json into place since it was read: look again rather than call the
        // folder foreign.
        if names.iter().any(|n| n == RUN_JSON) {
            continue;
        }
        let holds = if names.is_empty() {
            Holds::Nothing
        } else {
            Holds::Foreign { names }
        };
        return Ok((holds, ours));
    };
    let (holds, ours) = match serde_json::from_slice::<Value>(&recorded) {
        Ok(value) => {
            let ours = identity(Some(&value))?;
            let parsed: Value = serde_json::from_slice(&ours)?;
            if parsed == value {
                let rewrite = ours != recorded;
                (Holds::Same { rewrite }, ours)
            } else {
                let why = differences(&value, &parsed, "folder vs this run");
                let finished = finished_samples(root)?;
                (Holds::Other { why, finished }, ours)
            }
        }
        Err(e) => {
            let why = format!("its run.json is not valid JSON: {e}");
            let finished = finished_samples(root)?;
            (Holds::Other { why, finished }, identity(None)?)
        }
    };
    Ok((holds, ours))
}

/// The error for what `root` holds, unless opening it for writing may go on.
fn refuse(root: &Path, holds: &Holds, force: bool) -> Result<()> {
    match holds {
        Holds::Other { why, finished } if !force => bail!(
            "{} holds a different dataset: {why}. Choose another --out, or pass --force to replace it: --force would delete its {finished} finished samples",
            root.display()
        ),
        Holds::Foreign { names } if !force => bail!(
            "{} is not empty and holds no shmgen dataset (it has {}); choose another --out, or pass --force to write the dataset beside those files (they are kept)",
            root.display(),
            names.join(", ")
        ),
        _ => Ok(()),
    }
}

/// What differs between two run.json, field by field; `sides` names them in that order
/// ("folder vs this run").
pub fn differences(recorded: &Value, ours: &Value, sides: &str) -> String {
    let mut found = Vec::new();
    differences_into("", recorded, ours, &mut found);
    if found.is_empty() {
        return "its run.json differs".to_string();
    }
    let more = found.len().saturating_sub(DIFFERENCES_SHOWN);
    found.truncate(DIFFERENCES_SHOWN);
    let mut text = format!("{} ({sides})", found.join("; "));
    if more > 0 {
        text += &format!(" and {more} more differences");
    }
    text
}

fn differences_into(path: &str, recorded: &Value, ours: &Value, found: &mut Vec<String>) {
    let show = |v: Option<&Value>| match v {
        None => "absent".to_string(),
        Some(v) => {
            let text = v.to_string();
            match text.char_indices().nth(40) {
                Some((cut, _)) => format!("{}…", &text[..cut]),
                None => text,
            }
        }
    };
    if let (Value::Object(a), Value::Object(b)) = (recorded, ours) {
        let keys: BTreeSet<&String> = a.keys().chain(b.keys()).collect();
        for key in keys {
            let inner = if path.is_empty() {
                key.clone()
            } else {
                format!("{path}.{key}")
            };
            match (a.get(key), b.get(key)) {
                (Some(x), Some(y)) => differences_into(&inner, x, y, found),
                (x, y) => found.push(format!("{inner} {} vs {}", show(x), show(y))),
            }
        }
    } else if recorded != ours {
        let (a, b) = (show(Some(recorded)), show(Some(ours)));
        found.push(match path.strip_suffix(".hash") {
            Some(of) => format!("{of} content changed ({path} {a} vs {b})"),
            None => format!("{path} {a} vs {b}"),
        });
    }
}

/// Distinct samples listed in the manifest of `root`.
fn finished_samples(root: &Path) -> Result<u64> {
    let mut samples = HashSet::new();
    scan_manifest(&root.join(MANIFEST), |line| {
        if let Some((sample, _, _)) = line {
            samples.insert(sample);
        }
    })?;
    Ok(samples.len() as u64)
}

fn completed_in(
    root: &Path,
    (index, count): (u64, u64),
    total: u64,
    units: Option<FrameUnits>,
) -> Result<SampleSet> {
    let mut done = SampleSet::new(count);
    let per_sample = units.map_or(1, |u| u.per_sample());
    // Unit `chunk` of `sample` is done when `held` frames hold its frames.
    let mut mark = |sample: u64, held: Option<FrameSpan>| {
        for chunk in 0..per_sample {
            let unit = sample * per_sample + chunk;
            let inside = match (held, units) {
                (None, _) => true,
                (Some(held), Some(units)) => units.held_by(chunk, held),
                (Some(_), None) => false,
            };
            if inside && unit % count == index {
                done.insert(unit);
            }
        }
    };
    scan_entries(&root.join(MANIFEST), |entry, _, _| match entry {
        Entry::Sample(sample) if sample < total => mark(sample, None),
        Entry::Unit(sample, frames) if sample < total => mark(sample, Some(frames)),
        _ => {}
    })?;
    Ok(done)
}

/// The manifest line (without its newline) of a finished sample: its files in the order
/// written, with their sizes and hashes.
fn sample_line(
    sample: u64,
    views: u32,
    files: Vec<String>,
    hashes: serde_json::Map<String, Value>,
) -> Result<Vec<u8>> {
    let line = serde_json::json!({
        "sample": sample,
        "views": views,
        "files": files,
        "hashes": sorted(hashes),
    });
    Ok(serde_json::to_vec(&line)?)
}

/// The manifest line (without its newline) of frames `frames` of a sample.
fn unit_line(
    sample: u64,
    frames: FrameSpan,
    views: u32,
    files: Vec<String>,
    hashes: serde_json::Map<String, Value>,
) -> Result<Vec<u8>> {
    let line = serde_json::json!({
        "unit": {
            "sample": sample,
            "frames": [frames.start, frames.end],
            "of": frames.of,
            "per_unit": frames.per_unit,
        },
        "views": views,
        "files": files,
        "hashes": sorted(hashes),
    });
    Ok(serde_json::to_vec(&line)?)
}

/// `hashes` sorted by name whatever order the files were written in, and whichever map type
/// serde_json is built with: a line's bytes depend on the files' bytes alone.
fn sorted(hashes: serde_json::Map<String, Value>) -> serde_json::Map<String, Value> {
    let mut hashes: Vec<(String, Value)> = hashes.into_iter().collect();
    hashes.sort_by(|a, b| a.0.cmp(&b.0));
    hashes.into_iter().collect()
}

/// Whether frame ranges sorted by start cover every frame of their sample.
fn covers(ranges: impl Iterator<Item = FrameSpan>) -> bool {
    let mut reach = 0;
    let mut of = None;
    for range in ranges {
        if range.start > reach || of.is_some_and(|n| n != range.of) {
            return false;
        }
        reach = reach.max(range.end);
        of = Some(range.of);
    }
    of.is_some_and(|n| reach >= n)
}

/// The line of `sample` made of its unit lines at (frames, offset, length) in the manifest at
/// `path`, sorted by their first frame: their files in that order, each once.
fn sealed_line(path: &Path, sample: u64, lines: &[(FrameSpan, u64, usize)]) -> Result<Vec<u8>> {
    #[derive(serde::Deserialize)]
    struct UnitLine {
        views: u32,
        files: Vec<String>,
        hashes: serde_json::Map<String, Value>,
    }
    let mut source = File::open(path).with_context(|| format!("reading {}", path.display()))?;
    let (mut views, mut files, mut hashes) = (0, Vec::new(), serde_json::Map::new());
    let mut seen = HashSet::new();
    for &(_, offset, len) in lines {
        let mut bytes = vec![0; len];
        source.seek(SeekFrom::Start(offset))?;
        source.read_exact(&mut bytes)?;
        let unit: UnitLine = serde_json::from_slice(&bytes)
            .with_context(|| format!("{}: a unit line of sample {sample}", path.display()))?;
        views = unit.views;
        for file in unit.files {
            if seen.insert(file.clone()) {
                hashes.extend(unit.hashes.get(&file).map(|h| (file.clone(), h.clone())));
                files.push(file);
            }
        }
    }
    sample_line(sample, views, files, hashes)
}

/// The longest manifest line read (a sample's file list with its hashes: a few kB): a
/// received manifest without newlines is refused, never read whole.
const MANIFEST_LINE: u64 = 1 << 20;

/// Calls `each` for every line of the manifest at `path` (none if it is missing), streaming:
/// with (sample, byte offset, length) for a complete line that parses, else None. The
/// manifest must be a regular file (a FIFO is refused, not waited on, and a link is not
/// followed) with lines of at most `MANIFEST_LINE` bytes.
pub(super) fn scan_manifest(
    path: &Path,
    mut each: impl FnMut(Option<(u64, u64, usize)>),
) -> Result<()> {
    scan_entries(path, |entry, offset, len| match entry {
        Entry::Sample(sample) => each(Some((sample, offset, len))),
        _ => each(None),
    })
}

/// [`scan_manifest`] telling unit lines apart: calls `each` with every line's entry, byte
/// offset and length.
pub(super) fn scan_entries(path: &Path, mut each: impl FnMut(Entry, u64, usize)) -> Result<()> {
    #[derive(serde::Deserialize)]
    struct Line {
        sample: Option<u64>,
        unit: Option<UnitOf>,
    }
    #[derive(serde::Deserialize)]
    struct UnitOf {
        sample: u64,
        frames: [u32; 2],
        of: u32,
        per_unit: u32,
    }
    let Some(file) = open_manifest(path)? else {
        return Ok(());
    };
    let mut reader = BufReader::new(file);
    let (mut line, mut offset) = (Vec::new(), 0u64);
    for number in 1u64.. {
        line.clear();
        let len = (&mut reader)
            .take(MANIFEST_LINE + 1)
            .read_until(b'\n', &mut line)
            .with_context(|| format!("reading {}", path.display()))?;
        if len == 0 {
            break;
        }
        if len as u64 > MANIFEST_LINE {
            bail!(
                "{}: line {number} is longer than {MANIFEST_LINE} bytes; not a manifest shmgen wrote",
                path.display()
            );
        }
        let parsed = serde_json::from_slice::<Line>(&line)
            .ok()
            .filter(|_| line.ends_with(b"\n"));
        let entry = match parsed {
            Some(Line {
                sample: Some(sample),
                unit: None,
            }) => Entry::Sample(sample),
            Some(Line {
                sample: None,
                unit: Some(u),
            }) if u.frames[0] < u.frames[1] && u.frames[1] <= u.of => Entry::Unit(
                u.sample,
                FrameSpan {
                    start: u.frames[0],
                    end: u.frames[1],
                    of: u.of,
                    per_unit: u.per_unit.max(1),
                },
            ),
            _ => Entry::Unreadable,
        };
        each(entry, offset, len);
        offset += len as u64;
    }
    Ok(())
}

/// The manifest at `path` opened for reading, None if missing; refused unless a regular file.
pub(super) fn open_manifest(path: &Path) -> Result<Option<File>> {
    let file = match open_no_wait(path) {
        Ok(f) => f,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    if !file.metadata()?.is_file() {
        bail!(
            "{}: not a regular file; not a manifest shmgen wrote",
            path.display()
        );
    }
    Ok(Some(file))
}

/// The shard lock files in the staging folder of `root`, with the shard each names ("K/N").
pub(super) fn shard_lock_files(root: &Path) -> Result<Vec<(PathBuf, String)>> {
    shard_files(root, ".lock")
}

/// The shards that ended before the dataset was complete ("K/N"), from their marks.
pub(super) fn shards_finished(root: &Path) -> Result<Vec<String>> {
    let marks = shard_files(root, &format!(".{DONE}"))?;
    Ok(marks.into_iter().map(|(_, shard)| shard).collect())
}

/// The files `shard-K-of-N{suffix}` in the staging folder of `root`, with "K/N".
fn shard_files(root: &Path, suffix: &str) -> Result<Vec<(PathBuf, String)>> {
    let staging = root.join(STAGING);
    let mut found = Vec::new();
    for name in entries(&staging)? {
        if let Some(shard) = name
            .strip_prefix("shard-")
            .and_then(|s| s.strip_suffix(suffix))
        {
            let shard = shard.replacen("-of-", "/", 1);
            found.push((staging.join(&name), shard));
        }
    }
    Ok(found)
}

/// (K, N) of a shard named "K/N", if it is one (0 ≤ K < N).
pub(super) fn parse_shard(shard: &str) -> Option<(u64, u64)> {
    let (k, n) = shard.split_once('/')?;
    let (k, n) = (k.parse::<u64>().ok()?, n.parse::<u64>().ok()?);
    (k < n).then_some((k, n))
}

/// Whether a process holds the lock file at `path` now (false once it is removed).
pub(super) fn is_held_now(path: &Path) -> Result<bool> {
    match is_held(path) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
        held => held.with_context(|| format!("probing the lock {}", path.display())),
    }
}

/// Whether `name` is a temporary file of run.json or the manifest.
fn is_temporary(name: &str) -> bool {
    [RUN_JSON, MANIFEST]
        .iter()
        .any(|file| name.starts_with(&format!(".{file}.tmp-")))
}

/// The names in folder `dir` (none if it is missing).
fn entries(dir: &Path) -> Result<Vec<String>> {
    let read = match fs::read_dir(dir) {
        Ok(read) => read,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("reading {}", dir.display())),
    };
    let mut names = Vec::new();
    for entry in read {
        let entry = entry.with_context(|| format!("reading {}", dir.display()))?;
        names.push(entry.file_name().to_string_lossy().to_string());
    }
    names.sort();
    Ok(names)
}

/// Removes a file or a folder with its contents, if there.
pub(super) fn remove_all(path: &Path) -> Result<()> {
    let removed = match fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => fs::remove_dir_all(path),
        Ok(_) => fs::remove_file(path),
        Err(e) => Err(e),
    };
    match removed {
        Err(e) if e.kind() != io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("removing {}", path.display()))
        }
        _ => Ok(()),
    }
}

/// An I/O error while `doing` something in the dataset folder `root`, saying so plainly
/// when the disk is full.
fn io_error(e: io::Error, doing: impl Display, root: &Path) -> anyhow::Error {
    let full = matches!(
        e.kind(),
        io::ErrorKind::StorageFull | io::ErrorKind::QuotaExceeded
    );
    let context = if full {
        format!(
            "{doing} in {}: the disk is full (or the quota is used up); free space, then run the same command again to resume (finished samples are kept)",
            root.display()
        )
    } else {
        format!("{doing} in {}", root.display())
    };
    anyhow::Error::new(e).context(context)
}

/// Writes `bytes` to `path` through a temporary file in the same folder, flushed to disk,
/// and a rename: `path` has either its old or its new bytes, whatever happens. On failure
/// the temporary file is removed and the error names `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |out| out.write_all(bytes)).map_err(|e| {
        let full = e.kind() == io::ErrorKind::StorageFull;
        anyhow::Error::new(e).context(format!(
            "writing {}{}",
            path.display(),
            if full { " (the disk is full)" } else { "" }
        ))
    })
}

fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    static TEMPORARIES: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
    let tmp = path.with_file_name(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        TEMPORARIES.fetch_add(1, Ordering::Relaxed)
    ));
    let written = (|| {
        let mut out = BufWriter::new(File::create(&tmp)?);
        write(&mut out)?;
        let file = out.into_inner().map_err(|e| e.into_error())?;
        let point = format!("write:{name}");
        match fault::at(&point) {
            Fault::None => {}
            Fault::Full => {
                file.set_len(file.metadata()?.len() / 2)?;
                return Err(fault::disk_full());
            }
            Fault::Crash => {
                file.set_len(file.metadata()?.len() / 2)?;
                fault::crash(&point);
            }
        }
        file.sync_all()?;
        fault::check(&format!("rename:{name}"))?;
        fs::rename(&tmp, path)
    })();
    if written.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity(bytes: &'static [u8]) -> impl Fn(Option<&Value>) -> Result<Vec<u8>> {
        move |_| Ok(bytes.to_vec())
    }

    #[test]
    fn refuses_a_different_dataset_unless_forced() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("ds");
        let shard = (0, 1);
        drop(DatasetFolder::open(&root, &identity(b"{\"a\":1}"), false, shard).unwrap());
        drop(DatasetFolder::open(&root, &identity(b"{ \"a\": 1 }"), false, shard).unwrap());
        assert_eq!(fs::read(root.join(RUN_JSON)).unwrap(), b"{ \"a\": 1 }");
        let err = DatasetFolder::open(&root, &identity(b"{\"a\":2}"), false, shard)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("different dataset: a 1 vs 2"), "{err}");
        assert!(err.contains("would delete its 0 finished samples"), "{err}");
        drop(DatasetFolder::open(&root, &identity(b"{\"a\":2}"), true, shard).unwrap());
        assert_eq!(fs::read(root.join(RUN_JSON)).unwrap(), b"{\"a\":2}");
    }

    #[test]
    fn torn_manifest_lines_are_ignored_and_finishing_sorts() {
        let dir = tempfile::tempdir().unwrap();
        let open = || DatasetFolder::open(dir.path(), &identity(b"{}"), true, (0, 1)).unwrap();
        let folder = open();
        for s in [2u64, 0, 1, 0] {
            let mut stage = folder.stage(s).unwrap();
            stage.write(format!("samples/x{s}.txt"), b"data").unwrap();
            folder.commit(stage, 1).unwrap();
        }
        let mut f = OpenOptions::new()
            .append(true)
            .open(dir.path().join(MANIFEST))
            .unwrap();
        f.write_all(b"{\"sample\": 7, \"vie").unwrap();
        let done = folder.completed((0, 1), (10, None)).unwrap();
        assert_eq!(done.len(), 3);
        assert!((0..3).all(|s| done.contains(s)) && !done.contains(7));
        assert!(!folder.finish(4).unwrap());
        assert!(open().finish(3).unwrap());
        let text = fs::read_to_string(dir.path().join(MANIFEST)).unwrap();
        let order: Vec<u64> = text
            .lines()
            .map(|l| {
                serde_json::from_str::<Value>(l).unwrap()["sample"]
                    .as_u64()
                    .unwrap()
            })
            .collect();
        assert_eq!(order, vec![0, 1, 2]);
        assert!(!dir.path().join(STAGING).exists());
    }

    /// Stages `frames` of sample 0 (one file a frame, frame 0 with a sensor file first) as a
    /// unit of `units`, or the whole sample (None), and commits it.
    fn commit_frames(folder: &DatasetFolder, units: FrameUnits, frames: Option<Range<u32>>) {
        let mut stage = match &frames {
            Some(range) => folder.stage_frames(0, range.clone(), units).unwrap(),
            None => folder.stage(0).unwrap(),
        };
        let range = frames.unwrap_or(0..units.frames);
        if range.start == 0 {
            stage.write("samples/s.csv".into(), b"series").unwrap();
        }
        for k in range {
            let bytes = format!("frame {k}");
            stage
                .write(format!("samples/f{k}"), bytes.as_bytes())
                .unwrap();
        }
        folder.commit(stage, 7).unwrap();
    }

    #[test]
    fn units_covering_a_sample_seal_it_with_the_line_of_a_whole_sample_commit() {
        let units = FrameUnits {
            frames: 10,
            per_unit: 4,
        };
        assert_eq!(units.per_sample(), 3);
        assert_eq!(
            (0..3).map(|u| units.range(u)).collect::<Vec<_>>(),
            [0..4, 4..8, 8..10]
        );
        let whole = tempfile::tempdir().unwrap();
        let folder = DatasetFolder::open(whole.path(), &identity(b"{}"), true, (0, 1)).unwrap();
        commit_frames(&folder, units, None);
        let expected = fs::read(whole.path().join(MANIFEST)).unwrap();

        let dir = tempfile::tempdir().unwrap();
        let folder = DatasetFolder::open(dir.path(), &identity(b"{}"), true, (0, 1)).unwrap();
        let lines = || fs::read_to_string(dir.path().join(MANIFEST)).unwrap();
        // Out of order, and a unit of another split (frames 0–4) holding the first unit and
        // part of the second.
        let odd = FrameUnits {
            frames: 10,
            per_unit: 5,
        };
        commit_frames(&folder, units, Some(8..10));
        commit_frames(&folder, odd, Some(0..5));
        let done = folder.completed((0, 1), (1, Some(units))).unwrap();
        assert!(done.contains(0) && !done.contains(1) && done.contains(2));
        assert_eq!(lines().lines().count(), 2, "not yet sealed");
        commit_frames(&folder, units, Some(4..8));
        // Frames 5–7 were missing until now: sealed once, the whole sample's line.
        assert_eq!(lines().lines().count(), 4);
        let sealed = lines().lines().last().unwrap().to_string() + "\n";
        assert_eq!(sealed.as_bytes(), &expected[..]);
        let done = folder.completed((0, 1), (1, Some(units))).unwrap();
        assert_eq!(done.len(), 3);
        // Sealing again adds nothing; finishing drops the unit lines.
        folder.seal_covered(None).unwrap();
        assert_eq!(lines().lines().count(), 4);
        assert!(folder.finish(1).unwrap());
        assert_eq!(fs::read(dir.path().join(MANIFEST)).unwrap(), expected);
    }

    #[test]
    fn spans_cover_a_sample_only_without_gaps_and_of_one_length() {
        let span = |start, end, of| FrameSpan {
            start,
            end,
            of,
            per_unit: 1,
        };
        assert!(covers([span(0, 4, 9), span(2, 9, 9)].into_iter()));
        assert!(!covers([span(0, 4, 9), span(5, 9, 9)].into_iter()));
        assert!(!covers([span(1, 9, 9)].into_iter()));
        assert!(!covers([span(0, 4, 9), span(4, 9, 8)].into_iter()));
        assert!(!covers(std::iter::empty()));
    }

    #[test]
    fn sample_sets_hold_one_bit_per_sample_of_the_shard() {
        let mut set = SampleSet::new(3);
        for s in [1, 4, 301, 4] {
            set.insert(s);
        }
        assert_eq!(set.len(), 3);
        assert!(set.contains(301) && set.contains(1) && !set.contains(7));
        assert_eq!(set.bits.len(), 2);
    }
}
