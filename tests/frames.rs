//! Frames through the CLI: a recipe's frame is analysed, its labels land in the view JSON
//! (valid against the published schema) with the values a hand calculation gives, a recipe
//! error in a frame call points at its file, line and column, a rendered frame lies where the
//! closed-form deformed members put it (to a fraction of a pixel), and `scripts/frames.rhai`
//! gives the same bytes on any thread count, in shards and after a kill.

use std::path::Path;
use std::process::Command;

mod common;

use common::{hashes, load, off_box, ok, read_exr_channels, render, view_path};

fn shmgen() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shmgen"))
}

fn run(dir: &Path, recipe: &str) -> std::process::Output {
    let file = dir.join("recipe.rhai");
    std::fs::write(&file, recipe).unwrap();
    shmgen()
        .arg("run")
        .arg(&file)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap()
}

/// The error a run of `recipe` fails with (the run must fail).
fn refused(recipe: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let out = run(dir.path(), recipe);
    assert!(!out.status.success(), "the run should have failed");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The `analysis` of the first structure in view 0 of sample 0 of `recipe`, run into a
/// temporary folder, its view JSON checked against the published view schema.
fn first_analysis(recipe: &str) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    let out = run(dir.path(), recipe);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = dir.path().join("out/samples/0000/000000_00.json");
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let schema: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/schema/view.schema.json"),
        )
        .unwrap(),
    )
    .unwrap();
    let validator = jsonschema::validator_for(&schema).unwrap();
    assert!(validator.is_valid(&record), "{}", json.display());
    record["scene"]["structures"][0]["analysis"].clone()
}

const TWO_SPANS: &str = r#"
dataset(#{
    name: "two spans", seed: 1, samples: 1, views: 1, outputs: ["rgb", "depth"],
    camera: #{ width: 64, height: 48, fov_y: deg(60), distance: "frame" },
    scene: |rng| {
        let f = frame("girder", #{ plane: "xz", display_scale: 20.0 });
        let a = f.node(0, 0, 0);
        let b = f.node(6.0, 0, 0);
        let c = f.node(12.0, 0, 0);
        let s = i_section(0.15, 0.3, 0.0107, 0.0071);
        f.member_distributed_load(f.member(a, b, s), 1.0e4);
        f.member_distributed_load(f.member(b, c, s), 1.0e4);
        f.support(a, "pinned");
        f.support(b, "roller");
        f.support(c, "roller");
        f
    },
});
"#;

#[test]
fn a_two_span_girder_labels_its_reactions_by_the_three_moment_equation() {
    let analysis = &first_analysis(TWO_SPANS);
    let wl = 1.0e4 * 6.0;
    for (r, want) in analysis["reactions"]
        .as_array()
        .unwrap()
        .iter()
        .zip([3.0, 10.0, 3.0])
    {
        let got = r["force"][2].as_f64().unwrap();
        assert!((got - want / 8.0 * wl).abs() < 1e-9 * wl, "{got}");
    }
    assert_eq!(analysis["physically_plausible"], true);
}

fn warren(panels: i64) -> String {
    format!(
        r#"
import "frame" as frames;
dataset(#{{
    name: "warren", seed: 1, samples: 1, views: 1, outputs: ["rgb"],
    camera: #{{ width: 32, height: 32, fov_y: deg(60), distance: "frame" }},
    scene: |rng| frames::truss("warren", {panels}, 3.0, 2.5, 1.0e5),
}});
"#
    )
}

#[test]
fn the_stdlib_warren_truss_stands_and_its_end_diagonal_carries_the_reaction() {
    // Method of joints at the left support: the end diagonal alone balances the reaction,
    // N = −R / sin θ with sin θ = h / √(h² + p²); the reactions share the n/2 − 1 loads.
    let (p, h, load) = (3.0_f64, 2.5_f64, 1.0e5);
    for panels in [2, 4, 6, 8] {
        let analysis = first_analysis(&warren(panels));
        let reaction = (panels / 2 - 1) as f64 * load / 2.0;
        for r in analysis["reactions"].as_array().unwrap() {
            let got = r["force"][2].as_f64().unwrap();
            assert!(
                (got - reaction).abs() < 1e-9 * load,
                "{panels} panels: {got}"
            );
        }
        let diagonal = analysis["members"][0]["axial_force"].as_f64().unwrap();
        let want = -reaction * (h * h + p * p).sqrt() / h;
        assert!(
            (diagonal - want).abs() < 1e-9 * load,
            "{panels} panels: {diagonal} vs {want}"
        );
    }
}

#[test]
fn a_warren_truss_with_an_odd_number_of_diagonals_is_refused() {
    let err = refused(&warren(5));
    assert!(
        err.contains("even number of diagonals") && err.contains("got 5"),
        "{err}"
    );
}

#[test]
fn a_frame_call_on_a_missing_node_points_at_the_recipe() {
    let recipe = TWO_SPANS.replace("f.support(c, \"roller\");", "f.support(7, \"roller\");");
    let err = refused(&recipe);
    assert!(
        err.contains("recipe.rhai:15:11") && err.contains("node 7 does not exist"),
        "{err}"
    );
}

#[test]
fn a_mechanism_in_a_recipe_is_refused_with_its_dofs_named() {
    let recipe = TWO_SPANS.replace("f.support(a, \"pinned\");", "f.support(a, \"roller\");");
    let err = refused(&recipe);
    assert!(err.contains("mechanism") && err.contains("ux"), "{err}");
}

/// A 6 m steel cantilever (0.1 × 0.2 m, height along z) of eight members vibrating in its
/// first mode, carrying only its own mass.
const CANTILEVER_MODE: &str = r#"
dataset(#{
    name: "cantilever mode", seed: 1, samples: 1, views: 1, outputs: ["rgb", "depth"],
    camera: #{ width: 64, height: 48, fov_y: deg(60), distance: "frame" },
    scene: |rng| {
        let f = frame("cantilever", #{ plane: "xz", mass: "consistent" });
        let s = rectangle(0.1, 0.2);
        let a = f.node(0, 0, 0);
        for i in 1..=8 {
            let b = f.node(0.75 * i, 0, 0);
            f.member(b - 1, b, s);
        }
        f.support(a, "fixed");
        f.vibration([[1, 0.2]]);
        f
    },
});
"#;

#[test]
fn a_frame_vibration_snapshot_labels_its_frequencies_and_draws_its_amplitude() {
    let analysis = &first_analysis(CANTILEVER_MODE);
    assert_eq!(analysis["analysis"], "vibration_snapshot");
    // f₁ = (1.8751)² / (2π L²) √(E I / (ρ A)); eight members err by (β₁L/8)⁴/1440 ≈ 2e-6.
    let (e, rho, l) = (210e9_f64, 7850.0, 6.0);
    let (area, inertia) = (0.1 * 0.2, 0.1 * 0.2f64.powi(3) / 12.0);
    let beta_l = 1.875_104_068_711_961_f64;
    let f1 =
        beta_l.powi(2) / (2.0 * std::f64::consts::PI * l * l) * (e * inertia / (rho * area)).sqrt();
    let modes = &analysis["modes"];
    let got = modes["frequencies"][0].as_f64().unwrap();
    assert!((got / f1 - 1.0).abs() < 1e-5, "{got} vs {f1}");
    assert_eq!(modes["snapshot"][0]["mode"], 1);
    assert_eq!(modes["frequencies"].as_array().unwrap().len(), 6);
    // The tip moves the amplitude (display_scale 1).
    let tip = analysis["nodes"][8]["displacement"][2].as_f64().unwrap();
    assert!((tip - 0.2).abs() < 1e-12, "{tip}");
    assert!((analysis["max_displacement"].as_f64().unwrap() - 0.2).abs() < 1e-12);
}

#[test]
fn a_frame_vibration_with_loads_is_refused_at_the_recipe() {
    let recipe = CANTILEVER_MODE.replace(
        "f.vibration([[1, 0.2]]);",
        "f.node_load(8, [0.0, 0.0, -1.0e3]);\n        f.vibration([[1, 0.2]]);",
    );
    let err = refused(&recipe);
    assert!(
        err.contains("recipe.rhai:15:11")
            && err.contains("either static loads or a vibration snapshot"),
        "{err}"
    );
}

/// `scripts/frames.rhai` run with `sets` and `extra` into `out`.
fn frames_script(out: &Path, sets: &[&str], extra: &[&str]) -> std::process::Output {
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/frames.rhai");
    let mut args: Vec<&str> = Vec::new();
    for s in sets {
        args.extend(["--set", s]);
    }
    args.extend(extra);
    common::run(&recipe, out, &args)
}

#[test]
fn the_frames_script_is_the_same_bytes_on_one_or_two_threads_and_in_shards() {
    let dir = tempfile::tempdir().unwrap();
    let sets = [
        "size=48",
        "samples=6",
        "views=2",
        "outputs=rgb,depth,mask,displacement,mesh",
    ];
    // One thread; two; and two shards (the second on one thread) into one folder.
    let runs: [(&str, &[&str]); 4] = [
        ("t1", &["--threads", "1"]),
        ("t2", &["--threads", "2"]),
        ("sharded", &["--shard", "1/2"]),
        ("sharded", &["--shard", "0/2", "--threads", "1"]),
    ];
    for (folder, extra) in runs {
        ok(frames_script(&dir.path().join(folder), &sets, extra));
    }
    let [one, two, sharded] = ["t1", "t2", "sharded"].map(|f| hashes(&dir.path().join(f)));
    // run.json, manifest, per view rgb, depth, mask, displacement and json, and per sample the
    // deformed and rest meshes.
    assert_eq!(one.len(), 2 + 6 * (2 * 5 + 2));
    assert_eq!(one, two);
    assert_eq!(one, sharded);
}

#[test]
fn a_killed_frames_run_resumes_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    // 16 samples at 640 px: large enough that the kill lands mid-run.
    let samples = 16;
    let count = format!("samples={samples}");
    let sets = ["size=640", count.as_str(), "views=2"];
    ok(frames_script(
        &dir.path().join("clean"),
        &sets,
        &["--threads", "1"],
    ));
    let out = dir.path().join("killed");
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/frames.rhai");
    let mut args: Vec<&str> = sets.iter().flat_map(|s| ["--set", s]).collect();
    args.extend(["--threads", "1"]);
    let child = common::spawn_run(&recipe, &out, &args);
    let done_at_kill = common::kill_after_samples(child, &out, 3);
    assert!(
        (3..samples).contains(&done_at_kill),
        "kill must land mid-run ({done_at_kill} samples done)"
    );
    let resumed = ok(frames_script(&out, &sets, &["--threads", "1"]));
    let text = String::from_utf8_lossy(&resumed.stdout);
    assert!(text.contains("already present"), "{text}");
    assert_eq!(hashes(&dir.path().join("clean")), hashes(&out));
}

/// An L frame in the x–z plane: a column (0, 0, 0)–(0, 0, H) clamped at its base, a rigid
/// knee, a beam (0, 0, H)–(A, 0, H) cantilevering out with a downward force P at its tip; both
/// 0.2 m wide (y) × 0.3 m deep rectangles, drawn `SCALE` times.
const KNEE: (f64, f64, f64) = (3.0, 2.5, 2.0e4);
const SCALE: f64 = 30.0;

fn knee_recipe() -> String {
    let (h, a, p) = KNEE;
    format!(
        r#"dataset(#{{
    name: "knee", seed: 1, samples: 1, views: 2, outputs: ["depth", "mask", "displacement"],
    camera: #{{ width: 320, height: 240, fixed: [
        #{{ position: [1.3, -5.5, 1.2], target: [1.2, 0.0, 1.6] }},
        #{{ position: [3.5, -4.0, 4.5], target: [1.0, 0.0, 2.0] }}] }},
    scene: |rng| {{
        let f = frame("knee", #{{ plane: "xz", display_scale: {SCALE} }});
        let s = rectangle(0.2, 0.3);
        let base = f.node(0, 0, 0);
        let knee = f.node(0, 0, {h});
        let tip = f.node({a}, 0, {h});
        f.member(base, knee, s);
        f.member(knee, tip, s);
        f.support(base, "fixed");
        f.node_load(tip, [0.0, 0.0, -{p}]);
        f
    }},
}});
"#
    )
}

/// Where the closed form draws the rest point `r` of the L frame (sections turned rigidly by
/// the scaled rotation, as docs/frames.md draws them): the column carries the constant moment
/// P A (rotation θ z/H with θ = P A H/(E I), sway θ z²/(2H)) and shortens by P z/(E A); the
/// beam turns with the knee and bends as a cantilever, w = −θ x − P x² (3A − x)/(6 E I).
fn knee_truth(r: [f64; 3]) -> [f64; 3] {
    let (h, a, p) = KNEE;
    let (e, area, inertia) = (210e9, 0.2 * 0.3, 0.2 * 0.3f64.powi(3) / 12.0);
    let theta = p * a * h / (e * inertia);
    let knee = [theta * h / 2.0, -p * h / (e * area)];
    // Axis point, its displacement (x, z) and the rotation about +y (z turns toward x).
    // The column's rest points have |x| ≤ 0.15, the beam's beyond the knee x > 0.15.
    let (axis, [ux, uz], turn) = if r[0] <= 0.15 + 1e-6 {
        let z = r[2].clamp(0.0, h);
        (
            [0.0, 0.0, z],
            [theta * z * z / (2.0 * h), -p * z / (e * area)],
            theta * z / h,
        )
    } else {
        let x = r[0].clamp(0.0, a);
        let own = p * x * x * (3.0 * a - x) / (6.0 * e * inertia);
        (
            [x, 0.0, h],
            [knee[0], knee[1] - theta * x - own],
            theta + p * (2.0 * a * x - x * x) / (2.0 * e * inertia),
        )
    };
    let o = [r[0] - axis[0], r[2] - axis[2]];
    let (sin, cos) = (SCALE * turn).sin_cos();
    let turned = [cos * o[0] + sin * o[1], -sin * o[0] + cos * o[1]];
    [
        SCALE * ux + turned[0] - o[0],
        0.0,
        SCALE * uz + turned[1] - o[1],
    ]
}

#[test]
fn a_rendered_frame_lies_on_its_closed_form_deformed_members_within_the_pixel_tolerance() {
    // Each pixel's point, less its written displacement, is a point of the rest members (two
    // boxes: past the knee each runs as far as the other reaches along it, 0.15 m; past a free
    // end or the base, half its own smaller side, 0.1 m); the closed form carries that rest
    // point to within 0.1 px (the default chord tolerance) of where the pixel sees it. The
    // knee's overlap, where two members share the joint, is left out.
    let (h, a, _) = KNEE;
    let (_dir, out) = render(&knee_recipe(), &[]);
    let (mut worst_px, mut worst_rest, mut checked) = (0.0f64, 0.0f64, 0);
    for view in 0..2 {
        let v = load(&out, view, None);
        let (_, channels) = read_exr_channels(&view_path(&out, 0, view, None, "displacement.exr"));
        for row in 0..v.height {
            for col in 0..v.width {
                let i = row * v.width + col;
                let Some(p) = v.point(row, col) else {
                    continue;
                };
                let d = [&channels["R"], &channels["G"], &channels["B"]].map(|c| f64::from(c[i]));
                let r: [f64; 3] = std::array::from_fn(|k| p[k] - d[k]);
                // The column spans z ∈ [−0.1, h + 0.15], the beam x ∈ [−0.15, a + 0.1].
                let column = off_box(
                    [r[0], r[1], r[2] - (h + 0.05) / 2.0],
                    [0.15, 0.1, (h + 0.25) / 2.0],
                );
                let beam = off_box(
                    [r[0] - (a - 0.05) / 2.0, r[1], r[2] - h],
                    [(a + 0.25) / 2.0, 0.1, 0.15],
                );
                worst_rest = worst_rest.max(column.min(beam));
                if r[0] < 0.2 && r[2] > h - 0.2 {
                    continue;
                }
                let truth = knee_truth(r);
                let want: [f64; 3] = std::array::from_fn(|k| r[k] + truth[k]);
                let (at, _) = v.project(want);
                let (seen, _) = v.project(p);
                worst_px = worst_px.max((at[0] - seen[0]).hypot(at[1] - seen[1]));
                checked += 1;
            }
        }
    }
    assert!(checked > 5000, "{checked} pixels checked");
    assert!(
        worst_rest < 1e-4,
        "a rest point {worst_rest} m off the rest members"
    );
    assert!(worst_px < 0.1, "{worst_px} px off the closed form");
}

/// A 10 m steel chain of 16 members (0.1 × 0.2 m), pinned and on a roller, its lane over
/// every member, crossed by one 10 kN axle at 30 m/s; filmed 0.5 s at 100 fps.
const CROSSED_CHAIN: &str = r#"
dataset(#{
    name: "crossed chain", seed: 1, samples: 1, views: 1, outputs: ["depth"],
    sequence: #{ duration: 0.5, fps: 100.0 },
    camera: #{ width: 48, height: 32, fov_y: deg(60),
        fixed: [#{ position: [5.0, -12.0, 0.0], target: [5.0, 0.0, 0.0] }] },
    scene: |rng| {
        let f = frame("chain", #{ plane: "xz" });
        let s = rectangle(0.1, 0.2);
        let nodes = [];
        for i in 0..17 { nodes.push(f.node(10.0 * i / 16.0, 0, 0)); }
        let lane = [];
        for i in 0..16 { lane.push(f.member(nodes[i], nodes[i + 1], s)); }
        f.support(nodes[0], "pinned");
        f.support(nodes[16], "roller");
        f.lane(lane);
        f.vehicle([[0.0, 1.0e4]], 30.0, 0.0);
        f.damping(0.02);
        f.modes(4);
        f
    },
});
"#;

#[test]
fn a_frame_crossed_by_a_vehicle_deflects_as_the_beams_modal_response_in_every_frame() {
    use shmgen::mechanics::Support;
    use shmgen::mechanics::dynamics::{Axle, ModalBeam, TimeLoad};
    let dir = tempfile::tempdir().unwrap();
    let out = run(dir.path(), CROSSED_CHAIN);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The truth: the beam module's modal solution of the same span (checked against Frýba's
    // series); 16 Hermite members put the frame's four frequencies above the beam's by at most
    // (4π/16)⁴/1440 = 2.6e-4, so mid-span agrees to 5e-4 of the peak.
    let inertia = 0.1 * 0.2f64.powi(3) / 12.0;
    let beam = ModalBeam::new(
        Support::SimplySupported,
        10.0,
        210e9 * inertia,
        7850.0 * 0.02,
        0.02,
        4,
    )
    .unwrap();
    let loads = [TimeLoad::Vehicle {
        axles: vec![Axle {
            behind: 0.0,
            force: 1.0e4,
        }],
        speed: 30.0,
        enters: 0.0,
    }];
    let times: Vec<f64> = (0..50).map(|k| k as f64 / 100.0).collect();
    let response = beam.respond(&loads, 0.0, &times, 64);
    let truth: Vec<f64> = (0..times.len())
        .map(|k| response.at(&beam, &loads, k, 5.0).deflection)
        .collect();
    let peak = truth.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(peak > 1.1 * 1.0e4 * 1000.0 / (48.0 * 210e9 * inertia));
    for (k, expected) in truth.iter().enumerate() {
        let json = dir
            .path()
            .join(format!("out/samples/0000/000000_00_f{k:04}.json"));
        let record: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let analysis = &record["scene"]["structures"][0]["analysis"];
        assert_eq!(analysis["analysis"], "modal_response");
        let sag = -analysis["nodes"][8]["displacement"][2].as_f64().unwrap();
        assert!(
            (sag - expected).abs() < 5e-4 * peak,
            "frame {k}: {sag} m, the beam's modal response {expected} m"
        );
    }
}

#[test]
fn a_frames_time_loads_need_a_connected_lane_declared_first() {
    let without_lane = CROSSED_CHAIN.replace("f.lane(lane);", "");
    assert!(refused(&without_lane).contains("declare it first, f.lane"));
    let broken = CROSSED_CHAIN.replace("f.lane(lane);", "f.lane([lane[0], lane[2]]);");
    let error = refused(&broken);
    assert!(
        error.contains("lane member 2 (position 1 in the lane) does not touch node 1"),
        "{error}"
    );
    assert!(error.contains("recipe.rhai:"), "{error}");
}
