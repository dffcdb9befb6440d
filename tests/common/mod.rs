//! Helpers the integration tests share: running the binary and reading what it wrote.
#![allow(dead_code)] // each test crate uses its own subset

use serde_json::Value;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

pub const BIN: &str = env!("CARGO_BIN_EXE_shmgen");

/// The files of `dir` with extension `extension`, by name.
pub fn files_with_extension(dir: &Path, extension: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == extension))
        .collect();
    files.sort();
    files
}

/// The `*.rhai` files of the repository's folder `folder` (`scripts`, `stdlib`), by name.
pub fn bundled_rhai(folder: &str) -> Vec<PathBuf> {
    files_with_extension(&Path::new(env!("CARGO_MANIFEST_DIR")).join(folder), "rhai")
}

/// Writes `bytes` to `dir/name`, creating folders on the way.
pub fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, bytes).unwrap();
    path
}

/// Linear → sRGB 0–255 (unrounded).
pub fn encoded(l: f64) -> f64 {
    let l = l.clamp(0.0, 1.0);
    255.0
        * if l <= 0.003_130_8 {
            12.92 * l
        } else {
            1.055 * l.powf(1.0 / 2.4) - 0.055
        }
}

/// The RGB of view `view` of sample 0 in dataset `out`.
pub fn rgb(out: &Path, view: u32) -> Vec<[u8; 3]> {
    let (_, _, channels, bytes) = read_png(&view_path(out, 0, view, None, "rgb.png"));
    assert_eq!(channels, 3);
    bytes.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// Pixels whose 3 × 3 neighbourhood has mask value `value` throughout (no anti-aliased edge).
pub fn inside(mask: &[u8], width: usize, value: u8) -> Vec<usize> {
    let height = mask.len() / width;
    (0..mask.len())
        .filter(|&i| {
            let (r, c) = (i / width, i % width);
            r > 0
                && c > 0
                && r + 1 < height
                && c + 1 < width
                && (r - 1..=r + 1)
                    .all(|rr| (c - 1..=c + 1).all(|cc| mask[rr * width + cc] == value))
        })
        .collect()
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

/// Asserts `record` (a view's JSON) is valid against the published view schema.
pub fn schema_valid(record: &Value) {
    let schema =
        read_json(&Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/schema/view.schema.json"));
    let validator = jsonschema::validator_for(&schema).unwrap();
    let errors: Vec<String> = validator
        .iter_errors(record)
        .map(|e| e.to_string())
        .collect();
    assert!(errors.is_empty(), "{errors:?}");
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

/// The depth channel `Y` of an OpenEXR file (OpenCV's grey), through the `exr` crate's reader.
pub fn read_exr(path: &Path) -> Vec<f32> {
    use exr::prelude::*;
    let image = read_first_flat_layer_from_file(path).unwrap();
    let channels = &image.layer_data.channel_data.list;
    assert_eq!(channels.len(), 1);
    assert_eq!(channels[0].name, Text::from("Y"));
    channels[0].sample_data.values_as_f32().collect()
}

/// Every channel of an OpenEXR file by name, each as float32, through the `exr` crate's
/// reader; with the image's (width, height).
pub fn read_exr_channels(path: &Path) -> ((usize, usize), BTreeMap<String, Vec<f32>>) {
    use exr::prelude::*;
    let image = read_first_flat_layer_from_file(path).unwrap();
    let size = image.layer_data.size;
    let channels = image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| {
            assert!(matches!(c.sample_data, FlatSamples::F32(_)), "float32 only");
            (c.name.to_string(), c.sample_data.values_as_f32().collect())
        })
        .collect();
    ((size.width(), size.height()), channels)
}

/// A PLY file through the `ply-rs-bw` crate: every element's rows.
pub fn read_ply(
    path: &Path,
) -> std::collections::HashMap<String, Vec<ply_rs_bw::ply::DefaultElement>> {
    let parser = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new();
    let mut file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    parser
        .read_ply(&mut file)
        .unwrap()
        .payload
        .into_iter()
        .collect()
}

/// A sample's own file of `kind` (`mesh.ply`, ...) in dataset `out`.
pub fn sample_path(out: &Path, sample: u64, kind: &str) -> PathBuf {
    out.join(format!("samples/{:04}/{sample:06}.{kind}", sample / 1000))
}

/// A view's file of `kind` in dataset `out` (copy k of a view is `…a{k}`).
pub fn view_path(out: &Path, sample: u64, view: u32, copy: Option<u32>, kind: &str) -> PathBuf {
    let copy = copy.map(|k| format!("a{k}")).unwrap_or_default();
    out.join(format!(
        "samples/{:04}/{sample:06}_{view:02}{copy}.{kind}",
        sample / 1000
    ))
}

/// A written view of sample 0: its depth, mask and record.
pub struct View {
    pub width: usize,
    pub height: usize,
    pub depth: Vec<f32>,
    pub mask: Vec<u8>,
    pub json: Value,
}

/// View `view` (copy `copy`) of sample 0 in dataset `out`.
pub fn load(out: &Path, view: u32, copy: Option<u32>) -> View {
    let json = read_json(&view_path(out, 0, view, copy, "json"));
    let (width, height, _, mask) = read_png(&view_path(out, 0, view, copy, "mask.png"));
    View {
        width,
        height,
        depth: read_exr(&view_path(out, 0, view, copy, "depth.exr")),
        mask,
        json,
    }
}

/// A row-major matrix of the JSON.
pub fn matrix<const R: usize, const C: usize>(value: &Value) -> [[f64; C]; R] {
    std::array::from_fn(|i| std::array::from_fn(|j| value[i][j].as_f64().unwrap()))
}

impl View {
    pub fn k(&self) -> [[f64; 3]; 3] {
        matrix(&self.json["camera"]["K"])
    }

    pub fn c2w(&self) -> [[f64; 4]; 4] {
        matrix(&self.json["camera"]["c2w_opencv"])
    }

    pub fn w2c(&self) -> [[f64; 4]; 4] {
        matrix(&self.json["camera"]["w2c_opencv"])
    }

    /// The world point pixel (row, col) sees, back-projected with the written K and pose
    /// (pinhole).
    pub fn point(&self, row: usize, col: usize) -> Option<[f64; 3]> {
        let z = f64::from(self.depth[row * self.width + col]);
        (z > 0.0).then(|| {
            let k = self.k();
            let (u, v) = (col as f64 + 0.5, row as f64 + 0.5);
            let cam = [(u - k[0][2]) * z / k[0][0], (v - k[1][2]) * z / k[1][1], z];
            transform(&self.c2w(), cam)
        })
    }

    /// The lens of the view, (k1, k2, p1, p2, k3) (all zero for a pinhole).
    pub fn lens(&self) -> [f64; 5] {
        let d = &self.json["camera"]["distortion"];
        ["k1", "k2", "p1", "p2", "k3"].map(|k| d[k].as_f64().unwrap())
    }

    /// The undistorted normalised coordinates of pixel (row, col)'s centre, through the
    /// written K and lens with OpenCV's undistortion.
    pub fn ray(&self, row: usize, col: usize) -> (f64, f64) {
        let k = self.k();
        let (xd, yd) = (
            (col as f64 + 0.5 - k[0][2]) / k[0][0],
            (row as f64 + 0.5 - k[1][2]) / k[1][1],
        );
        undistort(&self.lens(), xd, yd)
    }

    /// The world point pixel (row, col) sees, back-projected with the written K, lens and pose.
    pub fn point_through_lens(&self, row: usize, col: usize) -> Option<[f64; 3]> {
        let z = f64::from(self.depth[row * self.width + col]);
        let (x, y) = self.ray(row, col);
        (z > 0.0).then(|| transform(&self.c2w(), [x * z, y * z, z]))
    }

    /// Where world point `p` projects through the written pose, lens and K.
    pub fn project_through_lens(&self, p: [f64; 3]) -> [f64; 2] {
        let k = self.k();
        let c = transform(&self.w2c(), p);
        let (x, y) = distort(&self.lens(), c[0] / c[2], c[1] / c[2]);
        [k[0][0] * x + k[0][2], k[1][1] * y + k[1][2]]
    }

    /// Where world point `p` projects (pinhole), with its planar depth.
    pub fn project(&self, p: [f64; 3]) -> ([f64; 2], f64) {
        let k = self.k();
        let c = transform(&self.w2c(), p);
        (
            [
                k[0][0] * c[0] / c[2] + k[0][2],
                k[1][1] * c[1] / c[2] + k[1][2],
            ],
            c[2],
        )
    }

    /// Whether pixel (row, col) and its 8 neighbours all see a structure.
    pub fn inside(&self, row: usize, col: usize) -> bool {
        (row > 0 && col > 0 && row + 1 < self.height && col + 1 < self.width)
            && (row - 1..=row + 1)
                .all(|r| (col - 1..=col + 1).all(|c| self.mask[r * self.width + c] == 255))
    }
}

/// OpenCV's undistortPoints iteration (its documentation's model, solved by fixed point):
/// x ← (x_d − δ(x)) / radial(x), independent of shmgen's Newton solver. `d` is
/// (k1, k2, p1, p2, k3).
pub fn undistort(d: &[f64; 5], xd: f64, yd: f64) -> (f64, f64) {
    let (mut x, mut y) = (xd, yd);
    for _ in 0..200 {
        let (radial, dx, dy) = distortion_terms(d, x, y);
        (x, y) = ((xd - dx) / radial, (yd - dy) / radial);
    }
    (x, y)
}

/// OpenCV's distortion of normalised coordinates (x, y): x·radial + δx, y·radial + δy.
pub fn distort(d: &[f64; 5], x: f64, y: f64) -> (f64, f64) {
    let (radial, dx, dy) = distortion_terms(d, x, y);
    (x * radial + dx, y * radial + dy)
}

/// The radial factor and tangential terms of OpenCV's model at (x, y).
fn distortion_terms(d: &[f64; 5], x: f64, y: f64) -> (f64, f64, f64) {
    let [k1, k2, p1, p2, k3] = *d;
    let r2 = x * x + y * y;
    let radial = 1.0 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
    let dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    let dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    (radial, dx, dy)
}

/// How far `p` is from the surface of the box [−half, half], metres, inside or out.
pub fn off_box(p: [f64; 3], half: [f64; 3]) -> f64 {
    let outside = (0..3)
        .map(|i| (p[i].abs() - half[i]).max(0.0).powi(2))
        .sum::<f64>()
        .sqrt();
    let inside = (0..3)
        .map(|i| half[i] - p[i].abs())
        .fold(f64::INFINITY, f64::min)
        .max(0.0);
    outside.max(inside)
}

/// `m · [p, 1]`, the first three rows.
pub fn transform(m: &[[f64; 4]; 4], p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3])
}

/// Runs `recipe` (written to a temporary folder) into `out` there; returns the folder (removed
/// when dropped) and `out`.
pub fn render(recipe: &str, extra: &[&str]) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "recipe.rhai", recipe);
    let out = dir.path().join("out");
    ok(run(&path, &out, extra));
    (dir, out)
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

/// A PNG's IHDR width and height set to `width × height` (its CRC made right again), the
/// image data left as it was: a header a careless reader allocates by. False if `bytes` is
/// not a PNG.
pub fn inflate_png(bytes: &mut [u8], width: u32, height: u32) -> bool {
    if bytes.len() < 33 || &bytes[12..16] != b"IHDR" {
        return false;
    }
    bytes[16..20].copy_from_slice(&width.to_be_bytes());
    bytes[20..24].copy_from_slice(&height.to_be_bytes());
    let crc = crc32(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    true
}

/// CRC-32 as PNG defines it (ISO 3309), bit by bit: no table needed for one chunk.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Kills `child` (SIGKILL) once the dataset it writes into `out` lists `samples` samples in
/// its manifest (or after a minute); returns how many it lists then.
pub fn kill_after_samples(mut child: std::process::Child, out: &Path, samples: usize) -> usize {
    let manifest = out.join("manifest.jsonl");
    let lines = || {
        std::fs::read_to_string(&manifest)
            .map(|t| t.lines().count())
            .unwrap_or(0)
    };
    let deadline = Instant::now() + Duration::from_secs(60);
    while lines() < samples && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    lines()
}

/// `shmgen run RECIPE --out OUT EXTRA...` started in the background, its output discarded.
pub fn spawn_run(recipe: &Path, out: &Path, extra: &[&str]) -> std::process::Child {
    Command::new(BIN)
        .arg("run")
        .arg(recipe)
        .arg("--out")
        .arg(out)
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap()
}

/// The files of view 0 of sample 0 a damage test reads, and each seen pixel's rest point.
pub struct DamageView {
    /// Image width, pixels.
    pub width: usize,
    /// Intrinsics and camera-to-world (OpenCV axes) from the view's JSON.
    pub k: [[f64; 3]; 3],
    pub c2w: [[f64; 4]; 4],
    pub depth: Vec<f32>,
    pub class: Vec<u8>,
    pub instance: Vec<u16>,
    pub rgb: Vec<u8>,
    /// World rest point (the back-projected hit minus the written displacement) of every
    /// pixel with a finite positive depth.
    pub rest: Vec<Option<[f64; 3]>>,
}

impl DamageView {
    /// The camera centre and pixel `i`'s ray through its centre (camera z = 1, world
    /// coordinates: the ray's parameter is the planar depth).
    pub fn ray(&self, i: usize) -> ([f64; 3], [f64; 3]) {
        let origin = transform(&self.c2w, [0.0; 3]);
        let (row, col) = ((i / self.width) as f64, (i % self.width) as f64);
        let cam = [
            (col + 0.5 - self.k[0][2]) / self.k[0][0],
            (row + 0.5 - self.k[1][2]) / self.k[1][1],
            1.0,
        ];
        let p = transform(&self.c2w, cam);
        (origin, std::array::from_fn(|a| p[a] - origin[a]))
    }
}

/// Reads view 0 of sample 0 of `out` (depth, displacement, damage layers, RGB, camera).
pub fn damage_view(out: &Path) -> DamageView {
    let file = |kind: &str| view_path(out, 0, 0, None, kind);
    let json = read_json(&file("json"));
    let k: [[f64; 3]; 3] = matrix(&json["camera"]["K"]);
    let c2w: [[f64; 4]; 4] = matrix(&json["camera"]["c2w_opencv"]);
    let depth = read_exr(&file("depth.exr"));
    let (_, disp) = read_exr_channels(&file("displacement.exr"));
    let (width, _, _, class) = read_png(&file("damage_class.png"));
    let (_, _, instance) = read_png16(&file("damage_instance.png"));
    let (_, _, _, rgb) = read_png(&file("rgb.png"));
    let rest = depth
        .iter()
        .enumerate()
        .map(|(i, &z)| {
            (z > 0.0 && z.is_finite()).then(|| {
                let (row, col) = ((i / width) as f64, (i % width) as f64);
                let z = f64::from(z);
                let cam = [
                    (col + 0.5 - k[0][2]) * z / k[0][0],
                    (row + 0.5 - k[1][2]) * z / k[1][1],
                    z,
                ];
                let world = transform(&c2w, cam);
                let d = ["R", "G", "B"].map(|c| f64::from(disp[c][i]));
                std::array::from_fn(|a| world[a] - d[a])
            })
        })
        .collect();
    DamageView {
        width,
        k,
        c2w,
        depth,
        class,
        instance,
        rgb,
        rest,
    }
}

/// A `.npy` file (format 1.0, C order) laid out by hand from NumPy's NEP 1.
pub fn write_npy(path: &Path, descr: &str, shape: &[usize], data: &[u8]) {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': False, 'shape': ({}{}), }}",
        dims.join(", "),
        if shape.len() == 1 { "," } else { "" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend_from_slice(data);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, bytes).unwrap();
}
