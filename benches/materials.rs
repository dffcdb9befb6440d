//! Materials benchmark: what texturing costs, and the material cache's speed against its error.
//!
//! First the table of docs/materials.md: A1 and A2 with the paper's prompts (the smoke runs'
//! samples, 960×960), the material fields evaluated at every pixel (the reference, and what
//! runs do) and cached per sample in surface space at several texel bounds
//! (`SampleRenderer::with_texel_fraction`); for each, the median trace + RGB time per view
//! (one thread), the material evaluations per sample (pixels that meet a surface, or the
//! cache's lattice points: a count independent of the machine), and the RGB error
//! against the reference over the structure's pixels (RMS and 99th percentile of the largest
//! channel difference, 8-bit levels, the worst view). Whole runs in pairs/s, every default
//! output written, are the pipeline benchmark's rows (`cargo bench --bench pipeline`).
//! Then the paper's seven prompts on the gallery beam and silo (scripts/prompt_gallery.rhai)
//! with sun, sky, shadows and a sky backdrop, against the same scenes in a plain colour: the
//! trace and RGB time per view and the share of pixels the structure covers. Asserts nothing.
//!
//!     cargo bench --bench materials
//!     SHMGEN_BENCH_ONLY=cache cargo bench --bench materials      (the table only)
//!     SHMGEN_BENCH_SAMPLES=3 SHMGEN_BENCH_VIEWS=6 ...            (fewer samples and views)

use shmgen::build::BuiltSample;
use shmgen::materials::cache::RgbError;
use shmgen::materials::{Material, Shader};
use shmgen::output::ViewLayers;
use shmgen::pipeline::{SampleRenderer, prepare};
use shmgen::recipe::Recipe;
use shmgen::render::NO_HIT;
use shmgen::scene::Structure;
use shmgen::seeds::{Scope, Stream};
use std::path::Path;
use std::time::Instant;

#[path = "support/mod.rs"]
mod support;
use support::{median, setting};

/// Texel bounds of the table (None: the per-pixel reference).
const FRACTIONS: [Option<f64>; 5] = [None, Some(0.5), Some(1.0), Some(2.0), Some(4.0)];

fn main() {
    cache_table();
    if std::env::var("SHMGEN_BENCH_ONLY").is_ok_and(|o| o == "cache") {
        return;
    }
    gallery();
}

/// The speed–error table of the material cache (docs/materials.md).
fn cache_table() {
    let scripts = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts");
    let samples = setting("SHMGEN_BENCH_SAMPLES", 6);
    let views = setting("SHMGEN_BENCH_VIEWS", 20) as u32;
    println!(
        "material cache: 960×960, {samples} samples × {views} views, trace + RGB per view on 1 thread"
    );
    println!(
        "| job | texel bound | evaluations/sample | ms/view | views/s | RMS (worst view) | p99 (worst view) |"
    );
    println!("|---|---|---|---|---|---|---|");
    let jobs = [
        ("A1", "a1_beams.rhai", samples.max(3)),
        ("A2", "a2_silo.rhai", samples.clamp(1, 3)),
    ];
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for (job, script, samples) in jobs {
        let count = samples.to_string();
        let sets = [
            ("samples".to_string(), count),
            ("views".to_string(), views.to_string()),
        ];
        let recipe = Recipe::load(&scripts.join(script), &sets).expect("recipe loads");
        let built: Vec<BuiltSample> = (0..samples)
            .map(|i| prepare(&recipe, i).expect("sample"))
            .collect();
        pool.install(|| {
            let reference: Vec<Vec<Vec<u8>>> = built
                .iter()
                .map(|sample| render_all(&recipe, sample, views, None).images)
                .collect();
            for fraction in FRACTIONS {
                let mut times = Vec::new();
                let mut points = Vec::new();
                let mut worst = RgbError::default();
                for (k, (sample, truth)) in built.iter().zip(&reference).enumerate() {
                    let r = render_all(&recipe, sample, views, fraction);
                    if let (Ok(dir), Some(f)) = (std::env::var("SHMGEN_BENCH_IMAGES"), fraction) {
                        save_comparison(
                            Path::new(&dir),
                            &format!("{job}-s{k}-f{f}"),
                            &truth[0],
                            &r.images[0],
                        );
                    }
                    times.extend(r.ms);
                    points.push(r.points as f64);
                    for ((image, want), hits) in r.images.iter().zip(truth).zip(&r.hits) {
                        worst = worst.worst(RgbError::of(image, want, hits));
                    }
                }
                let name = match fraction {
                    None => "per pixel (reference)".to_string(),
                    Some(f) => format!("{f}"),
                };
                let ms = median(times);
                println!(
                    "| {job} | {name} | {:.0} | {ms:.1} | {:.1} | {:.2} | {} |",
                    median(points),
                    1e3 / ms,
                    worst.rms,
                    worst.p99
                );
            }
        });
    }
}

/// The reference, the cached image and their difference (×8, grey at 0) side by side, as a PNG
/// `name`.png in `dir`.
fn save_comparison(dir: &Path, name: &str, reference: &[u8], cached: &[u8]) {
    let side = ((reference.len() / 3) as f64).sqrt() as u32;
    let mut out = image::RgbImage::new(3 * side, side);
    for (i, (p, q)) in reference.chunks(3).zip(cached.chunks(3)).enumerate() {
        let (x, y) = (i as u32 % side, i as u32 / side);
        out.put_pixel(x, y, image::Rgb([p[0], p[1], p[2]]));
        out.put_pixel(x + side, y, image::Rgb([q[0], q[1], q[2]]));
        let d = |k: usize| (128 + 8 * (i32::from(q[k]) - i32::from(p[k]))).clamp(0, 255) as u8;
        out.put_pixel(x + 2 * side, y, image::Rgb([d(0), d(1), d(2)]));
    }
    std::fs::create_dir_all(dir).expect("image folder");
    out.save(dir.join(format!("{name}.png")))
        .expect("image written");
}

/// What rendering a sample's views gave.
struct Rendered {
    images: Vec<Vec<u8>>,
    /// Per view, per pixel: whether the centre ray met a surface.
    hits: Vec<Vec<bool>>,
    ms: Vec<f64>,
    points: usize,
}

/// The RGB of every view of `sample` with the materials cached at `fraction` (None: per pixel).
fn render_all(
    recipe: &Recipe,
    sample: &BuiltSample,
    views: u32,
    fraction: Option<f64>,
) -> Rendered {
    let renderer = SampleRenderer::new(&recipe.dataset, sample).with_texel_fraction(fraction);
    let mut out = Rendered {
        images: Vec::new(),
        hits: Vec::new(),
        ms: Vec::new(),
        points: 0,
    };
    for view in 0..views {
        let t = Instant::now();
        let rendered = renderer.view(view).expect("a finite camera");
        let rgb = rendered.rgb().to_vec();
        out.ms.push(t.elapsed().as_secs_f64() * 1e3);
        out.images.push(rgb);
        out.hits.push(
            rendered
                .gbuffer
                .triangle
                .iter()
                .map(|&t| t != NO_HIT)
                .collect(),
        );
    }
    // Per pixel, the material is evaluated once for each centre ray that meets it (and again
    // at the few anti-aliased edge pixels); cached, once for each lattice point.
    out.points = match fraction {
        None => out.hits.iter().flatten().filter(|&&hit| hit).count(),
        Some(_) => renderer.cached_points(),
    };
    out
}

/// The paper's prompts on the gallery's structures, textured against plain.
fn gallery() {
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
