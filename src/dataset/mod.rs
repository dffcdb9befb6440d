//! Reading a finished dataset: `run.json`, the manifest, the views and per-sample files it
//! lists, each view's camera, and the decoders of the files a view holds.
//!
//! Owns: deciding whether a folder is a finished shmgen dataset, and listing what it holds,
//! for the commands that read datasets (`export`, `eval`, `verify`); the rule by which an
//! untrusted dataset's files are opened (`files`) and checked against the sizes and BLAKE3
//! hashes the manifest records (`content`). Must not touch:
//! anything on disk (it only reads), recipes, rendering, or how datasets are written (`output`
//! owns the layout and the writing; this module reads what `manifest.jsonl` lists rather than
//! guessing names).

mod camera;
mod content;
pub mod files;
mod part;
mod read;

pub use camera::Camera;
pub use content::{Check, Hashing, Verified, check_stream, verify};
pub use part::{Part, PartSample};
pub use read::{GreyImage, Layer, decode_exr, decode_grey_png, decode_rgb_png};

use anyhow::{Context, Result, bail};
use files::{Bound, MANIFEST_LINE, RECORD, image_bound, open_inside, read_bounded};
use serde_json::Value;
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// The version tag of `run.json` this reader understands.
pub const RUN_SCHEMA: &str = "shmgen.run/1";

/// A finished dataset: every sample of `run.json` is in the manifest and every file listed
/// there exists.
pub struct Dataset {
    root: PathBuf,
    /// `run.json`, as parsed.
    pub run: Value,
    /// The samples, in index order (0, 1, …).
    pub samples: Vec<Sample>,
    /// Size and BLAKE3 of each file, as the manifest records them (none in datasets written
    /// before the manifest had them).
    checks: HashMap<String, Check>,
}

/// One sample: its views (clean and augmented copies) and its per-sample files (meshes).
pub struct Sample {
    /// Sample index.
    pub index: u64,
    /// Its views in file-name order: view 0, its copies `a0`, `a1`, …, view 1, ….
    pub views: Vec<View>,
    /// Files of the whole sample (`{sample:06}.mesh.ply`, …), relative to the root, sorted.
    pub files: Vec<String>,
}

/// One view (or augmented copy of a view) and the files it has.
#[derive(Clone, Debug)]
pub struct View {
    /// Sample index.
    pub sample: u64,
    /// View index.
    pub view: u32,
    /// Augmented copy index, None for the clean view.
    pub copy: Option<u32>,
    /// The frame of a sequence (docs/sequences.md), None for a still.
    pub frame: Option<u32>,
    /// The file-name stem shared by its files, e.g. `000003_01`, `000003_01a0` or
    /// `000003_01_f0042`; WebDataset's key (no dots).
    pub stem: String,
    /// Its files relative to the dataset root, sorted by name (the record `…json` included).
    pub files: Vec<String>,
}

/// The one of `files` of `kind`.
fn of_kind<'a>(files: &'a [String], kind: &str) -> Option<&'a str> {
    files
        .iter()
        .find(|f| kind_of(f) == Some(kind))
        .map(String::as_str)
}

impl View {
    /// The file of `kind` (`rgb.png`, `depth.exr`, `json`, …), relative to the root.
    pub fn file(&self, kind: &str) -> Option<&str> {
        of_kind(&self.files, kind)
    }

    /// The folder of its files relative to the root, e.g. `samples/0000`.
    pub fn folder(&self) -> &str {
        self.files[0]
            .rsplit_once('/')
            .map_or("", |(folder, _)| folder)
    }

    /// The kinds of its files (`depth.exr`, `json`, …) with their relative paths.
    pub fn kinds(&self) -> impl Iterator<Item = (&str, &str)> {
        self.files
            .iter()
            .filter_map(|f| kind_of(f).map(|k| (k, f.as_str())))
    }
}

impl Sample {
    /// The per-sample file of `kind` (`mesh.ply`, `rest.ply`, …), relative to the root.
    pub fn file(&self, kind: &str) -> Option<&str> {
        of_kind(&self.files, kind)
    }
}

/// What follows the first dot of a file name: `depth.exr` of `…/000003_01.depth.exr`.
pub fn kind_of(relative: &str) -> Option<&str> {
    let name = relative.rsplit('/').next()?;
    name.split_once('.').map(|(_, kind)| kind)
}

/// What a file name in the layout names: a view's file or a whole sample's.
enum Owner {
    View {
        sample: u64,
        view: u32,
        copy: Option<u32>,
        frame: Option<u32>,
    },
    Sample(u64),
}

/// Parses a file's stem: `000003` (the sample), `000003_01` (view 1), `000003_01a2` (copy 2),
/// with `_f0042` after it in frame 42 of a sequence (`000003_f0042` is the sample's own file in
/// that frame, grouped with the sample's files).
fn owner_of(stem: &str) -> Option<Owner> {
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let (stem, frame) = match stem.rsplit_once("_f") {
        Some((rest, frame)) if digits(frame) => (rest, Some(frame.parse().ok()?)),
        _ => (stem, None),
    };
    let Some((sample, rest)) = stem.split_once('_') else {
        return digits(stem)
            .then(|| stem.parse().ok().map(Owner::Sample))
            .flatten();
    };
    let (view, copy) = match rest.split_once('a') {
        Some((view, copy)) => (view, Some(copy)),
        None => (rest, None),
    };
    if !digits(sample) || !digits(view) || copy.is_some_and(|c| !digits(c)) {
        return None;
    }
    Some(Owner::View {
        sample: sample.parse().ok()?,
        view: view.parse().ok()?,
        copy: match copy {
            Some(c) => Some(c.parse().ok()?),
            None => None,
        },
        frame,
    })
}

impl Dataset {
    /// Opens the dataset at `root`, refusing a folder that is not a shmgen dataset, whose
    /// manifest does not yet list every sample (a run still going, or stopped), or one of whose
    /// listed files is missing, not a regular file inside it, or not of the recorded size.
    pub fn open(root: &Path) -> Result<Dataset> {
        let dataset = Dataset::open_unchecked(root)?;
        for sample in &dataset.samples {
            let views = sample.views.iter().flat_map(|v| &v.files);
            for relative in sample.files.iter().chain(views) {
                dataset.open_file(relative)?;
            }
        }
        Ok(dataset)
    }

    /// `open` without looking at the listed files (`verify` looks at every one itself).
    fn open_unchecked(root: &Path) -> Result<Dataset> {
        let Run {
            value: run, total, ..
        } = read_run(root)?;
        let (listed, checks) = read_manifest(root)?;
        let missing = (0..total).find(|s| !listed.contains_key(s));
        if let Some(first) = missing {
            let present = listed.keys().filter(|&&s| s < total).count();
            bail!(
                "{}: the dataset is not finished: manifest.jsonl lists {present} of {total} samples (sample {first} is missing); run `shmgen run` with the same recipe and --out again to finish it",
                root.display()
            );
        }
        if let Some(extra) = listed.keys().find(|&&s| s >= total) {
            bail!(
                "{}: manifest.jsonl lists sample {extra}, but run.json has {total} samples",
                root.display()
            );
        }
        let mut samples = Vec::with_capacity(listed.len());
        for (index, files) in listed {
            samples.push(sample_of(index, files)?);
        }
        Ok(Dataset {
            root: root.to_path_buf(),
            run,
            samples,
            checks,
        })
    }

    /// The dataset's folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// A path relative to the dataset root, made absolute (for messages: files are opened
    /// with [`Dataset::open_file`]).
    pub fn path(&self, relative: &str) -> PathBuf {
        self.root.join(relative)
    }

    /// The listed file `relative`, opened as `files` says (a regular file inside the dataset,
    /// no link followed), with the size and hash the manifest records for it, if any.
    pub fn open_file(&self, relative: &str) -> Result<(File, Option<Check>)> {
        let file = open_inside(&self.root, relative)?;
        let check = self.checks.get(relative).copied();
        if let Some(check) = check {
            check.size(file.metadata()?.len(), relative)?;
        }
        Ok((file, check))
    }

    /// All bytes of the listed file `relative`, at most `bound`, checked against the
    /// manifest's hash when it has one.
    pub fn read(&self, relative: &str, bound: Bound) -> Result<Vec<u8>> {
        let (file, check) = self.open_file(relative)?;
        let bytes = read_bounded(file, relative, bound)?;
        if let Some(check) = check {
            check.content(&bytes, relative)?;
        }
        Ok(bytes)
    }

    /// Reads the listed file `relative` through, checking it against the manifest's record.
    pub fn verify_file(&self, relative: &str) -> Result<()> {
        let (file, check) = self.open_file(relative)?;
        check_stream(file, check, relative, &mut std::io::sink()).map(drop)
    }

    /// The components of the view's EXR of `kind` (`depth.exr`, `flow.exr`, …) in component
    /// order, from the first of the channel sets `sets` the file has (see [`decode_exr`]), its
    /// header checked against the view's size before any pixel is decoded.
    pub fn layer(&self, view: &View, kind: &str, sets: &[&[&str]]) -> Result<Layer> {
        let relative = self.file_of(view, kind)?;
        let (width, height) = self.size(view)?;
        let components = sets.first().map_or(1, |names| names.len());
        let bound = Bound {
            what: "an EXR of the view's size",
            bytes: image_bound(width, height, components as u64, 4),
        };
        decode_exr(
            &self.read(relative, bound)?,
            relative,
            sets,
            (width, height),
        )
    }

    /// The view's grey PNG of `kind` (`mask.png`, `valid.png`, …), its header checked
    /// against the view's size before it is decoded.
    pub fn grey(&self, view: &View, kind: &str) -> Result<GreyImage> {
        let what = "a grey PNG of the view's size";
        self.png(view, kind, what, 2, decode_grey_png)
    }

    /// The view's 8-bit RGB PNG of `kind` (`rgb.png`, `rest_rgb.png`), row-major, its header
    /// checked against the view's size before it is decoded.
    pub fn rgb(&self, view: &View, kind: &str) -> Result<Vec<[u8; 3]>> {
        let what = "an RGB PNG of the view's size";
        self.png(view, kind, what, 3, decode_rgb_png)
    }

    /// The view's PNG of `kind` read within the bound of `what`, `bytes` bytes a pixel at
    /// the view's size, and decoded by `decode` (which checks the header against that size).
    fn png<T>(
        &self,
        view: &View,
        kind: &str,
        what: &'static str,
        bytes: u64,
        decode: ImageDecoder<T>,
    ) -> Result<T> {
        let relative = self.file_of(view, kind)?;
        let (width, height) = self.size(view)?;
        let bound = Bound {
            what,
            bytes: image_bound(width, height, 1, bytes),
        };
        decode(&self.read(relative, bound)?, relative, (width, height))
    }

    /// The view's width and height, from its record.
    pub fn size(&self, view: &View) -> Result<(u32, u32)> {
        let camera = self.camera(view)?;
        Ok((camera.width, camera.height))
    }

    fn file_of<'a>(&self, view: &'a View, kind: &str) -> Result<&'a str> {
        view.file(kind)
            .with_context(|| format!("view {} has no {kind} file", view.stem))
    }

    /// Every view of every sample, in sample order.
    pub fn views(&self) -> impl Iterator<Item = &View> {
        self.samples.iter().flat_map(|s| s.views.iter())
    }

    /// The camera of a view, from its record.
    pub fn camera(&self, view: &View) -> Result<Camera> {
        let record = self.record(view)?;
        Camera::from_record(&record)
            .with_context(|| view.file("json").unwrap_or(&view.stem).to_string())
    }

    /// The view's JSON record, parsed.
    pub fn record(&self, view: &View) -> Result<Value> {
        let json = view
            .file("json")
            .with_context(|| format!("view {} has no record (.json)", view.stem))?;
        serde_json::from_slice(&self.read(json, RECORD)?)
            .with_context(|| format!("{json}: does not parse as JSON"))
    }

    /// `dataset.name`, `dataset.seed` and the recipe hash: what identifies the dataset an
    /// export or evaluation came from (never its path, so outputs do not depend on where the
    /// dataset lies).
    pub fn identity(&self) -> Value {
        serde_json::json!({
            "name": self.run.pointer("/dataset/name"),
            "seed": self.run.pointer("/dataset/seed"),
            "samples": self.samples.len(),
            "recipe_hash": self.run.pointer("/recipe/hash"),
        })
    }
}

/// A dataset's `run.json`: its bytes, as parsed, and the number of samples it declares.
struct Run {
    bytes: Vec<u8>,
    value: Value,
    total: u64,
}

/// Reads `run.json` of the folder `root` as an untrusted dataset's file, refusing a folder
/// that is not a shmgen dataset of the schema this reader understands.
fn read_run(root: &Path) -> Result<Run> {
    if !root.is_dir() {
        bail!("{}: no such folder", root.display());
    }
    let run_path = root.join("run.json");
    if std::fs::symlink_metadata(&run_path).is_err() {
        bail!(
            "{}: not a shmgen dataset (no run.json; give the folder `shmgen run --out` wrote)",
            root.display()
        );
    }
    let bytes = read_inside(root, "run.json", RECORD)?;
    let run: Value = serde_json::from_slice(&bytes).with_context(|| {
        format!(
            "{}: not a shmgen dataset (run.json does not parse)",
            root.display()
        )
    })?;
    let schema = run.get("schema").and_then(Value::as_str).unwrap_or("none");
    if schema != RUN_SCHEMA {
        bail!(
            "{}: run.json has schema {schema:?}; this shmgen reads {RUN_SCHEMA:?}",
            run_path.display()
        );
    }
    let total = run
        .pointer("/dataset/samples")
        .and_then(Value::as_u64)
        .with_context(|| format!("{}: no dataset.samples", run_path.display()))?;
    Ok(Run {
        bytes,
        value: run,
        total,
    })
}

/// A decoder of an image file's bytes: (bytes, the file's name, the view's width and height).
type ImageDecoder<T> = fn(&[u8], &str, (u32, u32)) -> Result<T>;

/// Sample index → the files its manifest line lists.
type Listed = BTreeMap<u64, Vec<String>>;

/// All of the dataset's file `relative` (`run.json`, …), as `files` opens it, at most `bound`.
fn read_inside(root: &Path, relative: &str, bound: Bound) -> Result<Vec<u8>> {
    read_bounded(open_inside(root, relative)?, relative, bound)
}

/// One line of `manifest.jsonl`: a finished sample, its files and their records.
#[derive(serde::Deserialize)]
struct Line {
    sample: u64,
    files: Vec<String>,
    #[serde(default)]
    hashes: BTreeMap<String, Check>,
}

/// Sample index → its files, from every complete line of the manifest, and the size and
/// hash of every file whose line records them.
fn read_manifest(root: &Path) -> Result<(Listed, HashMap<String, Check>)> {
    let path = root.join("manifest.jsonl");
    if std::fs::symlink_metadata(&path).is_err() {
        bail!(
            "{}: the dataset is not finished (no manifest.jsonl)",
            root.display()
        );
    }
    let (mut listed, mut checks) = (BTreeMap::new(), HashMap::new());
    each_line(root, |number, _, parsed| {
        let Some(parsed) = parsed else {
            bail!(
                "{}: line {number} is incomplete or does not parse; the dataset is not finished (run `shmgen run` again to finish it)",
                path.display()
            );
        };
        if let std::collections::btree_map::Entry::Vacant(entry) = listed.entry(parsed.sample) {
            // A line speaks for its own files only.
            let own = |(file, _): &(String, Check)| parsed.files.contains(file);
            checks.extend(parsed.hashes.into_iter().filter(own));
            entry.insert(parsed.files);
        }
        Ok(())
    })?;
    Ok((listed, checks))
}

/// Calls `each` with every line of the manifest of `root` (numbered from 1, its bytes, and
/// what it says if it is complete and parses: a line without its newline is a torn append of
/// a run that was killed). Each line is read up to `MANIFEST_LINE` bytes: a manifest without
/// newlines is refused, never read whole.
fn each_line(
    root: &Path,
    mut each: impl FnMut(u64, &[u8], Option<Line>) -> Result<()>,
) -> Result<()> {
    let path = root.join("manifest.jsonl");
    let mut reader = BufReader::new(open_inside(root, "manifest.jsonl")?);
    let mut line = Vec::new();
    for number in 1.. {
        line.clear();
        let read = (&mut reader)
            .take(MANIFEST_LINE + 1)
            .read_until(b'\n', &mut line)
            .with_context(|| format!("reading {}", path.display()))?;
        if read == 0 {
            break;
        }
        if line.len() as u64 > MANIFEST_LINE {
            bail!(
                "{}: line {number} is longer than {MANIFEST_LINE} bytes; not a manifest shmgen wrote",
                path.display()
            );
        }
        let parsed = line
            .ends_with(b"\n")
            .then(|| serde_json::from_slice::<Line>(&line).ok())
            .flatten();
        each(number, &line, parsed)?;
    }
    Ok(())
}

/// Groups a sample's files into its views and its own files.
fn sample_of(index: u64, mut files: Vec<String>) -> Result<Sample> {
    files.sort();
    files.dedup();
    let mut views: BTreeMap<(u32, Option<u32>, Option<u32>), View> = BTreeMap::new();
    let mut own = Vec::new();
    for file in files {
        if file.contains("..") || file.starts_with('/') || file.contains('\\') {
            bail!("manifest.jsonl: sample {index} lists {file:?}, outside the dataset folder");
        }
        let name = file.rsplit('/').next().unwrap_or(&file);
        let stem = name.split('.').next().unwrap_or(name);
        match owner_of(stem) {
            Some(Owner::Sample(s)) if s == index => own.push(file),
            Some(Owner::View {
                sample,
                view,
                copy,
                frame,
            }) if sample == index => {
                let entry = views.entry((view, copy, frame)).or_insert_with(|| View {
                    sample,
                    view,
                    copy,
                    frame,
                    stem: stem.to_string(),
                    files: Vec::new(),
                });
                entry.files.push(file);
            }
            _ => bail!(
                "manifest.jsonl: sample {index} lists {file}, which is not a file of sample {index}"
            ),
        }
    }
    Ok(Sample {
        index,
        views: views.into_values().collect(),
        files: own,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn stems_name_samples_views_and_copies() {
        assert!(matches!(owner_of("000012"), Some(Owner::Sample(12))));
        assert!(matches!(
            owner_of("000012_03"),
            Some(Owner::View {
                sample: 12,
                view: 3,
                copy: None,
                frame: None
            })
        ));
        assert!(matches!(
            owner_of("000012_03a1_f0042"),
            Some(Owner::View {
                sample: 12,
                view: 3,
                copy: Some(1),
                frame: Some(42)
            })
        ));
        assert!(matches!(owner_of("000012_f0007"), Some(Owner::Sample(12))));
        assert!(matches!(
            owner_of("1000000_10a2"),
            Some(Owner::View {
                sample: 1_000_000,
                view: 10,
                copy: Some(2),
                frame: None
            })
        ));
        for bad in [
            "",
            "x",
            "000012_",
            "000012_03a",
            "000012_x3",
            "12_3b1",
            "000012_03_f",
        ] {
            assert!(owner_of(bad).is_none(), "{bad}");
        }
        assert_eq!(
            kind_of("samples/0000/000003_01.depth.exr"),
            Some("depth.exr")
        );
        assert_eq!(kind_of("samples/0000/000003.mesh.ply"), Some("mesh.ply"));
    }

    fn dataset(dir: &Path, samples: u64, manifest: &str) {
        fs::write(
            dir.join("run.json"),
            format!(r#"{{"schema":"shmgen.run/1","dataset":{{"samples":{samples}}}}}"#),
        )
        .unwrap();
        fs::write(dir.join("manifest.jsonl"), manifest).unwrap();
    }

    #[test]
    fn unfinished_and_foreign_folders_are_refused_with_the_reason() {
        let dir = tempfile::tempdir().unwrap();
        let err = |d: &Path| format!("{:#}", Dataset::open(d).err().unwrap());
        assert!(err(dir.path()).contains("no run.json"));
        fs::write(dir.path().join("run.json"), r#"{"schema":"other/2"}"#).unwrap();
        assert!(err(dir.path()).contains("\"other/2\""));
        fs::create_dir_all(dir.path().join("samples/0000")).unwrap();
        fs::write(dir.path().join("samples/0000/000000_00.json"), "{}").unwrap();
        fs::write(dir.path().join("samples/0000/000000.mesh.ply"), "").unwrap();
        let line = r#"{"sample":0,"views":1,"files":["samples/0000/000000_00.json","samples/0000/000000.mesh.ply"]}"#;
        dataset(dir.path(), 2, &format!("{line}\n"));
        assert!(err(dir.path()).contains("lists 1 of 2 samples (sample 1 is missing)"));
        dataset(dir.path(), 1, line);
        assert!(err(dir.path()).contains("line 1 is incomplete"));
        dataset(dir.path(), 1, &format!("{line}\n"));
        let d = Dataset::open(dir.path()).unwrap();
        assert_eq!(d.samples[0].files, ["samples/0000/000000.mesh.ply"]);
        assert_eq!(d.samples[0].views[0].stem, "000000_00");
        assert_eq!(d.samples[0].views[0].folder(), "samples/0000");
        fs::remove_file(dir.path().join("samples/0000/000000_00.json")).unwrap();
        assert!(err(dir.path()).contains("samples/0000/000000_00.json: missing"));
    }
}
