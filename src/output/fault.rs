//! Fault injection for the robustness tests, off unless `SHMGEN_TEST_FAULT` is set.
//!
//! `SHMGEN_TEST_FAULT=POINT@N` makes the process exit at once (exit code 86, no clean-up: as
//! `kill -9` would leave things) the N-th time (from 1) it passes POINT; `POINT@N:full`
//! makes that passage fail as a full disk does instead (`ENOSPC`). The points:
//!
//! - `write:FILE` — writing the temporary file of `run.json` or `manifest.jsonl` (a crash
//!   leaves half of it; a full disk fails after half of it),
//! - `rename:FILE` — between writing that temporary file and renaming it into place,
//! - `stage` — writing a sample's file into staging (half of it, as above),
//! - `commit` — after a sample's files are moved into place, before its manifest line,
//! - `append` — appending a manifest line (a crash leaves half of the line),
//! - `committed` — after the manifest line, before the sample's staging folder is removed.

use std::io;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

/// The environment variable that arms a fault.
pub const VARIABLE: &str = "SHMGEN_TEST_FAULT";

/// Exit code of an injected crash.
pub const CRASH_EXIT: i32 = 86;

struct Armed {
    point: String,
    at: u64,
    full: bool,
    passed: AtomicU64,
}

fn armed() -> Option<&'static Armed> {
    static ARMED: OnceLock<Option<Armed>> = OnceLock::new();
    ARMED
        .get_or_init(|| {
            let spec = std::env::var(VARIABLE).ok()?;
            let (spec, full) = match spec.strip_suffix(":full") {
                Some(s) => (s.to_string(), true),
                None => (spec, false),
            };
            let (point, at) = spec.rsplit_once('@')?;
            Some(Armed {
                point: point.to_string(),
                at: at.parse().ok()?,
                full,
                passed: AtomicU64::new(0),
            })
        })
        .as_ref()
}

/// What to do at a fault point.
pub enum Fault {
    /// Carry on.
    None,
    /// Fail as a full disk does.
    Full,
    /// Exit now, after doing half of the step (the caller does that half and calls
    /// [`crash`]).
    Crash,
}

/// Passes the fault point `point`.
pub fn at(point: &str) -> Fault {
    let Some(armed) = armed() else {
        return Fault::None;
    };
    if armed.point != point || armed.passed.fetch_add(1, Ordering::SeqCst) + 1 != armed.at {
        return Fault::None;
    }
    if armed.full {
        Fault::Full
    } else {
        Fault::Crash
    }
}

/// Exits the process at once, as an injected crash.
pub fn crash(point: &str) -> ! {
    eprintln!("{VARIABLE}: crashing at {point}");
    std::process::exit(CRASH_EXIT)
}

/// The error a full disk gives (`ENOSPC`).
pub fn disk_full() -> io::Error {
    if cfg!(target_os = "linux") {
        io::Error::from_raw_os_error(28)
    } else {
        io::Error::from(io::ErrorKind::StorageFull)
    }
}

/// Passes a fault point where nothing is half done: crashes, or fails as a full disk.
pub fn check(point: &str) -> io::Result<()> {
    match at(point) {
        Fault::None => Ok(()),
        Fault::Full => Err(disk_full()),
        Fault::Crash => crash(point),
    }
}

/// Writes `bytes` with `write`, passing the fault point `point`: a crash or a full disk
/// there comes after half of the bytes.
pub fn write_through(
    point: &str,
    bytes: &[u8],
    mut write: impl FnMut(&[u8]) -> io::Result<()>,
) -> io::Result<()> {
    match at(point) {
        Fault::None => write(bytes),
        fault => {
            write(&bytes[..bytes.len() / 2])?;
            match fault {
                Fault::Full => Err(disk_full()),
                _ => crash(point),
            }
        }
    }
}
