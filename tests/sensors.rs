//! Virtual sensors through the CLI: a beam's sensors declared in a recipe are written beside
//! the sample as CSV and `.npy` (one pair per rate) with the values the closed forms give (a
//! step's static deflection PL³/48EI and bottom-fibre strain (PL/4)c/EI), the two files hold
//! the same numbers, and a bad sensor is refused at its file, line and column with its value;
//! `shmgen eval` of histories: the truth as prediction scores 0, an offset scores its size, a
//! missing file makes the evaluation partial, and the first frequency it identifies from a
//! hammer test's record is the beam's closed form (π/2L²)√(EI/m).

use std::path::Path;
use std::process::Command;

mod common;

/// `shmgen run` of `recipe` (written to `dir/recipe.rhai`) into `dir/out`.
fn run(dir: &Path, recipe: &str) -> std::process::Output {
    let file = dir.join("recipe.rhai");
    std::fs::write(&file, recipe).unwrap();
    common::run(&file, &dir.join("out"), &[])
}

/// A 10 m steel beam 0.2 × 0.5 m under a step of `FORCE` at mid-span at 0.5 s, damped at ζ = 0.6 so it
/// has settled long before 3 s, with the sensors `sensors` (Rhai calls on the beam).
fn recipe(sensors: &str) -> String {
    format!(
        r#"dataset(#{{
    name: "sensors", seed: 1, samples: 1, views: 1, outputs: ["mask"],
    camera: #{{ width: 16, height: 16, fov_y: deg(60), distance: "frame" }},
    sequence: #{{ duration: 3.0, fps: 10.0 }},
    scene: |rng| beam(#{{ length: 10.0, width: 0.2, height: 0.5 }})
        .ramp(5.0, {FORCE:e}, 0.5, 0.0).damping(0.6)
{sensors}
}});
"#
    )
}

const FORCE: f64 = 1.0e4;

fn read(dir: &Path, kind: &str) -> Vec<u8> {
    std::fs::read(dir.join(format!("out/samples/0000/000000.{kind}"))).unwrap()
}

#[test]
fn a_beams_sensors_are_written_per_rate_with_the_closed_form_values() {
    let dir = tempfile::tempdir().unwrap();
    let sensors = r#"        .sensor(#{ name: "mid", kind: "displacement", at: 5.0, rate: 50.0 })
        .sensor(#{ name: "gauge", kind: "strain_bottom", at: 5.0, rate: 50.0 })
        .sensor(#{ kind: "acceleration", at: 2.5, rate: 200.0 })"#;
    let out = run(dir.path(), &recipe(sensors));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = String::from_utf8(read(dir.path(), "sensors_50hz.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time[s],mid:displacement[m]@5m,gauge:strain_bottom[m/m]@5m"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // 3 s at 50 Hz: t = 0, 0.02, …, 2.98.
    assert_eq!(rows.len(), 150);
    assert_eq!(rows[0], [0.0, 0.0, 0.0]);
    let ei = 210e9 * 0.2 * 0.5f64.powi(3) / 12.0;
    let deflection = FORCE * 1000.0 / (48.0 * ei);
    let strain = FORCE * 10.0 / 4.0 * 0.25 / ei;
    let last = &rows[149];
    assert!((last[1] / deflection - 1.0).abs() < 1e-9, "{}", last[1]);
    assert!((last[2] / strain - 1.0).abs() < 1e-9, "{}", last[2]);

    // The .npy: float64 [150, 3], the same numbers in the same order.
    let npy = read(dir.path(), "sensors_50hz.npy");
    let header_len = u16::from_le_bytes([npy[8], npy[9]]) as usize;
    let header = std::str::from_utf8(&npy[10..10 + header_len]).unwrap();
    assert!(header.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (150, 3), }"));
    let values: Vec<f64> = npy[10 + header_len..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(values, rows.concat());

    // The accelerometer has its own file at its own rate, named by default.
    let fast = String::from_utf8(read(dir.path(), "sensors_200hz.csv")).unwrap();
    assert!(fast.starts_with("time[s],sensor3:acceleration[m/s^2]@2.5m\n"));
    assert_eq!(fast.lines().count(), 1 + 600);
}

#[test]
fn a_bad_sensor_is_refused_at_its_call_with_its_value() {
    for (sensor, expected) in [
        (
            r#"        .sensor(#{ kind: "strain", at: 5.0, rate: 50.0 })"#,
            "\"strain\"",
        ),
        (
            r#"        .sensor(#{ kind: "velocity", at: 12.5, rate: 50.0 })"#,
            "12.5",
        ),
        (
            r#"        .sensor(#{ kind: "velocity", at: 5.0, rate: -2.0 })"#,
            "-2",
        ),
        (
            r#"        .sensor(#{ kind: "velocity", at: 5.0, rate: 5.0, name: "a b" })"#,
            "\"a b\"",
        ),
    ] {
        // The sensor call is on line 7 of the recipe.
        assert_refused(&recipe(sensor), "recipe.rhai:7:", expected);
    }
}

/// `recipe` fails, pointing at `site` and naming `expected`.
fn assert_refused(recipe: &str, site: &str, expected: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = run(dir.path(), recipe);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(site) && stderr.contains(expected),
        "{stderr}"
    );
}

/// A hammer blow at mid-span of the same beam at ζ = 1 %, recorded at mid-span by a
/// displacement sensor at 200 Hz and an accelerometer at 500 Hz for 4 s.
fn hammer_test() -> String {
    let sensors = r#"        .sensor(#{ name: "mid", kind: "displacement", at: 5.0, rate: 200.0 })
        .sensor(#{ name: "acc", kind: "acceleration", at: 5.0, rate: 500.0 })"#;
    recipe(sensors)
        .replace(
            ".ramp(5.0, 1e4, 0.5, 0.0).damping(0.6)",
            ".hammer(5.0, 1e4, 0.1, 0.005).damping(0.01)",
        )
        .replace("duration: 3.0", "duration: 4.0")
}

fn eval(dir: &Path, predictions: &Path) -> (std::process::Output, serde_json::Value) {
    let json = dir.join("report.json");
    let out = Command::new(env!("CARGO_BIN_EXE_shmgen"))
        .arg("eval")
        .arg(dir.join("out"))
        .arg(predictions)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    let report = std::fs::read_to_string(&json)
        .map(|t| serde_json::from_str(&t).unwrap())
        .unwrap_or_default();
    (out, report)
}

#[test]
fn eval_scores_histories_against_the_sensors() {
    let dir = tempfile::tempdir().unwrap();
    assert!(hammer_test().contains(".hammer(5.0, 1e4, 0.1, 0.005).damping(0.01)"));
    let out = run(dir.path(), &hammer_test());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let truth = String::from_utf8(read(dir.path(), "sensors_200hz.csv")).unwrap();
    let predictions = dir.path().join("pred/0000");
    std::fs::create_dir_all(&predictions).unwrap();

    // The truth itself: zero error, and complete only once every history is predicted.
    std::fs::write(predictions.join("000000.sensors_200hz.csv"), &truth).unwrap();
    let (out, report) = eval(dir.path(), &dir.path().join("pred"));
    assert_eq!(
        out.status.code(),
        Some(2),
        "the 500 Hz file has no prediction"
    );
    assert_eq!(report["unscored"][0]["quantity"], "history");
    assert_eq!(
        report["unscored"][0]["first"][0],
        "000000.sensors_500hz.csv"
    );
    let mid = &report["histories"]["files"][0]["sensors"][0];
    assert_eq!(
        (mid["rmse"].as_f64(), mid["peak_error"].as_f64()),
        (Some(0.0), Some(0.0))
    );

    // The beam's first frequency, identified from the truth, against the closed form.
    let ei = 210e9 * 0.2 * 0.5f64.powi(3) / 12.0;
    let mass = 7850.0 * 0.2 * 0.5;
    let f1 = std::f64::consts::PI / (2.0 * 100.0) * (ei / mass).sqrt();
    let identified = mid["frequency_truth"].as_f64().unwrap();
    assert!(
        (identified / f1 - 1.0).abs() < 2e-3,
        "{identified} Hz vs {f1} Hz"
    );

    // An offset of 0.1 mm: RMSE 0.1 mm; the accelerometer's truth as its own prediction.
    let mut lines = truth.lines();
    let mut shifted = format!("{}\n", lines.next().unwrap().split(',').next().unwrap());
    shifted = shifted.replace('\n', ",mid\n");
    for line in lines {
        let (t, v) = line.split_once(',').unwrap();
        shifted += &format!("{t},{}\n", v.parse::<f64>().unwrap() + 1e-4);
    }
    std::fs::write(predictions.join("000000.sensors_200hz.csv"), shifted).unwrap();
    let fast = read(dir.path(), "sensors_500hz.csv");
    std::fs::write(predictions.join("000000.sensors_500hz.csv"), fast).unwrap();
    let (out, report) = eval(dir.path(), &dir.path().join("pred"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mid = &report["histories"]["sensors"][0];
    assert_eq!(mid["sensor"], "mid");
    assert!(
        (mid["rmse"].as_f64().unwrap() - 1e-4).abs() < 1e-12,
        "{mid}"
    );
    assert!(mid["frequency_error"].as_f64().unwrap() < 1e-9);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("histories: 2 files"), "{text}");
}

/// The 10 m chain of 16 steel members 0.1 × 0.2 m of `tests/frames.rs`, pinned and on a
/// roller, its lane over every member, under a step of `FORCE` at mid-span at 0.5 s damped at
/// ζ = 0.6, with the sensors `sensors` (Rhai calls on the frame `f`).
fn frame_recipe(sensors: &str) -> String {
    format!(
        r#"dataset(#{{
    name: "frame sensors", seed: 1, samples: 1, views: 1, outputs: ["mask"],
    camera: #{{ width: 16, height: 16, fov_y: deg(60), distance: "frame" }},
    sequence: #{{ duration: 3.0, fps: 10.0 }},
    scene: |rng| {{
        let f = frame("chain", #{{ plane: "xz" }});
        let s = rectangle(0.1, 0.2);
        let nodes = [];
        for i in 0..17 {{ nodes.push(f.node(10.0 * i / 16.0, 0, 0)); }}
        let lane = [];
        for i in 0..16 {{ lane.push(f.member(nodes[i], nodes[i + 1], s)); }}
        f.support(nodes[0], "pinned");
        f.support(nodes[16], "roller");
        f.lane(lane);
        f.ramp(5.0, {FORCE:e}, 0.5, 0.0);
        f.damping(0.6);
{sensors}
        f
    }}
}});
"#
    )
}

#[test]
fn a_frames_sensors_are_written_with_their_members_and_the_closed_form_values() {
    let dir = tempfile::tempdir().unwrap();
    let sensors = r#"        f.sensor(#{ name: "mid", kind: "displacement", member: 7, at: 0.625, rate: 50.0 });
        f.sensor(#{ name: "gauge", kind: "strain_bottom", member: 8, at: 0.0, rate: 50.0 });
        f.sensor(#{ name: "end", kind: "rotation", member: 0, at: 0.0, rate: 50.0 });
        f.sensor(#{ name: "up", kind: "displacement", member: 7, at: 0.625, rate: 50.0,
            direction: [0.0, 0.0, 1.0] });"#;
    let out = run(dir.path(), &frame_recipe(sensors));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = String::from_utf8(read(dir.path(), "sensors_50hz.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time[s],mid:displacement[m]@member7+0.625m,gauge:strain_bottom[m/m]@member8+0m,\
         end:rotation[rad]@member0+0m,up:displacement[m]@member7+0.625m"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 150);
    assert_eq!(
        rows[0], [0.0; 5],
        "at rest under the self-weight: nothing yet"
    );
    // Settled: PL³/48EI, (PL/4)c/EI, PL²/16EI, and the same deflection measured upward.
    let ei = 210e9 * 0.1 * 0.2f64.powi(3) / 12.0;
    let exact = [
        FORCE * 1000.0 / (48.0 * ei),
        FORCE * 10.0 / 4.0 * 0.1 / ei,
        FORCE * 100.0 / (16.0 * ei),
        -FORCE * 1000.0 / (48.0 * ei),
    ];
    for (got, exact) in rows[149][1..].iter().zip(exact) {
        assert!((got / exact - 1.0).abs() < 1e-6, "{got} vs {exact}");
    }
}

#[test]
fn a_bad_frame_sensor_is_refused_at_its_call_with_its_value() {
    for (sensor, expected) in [
        (
            r#"        f.sensor(#{ kind: "velocity", member: 16, at: 0.1, rate: 50.0 });"#,
            "16",
        ),
        (
            r#"        f.sensor(#{ kind: "velocity", at: 0.1, rate: 50.0 });"#,
            "sensor.member is needed",
        ),
        (
            r#"        f.sensor(#{ kind: "velocity", member: 2, at: 0.7, rate: 50.0 });"#,
            "0.7",
        ),
        (
            r#"        f.sensor(#{ kind: "velocity", member: 2, at: 0.1, rate: 5.0, direction: [0, 0, 2] });"#,
            "direction",
        ),
    ] {
        // The sensor call is on line 17 of the recipe.
        assert_refused(&frame_recipe(sensor), "recipe.rhai:17:", expected);
    }
}
