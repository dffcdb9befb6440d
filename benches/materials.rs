//! Materials benchmark: what texturing costs. The paper's seven prompts on the gallery beam and
//! silo (scripts/prompt_gallery.rhai) at 960×960 with sun, sky, shadows and a sky backdrop,
//! against the same scenes in a plain colour. Prints medians of trace + RGB per view (one
//! thread) and the share of pixels the structure covers; asserts nothing.
//!
//!     cargo bench --bench materials

use shmgen::build::BuiltSample;
use shmgen::materials::{Material, Shader};
use shmgen::output::ViewLayers;
use shmgen::pipeline::{SampleRenderer, prepare};
use shmgen::recipe::Recipe;
use shmgen::scene::Structure;
use shmgen::seeds::{Scope, Stream};
use std::path::Path;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/prompt_gallery.rhai");
    let views = 6u32;
    let sets = [("views".to_string(), views.to_string())];
    let recipe = Recipe::load(&path, &sets).expect("gallery loads");
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "shmgen materials benchmark: 960×960, {views} views per scene, 1 thread (machine: {cores} cores)"
    );
    println!(
        "  {:<48} {:>12} {:>12} {:>9}",
        "prompt (structure)", "textured ms", "plain ms", "coverage"
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        for index in 0..recipe.dataset.samples {
            let textured = prepare(&recipe, index).expect("sample");
            // The same scene with every structure in its material's plain mean colour.
            let mut plain = prepare(&recipe, index).expect("sample");
            let mut stream = Stream::new(0, Scope::Sample(index), "material");
            plain.shaders = plain
                .scene
                .structures
                .iter()
                .map(|s| Shader::new(&Material::plain(s.material().colour), &mut stream))
                .collect();
            let (t_ms, coverage) = time_views(&recipe, &textured, views);
            let (p_ms, _) = time_views(&recipe, &plain, views);
            let structure = match &textured.scene.structures[0] {
                Structure::Beam(_) => "beam",
                Structure::Assembly(_) => "silo",
                Structure::Frame(_) => "frame",
            };
            let prompt = textured.scene.structures[0]
                .material()
                .prompt
                .clone()
                .unwrap_or_default()
                .replace("A photo of ", "");
            println!(
                "  {:<48} {t_ms:>12.1} {p_ms:>12.1} {:>8.1}%",
                format!("{prompt} ({structure})"),
                100.0 * coverage
            );
        }
    });
}

/// Median milliseconds of tracing + shading one view, and the median share of pixels hit.
fn time_views(recipe: &Recipe, sample: &BuiltSample, views: u32) -> (f64, f64) {
    let renderer = SampleRenderer::new(&recipe.dataset, sample);
    let mut times = Vec::new();
    let mut coverage = Vec::new();
    for view in 0..views {
        let t = Instant::now();
        let rendered = renderer.view(view).expect("a finite camera");
        std::hint::black_box(rendered.rgb());
        times.push(t.elapsed().as_secs_f64() * 1e3);
        coverage.push(rendered.coverage());
    }
    (median(times), median(coverage))
}
