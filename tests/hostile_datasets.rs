//! Hostile datasets: a dataset received from someone else is untrusted input. Every kind of
//! file a dataset holds (run.json, the manifest, each view's images, EXR layers and record,
//! each sample's meshes) is in turn truncated, emptied, scrambled, grown, inflated to declare
//! 40000 × 40000 pixels, replaced by a link to a file outside the dataset, by a link to
//! `/dev/zero`, by a FIFO or by a folder, and one of the dataset's folders by a link. Each
//! hostile copy goes to every command that reads a dataset: `export` in every format (linked
//! and copied), `eval` and `verify`.
//!
//! Every command must end within its time limit, under a 3 GiB address-space limit, with
//! either success or a clear error (exit 1, `error: …`, no panic, no abort), and:
//! - never put a byte of a file from outside the dataset into its output (a link is always
//!   refused, naming it);
//! - on an error, leave no output folder and no staging folder behind;
//! - with the manifest's hashes left as they were, refuse every changed file (the hashes
//!   tell it from the good one); with the hashes rewritten to match the hostile bytes (an
//!   attacker can), still never crash: the decoders check headers before decoding.
//!
//! `SHMGEN_FUZZ_CASES=N` runs only the first N hostile datasets.

mod common;

use common::{BIN, stderr};
use std::fs;
use std::os::unix::fs::symlink;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// What no command may ever output: the content of the file outside the dataset that links
/// point at.
const SECRET: &[u8] = b"SECRET-of-the-person-exporting-4f1c9a";

/// Address space each command may use: a file that makes a reader allocate by what it
/// declares rather than what it holds ends in an abort, which the test reports.
const MEMORY: u64 = 3 << 30;

/// One sample of two small views with every kind of file a dataset can hold.
const RECIPE: &str = r#"
import "beam" as beam;
dataset(#{
    name: "hostile", seed: 5, samples: 1, views: 2,
    outputs: ["rgb", "depth", "mask", "parts", "normals", "displacement", "flow", "rest_rgb",
              "rest_depth", "ray_distance", "mesh", "mesh_gltf", "points"],
    points: 300,
    camera: #{ width: 40, height: 32, pitch: [deg(10), deg(40)] },
    scene: |rng| beam::simply_supported(3.0, 0.2, 0.4, 1.5, 0.05).material("rusty steel"),
});
"#;

/// How the bytes or the entry of one file are made hostile.
#[derive(Clone, Copy, Debug)]
enum Harm {
    Truncated,
    Emptied,
    Scrambled,
    Grown,
    /// An image header declaring 40000 × 40000 pixels (PNG IHDR, EXR dataWindow).
    Inflated,
    LinkOutside,
    LinkDevZero,
    Fifo,
    Folder,
}

const HARMS: [Harm; 9] = [
    Harm::Truncated,
    Harm::Emptied,
    Harm::Scrambled,
    Harm::Grown,
    Harm::Inflated,
    Harm::LinkOutside,
    Harm::LinkDevZero,
    Harm::Fifo,
    Harm::Folder,
];

impl Harm {
    fn is_entry(self) -> bool {
        matches!(
            self,
            Harm::LinkOutside | Harm::LinkDevZero | Harm::Fifo | Harm::Folder
        )
    }
}

/// One hostile dataset.
#[derive(Clone, Debug)]
struct Case {
    /// The file (relative to the root) made hostile, or a folder replaced by a link.
    target: String,
    harm: Harm,
    /// Whether the manifest's size and hash of `target` are rewritten to match.
    rehash: bool,
}

fn commands(data: &Path, out: &Path) -> Vec<Vec<String>> {
    let (d, o) = (data.display().to_string(), out.display().to_string());
    let export = |format: &str, extra: &[&str]| {
        let mut c = vec!["export", &d, "--format", format, "--out", &o];
        c.extend(extra);
        c.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    vec![
        export("nerfstudio", &[]),
        export("nerfstudio", &["--copy"]),
        export("colmap", &["--copy"]),
        export("webdataset", &[]),
        export("png16", &[]),
        export("flow", &[]),
        // Predictions: the dataset's own layers, so every kind of file it holds is read.
        ["eval", &d, &format!("{d}/samples")]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        ["verify", &d].iter().map(|s| s.to_string()).collect(),
    ]
}

/// Runs `shmgen args` with the time and memory limits.
fn limited(args: &[String], limit: Duration) -> (Output, bool) {
    let mut command = Command::new(BIN);
    command
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    // SAFETY: setrlimit is async-signal-safe; nothing else runs between fork and exec.
    unsafe {
        command.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: MEMORY,
                rlim_max: MEMORY,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let child = command.spawn().unwrap();
    let id = child.id();
    let start = Instant::now();
    let watchdog = std::thread::spawn(move || {
        while start.elapsed() < limit {
            std::thread::sleep(Duration::from_millis(20));
            if Path::new(&format!("/proc/{id}/status"))
                .exists()
                .then(|| fs::read_to_string(format!("/proc/{id}/status")).unwrap_or_default())
                .is_none_or(|s| s.contains("State:\tZ"))
            {
                return true;
            }
        }
        // SAFETY: sending a signal to our own child.
        unsafe { libc::kill(id as i32, libc::SIGKILL) };
        false
    });
    let output = child.wait_with_output().unwrap();
    (output, watchdog.join().unwrap())
}

/// Every file below `root`, with its bytes.
fn files_below(root: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries {
            let path = entry.unwrap().path();
            let meta = fs::symlink_metadata(&path).unwrap();
            if meta.is_dir() {
                stack.push(path);
            } else if meta.is_file() {
                out.push((path.clone(), fs::read(&path).unwrap()));
            } else {
                out.push((path, b"<not a regular file>".to_vec()));
            }
        }
    }
    out
}

fn contains(haystack: &[u8], needle: &[u8]) -> bool {
    haystack.windows(needle.len()).any(|w| w == needle)
}

/// EXR: the dataWindow attribute (box2i: xMin, yMin, xMax, yMax) made 40000 × 40000.
fn inflate_exr(bytes: &mut [u8]) -> bool {
    let key = b"dataWindow\0box2i\0";
    let Some(at) = bytes.windows(key.len()).position(|w| w == key) else {
        return false;
    };
    let values = at + key.len() + 4;
    bytes[values + 8..values + 12].copy_from_slice(&39999i32.to_le_bytes());
    bytes[values + 12..values + 16].copy_from_slice(&39999i32.to_le_bytes());
    true
}

/// Applies `case` to the copy of the dataset at `data`; false if it does not apply to that
/// file (inflating a file that is not an image).
fn harm(data: &Path, secret: &Path, case: &Case) -> bool {
    let path = data.join(&case.target);
    if path.is_dir() {
        // A folder of the dataset replaced by a link to a copy of it elsewhere.
        let copy = secret.with_extension(format!("folder-{}", std::process::id()));
        let _ = fs::remove_dir_all(&copy);
        fs::rename(&path, &copy).unwrap();
        symlink(&copy, &path).unwrap();
        return true;
    }
    let mut bytes = fs::read(&path).unwrap();
    match case.harm {
        Harm::Truncated => bytes.truncate(bytes.len() / 2),
        Harm::Emptied => bytes.clear(),
        Harm::Scrambled => {
            let n = bytes.len();
            for i in (n / 3..n).step_by(7) {
                bytes[i] = bytes[i].wrapping_mul(31).wrapping_add(17);
            }
        }
        Harm::Grown => bytes.extend(std::iter::repeat_n(b'A', 17 << 20)),
        Harm::Inflated => {
            if !(common::inflate_png(&mut bytes, 40000, 40000) || inflate_exr(&mut bytes)) {
                return false;
            }
        }
        Harm::LinkOutside | Harm::LinkDevZero | Harm::Fifo | Harm::Folder => {}
    }
    fs::remove_file(&path).unwrap();
    match case.harm {
        Harm::LinkOutside => symlink(secret, &path).unwrap(),
        Harm::LinkDevZero => symlink("/dev/zero", &path).unwrap(),
        Harm::Fifo => {
            let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
            // SAFETY: a valid NUL-terminated path.
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        }
        Harm::Folder => fs::create_dir(&path).unwrap(),
        _ => fs::write(&path, &bytes).unwrap(),
    }
    if case.rehash && !case.harm.is_entry() {
        rehash(data, &case.target, &bytes);
    }
    true
}

/// Rewrites the manifest's record of `target` to match `bytes`, as an attacker could.
fn rehash(data: &Path, target: &str, bytes: &[u8]) {
    let manifest = data.join("manifest.jsonl");
    let Ok(text) = fs::read_to_string(&manifest) else {
        return;
    };
    let mut out = String::new();
    for line in text.lines() {
        let mut v: serde_json::Value = serde_json::from_str(line).unwrap();
        if let Some(record) = v["hashes"].get_mut(target) {
            *record = serde_json::json!({
                "bytes": bytes.len(),
                "blake3": blake3::hash(bytes).to_hex().as_str(),
            });
        }
        out += &v.to_string();
        out.push('\n');
    }
    fs::write(manifest, out).unwrap();
}

fn copy_tree(from: &Path, to: &Path) {
    fs::create_dir_all(to).unwrap();
    for entry in fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            fs::copy(entry.path(), target).unwrap();
        }
    }
}

/// The hostile datasets: every harm to one file of each kind (view 0's files, the sample's
/// own files, run.json, the manifest), with and without rewritten hashes, and each folder of
/// the dataset replaced by a link.
fn cases(clean: &Path) -> Vec<Case> {
    let mut targets = vec!["run.json".to_string(), "manifest.jsonl".to_string()];
    targets.extend(
        common::manifest_files(clean)
            .into_iter()
            .filter(|f| !f.contains("_01")),
    );
    let mut cases = Vec::new();
    for target in &targets {
        for harm in HARMS {
            for rehash in [false, true] {
                if rehash && (harm.is_entry() || !target.starts_with("samples/")) {
                    continue;
                }
                cases.push(Case {
                    target: target.clone(),
                    harm,
                    rehash,
                });
            }
        }
    }
    for folder in ["samples", "samples/0000"] {
        cases.push(Case {
            target: folder.to_string(),
            harm: Harm::LinkOutside,
            rehash: false,
        });
    }
    cases
}

/// What went wrong with one command on one hostile dataset, if anything.
fn judge(
    case: &Case,
    args: &[String],
    out: &Path,
    output: &Output,
    finished: bool,
) -> Option<String> {
    let err = stderr(output);
    let code = output.status.code();
    let resized = matches!(case.harm, Harm::Truncated | Harm::Emptied | Harm::Grown);
    // Refused whatever the command: a link, FIFO or folder where a file belongs; with the
    // hashes as written, a file whose size changed (every reader checks sizes on opening),
    // and any change at all for `verify`. A same-size change to a file a command does not
    // read (an RGB image for `export --format png16`) may pass.
    let must_fail = case.harm.is_entry()
        || !case.target.starts_with("samples/")
        || (!case.rehash && (resized || args[0] == "verify"));
    let trouble = if !finished {
        Some("did not finish within its time limit".to_string())
    } else if let Some(signal) = output.status.signal() {
        Some(format!("killed by signal {signal} (abort?)"))
    } else if err.contains("panicked") || err.contains("memory allocation") {
        Some("panicked or failed to allocate".to_string())
    } else if !matches!(code, Some(0) | Some(1)) {
        Some(format!("exit code {code:?}"))
    } else if code == Some(1) && !err.contains("error") {
        Some("failed without saying why".to_string())
    } else if files_below(out).iter().any(|(_, b)| contains(b, SECRET)) {
        Some("a file from outside the dataset is in the output".to_string())
    } else if must_fail && code != Some(1) {
        Some("a hostile file was not refused".to_string())
    } else if code == Some(1) && (out.exists() || staging_left(out)) {
        Some("an output was left behind after the error".to_string())
    } else {
        None
    };
    trouble.map(|t| format!("{case:?} `shmgen {}`: {t}\n{err}", args.join(" ")))
}

fn staging_left(out: &Path) -> bool {
    let name = out.file_name().unwrap().to_string_lossy().to_string();
    fs::read_dir(out.parent().unwrap()).unwrap().any(|e| {
        e.unwrap()
            .file_name()
            .to_string_lossy()
            .starts_with(&format!(".{name}"))
    })
}

#[test]
fn every_reader_survives_every_hostile_file_of_a_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let clean = dir.path().join("clean");
    let recipe = common::write(dir.path(), "every_output.rhai", RECIPE);
    common::ok(common::run(&recipe, &clean, &[]));
    let secret = dir.path().join("secret.txt");
    fs::write(&secret, SECRET).unwrap();

    let mut all = cases(&clean);
    if let Some(n) = std::env::var("SHMGEN_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
    {
        all.truncate(n);
    }
    let (queue, failures) = (
        Mutex::new(all.into_iter().enumerate()),
        Mutex::new(Vec::new()),
    );
    let runs = Mutex::new(0usize);
    let started = Instant::now();
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| {
                loop {
                    let Some((i, case)) = queue.lock().unwrap().next() else {
                        return;
                    };
                    let data = dir.path().join(format!("d{i}"));
                    copy_tree(&clean, &data);
                    if !harm(&data, &secret.with_extension(format!("{i}")), &case) {
                        fs::remove_dir_all(&data).unwrap();
                        continue;
                    }
                    if matches!(case.harm, Harm::LinkOutside) {
                        fs::write(secret.with_extension(format!("{i}")), SECRET).unwrap();
                    }
                    let out = dir.path().join(format!("o{i}"));
                    for args in commands(&data, &out) {
                        let (output, finished) = limited(&args, Duration::from_secs(60));
                        *runs.lock().unwrap() += 1;
                        if let Some(f) = judge(&case, &args, &out, &output, finished) {
                            failures.lock().unwrap().push(f);
                        }
                        let _ = fs::remove_dir_all(&out);
                    }
                    let _ = fs::remove_dir_all(&data);
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    eprintln!(
        "{} commands on hostile datasets in {:.1} s",
        runs.into_inner().unwrap(),
        started.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
