//! No command writes onto a dataset or an export: an output path (`run --out`, `export --out`,
//! `eval --json`, `watch --out`, anything later) may not be one, nor lie inside one, however
//! it is spelled.
//!
//! Folders are recognised by what they hold, not by their path: a dataset has a
//! `manifest.jsonl` or a shmgen `run.json`, an export a shmgen `export.json` (or is an export's
//! hidden staging folder). The output's nearest existing folder is resolved (`..` and links
//! gone) and it and every folder above it are looked at, so `D/samples/../run.json`, a link to
//! `D` and a bind mount of `D` are all seen as inside `D`. When the command reads a dataset
//! too, a folder that is the same inode as that dataset counts as well.

use super::folder::read_record;
use anyhow::{Result, bail};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// What a folder is, for a writer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Holder {
    Dataset,
    Export,
}

impl Holder {
    fn name(self) -> &'static str {
        match self {
            Holder::Dataset => "dataset",
            Holder::Export => "export",
        }
    }
}

/// Refuses the output `out` (given as `flag`, e.g. `--json`) if it is or lies inside a dataset
/// or an export, or inside `source` (the dataset the command reads). `run --out` passes
/// `own_dataset`: its `out` may be a dataset (its own, resumed or replaced as `run` decides),
/// but not an export, and not inside either; never `source` itself (`merge OUT PART` passes
/// each part as `source`).
pub fn refuse_data_target(
    out: &Path,
    flag: &str,
    source: Option<&Path>,
    own_dataset: bool,
) -> Result<()> {
    let Some(existing) = nearest_existing(out) else {
        return Ok(());
    };
    let source_id = source.and_then(identity);
    for folder in existing.ancestors() {
        let itself = folder == existing && existing_is_out(out, &existing);
        let is_source = source_id.is_some() && identity(folder) == source_id;
        let holder = holder(folder).or_else(|| is_source.then_some(Holder::Dataset));
        match holder {
            None => {}
            // A command may write onto its own dataset, never onto the one it reads.
            Some(Holder::Dataset) if itself && own_dataset && !is_source => {}
            Some(holder) => {
                let place = if itself { "is" } else { "lies inside" };
                bail!(
                    "{flag} {}: {place} the {} {}; shmgen never writes onto a dataset or an export (choose a path outside it)",
                    out.display(),
                    holder.name(),
                    folder.display()
                );
            }
        }
    }
    Ok(())
}

/// The resolved form of `out` if it exists as a folder, else of its nearest existing parent.
fn nearest_existing(out: &Path) -> Option<PathBuf> {
    let absolute = std::path::absolute(out).ok()?;
    absolute
        .ancestors()
        .filter(|a| a.is_dir())
        .find_map(|a| a.canonicalize().ok())
}

/// Whether the resolved folder `existing` is `out` itself (an existing folder) rather than a
/// parent of it.
fn existing_is_out(out: &Path, existing: &Path) -> bool {
    out.is_dir() && out.canonicalize().is_ok_and(|o| o == existing)
}

/// Whether `folder` is a dataset or an export, from what it holds.
fn holder(folder: &Path) -> Option<Holder> {
    let has = |name: &str| std::fs::symlink_metadata(folder.join(name)).is_ok();
    let staging = folder
        .file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.starts_with('.') && n.contains(".export-"));
    if has("manifest.jsonl") || schema_of(&folder.join("run.json")).is_some() {
        Some(Holder::Dataset)
    } else if staging || schema_of(&folder.join("export.json")).is_some() {
        Some(Holder::Export)
    } else {
        None
    }
}

/// The shmgen schema a record declares (`shmgen.run/1`, …), if it is a regular file that
/// declares one (read as `run` reads its own run.json: a FIFO never blocks the check).
fn schema_of(path: &Path) -> Option<String> {
    let bytes = read_record(path).ok().flatten()?;
    let record: Value = serde_json::from_slice(&bytes).ok()?;
    let schema = record.get("schema")?.as_str()?;
    schema.starts_with("shmgen.").then(|| schema.to_string())
}

/// The device and inode of a folder: a bind mount or another spelling of the same folder has
/// the same.
#[cfg(unix)]
fn identity(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn identity(path: &Path) -> Option<PathBuf> {
    path.canonicalize().ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn refused(out: &Path, source: Option<&Path>, own: bool) -> Option<String> {
        refuse_data_target(out, "--out", source, own)
            .err()
            .map(|e| e.to_string())
    }

    #[test]
    fn outputs_onto_or_inside_datasets_and_exports_are_refused_by_any_spelling() {
        let dir = tempfile::tempdir().unwrap();
        let (d, e, plain) = (
            dir.path().join("d"),
            dir.path().join("e"),
            dir.path().join("p"),
        );
        fs::create_dir_all(d.join("samples/0000")).unwrap();
        fs::write(d.join("run.json"), r#"{"schema":"shmgen.run/1"}"#).unwrap();
        fs::create_dir_all(&e).unwrap();
        fs::write(e.join("export.json"), r#"{"schema":"shmgen.export/1"}"#).unwrap();
        fs::create_dir_all(&plain).unwrap();
        // Someone else's run.json does not make a folder a dataset.
        fs::write(plain.join("run.json"), r#"{"schema":"other"}"#).unwrap();

        let inside = refused(&d.join("run.json"), None, false).unwrap();
        assert!(inside.contains("lies inside the dataset"), "{inside}");
        assert!(refused(&d.join("samples/../report.json"), None, false).is_some());
        assert!(refused(&d.join("samples/new/sheet.png"), None, false).is_some());
        assert!(refused(&e.join("x.json"), None, false).is_some());
        assert!(refused(&d, None, false).unwrap().contains("is the dataset"));
        assert!(refused(&e, None, true).unwrap().contains("is the export"));
        assert!(
            refused(&d, None, true).is_none(),
            "run resumes its own dataset"
        );
        assert!(refused(&d.join("samples"), None, true).is_some());
        assert!(refused(&plain.join("report.json"), None, false).is_none());
        assert!(refused(&dir.path().join("new/report.json"), None, false).is_none());

        #[cfg(unix)]
        {
            let link = dir.path().join("link");
            std::os::unix::fs::symlink(&d, &link).unwrap();
            assert!(refused(&link.join("run.json"), None, false).is_some());
            // A folder that is the source dataset by inode, whatever it holds.
            fs::remove_file(d.join("run.json")).unwrap();
            assert!(refused(&d.join("report.json"), None, false).is_none());
            assert!(refused(&link.join("report.json"), Some(&d), false).is_some());
            // A FIFO where a record would be is not one, and is never opened for a blocking
            // read (the check would wait forever for a writer).
            let fifo = plain.join("export.json");
            let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
            // SAFETY: a valid NUL-terminated path.
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
            assert!(refused(&plain.join("report.json"), None, false).is_none());
        }
    }
}
