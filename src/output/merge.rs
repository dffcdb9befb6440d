//! The dataset folder a merge writes (`shmgen merge OUT PART...`): finished samples arriving
//! from other folders, committed as a run commits its own.
//!
//! The merge holds the folder lock from start to end, so no run finishes the folder (and
//! tidies away the merge's staging) meanwhile; runs writing shards go on, and one that
//! starts waits. Each sample's files are placed in `.partial/merge/` (a hard link or a
//! checked copy, made by the caller), renamed into place, and only then is its manifest line
//! appended: a killed merge leaves a partial dataset that a run or another merge finishes,
//! never a manifest listing a file that is not there.

use super::folder::{DatasetFolder, Identity, STAGING, remove_all};
use super::lock::Lock;
use anyhow::{Context, Result, bail};
use std::fs::{self, File};
use std::path::{Path, PathBuf};

/// A dataset folder opened to receive finished samples.
pub struct MergeTarget {
    folder: DatasetFolder,
    lock: Lock,
    staging: PathBuf,
}

/// A sample arriving: the paths its files are placed at before being renamed into place.
pub struct Arrival {
    sample: u64,
    dir: PathBuf,
    files: Vec<String>,
}

impl Arrival {
    /// Where to place the file `relative` (relative to the dataset root) of the sample.
    pub fn place(&mut self, relative: &str) -> PathBuf {
        let path = self.dir.join(self.files.len().to_string());
        self.files.push(relative.to_string());
        path
    }
}

impl MergeTarget {
    /// Opens `root` (created if missing) to receive samples of the dataset whose run.json
    /// `identity` gives: a folder holding nothing gets that run.json, one holding the same
    /// dataset is added to, anything else is refused (no `--force`: a merge deletes nothing).
    pub fn open(root: &Path, identity: Identity) -> Result<MergeTarget> {
        let existed = root.exists();
        fs::create_dir_all(root).with_context(|| format!("creating {}", root.display()))?;
        let folder = DatasetFolder {
            root: root.to_path_buf(),
            shard: None,
        };
        let opened = folder.lock_folder().and_then(|lock| {
            folder.take_for(identity, false)?;
            folder.terminate_torn_line()?;
            Ok(lock)
        });
        let lock = match opened {
            Ok(lock) => lock,
            Err(e) => {
                // Leave a refused folder as it was.
                let _ = fs::remove_dir_all(folder.path(STAGING));
                if !existed {
                    let _ = fs::remove_dir(root);
                }
                return Err(e);
            }
        };
        let staging = folder.path(STAGING).join("merge");
        remove_all(&staging)?;
        Ok(MergeTarget {
            folder,
            lock,
            staging,
        })
    }

    /// A fresh staging folder for `sample`.
    pub fn arrive(&self, sample: u64) -> Result<Arrival> {
        let dir = self.staging.join(format!("{sample:06}"));
        remove_all(&dir)?;
        fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        Ok(Arrival {
            sample,
            dir,
            files: Vec::new(),
        })
    }

    /// Moves the placed files into place, then appends the sample's manifest line `line`
    /// (as its part recorded it, newline included), which must list exactly those files.
    pub fn commit(&self, arrival: Arrival, line: &[u8]) -> Result<()> {
        if !line.ends_with(b"\n") {
            bail!(
                "sample {}: a manifest line ends with a newline",
                arrival.sample
            );
        }
        self.folder.move_into_place(&arrival.dir, &arrival.files)?;
        self.folder.append_line(line)?;
        // rename(2) between two hard links of one file does nothing and leaves the staged
        // link: a merge killed after placing a sample and resumed links the same files again.
        remove_all(&arrival.dir)
    }

    /// Ends the merge: sorts the manifest once it lists all `total` samples (so the folder
    /// has the bytes a single run gives), removes what interrupted runs and merges left, and
    /// releases the folder. Returns whether the dataset is complete.
    pub fn finish(self, total: u64) -> Result<bool> {
        remove_all(&self.staging)?;
        let complete = self.folder.tidy(total)?;
        self.lock.remove()?;
        let _ = fs::remove_dir(self.folder.path(STAGING));
        Ok(complete)
    }
}

/// Whether the opened `file` and the file at `path` (not followed if a link) are one.
#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), fs::symlink_metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// Whether the opened `file` and the file at `path` (not followed if a link) are one.
#[cfg(not(unix))]
fn same_file(_: &File, path: &Path) -> bool {
    fs::symlink_metadata(path).is_ok_and(|m| m.is_file())
}

/// Hard-links `from` (opened as `file`) to `to`, and makes sure the link is that very file:
/// had `from` been swapped for a link meanwhile, `to` would hold the link. False (nothing left
/// at `to`) when the filesystem refuses the link (another filesystem, or no links).
pub fn hard_link_opened(file: &File, from: &Path, to: &Path) -> Result<bool> {
    if fs::hard_link(from, to).is_err() {
        return Ok(false);
    }
    if !same_file(file, to) {
        fs::remove_file(to).with_context(|| format!("removing {}", to.display()))?;
        bail!(
            "{}: changed while being read (it is no longer the file that was opened)",
            from.display()
        );
    }
    Ok(true)
}
