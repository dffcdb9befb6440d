//! `shmgen run` against how it is called and what happens to it: the recipe path spelled in
//! any way, crashes and full disks at every step, concurrent processes on one folder, and
//! datasets too large to validate up front.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

mod common;

use common::{BIN, hashes, ok, read_json, stderr, write};

/// A small recipe importing the stdlib and a module of its own folder; `fail_at` makes one
/// sample's scene fail.
const RECIPE: &str = r#"
import "beam" as beam;
import "finish" as finish;
dataset(#{
    name: "robust",
    seed: param("seed", 0),
    samples: param("samples", 6),
    views: param("views", 2),
    camera: #{ width: param("width", 48), height: param("height", 36), pitch: [deg(-60), deg(90)] },
    scene: |rng| {
        let length = rng.uniform(1.0, 4.0);
        let b = beam::paper_cuboid(length, rng.uniform(0.02, 0.25), rng.uniform(0.05, 1.5));
        if rng.chance(0.5) { b.cantilever(); }
        // Loads kept 0.1 L from the supports: closer, a stocky beam's target becomes shear
        // strain beyond what Timoshenko theory represents and is refused (docs/mechanics.md §5.3).
        b.point_load(rng.uniform(0.1, 0.9) * length, rng.uniform(0.0, 0.08) * length);
        if rng.sample == param("fail_at", -1) { throw "this sample fails on purpose"; }
        finish::grey(b)
    },
});
"#;

const MODULE: &str = "fn grey(b) { b.colour([0.6, 0.6, 0.6]) }\n";

/// No extra arguments.
const NO_ARGS: &[&str] = &[];

/// Exit code of a crash injected with SHMGEN_TEST_FAULT.
const CRASHED: i32 = 86;

/// Writes the recipe and its module into `dir` (as `name`); returns the recipe's path.
fn study(dir: &Path, name: &str) -> PathBuf {
    write(dir, "finish.rhai", MODULE);
    write(dir, name, RECIPE)
}

/// A temporary folder holding the recipe (`r.rhai`) and its module, and the dataset `clean`
/// made from it in one uninterrupted run with `args`: (folder, recipe, clean dataset).
fn study_with_clean_run(args: &[impl AsRef<OsStr>]) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let recipe = study(dir.path(), "r.rhai");
    let clean = dir.path().join("clean");
    ok(output(shmgen(dir.path(), &recipe, &clean, args)));
    (dir, recipe, clean)
}

/// Arguments from space-separated words: `NAME=VALUE` becomes `--set NAME=VALUE`, options
/// (`--threads=2`) stay as they are.
fn sets(words: &str) -> Vec<String> {
    words
        .split_whitespace()
        .flat_map(|w| match w.starts_with("--") {
            true => vec![w.to_string()],
            false => vec!["--set".to_string(), w.to_string()],
        })
        .collect()
}

/// `shmgen run RECIPE --out OUT --quiet EXTRA...` from the working directory `cwd`.
fn shmgen(
    cwd: &Path,
    recipe: impl AsRef<Path>,
    out: &Path,
    extra: &[impl AsRef<OsStr>],
) -> Command {
    let mut command = Command::new(BIN);
    command
        .current_dir(cwd)
        .arg("run")
        .arg(recipe.as_ref())
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra);
    command
}

fn output(mut command: Command) -> Output {
    command.output().unwrap()
}

fn spawn(mut command: Command) -> Child {
    command
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// One process per shard of `shards`, all started at once.
fn spawn_shards(
    cwd: &Path,
    recipe: &Path,
    out: &Path,
    args: &[String],
    shards: &[&str],
) -> Vec<Child> {
    shards
        .iter()
        .map(|shard| {
            let mut command = shmgen(cwd, recipe, out, args);
            command.args(["--shard", shard]);
            spawn(command)
        })
        .collect()
}

fn manifest_lines(out: &Path) -> usize {
    std::fs::read_to_string(out.join("manifest.jsonl"))
        .map(|t| t.lines().count())
        .unwrap_or(0)
}

fn wait_for(what: &str, mut done: impl FnMut() -> bool) {
    let deadline = Instant::now() + Duration::from_secs(120);
    while !done() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// Asserts that the run failed, saying each of `fragments`; returns what it said.
fn fails_with(output: &Output, fragments: &[&str]) -> String {
    let text = stderr(output);
    assert!(!output.status.success(), "must fail:\n{text}");
    for fragment in fragments {
        assert!(text.contains(fragment), "expected `{fragment}` in:\n{text}");
    }
    text
}

/// `out` holds the same bytes as `clean`, and nothing else.
fn assert_same_dataset(clean: &Path, out: &Path) {
    assert_eq!(hashes(clean), hashes(out));
    assert_no_leftovers(out);
}

/// Nothing an interrupted run leaves may remain in a finished dataset.
fn assert_no_leftovers(out: &Path) {
    for name in std::fs::read_dir(out).unwrap() {
        let name = name.unwrap().file_name().to_string_lossy().to_string();
        assert!(
            ["run.json", "manifest.jsonl", "samples"].contains(&name.as_str()),
            "leftover {name} in {}",
            out.display()
        );
    }
}

#[test]
fn the_dataset_is_the_same_however_the_recipe_path_is_spelled() {
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("study");
    let recipe = study(&work, "r.rhai");
    let clean = dir.path().join("clean");
    ok(output(shmgen(&work, "r.rhai", &clean, NO_ARGS)));

    // Three shards, each given the recipe another way, from another working directory.
    let out = dir.path().join("out");
    ok(output(shmgen(&work, "r.rhai", &out, &["--shard", "0/3"])));
    ok(output(shmgen(&work, "./r.rhai", &out, &["--shard", "1/3"])));
    ok(output(shmgen(
        Path::new("/"),
        &recipe,
        &out,
        &["--shard", "2/3"],
    )));
    assert_eq!(hashes(&clean), hashes(&out));
    let rerun = ok(output(shmgen(
        dir.path(),
        "study/../study/r.rhai",
        &out,
        NO_ARGS,
    )));
    assert!(String::from_utf8_lossy(&rerun.stdout).contains("(6 already present)"));

    // A renamed copy elsewhere is the same dataset: nothing is redone and run.json keeps
    // the name the dataset was created with.
    let copy = study(&dir.path().join("elsewhere"), "renamed.rhai");
    let resumed = ok(output(shmgen(dir.path(), &copy, &out, NO_ARGS)));
    assert!(String::from_utf8_lossy(&resumed.stdout).contains("(6 already present)"));
    assert_eq!(hashes(&clean), hashes(&out));

    // A run.json with the same content in other bytes (another key order, as another
    // version might write it) is the same dataset, and gets this version's bytes.
    let run_json = out.join("run.json");
    let value = read_json(&run_json);
    std::fs::write(&run_json, serde_json::to_vec(&value).unwrap()).unwrap();
    assert_ne!(hashes(&clean), hashes(&out));
    ok(output(shmgen(&work, "r.rhai", &out, NO_ARGS)));
    assert_eq!(hashes(&clean), hashes(&out));
}

#[test]
fn a_different_dataset_is_named_and_force_says_what_it_deletes() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = study(dir.path(), "r.rhai");
    let out = dir.path().join("ds");
    ok(output(shmgen(
        dir.path(),
        &recipe,
        &out,
        &["--set", "samples=4"],
    )));
    let before = hashes(&out);

    let refused = output(shmgen(
        dir.path(),
        &recipe,
        &out,
        &["--set", "samples=4", "--set", "seed=1"],
    ));
    let text = stderr(&refused);
    assert!(!refused.status.success());
    assert!(text.contains("holds a different dataset"), "{text}");
    assert!(text.contains("dataset.seed 0 vs 1"), "{text}");
    assert!(
        text.contains("--force would delete its 4 finished samples"),
        "{text}"
    );
    let refused = output(shmgen(dir.path(), &recipe, &out, &["--set", "samples=5"]));
    fails_with(&refused, &["params.samples 4 vs 5"]);

    write(dir.path(), "finish.rhai", MODULE.replace("0.6", "0.7"));
    let refused = output(shmgen(dir.path(), &recipe, &out, &["--set", "samples=4"]));
    fails_with(&refused, &["recipe content changed"]);
    write(dir.path(), "finish.rhai", MODULE);
    assert_eq!(before, hashes(&out), "a refused run touches nothing");

    let mut tool = read_json(&out.join("run.json"));
    tool["tool"]["version"] = "0.0.1".into();
    write(&out, "run.json", serde_json::to_vec_pretty(&tool).unwrap());
    let refused = output(shmgen(dir.path(), &recipe, &out, &["--set", "samples=4"]));
    assert!(
        stderr(&refused).contains("tool.version \"0.0.1\" vs"),
        "{}",
        stderr(&refused)
    );

    let forced = ok(output(shmgen(
        dir.path(),
        &recipe,
        &out,
        &["--set", "samples=4", "--set", "seed=1", "--force"],
    )));
    let text = stderr(&forced);
    assert!(
        text.contains("deleting its 4 finished samples") && text.contains("dataset.seed 0 vs 1"),
        "{text}"
    );
    // --force never deletes the same dataset: it resumes.
    let again = ok(output(shmgen(
        dir.path(),
        &recipe,
        &out,
        &["--set", "samples=4", "--set", "seed=1", "--force"],
    )));
    assert!(!stderr(&again).contains("deleting"), "{}", stderr(&again));
    assert!(String::from_utf8_lossy(&again.stdout).contains("(4 already present)"));
}

#[test]
fn a_crash_or_a_full_disk_at_any_step_resumes_to_the_same_bytes() {
    let (dir, recipe, clean) = study_with_clean_run(NO_ARGS);
    // Shard 1/2 runs first, so the manifest must be sorted when shard 0/2 finishes.
    let faults = [
        "write:run.json@1",
        "rename:run.json@1",
        "stage@1",
        "stage@7",
        "commit@1",
        "commit@2",
        "append@1",
        "append@3",
        "committed@2",
        "write:manifest.jsonl@1",
        "rename:manifest.jsonl@1",
        "write:run.json@1:full",
        "stage@5:full",
        "append@2:full",
        "write:manifest.jsonl@1:full",
    ];
    for fault in faults {
        let out = dir.path().join(fault.replace([':', '@'], "_"));
        let mut faulted = 0;
        for shard in ["1/2", "0/2"] {
            let mut command = shmgen(dir.path(), &recipe, &out, &["--shard", shard]);
            command.env("SHMGEN_TEST_FAULT", fault);
            let first = output(command);
            if !first.status.success() {
                faulted += 1;
                let text = stderr(&first);
                if fault.ends_with(":full") {
                    assert_eq!(first.status.code(), Some(1), "{fault}: {text}");
                    assert!(text.contains("the disk is full"), "{fault}: {text}");
                    assert!(!text.contains(".partial"), "{fault}: {text}");
                } else {
                    assert_eq!(first.status.code(), Some(CRASHED), "{fault}: {text}");
                }
            }
            ok(output(shmgen(
                dir.path(),
                &recipe,
                &out,
                &["--shard", shard],
            )));
        }
        assert!(faulted > 0, "{fault} was never reached");
        assert_eq!(hashes(&clean), hashes(&out), "after {fault}");
        assert_no_leftovers(&out);
    }
}

#[test]
fn what_a_crash_leaves_never_makes_a_folder_unusable() {
    let (dir, recipe, clean) = study_with_clean_run(NO_ARGS);
    // Killed between writing run.json's temporary file and renaming it: only half of that
    // file is there.
    let out = dir.path().join("first");
    let run_json = std::fs::read(clean.join("run.json")).unwrap();
    write(&out, ".run.json.tmp-4242", &run_json[..run_json.len() / 2]);
    ok(output(shmgen(dir.path(), &recipe, &out, NO_ARGS)));
    assert_same_dataset(&clean, &out);

    // Leftovers of every kind beside a dataset are removed by the next run that finishes.
    write(&out, ".run.json.tmp-77-0", "{");
    write(&out, ".manifest.jsonl.tmp-78-1", "{\"sample\": 0");
    write(&out, ".partial/000003/0", "half a file");
    write(&out, ".partial/shard-1-of-2/000001/2", "half a file");
    write(&out, ".partial/shard-1-of-2.lock", "pid 1");
    let rerun = ok(output(shmgen(dir.path(), &recipe, &out, NO_ARGS)));
    assert!(String::from_utf8_lossy(&rerun.stdout).contains("(6 already present)"));
    assert_same_dataset(&clean, &out);
}

#[test]
fn kill_9_at_random_moments_never_bricks_the_folder() {
    let args = sets("samples=24 --threads=2");
    let (dir, recipe, clean) = study_with_clean_run(&args);
    let out = dir.path().join("killed");
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut random = |below: u64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state % below
    };
    for round in 0..16 {
        // Two shards at once half of the time, so that kills land in either.
        let shards: &[&str] = if round % 2 == 0 {
            &["0/1"]
        } else {
            &["0/2", "1/2"]
        };
        let mut children = spawn_shards(dir.path(), &recipe, &out, &args, shards);
        std::thread::sleep(Duration::from_micros(random(150_000)));
        for child in &mut children {
            let _ = child.kill();
            child.wait().unwrap();
        }
    }
    ok(output(shmgen(dir.path(), &recipe, &out, &args)));
    assert_same_dataset(&clean, &out);
}

#[test]
fn one_process_per_shard_and_shards_side_by_side() {
    let slow = sets("samples=40 width=320 height=240 --threads=1");
    let (dir, recipe, clean) = study_with_clean_run(&slow);

    let out = dir.path().join("out");
    let mut first = spawn(shmgen(dir.path(), &recipe, &out, &slow));
    wait_for("the first sample", || manifest_lines(&out) >= 1);
    let second = output(shmgen(dir.path(), &recipe, &out, &slow));
    let text = stderr(&second);
    assert!(!second.status.success());
    let expected = format!(
        "shard 0/1 of {} is being written by another process (pid {}",
        out.display(),
        first.id()
    );
    assert!(text.contains(&expected), "{text}");
    let mut other = slow.clone();
    other.extend(sets("seed=9 --force"));
    let forced = output(shmgen(dir.path(), &recipe, &out, &other));
    fails_with(&forced, &["is being written by another process"]);
    assert!(first.wait().unwrap().success());
    assert_same_dataset(&clean, &out);

    // Different shards started together share the folder, whichever starts first.
    let fast = sets("samples=12");
    let clean = dir.path().join("clean-fast");
    ok(output(shmgen(dir.path(), &recipe, &clean, &fast)));
    for round in 0..4 {
        let out = dir.path().join(format!("together{round}"));
        let children = spawn_shards(dir.path(), &recipe, &out, &fast, &["0/3", "1/3", "2/3"]);
        for child in children {
            let done = child.wait_with_output().unwrap();
            assert!(done.status.success(), "{}", stderr(&done));
        }
        assert_same_dataset(&clean, &out);
    }
}

#[test]
fn a_late_failure_stops_there_and_keeps_every_earlier_sample() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = study(dir.path(), "r.rhai");
    let tiny = "samples=1000000 views=1 width=8 height=8";

    // A failure among the first samples writes nothing.
    let out = dir.path().join("early");
    let early = sets(&format!("{tiny} fail_at=999"));
    let failed = output(shmgen(dir.path(), &recipe, &out, &early));
    fails_with(&failed, &["while drawing the scene of sample 999"]);
    assert!(!out.exists(), "no file may be written");

    // A later one stops the run there: every sample before it is complete and listed.
    let out = dir.path().join("late");
    let late = sets(&format!("{tiny} fail_at=5000"));
    let failed = output(shmgen(dir.path(), &recipe, &out, &late));
    let text = stderr(&failed);
    assert!(!failed.status.success());
    assert!(text.contains("the run stopped at sample 5000"), "{text}");
    assert!(
        text.contains("while drawing the scene of sample 5000"),
        "{text}"
    );
    let manifest = std::fs::read_to_string(out.join("manifest.jsonl")).unwrap();
    let mut listed = Vec::new();
    for line in manifest.lines() {
        let entry: serde_json::Value = serde_json::from_str(line).unwrap();
        for file in entry["files"].as_array().unwrap() {
            let path = out.join(file.as_str().unwrap());
            assert!(std::fs::metadata(&path).unwrap().len() > 0, "{path:?}");
        }
        listed.push(entry["sample"].as_u64().unwrap());
    }
    listed.sort();
    assert!(!listed.contains(&5000));
    assert_eq!(listed[..5000], (0..5000).collect::<Vec<u64>>()[..]);
    assert_no_leftovers(&out);

    // Running again skips the finished samples and fails at the same one, now among the
    // first it validates: it writes nothing.
    let again = output(shmgen(dir.path(), &recipe, &out, &late));
    fails_with(&again, &["while drawing the scene of sample 5000"]);
    assert_eq!(
        std::fs::read_to_string(out.join("manifest.jsonl")).unwrap(),
        manifest
    );
}

/// Peak resident memory of a running process, bytes.
fn peak_memory(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[test]
fn the_largest_dataset_starts_at_once_in_bounded_memory() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = study(dir.path(), "r.rhai");
    let out = dir.path().join("huge");
    let samples = (1u64 << 40).to_string();
    let mut command = Command::new(BIN);
    command
        .arg("run")
        .arg(&recipe)
        .arg("--out")
        .arg(&out)
        .args(sets(&format!("samples={samples} views=1 width=8 height=8")));
    let mut child = spawn(command);
    let start = Instant::now();
    let mut peak = 0;
    let mut watch = |lines: usize| {
        wait_for("samples to be written", || {
            peak = peak.max(peak_memory(child.id()).unwrap_or(0));
            manifest_lines(&out) >= lines
        })
    };
    watch(1);
    let first_sample = start.elapsed();
    watch(2000);
    child.kill().unwrap();
    let done = child.wait_with_output().unwrap();
    let text = stderr(&done);
    assert!(text.contains("validating: 1000 samples"), "{text}");
    assert!(
        text.contains(&format!("rendering: {samples} samples")),
        "{text}"
    );
    assert!(
        peak < 200 << 20,
        "peak memory {} MB for 2^40 samples",
        peak >> 20
    );
    assert!(
        first_sample < Duration::from_secs(60),
        "first sample written after {first_sample:?}"
    );
    eprintln!(
        "2^40 samples: first sample after {first_sample:?}, peak memory {} MB",
        peak >> 20
    );
}

/// A real full disk: a 400 kB tmpfs mounted in a private mount namespace (skipped where
/// user namespaces are not available).
#[test]
fn a_real_full_disk_names_the_dataset_file_and_resumes() {
    let values = "samples=12 width=64 height=48";
    let (dir, recipe, clean) = study_with_clean_run(&sets(values));
    let args = format!("{} --quiet", sets(values).join(" "));
    let mnt = dir.path().join("mnt");
    let copy = dir.path().join("copy");
    std::fs::create_dir(&mnt).unwrap();
    let script = format!(
        "mount -t tmpfs -o size=400k tmpfs {mnt} || exit 77
         {BIN} run {recipe} --out {mnt}/ds {args} 2> {dir}/full.txt && exit 78
         mount -o remount,size=50m {mnt} || exit 79
         {BIN} run {recipe} --out {mnt}/ds {args} > /dev/null || exit 80
         cp -a {mnt}/ds {copy}",
        mnt = mnt.display(),
        recipe = recipe.display(),
        dir = dir.path().display(),
        copy = copy.display(),
    );
    let status = Command::new("unshare")
        .args(["--user", "--map-root-user", "--mount", "sh", "-c", &script])
        .status();
    match status.map(|s| s.code()) {
        Ok(Some(0)) => {}
        Ok(Some(77)) | Err(_) => {
            eprintln!("skipped: no private mount namespace here");
            return;
        }
        Ok(code) => panic!("step failed with {code:?}"),
    }
    let text = std::fs::read_to_string(dir.path().join("full.txt")).unwrap();
    assert!(text.contains("the disk is full"), "{text}");
    assert!(text.contains("No space left on device"), "{text}");
    assert!(!text.contains(".partial"), "{text}");
    assert!(
        text.contains("writing samples/")
            || text.contains("manifest.jsonl")
            || text.contains("run.json"),
        "{text}"
    );
    assert_eq!(hashes(&clean), hashes(&copy));
}
