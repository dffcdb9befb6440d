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
    let mut verified = Verified::default();
    for (len, unrecorded, failure) in results {
        verified.files += 1;
        verified.bytes += len;
        verified.unrecorded += u64::from(unrecorded);
        verified.failed.extend(failure);
    }
    Ok(verified)
}
