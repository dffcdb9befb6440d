//! Virtual sensors through the CLI: a beam's sensors declared in a recipe are written beside
//! the sample as CSV and `.npy` (one pair per rate) with the values the closed forms give (a
//! step's static deflection PL³/48EI and bottom-fibre strain (PL/4)c/EI), the two files hold
//! the same numbers, and a bad sensor is refused at its file, line and column with its value.

use std::path::Path;
use std::process::Command;

fn run(dir: &Path, recipe: &str) -> std::process::Output {
    let file = dir.join("recipe.rhai");
    std::fs::write(&file, recipe).unwrap();
    Command::new(env!("CARGO_BIN_EXE_shmgen"))
        .arg("run")
        .arg(&file)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap()
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
        let dir = tempfile::tempdir().unwrap();
        let out = run(dir.path(), &recipe(sensor));
        assert!(!out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr);
        // The sensor call is on line 7 of the recipe, its `.sensor` at column 9.
        assert!(
            stderr.contains("recipe.rhai:7:") && stderr.contains(expected),
            "{stderr}"
        );
    }
}
