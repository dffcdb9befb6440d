//! Advisory locks on files (std's `File::lock`: `flock` on Unix, `LockFileEx` on Windows)
//! whose holder may delete them. After locking, the lock is checked to still be the file at
//! its path, so no process ever holds a lock on a file another process has already removed
//! (it retries on the new file instead).

use std::fs::{self, File, OpenOptions, TryLockError};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

/// How many times a lock is retried when its file is removed under it.
const RETRIES: usize = 1000;

/// An exclusive lock on a file, released when dropped.
pub struct Lock {
    file: File,
    path: PathBuf,
}

impl Lock {
    /// Locks the lock file `path` (created with its folder if missing). With `wait`, blocks
    /// until the lock is free; without, returns `None` when another process holds it.
    pub fn acquire(path: &Path, wait: bool) -> io::Result<Option<Lock>> {
        let mut options = OpenOptions::new();
        options.read(true).write(true).create(true).truncate(false);
        Self::acquire_with(path, &options, wait)
    }

    /// Locks the file `path`, opened with `options` (which must create it if it may be
    /// missing).
    pub fn acquire_with(
        path: &Path,
        options: &OpenOptions,
        wait: bool,
    ) -> io::Result<Option<Lock>> {
        for _ in 0..RETRIES {
            if let Some(parent) = path.parent() {
                fs::create_dir_all(parent)?;
            }
            let file = match options.open(path) {
                Ok(file) => file,
                // Its folder was removed between creating it and opening the file.
                Err(e) if e.kind() == io::ErrorKind::NotFound => continue,
                Err(e) => return Err(e),
            };
            if wait {
                file.lock()?;
            } else {
                match file.try_lock() {
                    Ok(()) => {}
                    Err(TryLockError::WouldBlock) => return Ok(None),
                    Err(TryLockError::Error(e)) => return Err(e),
                }
            }
            if is_at(&file, path) {
                return Ok(Some(Lock {
                    file,
                    path: path.to_path_buf(),
                }));
            }
        }
        Err(io::Error::other(format!(
            "{} kept being removed while being locked",
            path.display()
        )))
    }

    /// The locked file.
    pub fn file(&self) -> &File {
        &self.file
    }

    /// Writes who holds the lock into the lock file, for another process's error message.
    pub fn record_holder(&mut self) -> io::Result<()> {
        self.file.set_len(0)?;
        self.file.write_all(holder().as_bytes())
    }

    /// Removes the lock file, then releases the lock.
    pub fn remove(self) -> io::Result<()> {
        match fs::remove_file(&self.path) {
            Err(e) if e.kind() != io::ErrorKind::NotFound => Err(e),
            _ => Ok(()),
        }
    }
}

/// The most of a lock file read for its holder (ours hold "pid P on host H").
const HOLDER_BYTES: u64 = 4096;

/// Who holds the lock file at `path`, as its holder recorded it ("pid 123 on host h"). A lock
/// file of a received folder is untrusted: read only if it is a regular file, not through a
/// link, and at most `HOLDER_BYTES` of it.
pub fn recorded_holder(path: &Path) -> String {
    let mut text = String::new();
    let read = open_no_wait(path).and_then(|f| {
        if !f.metadata()?.is_file() {
            return Err(io::Error::other("not a regular file"));
        }
        f.take(HOLDER_BYTES).read_to_string(&mut text)
    });
    match read {
        Ok(_) if !text.trim().is_empty() => text.trim().to_string(),
        _ => "pid unknown".to_string(),
    }
}

/// Opens `path` for reading without following a link or waiting on a FIFO.
pub(super) fn open_no_wait(path: &Path) -> io::Result<File> {
    let mut options = OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(
        &mut options,
        libc::O_NOFOLLOW | libc::O_NONBLOCK,
    );
    options.open(path)
}

/// This process, as a lock holder: "pid 123 on host h".
fn holder() -> String {
    match this_host() {
        Some(host) => format!("pid {} on host {host}", std::process::id()),
        None => format!("pid {}", std::process::id()),
    }
}

/// The name of the host this process runs on, as lock holders record it.
pub fn this_host() -> Option<String> {
    fs::read_to_string("/proc/sys/kernel/hostname")
        .or_else(|_| fs::read_to_string("/etc/hostname"))
        .ok()
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
}

/// The pid and host a holder recorded ("pid 123 on host h"), each if it was recorded.
pub fn parse_holder(recorded: &str) -> (Option<u32>, Option<&str>) {
    let rest = recorded.strip_prefix("pid ").unwrap_or("");
    let (pid, host) = match rest.split_once(" on host ") {
        Some((pid, host)) => (pid, Some(host)),
        None => (rest, None),
    };
    (pid.trim().parse().ok(), host.map(str::trim))
}

/// Whether some process holds the lock on the existing file `path` (never created here). It
/// is found out by taking the lock for an instant, so a process trying to take it at that very
/// instant is refused: callers outside `DatasetFolder`'s folder lock accept that.
pub fn is_held(path: &Path) -> io::Result<bool> {
    let file = open_no_wait(path)?;
    match file.try_lock() {
        Ok(()) => Ok(false),
        Err(TryLockError::WouldBlock) => Ok(true),
        Err(TryLockError::Error(e)) => Err(e),
    }
}

/// Whether `file` is (still) the file at `path`.
#[cfg(unix)]
fn is_at(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// Whether `file` is (still) the file at `path`.
#[cfg(not(unix))]
fn is_at(_file: &File, path: &Path) -> bool {
    path.exists()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_lock_is_refused_and_a_removed_one_is_not_inherited() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sub/x.lock");
        let mut first = Lock::acquire(&path, false).unwrap().unwrap();
        first.record_holder().unwrap();
        assert!(Lock::acquire(&path, false).unwrap().is_none());
        assert!(recorded_holder(&path).starts_with("pid "));
        assert!(is_held(&path).unwrap());
        let recorded = recorded_holder(&path);
        let (pid, host) = parse_holder(&recorded);
        assert_eq!(pid, Some(std::process::id()));
        assert_eq!(host.map(str::to_string), this_host());
        // A process that opened the file before its holder removed it must not end up
        // holding a lock on the removed file.
        let stale = File::open(&path).unwrap();
        first.remove().unwrap();
        let second = Lock::acquire(&path, false).unwrap().unwrap();
        assert!(!is_at(&stale, &path));
        assert!(is_at(second.file(), &path));
        drop(second);
        assert!(!is_held(&path).unwrap());
        assert_eq!(parse_holder("pid unknown"), (None, None));
    }
}
