//! `shmgen status`: what a dataset folder holds while shards write it, read without writing
//! or waiting: the dataset's identity, the samples done per shard, which shard locks are held
//! now and which were left behind, what to resubmit, and the rate at which samples arrive.
//!
//! Owns: reading the folder's state (`folder` owns the layout and the writing). Must not
//! touch: any file (a lock is taken for an instant, only to see whether it is free).
//!
//! The folder may be someone else's: run.json and the manifest are read as `folder` reads them
//! (regular files, no link, bounded records and lines), lock files as `lock` reads them, and
//! a sample's file only `lstat`ed for its modification time.
//!
//! The manifest records no time (a timestamp per line would make two runs of one recipe
//! differ), so progress comes from file times: a sample's files are renamed into place with
//! the time they were written, and the manifest lists samples in the order they finished
//! until the dataset is complete. The rate is measured over the last `RATE_WINDOW` lines.
//!
//! A run dealing out a sequence's frames (`run --frames-per-unit F`) leaves unit lines: the
//! shards are then counted in units of F frames (F as those lines record it), and each
//! unfinished sample with units says how many of its frames are done.

use super::folder::{
    Entry, FrameSpan, FrameUnits, MANIFEST, RUN_JSON, is_held_now, open_manifest, parse_shard,
    read_record, refuse_links, scan_entries, shard_lock_files, shards_finished,
};
use super::lock::{parse_holder, recorded_holder, this_host};
use anyhow::{Context, Result, bail};
use serde::Serialize;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet, HashSet, VecDeque};
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
use std::time::{Duration, SystemTime};

/// The version of `run.json` whose identity is read.
const RUN_SCHEMA: &str = "shmgen.run/1";
/// The most shards listed: a lock file's name (untrusted) must not make `status` list
/// billions of shards.
pub const MAX_SHARDS: u64 = 1 << 20;
/// Manifest lines (the latest samples) whose file times measure the rate.
const RATE_WINDOW: usize = 256;

/// Exit code of `shmgen status`: every sample is in the manifest.
pub const EXIT_COMPLETE: u8 = 0;
/// Exit code: samples are missing and no shard is being written (resubmit what it lists).
pub const EXIT_INCOMPLETE: u8 = 2;
/// Exit code: samples are missing and some shard is being written now (wait).
pub const EXIT_RUNNING: u8 = 3;

/// What a dataset folder holds now.
#[derive(Serialize)]
pub struct Status {
    /// `dataset.name` of run.json.
    pub name: Value,
    /// `dataset.seed` of run.json.
    pub seed: Value,
    /// Samples of the dataset (`dataset.samples`).
    pub samples: u64,
    /// Distinct samples in the manifest.
    pub done: u64,
    /// Whether every sample is in the manifest.
    pub complete: bool,
    /// Whether any shard lock is held now.
    pub running: bool,
    /// Shard counts N named by the shard lock files and the marks of shards that ended
    /// (`.partial/shard-K-of-N.done`) in the folder.
    pub shard_counts_seen: Vec<u64>,
    /// The shard count the per-shard lines are for.
    pub shard_count: u64,
    /// What the per-shard lines count: None, samples; Some(F), units of F frames of the
    /// sequence samples (the manifest holds unit lines of a run with `--frames-per-unit F`).
    pub frames_per_unit: Option<u32>,
    /// The samples not finished of which some frames are (units of frames), by sample.
    pub partial: Vec<PartialSample>,
    /// Each shard of `shard_count`.
    pub shards: Vec<ShardStatus>,
    /// Each shard lock file left in `.partial/`.
    pub locks: Vec<LockStatus>,
    /// Shards of `shard_count` with samples missing and no process writing them.
    pub resubmit: Vec<u64>,
    /// `resubmit` as Slurm's `--array=` list ("0-2,5").
    pub resubmit_array: String,
    /// Manifest lines ignored: torn by a killed run, or not parsing.
    pub unreadable_lines: u64,
    /// The rate, if two of the latest samples have distinct file times.
    pub progress: Option<Progress>,
}

/// A sample not finished with some of its frames done.
#[derive(Serialize)]
pub struct PartialSample {
    /// Its index.
    pub sample: u64,
    /// Its frames whose units are in the manifest.
    pub frames_done: u64,
    /// Its frames.
    pub frames: u64,
}

/// One shard K of `shard_count`.
#[derive(Serialize)]
pub struct ShardStatus {
    /// K.
    pub index: u64,
    /// Its samples (or units, see `frames_per_unit`) in the manifest.
    pub done: u64,
    /// Its samples (or units) in the dataset.
    pub expected: u64,
    /// Whether its lock is held now.
    pub running: bool,
}

/// A shard lock file in `.partial/`.
#[derive(Serialize)]
pub struct LockStatus {
    /// "K/N", as the file name says.
    pub shard: String,
    /// `running` (held now), `stale` (left, held by nobody) or `orphaned` (held, but the pid
    /// it records does not exist on this host). An orphaned lock is still held, so its shard
    /// counts as running: a run of it would be refused.
    pub state: &'static str,
    /// The pid the holder recorded.
    pub pid: Option<u32>,
    /// The host the holder recorded.
    pub host: Option<String>,
    /// What could be told of the holder, for people.
    pub note: String,
}

/// The rate samples arrive at, from file times.
#[derive(Serialize)]
pub struct Progress {
    /// Samples finished per second, over the samples measured.
    pub samples_per_second: f64,
    /// For the missing samples, at that rate (0 when complete).
    pub seconds_left: f64,
    /// Seconds since the newest sample was written.
    pub seconds_since_last: f64,
    /// Samples the rate was measured over.
    pub measured_over: usize,
    /// Where the times come from.
    pub source: &'static str,
}

impl Status {
    /// The exit code scripts test: `EXIT_COMPLETE`, `EXIT_INCOMPLETE` or `EXIT_RUNNING`.
    pub fn exit_code(&self) -> u8 {
        match (self.complete, self.running) {
            (true, _) => EXIT_COMPLETE,
            (false, false) => EXIT_INCOMPLETE,
            (false, true) => EXIT_RUNNING,
        }
    }
}

/// The status of the dataset folder `root`, per shard of `shards` (1 to `MAX_SHARDS`; default:
/// the count of the shards running now, else the largest count `.partial/` names, else 1).
pub fn status(root: &Path, shards: Option<u64>) -> Result<Status> {
    if !root.is_dir() {
        bail!("{}: no such folder", root.display());
    }
    refuse_links(root)?;
    let run = identity(root)?;
    let samples = run
        .pointer("/dataset/samples")
        .and_then(Value::as_u64)
        .with_context(|| format!("{}: no dataset.samples", root.join(RUN_JSON).display()))?;
    let manifest = read_manifest(root, samples)?;
    let grid = manifest.grid();
    // Units of work: samples, or units of frames when the manifest has unit lines.
    let total_units = samples.saturating_mul(grid.map_or(1, |g| g.per_sample()));
    let locks = lock_states(root)?;
    let finished = shards_finished(root)?;
    let counts_seen: BTreeSet<u64> = locks
        .iter()
        .map(|l| l.shard.as_str())
        .chain(finished.iter().map(String::as_str))
        .filter_map(|shard| parse_shard(shard).map(|(_, n)| n))
        .filter(|&n| n <= total_units.clamp(1, MAX_SHARDS))
        .collect();
    let running_now: Vec<(u64, u64)> = locks
        .iter()
        .filter(|l| l.state != "stale")
        .filter_map(|l| parse_shard(&l.shard))
        .collect();
    let shard_count = match shards {
        Some(n) if !(1..=MAX_SHARDS).contains(&n) => {
            bail!("--shards {n}: expected a shard count from 1 to {MAX_SHARDS}")
        }
        Some(n) => n,
        None => running_now
            .iter()
            .map(|&(_, n)| n)
            .filter(|n| counts_seen.contains(n))
            .max()
            .or_else(|| counts_seen.last().copied())
            .unwrap_or(1),
    };
    let units = match grid {
        Some(grid) => manifest.units_done(grid),
        None => manifest.samples.iter().copied().collect(),
    };
    let shard_list = per_shard(units, total_units, shard_count, &running_now);
    let resubmit: Vec<u64> = shard_list
        .iter()
        .filter(|s| s.done < s.expected && !s.running)
        .map(|s| s.index)
        .collect();
    let done = manifest.samples.len() as u64;
    let complete = done == samples;
    Ok(Status {
        name: run.pointer("/dataset/name").cloned().unwrap_or(Value::Null),
        seed: run.pointer("/dataset/seed").cloned().unwrap_or(Value::Null),
        samples,
        done,
        complete,
        running: !running_now.is_empty(),
        shard_counts_seen: counts_seen.into_iter().collect(),
        shard_count,
        frames_per_unit: grid.map(|g| g.per_unit),
        partial: manifest.partial(),
        shards: shard_list,
        resubmit_array: array_list(&resubmit),
        resubmit,
        locks,
        unreadable_lines: manifest.unreadable,
        progress: progress(root, &manifest.latest, samples - done.min(samples)),
    })
}

/// run.json, refused unless it is a shmgen run record.
fn identity(root: &Path) -> Result<Value> {
    let path = root.join(RUN_JSON);
    let Some(bytes) = read_record(&path)? else {
        bail!(
            "{}: not a shmgen dataset (no run.json; give the folder `shmgen run --out` wrote)",
            root.display()
        );
    };
    let run: Value = serde_json::from_slice(&bytes).with_context(|| {
        format!(
            "{}: not a shmgen dataset (run.json does not parse)",
            root.display()
        )
    })?;
    let schema = run.get("schema").and_then(Value::as_str).unwrap_or("none");
    if schema != RUN_SCHEMA {
        bail!(
            "{}: not a shmgen dataset: run.json has schema {schema:?}, this shmgen reads {RUN_SCHEMA:?}",
            path.display()
        );
    }
    Ok(run)
}

/// What the manifest says: the distinct samples below the dataset's count, the first file of
/// each of the latest lines (for their times), and the lines that could not be read.
struct Manifest {
    samples: HashSet<u64>,
    /// The unit lines of the samples below the dataset's count, by sample.
    units: BTreeMap<u64, Vec<FrameSpan>>,
    /// The last unit line's span: the frames per unit and per sample of the latest run.
    last_unit: Option<FrameSpan>,
    latest: Vec<String>,
    unreadable: u64,
}

fn read_manifest(root: &Path, total: u64) -> Result<Manifest> {
    let path = root.join(MANIFEST);
    let mut samples = HashSet::new();
    let (mut units, mut last_unit) = (BTreeMap::<u64, Vec<FrameSpan>>::new(), None);
    let mut latest = VecDeque::with_capacity(RATE_WINDOW);
    let mut unreadable = 0;
    scan_entries(&path, |entry, offset, len| match entry {
        Entry::Sample(sample) if sample < total => {
            samples.insert(sample);
            if latest.len() == RATE_WINDOW {
                latest.pop_front();
            }
            latest.push_back((offset, len));
        }
        Entry::Unit(sample, span) if sample < total => {
            units.entry(sample).or_default().push(span);
            last_unit = Some(span);
        }
        _ => unreadable += 1,
    })?;
    Ok(Manifest {
        samples,
        units,
        last_unit,
        latest: first_files(&path, &latest)?,
        unreadable,
    })
}

impl Manifest {
    /// How the latest run dealt out frames, if the manifest has unit lines.
    fn grid(&self) -> Option<FrameUnits> {
        self.last_unit.map(|span| FrameUnits {
            frames: span.of,
            per_unit: span.per_unit,
        })
    }

    /// The units (numbered `sample × units per sample + unit`) done: every unit of a finished
    /// sample, and those a unit line holds.
    fn units_done(&self, grid: FrameUnits) -> Vec<u64> {
        let per_sample = grid.per_sample();
        let mut done = Vec::new();
        for &sample in &self.samples {
            done.extend((0..per_sample).map(|unit| sample * per_sample + unit));
        }
        for (sample, spans) in (self.units.iter()).filter(|(s, _)| !self.samples.contains(s)) {
            let held = |unit| spans.iter().any(|&span| grid.held_by(unit, span));
            done.extend(
                (0..per_sample)
                    .filter(|&u| held(u))
                    .map(|u| sample * per_sample + u),
            );
        }
        done
    }

    /// The samples not finished with frames done, and how many.
    fn partial(&self) -> Vec<PartialSample> {
        (self.units.iter())
            .filter(|(sample, _)| !self.samples.contains(sample))
            .map(|(&sample, spans)| PartialSample {
                sample,
                frames_done: frames_held(spans),
                frames: spans.iter().map(|s| u64::from(s.of)).max().unwrap_or(0),
            })
            .collect()
    }
}

/// Frames held by at least one of `spans`.
fn frames_held(spans: &[FrameSpan]) -> u64 {
    let mut spans: Vec<(u32, u32)> = spans.iter().map(|s| (s.start, s.end)).collect();
    spans.sort_unstable();
    let (mut held, mut reach) = (0u64, 0u32);
    for (start, end) in spans {
        let from = start.max(reach);
        if end > from {
            held += u64::from(end - from);
            reach = end;
        }
    }
    held
}

/// The first file each of the manifest's lines at (offset, length) lists.
fn first_files(path: &Path, lines: &VecDeque<(u64, usize)>) -> Result<Vec<String>> {
    #[derive(serde::Deserialize)]
    struct Line {
        #[serde(default)]
        files: Vec<String>,
    }
    let Some(mut file) = open_manifest(path)? else {
        return Ok(Vec::new());
    };
    let mut first = Vec::new();
    let mut bytes = Vec::new();
    for &(offset, len) in lines {
        bytes.resize(len, 0);
        file.seek(SeekFrom::Start(offset))?;
        // The manifest may have been sorted in place of the one scanned: a line not found
        // again is left out of the rate.
        if file.read_exact(&mut bytes).is_err() {
            continue;
        }
        if let Ok(line) = serde_json::from_slice::<Line>(&bytes) {
            first.extend(line.files.into_iter().next());
        }
    }
    Ok(first)
}

/// Each shard lock file, and whether it is held now.
fn lock_states(root: &Path) -> Result<Vec<LockStatus>> {
    let host = this_host();
    let mut states = Vec::new();
    for (path, shard) in shard_lock_files(root)? {
        let held = is_held_now(&path)?;
        let recorded = recorded_holder(&path);
        let (pid, holder_host) = parse_holder(&recorded);
        let here = holder_host.is_some() && holder_host == host.as_deref();
        let (state, note) = match (held, pid) {
            (false, _) => (
                "stale",
                format!("left by {recorded}, which ended without removing it; held by nobody"),
            ),
            (true, Some(pid)) if here && !pid_exists(pid) => (
                "orphaned",
                format!(
                    "held, but pid {pid} does not exist on this host (another pid namespace, e.g. a container, or a process it started holds it)"
                ),
            ),
            (true, _) if here => ("running", format!("{recorded} (alive)")),
            (true, _) => (
                "running",
                format!("{recorded} (another host: its pid cannot be checked from here)"),
            ),
        };
        states.push(LockStatus {
            shard,
            state,
            pid,
            host: holder_host.map(str::to_string),
            note,
        });
    }
    Ok(states)
}

/// Whether a process `pid` exists on this host.
#[cfg(unix)]
fn pid_exists(pid: u32) -> bool {
    // Pid 0 would ask about this process's group.
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return false;
    };
    if pid == 0 {
        return false;
    }
    // Signal 0 checks existence; EPERM means it exists but belongs to another user.
    let signalled = unsafe { libc::kill(pid, 0) } == 0;
    signalled || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

#[cfg(not(unix))]
fn pid_exists(_pid: u32) -> bool {
    true
}

/// Samples done and expected in each shard K of `count`.
fn per_shard(
    done: impl IntoIterator<Item = u64>,
    total: u64,
    count: u64,
    running: &[(u64, u64)],
) -> Vec<ShardStatus> {
    let mut done_in: BTreeMap<u64, u64> = BTreeMap::new();
    for sample in done {
        *done_in.entry(sample % count).or_default() += 1;
    }
    (0..count.min(total.max(1)))
        .map(|index| ShardStatus {
            index,
            done: done_in.get(&index).copied().unwrap_or(0),
            expected: if index < total {
                (total - index - 1) / count + 1
            } else {
                0
            },
            running: running.contains(&(index, count)),
        })
        .collect()
}

/// Indices as Slurm writes an array: runs of consecutive ones as ranges, "0-2,5".
pub fn array_list(indices: &[u64]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        parts.push(if i == j {
            indices[i].to_string()
        } else {
            format!("{}-{}", indices[i], indices[j])
        });
        i = j + 1;
    }
    parts.join(",")
}

/// The rate of the latest samples, from the modification times of their first files.
fn progress(root: &Path, latest: &[String], missing: u64) -> Option<Progress> {
    let times: Vec<SystemTime> = latest
        .iter()
        .filter(|f| is_relative_inside(f))
        .filter_map(|f| std::fs::symlink_metadata(root.join(f)).ok())
        .filter_map(|m| m.modified().ok())
        .collect();
    let (first, last) = (times.iter().min()?, times.iter().max()?);
    let span = last.duration_since(*first).unwrap_or(Duration::ZERO);
    if times.len() < 2 || span.is_zero() {
        return None;
    }
    let rate = (times.len() - 1) as f64 / span.as_secs_f64();
    let since = SystemTime::now()
        .duration_since(*last)
        .unwrap_or(Duration::ZERO);
    Some(Progress {
        samples_per_second: rate,
        seconds_left: missing as f64 / rate,
        seconds_since_last: since.as_secs_f64(),
        measured_over: times.len(),
        source: "modification times of the files of the latest samples in manifest.jsonl (it records no times)",
    })
}

/// Whether a manifest's path stays inside the dataset.
fn is_relative_inside(relative: &str) -> bool {
    relative
        .split('/')
        .all(|p| !p.is_empty() && p != "." && p != ".." && !p.contains('\\'))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_are_runs_of_consecutive_indices() {
        assert_eq!(array_list(&[]), "");
        assert_eq!(array_list(&[3]), "3");
        assert_eq!(array_list(&[0, 1, 2, 5, 7, 8]), "0-2,5,7-8");
    }

    #[test]
    fn shards_expect_the_samples_congruent_to_their_index() {
        // 10 samples in 4 shards: 0,4,8 / 1,5,9 / 2,6 / 3,7.
        let done: HashSet<u64> = [0, 4, 9, 3].into();
        let shards = per_shard(done.iter().copied(), 10, 4, &[(2, 4)]);
        let got: Vec<(u64, u64, bool)> = shards
            .iter()
            .map(|s| (s.done, s.expected, s.running))
            .collect();
        assert_eq!(
            got,
            vec![(2, 3, false), (1, 3, false), (0, 2, true), (1, 2, false)]
        );
        // More shards than samples: the shards without samples are not listed.
        assert_eq!(per_shard(done, 2, 4, &[]).len(), 2);
    }
}
