//! Helpers the integration tests share: running the binary and reading what it wrote.
#![allow(dead_code)] // each test crate uses its own subset

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

pub const BIN: &str = env!("CARGO_BIN_EXE_shmgen");

/// Writes `bytes` to `dir/name`, creating folders on the way.
pub fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, bytes).unwrap();
    path
}

/// `shmgen run RECIPE --out OUT --quiet EXTRA...`.
pub fn run(recipe: &Path, out: &Path, extra: &[&str]) -> Output {
    Command::new(BIN)
        .arg("run")
        .arg(recipe)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap()
}

/// `shmgen ARGS...`, killed if it runs longer than `limit`; returns what it printed and
/// whether it finished by itself.
pub fn run_limited(limit: Duration, args: &[&std::ffi::OsStr]) -> (Output, bool) {
    let mut child = Command::new(BIN)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Drained while the child runs, so that it never blocks on a full pipe.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            pipe.unwrap().read_to_end(&mut bytes).unwrap();
            bytes
        })
    };
    let stdout = drain(child.stdout.take().map(|p| Box::new(p) as _));
    let stderr = drain(child.stderr.take().map(|p| Box::new(p) as _));
    let start = Instant::now();
    let (status, finished) = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break (status, true);
        }
        if start.elapsed() > limit {
            child.kill().unwrap();
            break (child.wait().unwrap(), false);
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let output = Output {
        status,
        stdout: stdout.join().unwrap(),
        stderr: stderr.join().unwrap(),
    };
    (output, finished)
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).to_string()
}

pub fn ok(output: Output) -> Output {
    assert!(
        output.status.success(),
        "shmgen failed:\n{}",
        stderr(&output)
    );
    output
}

/// blake3 of every file under `root`, by relative path.
pub fn hashes(root: &Path) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path.strip_prefix(root).unwrap().display().to_string();
                out.insert(rel, blake3_hex(&std::fs::read(&path).unwrap()));
            }
        }
    }
    out
}

pub fn blake3_hex(bytes: &[u8]) -> String {
    blake3::hash(bytes).to_hex().to_string()
}

pub fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// A PNG through the `png` crate: its frame information and bytes.
fn decode_png(path: &Path) -> (png::OutputInfo, Vec<u8>) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info, buf)
}

/// 8-bit PNG through the `png` crate: (width, height, channels, samples).
pub fn read_png(path: &Path) -> (usize, usize, usize, Vec<u8>) {
    let (info, buf) = decode_png(path);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let (w, h) = (info.width as usize, info.height as usize);
    (w, h, buf.len() / (w * h), buf)
}

/// The depth channel `Z` of an OpenEXR file, through the `exr` crate's reader.
pub fn read_exr(path: &Path) -> Vec<f32> {
    use exr::prelude::*;
    let image = read_first_flat_layer_from_file(path).unwrap();
    let channels = &image.layer_data.channel_data.list;
    assert_eq!(channels.len(), 1);
    assert_eq!(channels[0].name, Text::from("Z"));
    channels[0].sample_data.values_as_f32().collect()
}

/// A view's file of `kind` in dataset `out` (copy k of a view is `…a{k}`).
pub fn view_path(out: &Path, sample: u64, view: u32, copy: Option<u32>, kind: &str) -> PathBuf {
    let copy = copy.map(|k| format!("a{k}")).unwrap_or_default();
    out.join(format!(
        "samples/{:04}/{sample:06}_{view:02}{copy}.{kind}",
        sample / 1000
    ))
}

/// `scripts/quickstart.rhai` run into `dir/name` with `--set` values such as `samples=2`.
pub fn quickstart(dir: &Path, name: &str, sets: &[&str]) -> PathBuf {
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/quickstart.rhai");
    let out = dir.join(name);
    let mut extra = Vec::new();
    for set in sets {
        extra.extend(["--set", set]);
    }
    ok(run(&recipe, &out, &extra));
    out
}

/// Every file `manifest.jsonl` of dataset `out` lists, in its order.
pub fn manifest_files(out: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(out.join("manifest.jsonl")).unwrap();
    text.lines()
        .flat_map(|line| {
            let v: serde_json::Value = serde_json::from_str(line).unwrap();
            v["files"]
                .as_array()
                .unwrap()
                .iter()
                .map(|f| f.as_str().unwrap().to_string())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// A 16-bit grey PNG through the `png` crate: (width, height, samples).
pub fn read_png16(path: &Path) -> (usize, usize, Vec<u16>) {
    let (info, buf) = decode_png(path);
    assert_eq!(
        (info.bit_depth, info.color_type),
        (png::BitDepth::Sixteen, png::ColorType::Grayscale)
    );
    let values = buf
        .chunks_exact(2)
        .map(|b| u16::from_be_bytes([b[0], b[1]]))
        .collect();
    (info.width as usize, info.height as usize, values)
}

/// `shmgen ARGS...`.
pub fn shmgen(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}
