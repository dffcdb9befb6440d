//! Augmentation benchmark: the cost of each operation on one 960×960 view of a textured beam
//! (scripts/augmentations.rhai), one thread, medians; and what an exact geometric copy costs
//! (the view traced and shaded again) against the image-space warp. Asserts nothing.
//!
//!     cargo bench --bench augment

use shmgen::augment::*;
use shmgen::output::ViewLayers;
use shmgen::pipeline::{SampleRenderer, prepare, view_camera};
use shmgen::recipe::Recipe;
use shmgen::seeds::{Scope, Stream};
use std::path::Path;
use std::time::Instant;

const SIDE: usize = 960;
const RUNS: usize = 7;

/// An operation timed on a copy of the image.
type Op<'a> = Box<dyn FnMut(&mut Vec<u8>) + 'a>;

/// Median wall time in milliseconds of `op` applied to a fresh copy of `image`.
fn median_ms(image: &[u8], mut op: impl FnMut(&mut Vec<u8>)) -> f64 {
    let mut times: Vec<f64> = (0..RUNS)
        .map(|_| {
            let mut img = image.to_vec();
            let start = Instant::now();
            op(&mut img);
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[RUNS / 2]
}

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/augmentations.rhai");
    let sets = [("size".to_string(), SIDE.to_string())];
    let recipe = Recipe::load(&path, &sets).expect("the augmentations recipe loads");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "augmentation benchmark: {SIDE}×{SIDE}, one thread, median of {RUNS} (machine: {cores} cores)"
    );
    pool.install(|| {
        let sample = prepare(&recipe, 0).expect("sample 0");
        let renderer = SampleRenderer::new(&recipe.dataset, &sample);
        let drawn = view_camera(&recipe.dataset, &sample, 0).expect("a camera");
        let render_ms = median_ms(&[], |_| {
            let view = renderer.view_with(0, drawn.camera, drawn);
            std::hint::black_box(view.rgb());
        });
        println!(
            "  {:<26} {render_ms:8.2} ms  (trace + shade: the cost of an exact geometric copy)",
            "render the view again"
        );
        let view = renderer.view_with(0, drawn.camera, drawn);
        report(view.rgb());
    });
}

fn report(image: &[u8]) {
    let (w, h) = (SIDE, SIDE);
    let jitter = ColourJitter {
        brightness: 1.1,
        contrast: 0.9,
        saturation: 1.2,
        hue: 0.05,
        ..ColourJitter::IDENTITY
    };
    let frame = Frame::same(w, h);
    let sim = Similarity::about_centre(w, h, 1.1, 0.7, [5.0, -3.0]);
    let depth = vec![2.5f32; w * h];
    let erasing = ErasingSpec {
        count: Range::Fixed(3.0),
        ..ErasingSpec::paper()
    }
    .draw(&mut Stream::new(0, Scope::Sample(0), "bench"), w, h)
    .unwrap_or(Erasing {
        rects: Vec::new(),
        fill: Filled::Black,
    });
    let noise = |model| Noise { model, seed: 1 };
    let rows: Vec<(&str, Op)> = vec![
        (
            "colour jitter (all four)",
            Box::new(|i| colour_jitter(i, w, h, &jitter, None)),
        ),
        (
            "exposure",
            Box::new(|i| exposure(i, w, h, &Exposure { stops: 0.5 })),
        ),
        ("gamma", Box::new(|i| gamma(i, w, h, &Gamma { gamma: 1.2 }))),
        (
            "vignette",
            Box::new(|i| vignette(i, w, h, &Vignette { strength: 0.3 })),
        ),
        (
            "noise gaussian",
            Box::new(|i| add_noise(i, w, h, &noise(NoiseModel::Gaussian { sigma: 5.0 }))),
        ),
        (
            "noise poisson-gaussian",
            Box::new(|i| {
                let model = NoiseModel::PoissonGaussian { a: 0.01, b: 1e-4 };
                add_noise(i, w, h, &noise(model))
            }),
        ),
        (
            "blur gaussian σ=2",
            Box::new(|i| blur(i, w, h, &Blur::Gaussian { sigma: 2.0 })),
        ),
        (
            "blur motion 15 px",
            Box::new(|i| {
                blur(
                    i,
                    w,
                    h,
                    &Blur::Motion {
                        length: 15.0,
                        angle: 0.5,
                    },
                )
            }),
        ),
        (
            "blur defocus r=5",
            Box::new(|i| blur(i, w, h, &Blur::Defocus { radius: 5.0 })),
        ),
        (
            "jpeg q=75",
            Box::new(|i| jpeg(i, w, h, &Jpeg { quality: 75 }).unwrap()),
        ),
        (
            "erase 3 rects",
            Box::new(|i| drop(erase(i, w, h, &erasing, None))),
        ),
        (
            "warp rgb (bilinear)",
            Box::new(|i| *i = warp_rgb(i, frame, &sim)),
        ),
        (
            "warp depth (nearest)",
            Box::new(|_| drop(warp_labels(&depth, frame, &sim))),
        ),
        (
            "warp validity mask",
            Box::new(|_| drop(warp_validity(frame, &sim))),
        ),
    ];
    println!("augment cost, {SIDE}×{SIDE}, one thread, median of {RUNS}:");
    for (name, op) in rows {
        println!("  {name:<26} {:8.2} ms", median_ms(image, op));
    }
}
