//! The two boundaries of a dataset, seen from the command line: what a command reads from a
//! dataset (regular files inside it, never a link, each of bounded size, headers before
//! pixels, contents checked against the manifest's sizes and BLAKE3 hashes) and where a
//! command may write (never onto or inside a dataset or an export, however the path is
//! spelled). `hostile_datasets.rs` throws every kind of hostile file at every reader; these
//! are the cases the issue names, each with the outcome asserted in full.

mod common;

use common::{blake3_hex, hashes, quickstart, read_json, run_limited, shmgen, stderr};
use std::ffi::OsStr;
use std::fs;
use std::os::unix::fs::symlink;
use std::path::Path;
use std::time::{Duration, Instant};

fn args<'a>(list: &'a [&'a str]) -> Vec<&'a OsStr> {
    list.iter().map(OsStr::new).collect()
}

/// `shmgen ARGS` must fail with a message holding every fragment; returns the message.
fn refused(list: &[&str], fragments: &[&str]) -> String {
    let output = shmgen(&args(list));
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "shmgen {list:?}:\n{err}");
    for fragment in fragments {
        assert!(
            err.contains(fragment),
            "shmgen {list:?}: no {fragment:?} in\n{err}"
        );
    }
    err
}

/// `shmgen export DATA --format webdataset --out OUT` must fail saying `fragment`, leaving no
/// OUT.
fn refused_export(data: &str, out: &Path, fragment: &str) {
    refused(
        &["export", data, "--format", "webdataset", "--out", &s(out)],
        &[fragment],
    );
    assert!(!out.exists());
}

fn s(path: &Path) -> String {
    path.display().to_string()
}

#[test]
fn no_command_writes_onto_or_inside_a_dataset_or_an_export_by_any_spelling() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=2"]);
    let before = hashes(&data);
    let export = dir.path().join("export");
    let d = s(&data);
    common::ok(shmgen(&args(&[
        "export",
        &d,
        "--format",
        "colmap",
        "--out",
        &s(&export),
    ])));
    let export_before = hashes(&export);
    let link = dir.path().join("link");
    symlink(&data, &link).unwrap();
    let recipe = s(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/quickstart.rhai"));

    let spellings = [
        format!("{d}/run.json"),
        format!("{d}/samples/../run.json"),
        format!("{}/run.json", s(&link)),
        format!("{d}/samples/0000/report.json"),
        format!("{}/cameras.json", s(&export)),
    ];
    for target in &spellings {
        refused(
            &["eval", &d, &format!("{d}/samples"), "--json", target],
            &["--json", "shmgen never writes onto a dataset or an export"],
        );
        refused(
            &["watch", &recipe, "--once", "--size", "16", "--out", target],
            &["--out", "shmgen never writes onto a dataset or an export"],
        );
    }
    refused(
        &[
            "export",
            &d,
            "--format",
            "png16",
            "--out",
            &format!("{}/more", s(&export)),
        ],
        &["lies inside the export"],
    );
    refused(
        &["run", &recipe, "--out", &format!("{d}/samples/nested")],
        &["lies inside the dataset"],
    );
    refused(&["run", &recipe, "--out", &s(&export)], &["is the export"]);
    // The dataset and the export are untouched: run.json is still the dataset's, so a later
    // run resumes rather than offering to delete the finished samples.
    assert_eq!(hashes(&data), before);
    assert_eq!(hashes(&export), export_before);
    let resumed = common::run(
        Path::new(&recipe),
        &data,
        &["--set", "samples=1", "--set", "views=2"],
    );
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    assert!(String::from_utf8_lossy(&resumed.stdout).contains("1 already present"));

    // Outside them, the same commands write.
    let report = dir.path().join("report.json");
    common::ok(shmgen(&args(&[
        "eval",
        &d,
        &format!("{d}/samples"),
        "--json",
        &s(&report),
    ])));
    assert_eq!(read_json(&report)["schema"], "shmgen.eval/2");
}

#[test]
fn a_link_inside_a_dataset_is_never_followed_by_any_reader() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=2"]);
    let secret = dir.path().join("passwd");
    fs::write(&secret, "root:x:0:0:SECRET-LINE\n").unwrap();
    let target = data.join("samples/0000/000000_01.mask.png");
    fs::remove_file(&target).unwrap();
    symlink(&secret, &target).unwrap();
    let d = s(&data);
    for (format, extra) in [
        ("webdataset", None),
        ("colmap", Some("--copy")),
        ("nerfstudio", Some("--copy")),
        ("nerfstudio", None),
    ] {
        let out = dir.path().join(format!("out-{format}"));
        let mut list = vec!["export", &d, "--format", format];
        let o = s(&out);
        list.extend(["--out", &o]);
        list.extend(extra);
        refused(&list, &["000000_01.mask.png", "symbolic link"]);
        assert!(!out.exists());
    }
    refused(
        &["verify", &d],
        &["000000_01.mask.png", "symbolic link", "1 of"],
    );
    // A folder of the dataset replaced by a link to a copy elsewhere: refused the same way.
    fs::remove_file(&target).unwrap();
    fs::copy(&secret, &target).unwrap();
    let moved = dir.path().join("elsewhere");
    fs::rename(data.join("samples/0000"), &moved).unwrap();
    symlink(&moved, data.join("samples/0000")).unwrap();
    refused_export(&d, &dir.path().join("w"), "symbolic link");
    // Resuming a run into it would rename files through the link: refused too.
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/quickstart.rhai");
    let resumed = common::run(&recipe, &data, &["--set", "samples=2", "--set", "views=2"]);
    assert!(
        stderr(&resumed).contains("is a symbolic link"),
        "{}",
        stderr(&resumed)
    );
}

#[test]
fn special_files_in_a_dataset_are_refused_without_reading_them() {
    let dir = tempfile::tempdir().unwrap();
    let clean = quickstart(dir.path(), "clean", &["samples=1", "views=1"]);
    for (file, message) in [
        ("manifest.jsonl", "symbolic link"),
        ("run.json", "symbolic link"),
        ("samples/0000/000000_00.depth.exr", "symbolic link"),
    ] {
        let data = dir.path().join("d");
        let _ = fs::remove_dir_all(&data);
        common::ok(
            std::process::Command::new("cp")
                .arg("-r")
                .arg(&clean)
                .arg(&data)
                .output()
                .unwrap(),
        );
        fs::remove_file(data.join(file)).unwrap();
        symlink("/dev/zero", data.join(file)).unwrap();
        let started = Instant::now();
        let d = s(&data);
        let (output, finished) = run_limited(
            Duration::from_secs(20),
            &args(&["eval", &d, &format!("{d}/samples")]),
        );
        assert!(
            finished && output.status.code() == Some(1),
            "{file}: {}",
            stderr(&output)
        );
        let err = stderr(&output);
        assert!(err.contains(file) && err.contains(message), "{file}: {err}");
        assert!(
            !err.contains("missing"),
            "{file} is there, as a link: {err}"
        );
        assert!(started.elapsed() < Duration::from_secs(10));
    }
}

/// A grey PNG of `width × height` whose pixel data is one compressed zero row repeated: a few
/// kB on disk however many pixels it declares.
fn declared_png(width: u32, height: u32) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, 1, 1);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Sixteen);
    encoder
        .write_header()
        .unwrap()
        .write_image_data(&[0, 0])
        .unwrap();
    // The header is what a careless reader allocates by.
    assert!(common::inflate_png(&mut out, width, height));
    out
}

#[test]
fn a_prediction_declaring_a_huge_image_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=1"]);
    let predictions = dir.path().join("p/0000");
    fs::create_dir_all(&predictions).unwrap();
    for side in [40_000u32, 100_000] {
        fs::write(
            predictions.join("000000_00.depth.png"),
            declared_png(side, side),
        )
        .unwrap();
        let started = Instant::now();
        let d = s(&data);
        let p = s(&dir.path().join("p"));
        let (output, finished) = run_limited(Duration::from_secs(20), &args(&["eval", &d, &p]));
        let err = stderr(&output);
        assert!(finished && output.status.code() == Some(1), "{err}");
        assert!(
            err.contains(&format!("{side}×{side} pixels, the view has 960×960")),
            "{err}"
        );
        assert!(
            started.elapsed() < Duration::from_secs(5),
            "{:?}",
            started.elapsed()
        );
    }
}

#[test]
fn verify_names_every_entry_the_manifest_does_not_list() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=1"]);
    let d = s(&data);
    common::ok(shmgen(&args(&["verify", &d])));
    // A copy can gain files: a stray view, a note at the top, a link, a FIFO. None of them is
    // part of the dataset, and a verified copy must be exactly the dataset.
    fs::write(data.join("samples/0000/000000_07.rgb.png"), b"not ours").unwrap();
    fs::write(data.join("notes.txt"), b"hello").unwrap();
    symlink("/etc/passwd", data.join("samples/link.png")).unwrap();
    let fifo = data.join("samples/0000/pipe");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    let with_fifo = made.is_ok_and(|status| status.success());
    let extra = if with_fifo { 4 } else { 3 };
    let err = refused(
        &["verify", &d],
        &[&format!(
            "0 of 4 files differ from what manifest.jsonl records, and {extra} entries"
        )],
    );
    for line in [
        "samples/0000/000000_07.rgb.png: a file manifest.jsonl does not list",
        "notes.txt: a file manifest.jsonl does not list",
        "samples/link.png: a link (not followed)",
    ] {
        assert!(err.contains(line), "{line} missing from:\n{err}");
    }
    if with_fifo {
        assert!(
            err.contains("samples/0000/pipe: not a regular file"),
            "{err}"
        );
    }
    for name in [
        "samples/0000/000000_07.rgb.png",
        "notes.txt",
        "samples/link.png",
    ] {
        fs::remove_file(data.join(name)).unwrap();
    }
    if with_fifo {
        fs::remove_file(&fifo).unwrap();
    }
    common::ok(shmgen(&args(&["verify", &d])));
}

#[test]
fn the_manifest_records_every_files_size_and_hash_and_verify_checks_them() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=2", "views=2"]);
    // Every listed file is recorded with its true size and BLAKE3, computed here by another
    // reader of the same bytes.
    let text = fs::read_to_string(data.join("manifest.jsonl")).unwrap();
    let mut recorded = 0;
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let files = v["files"].as_array().unwrap();
        assert_eq!(v["hashes"].as_object().unwrap().len(), files.len());
        for file in files {
            let file = file.as_str().unwrap();
            let bytes = fs::read(data.join(file)).unwrap();
            assert_eq!(v["hashes"][file]["bytes"], bytes.len());
            assert_eq!(v["hashes"][file]["blake3"], blake3_hex(&bytes).as_str());
            recorded += 1;
        }
    }
    assert_eq!(recorded, 2 * 2 * 4);
    let d = s(&data);
    let out = common::ok(shmgen(&args(&["verify", &d])));
    assert!(String::from_utf8_lossy(&out.stdout).contains(&format!("verified: {recorded} files")));

    // Same size, other bytes: only the hash tells. Every reader of it refuses it.
    let rgb = data.join("samples/0000/000001_01.rgb.png");
    let mut bytes = fs::read(&rgb).unwrap();
    let last = bytes.len() - 20;
    bytes[last] ^= 0x55;
    fs::write(&rgb, &bytes).unwrap();
    let depth = data.join("samples/0000/000000_00.depth.exr");
    let truncated = fs::read(&depth).unwrap();
    fs::write(&depth, &truncated[..truncated.len() - 1]).unwrap();
    let err = refused(&["verify", &d], &["2 of 16 files differ"]);
    assert!(err.contains("000001_01.rgb.png: its content is not what manifest.jsonl records"));
    assert!(
        err.contains("000000_00.depth.exr: ") && err.contains("bytes, but manifest.jsonl records")
    );
    fs::write(&depth, &truncated).unwrap();
    let changed = "000001_01.rgb.png: its content is not what manifest.jsonl records";
    refused_export(&d, &dir.path().join("w"), changed);
    // COLMAP hard-links the image: the link is made, then its bytes read through and checked.
    let colmap = dir.path().join("c");
    refused(
        &["export", &d, "--format", "colmap", "--out", &s(&colmap)],
        &[changed],
    );
    assert!(!colmap.exists());
}
