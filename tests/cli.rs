//! The `shmgen run` command end to end: determinism across threads, shards and kill -9,
//! the files read back through other readers, and every kind of bad input.

use std::path::Path;
use std::process::Command;

mod common;

use common::{BIN, bundled_rhai, hashes, off_box, ok, read_exr, read_json, run, write};

/// A small recipe (low resolution so the suite stays fast) importing the stdlib beam module.
const SMALL: &str = r#"
import "beam" as beam;
let samples = param("samples", 8);
dataset(#{
    name: "small",
    seed: param("seed", 0),
    samples: samples,
    views: param("views", 3),
    outputs: if param("ground_truth", false) {
        ["rgb", "depth", "mask", "normals", "displacement", "flow", "rest_rgb", "rest_depth", "ray_distance", "mesh", "mesh_gltf", "points"]
    } else { ["rgb", "depth", "mask"] },
    points: 500,
    camera: #{ width: param("width", 96), height: param("height", 72), pitch: [deg(-60), deg(90)] },
    scene: |rng| {
        let length = rng.uniform(1.0, 4.0);
        let b = beam::paper_cuboid(length, rng.uniform(0.02, 0.25), rng.uniform(0.05, 1.5));
        if rng.chance(0.5) { b.cantilever(); }
        b.point_load(rng.uniform(0.0, 1.0) * length, rng.uniform(0.0, 0.08) * length);
        b
    },
});
"#;

/// Every module of `stdlib/` imports with no standard-library folder to read
/// (`SHMGEN_STDLIB` naming none): the binary holds them all. And it holds them as they are:
/// the recipe hash in run.json, over the name and text of every file the recipe used, is the
/// one the folder's module gives.
#[test]
fn every_stdlib_module_imports_from_the_built_in_library() {
    let stdlib = Path::new(env!("CARGO_MANIFEST_DIR")).join("stdlib");
    let modules: Vec<String> = bundled_rhai("stdlib")
        .iter()
        .map(|path| path.file_stem().unwrap().to_str().unwrap().to_string())
        .collect();
    assert!(modules.contains(&"bridge".to_string()), "{modules:?}");
    let dir = tempfile::tempdir().unwrap();
    let nowhere = dir.path().join("no stdlib here");
    for module in &modules {
        let recipe = write(
            dir.path(),
            &format!("{module}_user.rhai"),
            format!(
                "import \"{module}\" as m;\ndataset(#{{ name: \"x\", samples: 1, views: 1, camera: #{{ width: 16, height: 16 }}, scene: |rng| beam(#{{ length: 2.0, width: 0.2, height: 0.3 }}) }});\n"
            ),
        );
        let hash = |library: &Path, out: &str| {
            let out = dir.path().join(format!("{module}_{out}"));
            let output = Command::new(BIN)
                .arg("run")
                .arg(&recipe)
                .arg("--out")
                .arg(&out)
                .arg("--quiet")
                .env("SHMGEN_STDLIB", library)
                .output()
                .unwrap();
            assert!(
                output.status.success(),
                "import \"{module}\" with SHMGEN_STDLIB={}: {}",
                library.display(),
                String::from_utf8_lossy(&output.stderr)
            );
            read_json(&out.join("run.json"))["recipe"]["hash"].clone()
        };
        let built_in = hash(&nowhere, "built_in");
        assert!(built_in.is_string(), "{built_in}");
        assert_eq!(built_in, hash(&stdlib, "folder"), "module \"{module}\"");
    }
}

#[test]
fn same_bytes_with_one_or_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(dir.path(), "small.rhai", SMALL);
    ok(run(&recipe, &dir.path().join("t1"), &["--threads", "1"]));
    ok(run(&recipe, &dir.path().join("t2"), &["--threads", "2"]));
    let (a, b) = (
        hashes(&dir.path().join("t1")),
        hashes(&dir.path().join("t2")),
    );
    assert_eq!(
        a.len(),
        2 + 8 * 3 * 4,
        "run.json, manifest and 4 files per view"
    );
    assert_eq!(a, b);
}

#[test]
fn ground_truth_outputs_have_the_same_bytes_with_one_or_two_threads_and_in_shards() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(dir.path(), "small.rhai", SMALL);
    let gt = ["--set", "ground_truth=true", "--set", "samples=5"];
    ok(run(
        &recipe,
        &dir.path().join("t1"),
        &[&gt[..], &["--threads", "1"]].concat(),
    ));
    ok(run(
        &recipe,
        &dir.path().join("t2"),
        &[&gt[..], &["--threads", "2"]].concat(),
    ));
    let sharded = dir.path().join("sharded");
    ok(run(
        &recipe,
        &sharded,
        &[&gt[..], &["--shard", "1/2"]].concat(),
    ));
    ok(run(
        &recipe,
        &sharded,
        &[&gt[..], &["--shard", "0/2", "--threads", "1"]].concat(),
    ));
    let one = hashes(&dir.path().join("t1"));
    // run.json, manifest, 11 files per view (json included) and 4 per sample.
    assert_eq!(one.len(), 2 + 5 * (3 * 11 + 4));
    assert_eq!(one, hashes(&dir.path().join("t2")));
    assert_eq!(one, hashes(&sharded));
}

#[test]
fn shards_merge_into_the_same_bytes_as_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(dir.path(), "small.rhai", SMALL);
    ok(run(&recipe, &dir.path().join("whole"), &[]));
    let sharded = dir.path().join("sharded");
    let first = ok(run(&recipe, &sharded, &["--shard", "1/2"]));
    assert!(String::from_utf8_lossy(&first.stdout).contains("incomplete"));
    ok(run(
        &recipe,
        &sharded,
        &["--shard", "0/2", "--threads", "1"],
    ));
    assert_eq!(hashes(&dir.path().join("whole")), hashes(&sharded));
}

#[test]
fn killed_run_resumes_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(dir.path(), "small.rhai", SMALL);
    let args = [
        "--set",
        "samples=40",
        "--set",
        "width=320",
        "--set",
        "height=240",
        "--threads",
        "1",
    ];
    ok(run(&recipe, &dir.path().join("clean"), &args));
    let out = dir.path().join("killed");
    let child = common::spawn_run(&recipe, &out, &args);
    let done_at_kill = common::kill_after_samples(child, &out, 3);
    assert!(
        (3..40).contains(&done_at_kill),
        "kill must land mid-run ({done_at_kill} samples done)"
    );
    let resumed = ok(run(&recipe, &out, &args));
    let text = String::from_utf8_lossy(&resumed.stdout);
    assert!(text.contains("already present"), "{text}");
    assert_eq!(hashes(&dir.path().join("clean")), hashes(&out));
}

/// The files of a dataset read back through independent readers: EXR via the exr crate,
/// PNG via the png crate, cameras via the JSON. An unloaded beam is an exact box, so every
/// back-projected depth pixel must lie on the box surface.
#[test]
fn written_files_round_trip_through_other_readers() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(
        dir.path(),
        "box.rhai",
        r#"dataset(#{
            seed: 3, samples: 1, views: 3,
            camera: #{ width: 200, height: 150, distance: [6.0, 9.0] },
            scene: |rng| beam(#{ length: 3.0, width: 0.4, height: 0.8 }).at(10.0, -20.0, 5.0),
        })"#,
    );
    let out = dir.path().join("ds");
    ok(run(&recipe, &out, &[]));
    for view in 0..3 {
        let meta: serde_json::Value =
            read_json(&out.join(format!("samples/0000/000000_{view:02}.json")));
        let m = |key: &str| -> Vec<Vec<f64>> {
            serde_json::from_value(meta["camera"][key].clone()).unwrap()
        };
        let (k, c2w, w2c, gl) = (m("K"), m("c2w_opencv"), m("w2c_opencv"), m("c2w_opengl"));
        assert_eq!(meta["camera"]["pixel_center"], 0.5);
        assert_eq!((k[0][2], k[1][2]), (100.0, 75.0));
        // OpenGL axes: the same pose with y and z columns negated.
        for r in 0..3 {
            assert_eq!(gl[r][0], c2w[r][0]);
            assert_eq!(
                (gl[r][1], gl[r][2], gl[r][3]),
                (-c2w[r][1], -c2w[r][2], c2w[r][3])
            );
        }
        // w2c · c2w = I.
        #[expect(
            clippy::needless_range_loop,
            reason = "r, c and i are the indices of a matrix product, spelled as in its formula"
        )]
        for r in 0..4 {
            for c in 0..4 {
                let v: f64 = (0..4).map(|i| w2c[r][i] * c2w[i][c]).sum();
                assert!((v - f64::from(u8::from(r == c))).abs() < 1e-9);
            }
        }
        let depth = read_exr(&out.join(format!("samples/0000/000000_{view:02}.depth.exr")));
        let mask = read_png(&out.join(format!("samples/0000/000000_{view:02}.mask.png")));
        assert_eq!(depth.len(), 200 * 150);
        let mut hits = 0;
        for (i, &z) in depth.iter().enumerate() {
            assert!(z.is_finite() && z >= 0.0);
            assert_eq!(mask[i] == 255, z > 0.0, "mask and depth agree");
            if z == 0.0 {
                continue;
            }
            hits += 1;
            let (row, col) = ((i / 200) as f64, (i % 200) as f64);
            let z = f64::from(z);
            let cam = [
                (col + 0.5 - k[0][2]) * z / k[0][0],
                (row + 0.5 - k[1][2]) * z / k[1][1],
                z,
            ];
            let p: Vec<f64> = (0..3)
                .map(|r| c2w[r][0] * cam[0] + c2w[r][1] * cam[1] + c2w[r][2] * cam[2] + c2w[r][3])
                .collect();
            let local = [p[0] - 10.0, p[1] + 20.0, p[2] - 5.0];
            let half = [1.5, 0.2, 0.4];
            let off = off_box(local, half);
            assert!(off < 1e-5 * 3.2, "pixel {i}: {off} m off the box");
        }
        assert!(hits > 100, "{hits} hits");
    }
}

fn read_png(path: &Path) -> Vec<u8> {
    common::read_png(path).3
}

/// Runs a bad recipe; it must fail with a message containing every `expected` fragment and
/// leave no output folder behind.
fn rejects(recipe_text: &str, extra: &[&str], expected: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(dir.path(), "bad.rhai", recipe_text);
    let out = dir.path().join("out");
    let output = run(&recipe, &out, extra);
    let stderr =
        String::from_utf8_lossy(&output.stderr).replace(&dir.path().display().to_string(), "<dir>");
    assert!(!output.status.success(), "must fail:\n{stderr}");
    for fragment in expected {
        assert!(
            stderr.contains(fragment),
            "expected `{fragment}` in:\n{stderr}"
        );
    }
    assert!(!out.exists(), "no partial files may be written");
}

fn with_scene(scene_body: &str) -> String {
    format!("dataset(#{{\n    samples: 20,\n    scene: |rng| {{\n{scene_body}\n    }},\n}})\n")
}

#[test]
fn parameters_read_inside_the_scene_follow_set() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(
        dir.path(),
        "p.rhai",
        r#"dataset(#{ samples: 1, camera: #{ width: 32, height: 24 },
            scene: |rng| beam(#{ length: param("span", 2.0), width: 0.1, height: 0.2 }) })"#,
    );
    let out = dir.path().join("ds");
    ok(run(&recipe, &out, &["--set", "span=3.5"]));
    let meta: serde_json::Value = read_json(&out.join("samples/0000/000000_00.json"));
    assert_eq!(meta["scene"]["structures"][0]["length"], 3.5);
}

/// Every section, support and load kind through a recipe, read back from the JSON.
#[test]
fn beam_api_reaches_the_labels() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(
        dir.path(),
        "api.rhai",
        r#"
        import "beam" as beam;
        dataset(#{ samples: 5, camera: #{ width: 64, height: 48 }, scene: |rng| {
            let k = rng.sample;
            if k == 0 { beam::steel_i(6.0, 0.15, 0.3, 0.0107, 0.0071).fixed_fixed().distributed_load(20000.0) }
            else if k == 1 { beam::steel_tube(4.0, 0.3, 0.01).propped_cantilever().point_force(2.0, 5000.0).end_moments(0.0, 1000.0) }
            else if k == 2 { beam(#{ length: 1.0, section: hollow_box(0.4, 0.5, 0.02) }).cantilever().point_force(1.0, 1.0).target_deflection_at(0.5, 0.01).theory("euler_bernoulli") }
            else if k == 3 { beam(#{ length: 3.0, width: 0.1, height: 0.2 }).cantilever().vibration([[1, 0.05], [4, 0.01]]) }
            else { beam(#{ length: 2.0, width: 0.05, height: 0.05, axial: "restrained" }).distributed_load(1.0).target_deflection(0.05) }
        } })"#,
    );
    let out = dir.path().join("ds");
    ok(run(&recipe, &out, &[]));
    let meta = |s: u64| -> serde_json::Value {
        read_json(&out.join(format!("samples/0000/{s:06}_00.json")))
    };
    // Fixed–fixed UDL on an I-beam: Timoshenko, δ = qL⁴/(384 EI)·(1 + 4Φ), Φ = 12EI/(κGAL²)
    // (docs/mechanics.md §4.3), with E = 210 GPa, ν = 0.3 and the section's A, I, κ from the JSON.
    let s0 = &meta(0)["scene"]["structures"][0];
    let p = |k: &str| s0["section_properties"][k].as_f64().unwrap();
    let (e, g) = (210e9, 210e9 / 2.6);
    let phi = 12.0 * e * p("second_moment") / (p("shear_coefficient") * g * p("area") * 36.0);
    let want = 20000.0 * 6f64.powi(4) / (384.0 * e * p("second_moment")) * (1.0 + 4.0 * phi);
    let got = s0["labels"]["max_deflection"].as_f64().unwrap();
    assert_eq!(s0["labels"]["theory"], "timoshenko");
    assert!(
        (got / want - 1.0).abs() < 1e-9,
        "fixed–fixed UDL {got} vs {want}"
    );
    assert_eq!(s0["section"]["shape"], "i_section");
    // Two clamps hold the axis unless told otherwise: the spec leaves `axial` out, the labels
    // say what applied, with the tension (EA/2L)∫v′² the stretched axis carries.
    assert!(s0.get("axial").is_none());
    assert_eq!(s0["labels"]["axial"], "restrained");
    let force = s0["labels"]["membrane_force"].as_f64().unwrap();
    let stress = s0["labels"]["membrane_stress"].as_f64().unwrap();
    assert!(force > 0.0 && (stress * p("area") / force - 1.0).abs() < 1e-12);
    assert!(s0["labels"]["membrane_error"].as_f64().unwrap() < 0.01);
    // Immovable pins asked for in the beam's options, δ = h: von Kármán.
    let s4 = &meta(4)["scene"]["structures"][0];
    assert_eq!(s4["axial"], "restrained");
    assert_eq!(s4["labels"]["theory"], "von_karman");
    assert_eq!(s4["labels"]["membrane_error"], 0.0);
    assert!((s4["labels"]["max_deflection"].as_f64().unwrap() - 0.05).abs() < 1e-12);
    assert_eq!(
        meta(1)["scene"]["structures"][0]["support"],
        "propped_cantilever"
    );
    let s2 = &meta(2)["scene"]["structures"][0]["labels"];
    assert_eq!(s2["theory"], "euler_bernoulli");
    let s3 = &meta(3)["scene"]["structures"][0]["labels"];
    assert_eq!(s3["modes"].as_array().unwrap().len(), 2);
    // Cantilever modes peak at the tip with |φ_n(1)| = 1, so the snapshot's peak lies between
    // |0.05 − 0.01| and 0.05 + 0.01.
    let peak = s3["max_deflection"].as_f64().unwrap().abs();
    assert!((0.04 - 1e-12..=0.06 + 1e-12).contains(&peak), "{peak}");
}

/// Deformations beyond what a theory represents, and axial conditions the supports or theory
/// cannot have, are errors at the recipe line that declared them.
#[test]
fn out_of_range_beams_are_named_at_their_line() {
    let beam = "        beam(#{ length: 2.0, width: 0.2, height: 0.3 })";
    rejects(
        &with_scene(&format!("{beam}.end_moments(1e28, 0.0)")),
        &[],
        &[
            "structure 0: euler_bernoulli theory cannot represent this deflection",
            "slope of the axis |dv/dx| = 7.05e19 at x = 0 m exceeds 0.5",
            "<dir>/bad.rhai:4:",
        ],
    );
    rejects(
        &with_scene(&format!(
            "{beam}.point_force(1.0, 1.0).target_deflection_at(1e-12, 1e-3)"
        )),
        &[],
        &[
            "exceeds 0.5",
            "reduce the target deflection",
            "<dir>/bad.rhai:4:",
        ],
    );
    rejects(
        &with_scene(&format!(
            "{beam}.vibration([[1, 0.3], [5, 0.3], [20, 0.3]])"
        )),
        &[],
        &["slope of the axis", "reduce the mode amplitudes"],
    );
    rejects(
        &with_scene(&format!(
            "{beam}.cantilever().axial(\"restrained\").point_force(2.0, 1.0)"
        )),
        &[],
        &[
            "a cantilever's free end cannot hold the axis",
            "<dir>/bad.rhai:4:",
        ],
    );
    rejects(
        &with_scene(&format!(
            "{beam}.fixed_fixed().axial(\"free\").theory(\"von_karman\")"
        )),
        &[],
        &["needs an axially restrained beam"],
    );
    rejects(
        &with_scene(&format!("{beam}.axial(\"stuck\")")),
        &[],
        &["axial = \"stuck\" is unknown"],
    );
}

#[test]
fn bad_sections_and_loads_are_named() {
    rejects(
        &with_scene("        beam(#{ length: 2.0, section: tube(0.2, 0.15) })"),
        &[],
        &[
            "section wall = 0.15 m must be less than the radius",
            "<dir>/bad.rhai:4:",
        ],
    );
    rejects(
        &with_scene(
            "        beam(#{ length: 2.0, width: 0.1, height: 0.2 }).distributed_load(1.5, 0.5, 100.0)",
        ),
        &[],
        &["distributed_load from = 1.5 m must be less than to = 0.5 m"],
    );
    rejects(
        &with_scene(
            "        beam(#{ length: 2.0, width: 0.1, height: 0.2 }).point_load(0.0, 0.01)",
        ),
        &[],
        &[
            "target deflection 0.01 m cannot be reached: the loads do not deflect the beam anywhere (is every load on a support?)",
        ],
    );
    // Asked for where the loads leave the beam still: said there, not "nowhere at x = 0 m".
    rejects(
        &with_scene(
            "        beam(#{ length: 2.0, width: 0.1, height: 0.2 }).point_force(1.0, 100.0).target_deflection_at(0.0, 0.01)",
        ),
        &[],
        &[
            "target deflection 0.01 m at x = 0 m cannot be reached: the loads do not deflect the beam there (is x = 0 m a support",
        ],
    );
    rejects(
        &with_scene(
            "        beam(#{ length: 2.0, width: 0.1, height: 0.2 }).vibration([[0, 0.01]])",
        ),
        &[],
        &["mode 0 must be a whole number from 1"],
    );
}

/// A structure the standard library does not have, written as a Rhai module next to the
/// recipe, renders with no Rust change; its part labels reach the segmentation images.
#[test]
fn a_user_written_structure_module_renders_with_parts_and_instances() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "lamp_post.rhai",
        r#"
        /// A street lamp: a 6 m steel pole on a square footing, a bent arm and a lamp head.
        fn lamp_post(height) {
            let footing = shape::box(0.6, 0.6, 0.4).translate(0.0, 0.0, 0.2).part("footing");
            let pole = shape::frustum(0.09, 0.06, height).translate(0.0, 0.0, 0.4).part("pole");
            let arm = shape::bend([[-0.03, -0.03], [0.03, -0.03], [0.03, 0.03], [-0.03, 0.03]], 0.8, PI() / 2.0)
                .translate(0.0, 0.0, 0.4 + height).part("arm");
            let head = shape::cap(0.3, 0.15).rotate_x(PI()).translate(0.8, 0.0, 0.4 + height + 0.8).part("head");
            assembly("lamp post", [footing, pole, arm, head]).colour([0.3, 0.32, 0.35])
        }
        "#,
    );
    let recipe = write(
        dir.path(),
        "street.rhai",
        r#"
        import "lamp_post" as lamps;
        dataset(#{ samples: 2, views: 2, outputs: ["rgb", "depth", "mask", "parts", "instances"],
            camera: #{ width: 160, height: 240, pitch: [0.0, 0.3] },
            scene: |rng| [lamps::lamp_post(6.0), lamps::lamp_post(4.0).translate(3.0, 0.0, 0.0)] })
        "#,
    );
    let out = dir.path().join("ds");
    ok(run(&recipe, &out, &[]));
    for view in ["000000_00", "000001_01"] {
        let meta: serde_json::Value = read_json(&out.join(format!("samples/0000/{view}.json")));
        let parts: Vec<String> =
            serde_json::from_value(meta["segmentation"]["part_ids"].clone()).unwrap();
        assert_eq!(parts, ["background", "footing", "pole", "arm", "head"]);
        assert_eq!(meta["segmentation"]["instance_ids"][2]["name"], "lamp post");
        let depth = read_exr(&out.join(format!("samples/0000/{view}.depth.exr")));
        let part = read_png(&out.join(format!("samples/0000/{view}.parts.png")));
        let instance = read_png(&out.join(format!("samples/0000/{view}.instances.png")));
        let m = |key: &str| -> Vec<Vec<f64>> {
            serde_json::from_value(meta["camera"][key].clone()).unwrap()
        };
        let (k, c2w) = (m("K"), m("c2w_opencv"));
        let mut seen = std::collections::BTreeSet::new();
        for (i, &z) in depth.iter().enumerate() {
            assert_eq!(z > 0.0, part[i] != 0);
            assert_eq!(z > 0.0, instance[i] != 0);
            if z == 0.0 {
                continue;
            }
            seen.insert((part[i], instance[i]));
            // Height of the surface point: the footing lies below 0.4 m, the pole and head above.
            let (row, col) = ((i / 160) as f64, (i % 160) as f64);
            let z = f64::from(z);
            let cam = [
                (col + 0.5 - k[0][2]) * z / k[0][0],
                (row + 0.5 - k[1][2]) * z / k[1][1],
                z,
            ];
            let height = c2w[2][0] * cam[0] + c2w[2][1] * cam[1] + c2w[2][2] * cam[2] + c2w[2][3];
            match parts[part[i] as usize].as_str() {
                "footing" => assert!(height < 0.4 + 1e-6, "footing pixel at {height} m"),
                "pole" => assert!(height > 0.4 - 1e-6, "pole pixel at {height} m"),
                "head" => assert!(height > 4.4 + 0.8 - 0.16, "head pixel at {height} m"),
                _ => {}
            }
        }
        assert!(
            seen.iter().any(|&(_, inst)| inst == 1) && seen.iter().any(|&(_, inst)| inst == 2),
            "{seen:?}"
        );
        assert!(seen.iter().any(|&(p, _)| p == 2), "the poles are visible");
    }
}

#[test]
fn stdlib_structures_render_with_their_parts() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(
        dir.path(),
        "structures.rhai",
        r#"
        import "portal_frame" as portal;
        import "column" as column;
        dataset(#{ samples: 1, views: 1, outputs: ["depth", "parts"], camera: #{ width: 200, height: 150, pitch: [0.3, 0.3], yaw: [-1.3, -1.3] },
            scene: |rng| [portal::steel(12.0, 5.0), column::circular(0.5, 4.0).translate(0.0, -4.0, 0.0)] })
        "#,
    );
    let out = dir.path().join("ds");
    ok(run(&recipe, &out, &[]));
    let meta: serde_json::Value = read_json(&out.join("samples/0000/000000_00.json"));
    let parts: Vec<String> =
        serde_json::from_value(meta["segmentation"]["part_ids"].clone()).unwrap();
    for expected in [
        "columns",
        "base plates",
        "haunches",
        "girder",
        "footing",
        "shaft",
        "capital",
    ] {
        assert!(
            parts.iter().any(|p| p == expected),
            "{expected} missing from {parts:?}"
        );
    }
    let seen: std::collections::BTreeSet<u8> =
        read_png(&out.join("samples/0000/000000_00.parts.png"))
            .into_iter()
            .collect();
    let index = |name: &str| parts.iter().position(|p| p == name).unwrap() as u8;
    assert!(
        seen.contains(&index("girder"))
            && seen.contains(&index("columns"))
            && seen.contains(&index("shaft")),
        "{seen:?}"
    );
}

#[test]
fn imported_meshes_render_and_broken_files_are_reported_at_the_call() {
    let dir = tempfile::tempdir().unwrap();
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    std::fs::create_dir(dir.path().join("models")).unwrap();
    for f in ["tetra.obj", "tetra.glb", "face_out_of_range.obj"] {
        std::fs::copy(corpus.join(f), dir.path().join("models").join(f)).unwrap();
    }
    let recipe = write(
        dir.path(),
        "imported.rhai",
        r#"dataset(#{ samples: 1, views: 2, camera: #{ width: 64, height: 48 },
            scene: |rng| [assembly("tetra", [shape::mesh("models/tetra.obj", #{ normalize: true }).scale(2.0)]),
                          assembly("glb", [shape::mesh("models/tetra.glb").translate(3.0, 0.0, 0.0)]),
                          assembly("pier", [shape::mesh("models/tetra.obj")
                              .deform_as_beam("z", "x", beam(#{ length: 1.0, width: 1.0, height: 1.0 }).cantilever().point_load(1.0, 0.2))
                              .scale(1.0, 1.0, 4.0)])] })"#,
    );
    let out = dir.path().join("ds");
    ok(run(&recipe, &out, &[]));
    let meta: serde_json::Value = read_json(&out.join("samples/0000/000000_00.json"));
    assert_eq!(
        meta["scene"]["structures"][0]["shapes"][0]["primitive"]["file"],
        "models/tetra.obj"
    );
    assert!(meta["coverage"].as_f64().unwrap() > 0.0);
    assert_eq!(
        meta["scene"]["structures"][2]["shapes"][0]["bending"]["towards"],
        serde_json::json!([1.0, 0.0, 0.0])
    );

    let bad = write(
        dir.path(),
        "bad.rhai",
        "dataset(#{ scene: |rng| assembly(\"x\", [\n    shape::mesh(\"models/face_out_of_range.obj\")]) })\n",
    );
    let output = run(&bad, &dir.path().join("out"), &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains("bad.rhai:2:")
            && stderr.contains("face_out_of_range.obj")
            && stderr.contains("out of range"),
        "{stderr}"
    );
    let escape = write(
        dir.path(),
        "escape.rhai",
        "dataset(#{ scene: |rng| assembly(\"x\", [shape::mesh(\"../secret.obj\")]) })\n",
    );
    let stderr =
        String::from_utf8_lossy(&run(&escape, &dir.path().join("out2"), &[]).stderr).to_string();
    assert!(stderr.contains("without '..'"), "{stderr}");
}

#[test]
fn the_a2_silo_recipe_records_damage_and_its_plausible_size() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/a2_silo.rhai");
    let out = dir.path().join("a2");
    ok(run(
        &recipe,
        &out,
        &[
            "--set",
            "samples=3",
            "--set",
            "views=1",
            "--set",
            "damage=1.0",
        ],
    ));
    for s in 0..3 {
        let meta = read_json(&out.join(format!("samples/0000/{s:06}_00.json")));
        let parts: Vec<String> =
            serde_json::from_value(meta["segmentation"]["part_ids"].clone()).unwrap();
        assert_eq!(
            parts,
            [
                "background",
                "shell",
                "roof",
                "hopper",
                "ring beams",
                "legs",
                "bracing"
            ]
        );
        let shell = &meta["scene"]["structures"][0]["shapes"][0]["shell"][0];
        let (drawn, plausible) = (
            shell["amplitude"].as_f64().unwrap(),
            shell["plausible_amplitude"].as_f64().unwrap(),
        );
        assert!((0.02..=0.15).contains(&drawn), "{shell}");
        assert!(
            plausible > 0.0 && plausible < 0.02,
            "real loads give millimetres: {shell}"
        );
    }
    // Parity with the paper's silo mesh (26,260 vertices, 18,200 mostly quad faces): within
    // 20 % in vertices and in quad-equivalent faces (our triangles / 2).
    let paper = dir.path().join("a2-paper");
    ok(run(
        &recipe,
        &paper,
        &[
            "--set",
            "samples=1",
            "--set",
            "views=1",
            "--set",
            "paper_mesh=true",
        ],
    ));
    let mesh = &read_json(&paper.join("samples/0000/000000_00.json"))["mesh"];
    let (v, t) = (
        mesh["vertices"].as_f64().unwrap(),
        mesh["triangles"].as_f64().unwrap(),
    );
    assert!(
        (v / 26_260.0 - 1.0).abs() < 0.2 && (t / 2.0 / 18_200.0 - 1.0).abs() < 0.2,
        "{v} vertices, {t} triangles"
    );
    rejects(
        "dataset(#{ scene: |rng| assembly(\"x\", [shape::box(1.0, 1.0, 1.0).ovalise(0.1, 2, 0.0)]) })",
        &[],
        &["shell patterns apply to tubes", "<dir>/bad.rhai:1:"],
    );
}

#[test]
fn syntax_error_points_at_file_line_column() {
    rejects(
        "let x = 3;\nlet y = (x + ;\n",
        &[],
        &["<dir>/bad.rhai:2:", "let y = (x + ;", "^"],
    );
}

#[test]
fn runtime_error_inside_the_scene_points_at_its_line() {
    rejects(
        &with_scene("        let a = [1, 2];\n        a[7]"),
        &[],
        &[
            "Array index 7 out of bounds",
            "<dir>/bad.rhai:5:11",
            "sample 0",
        ],
    );
}

#[test]
fn endless_loop_is_stopped() {
    rejects(
        "let i = 0;\nloop { i += 1; }\n",
        &[],
        &["endless loop", "<dir>/bad.rhai:2:"],
    );
}

#[test]
fn negative_width_is_named_with_its_value() {
    rejects(
        &with_scene("        beam(#{ length: 2.0, width: -0.1, height: 0.3 })"),
        &[],
        &["beam.width = -0.1 must be positive", "<dir>/bad.rhai:4:"],
    );
}

#[test]
fn load_outside_the_span_is_refused() {
    rejects(
        &with_scene(
            "        beam(#{ length: 2.0, width: 0.1, height: 0.3 }).cantilever().point_load(2.5, 0.01)",
        ),
        &[],
        &[
            "point_load position = 2.5 m lies outside the span [0, 2] m",
            "<dir>/bad.rhai:4:",
        ],
    );
}

#[test]
fn nan_is_refused() {
    rejects(
        &with_scene("        beam(#{ length: 2.0, width: 0.1, height: (-1.0).sqrt() })"),
        &[],
        &[
            "beam.height = NaN is not a finite number",
            "<dir>/bad.rhai:4:",
        ],
    );
}

#[test]
fn unknown_options_are_refused_with_a_suggestion() {
    rejects(
        SMALL,
        &["--set", "sampels=3"],
        &["--set sampels=3", "did you mean `samples`?"],
    );
    rejects(
        "dataset(#{ camera: #{ pich: 0.3 }, scene: |rng| beam(#{ length: 1.0, width: 0.1, height: 0.1 }) })",
        &[],
        &[
            "unknown option `dataset.camera.pich`; did you mean `pitch`?",
            "<dir>/bad.rhai:1:",
        ],
    );
    rejects(
        SMALL,
        &["--set", "samples=many"],
        &["--set samples=many: expected a whole number"],
    );
}

/// What an error shown at the first `token` of `text` (a recipe saved as `bad.rhai`) prints:
/// its place `<dir>/bad.rhai:line:col`, the source line, and the caret under the token.
fn shown_at(text: &str, token: &str) -> [String; 3] {
    let (line, col, source) = text
        .lines()
        .enumerate()
        .find_map(|(i, l)| l.find(token).map(|c| (i + 1, c + 1, l)))
        .unwrap_or_else(|| panic!("`{token}` is not in the recipe"));
    let gutter = line.to_string().len();
    [
        format!("<dir>/bad.rhai:{line}:{col}\n"),
        format!("{line} | {source}\n"),
        format!("{:gutter$} | {:>col$}\n", "", "^"),
    ]
}

/// A recipe whose dataset map holds `options` (and a small camera unless they set one) and
/// whose scene is `scene`.
fn dataset_with(options: &str, scene: &str) -> String {
    let camera = match options.contains("camera:") {
        true => "",
        false => "    camera: #{ width: 32, height: 24 },\n",
    };
    format!("dataset(#{{\n    samples: 2,\n{camera}{options}\n    scene: |rng| {scene},\n}})\n")
}

const A_BEAM: &str = "beam(#{ length: 1.0, width: 0.1, height: 0.1 })";

/// Every option map the API checks for unknown keys shows a misspelt key at the key itself:
/// nested maps, list items, quoted keys, the scene's calls and methods, a map built in a
/// variable, and the right one of two keys spelt alike.
#[test]
fn an_unknown_option_is_shown_at_its_key() {
    let shape = |call: &str| format!("assembly(\"a\", [{call}])");
    let cases: Vec<(String, &str)> = vec![
        (dataset_with("    sampels: 3,", A_BEAM), "sampels"),
        (
            dataset_with("    light: #{ sun: #{ elevaton: 0.5 } },", A_BEAM),
            "elevaton",
        ),
        (
            dataset_with(
                "    background: #{ sky: #{ \"zenit\": [0.1, 0.2, 0.3] } },",
                A_BEAM,
            ),
            "\"zenit\"",
        ),
        (
            dataset_with("    ground: #{ materal: \"grass\" },", A_BEAM),
            "materal",
        ),
        (
            dataset_with(
                "    augment: #{ operations: [\n        #{ op: \"gamma\", gamma: 1.1, probability: 1.0 },\n        #{ op: \"gamma\", gamma: 1.1, probability: 1.0, probabilty: 0.5 },\n    ] },",
                A_BEAM,
            ),
            "probabilty",
        ),
        (
            dataset_with(
                "    views: 2,\n    camera: #{ fixed: [#{ position: [3.0, 0.0, 1.0] }, #{ position: [0.0, 3.0, 1.0], rol: 0.1 }] },",
                A_BEAM,
            ),
            "rol",
        ),
        // The light's misspelt key comes first in the text, but the background is read first.
        (
            dataset_with(
                "    light: #{ sun: #{ colr: [1.0, 1.0, 1.0] } },\n    background: #{ sky: #{ colr: [0.1, 0.2, 0.3] } },",
                A_BEAM,
            ),
            "colr: [0.1",
        ),
        (
            dataset_with(
                "",
                "beam(#{ length: 1.0, width: 0.1, height: 0.1, segmets: 4 })",
            ),
            "segmets",
        ),
        (
            dataset_with(
                "",
                &format!("{A_BEAM}.material(\"steel\", #{{ roughnes: 0.5 }})"),
            ),
            "roughnes",
        ),
        (
            dataset_with(
                "",
                &shape("shape::mesh(\"pier.obj\", #{ normalise: true })"),
            ),
            "normalise",
        ),
        (
            format!(
                "let lens = #{{ f_number: 2.8, focus_distance: 3.0, sensor_widht: 0.036 }};\n{}",
                dataset_with(
                    "    camera: #{ width: 32, height: 24, depth_of_field: lens },",
                    A_BEAM
                )
            ),
            "sensor_widht",
        ),
    ];
    for (text, key) in cases {
        let mut expected = shown_at(&text, key).to_vec();
        expected.push("unknown option `".to_string());
        let expected: Vec<&str> = expected.iter().map(String::as_str).collect();
        rejects(&text, &[], &expected);
    }
}

/// In an imported module, the key is shown in the module's file.
#[test]
fn an_unknown_option_in_a_module_is_shown_in_the_module() {
    let module = "fn portal(span) {\n    beam(#{ length: span, width: 0.1, height: 0.3, \"axail\": \"free\" })\n}\n";
    let stderr = failing_portal(module);
    let col = module.lines().nth(1).unwrap().find("\"axail\"").unwrap() + 1;
    assert!(
        stderr.contains(&format!("frames.rhai:2:{col}\n")),
        "{stderr}"
    );
    assert!(stderr.contains("did you mean `axial`?"), "{stderr}");
}

/// A misspelt method or function gets the nearest name that exists, in `run` and in `check`,
/// at the call; a name that exists but not for the arguments given is said to exist.
#[test]
fn an_unknown_function_gets_the_nearest_name() {
    let cases = [
        (
            format!("{A_BEAM}.materail(\"steel\")"),
            "materail",
            "did you mean `material`?",
        ),
        (
            "assembly(\"a\", [shape::bx(1.0, 1.0, 1.0)])".to_string(),
            "bx(",
            "did you mean `shape::box`?",
        ),
        (
            format!("{A_BEAM}.material(3)"),
            "material",
            "`material` exists, but not for these arguments",
        ),
    ];
    for (scene, call, hint) in cases {
        let text = dataset_with("", &scene);
        let mut expected = shown_at(&text, call).to_vec();
        expected.push(hint.to_string());
        let expected: Vec<&str> = expected.iter().map(String::as_str).collect();
        rejects(&text, &[], &expected);
        let dir = tempfile::tempdir().unwrap();
        let recipe = write(dir.path(), "bad.rhai", &text);
        let output = Command::new(BIN)
            .arg("check")
            .arg(&recipe)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr)
            .replace(&dir.path().display().to_string(), "<dir>");
        assert!(!output.status.success(), "{stderr}");
        for fragment in &expected {
            assert!(
                stderr.contains(fragment),
                "check: `{fragment}` in:\n{stderr}"
            );
        }
    }
}

#[test]
fn a_failure_in_a_later_sample_writes_nothing() {
    // Most samples are fine; some draw an impossible load position.
    rejects(
        &with_scene(
            "        let b = beam(#{ length: 2.0, width: 0.1, height: 0.3 });\n        b.point_load(rng.uniform(0.0, 2.6), 0.01)",
        ),
        &[],
        &["outside the span", "while drawing the scene of sample"],
    );
}

/// Runs a recipe whose scene is `frames::portal(3.0)` from the module `frames.rhai` holding
/// `module`, which must fail; its stderr.
fn failing_portal(module: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "frames.rhai", module);
    let recipe = write(
        dir.path(),
        "bad.rhai",
        "import \"frames\" as frames;\ndataset(#{ scene: |rng| frames::portal(3.0) })\n",
    );
    let output = run(&recipe, &dir.path().join("out"), &[]);
    assert!(!output.status.success());
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn errors_inside_imported_modules_point_into_the_module() {
    let stderr = failing_portal(
        "fn portal(span) {\n    beam(#{ length: span, width: 0.0, height: 0.3 })\n}\n",
    );
    assert!(stderr.contains("frames.rhai:2:"), "{stderr}");
    assert!(
        stderr.contains("beam.width = 0 must be positive"),
        "{stderr}"
    );
}

#[test]
fn imports_cannot_leave_the_recipe_and_stdlib_folders() {
    rejects(
        "import \"../secret\" as s;\ndataset(#{ scene: |rng| () })\n",
        &[],
        &["no '..'", "<dir>/bad.rhai:1:"],
    );
}

#[test]
fn a_folder_holding_another_dataset_is_refused_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(dir.path(), "small.rhai", SMALL);
    let out = dir.path().join("ds");
    ok(run(&recipe, &out, &["--set", "samples=2"]));
    let before = hashes(&out);
    let refused = run(&recipe, &out, &["--set", "samples=3"]);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("different dataset"));
    assert_eq!(before, hashes(&out), "a refused run touches nothing");
    ok(run(&recipe, &out, &["--set", "samples=3", "--force"]));
    assert_eq!(hashes(&out).len(), 2 + 3 * 3 * 4);
}

#[test]
fn a_mesh_shared_between_samples_renders_as_if_each_built_its_own() {
    // The same imported mesh in every sample (only the cameras change): a run shares one BVH
    // between its samples, a shard of one sample builds its own; the bytes must not differ.
    let dir = tempfile::tempdir().unwrap();
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
    std::fs::copy(corpus.join("tetra.obj"), dir.path().join("tetra.obj")).unwrap();
    let recipe = write(
        dir.path(),
        "static.rhai",
        r#"dataset(#{ samples: 4, views: 2, camera: #{ width: 64, height: 48 },
            scene: |rng| assembly("tetra", [shape::mesh("tetra.obj", #{ normalize: true })]) })"#,
    );
    ok(run(&recipe, &dir.path().join("t1"), &["--threads", "1"]));
    ok(run(&recipe, &dir.path().join("t2"), &["--threads", "2"]));
    let alone = dir.path().join("alone");
    for shard in 0..4 {
        ok(run(&recipe, &alone, &["--shard", &format!("{shard}/4")]));
    }
    let one = hashes(&dir.path().join("t1"));
    assert_eq!(
        one.len(),
        2 + 4 * 2 * 4,
        "run.json, manifest and 4 files per view"
    );
    assert_eq!(one, hashes(&dir.path().join("t2")));
    assert_eq!(one, hashes(&alone));
}
