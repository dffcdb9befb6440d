//! `shmgen status` seen from outside: samples done per shard against the residue classes of
//! the sample indices, locks held by this test process (running), left by nobody (stale) or
//! held under a dead pid (orphaned), what to resubmit, the rate from file times set here, the
//! exit codes, the JSON shape, folders that are not datasets; and `run` refusing a second
//! shard count while the first is being written.

use serde_json::Value;
use std::collections::BTreeSet;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, SystemTime};

mod common;

use common::{BIN, ok, run, stderr, write};

/// Samples in the test dataset.
const SAMPLES: u64 = 10;

const RECIPE: &str = r#"
import "beam" as beam;
dataset(#{
    name: "tiny",
    seed: 7,
    samples: 10,
    views: 1,
    outputs: ["rgb", "depth"],
    camera: #{ width: 32, height: 24, pitch: [deg(-60), deg(90)] },
    scene: |rng| {
        let b = beam::paper_cuboid(rng.uniform(1.0, 3.0), 0.1, 0.3);
        b.cantilever();
        b
    },
});
"#;

/// A temporary folder with the recipe, and the dataset path in it.
fn setup() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(dir.path(), "tiny.rhai", RECIPE);
    let out = dir.path().join("d");
    (dir, recipe, out)
}

fn status(out: &Path, extra: &[&str]) -> Output {
    Command::new(BIN)
        .arg("status")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

/// `status --json`, parsed, with its exit code.
fn status_json(out: &Path) -> (Value, Option<i32>) {
    let output = status(out, &["--json"]);
    let text = String::from_utf8_lossy(&output.stdout);
    let json =
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}\n{}", stderr(&output)));
    (json, output.status.code())
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).to_string()
}

/// The samples of `count` shards' shard `index`: independent of shmgen's arithmetic.
fn samples_of(index: u64, count: u64) -> Vec<u64> {
    (0..SAMPLES).filter(|s| s % count == index).collect()
}

/// Holds the lock of `.partial/shard-{shard}.lock` the way a running shard does, recording
/// `pid` on this host; released when dropped.
fn hold_lock(out: &Path, shard: &str, pid: u32) -> File {
    let path = out
        .join(".partial")
        .join(format!("shard-{}.lock", shard.replace('/', "-of-")));
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let file = File::create(&path).unwrap();
    file.lock().unwrap();
    std::fs::write(&path, format!("pid {pid} on host {}", host())).unwrap();
    file
}

fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .unwrap()
        .trim()
        .to_string()
}

fn u64s(value: &Value) -> Vec<u64> {
    value
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect()
}

#[test]
fn a_partial_dataset_lists_samples_per_shard_and_what_to_resubmit() {
    let (_dir, recipe, out) = setup();
    ok(run(&recipe, &out, &["--shard", "1/4"]));
    let (json, code) = status_json(&out);
    assert_eq!(code, Some(2), "incomplete, nothing running: {json}");
    assert_eq!(json["name"], "tiny");
    assert_eq!(json["seed"], 7);
    assert_eq!(json["samples"], SAMPLES);
    assert_eq!(json["done"], samples_of(1, 4).len());
    assert_eq!(json["complete"], false);
    assert_eq!(json["running"], false);
    // The shard count comes from the finished shard's mark, though its lock is gone.
    assert_eq!(json["shard_count"], 4);
    assert_eq!(u64s(&json["shard_counts_seen"]), vec![4]);
    for (k, shard) in json["shards"].as_array().unwrap().iter().enumerate() {
        let k = k as u64;
        assert_eq!(shard["index"], k);
        assert_eq!(shard["expected"], samples_of(k, 4).len());
        let done = if k == 1 { samples_of(k, 4).len() } else { 0 };
        assert_eq!(shard["done"], done, "shard {k}");
    }
    assert_eq!(u64s(&json["resubmit"]), vec![0, 2, 3]);
    assert_eq!(json["resubmit_array"], "0,2-3");
    let text = stdout(&status(&out, &[]));
    assert!(text.contains("3 of 10 samples"), "{text}");
    assert!(
        text.contains("--shard 0/4 --shard 2/4 --shard 3/4"),
        "{text}"
    );
    assert!(text.contains("--array=0,2-3"), "{text}");
    // Another count on request.
    let per_two = stdout(&status(&out, &["--shards", "2"]));
    assert!(per_two.contains("1/2: 3 of 5"), "{per_two}");
}

#[test]
fn a_complete_dataset_exits_zero_with_nothing_to_resubmit() {
    let (_dir, recipe, out) = setup();
    ok(run(&recipe, &out, &["--shard", "1/2"]));
    ok(run(&recipe, &out, &["--shard", "0/2"]));
    let (json, code) = status_json(&out);
    assert_eq!(code, Some(0), "{json}");
    assert_eq!(json["complete"], true);
    assert_eq!(json["done"], SAMPLES);
    assert_eq!(u64s(&json["resubmit"]), Vec::<u64>::new());
    // The marks of shards that ended early are gone with `.partial/`.
    assert!(!out.join(".partial").exists());
    assert!(stdout(&status(&out, &[])).contains("(complete)"));
}

#[test]
fn locks_are_told_apart_running_stale_and_orphaned() {
    let (_dir, recipe, out) = setup();
    ok(run(&recipe, &out, &["--shard", "1/4"]));
    // Shard 2: held now by this process. Shard 3: left by a process that is gone, held by
    // nobody. Shard 0: held, but under the pid of a child that has exited.
    let _running = hold_lock(&out, "2/4", std::process::id());
    let stale = hold_lock(&out, "3/4", 1);
    drop(stale);
    let mut child = Command::new("true").spawn().unwrap();
    let dead = child.id();
    child.wait().unwrap();
    let _orphaned = hold_lock(&out, "0/4", dead);

    let (json, code) = status_json(&out);
    assert_eq!(code, Some(3), "incomplete and running: {json}");
    assert_eq!(json["running"], true);
    let states: BTreeSet<(String, String, u64)> = json["locks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| {
            assert_eq!(l["host"], host());
            (
                l["shard"].as_str().unwrap().to_string(),
                l["state"].as_str().unwrap().to_string(),
                l["pid"].as_u64().unwrap(),
            )
        })
        .collect();
    let expected: BTreeSet<(String, String, u64)> = [
        ("0/4", "orphaned", u64::from(dead)),
        ("2/4", "running", u64::from(std::process::id())),
        ("3/4", "stale", 1),
    ]
    .into_iter()
    .map(|(s, st, p)| (s.to_string(), st.to_string(), p))
    .collect();
    assert_eq!(states, expected);
    // Held locks (running or orphaned) are not to be resubmitted (a run of them would be
    // refused); the stale one is.
    assert_eq!(json["shards"][2]["running"], true);
    assert_eq!(json["shards"][0]["running"], true);
    assert_eq!(u64s(&json["resubmit"]), vec![3]);
    let text = stdout(&status(&out, &[]));
    assert!(text.contains("lock 3/4: stale"), "{text}");
    assert!(
        text.contains(&format!("pid {dead} does not exist")),
        "{text}"
    );
}

#[test]
fn progress_is_the_rate_of_the_latest_samples_file_times() {
    let (_dir, recipe, out) = setup();
    ok(run(&recipe, &out, &["--shard", "1/4"]));
    // Samples 1, 5, 9 written 10 s apart: 2 intervals in 20 s = 0.1 samples/s, and the 7
    // missing samples take 70 s at that rate.
    let start = SystemTime::now() - Duration::from_secs(600);
    let manifest = std::fs::read_to_string(out.join("manifest.jsonl")).unwrap();
    for (i, line) in manifest.lines().enumerate() {
        let line: Value = serde_json::from_str(line).unwrap();
        let first = line["files"][0].as_str().unwrap();
        let file = File::options().write(true).open(out.join(first)).unwrap();
        file.set_modified(start + Duration::from_secs(10 * i as u64))
            .unwrap();
    }
    let (json, _) = status_json(&out);
    let progress = &json["progress"];
    assert_eq!(progress["measured_over"], 3);
    let rate = progress["samples_per_second"].as_f64().unwrap();
    assert!((rate - 0.1).abs() < 1e-9, "{progress}");
    let left = progress["seconds_left"].as_f64().unwrap();
    assert!((left - 70.0).abs() < 1e-6, "{progress}");
    let since = progress["seconds_since_last"].as_f64().unwrap();
    assert!((580.0..700.0).contains(&since), "{progress}");
    let text = stdout(&status(&out, &[]));
    assert!(
        text.contains("0.10 samples/s") && text.contains("1 min 10 s left"),
        "{text}"
    );
}

#[test]
fn the_json_has_the_documented_fields() {
    let (_dir, recipe, out) = setup();
    ok(run(&recipe, &out, &["--shard", "0/2"]));
    let (json, _) = status_json(&out);
    let keys: BTreeSet<&str> = json
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    let documented: BTreeSet<&str> = [
        "name",
        "seed",
        "samples",
        "done",
        "complete",
        "running",
        "shard_counts_seen",
        "shard_count",
        "frames_per_unit",
        "partial",
        "shards",
        "locks",
        "resubmit",
        "resubmit_array",
        "unreadable_lines",
        "progress",
    ]
    .into();
    assert_eq!(keys, documented);
    let shard: BTreeSet<&str> = json["shards"][0]
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    assert_eq!(shard, ["index", "done", "expected", "running"].into());
}

#[test]
fn torn_lines_are_counted_not_taken_as_samples() {
    let (_dir, recipe, out) = setup();
    ok(run(&recipe, &out, &["--shard", "1/4"]));
    let mut manifest = std::fs::read(out.join("manifest.jsonl")).unwrap();
    manifest.extend_from_slice(b"{\"sample\": 0, \"fil");
    std::fs::write(out.join("manifest.jsonl"), manifest).unwrap();
    let (json, _) = status_json(&out);
    assert_eq!(json["done"], 3);
    assert_eq!(json["unreadable_lines"], 1);
}

#[test]
fn folders_that_are_not_datasets_are_errors_with_exit_one() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<(PathBuf, &str)> = vec![
        (dir.path().join("missing"), "no such folder"),
        (
            {
                let p = dir.path().join("empty");
                std::fs::create_dir(&p).unwrap();
                p
            },
            "not a shmgen dataset (no run.json",
        ),
        (
            {
                let p = dir.path().join("foreign");
                write(
                    &p,
                    "run.json",
                    r#"{"schema":"other/1","dataset":{"samples":3}}"#,
                );
                p
            },
            "not a shmgen dataset: run.json has schema \"other/1\"",
        ),
        (
            {
                let p = dir.path().join("garbage");
                write(&p, "run.json", "not json");
                p
            },
            "run.json does not parse",
        ),
        (
            {
                let p = dir.path().join("linked");
                write(
                    &p,
                    "run.json",
                    r#"{"schema":"shmgen.run/1","dataset":{"samples":3}}"#,
                );
                std::os::unix::fs::symlink("/etc/hostname", p.join("manifest.jsonl")).unwrap();
                p
            },
            "is a symbolic link",
        ),
    ];
    for (folder, message) in cases {
        let output = status(&folder, &[]);
        assert_eq!(output.status.code(), Some(1), "{}", folder.display());
        assert!(stderr(&output).contains(message), "{}", stderr(&output));
        assert!(output.stdout.is_empty());
    }
}

#[test]
fn a_second_shard_count_is_refused_while_the_first_runs_and_resumes_after() {
    let (_dir, recipe, out) = setup();
    ok(run(&recipe, &out, &["--shard", "1/4"]));
    let before = std::fs::read(out.join("manifest.jsonl")).unwrap();
    let running = hold_lock(&out, "2/4", std::process::id());
    let refused = run(&recipe, &out, &["--shard", "0/3"]);
    assert_eq!(refused.status.code(), Some(1));
    let text = stderr(&refused);
    assert!(
        text.contains("shard 0/3 refused") && text.contains("being written in 4 shards"),
        "{text}"
    );
    assert!(
        text.contains(&format!("pid {}", std::process::id())),
        "{text}"
    );
    assert_eq!(
        std::fs::read(out.join("manifest.jsonl")).unwrap(),
        before,
        "nothing rendered"
    );
    // The same count is not refused.
    ok(run(&recipe, &out, &["--shard", "3/4"]));
    drop(running);
    // Once the first count ended (its lock left but free), another count resumes it and skips
    // the finished samples: 0/3 owns 0, 3, 6, 9, of which 3 and 9 are done by 1/4 and 3/4.
    let resumed = stdout(&ok(run(&recipe, &out, &["--shard", "0/3"])));
    assert!(
        resumed.contains("2 samples rendered (2 already present)"),
        "{resumed}"
    );
}

/// `shmgen status D` within 10 s: (output, finished by itself).
fn status_limited(out: &Path) -> (Output, bool) {
    let args = [std::ffi::OsStr::new("status"), out.as_os_str()];
    common::run_limited(Duration::from_secs(10), &args)
}

fn fifo(path: &Path) {
    let _ = std::fs::remove_file(path);
    let made = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(made.success());
}

#[test]
fn a_hostile_folder_never_blocks_or_floods_status() {
    let (dir, recipe, clean) = setup();
    ok(run(&recipe, &clean, &["--shard", "1/4"]));
    let copy = |name: &str| {
        let to = dir.path().join(name);
        let copied = Command::new("cp").arg("-a").arg(&clean).arg(&to).status();
        assert!(copied.unwrap().success());
        to
    };
    // Each case: the folder, and the exit code with a word of the message (None: not an
    // error, but done within the limit).
    let mut cases: Vec<(PathBuf, i32, &str)> = Vec::new();

    let d = copy("fifo_manifest");
    fifo(&d.join("manifest.jsonl"));
    cases.push((d, 1, "not a regular file"));

    let d = copy("fifo_run_json");
    fifo(&d.join("run.json"));
    cases.push((d, 1, "not a record shmgen wrote"));

    let d = copy("long_line");
    std::fs::write(d.join("manifest.jsonl"), vec![b'{'; 2 << 20]).unwrap();
    cases.push((d, 1, "longer than"));

    // A lock file that is a FIFO: probed and read without waiting on it.
    let d = copy("fifo_lock");
    fifo(&d.join(".partial/shard-0-of-4.lock"));
    cases.push((d, 2, "lock 0/4: stale"));

    // Samples and a shard count of 2⁶⁴ − 1 in run.json and a lock file's name: counted, not
    // listed one by one.
    let d = copy("huge");
    let run_json = std::fs::read_to_string(d.join("run.json")).unwrap();
    let mut value: Value = serde_json::from_str(&run_json).unwrap();
    value["dataset"]["samples"] = u64::MAX.into();
    std::fs::write(d.join("run.json"), value.to_string()).unwrap();
    let huge_lock = format!(".partial/shard-0-of-{}.lock", u64::MAX);
    write(&d, &huge_lock, "pid 1");
    cases.push((d, 2, "shards of 4:"));

    for (folder, code, word) in cases {
        let (output, finished) = status_limited(&folder);
        let text = format!("{}{}", stdout(&output), stderr(&output));
        assert!(finished, "{}: did not finish", folder.display());
        assert_eq!(
            output.status.code(),
            Some(code),
            "{}: {text}",
            folder.display()
        );
        assert!(text.contains(word), "{}: {text}", folder.display());
        assert!(
            text.len() < 10_000,
            "{}: {} bytes",
            folder.display(),
            text.len()
        );
    }
}

/// The same readers serve `run`'s resume: a FIFO manifest is refused, not waited on for ever,
/// and a manifest without newlines is refused, not read whole.
#[test]
fn run_refuses_a_manifest_that_is_a_fifo_or_one_endless_line() {
    let (_dir, recipe, out) = setup();
    ok(run(&recipe, &out, &["--shard", "1/4"]));
    let manifest = out.join("manifest.jsonl");
    let resume = || {
        let args: Vec<&std::ffi::OsStr> = vec![
            "run".as_ref(),
            recipe.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
            "--shard".as_ref(),
            "0/4".as_ref(),
        ];
        common::run_limited(Duration::from_secs(20), &args)
    };
    fifo(&manifest);
    let (output, finished) = resume();
    assert!(finished, "run waited on a FIFO manifest");
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr(&output).contains("manifest.jsonl: not a regular file"));
    std::fs::remove_file(&manifest).unwrap();
    std::fs::write(&manifest, vec![b'{'; 2 << 20]).unwrap();
    let (output, _) = resume();
    assert_eq!(output.status.code(), Some(1));
    assert!(stderr(&output).contains("line 1 is longer than 1048576 bytes"));
}
