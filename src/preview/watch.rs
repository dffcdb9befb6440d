//! `shmgen watch`: recompile the recipe and rewrite its contact sheet whenever the recipe, a
//! module it imports or a file it reads changes.
//!
//! Owns: which folders are watched, which file events count, the coalescing of one save's
//! events into one reload, the background scene pass after each sheet, and reporting
//! (terminal and, optionally, the web page). Must not touch: the recipe's files (it only
//! reads them) or the dataset format. A broken save never ends the watcher: the error is shown
//! and the last good sheet stays in place.
//!
//! The sheet shows only the first samples, so a mistake in a branch that only later samples
//! take (`if rng.sample % 5 == 4 { ... }`) would pass unseen until the full run. After each
//! sheet, one background thread therefore draws every sample's scene (`check::draw_scenes`,
//! the pass of `shmgen check`) and reports the first error with its sample, or that all
//! passed and how long it took. A new save abandons the pass between two samples.
//!
//! Folders, not files, are watched (non-recursively): an editor's atomic save replaces the
//! file, and a watch on the file itself would be lost with the old inode (inotify(7);
//! docs/implementation-notes.md §2.1). Not recursively, because a recipe's folder may also
//! hold datasets, whose thousands of files must neither cost watches nor trigger reloads.

use super::check::{ScenePass, draw_scenes, scenes_passed};
use super::serve::Server;
use super::sheet::{self, Preview, PreviewOptions};
use crate::output::refuse_data_target;
use crate::output::write_atomic;
use crate::recipe::Recipe;
use anyhow::{Context, Result, bail};
use notify::event::{AccessKind, AccessMode, ModifyKind};
use notify::{Event, EventKind, RecursiveMode, Watcher};
use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A save is many events (writes, close, rename, or a delete then a create); a reload waits
/// until none has arrived for this long.
const QUIET: Duration = Duration::from_millis(100);

/// Extensions of files a recipe can use, so that a new module or mesh next to the recipe
/// (perhaps the one a broken import is looking for) triggers a reload.
const SOURCE_EXTENSIONS: &[&str] = &[
    "rhai", "obj", "ply", "stl", "gltf", "glb", "bin", "png", "jpg", "jpeg",
];

/// Every preview sheet ends so; two watchers in one folder must not trigger each other.
const PREVIEW_SUFFIX: &str = ".preview.png";

/// What `shmgen watch` watches and where its sheet goes.
pub struct WatchOptions {
    /// The recipe file.
    pub recipe: PathBuf,
    /// Recipe parameters set on the command line (`--set name=value`).
    pub sets: Vec<(String, String)>,
    /// Which samples and views the sheet shows, and how small.
    pub preview: PreviewOptions,
    /// Where the sheet goes; None puts `<recipe stem>.preview.png` next to the recipe.
    pub out: Option<PathBuf>,
    /// Also serve the sheet at http://127.0.0.1:PORT/ (0 picks a port).
    pub serve: Option<u16>,
    /// Write one sheet and exit (an error if the recipe is broken).
    pub once: bool,
}

/// Runs `shmgen watch` until Ctrl-C (or once, with `--once`).
pub fn watch(options: &WatchOptions) -> Result<()> {
    let out = options
        .out
        .clone()
        .unwrap_or_else(|| default_out(&options.recipe));
    refuse_data_target(&out, "--out", None, false)?;
    if options.once {
        let start = Instant::now();
        let (preview, _, _) = build(options)?;
        write_atomic(&out, &preview.png)?;
        println!("{}", summary(&preview, start, &out));
        return Ok(());
    }
    // A mistyped path would otherwise wait forever for a file that never comes.
    if !options.recipe.is_file() {
        bail!("{}: no such recipe file", options.recipe.display());
    }
    Session::new(options, out)?.run()
}

/// `<stem>.preview.png` next to the recipe.
fn default_out(recipe: &Path) -> PathBuf {
    let stem = recipe.file_stem().unwrap_or_default().to_string_lossy();
    recipe.with_file_name(format!("{stem}{PREVIEW_SUFFIX}"))
}

/// Loads the recipe and renders its sheet; also returns the files the recipe used, and the
/// recipe with its number of samples (the sheet cuts the dataset down to what it shows).
fn build(options: &WatchOptions) -> Result<(Preview, Vec<PathBuf>, (Recipe, u64))> {
    let mut recipe = Recipe::load(&options.recipe, &options.sets)?;
    let samples = recipe.dataset.samples;
    let preview = sheet::render(&mut recipe, &options.preview)?;
    // After rendering: drawing the preview's samples may have read more mesh files.
    let files = recipe.watched_paths();
    Ok((preview, files, (recipe, samples)))
}

fn summary(preview: &Preview, start: Instant, out: &Path) -> String {
    // The sheet fits a screen: say when that left images out.
    let shown = if preview.shown < preview.images {
        format!(" ({} of {} images shown)", preview.shown, preview.images)
    } else {
        String::new()
    };
    format!(
        "preview: {} samples × {} views at {}×{}{shown} in {:.2} s → {}",
        preview.samples,
        preview.views,
        preview.width,
        preview.height,
        start.elapsed().as_secs_f64(),
        out.display()
    )
}

enum Message {
    Files(notify::Result<Event>),
    Stop,
}

/// The relevant paths of one save, and when its first event came.
struct Batch {
    paths: BTreeSet<PathBuf>,
    since: Instant,
}

struct Session<'a> {
    options: &'a WatchOptions,
    out: PathBuf,
    watched: Watched,
    watcher: notify::RecommendedWatcher,
    events: Receiver<Message>,
    server: Option<Arc<Server>>,
    has_preview: bool,
    scene_pass: ScenePasses,
}

impl<'a> Session<'a> {
    fn new(options: &'a WatchOptions, out: PathBuf) -> Result<Self> {
        let (tx, events) = channel();
        let stop = tx.clone();
        ctrlc::set_handler(move || {
            let _ = stop.send(Message::Stop);
        })
        .context("installing the Ctrl-C handler")?;
        let watcher = notify::recommended_watcher(move |event| {
            let _ = tx.send(Message::Files(event));
        })
        .context("starting the file watcher")?;
        let server = options.serve.map(Server::start).transpose()?.map(Arc::new);
        if let Some(server) = &server {
            println!("serving the preview at {}", server.url);
        }
        let mut session = Session {
            options,
            watched: Watched::new(&options.recipe, &out),
            out,
            watcher,
            events,
            scene_pass: ScenePasses::new(server.clone()),
            server,
            has_preview: false,
        };
        // Watch before the first build, so an edit made while it runs is not missed.
        session.watched.watch(&mut session.watcher, Vec::new());
        Ok(session)
    }

    fn run(mut self) -> Result<()> {
        self.reload(None);
        println!(
            "watching {} and the files it uses; Ctrl-C stops",
            self.options.recipe.display()
        );
        while let Some(batch) = next_batch(&self.events, &self.watched) {
            if self.watched.changed(&batch.paths) {
                self.reload(Some(batch.since));
            }
        }
        println!("stopped watching");
        Ok(())
    }

    /// Rebuilds the sheet; on any error shows it and keeps the last good sheet. `since` is
    /// when the change that caused it was first seen.
    fn reload(&mut self, since: Option<Instant>) {
        let start = Instant::now();
        self.scene_pass.abandon();
        self.watched.snapshot();
        let result = build(self.options).and_then(|(preview, files, recipe)| {
            self.watched.watch(&mut self.watcher, files);
            write_atomic(&self.out, &preview.png)?;
            Ok((preview, recipe))
        });
        match result {
            Ok((preview, (recipe, samples))) => {
                let line = summary(&preview, start, &self.out);
                match since {
                    Some(since) => println!(
                        "{line} ({:.2} s after the change)",
                        since.elapsed().as_secs_f64()
                    ),
                    None => println!("{line}"),
                }
                if let Some(server) = &self.server {
                    server.publish(preview.png, line);
                }
                self.has_preview = true;
                self.scene_pass.start(recipe, samples, preview.samples);
            }
            Err(e) => {
                let error = format!("{e:#}");
                eprintln!("{error}");
                eprintln!(
                    "{}",
                    if self.has_preview {
                        "keeping the last good preview"
                    } else {
                        "no preview yet: waiting for a good save"
                    }
                );
                if let Some(server) = &self.server {
                    server.fail(error);
                }
            }
        }
    }
}

/// Runs the background scene pass of the latest good sheet, one at a time.
struct ScenePasses {
    /// Counts reloads; a pass stops as soon as it no longer runs for the latest one.
    generation: Arc<AtomicU64>,
    /// Held while a pass reports and while a reload moves the generation on, so that an
    /// abandoned pass can never print after the reload has begun.
    reporting: Arc<Mutex<()>>,
    server: Option<Arc<Server>>,
}

/// How often a long pass says how far it got.
const PROGRESS_EVERY: Duration = Duration::from_secs(10);

impl ScenePasses {
    fn new(server: Option<Arc<Server>>) -> Self {
        ScenePasses {
            generation: Arc::default(),
            reporting: Arc::default(),
            server,
        }
    }

    /// Abandons the running pass (it stops before its next sample, and says nothing more).
    fn abandon(&self) {
        let _reporting = self.reporting.lock().unwrap();
        self.generation.fetch_add(1, Ordering::SeqCst);
    }

    /// Draws the scenes of all `samples` of `recipe` on one background thread, so that the
    /// watcher, the sheet's renders and the editor stay responsive. `shown` samples are on
    /// the sheet.
    fn start(&self, recipe: Recipe, samples: u64, shown: u64) {
        let pass = Pass {
            generation: self.generation.clone(),
            mine: self.generation.load(Ordering::SeqCst),
            reporting: self.reporting.clone(),
            server: self.server.clone(),
            samples,
            shown,
        };
        let spawned = std::thread::Builder::new()
            .name("scene pass".into())
            .spawn(move || pass.run(&recipe));
        if let Err(e) = spawned {
            eprintln!("warning: cannot start the scene pass: {e}");
        }
    }
}

/// One background pass over every sample's scene.
struct Pass {
    generation: Arc<AtomicU64>,
    /// The generation this pass runs for.
    mine: u64,
    reporting: Arc<Mutex<()>>,
    server: Option<Arc<Server>>,
    samples: u64,
    shown: u64,
}

impl Pass {
    fn current(&self) -> bool {
        self.generation.load(Ordering::SeqCst) == self.mine
    }

    fn run(&self, recipe: &Recipe) {
        // A pool of one thread: the pass must not compete with the sheet for every core,
        // and in one thread it draws the samples in order.
        let pool = match rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .thread_name(|_| "scene pass".into())
            .build()
        {
            Ok(pool) => pool,
            Err(e) => return eprintln!("warning: cannot start the scene pass: {e}"),
        };
        let start = Instant::now();
        let last_said = Mutex::new(start);
        let drawn = AtomicU64::new(0);
        let stop = || {
            let n = drawn.fetch_add(1, Ordering::Relaxed);
            self.progress(n, start, &mut last_said.lock().unwrap());
            !self.current()
        };
        let outcome = pool.install(|| draw_scenes(recipe, 0..self.samples, &stop));
        self.report(outcome);
    }

    /// Every `PROGRESS_EVERY`, how many samples are drawn: a dataset of many thousands
    /// takes a while, and the engineer should know the pass is still going.
    fn progress(&self, drawn: u64, start: Instant, last_said: &mut Instant) {
        if last_said.elapsed() < PROGRESS_EVERY {
            return;
        }
        *last_said = Instant::now();
        let _reporting = self.reporting.lock().unwrap();
        if self.current() {
            println!(
                "scenes: {drawn} of {} samples drawn without error so far ({:.0} s)",
                self.samples,
                start.elapsed().as_secs_f64()
            );
        }
    }

    fn report(&self, outcome: ScenePass) {
        let _reporting = self.reporting.lock().unwrap();
        if !self.current() {
            return;
        }
        match outcome {
            ScenePass::Passed { seconds } => {
                let line = scenes_passed(self.samples, seconds);
                println!("{line}");
                if let Some(server) = &self.server {
                    server.scenes_checked(line);
                }
            }
            ScenePass::Failed {
                sample,
                error,
                seconds,
            } => {
                let error = format!(
                    "{error}\nscenes: the scene of sample {sample} fails (found after drawing {} of {} samples in {seconds:.2} s; the sheet shows samples 0–{})",
                    sample + 1,
                    self.samples,
                    self.shown.saturating_sub(1)
                );
                eprintln!("{error}");
                if let Some(server) = &self.server {
                    server.fail(error);
                }
            }
            ScenePass::Abandoned => {}
        }
    }
}

/// Waits for events that concern the recipe, then until the folder has been quiet for
/// `QUIET`. None when asked to stop.
fn next_batch(events: &Receiver<Message>, watched: &Watched) -> Option<Batch> {
    let mut paths = BTreeSet::new();
    let mut since = None;
    let mut deadline: Option<Instant> = None;
    loop {
        let message = match deadline {
            None => events.recv().ok()?,
            Some(deadline) => {
                match events.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
                    Ok(message) => message,
                    Err(RecvTimeoutError::Timeout) => break,
                    Err(RecvTimeoutError::Disconnected) => return None,
                }
            }
        };
        let event = match message {
            Message::Stop => return None,
            Message::Files(Err(e)) => {
                eprintln!("warning: file watcher: {e}");
                continue;
            }
            Message::Files(Ok(event)) => event,
        };
        if !changes_content(&event.kind) {
            continue;
        }
        let mut relevant = event.paths.into_iter().filter(|p| watched.concerns(p));
        if let Some(first) = relevant.next() {
            paths.insert(first);
            paths.extend(relevant);
            since.get_or_insert_with(Instant::now);
            deadline = Some(Instant::now() + QUIET);
        }
    }
    Some(Batch {
        paths,
        since: since.expect("a batch has a first event"),
    })
}

/// Events that may change what a file holds; opening, reading and metadata-only changes
/// (editors touch those often) do not count.
fn changes_content(kind: &EventKind) -> bool {
    match kind {
        EventKind::Access(access) => matches!(access, AccessKind::Close(AccessMode::Write)),
        EventKind::Modify(modify) => !matches!(modify, ModifyKind::Metadata(_)),
        _ => true,
    }
}

/// The files a recipe depends on, the folders watched for them, and what each file held when
/// it last triggered a reload.
struct Watched {
    recipe: PathBuf,
    recipe_folder: PathBuf,
    out: PathBuf,
    files: BTreeSet<PathBuf>,
    folders: BTreeSet<PathBuf>,
    seen: HashMap<PathBuf, Option<blake3::Hash>>,
}

impl Watched {
    fn new(recipe: &Path, out: &Path) -> Self {
        let recipe = absolute(recipe);
        Watched {
            recipe_folder: recipe.parent().map(Path::to_path_buf).unwrap_or_default(),
            recipe,
            out: absolute(out),
            files: BTreeSet::new(),
            folders: BTreeSet::new(),
            seen: HashMap::new(),
        }
    }

    /// Watches the folders of `files` (the recipe's dependencies after a good load), the
    /// recipe's folder and the folders directly inside it, and stops watching folders no
    /// longer needed (an import was removed).
    fn watch(&mut self, watcher: &mut impl Watcher, files: Vec<PathBuf>) {
        self.files = files.iter().map(|f| absolute(f)).collect();
        self.files.insert(self.recipe.clone());
        let wanted: BTreeSet<PathBuf> = self
            .files
            .iter()
            .filter_map(|f| f.parent().map(Path::to_path_buf))
            .chain(subfolders(&self.recipe_folder))
            .collect();
        for gone in self.folders.difference(&wanted) {
            let _ = watcher.unwatch(gone);
        }
        let mut watching = BTreeSet::new();
        for folder in wanted {
            if self.folders.contains(&folder) {
                watching.insert(folder);
                continue;
            }
            match watcher.watch(&folder, RecursiveMode::NonRecursive) {
                Ok(()) => {
                    watching.insert(folder);
                }
                Err(e) => eprintln!("warning: cannot watch {}: {e}", folder.display()),
            }
        }
        self.folders = watching;
    }

    /// Whether an event on `path` may change the preview: a file the recipe used, or a
    /// source-like file in the recipe's folder. Never the sheet itself or an editor's scratch
    /// file (backup, swap, vim's `4913` probe, temporary files of atomic saves).
    fn concerns(&self, path: &Path) -> bool {
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
            return false;
        };
        if path == self.out || name.ends_with(PREVIEW_SUFFIX) || is_scratch(name) {
            return false;
        }
        self.files.contains(path)
            || path.starts_with(&self.recipe_folder)
                && path
                    .extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| SOURCE_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
    }

    /// Records what each path holds now. True when any differs from what it held at the last
    /// reload (a path never seen counts as changed): saving identical content, or a save
    /// split over two batches, does not reload twice.
    fn changed(&mut self, paths: &BTreeSet<PathBuf>) -> bool {
        let mut any = false;
        for path in paths {
            let now = content(path);
            any |= self.seen.insert(path.clone(), now) != Some(now);
        }
        any
    }

    /// Records what every known dependency holds, just before a reload reads them: a later
    /// write then always differs from the record, and an event already queued for content
    /// the reload has read does not reload again.
    fn snapshot(&mut self) {
        for file in &self.files {
            self.seen.insert(file.clone(), content(file));
        }
    }
}

/// Hash of a file's bytes; None when it cannot be read (deleted, say).
fn content(path: &Path) -> Option<blake3::Hash> {
    std::fs::read(path).ok().map(|b| blake3::hash(&b))
}

/// The visible folders directly inside `folder`. A recipe's textures, meshes and backgrounds
/// live there, and some count before the recipe has read them: an image dropped into
/// `textures/` under a prompt's name becomes that prompt's texture.
fn subfolders(folder: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect()
}

fn is_scratch(name: &str) -> bool {
    let extension = name.rsplit_once('.').map_or("", |(_, e)| e);
    name.ends_with('~')
        || name.starts_with(".#")
        || name == "4913"
        || matches!(extension, "swp" | "swx" | "tmp")
}

/// `path` made absolute with its folder's symlinks resolved, as the watcher reports paths
/// inside the (resolved) folders it watches.
fn absolute(path: &Path) -> PathBuf {
    let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    match (path.parent(), path.file_name()) {
        (Some(folder), Some(name)) => folder.canonicalize().map(|f| f.join(name)).unwrap_or(path),
        _ => path,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn editor_scratch_files_and_previews_do_not_count() {
        let dir = tempfile::tempdir().unwrap();
        let recipe = dir.path().join("study.rhai");
        let mut watched = Watched::new(&recipe, &default_out(&recipe));
        watched.files.insert(watched.recipe.clone());
        let folder = watched.recipe_folder.clone();
        for yes in [
            "study.rhai",
            "piece.rhai",
            "models/pier.obj",
            "tex/rust.JPG",
        ] {
            assert!(watched.concerns(&folder.join(yes)), "{yes}");
        }
        for no in [
            "study.rhai~",
            ".study.rhai.swp",
            "4913",
            "study.rhai.tmp",
            ".#study.rhai",
            "study.preview.png",
            "other.preview.png",
            "notes.txt",
        ] {
            assert!(!watched.concerns(&folder.join(no)), "{no}");
        }
        assert!(!watched.concerns(Path::new("/elsewhere/x.rhai")));
    }

    #[test]
    fn identical_content_is_not_a_change() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a.rhai");
        let mut watched = Watched::new(&file, &dir.path().join("a.png"));
        let paths = BTreeSet::from([file.clone()]);
        std::fs::write(&file, "1").unwrap();
        assert!(watched.changed(&paths), "first sight counts");
        assert!(!watched.changed(&paths));
        std::fs::write(&file, "2").unwrap();
        assert!(watched.changed(&paths));
        std::fs::remove_file(&file).unwrap();
        assert!(watched.changed(&paths), "deleted");
        assert!(!watched.changed(&paths), "still deleted");
    }

    #[test]
    fn reads_and_metadata_do_not_trigger() {
        use notify::event::{CreateKind, MetadataKind, RemoveKind};
        assert!(changes_content(&EventKind::Create(CreateKind::File)));
        assert!(changes_content(&EventKind::Remove(RemoveKind::File)));
        assert!(changes_content(&EventKind::Access(AccessKind::Close(
            AccessMode::Write
        ))));
        assert!(!changes_content(&EventKind::Access(AccessKind::Open(
            AccessMode::Any
        ))));
        assert!(!changes_content(&EventKind::Modify(ModifyKind::Metadata(
            MetadataKind::Any
        ))));
    }
}
