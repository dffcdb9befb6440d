//! Which files a recipe may read, and reading them within bounds.
//!
//! A recipe reads only regular files whose real path (every symlink resolved) lies inside its
//! own folder or the standard-library folder; each is read up to a size fixed by its kind, and
//! never more even if it grows while being read. Fifos, devices and folders are refused without
//! being opened, so none can block a run or stream without end. Messages about a refused file
//! name it and say why; they never show what it holds.

use super::engine::stdlib_dir;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Largest recipe or module source, bytes.
pub const MAX_SOURCE_BYTES: u64 = 4 << 20;
/// Largest texture or background image file, bytes.
pub const MAX_IMAGE_BYTES: u64 = 256 << 20;
/// Largest mesh file (and glTF buffer file), bytes.
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// What a file is read as; each kind has its own size bound.
#[derive(Clone, Copy, Debug)]
pub enum Kind {
    Source,
    Image,
    Mesh,
}

impl Kind {
    fn limit(self) -> u64 {
        match self {
            Kind::Source => MAX_SOURCE_BYTES,
            Kind::Image => MAX_IMAGE_BYTES,
            Kind::Mesh => MAX_MESH_BYTES,
        }
    }

    /// How messages and the recipe's identity name the kind.
    pub fn noun(self) -> &'static str {
        match self {
            Kind::Source => "Rhai source",
            Kind::Image => "image",
            Kind::Mesh => "mesh",
        }
    }
}

/// The folders a recipe may read from, with their symlinks resolved.
#[derive(Debug)]
pub struct Allowed {
    roots: Vec<PathBuf>,
}

impl Allowed {
    /// The recipe's folder and the standard library (if it exists).
    pub fn new(recipe_folder: &Path) -> Self {
        Allowed {
            roots: [recipe_folder.to_path_buf(), stdlib_dir()]
                .iter()
                .filter_map(|f| f.canonicalize().ok())
                .collect(),
        }
    }

    /// The real path of `path`, or None when nothing is there (a dangling link included).
    /// Fails when it resolves outside the allowed folders.
    pub fn resolve(&self, path: &Path) -> Result<Option<PathBuf>, String> {
        let real = match path.canonicalize() {
            Ok(real) => real,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(format!("{}: {e}", path.display())),
        };
        if self.roots.iter().any(|root| real.starts_with(root)) {
            Ok(Some(real))
        } else {
            Err(format!(
                "{} resolves to {}, outside the recipe's folder and the standard library: a recipe reads only files inside them (symlinks included)",
                path.display(),
                real.display()
            ))
        }
    }

    /// The bytes of the file at `path` if it is an allowed regular file within `kind`'s size
    /// bound; None when nothing is there.
    pub fn read(&self, path: &Path, kind: Kind) -> Result<Option<Vec<u8>>, String> {
        match self.resolve(path)? {
            None => Ok(None),
            Some(real) => read_regular(&real, kind)
                .map(Some)
                .map_err(|e| format!("{}: {e}", path.display())),
        }
    }

    /// Checks what `read` checks without reading: an allowed regular file within bounds.
    pub fn check(&self, path: &Path, kind: Kind) -> Result<Option<PathBuf>, String> {
        match self.resolve(path)? {
            None => Ok(None),
            Some(real) => {
                let meta =
                    std::fs::metadata(&real).map_err(|e| format!("{}: {e}", path.display()))?;
                regular(&meta, kind).map_err(|e| format!("{}: {e}", path.display()))?;
                Ok(Some(real))
            }
        }
    }
}

/// Reads the regular file at `path` (wherever it is), at most `kind`'s bound. The type is
/// checked before opening (opening a fifo would wait for a writer) and again on the open file.
pub fn read_regular(path: &Path, kind: Kind) -> Result<Vec<u8>, String> {
    let before = std::fs::metadata(path).map_err(|e| e.to_string())?;
    regular(&before, kind)?;
    let mut file = File::open(path).map_err(|e| e.to_string())?;
    let meta = file.metadata().map_err(|e| e.to_string())?;
    regular(&meta, kind)?;
    let limit = kind.limit();
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    (&mut file)
        .take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > limit {
        return Err(too_large(kind));
    }
    Ok(bytes)
}

fn regular(meta: &std::fs::Metadata, kind: Kind) -> Result<(), String> {
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a folder"
        } else {
            "a special file (fifo, device or socket)"
        };
        return Err(format!("is {what}, not a regular {} file", kind.noun()));
    }
    if meta.len() > kind.limit() {
        return Err(too_large(kind));
    }
    Ok(())
}

fn too_large(kind: Kind) -> String {
    let limit = kind.limit();
    let size = if limit.is_multiple_of(1 << 30) {
        format!("{} GiB", limit >> 30)
    } else {
        format!("{} MiB", limit >> 20)
    };
    format!(
        "is larger than {size}, the limit for a {} file",
        kind.noun()
    )
}

/// The text of a Rhai source: UTF-8, without a leading byte-order mark. The error says where
/// the first invalid byte is, never what surrounds it.
pub fn source_text(bytes: Vec<u8>) -> Result<String, String> {
    match String::from_utf8(bytes) {
        Ok(text) => Ok(match text.strip_prefix('\u{feff}') {
            Some(rest) => rest.to_string(),
            None => text,
        }),
        Err(e) => {
            let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
            let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
            let start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
            let column = String::from_utf8_lossy(&valid[start..]).chars().count() + 1;
            Err(format!(
                "is not UTF-8 text (invalid byte at line {line}, column {column}); save it as UTF-8"
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sources_lose_their_byte_order_mark_and_name_bad_bytes_by_place() {
        assert_eq!(source_text(b"\xef\xbb\xbf1 + 1".to_vec()).unwrap(), "1 + 1");
        let e = source_text(b"let a = 1;\nlet b = \"\xff\";".to_vec()).unwrap_err();
        assert!(e.contains("line 2, column 10"), "{e}");
    }
}
