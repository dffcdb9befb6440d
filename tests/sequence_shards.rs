//! Frame ranges as units of work, seen from outside: `shmgen run --frames-per-unit F` splits
//! every sequence sample into ranges of F frames that shards (`--shard K/N`) take, that are
//! committed and resumed alone, and that `merge` gathers from node-local folders. The
//! independent truth is the run without it: every file, manifest included, has the bytes a
//! one-thread run of whole samples gives, with the flow between frames and motion blur
//! crossing the units' boundaries, the mount shaking and the sensor series written once.

mod common;

use common::{BIN, hashes, ok, run, stderr, write};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Exit code of a crash injected with `SHMGEN_TEST_FAULT`.
const CRASH_EXIT: i32 = 86;

/// Two crossings of a beam (a vehicle, so every frame differs) filmed by two fixed cameras on
/// shaking mounts for 11 frames, with motion blur, the flow between frames and sensors.
const RECIPE: &str = r#"dataset(#{
    name: "units", seed: 9, samples: 2, views: 2,
    outputs: ["rgb", "depth", "mask", "displacement", "frame_flow", "point_tracks", "mesh"],
    sequence: #{ duration: 0.35, fps: 30.0, motion_blur: 2,
        mount: #{ rotation: 2e-4, translation: 2e-4, band: 6.0 } },
    camera: #{ width: 40, height: 30, fov_y: deg(50),
        fixed: [#{ position: [1.0, -1.2, 0.2], target: [1.0, 0.0, 0.0] },
                #{ position: [0.4, -1.0, 0.3], target: [1.0, 0.0, 0.0] }] },
    scene: |rng| {
        let b = beam(#{ length: 2.0, width: 0.1, height: 0.2 });
        b.simply_supported();
        b.theory("euler_bernoulli");
        b.at(1.0, 0.0, 0.0);
        b.vehicle([[0.0, 3e5]], rng.uniform(4.0, 8.0), 0.0); b.damping(0.03); b.modes(4);
        b.sensor(#{ name: "mid", kind: "displacement", at: 1.0, rate: 60.0 });
        b
    },
});
"#;

struct Setup {
    dir: tempfile::TempDir,
    recipe: PathBuf,
}

impl Setup {
    fn new() -> Setup {
        let dir = tempfile::tempdir().unwrap();
        let recipe = write(dir.path(), "units.rhai", RECIPE);
        Setup { dir, recipe }
    }

    fn out(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// `shmgen run` of the recipe into `out` with `extra`, which must succeed; its stdout.
    fn run(&self, out: &Path, extra: &[&str]) -> String {
        String::from_utf8_lossy(&ok(run(&self.recipe, out, extra)).stdout).to_string()
    }

    /// `shmgen run` into `out` on one thread in units of `frames_per_unit` frames, crashing
    /// at the fault `fault` (`SHMGEN_TEST_FAULT`), as `kill -9` would leave it.
    fn crash(&self, out: &Path, frames_per_unit: &str, fault: &str) {
        let crashed = Command::new(BIN)
            .args(["run", self.recipe.to_str().unwrap(), "--out"])
            .arg(out)
            .args([
                "--quiet",
                "--threads",
                "1",
                "--frames-per-unit",
                frames_per_unit,
            ])
            .env("SHMGEN_TEST_FAULT", fault)
            .output()
            .unwrap();
        let code = crashed.status.code();
        assert_eq!(code, Some(CRASH_EXIT), "{}", stderr(&crashed));
    }

    /// The reference: whole samples, one thread.
    fn reference(&self) -> BTreeMap<String, String> {
        let out = self.out("reference");
        self.run(&out, &["--threads", "1"]);
        hashes(&out)
    }
}

#[test]
fn frame_ranges_in_shards_give_the_bytes_of_one_thread_into_one_folder_or_merged() {
    let setup = Setup::new();
    let reference = setup.reference();
    let sensors = reference.keys().filter(|f| f.contains(".sensors_")).count();
    assert!(sensors > 0 && reference.contains_key("manifest.jsonl"));
    assert!(
        reference
            .keys()
            .any(|f| f.ends_with("_01_f0010.flow_prev.exr"))
    );

    // Units of 4 frames (0–3, 4–7, 8–10): boundaries inside each sequence, where the flow to
    // the frame before and after and the blurred exposure need frames of another unit.
    let whole = setup.out("units");
    let loud = Command::new(BIN)
        .args(["run", setup.recipe.to_str().unwrap(), "--out"])
        .arg(&whole)
        .args(["--frames-per-unit", "4"])
        .output()
        .unwrap();
    let loud = ok(loud);
    let said = String::from_utf8_lossy(&loud.stdout).to_string();
    assert!(said.contains("done: 6 units of frames rendered"), "{said}");
    // Progress counts what is dealt out.
    let progress = stderr(&loud);
    assert!(
        progress.contains("rendering: 6 units of frames"),
        "{progress}"
    );
    assert_same(&reference, &whole);

    // Two shards of units of 3 frames into one folder, the second on one thread.
    let shared = setup.out("shared");
    for shard in ["1/2", "0/2"] {
        setup.run(&shared, &["--frames-per-unit", "3", "--shard", shard]);
    }
    assert_same(&reference, &shared);

    // Three shards of units of 2 frames on three "nodes", then merged.
    let parts: Vec<PathBuf> = (0..3).map(|k| setup.out(&format!("part{k}"))).collect();
    for (k, part) in parts.iter().enumerate() {
        let shard = format!("{k}/3");
        let said = setup.run(part, &["--frames-per-unit", "2", "--shard", &shard]);
        assert!(said.contains("dataset incomplete"), "{said}");
    }
    // The sensor series are written once a sample, by the unit of its frame 0.
    let with_sensors: Vec<String> = (parts.iter())
        .flat_map(|p| {
            std::fs::read_to_string(p.join("manifest.jsonl"))
                .unwrap()
                .lines()
                .map(str::to_string)
                .collect::<Vec<_>>()
        })
        .filter(|line| line.contains(".sensors_"))
        .collect();
    assert_eq!(with_sensors.len(), 2);
    assert!(
        with_sensors.iter().all(|l| l.contains(r#""frames":[0,2]"#)),
        "{with_sensors:?}"
    );
    // Each part has a third of the frames and no finished sample.
    let status = shmgen(&["status", parts[1].to_str().unwrap(), "--json"]);
    let status: serde_json::Value = serde_json::from_slice(&status.stdout).unwrap();
    assert_eq!(status["done"], 0, "{status}");
    assert_eq!(status["frames_per_unit"], 2, "{status}");
    // 6 units a sample (0–1, …, 10), 12 in all: shard 1 of 3 has units 1, 4, 7, 10.
    assert_eq!(status["shards"][1]["done"], 4, "{status}");
    assert_eq!(status["shards"][1]["expected"], 4, "{status}");
    assert_eq!(status["shards"][0]["done"], 0, "{status}");
    assert_eq!(status["resubmit"], serde_json::json!([0, 2]), "{status}");
    // Sample 0's units 1 and 4 hold frames 2–3 and 8–9; sample 1's 7 and 10 hold 2–3, 8–9.
    let frames_done: Vec<u64> = (status["partial"].as_array().unwrap().iter())
        .map(|p| p["frames_done"].as_u64().unwrap())
        .collect();
    assert_eq!(frames_done, vec![4, 4], "{status}");

    let merged = setup.out("merged");
    let mut args = vec!["merge", merged.to_str().unwrap()];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    let said = String::from_utf8_lossy(&ok(shmgen(&args)).stdout).to_string();
    assert!(said.contains("complete: all 2 samples"), "{said}");
    assert_same(&reference, &merged);
}

#[test]
fn a_sequence_killed_mid_sample_resumes_from_its_last_committed_unit() {
    let setup = Setup::new();
    let reference = setup.reference();
    let out = setup.out("killed");
    // One thread, units of 3 frames (4 a sample): the crash comes after the manifest line of
    // the third unit, in the middle of sample 0.
    setup.crash(&out, "3", "committed@3");
    let manifest = std::fs::read_to_string(out.join("manifest.jsonl")).unwrap();
    assert_eq!(manifest.lines().count(), 3, "{manifest}");
    assert!(
        manifest
            .lines()
            .all(|l| l.starts_with(r#"{"files""#) && l.contains(r#""unit""#))
    );
    // The committed frames 0–8 of sample 0, as they are on disk before the resume.
    let committed: Vec<(PathBuf, Identity)> = (0..9)
        .map(|k| out.join(format!("samples/0000/000000_01_f{k:04}.rgb.png")))
        .map(|path| {
            let identity = identity(&path);
            (path, identity)
        })
        .collect();

    let said = setup.run(&out, &["--threads", "1", "--frames-per-unit", "3"]);
    assert!(
        said.contains("done: 5 units of frames rendered (3 already present)"),
        "{said}"
    );
    for (path, before) in &committed {
        assert_eq!(
            &identity(path),
            before,
            "{} was written again",
            path.display()
        );
    }
    assert_same(&reference, &out);
}

#[test]
fn a_torn_unit_line_is_redone_and_the_sample_sealed_once() {
    let setup = Setup::new();
    let reference = setup.reference();
    let out = setup.out("torn");
    // Units of 6 frames (2 a sample): the crash tears the second unit's line, so sample 0 has
    // one whole unit and half a line; the resume (in units of 4) redoes frames 6–10 only as
    // the units 4–7 and 8–10 it does not hold, and seals sample 0 from three overlapping units.
    setup.crash(&out, "6", "append@2");
    let said = setup.run(&out, &["--threads", "1", "--frames-per-unit", "4"]);
    // Sample 0: 0–3 is held by the unit 0–5 committed; 4–7 and 8–10 are not. Sample 1: all 3.
    assert!(
        said.contains("done: 5 units of frames rendered (1 already present)"),
        "{said}"
    );
    assert_same(&reference, &out);
}

#[test]
fn frames_per_unit_is_refused_for_stills_and_zero_and_stills_shard_as_before() {
    let setup = Setup::new();
    let still = write(
        setup.dir.path(),
        "still.rhai",
        RECIPE.replace("    sequence: #{ duration: 0.35, fps: 30.0, motion_blur: 2,\n        mount: #{ rotation: 2e-4, translation: 2e-4, band: 6.0 } },\n", "")
            .replace(r#", "frame_flow", "point_tracks""#, "")
            .replace(
                r#"        b.sensor(#{ name: "mid", kind: "displacement", at: 1.0, rate: 60.0 });
"#,
                "",
            )
            .replace("b.vehicle([[0.0, 3e5]], rng.uniform(4.0, 8.0), 0.0); b.damping(0.03); b.modes(4);", "b.point_force(rng.uniform(0.5, 1.5), 2e5);"),
    );
    let refused = run(&still, &setup.out("s"), &["--frames-per-unit", "4"]);
    assert!(!refused.status.success());
    assert!(
        stderr(&refused).contains("--frames-per-unit 4: the recipe films no sequence"),
        "{}",
        stderr(&refused)
    );
    assert!(!setup.out("s").exists(), "a refused run writes nothing");
    let zero = run(&setup.recipe, &setup.out("z"), &["--frames-per-unit", "0"]);
    assert!(stderr(&zero).contains("--frames-per-unit 0: a unit holds at least one frame"));

    // Stills in shards: the samples dealt out as before, the same bytes as one run.
    let one = setup.out("one");
    ok(run(&still, &one, &["--threads", "1"]));
    let sharded = setup.out("sharded");
    for shard in ["1/2", "0/2"] {
        let said = String::from_utf8_lossy(&ok(run(&still, &sharded, &["--shard", shard])).stdout)
            .to_string();
        assert!(said.contains("done: 1 samples rendered"), "{said}");
    }
    assert_eq!(hashes(&one), hashes(&sharded));
}

/// Asserts that the folder `out` holds the files of `reference` with their bytes, naming
/// those that differ.
fn assert_same(reference: &BTreeMap<String, String>, out: &Path) {
    let got = hashes(out);
    let differing: Vec<&String> = (reference.keys().chain(got.keys()))
        .filter(|f| reference.get(*f) != got.get(*f))
        .collect();
    assert!(
        differing.is_empty(),
        "{}: differ from the reference: {differing:?}",
        out.display()
    );
}

/// `shmgen ARGS...`.
fn shmgen(args: &[&str]) -> std::process::Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// What tells a file written again from the same file left alone: its inode (a rewrite renames
/// a new file into place) and modification time.
type Identity = (u64, std::time::SystemTime);

fn identity(path: &Path) -> Identity {
    use std::os::unix::fs::MetadataExt;
    let meta = std::fs::metadata(path).unwrap();
    (meta.ino(), meta.modified().unwrap())
}
