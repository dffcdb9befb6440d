//! A part of a dataset: a folder `shmgen run --shard` wrote on one node, finished or not,
//! read as untrusted input for `shmgen merge`.
//!
//! Unlike [`super::Dataset`], a part may lack samples (other shards wrote them elsewhere) and
//! may end in a torn manifest line (a killed run): only the samples its manifest lists are
//! its own, and each of them must record the size and BLAKE3 hash of every file, because a
//! merge passes on no byte it has not checked. Files no line lists are a run's unfinished
//! work: they are counted, never read. A part written in units of frames
//! (`run --frames-per-unit`) may hold unit lines of samples it has not finished: each is a
//! finished unit, passed on as it is (OUT seals a sample once its units cover it).

use super::content::Check;
use super::files::open_inside;
use super::{Line, Run, each_line, read_run, sample_of};
use anyhow::{Result, bail};
use serde_json::Value;
use std::collections::{BTreeMap, HashSet};
use std::fs::{self, File};
use std::path::{Path, PathBuf};

/// A folder holding some finished samples of a dataset.
pub struct Part {
    root: PathBuf,
    /// `run.json`'s bytes, as written.
    pub run_bytes: Vec<u8>,
    /// `run.json`, as parsed: what identifies the dataset.
    pub run: Value,
    /// The samples the dataset has (all parts together).
    pub total: u64,
    /// Its finished samples by index.
    pub samples: BTreeMap<u64, PartSample>,
    /// Its finished units of frames of sequence samples, by (sample, first frame, end frame),
    /// for the samples it has not finished.
    pub units: BTreeMap<(u64, u32, u32), PartSample>,
    /// Manifest lines that are torn or do not parse (a run killed while appending).
    pub torn: u64,
    /// Files under `samples/` that no manifest line lists (samples a run did not finish).
    pub unlisted: u64,
}

/// A unit line of the manifest (`output::folder` writes them): frames [start, end) of a
/// sample, with their files.
#[derive(serde::Deserialize)]
struct UnitLine {
    unit: UnitOf,
    files: Vec<String>,
    #[serde(default)]
    hashes: BTreeMap<String, Check>,
}

#[derive(serde::Deserialize)]
struct UnitOf {
    sample: u64,
    frames: [u32; 2],
}

/// A finished sample (or unit of frames) of a part.
pub struct PartSample {
    /// Its manifest line, as written (newline included).
    pub line: Vec<u8>,
    /// Its files with their recorded sizes and hashes, by path relative to the root.
    pub files: BTreeMap<String, Check>,
}

impl Part {
    /// Reads the part at `root`: `run.json`, the manifest's finished samples (each of whose
    /// files must have a recorded size and hash), and how many files of unfinished samples
    /// lie beside them. Refuses a folder that is not a shmgen dataset, a manifest listing
    /// files outside its sample or samples the dataset does not have, and any link in
    /// `samples/`.
    pub fn open(root: &Path) -> Result<Part> {
        let Run {
            bytes,
            value,
            total,
        } = read_run(root)?;
        let mut part = Part {
            root: root.to_path_buf(),
            run_bytes: bytes,
            run: value,
            total,
            samples: BTreeMap::new(),
            units: BTreeMap::new(),
            torn: 0,
            unlisted: 0,
        };
        if fs::symlink_metadata(root.join("manifest.jsonl")).is_ok() {
            part.read_lines()?;
        }
        let finished = &part.samples;
        part.units
            .retain(|(sample, _, _), _| !finished.contains_key(sample));
        part.unlisted = part.count_unlisted()?;
        Ok(part)
    }

    fn read_lines(&mut self) -> Result<()> {
        let name = self.root.join("manifest.jsonl").display().to_string();
        let (total, samples, torn) = (self.total, &mut self.samples, &mut self.torn);
        let units = &mut self.units;
        each_line(&self.root, |number, bytes, parsed| {
            let unit = (parsed.is_none() && bytes.ends_with(b"\n"))
                .then(|| serde_json::from_slice::<UnitLine>(bytes).ok())
                .flatten();
            let (line, key) = match (parsed, unit) {
                (Some(line), _) => (line, None),
                (None, Some(u)) if u.unit.frames[0] < u.unit.frames[1] => {
                    let [start, end] = u.unit.frames;
                    let line = Line {
                        sample: u.unit.sample,
                        files: u.files,
                        hashes: u.hashes,
                    };
                    (line, Some((u.unit.sample, start, end)))
                }
                _ => {
                    *torn += 1;
                    return Ok(());
                }
            };
            if line.sample >= total {
                bail!(
                    "{name}: line {number} lists sample {}, but run.json has {total} samples",
                    line.sample
                );
            }
            sample_of(line.sample, line.files.clone())?;
            let mut files = BTreeMap::new();
            for file in &line.files {
                let Some(check) = line.hashes.get(file) else {
                    bail!(
                        "{name}: line {number} records no size and hash of {file} (written by an older shmgen); merge passes on only checked bytes: render this part again with this shmgen"
                    );
                };
                files.insert(file.clone(), *check);
            }
            let finished = PartSample {
                line: bytes.to_vec(),
                files,
            };
            // The first line of a sample (or unit) is the one every reader takes.
            match key {
                Some(key) => units.entry(key).or_insert(finished),
                None => samples.entry(line.sample).or_insert(finished),
            };
            Ok(())
        })
    }

    /// Files under `samples/` no manifest line lists, refusing links (a part is read as
    /// untrusted input, and a link there could pass a file from outside into the merge).
    fn count_unlisted(&self) -> Result<u64> {
        let listed: HashSet<&str> = (self.samples.values())
            .chain(self.units.values())
            .flat_map(|s| s.files.keys().map(String::as_str))
            .collect();
        let mut unlisted = 0;
        for (relative, is_folder) in entries_without_links(&self.root, "samples")? {
            if !is_folder {
                unlisted += 1;
                continue;
            }
            for (file, is_folder) in entries_without_links(&self.root, &relative)? {
                unlisted += u64::from(is_folder || !listed.contains(file.as_str()));
            }
        }
        Ok(unlisted)
    }

    /// The part's folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// A path relative to the part's root, made absolute.
    pub fn path(&self, relative: &str) -> PathBuf {
        self.root.join(relative)
    }

    /// The listed file `relative`, opened as `files` says (a regular file inside the part, no
    /// link followed), refused unless of the recorded size; with its record, to check the
    /// bytes against as they are read.
    pub fn open_file(&self, relative: &str, check: Check) -> Result<File> {
        let file = open_inside(&self.root, relative)?;
        check.size(
            file.metadata()?.len(),
            &self.path(relative).display().to_string(),
        )?;
        Ok(file)
    }
}

/// The entries of the folder `relative` of `root` (none if it is missing) as (path relative
/// to the root, whether a folder), refusing links and anything but files and folders.
fn entries_without_links(root: &Path, relative: &str) -> Result<Vec<(String, bool)>> {
    let folder = root.join(relative);
    if fs::symlink_metadata(&folder).is_ok_and(|m| m.file_type().is_symlink()) {
        bail!(
            "{}: is a symbolic link; a merge takes nothing from a part that holds links",
            folder.display()
        );
    }
    let read = match fs::read_dir(&folder) {
        Ok(read) => read,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => bail!("{}: {e}", folder.display()),
    };
    let mut found = Vec::new();
    for entry in read {
        let entry = entry?;
        let kind = entry.file_type()?;
        if kind.is_symlink() {
            bail!(
                "{}: is a symbolic link; a dataset's files must be regular files inside it, and a merge takes nothing from a part that holds links",
                entry.path().display()
            );
        }
        let name = entry.file_name().to_string_lossy().to_string();
        found.push((format!("{relative}/{name}"), kind.is_dir()));
    }
    Ok(found)
}
