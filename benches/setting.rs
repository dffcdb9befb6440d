//! Setting benchmark: what a ground and drawn supports cost per view. The beam (on a pin and a
//! roller), the water silo and the bridge of scripts/outdoor.rhai at 960×960 with sun, sky,
//! shadows and a sky backdrop, each with the ground on and off and (the beam) with its
//! supports drawn or not. Prints medians of trace + RGB + depth per view on one thread, and
//! the BVH build per sample; asserts nothing.
//!
//!     cargo bench --bench setting

use shmgen::build::{BuiltSample, build_sample};
use shmgen::output::ViewLayers;
use shmgen::pipeline::{SampleRenderer, prepare};
use shmgen::recipe::Recipe;
use shmgen::scene::{DatasetSpec, Structure};
use std::path::Path;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/outdoor.rhai");
    let views = 6u32;
    let sets = [("views".to_string(), views.to_string())];
    let recipe = Recipe::load(&path, &sets).expect("outdoor loads");
    let mut bare = recipe.dataset.clone();
    bare.ground = None;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "shmgen setting benchmark: 960×960, {views} views per scene, 1 thread (machine: {cores} cores)"
    );
    println!(
        "  {:<34} {:>10} {:>10} {:>9}",
        "scene", "view ms", "BVH ms", "coverage"
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        for (index, name) in [(0, "beam"), (7, "silo"), (14, "bridge")] {
            let drawn = prepare(&recipe, index).expect("sample").scene;
            for supports in [true, false] {
                if !supports && name != "beam" {
                    continue;
                }
                let mut scene = drawn.clone();
                for s in &mut scene.structures {
                    if let Structure::Beam(b) = s {
                        b.supports_drawn &= supports;
                    }
                }
                for (dataset, ground) in [(&recipe.dataset, "ground"), (&bare, "no ground")] {
                    let sample = build_sample(dataset, index, scene.clone()).expect("builds");
                    let (view_ms, bvh_ms, coverage) = time_views(dataset, &sample, views);
                    let label = match (name, supports) {
                        ("beam", true) => format!("beam, supports, {ground}"),
                        ("beam", false) => format!("beam, no supports, {ground}"),
                        _ => format!("{name}, {ground}"),
                    };
                    println!(
                        "  {label:<34} {view_ms:>10.1} {bvh_ms:>10.2} {:>8.1}%",
                        100.0 * coverage
                    );
                }
            }
        }
    });
}

/// Median milliseconds of tracing, shading and taking the depth of one view, the BVH build,
/// and the median share of pixels the structures cover.
fn time_views(dataset: &DatasetSpec, sample: &BuiltSample, views: u32) -> (f64, f64, f64) {
    let t = Instant::now();
    let renderer = SampleRenderer::new(dataset, sample);
    let bvh = t.elapsed().as_secs_f64() * 1e3;
    let mut times = Vec::new();
    let mut coverage = Vec::new();
    for view in 0..views {
        let t = Instant::now();
        let rendered = renderer.view(view).expect("a finite camera");
        std::hint::black_box(rendered.rgb());
        std::hint::black_box(rendered.depth());
        times.push(t.elapsed().as_secs_f64() * 1e3);
        coverage.push(rendered.coverage());
    }
    (median(times), bvh, median(coverage))
}
