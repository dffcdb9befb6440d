//! Ground-truth benchmark: what each ground-truth output adds to a 960×960 view on one thread
//! (layer computed and encoded, the rest trace included where the output needs it; depth and
//! RGB for scale), the rest BVH built once per sample, and the per-sample meshes and points. Medians over the views of
//! the first samples of the quickstart beams (about 4 % of the frame) and the A2 water silo
//! (about 17 %). Asserts nothing.
//!
//!     cargo bench --bench ground_truth

use shmgen::output::{SAMPLE_WRITERS, WRITERS, Writer};
use shmgen::pipeline::{SampleGeometry, SampleRenderer, prepare, view_camera};
use shmgen::recipe::Recipe;
use std::path::Path;
use std::time::Instant;

#[path = "support/mod.rs"]
mod support;
use support::median;

/// The outputs this benchmark prices, per view; depth and RGB for scale (the machine is shared
/// and noisy, so ratios travel better than milliseconds).
const PER_VIEW: [&str; 8] = [
    "depth",
    "rgb",
    "normals",
    "displacement",
    "flow",
    "rest_rgb",
    "rest_depth",
    "ray_distance",
];
const SAMPLES: u64 = 2;
const VIEWS: u32 = 4;
const RUNS: usize = 3;

fn ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

fn writer(name: &str) -> &'static Writer {
    WRITERS.iter().find(|w| w.output == name).expect("a writer")
}

/// Prints the medians of one recipe's views.
fn bench(script: &str, sets: &[(String, String)]) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(script);
    let recipe = Recipe::load(&path, sets).expect("the recipe loads");
    let (mut per_view, mut trace, mut rest_bvh) =
        (vec![Vec::new(); PER_VIEW.len()], vec![], vec![]);
    let mut per_sample = vec![Vec::new(); SAMPLE_WRITERS.len()];
    let mut coverage = Vec::new();
    for index in 0..SAMPLES {
        let sample = prepare(&recipe, index).expect("the sample builds");
        let renderer = SampleRenderer::new(&recipe.dataset, &sample);
        for view in 0..VIEWS {
            let drawn = view_camera(&recipe.dataset, &sample, view).expect("a camera");
            let start = Instant::now();
            let v = renderer.view_with(view, drawn.camera, drawn);
            trace.push(ms(start));
            coverage.push(shmgen::output::ViewLayers::coverage(&v));
            if view == 0 {
                // The first rest output builds the sample's rest BVH: timed on its own.
                let start = Instant::now();
                std::hint::black_box((writer("rest_depth").write)(&v).unwrap());
                rest_bvh.push(ms(start));
            }
            for (k, name) in PER_VIEW.iter().enumerate() {
                for _ in 0..RUNS {
                    // A fresh view each time: nothing cached from another output.
                    let v = renderer.view_with(view, drawn.camera, drawn);
                    let start = Instant::now();
                    std::hint::black_box((writer(name).write)(&v).unwrap());
                    per_view[k].push(ms(start));
                }
            }
        }
        let geometry = SampleGeometry::new(&recipe.dataset, &sample);
        for (k, w) in SAMPLE_WRITERS.iter().enumerate() {
            let start = Instant::now();
            std::hint::black_box((w.write)(&geometry).unwrap());
            per_sample[k].push(ms(start));
        }
        println!(
            "  sample {index}: {} vertices, {} triangles",
            sample.mesh.positions.len(),
            sample.mesh.triangles.len()
        );
    }
    println!(
        "  coverage {:.1} %; loaded trace {:.1} ms per view; rest BVH {:.1} ms per sample (min of first use, includes one rest trace)",
        100.0 * median(coverage),
        median(trace),
        rest_bvh.iter().copied().fold(f64::INFINITY, f64::min)
    );
    for (name, times) in PER_VIEW.iter().zip(per_view) {
        println!("  {name:<14} {:8.1} ms per view", median(times));
    }
    for (w, times) in SAMPLE_WRITERS.iter().zip(per_sample) {
        println!("  {:<14} {:8.1} ms per sample", w.output, median(times));
    }
}

fn main() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    println!(
        "ground-truth benchmark: 960×960, one thread, medians ({SAMPLES} samples × {VIEWS} views × {RUNS} runs)"
    );
    pool.install(|| {
        println!("quickstart beams:");
        bench("scripts/quickstart.rhai", &[]);
        println!("A2 water silo, damaged:");
        bench("scripts/a2_silo.rhai", &[("damage".into(), "1.0".into())]);
    });
}
