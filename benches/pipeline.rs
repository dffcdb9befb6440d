//! Pipeline benchmark: image/depth pairs per second for the quickstart scene at 960×960 with
//! RGB, depth, mask and JSON written, plus a per-stage breakdown of one view. Prints medians;
//! asserts nothing (speed is measured, never tested).
//!
//!     cargo bench --bench pipeline

use shmgen::materials::Backdrop;
use shmgen::output::{depth_exr, mask_png, rgb_png};
use shmgen::pipeline::{self, RunOptions, Shard, prepare, view_camera};
use shmgen::recipe::Recipe;
use shmgen::render::{SampleSurfaces, TraceMesh, shade};
use std::path::Path;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let recipe_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/quickstart.rhai");
    let samples = 10u64;
    let sets = [
        ("samples".to_string(), samples.to_string()),
        ("views".to_string(), "20".to_string()),
    ];
    let mut recipe = Recipe::load(&recipe_path, &sets).expect("quickstart loads");
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "shmgen pipeline benchmark: quickstart, {samples} beams × 20 views at 960×960, RGB + depth + mask + JSON, {cores} cores"
    );

    for (threads, antialias) in [(1, true), (cores, true), (cores, false)] {
        recipe.dataset.antialias = antialias;
        let mut rates = Vec::new();
        for _ in 0..5 {
            let dir = tempfile::tempdir().unwrap();
            let options = RunOptions {
                out: dir.path().join("ds"),
                threads: Some(threads),
                shard: Shard::WHOLE,
                force: false,
                quiet: true,
            };
            let summary = pipeline::run(&recipe, &options).expect("run");
            rates.push(summary.pairs as f64 / summary.seconds);
        }
        let label = if antialias { "on" } else { "off" };
        let runs: Vec<String> = rates.iter().map(|r| format!("{r:.1}")).collect();
        println!(
            "  {threads} thread(s), anti-aliasing {label}: median {:.1} pairs/s ({:.1} ms per pair), runs {runs:?}",
            median(rates.clone()),
            1e3 / median(rates)
        );
    }

    // Per-stage cost of single views, one thread.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let mut stages: [(&str, Vec<f64>); 7] = [
            ("prepare scene+mesh", vec![]),
            ("BVH build", vec![]),
            ("trace", vec![]),
            ("shade", vec![]),
            ("RGB PNG", vec![]),
            ("depth EXR", vec![]),
            ("mask PNG", vec![]),
        ];
        let mut coverage = Vec::new();
        for s in 0..samples {
            let t = Instant::now();
            let sample = prepare(&recipe, s).unwrap();
            stages[0].1.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            let mesh = TraceMesh::build(&sample.mesh);
            stages[1].1.push(t.elapsed().as_secs_f64());
            for view in 0..20 {
                let camera = view_camera(&recipe.dataset, &sample, view).unwrap().camera;
                let t = Instant::now();
                let g = mesh.trace(&camera);
                stages[2].1.push(t.elapsed().as_secs_f64());
                coverage.push(
                    g.triangle.iter().filter(|&&t| t != u32::MAX).count() as f64
                        / g.triangle.len() as f64,
                );
                let t = Instant::now();
                let surfaces = SampleSurfaces {
                    mesh: &sample.mesh,
                    rest: &sample.rest,
                    piece: &sample.piece,
                    pieces: &sample.pieces,
                    shaders: &sample.shaders,
                };
                let rgb = shade(
                    &g,
                    &mesh,
                    &camera,
                    &sample.lighting,
                    &surfaces,
                    &Backdrop::Colour([0, 0, 0]),
                    true,
                );
                stages[3].1.push(t.elapsed().as_secs_f64());
                let t = Instant::now();
                std::hint::black_box(rgb_png(g.width, g.height, &rgb));
                stages[4].1.push(t.elapsed().as_secs_f64());
                let t = Instant::now();
                std::hint::black_box(depth_exr(g.width, g.height, &g.depth));
                stages[5].1.push(t.elapsed().as_secs_f64());
                let mask: Vec<u8> = g
                    .triangle
                    .iter()
                    .map(|&t| if t == u32::MAX { 0 } else { 255 })
                    .collect();
                let t = Instant::now();
                std::hint::black_box(mask_png(g.width, g.height, &mask));
                stages[6].1.push(t.elapsed().as_secs_f64());
            }
        }
        println!(
            "  per-stage medians, 1 thread (median coverage {:.1} % of pixels):",
            100.0 * median(coverage)
        );
        for (name, times) in stages {
            println!("    {name:<20} {:>8.2} ms", 1e3 * median(times));
        }
    });
}
