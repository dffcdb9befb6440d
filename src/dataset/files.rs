//! Opening the files of a dataset someone else may have made: a received dataset is untrusted
//! input, so a file it lists is read only if it is a regular file inside the dataset, reached
//! without following a link, and only up to a size stated for its kind.
//!
//! Owns: the rule every reader of a dataset follows (`export`, `eval`, `verify`), and the
//! bounds. Must
//! not touch: what the bytes mean (the decoders in `read` check headers against the view
//! before decoding pixels), or anything on disk (it only opens for reading).
//!
//! Why each part:
//! - **No links.** `ln -s ~/.ssh/id_ed25519 D/samples/0000/000000_00.rgb.png` in a received
//!   dataset would otherwise pull a file of the person exporting it into what they publish.
//!   Every folder between the root and the file is opened with `O_NOFOLLOW | O_DIRECTORY`,
//!   relative to the one above it, and the file itself with `O_NOFOLLOW`: a link anywhere
//!   below the root is refused, however the path is spelled. The root itself is the folder
//!   the user named, link or not.
//! - **Regular files only.** A FIFO would block a read forever and `/dev/zero` never ends: the
//!   file is opened non-blocking and `fstat` of the opened descriptor must say "regular file".
//! - **Bounded reads.** A file larger than its kind may be is refused before a byte is read,
//!   and reads stop at the bound whatever the file does meanwhile.

use anyhow::{Result, bail};
use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// The most a file of some kind may hold, and the kind's name for messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bound {
    /// What the file is ("a view record", "an image of 960×960"), for messages.
    pub what: &'static str,
    /// Bytes.
    pub bytes: u64,
}

/// `run.json` and a view's JSON record: a few kB in practice; 16 MiB leaves room for any
/// recipe's parameters.
pub const RECORD: Bound = Bound {
    what: "a JSON record",
    bytes: 16 << 20,
};

/// One line of `manifest.jsonl` (a sample's file list with its hashes: a few kB).
pub const MANIFEST_LINE: u64 = 1 << 20;

/// A mesh, point cloud or other per-sample file: the largest mesh the importer accepts.
pub const SAMPLE_FILE: Bound = Bound {
    what: "a per-sample file",
    bytes: 4 << 30,
};

/// The largest image file of `width × height` pixels of `channels` samples of `bytes` bytes:
/// the raw size twice over (no lossless encoding of real data grows that much: PNG's and
/// EXR's zip add a few bytes per block) plus 1 MiB for headers, offset tables and metadata.
pub fn image_bound(width: u32, height: u32, channels: u64, bytes: u64) -> u64 {
    let raw = u64::from(width) * u64::from(height) * channels * bytes;
    raw.saturating_mul(2).saturating_add(1 << 20)
}

/// Opens `relative` (a `/`-separated path from a manifest) inside the folder `root` for
/// reading: a regular file reached without following a link. Errors name the file and say
/// what it is instead (missing, a link, a FIFO or device, a folder).
pub fn open_inside(root: &Path, relative: &str) -> Result<File> {
    let parts: Vec<&str> = relative.split('/').collect();
    if parts
        .iter()
        .any(|p| p.is_empty() || *p == "." || *p == ".." || p.contains('\\'))
    {
        bail!("{relative}: not a path inside the dataset (empty, `.` or `..` parts, or `\\`)");
    }
    let name = root.join(relative).display().to_string();
    let file = walk(root, &parts).map_err(|e| described(e, &name))?;
    regular(file, &name)
}

/// Opens `path` (a file the user named, e.g. a prediction: links allowed) for reading,
/// refusing anything but a regular file without blocking on a FIFO.
pub fn open_regular(path: &Path) -> Result<File> {
    let name = path.display().to_string();
    let file = open_options(false)
        .open(path)
        .map_err(|e| described(e, &name))?;
    regular(file, &name)
}

/// All of `file` (called `name` in messages), refused before reading if it is larger than
/// `bound`; the read itself stops at the bound.
pub fn read_bounded(file: File, name: &str, bound: Bound) -> Result<Vec<u8>> {
    let len = file.metadata()?.len();
    if len > bound.bytes {
        bail!(
            "{name}: {len} bytes, more than {} may hold ({} bytes); the file is not what its name says",
            bound.what,
            bound.bytes
        );
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(bound.bytes + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    if bytes.len() as u64 > bound.bytes {
        bail!("{name}: grew past {} bytes while being read", bound.bytes);
    }
    Ok(bytes)
}

/// Refuses an opened file that is not a regular file.
fn regular(file: File, name: &str) -> Result<File> {
    let meta = file.metadata()?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a folder"
        } else {
            "a FIFO, socket or device"
        };
        bail!("{name}: is {kind}, not a regular file");
    }
    Ok(file)
}

/// An open error as a person reads it: what `name` is instead of a readable file.
fn described(e: io::Error, name: &str) -> anyhow::Error {
    let link = cfg!(unix) && e.raw_os_error() == Some(libc_eloop());
    match e.kind() {
        io::ErrorKind::NotFound => anyhow::anyhow!("{name}: missing"),
        _ if link => anyhow::anyhow!(
            "{name}: is (or lies under) a symbolic link; a dataset's files must be regular files inside it, and links are never followed"
        ),
        io::ErrorKind::NotADirectory => anyhow::anyhow!(
            "{name}: a part of the path is not a folder (or is a symbolic link to one); links are never followed"
        ),
        _ => anyhow::Error::new(e).context(format!("opening {name}")),
    }
}

#[cfg(unix)]
fn libc_eloop() -> i32 {
    libc::ELOOP
}

#[cfg(not(unix))]
fn libc_eloop() -> i32 {
    -1
}

/// Read-only, non-blocking (a FIFO opens without waiting for a writer), and on Unix without
/// following a link at the last component when `no_follow`.
fn open_options(no_follow: bool) -> std::fs::OpenOptions {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        let follow = if no_follow { libc::O_NOFOLLOW } else { 0 };
        options.custom_flags(libc::O_NONBLOCK | follow);
    }
    options
}

/// Opens `parts` below `root`, each folder relative to the one above it, none followed if a
/// link.
#[cfg(unix)]
fn walk(root: &Path, parts: &[&str]) -> io::Result<File> {
    use std::ffi::CString;
    use std::os::fd::{AsRawFd, FromRawFd};
    let mut dir = File::open(root)?;
    for (i, part) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        let name = CString::new(*part).map_err(|_| io::ErrorKind::InvalidInput)?;
        let flags = libc::O_RDONLY
            | libc::O_NOFOLLOW
            | libc::O_CLOEXEC
            | if last {
                libc::O_NONBLOCK
            } else {
                libc::O_DIRECTORY
            };
        // SAFETY: `dir` is an open descriptor and `name` a NUL-terminated string; the new
        // descriptor, if any, is owned by the File made from it.
        let fd = unsafe { libc::openat(dir.as_raw_fd(), name.as_ptr(), flags) };
        if fd < 0 {
            return Err(io::Error::last_os_error());
        }
        // SAFETY: `fd` was just opened and is owned by nothing else.
        dir = unsafe { File::from_raw_fd(fd) };
    }
    Ok(dir)
}

/// Without `openat`: every component is checked not to be a link, then the file opened.
#[cfg(not(unix))]
fn walk(root: &Path, parts: &[&str]) -> io::Result<File> {
    let mut path = root.to_path_buf();
    for part in parts {
        path.push(part);
        if std::fs::symlink_metadata(&path)?.file_type().is_symlink() {
            return Err(io::Error::other("a symbolic link"));
        }
    }
    open_options(true).open(&path)
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::fs;
    use std::os::unix::fs::symlink;

    fn message(result: Result<File>) -> String {
        format!("{:#}", result.expect_err("refused"))
    }

    #[test]
    fn links_anywhere_below_the_root_are_refused_and_the_root_may_be_one() {
        let dir = tempfile::tempdir().unwrap();
        let (root, outside) = (dir.path().join("d"), dir.path().join("secret"));
        fs::create_dir_all(root.join("samples/0000")).unwrap();
        fs::write(&outside, "secret").unwrap();
        fs::write(root.join("samples/0000/a.json"), "{}").unwrap();
        symlink(&outside, root.join("samples/0000/b.json")).unwrap();
        symlink(root.join("samples"), root.join("linked")).unwrap();
        symlink(&root, dir.path().join("root-link")).unwrap();

        assert!(open_inside(&root, "samples/0000/a.json").is_ok());
        assert!(open_inside(&dir.path().join("root-link"), "samples/0000/a.json").is_ok());
        assert!(message(open_inside(&root, "samples/0000/b.json")).contains("symbolic link"));
        assert!(message(open_inside(&root, "linked/0000/a.json")).contains("link"));
        assert!(message(open_inside(&root, "samples/0000/c.json")).contains("missing"));
        for bad in ["../secret", "samples//a", "./run.json", "samples\\0000"] {
            assert!(message(open_inside(&root, bad)).contains("not a path inside"));
        }
    }

    #[test]
    fn devices_fifos_and_folders_are_not_files_and_reads_stop_at_the_bound() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        // Opening a FIFO without a writer would block without O_NONBLOCK.
        assert!(message(open_regular(&fifo)).contains("FIFO"));
        assert!(message(open_regular(Path::new("/dev/zero"))).contains("device"));
        assert!(message(open_regular(dir.path())).contains("folder"));

        let file = dir.path().join("big");
        fs::write(&file, vec![7u8; 100]).unwrap();
        let small = Bound {
            what: "a test file",
            bytes: 99,
        };
        let err = read_bounded(open_regular(&file).unwrap(), "big", small).unwrap_err();
        assert!(format!("{err}").contains("100 bytes, more than a test file may hold"));
        let exact = Bound {
            bytes: 100,
            ..small
        };
        let bytes = read_bounded(open_regular(&file).unwrap(), "big", exact).unwrap();
        assert_eq!(bytes, vec![7u8; 100]);
    }
}
