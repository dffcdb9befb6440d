//! Monitoring sequences seen from outside: a recipe declaring `dataset.sequence` and time loads
//! on a beam, run by the binary. Frames of a load history that has stopped changing are the
//! still of that load, byte for byte; each frame's deflection is the modal response at its
//! instant; runs are the same on any thread count, split into shards and after a kill
//! mid-sequence; bad values are refused at their line with their value.

mod common;
mod crossing;

use common::{hashes, ok, read_json, render, run, stderr, write};
use crossing::{CROSSING_FPS, CROSSING_FRAMES, Crossing, crossing_recipe, frame_view};
use shmgen::mechanics::Support;
use shmgen::mechanics::dynamics::{Axle, ModalBeam, TimeLoad};
use std::path::Path;

/// The layers the crossing's flow tests read.
const FLOW_OUTPUTS: &str = r#""depth", "mask", "frame_flow", "mesh""#;

/// A 2 m steel beam 0.1 × 0.2 m, simply supported, filmed side-on by one fixed camera.
/// `sequence` goes into `dataset(...)` (empty for a still), `calls` onto the beam.
fn recipe(sequence: &str, calls: &str, outputs: &str) -> String {
    format!(
        r#"dataset(#{{
    name: "seq", seed: 5, samples: 1, views: 1, outputs: [{outputs}],
    {sequence}
    camera: #{{ width: 64, height: 48, fov_y: deg(40),
        fixed: [#{{ position: [1.0, -4.0, 0.3], target: [1.0, 0.0, 0.0] }}] }},
    scene: |rng| {{
        let b = beam(#{{ length: 2.0, width: 0.1, height: 0.2 }});
        b.simply_supported();
        b.theory("euler_bernoulli");
        b.at(1.0, 0.0, 0.0);
        {calls}
        b
    }},
}});
"#
    )
}

const LAYERS: &str = r#""rgb", "depth", "mask", "displacement", "mesh""#;

/// The file of frame `frame` of view 0 of sample 0 with kind `kind` (`rgb.png`, ...).
fn frame_file(out: &Path, frame: u32, kind: &str) -> Vec<u8> {
    std::fs::read(out.join(format!("samples/0000/000000_00_f{frame:04}.{kind}"))).unwrap()
}

fn still_file(out: &Path, kind: &str) -> Vec<u8> {
    std::fs::read(out.join(format!("samples/0000/000000_00.{kind}"))).unwrap()
}

#[test]
fn frames_of_a_finished_load_history_are_the_still_of_that_load_byte_for_byte() {
    let (_a, still) = render(&recipe("", "b.point_force(0.7, 4e5);", LAYERS), &[]);
    // Three histories that hold 4e5 N at 0.7 m: a step at t = 0 and a ramp finished by 0.05 s,
    // both quasi-static (every frame, and frames from t = 0.05 on), and the load declared static
    // on a beam in motion without time loads (every frame).
    let sequence = "sequence: #{ duration: 0.1, fps: 60.0 },";
    let step = recipe(
        sequence,
        "b.ramp(0.7, 4e5, 0.0, 0.0); b.quasi_static(true);",
        LAYERS,
    );
    let ramp = recipe(
        sequence,
        "b.ramp(0.7, 4e5, 0.0, 0.05); b.quasi_static(true);",
        LAYERS,
    );
    let constant = recipe(
        sequence,
        "b.point_force(0.7, 4e5); b.damping(0.05);",
        LAYERS,
    );
    let (_b, step) = render(&step, &[]);
    let (_c, ramp) = render(&ramp, &[]);
    let (_d, constant) = render(&constant, &[]);
    for kind in ["rgb.png", "depth.exr", "mask.png", "displacement.exr"] {
        let expected = still_file(&still, kind);
        for k in 0..6 {
            assert!(
                frame_file(&step, k, kind) == expected,
                "step, frame {k}: {kind}"
            );
            assert!(
                frame_file(&constant, k, kind) == expected,
                "constant, frame {k}: {kind}"
            );
        }
        for k in 3..6 {
            assert!(
                frame_file(&ramp, k, kind) == expected,
                "ramp, frame {k}: {kind}"
            );
        }
    }
    // Before the ramp has finished the beam is less deflected: the comparison can tell (depth
    // cannot, side-on: the beam moves across the view, not along it).
    let displacement = still_file(&still, "displacement.exr");
    assert!(frame_file(&ramp, 1, "displacement.exr") != displacement);
    let mesh = std::fs::read(still.join("samples/0000/000000.mesh.ply")).unwrap();
    let frame_mesh = std::fs::read(step.join("samples/0000/000000_f0004.mesh.ply")).unwrap();
    assert!(mesh == frame_mesh);
}

/// The vehicle of the label test: two axles 0.5 m apart crossing the 2 m span at 8 m/s.
const AXLES: [(f64, f64); 2] = [(0.0, 3e5), (0.5, 2e5)];
const SPEED: f64 = 8.0;
const ENTERS: f64 = 0.02;

#[test]
fn each_frame_deflects_as_the_modal_response_at_its_instant() {
    let calls = format!(
        "b.vehicle([[{}, {}], [{}, {}]], {SPEED}, {ENTERS}); b.damping(0.03); b.modes(6);",
        AXLES[0].0, AXLES[0].1, AXLES[1].0, AXLES[1].1
    );
    let fps = 120.0;
    let sequence = format!("sequence: #{{ duration: 0.5, fps: {fps} }},");
    let (_dir, out) = render(&recipe(&sequence, &calls, r#""depth""#), &[]);

    // The truth: ModalBeam directly, on the same beam (E = 210 GPa, steel 7850 kg/m³).
    let (width, height, length): (f64, f64, f64) = (0.1, 0.2, 2.0);
    let ei = 210e9 * width * height.powi(3) / 12.0;
    let mass = 7850.0 * width * height;
    let beam = ModalBeam::new(Support::SimplySupported, length, ei, mass, 0.03, 6).unwrap();
    let loads = [TimeLoad::Vehicle {
        axles: AXLES
            .iter()
            .map(|&(behind, force)| Axle { behind, force })
            .collect(),
        speed: SPEED,
        enters: ENTERS,
    }];
    let frames = 60;
    let times: Vec<f64> = (0..frames).map(|k| k as f64 / fps).collect();
    let response = beam.respond(&loads, 0.0, &times, 64);
    let mut dynamic_seen = 0.0f64;
    for (k, &time) in times.iter().enumerate() {
        let record = read_json(&out.join(format!("samples/0000/000000_00_f{k:04}.json")));
        assert_eq!(record["frame"]["index"], k);
        assert_eq!(record["frame"]["time"].as_f64().unwrap(), time);
        let labels = &record["scene"]["structures"][0]["labels"];
        let label = labels["max_deflection"].as_f64().unwrap();
        // The truth's largest deflection, on a fine grid of the span plus every axle on it.
        let axles_on = beam.static_loads(&loads, time);
        let points = (0..=4000)
            .map(|i| length * i as f64 / 4000.0)
            .chain(axles_on.iter().map(|l| match *l {
                shmgen::mechanics::Load::Point { at, .. } => at,
                _ => 0.0,
            }));
        let truth = points
            .map(|x| response.at(&beam, &loads, k, x).deflection)
            .fold(0.0f64, |a, v| if v.abs() > a.abs() { v } else { a });
        assert!(
            (label - truth).abs() <= 1e-5 * truth.abs().max(1e-6),
            "frame {k}: label {label} m, modal response {truth} m"
        );
        // The frames are dynamic: mid-span departs from the static deflection under the same
        // forces (checked below to be a visible share of the deflection).
        let mid = response.at(&beam, &loads, k, length / 2.0).deflection;
        dynamic_seen = dynamic_seen.max((mid - static_mid(&beam, &loads, time)).abs());
    }
    assert!(dynamic_seen > 1e-6, "no dynamic part seen: {dynamic_seen}");
}

/// Mid-span deflection of the static solution under the forces acting at `t`: a single-step
/// response with every mode's dynamic part removed, by superposing point-load closed forms.
fn static_mid(beam: &ModalBeam, loads: &[TimeLoad], t: f64) -> f64 {
    let (length, ei) = (2.0, 210e9 * 0.1 * 0.2f64.powi(3) / 12.0);
    beam.static_loads(loads, t)
        .iter()
        .map(|load| match *load {
            // Mid-span deflection of a simply supported span under P at a (a ≤ L/2 mirrored):
            // P a (3L² − 4a²) / (48 EI).
            shmgen::mechanics::Load::Point { at, force } => {
                let a = at.min(length - at);
                force * a * (3.0 * length * length - 4.0 * a * a) / (48.0 * ei)
            }
            _ => 0.0,
        })
        .sum()
}

/// A short, small run of `scripts/monitoring.rhai`: three crossings, 15 frames, 48 px.
const MONITORING_SETS: [&str; 6] = [
    "--set",
    "size=48",
    "--set",
    "duration=0.25",
    "--set",
    "samples=3",
];

fn monitoring_recipe() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/monitoring.rhai")
}

fn monitoring(out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = MONITORING_SETS.to_vec();
    args.extend(extra);
    run(&monitoring_recipe(), out, &args)
}

#[test]
fn sequences_are_the_same_bytes_on_any_thread_count_shard_split_and_after_a_kill() {
    let dir = tempfile::tempdir().unwrap();
    let one = dir.path().join("one");
    let two = dir.path().join("two");
    ok(monitoring(&one, &["--threads", "1"]));
    ok(monitoring(&two, &["--threads", "2"]));
    let reference = hashes(&one);
    assert!(reference.keys().any(|f| f.ends_with("_01_f0014.rgb.png")));
    assert_eq!(reference, hashes(&two));
    // Two shards (by sample) into one folder, the second on one thread.
    let sharded = dir.path().join("sharded");
    ok(monitoring(&sharded, &["--shard", "1/2"]));
    ok(monitoring(&sharded, &["--shard", "0/2", "--threads", "1"]));
    assert_eq!(reference, hashes(&sharded));

    // Killed once the first sample is listed: the second is then mid-sequence.
    let killed = dir.path().join("killed");
    let mut args = MONITORING_SETS.to_vec();
    args.extend(["--threads", "1"]);
    let child = common::spawn_run(&monitoring_recipe(), &killed, &args);
    let done = common::kill_after_samples(child, &killed, 1);
    assert!(
        done < 3,
        "the kill must land before the end ({done} samples done)"
    );
    ok(monitoring(&killed, &["--threads", "1"]));
    assert_eq!(reference, hashes(&killed));
}

#[test]
fn bad_sequences_and_time_loads_are_refused_at_their_line_with_their_value() {
    let dir = tempfile::tempdir().unwrap();
    // Dataset options are shown at the `dataset(` call (line 1), as every dataset option's value
    // is; beam calls at their own line.
    let cases = [
        ("sequence: #{ duration: 1.0, fps: 0 },", "", "fps = 0", 1),
        (
            "sequence: #{ duration: 1.0, fps: 30.0, exposure: 0.5 },",
            "",
            "exposure = 0.5",
            1,
        ),
        (
            "sequence: #{ duration: 1.0, fps: 30.0 },",
            "b.vehicle([[0.0, 1e4]], -3.0, 0.0);",
            "speed must be positive, got -3 m/s",
            11,
        ),
        (
            "sequence: #{ duration: 1.0, fps: 30.0 },",
            "b.hammer(2.5, 1e4, 0.1, 0.01);",
            "load position 2.5 m lies off the span",
            11,
        ),
        (
            "sequence: #{ duration: 1.0, fps: 30.0 },",
            "b.damping(1.5);",
            "damping ratio = 1.5",
            11,
        ),
        (
            "sequence: #{ duration: 1.0, fps: 30.0 },",
            "b.ambient(rng, 1.0, -2.0, 10.0, 0.0, 1.0);",
            "ambient rms = -2",
            11,
        ),
    ];
    for (i, (sequence, calls, says, line)) in cases.into_iter().enumerate() {
        let path = write(
            dir.path(),
            &format!("bad{i}.rhai"),
            recipe(sequence, calls, LAYERS),
        );
        let out = run(&path, &dir.path().join(format!("out{i}")), &[]);
        assert!(!out.status.success(), "case {i} ran");
        let text = stderr(&out);
        assert!(text.contains(says), "case {i}: {text}");
        assert!(
            text.contains(&format!("bad{i}.rhai:{line}:")),
            "case {i}: no line {line} in {text}"
        );
    }
}

#[test]
fn a_sequence_lists_each_file_once_and_its_sensor_series_once_per_sample() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    ok(run(
        &monitoring_recipe(),
        &out,
        &[
            "--set",
            "size=32",
            "--set",
            "duration=0.1",
            "--set",
            "samples=1",
        ],
    ));
    let manifest = std::fs::read_to_string(out.join("manifest.jsonl")).unwrap();
    let line: serde_json::Value = serde_json::from_str(manifest.lines().next().unwrap()).unwrap();
    let files: Vec<&str> = line["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    let unique: std::collections::BTreeSet<&str> = files.iter().copied().collect();
    assert_eq!(files.len(), unique.len(), "a file listed twice: {files:?}");
    // 6 frames × 2 views × (rgb, depth, mask, json) and the two rates' CSV and NPY.
    assert_eq!(files.len(), 6 * 2 * 4 + 4, "{files:?}");
    let sensors = files.iter().filter(|f| f.contains(".sensors_")).count();
    assert_eq!(sensors, 4, "{files:?}");
}

/// A 2 m steel beam 0.1 × 0.2 m (EI = 210 GPa × 0.1 · 0.2³/12) in a plain colour on black,
/// filmed side-on from 2 m at 640 × 480 px by one fixed camera, over `sequence`.
fn blur_recipe(sequence: &str, calls: &str) -> String {
    format!(
        r#"dataset(#{{
    name: "blur", seed: 5, samples: 1, views: 1, outputs: ["rgb", "mask"],
    background: "black",
    {sequence}
    camera: #{{ width: 640, height: 480, fov_y: deg(40),
        fixed: [#{{ position: [1.0, -2.0, 0.15], target: [1.0, 0.0, 0.0] }}] }},
    scene: |rng| {{
        let b = beam(#{{ length: 2.0, width: 0.1, height: 0.2 }});
        b.simply_supported();
        b.theory("euler_bernoulli");
        b.colour([0.6, 0.6, 0.6]);
        b.at(1.0, 0.0, 0.0);
        {calls}
        b
    }},
}});
"#
    )
}

/// Linear light (green) of column `x` of frame `frame`'s RGB, row by row.
fn linear_column(out: &Path, frame: u32, x: usize) -> Vec<f64> {
    let path = out.join(format!("samples/0000/000000_00_f{frame:04}.rgb.png"));
    let (w, h, channels, bytes) = common::read_png(&path);
    (0..h)
        .map(|y| {
            let code = f64::from(bytes[(y * w + x) * channels + 1]) / 255.0;
            if code <= 0.04045 {
                code / 12.92
            } else {
                ((code + 0.055) / 1.055).powf(2.4)
            }
        })
        .collect()
}

/// Mean and variance of the rows where `column` falls from the beam's face (above) to the
/// black background (below) within `rows`: the fall between each row and the next, as weights.
fn edge_spread(column: &[f64], rows: std::ops::Range<usize>) -> (f64, f64) {
    let face = column[rows.start];
    let falls: Vec<(f64, f64)> = rows
        .map(|y| {
            (
                y as f64 + 1.0,
                ((column[y] - column[y + 1]) / face).max(0.0),
            )
        })
        .collect();
    let total: f64 = falls.iter().map(|f| f.1).sum();
    let mean = falls.iter().map(|(y, w)| y * w).sum::<f64>() / total;
    let var = falls
        .iter()
        .map(|(y, w)| w * (y - mean).powi(2))
        .sum::<f64>()
        / total;
    (mean, var)
}

#[test]
fn a_still_structure_blurs_to_its_unblurred_frames_byte_for_byte() {
    let calls = "b.point_force(0.7, 4e5); b.damping(0.05);";
    let sharp = blur_recipe("sequence: #{ duration: 0.1, fps: 30.0 },", calls);
    let blurred = blur_recipe(
        "sequence: #{ duration: 0.1, fps: 30.0, motion_blur: 5 },",
        calls,
    );
    let (_a, sharp) = render(&sharp, &[]);
    let (_b, blurred) = render(&blurred, &[]);
    for k in 0..3 {
        for kind in ["rgb.png", "mask.png"] {
            assert!(
                frame_file(&sharp, k, kind) == frame_file(&blurred, k, kind),
                "frame {k}: {kind}"
            );
        }
        let record = read_json(&blurred.join(format!("samples/0000/000000_00_f{k:04}.json")));
        assert_eq!(record["frame"]["motion_blur"], 5);
        let record = read_json(&sharp.join(format!("samples/0000/000000_00_f{k:04}.json")));
        assert!(record["frame"].get("motion_blur").is_none());
    }
}

#[test]
fn a_moving_edge_spreads_over_the_distance_it_moves_during_the_exposure() {
    // A force ramping to 1e7 N over 0.4 s at mid-span, quasi-static: the mid-span deflection
    // grows at a constant rate, w(t) = (F t / 0.4 s) L³ / 48EI. Frame 1 (t = 0.1 s) is exposed
    // over [0.05, 0.15] s, 8 sub-instants.
    let calls = "b.ramp(1.0, 1e7, 0.0, 0.4); b.quasi_static(true);";
    let n = 8.0;
    let sequence =
        |blur: &str| format!("sequence: #{{ duration: 0.25, fps: 10.0, exposure: 0.1{blur} }},");
    let (_a, sharp) = render(&blur_recipe(&sequence(""), calls), &[]);
    let (_b, blurred) = render(&blur_recipe(&sequence(", motion_blur: 8"), calls), &[]);
    let ei = 210e9 * 0.1 * 0.2f64.powi(3) / 12.0;
    let w = |t: f64| 1e7 * t / 0.4 * 8.0 / (48.0 * ei);
    // The near bottom edge at mid-span, where the first and last sub-instants see it.
    let record = read_json(&blurred.join("samples/0000/000000_00_f0001.json"));
    let k: [[f64; 3]; 3] = common::matrix(&record["camera"]["K"]);
    let w2c: [[f64; 4]; 4] = common::matrix(&record["camera"]["w2c_opencv"]);
    let row_of = |t: f64| {
        let c = common::transform(&w2c, [1.0, -0.05, -0.1 - w(t)]);
        k[1][1] * c[1] / c[2] + k[1][2]
    };
    let exposure = record["frame"]["exposure"].as_f64().unwrap();
    assert_eq!(exposure, 0.1);
    let (first, last) = (0.05 + exposure / (2.0 * n), 0.15 - exposure / (2.0 * n));
    let travel = row_of(last) - row_of(first);
    assert!(
        travel > 8.0,
        "the edge travels {travel} px: too little to measure"
    );
    let x = (k[0][2]) as usize;
    let rows = (row_of(first) as usize - 6)..(row_of(last) as usize + 6);
    let (_, sharp_var) = edge_spread(&linear_column(&sharp, 1, x), rows.clone());
    let (mean, var) = edge_spread(&linear_column(&blurred, 1, x), rows);
    // n equally spaced edges over `travel`: variance travel² (n + 1) / (12 (n − 1)), added to
    // the sharp edge's own; centred where the edge is at mid-exposure.
    let expected = travel.powi(2) * (n + 1.0) / (12.0 * (n - 1.0));
    let added = var - sharp_var;
    assert!(
        (added / expected - 1.0).abs() < 0.05,
        "added variance {added} px², expected {expected} (travel {travel} px)"
    );
    let middle = row_of(0.1);
    assert!((mean - middle).abs() < 0.25, "{mean} against {middle}");
}

/// The 2 m beam of `recipe`, static, filmed by a camera flying `path` (a `sequence.paths` entry).
fn flight_recipe(path: &str) -> String {
    recipe(
        &format!("sequence: #{{ duration: 0.2, fps: 20.0, paths: [{path}] }},"),
        "",
        r#""rgb", "depth", "mask""#,
    )
}

#[test]
fn a_flying_camera_is_written_where_its_path_is_and_sees_fixed_points_where_they_project() {
    // A straight flight along the beam, 3 m in front of it, looking at a point 10 m beyond.
    let (from, to, target) = ([0.2, -3.0, 0.4], [1.8, -3.0, 0.6], [1.0, 10.0, 0.0]);
    let path = format!("#{{ view: 0, from: {from:?}, to: {to:?}, target: {target:?} }}");
    let (_dir, out) = render(&flight_recipe(&path), &[]);
    // A point on the beam's near face (y = -0.05), a quarter span from its centre.
    let point = [0.5, -0.05, 0.02];
    let mut columns = Vec::new();
    for k in 0..4u32 {
        let t = f64::from(k) / 20.0;
        let s = t / 0.2;
        let expected: [f64; 3] = std::array::from_fn(|i| from[i] + s * (to[i] - from[i]));
        let record = read_json(&out.join(format!("samples/0000/000000_00_f{k:04}.json")));
        let position: Vec<f64> = (0..3)
            .map(|i| record["camera"]["position"][i].as_f64().unwrap())
            .collect();
        for i in 0..3 {
            assert!(
                (position[i] - expected[i]).abs() < 1e-12,
                "frame {k}: {position:?}"
            );
        }
        let w2c: [[f64; 4]; 4] = common::matrix(&record["camera"]["w2c_opencv"]);
        let k_matrix: [[f64; 3]; 3] = common::matrix(&record["camera"]["K"]);
        // It looks at the target: the target projects to the principal point.
        let c = common::transform(&w2c, target);
        assert!(
            c[0].abs() < 1e-9 && c[1].abs() < 1e-9 && c[2] > 0.0,
            "{c:?}"
        );
        // The fixed point: its pixel sees the beam at the point's own depth.
        let c = common::transform(&w2c, point);
        let (u, v) = (
            k_matrix[0][0] * c[0] / c[2] + k_matrix[0][2],
            k_matrix[1][1] * c[1] / c[2] + k_matrix[1][2],
        );
        let pixel = v as usize * 64 + u as usize;
        let mask = common::read_png(&out.join(format!("samples/0000/000000_00_f{k:04}.mask.png")));
        assert_eq!(mask.3[pixel], 255, "frame {k}: ({u}, {v})");
        let depth =
            common::read_exr(&out.join(format!("samples/0000/000000_00_f{k:04}.depth.exr")));
        // The face is flat: across the pixel's half-width its depth changes by under 2 cm here.
        assert!(
            (f64::from(depth[pixel]) - c[2]).abs() < 0.02,
            "frame {k}: {} against {}",
            depth[pixel],
            c[2]
        );
        columns.push(u);
    }
    // The camera flew 1.2 m along the beam in those frames: the point crossed the image.
    assert!(columns[0] - columns[3] > 5.0, "{columns:?}");
}

#[test]
fn a_flying_camera_looks_at_the_target_its_waypoints_sweep_between() {
    // A pass along the beam whose gaze sweeps from its left end to its right end; the middle
    // waypoint takes the path's target.
    let path = "#{ view: 0, target: [1.0, 0.0, 0.0], waypoints: [
        [0.0, [0.4, -3.0, 0.5], [0.0, 0.0, 0.0]],
        [0.1, [1.0, -3.0, 0.5]],
        [0.2, [1.6, -3.0, 0.5], [2.0, 0.0, 0.1]] ] }";
    let (_dir, out) = render(&flight_recipe(path), &[]);
    for k in 0..4u32 {
        let t = f64::from(k) / 20.0;
        let s = (t / 0.1).fract();
        let (from, to) = if t < 0.1 {
            ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0])
        } else {
            ([1.0, 0.0, 0.0], [2.0, 0.0, 0.1])
        };
        let aim: [f64; 3] = std::array::from_fn(|i| from[i] + s * (to[i] - from[i]));
        let record = read_json(&out.join(format!("samples/0000/000000_00_f{k:04}.json")));
        let w2c: [[f64; 4]; 4] = common::matrix(&record["camera"]["w2c_opencv"]);
        // The point aimed at then lies on the optical axis, in front of the camera.
        let c = common::transform(&w2c, aim);
        assert!(
            c[0].abs() < 1e-9 && c[1].abs() < 1e-9 && c[2] > 0.0,
            "frame {k}: {aim:?} seen at {c:?}"
        );
        // The camera stays level: world z up is in the image's vertical plane.
        let right = [w2c[0][0], w2c[0][1], w2c[0][2]];
        assert!(right[2].abs() < 1e-12, "frame {k}: {right:?}");
    }
}

#[test]
fn bad_flight_paths_are_refused_at_the_dataset_call_with_their_value() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "#{ view: 3, from: [0.0, -3.0, 0.0], to: [1.0, -3.0, 0.0], target: [1.0, 0.0, 0.0] }",
            "sequence.paths[0].view = 3 but the dataset has 1 views",
        ),
        (
            "#{ view: 0, waypoints: [[0.1, [0.0, -3.0, 0.0]], [0.05, [1.0, -3.0, 0.0]]], target: [1.0, 0.0, 0.0] }",
            "waypoints[1]: time 0.05 s must be finite and after the waypoint before (0.1 s)",
        ),
        (
            "#{ view: 0, from: [0.0, 0.0, 0.0], to: [2.0, 0.0, 0.0], target: [1.0, 0.0, 0.0] }",
            "passes through its target [1.0, 0.0, 0.0]",
        ),
        (
            "#{ view: 0, waypoints: [[0.0, [0.0, -3.0]]], target: [1.0, 0.0, 0.0] }",
            "must be a list of [time, [x, y, z]]",
        ),
        (
            "#{ view: 0, from: [0.0, -3.0, 0.0], target: [1.0, 0.0, 0.0] }",
            "takes either waypoints",
        ),
        (
            "#{ view: 0, waypoints: [[0.0, [0.0, -3.0, 0.0], [1.0, 0.0, 0.0]], [0.1, [1.0, -3.0, 0.0]]] }",
            "[1] = [0.1, [1.0, -3.0, 0.0]] has no target of its own and the path no `target`",
        ),
        (
            "#{ view: 0, waypoints: [[0.0, [0.0, -3.0, 0.0], [2.0, -3.0, 0.0]], [0.2, [2.0, -3.0, 0.0], [0.0, -3.0, 0.0]]] }",
            "passes through its target [1.0, -3.0, 0.0] (at [1.0, -3.0, 0.0], t = 0.1 s)",
        ),
    ];
    for (i, (path, says)) in cases.into_iter().enumerate() {
        let file = write(dir.path(), &format!("bad{i}.rhai"), flight_recipe(path));
        let out = run(&file, &dir.path().join(format!("out{i}")), &[]);
        assert!(!out.status.success(), "case {i} ran");
        let text = stderr(&out);
        assert!(text.contains(says), "case {i}: {text}");
        assert!(
            text.contains(&format!("bad{i}.rhai:1:")),
            "case {i}: {text}"
        );
    }
}

/// Frame `frame`'s flow to the next (`"next"`) or previous (`"prev"`) frame: (u, v) where
/// valid, per pixel.
fn frame_flow(out: &Path, frame: usize, side: &str) -> Vec<Option<[f64; 2]>> {
    let path = |kind: &str| out.join(format!("samples/0000/000000_00_f{frame:04}.{kind}"));
    let (_, channels) = common::read_exr_channels(&path(&format!("flow_{side}.exr")));
    let (_, _, _, valid) = common::read_png(&path(&format!("flow_{side}_valid.png")));
    (0..valid.len())
        .map(|i| {
            (valid[i] == 255).then(|| [f64::from(channels["R"][i]), f64::from(channels["G"][i])])
        })
        .collect()
}

/// Compares the flow of every frame to the next and the previous with the projection, through
/// the other frame's written camera, of each seen point carried by the closed-form kinematics;
/// returns the largest error (px), the largest flow (px) and the largest share of the flow the
/// camera's own motion makes.
fn check_frame_flows(out: &Path, crossing: &Crossing) -> (f64, f64, f64) {
    let views: Vec<common::View> = (0..CROSSING_FRAMES).map(|k| frame_view(out, k)).collect();
    let (mut worst, mut largest, mut camera_part) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..CROSSING_FRAMES {
        let this = &views[k];
        for (side, other) in [("next", k + 1), ("prev", k.wrapping_sub(1))] {
            let flow = frame_flow(out, k, side);
            let Some(that) = views.get(other) else {
                assert!(
                    flow.iter().all(Option::is_none),
                    "frame {k}: {side} at the end"
                );
                continue;
            };
            let (mut valid, mut seen) = (0, 0);
            for row in 0..this.height {
                for col in 0..this.width {
                    let Some(p) = this.point(row, col) else {
                        continue;
                    };
                    seen += 1;
                    let Some([u, v]) = flow[row * this.width + col] else {
                        continue;
                    };
                    valid += 1;
                    let moved = crossing.carried(p, k, other);
                    let ([tu, tv], _) = that.project(moved);
                    let (u0, v0) = (col as f64 + 0.5, row as f64 + 0.5);
                    let error = (u - (tu - u0)).hypot(v - (tv - v0));
                    // The chord error of the two tessellations (piecewise linear between
                    // stations) and the neglected second-order terms: a few thousandths.
                    assert!(
                        error < 5e-3,
                        "frame {k} {side}, pixel ({row}, {col}): flow ({u}, {v}), truth ({}, {}), error {error} px",
                        tu - u0,
                        tv - v0
                    );
                    worst = worst.max(error);
                    largest = largest.max(u.hypot(v));
                    // The same point moved, seen through this frame's camera: what the flow
                    // would be with a still camera.
                    let ([su, sv], _) = this.project(moved);
                    camera_part = camera_part.max((tu - su).hypot(tv - sv));
                }
            }
            assert!(
                valid as f64 > 0.95 * seen as f64,
                "frame {k} {side}: {valid} of {seen} pixels valid"
            );
        }
    }
    (worst, largest, camera_part)
}

#[test]
fn flow_between_frames_is_the_projected_difference_of_the_closed_form_displacements() {
    let (_dir, out) = render(&crossing_recipe("", FLOW_OUTPUTS), &[]);
    let crossing = Crossing::new();
    let (worst, largest, camera_part) = check_frame_flows(&out, &crossing);
    eprintln!(
        "still mounts: error {worst:.2e} px, flow up to {largest:.3} px, camera {camera_part:.2e} px"
    );
    // The beam moves a visible share of a pixel between frames, and the cameras do not.
    assert!(largest > 0.2, "flow up to {largest} px");
    assert!(camera_part < 1e-9, "{camera_part}");
    // The frames tessellate the beam differently (a station follows the axle): their unloaded
    // meshes differ, so no point can be carried by its triangle's weights from one frame's mesh
    // to the next.
    let rest = |k: usize| {
        std::fs::read(out.join(format!("samples/0000/000000_f{k:04}.rest.ply"))).unwrap()
    };
    let changes = (1..CROSSING_FRAMES).filter(|&k| rest(k) != rest(k - 1));
    assert!(changes.count() >= CROSSING_FRAMES - 2);
    exported_to_webdataset_as_arrays(&out);
}

/// `shmgen export --format webdataset` writes the flows between frames as float32 (H, W, 2)
/// arrays and their validity as bool (H, W) arrays, as it writes the still's flow.
fn exported_to_webdataset_as_arrays(out: &Path) {
    let wds = out.with_file_name("wds");
    ok(common::shmgen(&[
        "export".as_ref(),
        out.as_os_str(),
        "--format".as_ref(),
        "webdataset".as_ref(),
        "--out".as_ref(),
        wds.as_os_str(),
    ]));
    let mut headers = std::collections::BTreeMap::new();
    for shard in common::files_with_extension(&wds, "gz") {
        let gzip = flate2::read::GzDecoder::new(std::fs::File::open(&shard).unwrap());
        for entry in tar::Archive::new(gzip).entries().unwrap() {
            let mut entry = entry.unwrap();
            let name = entry.path().unwrap().to_string_lossy().to_string();
            let mut bytes = Vec::new();
            std::io::Read::read_to_end(&mut entry, &mut bytes).unwrap();
            let header = String::from_utf8_lossy(&bytes[..bytes.len().min(128)]).to_string();
            headers.insert(name, header);
        }
    }
    for side in ["next", "prev"] {
        let vectors = &headers[&format!("000000_00_f0003.flow_{side}.npy")];
        assert!(
            vectors.contains("'<f4'") && vectors.contains("(120, 160, 2)"),
            "{vectors}"
        );
        let valid = &headers[&format!("000000_00_f0003.flow_{side}_valid.npy")];
        assert!(
            valid.contains("'|b1'") && valid.contains("(120, 160)"),
            "{valid}"
        );
    }
}

#[test]
fn flow_between_frames_follows_each_frames_camera_when_the_mount_shakes() {
    let mount = ", mount: #{ rotation: 2e-3, translation: 1e-3, band: 5.0 }";
    let (_dir, out) = render(&crossing_recipe(mount, FLOW_OUTPUTS), &[]);
    let crossing = Crossing::new();
    let (worst, largest, camera_part) = check_frame_flows(&out, &crossing);
    eprintln!(
        "shaken mounts: error {worst:.2e} px, flow up to {largest:.3} px, camera {camera_part:.3} px"
    );
    assert!(
        camera_part > 0.3,
        "the mount moved the camera by {camera_part} px only"
    );
}

#[test]
fn flow_between_frames_is_refused_for_a_still_at_the_dataset_call() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "still.rhai",
        recipe("", "", r#""rgb", "frame_flow""#),
    );
    let out = run(&path, &dir.path().join("out"), &[]);
    assert!(!out.status.success());
    let text = stderr(&out);
    assert!(
        text.contains("\"frame_flow\"") && text.contains("dataset.sequence"),
        "{text}"
    );
    assert!(text.contains("still.rhai:1:"), "{text}");
}

/// Positions (m from x = 0) of the crossing's displacement and rotation sensors, all in view.
const SENSORS_AT: [f64; 3] = [0.8, 1.0, 1.2];

#[test]
fn displacement_sensors_agree_with_the_pixels_that_see_their_points() {
    // The crossing with, at each of SENSORS_AT, a displacement transducer and an inclinometer
    // sampled at the frame rate, and the per-pixel displacement written.
    let sensors: String = SENSORS_AT
        .iter()
        .enumerate()
        .map(|(i, at)| {
            format!(
                r#"b.sensor(#{{ name: "d{i}", kind: "displacement", at: {at}, rate: {CROSSING_FPS} }});
        b.sensor(#{{ name: "r{i}", kind: "rotation", at: {at}, rate: {CROSSING_FPS} }});
        "#
            )
        })
        .collect();
    let recipe = crossing_recipe("", r#""depth", "mask", "displacement""#)
        .replace("b.modes(6);", &format!("b.modes(6); {sensors}"));
    let (_dir, out) = render(&recipe, &[]);
    let csv = std::fs::read_to_string(out.join("samples/0000/000000.sensors_30hz.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), CROSSING_FRAMES);
    // What is compared: a sensor records the deflection v of the axis (downward) from the static
    // equilibrium, and this beam has no static load, so its equilibrium is the unloaded beam
    // from which the displacement label is measured. The camera sees the side face; the face's
    // point at the axis's height above the sensor moves down by v exactly (plane sections:
    // a fibre e above the axis drops by v + e(1 − cos θ)), and it sits in the pixel its moved
    // position projects to. The pixel's label is the displacement of the point its centre sees,
    // up to half a pixel away along the beam: within |θ| · (half a footprint) of v, θ the
    // inclinometer's reading, plus a micrometre for float32 and the chord error.
    let mut largest = 0.0f64;
    for (k, row) in rows.iter().enumerate() {
        let view = frame_view(&out, k);
        let (_, channels) = common::read_exr_channels(
            &out.join(format!("samples/0000/000000_00_f{k:04}.displacement.exr")),
        );
        for (i, &at) in SENSORS_AT.iter().enumerate() {
            let (v, theta) = (row[1 + 2 * i], row[2 + 2 * i]);
            let ([u, w], depth) = view.project([at, -0.05, -v]);
            let (col, line) = (u.floor() as usize, w.floor() as usize);
            let pixel = line * view.width + col;
            let seen = -f64::from(channels["B"][pixel]);
            let footprint = depth / view.k()[0][0];
            let bound = theta.abs() * footprint + 1e-6;
            assert!(
                (seen - v).abs() <= bound,
                "frame {k}, sensor d{i} at {at} m: sensor {v} m, pixel ({line}, {col}) {seen} m, bound {bound} m"
            );
            largest = largest.max(v.abs());
        }
    }
    // The crossing deflects the beam by millimetres, far beyond the bound.
    assert!(largest > 1e-3, "{largest}");
}
