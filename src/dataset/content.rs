//! Content checks: the size and BLAKE3 hash the manifest records for every file of a sample,
//! compared with the bytes on disk, so a truncated, replaced or tampered file is told from a
//! good one by every reader and by `shmgen verify`.
//!
//! BLAKE3 (O'Connor, Aumasson, Neves, Wilcox-O'Hearn, "BLAKE3: one function, fast
//! everywhere", 2020) is a cryptographic hash: a file with another content and the same hash
//! is beyond reach. Sizes are compared first, when a file is opened, because that costs no
//! read; the hash wherever the bytes are read anyway (eval, export's conversions and copies)
//! and, for every file, by `verify`.

use super::Dataset;
use super::files::open_inside;
use anyhow::{Result, bail};
use rayon::prelude::*;
use serde::Deserialize;
use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// What the manifest records of one file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(try_from = "Recorded")]
pub struct Check {
    /// Its size in bytes.
    pub bytes: u64,
    /// BLAKE3 of its bytes.
    pub blake3: [u8; 32],
}

/// A manifest's record of a file as written: `{"bytes": 1234, "blake3": "<64 hex digits>"}`.
#[derive(Deserialize)]
struct Recorded {
    bytes: u64,
    blake3: String,
}

impl TryFrom<Recorded> for Check {
    type Error = String;
    fn try_from(r: Recorded) -> Result<Check, String> {
        let hash = blake3::Hash::from_hex(&r.blake3)
            .map_err(|_| format!("blake3 {:?} is not 64 hexadecimal digits", r.blake3))?;
        Ok(Check {
            bytes: r.bytes,
            blake3: *hash.as_bytes(),
        })
    }
}

impl Check {
    /// Refuses a size other than the recorded one.
    pub fn size(&self, len: u64, name: &str) -> Result<()> {
        if len != self.bytes {
            bail!(
                "{name}: {len} bytes, but manifest.jsonl records {}: the file was truncated or changed after it was written",
                self.bytes
            );
        }
        Ok(())
    }

    /// Refuses bytes whose size or hash is not the recorded one.
    pub fn content(&self, bytes: &[u8], name: &str) -> Result<()> {
        self.size(bytes.len() as u64, name)?;
        self.hash(blake3::hash(bytes), name)
    }

    /// Refuses a hash other than the recorded one.
    pub fn hash(&self, hash: blake3::Hash, name: &str) -> Result<()> {
        if hash != blake3::Hash::from_bytes(self.blake3) {
            bail!(
                "{name}: its content is not what manifest.jsonl records (BLAKE3 {hash}); the file was changed after it was written"
            );
        }
        Ok(())
    }
}

/// A reader that hashes what passes through it, so a file copied or packed is checked in the
/// same pass.
pub struct Hashing<R> {
    inner: R,
    hasher: blake3::Hasher,
}

impl<R: Read> Hashing<R> {
    /// Hashes what is read from `inner`.
    pub fn new(inner: R) -> Hashing<R> {
        Hashing {
            inner,
            hasher: blake3::Hasher::new(),
        }
    }

    /// The hash of everything read so far.
    pub fn hash(&self) -> blake3::Hash {
        self.hasher.finalize()
    }
}

impl<R: Read> Read for Hashing<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }
}

/// Streams `file` (the dataset's file `relative`) into `out`, checking its bytes against the
/// manifest's record `check` on the way; returns its size.
pub fn check_stream(
    file: File,
    check: Option<Check>,
    relative: &str,
    out: &mut impl io::Write,
) -> Result<u64> {
    let mut reader = Hashing::new(file);
    let len = io::copy(&mut reader, out).map_err(|e| anyhow::anyhow!("{relative}: {e}"))?;
    if let Some(check) = check {
        check.size(len, relative)?;
        check.hash(reader.hash(), relative)?;
    }
    Ok(len)
}

/// What `verify` found.
#[derive(Debug, Default)]
pub struct Verified {
    /// Files checked.
    pub files: u64,
    /// Their bytes.
    pub bytes: u64,
    /// Files the manifest records no hash of (a dataset written before it had them).
    pub unrecorded: u64,
    /// Each file that failed, with why.
    pub failed: Vec<String>,
    /// Each entry of the folder the manifest does not list (a file no sample owns, a link,
    /// a FIFO), with what it is.
    pub extra: Vec<String>,
}

/// Reads every file the finished dataset at `root` lists, as an untrusted reader would, and
/// compares it with the manifest's record.
pub fn verify(root: &Path) -> Result<Verified> {
    let dataset = Dataset::open_unchecked(root)?;
    let files: Vec<&String> = dataset
        .samples
        .iter()
        .flat_map(|s| s.files.iter().chain(s.views.iter().flat_map(|v| &v.files)))
        .collect();
    let results: Vec<(u64, bool, Option<String>)> = files
        .par_iter()
        .map(|relative| {
            let check = dataset.checks.get(relative.as_str()).copied();
            let read = open_inside(root, relative)
                .and_then(|file| check_stream(file, check, relative, &mut io::sink()));
            match read {
                Ok(len) => (len, check.is_none(), None),
                Err(e) => (0, check.is_none(), Some(format!("{e:#}"))),
            }
        })
        .collect();
    let mut verified = Verified {
        extra: unlisted_entries(root, &files)?,
        ..Verified::default()
    };
    for (len, unrecorded, failure) in results {
        verified.files += 1;
        verified.bytes += len;
        verified.unrecorded += u64::from(unrecorded);
        verified.failed.extend(failure);
    }
    Ok(verified)
}

/// Files `run` writes beside the samples; `.partial/` holds the work of unfinished shards.
const OWN_FILES: [&str; 2] = ["run.json", "manifest.jsonl"];
const UNFINISHED_WORK: &str = ".partial";
/// How deep and how many entries the walk goes: a dataset has `samples/NNNN/file`, so
/// anything deeper or larger than this is not one, and the walk stops rather than run on.
const MAX_DEPTH: usize = 8;
const MAX_ENTRIES: usize = 50_000_000;

/// Every entry under `root` that is not a listed file, `run.json`, `manifest.jsonl` or in
/// `.partial/`, with what it is. Links are reported, never followed.
fn unlisted_entries(root: &Path, listed: &[&String]) -> Result<Vec<String>> {
    let listed: std::collections::HashSet<&str> =
        listed.iter().map(|f| f.as_str()).chain(OWN_FILES).collect();
    let mut extra = Vec::new();
    let mut pending = vec![(root.to_path_buf(), String::new(), 0)];
    let mut seen = 0usize;
    while let Some((folder, prefix, depth)) = pending.pop() {
        let entries =
            std::fs::read_dir(&folder).map_err(|e| anyhow::anyhow!("{}: {e}", folder.display()))?;
        for entry in entries {
            let entry = entry.map_err(|e| anyhow::anyhow!("{}: {e}", folder.display()))?;
            seen += 1;
            if seen > MAX_ENTRIES {
                bail!(
                    "{}: more than {MAX_ENTRIES} entries; not a dataset",
                    root.display()
                );
            }
            let name = entry.file_name().to_string_lossy().into_owned();
            let relative = format!("{prefix}{name}");
            // DirEntry's type is the entry's own (lstat): a link is a link here.
            let kind = entry
                .file_type()
                .map_err(|e| anyhow::anyhow!("{relative}: {e}"))?;
            if kind.is_dir() {
                if depth == 0 && name == UNFINISHED_WORK {
                    continue;
                }
                if depth + 1 >= MAX_DEPTH {
                    extra.push(format!("{relative}/: a folder deeper than any dataset has"));
                } else {
                    pending.push((entry.path(), format!("{relative}/"), depth + 1));
                }
            } else if kind.is_symlink() {
                extra.push(format!(
                    "{relative}: a link (not followed), which no dataset has"
                ));
            } else if !kind.is_file() {
                extra.push(format!(
                    "{relative}: not a regular file (a FIFO, socket or device)"
                ));
            } else if !listed.contains(relative.as_str()) {
                extra.push(format!("{relative}: a file manifest.jsonl does not list"));
            }
        }
    }
    extra.sort();
    Ok(extra)
}
