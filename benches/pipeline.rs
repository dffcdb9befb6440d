//! Pipeline benchmark: image/depth pairs per second of whole runs (every default output of the
//! recipe written to disk: RGB, depth, masks, JSON, manifest), on one thread and on every
//! core, for each row of the table in docs/benchmarks.md, issue 31's targets beside what was
//! measured, then a per-stage breakdown of single views.
//! Prints medians; asserts nothing (speed is measured, never tested).
//!
//!     cargo bench --bench pipeline                        (about a quarter of an hour on 2 cores)
//!     SHMGEN_BENCH_RUNS=1 SHMGEN_BENCH_STREAM=10000 cargo bench --bench pipeline   (quicker)
//!
//! Rows: the A1 smoke run with the paper's prompts, the quickstart, the A2 smoke run, the A1
//! and A2 smoke runs untextured (each prompt's plain colour: what the materials cost), an
//! imported mesh of a million triangles (written by the benchmark; 2 samples × 10 views, and
//! 10 × 2, where ten samples share its prepared triangles), a streaming run of tiny
//! views at growing sample counts (throughput and peak resident memory, each count in its own
//! process), and the time per pair at 3840×3840 against 960×960. Then the cost per view of
//! each daylight and camera effect, on and off (`SHMGEN_BENCH_ONLY=daylight`: only that;
//! `SHMGEN_BENCH_ONLY=breakdown`: only the per-stage breakdown, the lighting cache's filling
//! per sample included; `SHMGEN_BENCH_ONLY=targets`: only issue 31's target table (A1, A2 and
//! outdoor.rhai at 960², and `watch --once` of outdoor.rhai); `SHMGEN_BENCH_ONLY="light cache"`:
//! only the lighting cache's speed against error on outdoor.rhai, at `SHMGEN_BENCH_SIZE`²
//! (960 unless set); any other text: only the
//! table's rows whose name holds it, e.g. `SHMGEN_BENCH_ONLY=quickstart`).

use shmgen::build::BuiltSample;
use shmgen::cameras::Camera;
use shmgen::materials::environment::EnvironmentMap;
use shmgen::materials::{Backdrop, EnvironmentLight};
use shmgen::output::{depth_exr, mask_png, rgb_png};
use shmgen::pipeline::{prepare, view_camera};
use shmgen::recipe::Recipe;
use shmgen::render::{
    CacheSettings, GBuffer, LightCache, NO_HIT, SampleSurfaces, TraceMesh, shade,
};
use shmgen::scene::Shading;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

#[path = "support/mod.rs"]
mod support;
use support::{median, run_in_temp, setting};

/// Environment variable under which the benchmark runs one streaming count in a child.
const CHILD: &str = "SHMGEN_BENCH_STREAM_CHILD";

fn scripts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts")
}

fn load(path: &Path, sets: &[(&str, &str)]) -> Recipe {
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    Recipe::load(path, &sets).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// One whole run into a fresh folder: (pairs per second, seconds).
fn run_once(recipe: &Recipe, threads: usize) -> (f64, f64) {
    let summary = run_in_temp(recipe, threads);
    (summary.pairs as f64 / summary.seconds, summary.seconds)
}

/// Median pairs per second over `runs` whole runs.
fn rate(recipe: &Recipe, threads: usize, runs: u64) -> f64 {
    median((0..runs).map(|_| run_once(recipe, threads).0).collect())
}

/// A closed, finely tessellated torus with a rippled surface: `around` × `across` quads,
/// 2 · around · across triangles, as a binary little-endian PLY.
fn write_torus(path: &Path, around: u32, across: u32) {
    let mut vertices = Vec::with_capacity((around * across) as usize * 12);
    for i in 0..around {
        for j in 0..across {
            let (a, b) = (
                std::f64::consts::TAU * f64::from(i) / f64::from(around),
                std::f64::consts::TAU * f64::from(j) / f64::from(across),
            );
            let r = 0.6 + 0.02 * (12.0 * a).sin() * (7.0 * b).cos();
            let p = [
                (2.0 + r * b.cos()) * a.cos(),
                (2.0 + r * b.cos()) * a.sin(),
                1.2 * r * b.sin(),
            ];
            for c in p {
                vertices.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
    }
    let index = |i: u32, j: u32| ((i % around) * across + j % across) as i32;
    let mut faces = Vec::with_capacity((around * across) as usize * 26);
    for i in 0..around {
        for j in 0..across {
            let quad = [
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            ];
            for tri in [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]] {
                faces.push(3u8);
                for v in tri {
                    faces.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
    }
    let mut file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    write!(
        file,
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        around * across,
        2 * around * across
    )
    .unwrap();
    file.write_all(&vertices).unwrap();
    file.write_all(&faces).unwrap();
}

/// A recipe rendering the imported mesh `million.ply` next to it, plain grey, the paper's
/// camera, with `sets` (samples, views) applied; the mesh is written on first use.
fn million_recipe(dir: &Path, sets: &[(&str, &str)]) -> Recipe {
    if !dir.join("million.ply").exists() {
        write_torus(&dir.join("million.ply"), 1000, 500);
    }
    let path = dir.join("million.rhai");
    std::fs::write(
        &path,
        r#"dataset(#{ name: "million", seed: 3, samples: param("samples", 2), views: param("views", 10),
            outputs: ["rgb", "depth", "mask"],
            camera: #{ width: 960, height: 960, fov_y: PI() / 3.0, pitch: [deg(-20), deg(70)], distance: "frame" },
            scene: |rng| assembly("torus", [shape::mesh("million.ply")]).colour([0.6, 0.6, 0.6]) })"#,
    )
    .unwrap();
    load(&path, sets)
}

/// A run of `samples` samples of one 16×16 view each: "pairs/s peak_kB" on stdout.
fn stream_child(samples: &str) {
    let recipe = streaming_recipe(samples);
    let (rate, _) = run_once(
        &recipe,
        std::thread::available_parallelism().map_or(1, |n| n.get()),
    );
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let peak = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .unwrap_or(0);
    println!("{rate} {peak}");
}

fn streaming_recipe(samples: &str) -> Recipe {
    let mut recipe = load(
        &scripts().join("quickstart.rhai"),
        &[("samples", samples), ("views", "1")],
    );
    (recipe.dataset.camera.width, recipe.dataset.camera.height) = (16, 16);
    recipe
}

/// Throughput and peak memory of streaming runs, each in a child process of its own.
fn streaming(max: u64) {
    println!(
        "streaming run, quickstart beams, one 16×16 view each, every core, one run per count:"
    );
    println!("  | samples | pairs/s | peak RSS |");
    let mut count = 1000;
    while count <= max {
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .env(CHILD, count.to_string())
            .output()
            .expect("child run");
        let text = String::from_utf8_lossy(&out.stdout);
        let mut fields = text
            .split_whitespace()
            .map(|f| f.parse::<f64>().unwrap_or(0.0));
        let (rate, peak) = (fields.next().unwrap_or(0.0), fields.next().unwrap_or(0.0));
        println!("  | {count} | {rate:.0} | {:.1} MB |", peak / 1024.0);
        count *= 10;
    }
}

/// Seconds per pair at 3840×3840 over seconds per pair at 960×960 (pixels: 16×).
fn resolution_ratio(threads: usize, runs: u64) {
    let mut recipe = load(
        &scripts().join("quickstart.rhai"),
        &[("samples", "2"), ("views", "4")],
    );
    let mut per_pair = Vec::new();
    for side in [960, 3840] {
        (recipe.dataset.camera.width, recipe.dataset.camera.height) = (side, side);
        per_pair.push(1.0 / rate(&recipe, threads, runs));
    }
    println!(
        "3840×3840 against 960×960 (quickstart, {threads} threads): {:.1} ms vs {:.1} ms per pair, ratio {:.1} for 16× the pixels",
        1e3 * per_pair[1],
        1e3 * per_pair[0],
        per_pair[1] / per_pair[0]
    );
}

/// Times of each stage of a view, milliseconds, collected over views.
#[derive(Default)]
struct Stages {
    names: Vec<&'static str>,
    times: Vec<Vec<f64>>,
}

impl Stages {
    /// Runs `f`, adding its time to stage `name`.
    fn time<T>(&mut self, name: &'static str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let value = f();
        let ms = 1e3 * start.elapsed().as_secs_f64();
        match self.names.iter().position(|n| *n == name) {
            Some(i) => self.times[i].push(ms),
            None => {
                self.names.push(name);
                self.times.push(vec![ms]);
            }
        }
        value
    }
}

/// The surfaces of a built sample, as the renderer reads them.
fn surfaces_of(sample: &BuiltSample) -> SampleSurfaces<'_> {
    SampleSurfaces {
        mesh: &sample.mesh,
        rest: &sample.rest,
        piece: &sample.piece,
        pieces: &sample.pieces,
        shaders: &sample.shaders,
        cache: None,
    }
}

/// The anti-aliased RGB of a view `(camera, g)` of `sample` under its light, on a black
/// backdrop, with the lighting cache `cache` (None: per pixel).
fn shade_on_black(
    sample: &BuiltSample,
    mesh: &TraceMesh,
    (camera, g): (&Camera, &GBuffer),
    surfaces: &SampleSurfaces,
    cache: Option<&LightCache>,
) -> Vec<u8> {
    let black = Backdrop::Colour([0, 0, 0]);
    let lit = (&sample.lighting, cache);
    shade(g, mesh, camera, lit, surfaces, &black, true).rgb
}

/// The stages of one view of a built sample, timed.
fn view_stages(
    sample: &BuiltSample,
    (mesh, cache): (&TraceMesh, Option<&LightCache>),
    camera: &Camera,
    dir: &Path,
    stages: &mut Stages,
) -> GBuffer {
    let g = stages.time("visibility as run", || mesh.trace(camera));
    // Like with like: the same centre rays walked through the BVH (built per sample, below),
    // whichever path the run took; the hits are the same.
    stages.time("centre rays traced", || mesh.trace_rays(camera));
    let surfaces = surfaces_of(sample);
    let rgb = stages.time("shade (anti-aliased, as run)", || {
        shade_on_black(sample, mesh, (camera, &g), &surfaces, cache)
    });
    let png = stages.time("RGB PNG", || rgb_png(g.width, g.height, &rgb));
    let exr = stages.time("depth EXR", || depth_exr(g.width, g.height, &g.depth));
    let mask = stages.time("mask PNG", || {
        let mask: Vec<u8> = g
            .triangle
            .iter()
            .map(|&t| if t == NO_HIT { 0 } else { 255 })
            .collect();
        mask_png(g.width, g.height, &mask)
    });
    stages.time("write 3 files", || {
        for (name, bytes) in [("rgb.png", &png), ("depth.exr", &exr), ("mask.png", &mask)] {
            std::fs::write(dir.join(name), bytes).unwrap();
        }
    });
    g
}

/// Issue 31's targets: the job, the start of the name of the row that measures it, and the
/// pairs per second to reach on 2 cores.
const TARGETS: [(&str, &str, f64); 3] = [
    ("A1 (paper's prompts)", "a1_beams.rhai smoke (", 90.0),
    ("A2 (paper's prompts)", "a2_silo.rhai smoke (", 35.0),
    ("outdoor.rhai, cached", "outdoor.rhai (", 10.0),
];

/// Issue 31's targets (2 cores, 960², every default output), beside what the rows above
/// measured on every core and, when timed, `watch --once` of outdoor.rhai.
fn target_table(rates: &[(&str, f64)], watch: Option<(f64, f64)>) {
    println!("| target | measured | target |");
    for (job, row, target) in TARGETS {
        if let Some((_, all)) = rates.iter().find(|(name, _)| name.starts_with(row)) {
            println!("| {job} | {all:.1} pairs/s | ≥ {target} pairs/s |");
        }
    }
    if let Some((wall, cpu)) = watch {
        println!(
            "| watch --once outdoor.rhai (4 samples × 2 views) | {wall:.2} s ({cpu:.2} CPU-s) | ≤ 0.1 s |"
        );
    }
}

/// Median wall seconds of `shmgen watch --once scripts/outdoor.rhai` (the sheet written to a
/// temporary folder), and the CPU seconds (user + system) of its median run.
fn watch_once(runs: u64) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let times: Vec<(f64, f64)> = (0..runs.max(1))
        .map(|_| {
            let cpu_before = children_cpu_seconds();
            let started = Instant::now();
            let status = std::process::Command::new(env!("CARGO_BIN_EXE_shmgen"))
                .arg("watch")
                .arg(scripts().join("outdoor.rhai"))
                .args(["--once", "--out"])
                .arg(dir.path().join("sheet.png"))
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .status()
                .unwrap();
            assert!(status.success(), "watch --once outdoor.rhai failed");
            let wall = started.elapsed().as_secs_f64();
            (wall, children_cpu_seconds() - cpu_before)
        })
        .collect();
    let wall = median(times.iter().map(|t| t.0).collect());
    let cpu = times.iter().find(|t| t.0 == wall).map_or(f64::NAN, |t| t.1);
    (wall, cpu)
}

/// User and system CPU seconds of this process's waited-for children so far.
fn children_cpu_seconds() -> f64 {
    // SAFETY: getrusage writes the struct it is given and nothing else.
    let usage = unsafe {
        let mut usage = std::mem::zeroed::<libc::rusage>();
        libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage);
        usage
    };
    let seconds = |t: libc::timeval| t.tv_sec as f64 + 1e-6 * t.tv_usec as f64;
    seconds(usage.ru_utime) + seconds(usage.ru_stime)
}

/// The per-stage breakdown of every row.
fn stage_breakdowns(rows: &[(&str, Recipe)]) {
    println!("per-stage medians per view, 1 thread, ms (960×960; rows' first samples):");
    for (name, recipe) in rows {
        breakdown(name, recipe, 3);
    }
}

/// Per-stage medians over every view of the recipe's first `samples` samples, on one thread.
fn breakdown(name: &str, recipe: &Recipe, samples: u64) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut stages = Stages::default();
    let mut coverage = Vec::new();
    let mut paths = std::collections::BTreeMap::new();
    let (mut cache_fills, mut corners) = (Vec::new(), Vec::new());
    pool.install(|| {
        for s in 0..recipe.dataset.samples.min(samples) {
            let sample = stages.time("prepare (per sample)", || prepare(recipe, s).unwrap());
            let mesh = stages.time("scene mesh (per sample)", || TraceMesh::build(&sample.mesh));
            stages.time("BVH (per sample)", || mesh.build_bvh());
            let cache = (recipe.dataset.shading == Shading::Cached)
                .then(|| LightCache::new(&sample.lighting, CacheSettings::default()));
            let mut views = Vec::new();
            let started = Instant::now();
            for view in 0..recipe.dataset.views {
                let camera = view_camera(&recipe.dataset, &sample, view).unwrap().camera;
                let traced = (&mesh, cache.as_ref());
                let g = view_stages(&sample, traced, &camera, dir.path(), &mut stages);
                *paths.entry(g.visibility).or_insert(0) += 1;
                let hits = g.triangle.iter().filter(|&&t| t != NO_HIT).count();
                coverage.push(hits as f64 / g.triangle.len() as f64);
                views.push(camera);
            }
            if let Some(cache) = cache.as_ref().filter(|c| c.corners() > 0) {
                let filling = started.elapsed().as_secs_f64();
                cache_fills.push(fill_time(&sample, &mesh, cache, &views, filling));
                corners.push(cache.corners() as f64);
            }
        }
    });
    let cells: Vec<String> = stages
        .names
        .iter()
        .zip(stages.times)
        .map(|(n, t)| format!("{n} {:.2}", median(t)))
        .collect();
    println!(
        "  {name} (coverage {:.1} %; views as run: {paths:?}): {} ms",
        100.0 * median(coverage),
        cells.join(", ")
    );
    if !cache_fills.is_empty() {
        println!(
            "    lighting cache: filling it {:.1} ms per sample ({:.0} corners), within the \
             views' shading above",
            median(cache_fills),
            median(corners)
        );
    }
}

/// Milliseconds a sample's views spent filling the lighting cache: the time `first_pass`
/// (seconds) they took with it empty, less the time they take again with it full (lookups
/// only; every stage of a view but the shading is timed again too, so it cancels out).
fn fill_time(
    sample: &BuiltSample,
    mesh: &TraceMesh,
    cache: &LightCache,
    views: &[Camera],
    first_pass: f64,
) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let started = Instant::now();
    for camera in views {
        view_stages(
            sample,
            (mesh, Some(cache)),
            camera,
            dir.path(),
            &mut Stages::default(),
        );
    }
    1e3 * (first_pass - started.elapsed().as_secs_f64()).max(0.0)
}

/// Median milliseconds per view (one thread, 960×960, anti-aliased) of shading a1's first beam
/// outdoors under each lighting, every row one effect added to the hard-shadowed sun and sky;
/// then of each image effect on the shaded view.
fn daylight_costs(views: u32) {
    use shmgen::augment::{self, Blur, Noise, NoiseModel, Vignette, defocus_by_depth};
    use shmgen::cameras::DepthOfField;
    use shmgen::materials::{GroundBounce, Lighting, Sky, Sun, ToneCurve};
    let recipe = load(&scripts().join("a1_beams.rhai"), &[("samples", "1")]);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let sample = prepare(&recipe, 0).unwrap();
    let mesh = TraceMesh::build(&sample.mesh);
    let surfaces = surfaces_of(&sample);
    let black = Backdrop::Colour([0, 0, 0]);
    let up = 0.7f64;
    let outdoor = Lighting {
        ambient: 0.02,
        studio: None,
        sun: Some(Sun {
            direction: glam::DVec3::new(up.cos() * 0.6, up.cos() * 0.8, up.sin()),
            colour: [1.2, 1.1, 1.0],
            angular_diameter: 0.0,
            shadow_rays: 1,
        }),
        sky: Some(Sky {
            sky: [0.16, 0.2, 0.27],
            ground: [0.05, 0.04, 0.03],
            occlusion_rays: 0,
        }),
        environment: None,
        shadows: true,
        ground: None,
        film: Default::default(),
    };
    let with = |change: &dyn Fn(&mut Lighting)| {
        let mut l = outdoor.clone();
        change(&mut l);
        l
    };
    // A 512 × 256 map: a sky brighter towards the zenith over darker ground.
    let map = Arc::new(EnvironmentMap::from_texels(
        512,
        256,
        (0..256 * 512)
            .map(|i| {
                let up = 1.0 - (i / 512) as f32 / 128.0;
                if up > 0.0 {
                    [0.1 + 0.1 * up, 0.15 + 0.1 * up, 0.3]
                } else {
                    [0.05; 3]
                }
            })
            .collect(),
    ));
    let environment_backdrop = Backdrop::Environment {
        map: map.clone(),
        intensity: 1.0,
        rotation: 0.3,
    };
    let environment = |occlusion_rays: u32| {
        with(&|l| {
            l.sky = None;
            l.environment = Some(EnvironmentLight {
                map: map.clone(),
                intensity: 1.0,
                rotation: 0.3,
                occlusion_rays,
            });
        })
    };
    let lightings: Vec<(&str, Lighting, &Backdrop)> = vec![
        ("studio (A1's default)", sample.lighting.clone(), &black),
        ("sun with a hard shadow, sky", outdoor.clone(), &black),
        (
            "+ soft sun, 0.53°, 8 shadow rays",
            with(&|l| {
                let sun = l.sun.as_mut().unwrap();
                (sun.angular_diameter, sun.shadow_rays) = (0.53f64.to_radians(), 8);
            }),
            &black,
        ),
        (
            "+ sky occlusion, 16 rays",
            with(&|l| l.sky.as_mut().unwrap().occlusion_rays = 16),
            &black,
        ),
        (
            "+ ground bounce",
            with(&|l| {
                l.ground = Some(GroundBounce {
                    height: -3.0,
                    albedo: [0.2; 3],
                })
            }),
            &black,
        ),
        (
            "+ filmic tone, +1 EV",
            with(&|l| {
                l.film.tone = ToneCurve::Filmic;
                l.film.exposure = 2.0;
            }),
            &black,
        ),
        (
            "environment map light (SH) instead of the sky",
            environment(0),
            &black,
        ),
        ("+ environment occlusion, 16 rays", environment(16), &black),
        (
            "+ environment map background",
            environment(16),
            &environment_backdrop,
        ),
    ];
    let mut shade_ms = vec![Vec::new(); lightings.len()];
    let effects = [
        "depth of field, f/8 (focus on the nearest surface)",
        "depth of field, f/2.8 (the same)",
        "sensor vignette",
        "sensor noise",
        "sensor blur, σ 1 px",
    ];
    let mut effect_ms = vec![Vec::new(); effects.len()];
    pool.install(|| {
        for view in 0..views {
            let camera = view_camera(&recipe.dataset, &sample, view).unwrap().camera;
            let g = mesh.trace(&camera);
            let mut rgb = Vec::new();
            for (k, (_, lighting, backdrop)) in lightings.iter().enumerate() {
                let start = Instant::now();
                rgb = shade(
                    &g,
                    &mesh,
                    &camera,
                    (lighting, None),
                    &surfaces,
                    backdrop,
                    true,
                )
                .rgb;
                shade_ms[k].push(1e3 * start.elapsed().as_secs_f64());
            }
            let (w, h) = (g.width as usize, g.height as usize);
            // Focused on the nearest surface: the far side of the beam and the backdrop blur.
            let nearest = (g.depth.iter().copied().filter(|&d| d > 0.0)).fold(f32::MAX, f32::min);
            let lens = DepthOfField {
                f_number: 2.8,
                focus_distance: f64::from(nearest),
                sensor_width: 0.036,
            };
            let mut timed = |k: usize, effect: &mut dyn FnMut(&mut [u8])| {
                let mut image = rgb.clone();
                let start = Instant::now();
                effect(&mut image);
                effect_ms[k].push(1e3 * start.elapsed().as_secs_f64());
            };
            let mut defocus = |k: usize, f_number: f64| {
                let lens = DepthOfField {
                    f_number,
                    ..lens.clone()
                };
                timed(k, &mut |image| {
                    let (radius, distance) = lens.circles(&camera.intrinsics, &g.depth);
                    defocus_by_depth(image, w, h, &radius, &distance);
                });
            };
            defocus(0, 8.0);
            defocus(1, 2.8);
            timed(2, &mut |image| {
                augment::vignette(image, w, h, &Vignette { strength: 0.3 })
            });
            timed(3, &mut |image| {
                let model = NoiseModel::Gaussian { sigma: 3.0 };
                augment::add_noise(image, w, h, &Noise { model, seed: 1 })
            });
            timed(4, &mut |image| {
                augment::blur(image, w, h, &Blur::Gaussian { sigma: 1.0 })
            });
        }
    });
    println!(
        "daylight and camera effects, ms per 960×960 view (1 thread, a1's first beam, {views} views):"
    );
    println!("| shading | ms | against the row it adds to |");
    let medians: Vec<f64> = shade_ms.into_iter().map(median).collect();
    for (k, (name, _, _)) in lightings.iter().enumerate() {
        // The outdoor rows each add one effect to the hard-shadowed sun and sky.
        let base = if k >= 2 { medians[1] } else { medians[0] };
        println!("| {name} | {:.1} | {:+.1} |", medians[k], medians[k] - base);
    }
    println!("| image effect, on the shaded view | ms | |");
    for (name, times) in effects.iter().zip(effect_ms) {
        println!("| {name} | {:.1} | |", median(times));
    }
}

/// RMS and 99th percentile of the absolute difference of two 8-bit images, in levels, over
/// every channel of every pixel (sky pixels included: they never differ).
fn image_error(a: &[u8], b: &[u8]) -> (f64, f64) {
    let mut d: Vec<u8> = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).collect();
    let rms = (d.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>() / d.len() as f64).sqrt();
    d.sort_unstable();
    (rms, f64::from(d[d.len() * 99 / 100]))
}

/// The lighting cache's speed against its error on `outdoor.rhai` at `size`² (its beam, silo
/// and girder samples, both views, one thread, anti-aliased, a black backdrop): for each
/// setting, the worst view's RMS and 99th percentile difference from the per-pixel reference
/// in 8-bit levels, the median shading time per pair (the cache filled by the pair's views
/// included) and the corners traced per sample.
fn light_cache_table(size: u32) {
    use shmgen::render::{CacheSettings, LightCache};
    let recipe = load(
        &scripts().join("outdoor.rhai"),
        &[("size", &size.to_string())],
    );
    let base = CacheSettings::default();
    let settings = [
        (
            "tolerance 0.05, finest 1 px",
            CacheSettings {
                tolerance: 0.05,
                finest_pixels: 1.0,
                sky_finest_pixels: 1.0,
                ..base
            },
        ),
        ("default: tolerance 0.1, finest 2 px", base),
        (
            "tolerance 0.1, finest 2 px, sky's 8 px",
            CacheSettings {
                sky_finest_pixels: 8.0,
                ..base
            },
        ),
        (
            "tolerance 0.2, finest 4 px",
            CacheSettings {
                tolerance: 0.2,
                finest_pixels: 4.0,
                sky_finest_pixels: 4.0,
                ..base
            },
        ),
        (
            "tolerance 0.2, finest 4 px, coarsest 0.5 m, sky rays ×1",
            CacheSettings {
                tolerance: 0.2,
                finest_pixels: 4.0,
                sky_finest_pixels: 4.0,
                coarsest: 0.5,
                sky_ray_factor: 1,
                ..base
            },
        ),
    ];
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut reference_ms = Vec::new();
    let mut rows: Vec<(f64, f64, Vec<f64>, Vec<f64>)> =
        vec![(0.0, 0.0, Vec::new(), Vec::new()); settings.len()];
    pool.install(|| {
        for s in [0, 7, 14] {
            let sample = prepare(&recipe, s).unwrap();
            let mesh = TraceMesh::build_with_core(&sample.mesh, sample.structure_triangles());
            mesh.build_bvh();
            let surfaces = surfaces_of(&sample);
            let views: Vec<(Camera, GBuffer)> = (0..recipe.dataset.views)
                .map(|view| {
                    let camera = view_camera(&recipe.dataset, &sample, view).unwrap().camera;
                    let g = mesh.trace(&camera);
                    (camera, g)
                })
                .collect();
            let start = Instant::now();
            let reference: Vec<Vec<u8>> = views
                .iter()
                .map(|(camera, g)| shade_on_black(&sample, &mesh, (camera, g), &surfaces, None))
                .collect();
            reference_ms.push(1e3 * start.elapsed().as_secs_f64());
            for (row, (_, setting)) in rows.iter_mut().zip(&settings) {
                let start = Instant::now();
                let cache = LightCache::new(&sample.lighting, *setting);
                let images: Vec<Vec<u8>> = views
                    .iter()
                    .map(|(camera, g)| {
                        shade_on_black(&sample, &mesh, (camera, g), &surfaces, Some(&cache))
                    })
                    .collect();
                row.2.push(1e3 * start.elapsed().as_secs_f64());
                row.3.push(cache.corners() as f64);
                for (image, truth) in images.iter().zip(&reference) {
                    let (rms, p99) = image_error(image, truth);
                    (row.0, row.1) = (row.0.max(rms), row.1.max(p99));
                }
            }
        }
    });
    println!(
        "lighting cache on outdoor.rhai at {size}² (beam, silo, girder; 2 views each; 1 thread):"
    );
    println!("| setting | worst RMS | worst p99 | shading ms/pair | corners/sample |");
    let per_pair = |ms: Vec<f64>| median(ms) / f64::from(recipe.dataset.views);
    println!(
        "| per_pixel (the reference) | 0 | 0 | {:.0} | — |",
        per_pair(reference_ms)
    );
    for ((name, _), (rms, p99, ms, corners)) in settings.iter().zip(rows) {
        println!(
            "| {name} | {rms:.2} | {p99:.0} | {:.0} | {:.0} |",
            per_pair(ms),
            median(corners)
        );
    }
}

fn main() {
    if let Ok(samples) = std::env::var(CHILD) {
        return stream_child(&samples);
    }
    let only = std::env::var("SHMGEN_BENCH_ONLY").unwrap_or_default();
    if only == "daylight" {
        return daylight_costs(setting("SHMGEN_BENCH_VIEWS", 10) as u32);
    }
    if only == "light cache" {
        return light_cache_table(setting("SHMGEN_BENCH_SIZE", 960) as u32);
    }
    let runs = setting("SHMGEN_BENCH_RUNS", 3);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find_map(|l| l.strip_prefix("model name\t: ").map(str::to_string))
        })
        .unwrap_or_default();
    println!("shmgen pipeline benchmark: {cores} cores ({cpu}), medians of {runs} runs");
    let million_dir = tempfile::tempdir().unwrap();
    let rows = [
        (
            "a1_beams.rhai smoke (12 beams × 20 views, paper prompts)",
            load(&scripts().join("a1_beams.rhai"), &[("samples", "12")]),
        ),
        (
            "quickstart.rhai (10 beams × 20 views)",
            load(
                &scripts().join("quickstart.rhai"),
                &[("samples", "10"), ("views", "20")],
            ),
        ),
        (
            "a2_silo.rhai smoke (3 silos × 20 views)",
            load(&scripts().join("a2_silo.rhai"), &[("samples", "3")]),
        ),
        // What the geometry, the light and the writers cost alone: the same runs with every
        // structure in its prompt's plain colour (`textures=false`).
        (
            "a1_beams.rhai smoke, textures=false",
            load(
                &scripts().join("a1_beams.rhai"),
                &[("samples", "12"), ("textures", "false")],
            ),
        ),
        (
            "a2_silo.rhai smoke, textures=false",
            load(
                &scripts().join("a2_silo.rhai"),
                &[("samples", "3"), ("textures", "false")],
            ),
        ),
        (
            "outdoor.rhai (15 samples × 2 views: beams, silos, a girder on a ground), cached",
            load(&scripts().join("outdoor.rhai"), &[]),
        ),
        (
            "outdoor.rhai, shading=per_pixel (the reference)",
            load(&scripts().join("outdoor.rhai"), &[("shading", "per_pixel")]),
        ),
        (
            "imported mesh, 1,000,000 triangles (2 × 10 views)",
            million_recipe(million_dir.path(), &[]),
        ),
        (
            "the same mesh, 10 samples × 2 views (its triangles shared)",
            million_recipe(million_dir.path(), &[("samples", "10"), ("views", "2")]),
        ),
    ];
    // The shared-mesh row's stages are those of the row above it.
    let staged = &rows[..rows.len() - 1];
    if only == "breakdown" {
        return stage_breakdowns(staged);
    }
    println!("| row | 1 thread | {cores} threads |");
    let mut rates = Vec::new();
    let chosen = |name: &str| match only.as_str() {
        "targets" => TARGETS.iter().any(|(_, row, _)| name.starts_with(row)),
        only => name.contains(only),
    };
    for (name, recipe) in rows.iter().filter(|(name, _)| chosen(name)) {
        let one = rate(recipe, 1, runs);
        let all = rate(recipe, cores, runs);
        println!("| {name} | {one:.1} pairs/s | {all:.1} pairs/s |");
        rates.push((*name, all));
    }
    let timed_watch = only.is_empty() || only == "targets";
    target_table(&rates, timed_watch.then(|| watch_once(runs)));
    if !only.is_empty() {
        return;
    }
    resolution_ratio(cores, runs);
    streaming(setting("SHMGEN_BENCH_STREAM", 100_000));
    stage_breakdowns(staged);
    daylight_costs(setting("SHMGEN_BENCH_VIEWS", 10) as u32);
    light_cache_table(setting("SHMGEN_BENCH_SIZE", 960) as u32);
}
