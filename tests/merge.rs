//! `shmgen merge OUT PART...`, seen from outside: shards written into separate folders (as on
//! a cluster's node-local disks) merge into the bytes of a single run; parts that are not the
//! same dataset, samples that differ between parts, links inside a part and an OUT inside a
//! part are refused before anything is written; a killed merge resumes.

mod common;

use common::{BIN, blake3_hex, hashes, ok, run, stderr};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Exit code of a crash injected with `SHMGEN_TEST_FAULT`.
const CRASHED: i32 = 86;

fn quickstart() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/quickstart.rhai")
}

/// The quickstart into `out`, with `extra` arguments (`--shard`, `--set`).
fn quickstart_into(out: &Path, extra: &[&str]) {
    ok(run(&quickstart(), out, extra));
}

fn merge(out: &Path, parts: &[&Path]) -> Command {
    let mut command = Command::new(BIN);
    command.arg("merge").arg(out).args(parts);
    command
}

fn merged(out: &Path, parts: &[&Path]) -> Output {
    merge(out, parts).output().unwrap()
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).to_string()
}

/// A refusal whose message holds every one of `fragments`.
fn refused(output: &Output, fragments: &[&str]) {
    let text = stderr(output);
    assert!(!output.status.success(), "not refused: {}", stdout(output));
    for fragment in fragments {
        assert!(text.contains(fragment), "{fragment:?} not in: {text}");
    }
}

/// A single run of the quickstart with `sets`, and the same run as two shards written into
/// two separate folders.
struct Shards {
    dir: tempfile::TempDir,
    single: PathBuf,
    a: PathBuf,
    b: PathBuf,
}

fn shards(sets: &[&str]) -> Shards {
    let dir = tempfile::tempdir().unwrap();
    let (single, a, b) = (
        dir.path().join("single"),
        dir.path().join("node-a"),
        dir.path().join("node-b"),
    );
    quickstart_into(&single, sets);
    quickstart_into(&a, &[sets, &["--shard", "0/2"]].concat());
    quickstart_into(&b, &[sets, &["--shard", "1/2"]].concat());
    Shards { dir, single, a, b }
}

const SMALL: &[&str] = &["--set", "samples=4", "--set", "views=2"];

#[test]
fn two_node_local_shards_merge_into_the_bytes_of_a_single_run() {
    let s = shards(&[]);
    let (before_a, before_b) = (hashes(&s.a), hashes(&s.b));
    let out = s.dir.path().join("merged");
    let text = stdout(&ok(merged(&out, &[&s.a, &s.b])));
    // Every file, manifest.jsonl and run.json included, and nothing else.
    assert_eq!(hashes(&s.single), hashes(&out));
    assert!(text.contains("3 from"), "{text}");
    assert!(text.contains("complete: all 6 samples"), "{text}");
    // The parts are read, never written.
    assert_eq!(before_a, hashes(&s.a));
    assert_eq!(before_b, hashes(&s.b));
    ok(Command::new(BIN).arg("verify").arg(&out).output().unwrap());

    // Merging again adds nothing and changes nothing.
    let again = stdout(&ok(merged(&out, &[&s.b, &s.a])));
    assert!(again.contains("6 already there"), "{again}");
    assert_eq!(hashes(&s.single), hashes(&out));
}

#[test]
fn one_part_at_a_time_says_what_is_missing_then_completes() {
    let s = shards(SMALL);
    let out = s.dir.path().join("merged");
    let first = stdout(&ok(merged(&out, &[&s.b])));
    assert!(
        first.contains("incomplete: 2 of 4 samples missing (first: sample 0)"),
        "{first}"
    );
    // An incomplete merge is a partial dataset: no reader takes it for a finished one.
    let verify = Command::new(BIN).arg("verify").arg(&out).output().unwrap();
    refused(&verify, &["not finished"]);
    let second = stdout(&ok(merged(&out, &[&s.a])));
    assert!(second.contains("2 already there"), "{second}");
    assert!(second.contains("complete: all 4 samples"), "{second}");
    assert_eq!(hashes(&s.single), hashes(&out));
}

#[test]
fn identical_overlaps_are_taken_once_and_unfinished_samples_ignored() {
    let s = shards(SMALL);
    // A part that also holds the other's samples (a shard run twice, on two nodes), and
    // leftovers of a killed run: a file no manifest line lists and a torn last line.
    std::fs::write(s.a.join("samples/0000/000002_00.rgb.png.partial"), b"half").unwrap();
    let mut manifest = std::fs::read(s.a.join("manifest.jsonl")).unwrap();
    manifest.extend_from_slice(b"{\"sample\": 2, \"fi");
    std::fs::write(s.a.join("manifest.jsonl"), manifest).unwrap();
    let out = s.dir.path().join("merged");
    let text = stdout(&ok(merged(&out, &[&s.a, &s.single, &s.b])));
    assert_eq!(hashes(&s.single), hashes(&out));
    assert!(text.contains("2 from"), "{text}");
    assert!(
        text.contains("4 duplicates identical in several parts"),
        "{text}"
    );
    assert!(
        text.contains("2 files or lines of unfinished samples"),
        "{text}"
    );
}

/// Rewrites, in the part at `root`, the file `relative` with `bytes` and its manifest record
/// to match: a consistent part whose sample differs from the same sample elsewhere.
fn rewrite_consistently(root: &Path, relative: &str, bytes: &[u8]) {
    let old = std::fs::read(root.join(relative)).unwrap();
    // Unlinked first: the file may be a hard link to another part's.
    std::fs::remove_file(root.join(relative)).unwrap();
    std::fs::write(root.join(relative), bytes).unwrap();
    let manifest = std::fs::read_to_string(root.join("manifest.jsonl")).unwrap();
    let from = format!(
        "\"{relative}\":{{\"blake3\":\"{}\",\"bytes\":{}}}",
        blake3_hex(&old),
        old.len()
    );
    assert!(manifest.contains(&from), "{from} not in the manifest");
    let to = format!(
        "\"{relative}\":{{\"blake3\":\"{}\",\"bytes\":{}}}",
        blake3_hex(bytes),
        bytes.len()
    );
    std::fs::write(root.join("manifest.jsonl"), manifest.replace(&from, &to)).unwrap();
}

#[test]
fn samples_that_differ_between_parts_are_refused_and_nothing_is_written() {
    let s = shards(SMALL);
    let other = s.dir.path().join("node-c");
    ok(merged(&other, &[&s.a]));
    // Sample 2, consistent with its own manifest, but not what node-a rendered.
    let png = "samples/0000/000002_01.rgb.png";
    let mut bytes = std::fs::read(other.join(png)).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    rewrite_consistently(&other, png, &bytes);

    let out = s.dir.path().join("merged");
    refused(
        &merged(&out, &[&s.a, &s.b, &other]),
        &["sample 2 differs between", "node-a", "node-c", png],
    );
    assert!(!out.exists(), "a refused merge wrote {}", out.display());

    // The same against a sample OUT already holds.
    ok(merged(&out, &[&s.a]));
    let before = hashes(&out);
    refused(&merged(&out, &[&other]), &["sample 2 differs between OUT"]);
    assert_eq!(before, hashes(&out));
}

#[test]
fn a_part_of_another_dataset_is_refused_naming_it_and_what_differs() {
    let s = shards(SMALL);
    let foreign = s.dir.path().join("seed-1");
    quickstart_into(
        &foreign,
        &[SMALL, &["--set", "seed=1", "--shard", "1/2"]].concat(),
    );
    let out = s.dir.path().join("merged");
    refused(
        &merged(&out, &[&s.a, &foreign]),
        &[
            "PART",
            "seed-1",
            "is not the same dataset",
            "seed 2026 vs 1",
        ],
    );
    assert!(!out.exists());

    // The name of the recipe's file is not the dataset: a node may run a renamed copy.
    let renamed = s.dir.path().join("copy-of-quickstart.rhai");
    std::fs::copy(quickstart(), &renamed).unwrap();
    let b = s.dir.path().join("node-b-renamed");
    ok(run(&renamed, &b, &[SMALL, &["--shard", "1/2"]].concat()));
    ok(merged(&out, &[&s.a, &b]));
    assert_eq!(hashes(&s.single), hashes(&out));
    std::fs::remove_dir_all(&out).unwrap();

    // Nor into an OUT holding another dataset.
    refused(
        &merged(&foreign, &[&s.a]),
        &["holds a different dataset", "seed"],
    );
}

#[cfg(unix)]
#[test]
fn a_part_holding_a_link_is_refused() {
    let s = shards(SMALL);
    // The link points at a file with the very bytes the manifest records: still refused, as
    // a link could as well pull in any file of the person merging.
    let png = s.b.join("samples/0000/000001_00.rgb.png");
    let elsewhere = s.dir.path().join("elsewhere.png");
    std::fs::rename(&png, &elsewhere).unwrap();
    std::os::unix::fs::symlink(&elsewhere, &png).unwrap();
    let out = s.dir.path().join("merged");
    refused(
        &merged(&out, &[&s.a, &s.b]),
        &["000001_00.rgb.png", "symbolic link"],
    );
    assert!(!out.exists());

    // A linked folder is refused as well, before anything is written.
    for linked in ["samples/0000", "samples"] {
        let folder = s.a.join(linked);
        let moved = s.dir.path().join("elsewhere");
        std::fs::rename(&folder, &moved).unwrap();
        std::os::unix::fs::symlink(&moved, &folder).unwrap();
        refused(&merged(&out, &[&s.a]), &[linked, "symbolic link"]);
        assert!(!out.exists(), "{linked}");
        std::fs::remove_file(&folder).unwrap();
        std::fs::rename(&moved, &folder).unwrap();
    }
}

#[test]
fn an_out_holding_other_files_is_refused() {
    let s = shards(SMALL);
    let out = s.dir.path().join("notes");
    common::write(&out, "todo.txt", "keep me");
    refused(
        &merged(&out, &[&s.a]),
        &["is not empty and holds no shmgen dataset"],
    );
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);
}

#[test]
fn out_inside_or_equal_to_a_part_is_refused() {
    let s = shards(SMALL);
    let before = hashes(&s.a);
    refused(
        &merged(&s.a.join("merged"), &[&s.a, &s.b]),
        &["OUT", "lies inside the dataset", "node-a"],
    );
    refused(&merged(&s.a, &[&s.a, &s.b]), &["OUT", "is the dataset"]);
    let spelled = s.a.join("samples/..");
    refused(&merged(&spelled, &[&s.b, &s.a]), &["OUT"]);
    assert_eq!(before, hashes(&s.a));
}

#[test]
fn a_killed_merge_resumes_and_never_looks_complete() {
    let s = shards(SMALL);
    let out = s.dir.path().join("merged");
    // Killed while appending the third sample's manifest line: half of it is written.
    let killed = merge(&out, &[&s.a, &s.b])
        .env("SHMGEN_TEST_FAULT", "append@3")
        .output()
        .unwrap();
    assert_eq!(killed.status.code(), Some(CRASHED), "{}", stderr(&killed));
    let verify = Command::new(BIN).arg("verify").arg(&out).output().unwrap();
    refused(&verify, &["not finished"]);
    let resumed = stdout(&ok(merged(&out, &[&s.a, &s.b])));
    assert!(resumed.contains("2 already there"), "{resumed}");
    assert_eq!(hashes(&s.single), hashes(&out));
}
