//! The dataset folder: run.json, manifest.jsonl, staging and commit of samples.

use anyhow::{Context, Result, bail};
use std::collections::BTreeSet;
use std::fs::{self, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

const RUN_JSON: &str = "run.json";
const MANIFEST: &str = "manifest.jsonl";
const STAGING: &str = ".partial";
const SAMPLES: &str = "samples";

/// A dataset's output folder: `run.json`, `manifest.jsonl` and the committed samples, with a
/// staging area for samples being written.
pub struct DatasetFolder {
    root: PathBuf,
}

/// A sample being written: its files go into a private staging folder first.
pub struct SampleStage {
    sample: u64,
    dir: PathBuf,
    files: Vec<String>,
    /// Bytes staged so far.
    pub bytes: u64,
}

impl SampleStage {
    /// Writes one file of the sample (path relative to the dataset root) into staging.
    pub fn write(&mut self, relative: String, bytes: &[u8]) -> Result<()> {
        let staged = self.dir.join(self.files.len().to_string());
        fs::write(&staged, bytes).with_context(|| format!("writing {}", staged.display()))?;
        self.bytes += bytes.len() as u64;
        self.files.push(relative);
        Ok(())
    }
}

impl DatasetFolder {
    /// Opens `root` for the dataset described by `run_json`. A folder holding another
    /// dataset (different run.json) is refused unless `force`, which clears what shmgen wrote
    /// there before; files shmgen did not write are never touched.
    pub fn open(root: &Path, run_json: &[u8], force: bool) -> Result<DatasetFolder> {
        let folder = DatasetFolder {
            root: root.to_path_buf(),
        };
        fs::create_dir_all(root)
            .with_context(|| format!("creating output folder {}", root.display()))?;
        match fs::read(folder.path(RUN_JSON)) {
            Ok(existing) if existing == run_json => {
                folder.terminate_torn_line()?;
                return Ok(folder);
            }
            Ok(_) if !force => bail!(
                "{} holds a different dataset (its run.json differs: another recipe, seed, parameters or shmgen version); \
                 choose another --out or pass --force to replace it",
                root.display()
            ),
            Ok(_) => folder.clear()?,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                let foreign = fs::read_dir(root)?
                    .filter_map(|e| e.ok())
                    .any(|e| e.file_name() != STAGING);
                if foreign && !force {
                    bail!(
                        "{} is not empty and holds no shmgen dataset; choose another --out or pass --force to write into it",
                        root.display()
                    );
                }
            }
            Err(e) => {
                return Err(e)
                    .with_context(|| format!("reading {}", folder.path(RUN_JSON).display()));
            }
        }
        write_atomic(&folder.path(RUN_JSON), run_json)?;
        Ok(folder)
    }

    /// A crash can leave a manifest line without its newline; end it so that the next
    /// appended line stays parseable (the fragment itself is ignored).
    fn terminate_torn_line(&self) -> Result<()> {
        let path = self.path(MANIFEST);
        match fs::read(&path) {
            Ok(bytes) if bytes.last().is_some_and(|&b| b != b'\n') => {
                OpenOptions::new()
                    .append(true)
                    .open(&path)?
                    .write_all(b"\n")?;
            }
            _ => {}
        }
        Ok(())
    }

    fn path(&self, relative: &str) -> PathBuf {
        self.root.join(relative)
    }

    fn clear(&self) -> Result<()> {
        for dir in [SAMPLES, STAGING] {
            match fs::remove_dir_all(self.path(dir)) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e.into()),
                _ => {}
            }
        }
        for file in [MANIFEST, RUN_JSON] {
            match fs::remove_file(self.path(file)) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e.into()),
                _ => {}
            }
        }
        Ok(())
    }

    /// Samples listed in the manifest. Lines that do not parse (a torn write after a crash)
    /// are ignored: their sample is simply redone.
    pub fn completed(&self) -> Result<BTreeSet<u64>> {
        let text = match fs::read_to_string(self.path(MANIFEST)) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(BTreeSet::new()),
            Err(e) => return Err(e.into()),
        };
        Ok(text
            .split_inclusive('\n')
            .filter(|l| l.ends_with('\n'))
            .filter_map(manifest_sample)
            .collect())
    }

    /// A fresh staging area for `sample`, discarding leftovers of an interrupted attempt.
    pub fn stage(&self, sample: u64) -> Result<SampleStage> {
        let dir = self.path(STAGING).join(format!("{sample:06}"));
        if dir.exists() {
            fs::remove_dir_all(&dir)?;
        }
        fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        Ok(SampleStage {
            sample,
            dir,
            files: Vec::new(),
            bytes: 0,
        })
    }

    /// Moves the staged files into place, then records the sample in the manifest.
    pub fn commit(&self, stage: SampleStage, views: u32) -> Result<()> {
        for (i, relative) in stage.files.iter().enumerate() {
            let target = self.path(relative);
            if let Some(parent) = target.parent() {
                fs::create_dir_all(parent)?;
            }
            fs::rename(stage.dir.join(i.to_string()), &target)
                .with_context(|| format!("moving {} into place", target.display()))?;
        }
        let line =
            serde_json::json!({ "sample": stage.sample, "views": views, "files": stage.files });
        let mut line = serde_json::to_vec(&line)?;
        line.push(b'\n');
        // One write of a whole line in append mode: concurrent shards never interleave lines.
        let mut manifest = OpenOptions::new()
            .create(true)
            .append(true)
            .open(self.path(MANIFEST))?;
        manifest.write_all(&line)?;
        fs::remove_dir(&stage.dir)?;
        Ok(())
    }

    /// Once every sample of the dataset is in the manifest, rewrites it in sample order so
    /// that the finished dataset has the same bytes however it was run. Returns whether the
    /// dataset is complete.
    pub fn finalize(&self, total: u64) -> Result<bool> {
        let done = self.completed()?;
        if done.len() as u64 != total
            || done
                .iter()
                .next_back()
                .is_some_and(|&last| last + 1 != total)
        {
            return Ok(false);
        }
        let text = fs::read_to_string(self.path(MANIFEST))?;
        let mut lines: Vec<(u64, &str)> = text
            .split_inclusive('\n')
            .filter(|l| l.ends_with('\n'))
            .filter_map(|l| manifest_sample(l).map(|s| (s, l)))
            .collect();
        lines.sort_by_key(|&(s, _)| s);
        lines.dedup_by_key(|&mut (s, _)| s);
        let sorted: String = lines.into_iter().map(|(_, l)| l).collect();
        if sorted != text {
            write_atomic(&self.path(MANIFEST), sorted.as_bytes())?;
        }
        let _ = fs::remove_dir(self.path(STAGING));
        Ok(true)
    }
}

fn manifest_sample(line: &str) -> Option<u64> {
    serde_json::from_str::<serde_json::Value>(line)
        .ok()?
        .get("sample")?
        .as_u64()
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    fs::rename(&tmp, path)
        .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_a_different_dataset_unless_forced() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("ds");
        DatasetFolder::open(&root, b"{\"a\":1}", false).unwrap();
        DatasetFolder::open(&root, b"{\"a\":1}", false).unwrap();
        let err = DatasetFolder::open(&root, b"{\"a\":2}", false)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("different dataset"), "{err}");
        DatasetFolder::open(&root, b"{\"a\":2}", true).unwrap();
        assert_eq!(fs::read(root.join(RUN_JSON)).unwrap(), b"{\"a\":2}");
    }

    #[test]
    fn torn_manifest_lines_are_ignored_and_finalize_sorts() {
        let dir = tempfile::tempdir().unwrap();
        let folder = DatasetFolder::open(dir.path(), b"{}", true).unwrap();
        for s in [2u64, 0, 1] {
            let mut stage = folder.stage(s).unwrap();
            stage.write(format!("samples/x{s}.txt"), b"data").unwrap();
            folder.commit(stage, 1).unwrap();
        }
        let mut f = OpenOptions::new()
            .append(true)
            .open(dir.path().join(MANIFEST))
            .unwrap();
        f.write_all(b"{\"sample\": 7, \"vie").unwrap();
        assert_eq!(folder.completed().unwrap(), BTreeSet::from([0, 1, 2]));
        assert!(!folder.finalize(4).unwrap());
        assert!(folder.finalize(3).unwrap());
        let text = fs::read_to_string(dir.path().join(MANIFEST)).unwrap();
        let order: Vec<u64> = text.lines().filter_map(manifest_sample).collect();
        assert_eq!(order, vec![0, 1, 2]);
        assert!(!dir.path().join(STAGING).exists());
    }
}
