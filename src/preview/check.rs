//! `shmgen check`: validates a recipe and estimates what the full run will cost, without
//! writing the dataset.
//!
//! Owns: the report (dataset settings, structure sizes, run-time and disk estimates) and the
//! scene pass, which draws every sample's scene (the recipe's closure alone, nothing meshed or
//! rendered) so that an error in a branch only some samples take is found before the run;
//! `watch` runs the same pass in the background. Must not touch: the renderer or the dataset
//! format: the estimate times a real `pipeline::run` of a few samples into a temporary
//! folder, which is removed.

use crate::build::BuiltSample;
use crate::pipeline::{self, RunOptions, Shard, prepare};
use crate::recipe::{Recipe, RecipeError};
use crate::scene::Structure;
use anyhow::Result;
use rayon::prelude::*;
use std::collections::{BTreeMap, HashSet};
use std::ops::{ControlFlow, Range};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Samples drawn and meshed for the structure report.
const DRAWN: u64 = 8;

/// Runs `shmgen check`.
pub fn check(path: &Path, sets: &[(String, String)], threads: Option<usize>) -> Result<()> {
    let mut recipe = Recipe::load(path, sets)?;
    print_dataset(&recipe);
    let drawn = recipe.dataset.samples.min(DRAWN);
    let samples = (0..drawn)
        .into_par_iter()
        .map(|index| prepare(&recipe, index))
        .collect::<Result<Vec<_>>>()?;
    print_structures(&samples);
    // The samples above were drawn in full; the pass draws the scenes of all the others.
    let total = recipe.dataset.samples;
    match draw_scenes(&recipe, drawn..total, &|| false) {
        ScenePass::Passed { seconds } => println!("  {}", scenes_passed(total, seconds)),
        ScenePass::Failed { error, .. } => return Err(error.into()),
        ScenePass::Abandoned => unreachable!("the pass of `check` is never stopped"),
    }
    estimate(&mut recipe, threads)
}

/// How drawing the scenes of a range of samples ended.
pub enum ScenePass {
    /// Every scene was drawn without error.
    Passed { seconds: f64 },
    /// The scene of `sample`, the lowest failing one, fails with `error`.
    Failed {
        sample: u64,
        error: RecipeError,
        seconds: f64,
    },
    /// Stopped on request before the end.
    Abandoned,
}

/// Samples drawn one after the other by one task of the pass.
const SCENES_PER_TASK: u64 = 64;

/// Draws the scene of every sample in `samples` on the current rayon pool (a pool of one
/// thread draws them in order), stopping at the first error or as soon as `stop` says so
/// (asked before each sample). The error reported is that of the lowest failing sample, so
/// that it does not depend on the number of threads.
pub fn draw_scenes(
    recipe: &Recipe,
    samples: Range<u64>,
    stop: &(dyn Fn() -> bool + Sync),
) -> ScenePass {
    let start = Instant::now();
    let tasks = samples
        .end
        .saturating_sub(samples.start)
        .div_ceil(SCENES_PER_TASK);
    let failure = (0..tasks).into_par_iter().find_map_first(|task| {
        let first = samples.start + task * SCENES_PER_TASK;
        let part = first..(first + SCENES_PER_TASK).min(samples.end);
        first_failure(recipe, part, stop)
    });
    let seconds = start.elapsed().as_secs_f64();
    match failure {
        None => ScenePass::Passed { seconds },
        Some(Some((sample, error))) => ScenePass::Failed {
            sample,
            error,
            seconds,
        },
        Some(None) => ScenePass::Abandoned,
    }
}

/// The first failing sample of `samples` and its error; `Some(None)` when stopped first.
fn first_failure(
    recipe: &Recipe,
    samples: Range<u64>,
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<Option<(u64, RecipeError)>> {
    if stop() {
        return Some(None);
    }
    let (first, last) = (samples.start, samples.end.saturating_sub(1));
    let mut found = None;
    // After each sample but the last, `stop` is asked before the next one is drawn: once
    // per sample in all.
    let drawn = recipe.each_scene(samples, |sample, scene| {
        if let Err(error) = scene {
            found = Some(Some((sample, error)));
        } else if sample < last && stop() {
            found = Some(None);
        }
        match found {
            Some(_) => ControlFlow::Break(()),
            None => ControlFlow::Continue(()),
        }
    });
    match drawn {
        Ok(()) => found,
        Err(error) => Some(Some((first, error))),
    }
}

/// The line that says every scene was drawn, and how long the pass took.
pub fn scenes_passed(samples: u64, seconds: f64) -> String {
    format!(
        "scenes: all {} drawn without error (scene pass {:.2} s)",
        counted(samples, "sample"),
        seconds
    )
}

fn print_dataset(recipe: &Recipe) {
    let d = &recipe.dataset;
    let outputs: Vec<&str> = d.outputs.chosen().collect();
    println!(
        "{}: dataset \"{}\", seed {}",
        recipe.path.display(),
        d.name,
        d.seed
    );
    println!(
        "  {} samples × {} views = {} views at {}×{}; outputs {}",
        d.samples,
        d.views,
        d.samples * u64::from(d.views),
        d.camera.width,
        d.camera.height,
        outputs.join(", ")
    );
}

/// Per kind of structure: how many, and min / median / max of vertices and triangles.
fn print_structures(samples: &[BuiltSample]) {
    let mut kinds: BTreeMap<String, Vec<(usize, usize)>> = BTreeMap::new();
    for sample in samples {
        for (kind, size) in structure_sizes(sample) {
            kinds.entry(kind).or_default().push(size);
        }
    }
    println!(
        "  structures in samples 0–{} (drawn and meshed at full resolution):",
        samples.len().saturating_sub(1)
    );
    for (kind, sizes) in kinds {
        let (vertices, triangles): (Vec<usize>, Vec<usize>) = sizes.iter().copied().unzip();
        println!(
            "    {kind}: {}, vertices {}, triangles {} (min / median / max)",
            sizes.len(),
            spread(vertices),
            spread(triangles)
        );
    }
}

/// (kind, (vertices, triangles)) of every structure of a sample (its drawn supports
/// included). A ground is no structure: its triangles, owned by the id past the last
/// structure's, come last in the mesh and are left out.
fn structure_sizes(sample: &BuiltSample) -> Vec<(String, (usize, usize))> {
    let structures = &sample.scene.structures;
    let mut vertices = vec![HashSet::<u32>::new(); structures.len()];
    let mut triangles = vec![0; structures.len()];
    let structure_triangles = &sample.mesh.triangles[..sample.structure_triangles()];
    for (triangle, &owner) in structure_triangles.iter().zip(&sample.owner) {
        vertices[owner as usize].extend(triangle);
        triangles[owner as usize] += 1;
    }
    structures
        .iter()
        .zip(vertices.iter().zip(triangles))
        .map(|(structure, (v, t))| {
            let kind = match structure {
                Structure::Beam(_) => "beam".to_string(),
                Structure::Assembly(a) => format!("assembly \"{}\"", a.name),
                Structure::Frame(f) => format!("frame \"{}\"", f.name),
            };
            (kind, (v.len(), t))
        })
        .collect()
}

/// "min / median / max" of some counts.
fn spread(mut values: Vec<usize>) -> String {
    values.sort_unstable();
    let at = |i: usize| values[i].to_string();
    match values.len() {
        0 => "-".into(),
        n => format!("{} / {} / {}", at(0), at((n - 1) / 2), at(n - 1)),
    }
}

/// Times a real run of one round of samples (one per thread) and scales it to the dataset.
fn estimate(recipe: &mut Recipe, threads: Option<usize>) -> Result<()> {
    let threads = threads.unwrap_or_else(rayon::current_num_threads).max(1);
    let total = recipe.dataset.samples;
    let timed = total.min(threads as u64);
    recipe.dataset.samples = timed;
    let scratch = Scratch::new();
    let summary = pipeline::run(
        recipe,
        &RunOptions {
            out: scratch.0.clone(),
            threads: Some(threads),
            shard: Shard::WHOLE,
            frames_per_unit: None,
            force: true,
            quiet: true,
        },
    )?;
    let scale = total as f64 / timed as f64;
    let threads = counted(threads as u64, "thread");
    println!(
        "  timed run: {} ({} views) on {threads} in {:.2} s, {}",
        counted(timed, "sample"),
        summary.pairs,
        summary.seconds,
        bytes(summary.bytes as f64)
    );
    println!(
        "  estimate for all {total} samples on {threads}: {}, {} on disk",
        duration(summary.seconds * scale),
        bytes(summary.bytes as f64 * scale)
    );
    Ok(())
}

/// A temporary dataset folder, removed however `check` ends.
struct Scratch(PathBuf);

impl Scratch {
    fn new() -> Self {
        Scratch(std::env::temp_dir().join(format!("shmgen-check-{}", std::process::id())))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn duration(seconds: f64) -> String {
    match seconds {
        s if s < 120.0 => format!("{s:.1} s"),
        s if s < 7200.0 => format!("{:.0} min", s / 60.0),
        s => format!("{:.1} h", s / 3600.0),
    }
}

fn bytes(b: f64) -> String {
    match b {
        b if b < 1e6 => format!("{:.0} kB", b / 1e3),
        b if b < 1e9 => format!("{:.1} MB", b / 1e6),
        b => format!("{:.2} GB", b / 1e9),
    }
}

/// `1 thread`, `2 threads`.
fn counted(n: u64, noun: &str) -> String {
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// 200 samples whose scenes fail at samples 130 and 170 only.
    fn failing_at_130_and_170() -> (tempfile::TempDir, Recipe) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.rhai");
        std::fs::write(
            &path,
            "dataset(#{ samples: 200, scene: |rng| {\n    let b = beam(#{ length: 1.0, width: 0.1, height: 0.1 });\n    if rng.sample == 130 || rng.sample == 170 { b = b.materail(\"steel\"); }\n    b\n} })\n",
        )
        .unwrap();
        let recipe = Recipe::load(&path, &[]).unwrap();
        (dir, recipe)
    }

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    #[test]
    fn the_pass_reports_the_lowest_failing_sample_whatever_the_threads() {
        let (_dir, recipe) = failing_at_130_and_170();
        for threads in [1, 2] {
            match pool(threads).install(|| draw_scenes(&recipe, 0..200, &|| false)) {
                ScenePass::Failed { sample, error, .. } => {
                    assert_eq!(sample, 130, "{threads} threads");
                    assert!(error.to_string().contains("sample 130"), "{error}");
                }
                _ => panic!("{threads} threads: the pass did not fail"),
            }
        }
        assert!(matches!(
            draw_scenes(&recipe, 0..130, &|| false),
            ScenePass::Passed { .. }
        ));
        assert!(matches!(
            draw_scenes(&recipe, 171..200, &|| false),
            ScenePass::Passed { .. }
        ));
    }

    /// Asked once before each sample, and the pass ends as soon as it says stop.
    #[test]
    fn the_pass_stops_when_asked() {
        let (_dir, recipe) = failing_at_130_and_170();
        let asked = AtomicU64::new(0);
        let stop = || asked.fetch_add(1, Ordering::SeqCst) + 1 >= 100;
        let pass = pool(1).install(|| draw_scenes(&recipe, 0..200, &stop));
        assert!(matches!(pass, ScenePass::Abandoned));
        assert_eq!(asked.load(Ordering::SeqCst), 100);
        let asked = AtomicU64::new(0);
        let never = || {
            asked.fetch_add(1, Ordering::SeqCst);
            false
        };
        pool(1).install(|| draw_scenes(&recipe, 0..130, &never));
        assert_eq!(asked.load(Ordering::SeqCst), 130, "once per sample");
    }

    #[test]
    fn spreads_and_units() {
        assert_eq!(spread(vec![5, 1, 3, 2]), "1 / 2 / 5");
        assert_eq!(spread(vec![7]), "7 / 7 / 7");
        assert_eq!(duration(30.0), "30.0 s");
        assert_eq!(duration(600.0), "10 min");
        assert_eq!(duration(36000.0), "10.0 h");
        assert_eq!(bytes(2.5e6), "2.5 MB");
        assert_eq!(bytes(51_200.0), "51 kB");
        assert_eq!(bytes(3.2e9), "3.20 GB");
        assert_eq!(counted(1, "thread"), "1 thread");
        assert_eq!(counted(2, "sample"), "2 samples");
    }
}
