//! Where an export is written: a hidden sibling of `--out` renamed into place at the end, and
//! how files get there (hard link, copy, or new bytes).
//!
//! Images are hard-linked where the filesystem allows: an export of a 100 GB dataset then
//! costs no space, and unlike a symbolic link it keeps working when the dataset is moved or
//! deleted and is followed by every tool (tar, rsync, Python). A link that fails (another
//! filesystem, a filesystem without links) falls back to a copy. Either way the exported bytes
//! are the dataset's, so the export's content is the same.

use crate::dataset::{Check, Dataset, check_stream};
use crate::output::{hard_link_opened, refuse_data_target};
use anyhow::{Context, Result, bail};
use std::fs::{self, File};
use std::io;
use std::path::{Path, PathBuf};

/// A hidden folder beside `--out` that becomes `--out` on commit and is removed otherwise.
pub(super) struct Staging {
    tmp: PathBuf,
    out: PathBuf,
    committed: bool,
}

const MARK: &str = ".export-";

impl Staging {
    /// Refuses an `out` that exists or lies inside a dataset or an export (`source` or any
    /// other); removes what killed exports to the same `out` left; creates the hidden folder.
    pub(super) fn create(out: &Path, source: &Path) -> Result<Staging> {
        if fs::symlink_metadata(out).is_ok() {
            bail!(
                "--out {}: already exists; an export never writes into an existing folder (remove it or choose another)",
                out.display()
            );
        }
        let name = out
            .file_name()
            .and_then(|n| n.to_str())
            .with_context(|| format!("--out {}: needs a folder name", out.display()))?;
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        refuse_data_target(out, "--out", Some(source), false)?;
        fs::create_dir_all(&parent).with_context(|| format!("creating {}", parent.display()))?;
        remove_dead(&parent, name)?;
        let tmp = parent.join(format!(".{name}{MARK}{}", std::process::id()));
        if tmp.exists() {
            fs::remove_dir_all(&tmp).with_context(|| format!("removing {}", tmp.display()))?;
        }
        fs::create_dir(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
        Ok(Staging {
            tmp,
            out: out.to_path_buf(),
            committed: false,
        })
    }

    /// The folder to write into.
    pub(super) fn path(&self) -> &Path {
        &self.tmp
    }

    /// Renames the finished export to `--out`.
    pub(super) fn commit(mut self) -> Result<()> {
        // rename(2) would replace an empty folder made meanwhile; refuse it as at the start.
        if fs::symlink_metadata(&self.out).is_ok() {
            bail!(
                "--out {}: appeared while exporting; the export is left unfinished",
                self.out.display()
            );
        }
        fs::rename(&self.tmp, &self.out)
            .with_context(|| format!("moving the export into {}", self.out.display()))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.tmp);
        }
    }
}

/// Removes hidden folders of earlier exports to `name` whose process is gone (Linux: no
/// `/proc/PID`); elsewhere they are left, harmless, since none is ever taken for `--out`.
fn remove_dead(parent: &Path, name: &str) -> Result<()> {
    if !Path::new("/proc/self").exists() {
        return Ok(());
    }
    let prefix = format!(".{name}{MARK}");
    for entry in fs::read_dir(parent).with_context(|| format!("reading {}", parent.display()))? {
        let entry = entry?;
        let file = entry.file_name();
        let Some(pid) = file.to_str().and_then(|f| f.strip_prefix(&prefix)) else {
            continue;
        };
        if pid.parse::<u32>().is_ok() && !Path::new("/proc").join(pid).exists() {
            fs::remove_dir_all(entry.path())
                .with_context(|| format!("removing {}", entry.path().display()))?;
        }
    }
    Ok(())
}

/// Puts files into the export and counts how.
pub(super) struct Placer {
    copy: bool,
    pub(super) linked: usize,
    pub(super) copied: usize,
    pub(super) written: usize,
}

impl Placer {
    pub(super) fn new(copy: bool) -> Placer {
        Placer {
            copy,
            linked: 0,
            copied: 0,
            written: 0,
        }
    }

    /// `to` gets the bytes of the dataset's file `relative`: a hard link where possible,
    /// else a copy. Either way the file is opened as an untrusted dataset's files are (no
    /// link followed, regular files only), and its bytes are checked against the manifest's
    /// hash as they are read: what is exported is what the run wrote, or nothing.
    pub(super) fn place(&mut self, dataset: &Dataset, relative: &str, to: &Path) -> Result<()> {
        let (file, check) = dataset.open_file(relative)?;
        self.place_opened(file, check, &dataset.path(relative), relative, to)
    }

    /// `to` gets the bytes of `file` (opened from `from`, called `relative` in messages): a
    /// hard link where possible, else a copy, checked against `check` either way.
    pub(super) fn place_opened(
        &mut self,
        file: File,
        check: Option<Check>,
        from: &Path,
        relative: &str,
        to: &Path,
    ) -> Result<()> {
        make_parent(to)?;
        if !self.copy && hard_link_opened(&file, from, to)? {
            check_stream(file, check, relative, &mut io::sink())?;
            self.linked += 1;
            return Ok(());
        }
        let mut out = File::create(to).with_context(|| format!("creating {}", to.display()))?;
        check_stream(file, check, relative, &mut out)
            .with_context(|| format!("copying {relative} to {}", to.display()))?;
        self.copied += 1;
        Ok(())
    }

    /// Writes new bytes to `to`.
    pub(super) fn write(&mut self, to: &Path, bytes: &[u8]) -> Result<()> {
        make_parent(to)?;
        fs::write(to, bytes).with_context(|| format!("writing {}", to.display()))?;
        self.written += 1;
        Ok(())
    }
}

fn make_parent(path: &Path) -> Result<()> {
    if let Some(parent) = path.parent() {
        fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    }
    Ok(())
}
