//! `shmgen merge OUT PART...`: the folders shards wrote on different nodes gathered into one
//! dataset, with the bytes a single run gives.
//!
//! Owns: deciding what each part gives (`plan`) and placing it, every byte checked. Each part
//! is untrusted input read through `dataset::Part` (no links, bounded reads, recorded hashes);
//! all parts must be the same dataset (equal run.json), and a sample found in several parts
//! (or already in OUT) must have the same files with the same hashes, else nothing is written.
//! OUT is written through `output::MergeTarget`: sample by sample, files before manifest line,
//! so a killed merge leaves a partial dataset that the same merge (or `shmgen run`) finishes.
//! Files are hard-linked where the filesystem allows (as `export` does), copied otherwise.
//! Parts written in units of frames (`run --frames-per-unit`, one sequence spread over nodes)
//! give their finished units of unfinished samples: each is placed with its unit line, and
//! OUT seals a sample (its one line, as a single run writes it) once its units cover it.

use super::staging::Placer;
use crate::dataset::{Check, Part};
use crate::output::{MergeTarget, differences, refuse_data_target};
use anyhow::{Context, Result, bail};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What a merge did.
#[derive(Debug, Default)]
pub struct MergeSummary {
    /// Each part, with the samples and units of frames taken from it.
    pub taken: Vec<(PathBuf, u64)>,
    /// Samples OUT had already (identical in the parts that have them too).
    pub already: u64,
    /// Samples found in more than one part (identical), taken once.
    pub duplicates: u64,
    /// Units of frames of samples no part finished, taken from the parts.
    pub units: u64,
    /// Files of unfinished samples in the parts (no manifest line lists them) and torn
    /// manifest lines: ignored.
    pub unfinished: u64,
    /// Samples of the dataset neither OUT nor any part has.
    pub missing: u64,
    /// The first of them.
    pub first_missing: Option<u64>,
    /// Samples of the dataset.
    pub total: u64,
    /// Files hard-linked to the parts' and files copied.
    pub linked: usize,
    /// Files copied (the filesystem refused a link).
    pub copied: usize,
}

/// The samples to take and from which part, decided before anything is written.
struct Plan {
    /// Sample → index of the part it is taken from.
    take: BTreeMap<u64, usize>,
    /// (sample, first frame, end frame) of a unit → index of the part it is taken from.
    take_units: BTreeMap<(u64, u32, u32), usize>,
    already: u64,
    duplicates: u64,
}

/// Merges the finished samples of `parts` into `out` (created, or a partial dataset of the
/// same identity added to).
pub fn merge(out: &Path, parts: &[PathBuf]) -> Result<MergeSummary> {
    if parts.is_empty() {
        bail!("merge needs at least one PART (a folder `shmgen run --shard K/N` wrote)");
    }
    refuse_data_target(out, "OUT", None, true)?;
    for part in parts {
        refuse_data_target(out, "OUT", Some(part), true)?;
    }
    let parts: Vec<Part> = parts
        .iter()
        .map(|p| Part::open(p).with_context(|| format!("PART {}", p.display())))
        .collect::<Result<_>>()?;
    refuse_other_datasets(&parts)?;
    let existing = existing_dataset(out, &parts[0])?;
    let plan = plan(&parts, existing.as_ref())?;

    let total = parts[0].total;
    // OUT keeps its run.json; a new OUT gets the first part's (as the first shard's run
    // writes it into a shared folder).
    let run_json = existing.as_ref().unwrap_or(&parts[0]).run_bytes.clone();
    let identity = |_: Option<&Value>| Ok(run_json.clone());
    let target = MergeTarget::open(out, &identity)?;
    let mut placer = Placer::new(false);
    let mut taken = vec![0u64; parts.len()];
    let samples = (plan.take.iter()).map(|(&s, &from)| (s, from, &parts[from].samples[&s]));
    let units = (plan.take_units.iter()).map(|(key, &from)| (key.0, from, &parts[from].units[key]));
    for (sample, from, finished) in samples.chain(units) {
        let part = &parts[from];
        let mut arrival = target.arrive(sample)?;
        for (relative, &check) in &finished.files {
            let to = arrival.place(relative);
            let file = part.open_file(relative, check)?;
            let name = part.path(relative).display().to_string();
            placer.place_opened(file, Some(check), &part.path(relative), &name, &to)?;
        }
        target.commit(arrival, &finished.line)?;
        taken[from] += 1;
    }
    target.finish(total)?;

    // What OUT holds now, its samples sealed from units included.
    let merged = Part::open(out).with_context(|| format!("OUT {}", out.display()))?;
    let have = |s: &u64| merged.samples.contains_key(s);
    let missing = (0..total).filter(|s| !have(s)).count() as u64;
    Ok(MergeSummary {
        taken: parts
            .iter()
            .map(|p| p.root().to_path_buf())
            .zip(taken)
            .collect(),
        already: plan.already,
        duplicates: plan.duplicates,
        units: plan.take_units.len() as u64,
        unfinished: parts.iter().map(|p| p.torn + p.unlisted).sum(),
        missing,
        first_missing: (0..total).find(|s| !have(s)),
        total,
        linked: placer.linked,
        copied: placer.copied,
    })
}

/// Refuses parts whose run.json differs from the first part's, naming the part and what
/// differs.
fn refuse_other_datasets(parts: &[Part]) -> Result<()> {
    let first = &parts[0];
    for part in &parts[1..] {
        if !same_dataset(&part.run, &first.run) {
            bail!(
                "PART {} is not the same dataset as PART {}: {}; only shards of one run (same recipe, parameters and seed) merge",
                part.root().display(),
                first.root().display(),
                differences(&first.run, &part.run, "first part vs this one")
            );
        }
    }
    Ok(())
}

/// The dataset already in `out`, if it has a run.json: refused unless it is the parts'.
fn existing_dataset(out: &Path, first: &Part) -> Result<Option<Part>> {
    if std::fs::symlink_metadata(out.join("run.json")).is_err() {
        let holds_something = std::fs::read_dir(out).is_ok_and(|mut d| d.next().is_some());
        if holds_something {
            bail!(
                "OUT {} is not empty and holds no shmgen dataset; merge into a new folder (or a partial dataset of the same run)",
                out.display()
            );
        }
        return Ok(None);
    }
    let existing = Part::open(out).with_context(|| format!("OUT {}", out.display()))?;
    if !same_dataset(&existing.run, &first.run) {
        bail!(
            "OUT {} holds a different dataset than the parts: {}; merge into a new folder",
            out.display(),
            differences(&existing.run, &first.run, "OUT vs the parts")
        );
    }
    Ok(Some(existing))
}

/// Whether two run.json describe the same dataset: equal but for `recipe.file`, the name of
/// the recipe's file, which no output byte depends on (its content is `recipe.hash`), so that
/// nodes may run renamed copies of the recipe, as `run` resumes from one
/// (`pipeline::record::run_json`).
fn same_dataset(a: &Value, b: &Value) -> bool {
    let identity = |run: &Value| {
        let mut run = run.clone();
        if let Some(recipe) = run.get_mut("recipe").and_then(Value::as_object_mut) {
            recipe.remove("file");
        }
        run
    };
    identity(a) == identity(b)
}

/// Which part each sample is taken from: the first that has it. A sample in several parts,
/// or in a part and OUT, must have the same files with the same sizes and hashes there.
fn plan(parts: &[Part], existing: Option<&Part>) -> Result<Plan> {
    let mut plan = Plan {
        take: BTreeMap::new(),
        take_units: BTreeMap::new(),
        already: 0,
        duplicates: 0,
    };
    if let Some(out) = existing {
        plan.already = out.samples.len() as u64;
    }
    for (index, part) in parts.iter().enumerate() {
        for (&sample, finished) in &part.samples {
            let (other, where_) = match (existing, plan.take.get(&sample)) {
                (Some(out), _) if out.samples.contains_key(&sample) => (out, "OUT"),
                (_, Some(&first)) => (&parts[first], "PART"),
                _ => {
                    plan.take.insert(sample, index);
                    continue;
                }
            };
            let theirs = &other.samples[&sample].files;
            if let Some(file) = first_difference(theirs, &finished.files) {
                bail!(
                    "sample {sample} differs between {where_} {} and PART {} ({file}); they are not the same samples, so nothing was merged",
                    other.root().display(),
                    part.root().display()
                );
            }
            if where_ == "PART" {
                plan.duplicates += 1;
            }
        }
    }
    plan_units(parts, existing, &mut plan)?;
    Ok(plan)
}

/// Which part each unit of frames is taken from: the first that has it, for the samples
/// neither OUT nor any part finished and the units OUT does not have. A unit in several parts
/// must have the same files with the same sizes and hashes there.
fn plan_units(parts: &[Part], existing: Option<&Part>, plan: &mut Plan) -> Result<()> {
    let finished = |s: &u64| {
        plan.take.contains_key(s) || existing.is_some_and(|out| out.samples.contains_key(s))
    };
    let mut take_units: BTreeMap<(u64, u32, u32), usize> = BTreeMap::new();
    for (index, part) in parts.iter().enumerate() {
        for (key, unit) in part.units.iter().filter(|(key, _)| !finished(&key.0)) {
            if existing.is_some_and(|out| out.units.contains_key(key)) {
                continue;
            }
            let Some(&first) = take_units.get(key) else {
                take_units.insert(*key, index);
                continue;
            };
            if let Some(file) = first_difference(&parts[first].units[key].files, &unit.files) {
                bail!(
                    "frames {}–{} of sample {} differ between PART {} and PART {} ({file}); they are not the same frames, so nothing was merged",
                    key.1,
                    key.2 - 1,
                    key.0,
                    parts[first].root().display(),
                    part.root().display()
                );
            }
        }
    }
    plan.take_units = take_units;
    Ok(())
}

/// The first file (by name) listed by one sample's record and not the other, or recorded with
/// another size or hash, and how.
fn first_difference(a: &BTreeMap<String, Check>, b: &BTreeMap<String, Check>) -> Option<String> {
    let names: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
    let mut differing = names
        .into_iter()
        .filter(|name| a.get(*name) != b.get(*name));
    differing
        .next()
        .map(|name| match (a.get(name), b.get(name)) {
            (Some(_), Some(_)) => format!("{name} has other bytes"),
            _ => format!("{name} is in one only"),
        })
}
