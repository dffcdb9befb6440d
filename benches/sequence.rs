//! Sequence benchmark: rig frames per second of whole runs of `scripts/monitoring.rhai` (960²,
//! 2 views, 60 fps, 4 s, every default output written to disk), median of whole runs on 2
//! threads, with the CPU seconds the process spent per frame (the machine is shared: wall time
//! counts other jobs, CPU time does not); then the cost of one rig frame broken down by stage,
//! CPU time of one thread, median over the frames of the first sample.
//! Prints tables; asserts nothing (speed is measured, never tested).
//!
//!     cargo bench --bench sequence
//!     SHMGEN_BENCH_RUNS=1 SHMGEN_BENCH_FRAMES=30 cargo bench --bench sequence   (quicker)
//!
//! The stages of a frame, in the order the run does them: the frame's scene from the sample's
//! motion (`SampleMotion::scene_at`), building and tessellating it (`build_framed`), preparing
//! its mesh for tracing and the BVH, the sample's own files (meshes, when asked for),
//! then per view: the visibility raster (centre rays), shading the RGB, the labels (mask), the
//! writers' encoding (PNG, EXR) and writing the files.

use shmgen::build::build_framed;
use shmgen::output::{SAMPLE_WRITERS, ViewLayers, WRITERS};
use shmgen::pipeline::{SampleGeometry, SampleMotion, SampleRenderer, prepare};
use shmgen::recipe::Recipe;
use shmgen::render::TraceMesh;
use std::path::Path;
use std::sync::Arc;

#[path = "support/mod.rs"]
mod support;
use support::{median, run_in_temp, setting};

/// CPU seconds this thread has used.
fn thread_cpu_seconds() -> f64 {
    cpu_seconds(libc::CLOCK_THREAD_CPUTIME_ID)
}

/// CPU seconds this process has used, every thread.
fn process_cpu_seconds() -> f64 {
    cpu_seconds(libc::CLOCK_PROCESS_CPUTIME_ID)
}

fn cpu_seconds(clock: libc::clockid_t) -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec, which `t` is.
    let status = unsafe { libc::clock_gettime(clock, &mut t) };
    assert_eq!(status, 0, "clock_gettime({clock})");
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

fn monitoring(sets: &[(&str, &str)]) -> Recipe {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/monitoring.rhai");
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    Recipe::load(&path, &sets).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// One whole run into a fresh folder on `threads` threads: (rig frames per second of wall
/// time, CPU milliseconds per rig frame).
fn run_once(recipe: &Recipe, threads: usize) -> (f64, f64) {
    let cpu = process_cpu_seconds();
    let summary = run_in_temp(recipe, threads);
    let cpu = process_cpu_seconds() - cpu;
    let frames = summary.pairs as f64 / f64::from(recipe.dataset.cameras_per_sample());
    (frames / summary.seconds, 1e3 * cpu / frames)
}

/// CPU milliseconds of each stage, per rig frame (several calls in one frame, one per view,
/// add up), collected over frames.
#[derive(Default)]
struct Stages {
    names: Vec<&'static str>,
    /// Per stage: (frame, milliseconds) of every frame it ran in.
    times: Vec<Vec<(usize, f64)>>,
    frame: usize,
}

impl Stages {
    /// Starts the next frame.
    fn new_frame(&mut self) {
        self.frame += 1;
    }

    /// Runs `f`, adding its thread CPU time to stage `name` of the current frame.
    fn time<T>(&mut self, name: &'static str, f: impl FnOnce() -> T) -> T {
        let start = thread_cpu_seconds();
        let value = f();
        let ms = 1e3 * (thread_cpu_seconds() - start);
        let i = match self.names.iter().position(|n| *n == name) {
            Some(i) => i,
            None => {
                self.names.push(name);
                self.times.push(Vec::new());
                self.names.len() - 1
            }
        };
        match self.times[i].last_mut() {
            Some((frame, sum)) if *frame == self.frame => *sum += ms,
            _ => self.times[i].push((self.frame, ms)),
        }
        value
    }
}

/// The stages of the first `frames` frames of sample 0, timed one frame at a time on one
/// thread; prints the median of each stage per rig frame and their sum.
fn breakdown(recipe: &Recipe, frames: usize) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let dataset = &recipe.dataset;
    let mut stages = Stages::default();
    pool.install(|| {
        let sample = prepare(recipe, 0).unwrap();
        let sequence = dataset.sequence.as_ref().expect("a sequence");
        let motion = stages.time("mechanics (motion, per sample)", || {
            SampleMotion::new(&sample.scene, sequence).ok().unwrap()
        });
        let framing = sample.framing();
        let every = (motion.frames() / frames.max(1)).max(1);
        for k in (0..motion.frames()).step_by(every).take(frames) {
            stages.new_frame();
            let scene = stages.time("scene_at", || motion.scene_at(&sample.scene, k));
            let frame = stages.time("build + tessellate", || {
                build_framed(dataset, 0, scene, Some(framing)).ok().unwrap()
            });
            let core = frame.structure_triangles();
            let mesh = stages.time("trace mesh", || {
                TraceMesh::build_with_core(&frame.mesh, core)
            });
            stages.time("BVH", || mesh.build_bvh());
            stages.time("sample files", || {
                let geometry = SampleGeometry::new(dataset, &frame);
                let wanted = SAMPLE_WRITERS
                    .iter()
                    .filter(|w| dataset.outputs.wants(w.output));
                wanted
                    .map(|w| (w.write)(&geometry).unwrap().len())
                    .sum::<usize>()
            });
            let renderer = SampleRenderer::with_trace_mesh(dataset, &frame, Arc::new(mesh));
            for view in 0..dataset.cameras_per_sample() {
                let rendered = stages.time("raster", || renderer.view(view).unwrap());
                stages.time("shade", || rendered.rgb().len());
                stages.time("labels (mask, coverage)", || {
                    (rendered.mask().len(), rendered.coverage())
                });
                let files = stages.time("encode", || {
                    let wanted = WRITERS.iter().filter(|w| dataset.outputs.wants(w.output));
                    wanted
                        .flat_map(|w| (w.write)(&rendered as &dyn ViewLayers).unwrap())
                        .collect::<Vec<_>>()
                });
                stages.time("write", || {
                    for (i, bytes) in files.iter().enumerate() {
                        std::fs::write(dir.path().join(format!("{view}_{i}")), bytes).unwrap();
                    }
                });
            }
        }
    });
    println!(
        "per-stage CPU ms per rig frame ({} views, 1 thread, median over {frames} frames of sample 0):",
        dataset.cameras_per_sample()
    );
    println!("| stage | ms |");
    println!("|---|---:|");
    let mut total = 0.0;
    for (name, times) in stages.names.iter().zip(&stages.times) {
        let ms = median(times.iter().map(|t| t.1).collect());
        if !name.contains("per sample") {
            total += ms;
        }
        println!("| {name} | {ms:.2} |");
    }
    println!(
        "| sum per frame | {total:.2} (→ {:.0} frames/s a core) |",
        1e3 / total
    );
}

fn main() {
    let runs = setting("SHMGEN_BENCH_RUNS", 3);
    let frames = setting("SHMGEN_BENCH_FRAMES", 60) as usize;
    let recipe = monitoring(&[]);
    let threads = 2;
    let measured: Vec<(f64, f64)> = (0..runs).map(|_| run_once(&recipe, threads)).collect();
    let rate = median(measured.iter().map(|m| m.0).collect());
    let cpu = median(measured.iter().map(|m| m.1).collect());
    println!("| recipe | size | threads | rig frames/s (median of {runs}) | CPU ms per frame |");
    println!("|---|---|---:|---:|---:|");
    println!("| monitoring.rhai | 960² × 2 views | {threads} | {rate:.1} | {cpu:.1} |");
    println!();
    breakdown(&recipe, frames);
}
