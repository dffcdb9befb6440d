//! Hostile values in every recipe call: each numeric and string argument of each call the
//! recipe API offers takes extreme values (0, negative, ±1e±308, NaN, ±∞, huge counts, wrong
//! types), one at a time, in a small recipe that is otherwise valid. Every run must end within
//! its time limit in one of two ways:
//!
//! - success, with a complete dataset: every sample in the manifest, every file it lists
//!   present, every JSON number finite, every depth finite and non-negative; or
//! - a clear error (`error: …` on stderr, no panic, no abort, exit code 1) that leaves nothing
//!   behind: no output folder, or one holding no sample and no staging.
//!
//! `SHMGEN_FUZZ_CASES=N` runs only the first N cases (for a quick look); the full set runs in
//! CI.

mod common;

use common::{read_json, run_limited, stderr};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{LazyLock, Mutex};
use std::time::Duration;

/// The extreme values each `$` takes, as Rhai expressions.
const VALUES: &[&str] = &[
    "0",
    "0.0",
    "-1",
    "-1.0",
    "1e-308",
    "-1e-308",
    "1e-12",
    "1e-7",
    "100000",
    "1e15",
    "1e30",
    "1e308",
    "-1e308",
    "(0.0 / 0.0)",
    "(1.0 / 0.0)",
    "(-1.0 / 0.0)",
    "1000000000000",
    "-9223372036854775807",
    "\"text\"",
    "[]",
    "#{}",
    "true",
    "()",
];

/// Strings for the arguments that take names or prompts.
const WORDS: &[&str] = &[
    "\"\"",
    "\"x\"",
    "\"\u{1F600}\u{0000}\"",
    "\"rusty rusty rusty steel concrete timber blue\"",
    "0",
    "[]",
];

/// A beam and an assembly the templates build on.
const BEAM: &str = "beam(#{ length: 2.0, width: 0.2, height: 0.3 })";
const TUBE: &str = "shape::tube(1.0, 3.0, 0.05)";

/// Every call of the recipe API, with `$` where the hostile value goes (one argument at a
/// time: each template names one position). `scene` templates are the scene's return value;
/// `dataset` templates are options of `dataset(#{ ... })`.
const SCENES: &[&str] = &[
    // Beams: construction, sections, supports, loads, theory, tessellation, material.
    "beam(#{ length: $, width: 0.2, height: 0.3 })",
    "beam(#{ length: 2.0, width: $, height: 0.3 })",
    "beam(#{ length: 2.0, section: rectangle($, 0.3) })",
    "beam(#{ length: 2.0, section: i_section(0.2, 0.3, $, 0.01) })",
    "beam(#{ length: 2.0, section: hollow_box(0.2, 0.3, $) })",
    "beam(#{ length: 2.0, section: tube($, 0.01) })",
    "beam(#{ length: 2.0, width: 0.2, height: 0.3, segments: $ })",
    "BEAM.point_load($, 0.05)",
    "BEAM.point_load(1.0, $)",
    "BEAM.cantilever().point_load(2.0, $)",
    "BEAM.fixed_fixed().point_load(1.0, $)",
    "BEAM.point_force(1.0, $)",
    "BEAM.propped_cantilever().point_force($, 1000.0)",
    "BEAM.distributed_load($)",
    "BEAM.distributed_load(0.5, $, 1000.0)",
    "BEAM.end_moments($, 0.0)",
    "BEAM.cantilever().end_moments(0.0, $)",
    "BEAM.vibration([[$, 0.01]])",
    "BEAM.vibration([[1, $]])",
    "BEAM.cantilever().vibration([[3, 0.01], [$, 0.02]])",
    "BEAM.point_force(1.0, 1.0).target_deflection($)",
    "BEAM.point_force(1.0, 1.0).target_deflection_at($, 0.01)",
    "BEAM.fixed_fixed().distributed_load(1.0).target_deflection_at(1e-7, $)",
    "BEAM.point_load(1.0, 0.05).theory($)",
    "BEAM.fixed_fixed().point_load(1.0, 0.05).axial($)",
    "BEAM.fixed_fixed().distributed_load($)",
    "BEAM.axial(\"restrained\").point_load(1.0, $)",
    "BEAM.cantilever().point_load(2.0, 0.5).theory(\"elastica\").model_tolerance($)",
    "BEAM.point_load(1.0, 0.05).mapping($)",
    "BEAM.point_load(1.0, 0.05).segments($)",
    "BEAM.point_load(1.0, 0.05).chord_tolerance($)",
    "BEAM.point_load(1.0, 0.05).pixel_tolerance($)",
    "BEAM.point_force(1.0, 1000.0).elastic_modulus($)",
    "BEAM.point_force(1.0, 1000.0).poisson($)",
    "BEAM.point_force(1.0, 1000.0).yield_strength($)",
    "BEAM.at($, 0.0, 0.0)",
    "BEAM.at(0.0, 0.0, $)",
    "BEAM.yaw($)",
    "BEAM.material($)",
    "BEAM.colour([$, 0.5, 0.5])",
    // Shapes and assemblies.
    "assembly(\"a\", [shape::box($, 1.0, 1.0)])",
    "assembly(\"a\", [shape::cylinder($, 1.0)])",
    "assembly(\"a\", [shape::cone(1.0, $)])",
    "assembly(\"a\", [shape::frustum(1.0, $, 2.0)])",
    "assembly(\"a\", [shape::tube(1.0, 2.0, $)])",
    "assembly(\"a\", [shape::ring($, 0.2, 0.05)])",
    "assembly(\"a\", [shape::cap(1.0, $)])",
    "assembly(\"a\", [shape::extrude([[0.0, 0.0], [1.0, 0.0], [0.0, $]], 1.0)])",
    "assembly(\"a\", [shape::extrude([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], $)])",
    "assembly(\"a\", [shape::bend([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1]], $, 1.0)])",
    "assembly(\"a\", [shape::bend([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1]], 2.0, $)])",
    "assembly(\"a\", [shape::box(1.0, 1.0, 1.0).translate($, 0.0, 0.0)])",
    "assembly(\"a\", [shape::box(1.0, 1.0, 1.0).rotate_x($)])",
    "assembly(\"a\", [shape::box(1.0, 1.0, 1.0).scale($)])",
    "assembly(\"a\", [shape::box(1.0, 1.0, 1.0).scale(1.0, $, 1.0)])",
    "assembly(\"a\", [shape::box(1.0, 1.0, 1.0).part($)])",
    "assembly(\"a\", [TUBE.detail($, 4)])",
    "assembly(\"a\", [TUBE.detail(16, $)])",
    "assembly(\"a\", [TUBE.ovalise($, 2, 0.0)])",
    "assembly(\"a\", [TUBE.ovalise(0.01, $, 0.0)])",
    "assembly(\"a\", [TUBE.hoop_expansion($)])",
    "assembly(\"a\", [TUBE.dimple($, 0.5, 1.0, 0.3)])",
    "assembly(\"a\", [TUBE.dimple(0.02, 0.5, $, 0.3)])",
    "assembly(\"a\", [TUBE.buckle($, 0.5, 1.0, 0.4, 0.2)])",
    "assembly(\"a\", [TUBE.buckle(0.02, 0.5, 1.0, 0.4, $)])",
    "assembly(\"a\", [TUBE.elephant_foot($, 0.5)])",
    "assembly(\"a\", [TUBE.elephant_foot(0.02, $)])",
    "assembly(\"a\", [shape::box(2.0, 0.2, 0.2).deform_as_beam(\"x\", \"-z\", beam(#{ length: 2.0, width: 0.2, height: 0.2 }).point_load(1.0, $))])",
    "assembly(\"a\", [shape::box(2.0, 0.2, 0.2).deform_as_beam($, \"-z\", BEAM)])",
    "assembly($, [shape::box(1.0, 1.0, 1.0)])",
    "assembly(\"a\", [shape::box(1.0, 1.0, 1.0)]).pixel_tolerance($)",
    "assembly(\"a\", [shape::box(1.0, 1.0, 1.0)]).chord_tolerance($)",
    "assembly(\"a\", [shape::box(1.0, 1.0, 1.0)]).material($)",
    // The random source.
    "BEAM.at(rng.uniform(-1.0, $), 0.0, 0.0)",
    "BEAM.at(rng.uniform($, 1e308), 0.0, 0.0)",
    "BEAM.at(1.0 * rng.integer(0, $), 0.0, 0.0)",
    "if rng.chance($) { BEAM } else { BEAM.yaw(1.0) }",
    "rng.choice($)",
];

/// Options of `dataset(#{ ... })`, with the scene a plain beam.
const DATASETS: &[&str] = &[
    "samples: $",
    "views: $",
    "seed: $",
    "name: $",
    "antialias: $",
    "outputs: [$]",
    "outputs: $",
    "background: $",
    "background: [$, 0.0, 0.0]",
    "camera: #{ width: $, height: 16 }",
    "camera: #{ width: 16, height: 16, fov_y: $ }",
    "camera: #{ width: 16, height: 16, fov_y: [0.5, $] }",
    "camera: #{ width: 16, height: 16, yaw: [-1e308, $] }",
    "camera: #{ width: 16, height: 16, pitch: $ }",
    "camera: #{ width: 16, height: 16, roll: $ }",
    "camera: #{ width: 16, height: 16, distance: $ }",
    "camera: #{ width: 16, height: 16, margin: $ }",
    "camera: #{ width: 16, height: 16, aim_jitter: $ }",
    "camera: #{ width: 16, height: 16, principal_offset: #{ x: $ } }",
    "camera: #{ width: 16, height: 16, distortion: #{ k1: $ } }",
    "camera: #{ width: 16, height: 16, distortion: #{ p2: $ } }",
    "camera: #{ width: 16, height: 16, stereo: #{ baseline: $ } }",
    "camera: #{ width: 16, height: 16, stereo: #{ baseline: 0.1, toe_in: $ } }",
    "camera: #{ width: 16, height: 16, orbit: #{ distance: $ } }",
    "camera: #{ width: 16, height: 16, orbit: #{ pitch: 0.3, sweep: $ } }",
    "camera: #{ width: 16, height: 16, line: #{ from: [$, -10.0, 1.0], to: [5.0, -10.0, 1.0] } }",
    "camera: #{ width: 16, height: 16, fixed: [#{ position: [$, 5.0, 1.0] }] }",
    "light: #{ sun: #{ elevation: $ } }",
    "light: #{ sun: #{ intensity: $ } }",
    "light: #{ sun: #{ azimuth: [0.0, $] } }",
    "light: #{ sky: #{ intensity: $ } }",
    "light: #{ ambient: $ }",
    "light: #{ sun: #{ colour: [$, 1.0, 1.0] } }",
    "normals: $",
    "points: $",
];

/// One case: its recipe text and a label for failures.
struct Case {
    label: String,
    recipe: String,
}

fn cases() -> Vec<Case> {
    let mut cases = Vec::new();
    let dataset = |options: &str, scene: &str| {
        format!(
            "dataset(#{{ name: \"fuzz\", samples: 1, views: 1, outputs: [\"rgb\", \"depth\", \"mask\", \"parts\", \"instances\", \"cracks\", \"normals\", \"displacement\", \"flow\", \"rest_rgb\", \"rest_depth\", \"ray_distance\", \"mesh\", \"mesh_gltf\", \"points\"], points: 64, camera: #{{ width: 16, height: 16 }}, {options}, scene: |rng| {{ {scene} }} }})\n"
        )
    };
    for template in SCENES {
        let words = template.contains("material($)")
            || template.contains("theory($)")
            || template.contains("axial($)")
            || template.contains("mapping($)")
            || template.contains("part($)")
            || template.contains("assembly($");
        let values = if words { WORDS } else { VALUES };
        for value in values {
            let scene = template
                .replace("BEAM", BEAM)
                .replace("TUBE", TUBE)
                .replace('$', value);
            cases.push(Case {
                label: format!("scene {template} with $ = {value}"),
                recipe: dataset("seed: 1", &scene),
            });
        }
    }
    for template in DATASETS {
        for value in VALUES.iter().chain(WORDS) {
            // 10¹² samples is a valid dataset that takes for ever to write, not a hostile one.
            if template.starts_with("samples") && value.starts_with("1000000") {
                continue;
            }
            let options = template.replace('$', value);
            // The template's camera replaces the default one.
            let recipe = dataset("seed: 1", BEAM)
                .replacen("camera: #{ width: 16, height: 16 }, ", "", 1)
                .replacen("seed: 1", &format!("{options}, seed: 1"), 1);
            let recipe = if options.contains("camera:") {
                recipe
            } else {
                recipe.replacen("scene:", "camera: #{ width: 16, height: 16 }, scene:", 1)
            };
            let recipe = if options.starts_with("seed:") {
                recipe.replacen(", seed: 1", "", 1)
            } else if options.starts_with("points:") {
                recipe.replacen("points: 64, ", "", 1)
            } else {
                recipe
            };
            cases.push(Case {
                label: format!("dataset {template} with $ = {value}"),
                recipe,
            });
        }
    }
    cases
}

/// What was wrong with one run, if anything.
fn judge(case: &Case, dir: &Path) -> Option<String> {
    let recipe = dir.join("fuzz.rhai");
    std::fs::write(&recipe, &case.recipe).unwrap();
    let out = dir.join("out");
    let args: Vec<&std::ffi::OsStr> = vec![
        "run".as_ref(),
        recipe.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--quiet".as_ref(),
        "--threads".as_ref(),
        "1".as_ref(),
    ];
    let (output, finished) = run_limited(Duration::from_secs(60), &args);
    let text = stderr(&output);
    let verdict = if !finished {
        Some("did not finish within 60 s".to_string())
    } else if output.status.success() {
        complete(&out).err()
    } else if output.status.code() != Some(1) {
        Some(format!(
            "ended with {:?} (a panic or an abort)",
            output.status
        ))
    } else if text.contains("panicked") || !text.starts_with("error") {
        Some("failed without a clear error".to_string())
    } else {
        left_nothing(&out).err()
    };
    verdict.map(|v| {
        format!(
            "{}: {v}\n  stderr: {}",
            case.label,
            text.chars().take(600).collect::<String>()
        )
    })
}

/// A finished dataset: every sample listed, every listed file present, every number finite.
fn complete(out: &Path) -> Result<(), String> {
    let manifest = std::fs::read_to_string(out.join("manifest.jsonl"))
        .map_err(|e| format!("no manifest: {e}"))?;
    let run = read_json(&out.join("run.json"));
    valid(&RUN_SCHEMA, &run).map_err(|e| format!("run.json: {e}"))?;
    let samples = run["dataset"]["samples"].as_u64().unwrap_or(0);
    let lines: Vec<&str> = manifest.lines().collect();
    if lines.len() as u64 != samples {
        return Err(format!("{} of {samples} samples listed", lines.len()));
    }
    for line in lines {
        let entry: serde_json::Value = serde_json::from_str(line).map_err(|e| e.to_string())?;
        for file in entry["files"].as_array().into_iter().flatten() {
            let path = out.join(file.as_str().unwrap_or_default());
            let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
            if path.extension().is_some_and(|e| e == "json") {
                let record = serde_json::from_slice(&bytes).map_err(|e| e.to_string())?;
                valid(&VIEW_SCHEMA, &record).map_err(|e| format!("{}: {e}", path.display()))?;
            } else if path.extension().is_some_and(|e| e == "exr") {
                // Depths and distances are never negative; vectors may be.
                let name = path.to_string_lossy();
                let distance = name.ends_with("depth.exr") || name.ends_with("distance.exr");
                finite_floats(&bytes, distance).map_err(|e| format!("{}: {e}", path.display()))?;
            }
        }
    }
    Ok(())
}

/// The published schemas: a number written as `null` (how JSON shows NaN and ±∞) or any
/// other broken field fails them.
static VIEW_SCHEMA: LazyLock<jsonschema::Validator> = LazyLock::new(|| schema("view"));
static RUN_SCHEMA: LazyLock<jsonschema::Validator> = LazyLock::new(|| schema("run"));

fn schema(name: &str) -> jsonschema::Validator {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("docs/schema/{name}.schema.json"));
    jsonschema::validator_for(&read_json(&path)).unwrap()
}

fn valid(schema: &jsonschema::Validator, record: &serde_json::Value) -> Result<(), String> {
    match schema.iter_errors(record).next() {
        None => Ok(()),
        Some(e) => Err(format!("{e} at {}", e.instance_path())),
    }
}

/// Every float of an EXR is finite (and, for a distance, not negative).
fn finite_floats(bytes: &[u8], distance: bool) -> Result<(), String> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    for layer in &image.layer_data {
        for channel in &layer.channel_data.list {
            if let FlatSamples::F32(values) = &channel.sample_data {
                let wrong = |z: &&f32| !(z.is_finite() && (!distance || **z >= 0.0));
                if let Some(bad) = values.iter().find(wrong) {
                    return Err(format!("channel {} holds {bad}", channel.name));
                }
            }
        }
    }
    Ok(())
}

/// A run that fails on its only sample leaves no output folder at all.
fn left_nothing(out: &Path) -> Result<(), String> {
    match std::fs::read_dir(out) {
        Err(_) => Ok(()),
        Ok(entries) => {
            let names: Vec<String> = entries
                .filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().to_string())
                .collect();
            Err(format!("left {} behind: {names:?}", out.display()))
        }
    }
}

#[test]
fn hostile_values_in_every_call_end_in_a_dataset_or_a_clear_error() {
    let mut cases = cases();
    if let Some(n) = std::env::var("SHMGEN_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse::<usize>().ok())
    {
        cases.truncate(n);
    }
    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get().min(4));
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                let dir = tempfile::tempdir().unwrap();
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(case) = cases.get(i) else { break };
                    let place = dir.path().join(i.to_string());
                    std::fs::create_dir_all(&place).unwrap();
                    if let Some(failure) = judge(case, &place) {
                        failures.lock().unwrap().push(failure);
                    }
                    let _ = std::fs::remove_dir_all(&place);
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
