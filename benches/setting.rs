//! Setting benchmark: what a ground and drawn supports cost per view. The beam (on a pin and a
//! roller), the water silo and the bridge of scripts/outdoor.rhai at 960×960 with sun, sky,
//! shadows and a sky backdrop, each with the ground (grass, then in its flat mean colour) and
//! without, and (the beam) with its
//! supports drawn or not. Prints medians of trace + RGB + depth per view on one thread, and
//! the BVH build per sample; asserts nothing.
//!
//!     cargo bench --bench setting

use shmgen::build::{BuiltSample, build_sample};
use shmgen::materials::Material;
use shmgen::output::ViewLayers;
use shmgen::pipeline::{SampleRenderer, prepare};
use shmgen::recipe::Recipe;
use shmgen::scene::{DatasetSpec, Structure};
use std::path::Path;
use std::time::Instant;

/// Views timed per scene; the median is printed.
const VIEWS: u32 = 6;

fn main() {
    let recipe = Recipe::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/outdoor.rhai"),
        &[("views".to_string(), VIEWS.to_string())],
    )
    .expect("outdoor loads");
    let bare = DatasetSpec {
        ground: None,
        ..recipe.dataset.clone()
    };
    // The ground in one flat colour: what tracing and shading it cost without its texture.
    let mut flat = recipe.dataset.clone();
    if let Some(g) = &mut flat.ground {
        g.material = Material::plain(g.material.colour);
    }
    println!(
        "shmgen setting benchmark: 960×960, {VIEWS} views per scene, 1 thread (machine: {} cores)",
        std::thread::available_parallelism().map_or(1, |n| n.get())
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
                for (dataset, ground) in [
                    (&recipe.dataset, "ground"),
                    (&flat, "flat ground"),
                    (&bare, "no ground"),
                ] {
                    let sample = build_sample(dataset, index, scene.clone()).expect("builds");
                    let (view_ms, bvh_ms, coverage) = time_views(dataset, &sample);
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
fn time_views(dataset: &DatasetSpec, sample: &BuiltSample) -> (f64, f64, f64) {
    let t = Instant::now();
    let renderer = SampleRenderer::new(dataset, sample);
    let bvh = t.elapsed().as_secs_f64() * 1e3;
    let (mut times, mut coverage): (Vec<f64>, Vec<f64>) = (0..VIEWS)
        .map(|view| {
            let t = Instant::now();
            let rendered = renderer.view(view).expect("a finite camera");
            std::hint::black_box((rendered.rgb(), rendered.depth()));
            (t.elapsed().as_secs_f64() * 1e3, rendered.coverage())
        })
        .unzip();
    times.sort_by(f64::total_cmp);
    coverage.sort_by(f64::total_cmp);
    let middle = VIEWS as usize / 2;
    (times[middle], bvh, coverage[middle])
}
