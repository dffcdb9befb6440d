//! `shmgen eval` end to end: predictions made here from a dataset's truth by known changes
//! (identity, a scale, a shift, a constant offset), whose metrics have closed forms computed
//! here; the same prediction as EXR, .npy and millimetre PNG; meshes and point clouds against a
//! ground-truth mesh; and the errors a wrong prediction gets.

use serde_json::Value;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Output;

mod common;

use common::{
    blake3_hex, manifest_files, ok, quickstart, read_exr, read_png, read_png16, shmgen, stderr,
    view_path, write_npy,
};

/// `shmgen eval DATA PREDICTIONS --json … EXTRA`, which must score everything (exit 0): what
/// it printed and the JSON report.
fn eval(data: &Path, predictions: &Path, extra: &[&str]) -> (Output, Value) {
    let (output, report) = eval_any(data, predictions, extra);
    (ok(output), report)
}

/// `shmgen eval DATA PREDICTIONS --json … EXTRA` whatever its exit code: what it printed
/// and the JSON report.
fn eval_any(data: &Path, predictions: &Path, extra: &[&str]) -> (Output, Value) {
    let json = predictions.with_extension("report.json");
    let _ = std::fs::remove_file(&json);
    let mut args: Vec<&OsStr> = vec![
        OsStr::new("eval"),
        data.as_os_str(),
        predictions.as_os_str(),
        OsStr::new("--json"),
        json.as_os_str(),
    ];
    args.extend(extra.iter().map(OsStr::new));
    let output = shmgen(&args);
    let report = match std::fs::read(&json) {
        Ok(bytes) => serde_json::from_slice(&bytes).unwrap(),
        Err(_) => panic!("no report: {}", stderr(&output)),
    };
    (output, report)
}

/// `eval_any` of a partial evaluation: exit code 2.
fn eval_partial(data: &Path, predictions: &Path, extra: &[&str]) -> (Output, Value) {
    let (output, report) = eval_any(data, predictions, extra);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert_eq!(report["complete"], false, "{report}");
    (output, report)
}

fn eval_err(data: &Path, predictions: &Path, extra: &[&str]) -> String {
    let mut args: Vec<&OsStr> = vec![
        OsStr::new("eval"),
        data.as_os_str(),
        predictions.as_os_str(),
    ];
    args.extend(extra.iter().map(OsStr::new));
    let output = shmgen(&args);
    assert!(!output.status.success());
    stderr(&output)
}

fn f(report: &Value, key: &str) -> f64 {
    report[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} in {report}"))
}

fn write_file(path: &Path, bytes: &[u8]) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, bytes).unwrap();
}

/// An EXR of f32 channels through the `exr` crate.
fn write_exr(path: &Path, w: usize, h: usize, channels: &[(&str, Vec<f32>)]) {
    use exr::prelude::*;
    let list: Vec<AnyChannel<FlatSamples>> = channels
        .iter()
        .map(|(name, v)| AnyChannel::new(*name, FlatSamples::F32(v.clone())))
        .collect();
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(list)),
    );
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_file(path)
        .unwrap();
}

fn write_png(path: &Path, w: usize, h: usize, depth: png::BitDepth, data: &[u8]) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let mut encoder = png::Encoder::new(std::fs::File::create(path).unwrap(), w as u32, h as u32);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(depth);
    encoder
        .write_header()
        .unwrap()
        .write_image_data(data)
        .unwrap();
}

/// One view's truth, read with the test's own readers.
struct Truth {
    stem: String,
    sample: u64,
    view: u32,
    w: usize,
    h: usize,
    depth: Vec<f32>,
    mask: Vec<u8>,
}

impl Truth {
    /// Where its prediction of `kind` goes under `predictions/samples/`.
    fn prediction(&self, predictions: &Path, kind: &str) -> PathBuf {
        predictions.join(format!("samples/0000/{}.{kind}", self.stem))
    }

    /// Pixels scored with the structure mask.
    fn inside(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.depth.len()).filter(|&i| self.mask[i] > 0 && self.depth[i] > 0.0)
    }
}

fn truths(data: &Path) -> Vec<Truth> {
    let mut out = Vec::new();
    for file in manifest_files(data) {
        let Some(stem) = file.rsplit('/').next().unwrap().strip_suffix(".depth.exr") else {
            continue;
        };
        let (s, v) = stem.split_once('_').unwrap();
        let (sample, view) = (s.parse().unwrap(), v.parse().unwrap());
        let (w, h, _, mask) = read_png(&view_path(data, sample, view, None, "mask.png"));
        out.push(Truth {
            stem: stem.to_string(),
            sample,
            view,
            w,
            h,
            depth: read_exr(&view_path(data, sample, view, None, "depth.exr")),
            mask,
        });
    }
    out
}

/// Mean over images of a per-image statistic of (prediction, truth) over the scored pixels.
fn per_image(truths: &[Truth], stat: impl Fn(&Truth) -> f64) -> f64 {
    truths.iter().map(stat).sum::<f64>() / truths.len() as f64
}

#[test]
fn depth_metrics_have_their_closed_forms() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=2", "views=2"]);
    let truths = truths(&data);
    assert_eq!(truths.len(), 4);
    let pixels: usize = truths.iter().map(|t| t.inside().count()).sum();

    // The truth itself.
    let same = dir.path().join("same");
    for t in &truths {
        write_exr(
            &t.prediction(&same, "depth.exr"),
            t.w,
            t.h,
            &[("Z", t.depth.clone())],
        );
    }
    let (_, r) = eval(&data, &same, &[]);
    for key in ["abs_rel", "sq_rel", "rmse", "rmse_log"] {
        assert_eq!(f(&r, key), 0.0, "{key}");
    }
    for key in ["delta1", "delta2", "delta3"] {
        assert_eq!(f(&r, key), 1.0, "{key}");
    }
    assert_eq!(r["depth_counts"]["images"], 4);
    assert_eq!(r["depth_counts"]["pixels"], pixels);

    // 1.1 × the truth: AbsRel 0.1, SqRel 0.01·mean d*, RMSE 0.1·RMS(d*), per image.
    let scaled = dir.path().join("scaled");
    let times = |t: &Truth| -> Vec<f32> { t.depth.iter().map(|&d| d * 1.1).collect() };
    for t in &truths {
        write_exr(
            &t.prediction(&scaled, "depth.exr"),
            t.w,
            t.h,
            &[("Z", times(t))],
        );
    }
    let (_, r) = eval(&data, &scaled, &[]);
    let mean_of = |t: &Truth, g: &dyn Fn(f64) -> f64| {
        t.inside().map(|i| g(f64::from(t.depth[i]))).sum::<f64>() / t.inside().count() as f64
    };
    let rms = per_image(&truths, |t| 0.1 * mean_of(t, &|d| d * d).sqrt());
    let sq_rel = per_image(&truths, |t| 0.01 * mean_of(t, &|d| d));
    assert!((f(&r, "abs_rel") - 0.1).abs() < 1e-6, "{r}");
    assert!(
        (f(&r, "rmse") - rms).abs() < 1e-6 * rms,
        "{} vs {rms}",
        f(&r, "rmse")
    );
    assert!((f(&r, "sq_rel") - sq_rel).abs() < 1e-6 * sq_rel);
    assert!((f(&r, "rmse_log") - 1.1f64.ln()).abs() < 1e-6);
    assert_eq!(f(&r, "delta1"), 1.0);

    // Alignment recovers the 1.1.
    for align in ["median", "lstsq", "lstsq_shift"] {
        let (_, a) = eval(&data, &scaled, &["--align", align]);
        for key in ["abs_rel", "sq_rel", "rmse", "rmse_log"] {
            assert!(f(&a, key) < 1e-6, "{align}: {key} = {}", f(&a, key));
        }
        assert!((f(&a, "align_scale") - 1.0 / 1.1).abs() < 1e-6, "{align}");
    }

    // The same values as .npy float32 give the same report; float64 gives exactly 0.1.
    let npy = dir.path().join("npy32");
    for t in &truths {
        let bytes: Vec<u8> = times(t).iter().flat_map(|v| v.to_le_bytes()).collect();
        write_npy(&t.prediction(&npy, "depth.npy"), "<f4", &[t.h, t.w], &bytes);
    }
    let (_, n) = eval(&data, &npy, &[]);
    for key in ["abs_rel", "sq_rel", "rmse", "rmse_log", "delta1"] {
        assert_eq!(n[key], r[key], "{key}");
    }
    let npy64 = dir.path().join("npy64");
    for t in &truths {
        let bytes: Vec<u8> = t
            .depth
            .iter()
            .flat_map(|&v| (f64::from(v) * 1.1).to_le_bytes())
            .collect();
        write_npy(
            &t.prediction(&npy64, "depth.npy"),
            "<f8",
            &[t.h, t.w, 1],
            &bytes,
        );
    }
    let (_, n) = eval(&data, &npy64, &[]);
    assert!((f(&n, "abs_rel") - 0.1).abs() < 1e-12);

    // Millimetre PNGs (the dataset's own depth, exported) agree with EXRs of the same values.
    let png16 = dir.path().join("png16");
    let args = ["export", "--format", "png16", "--out"].map(OsStr::new);
    ok(shmgen(&[
        args[0],
        data.as_os_str(),
        args[1],
        args[2],
        args[3],
        png16.as_os_str(),
    ]));
    let (_, p) = eval(&data, &png16, &[]);
    let as_exr = dir.path().join("mm_exr");
    for t in &truths {
        let (_, _, mm) = read_png16(&view_path(&png16, t.sample, t.view, None, "depth_mm.png"));
        let metres: Vec<f32> = mm.iter().map(|&m| (f64::from(m) / 1000.0) as f32).collect();
        write_exr(
            &t.prediction(&as_exr, "depth.exr"),
            t.w,
            t.h,
            &[("Z", metres)],
        );
    }
    let (_, e) = eval(&data, &as_exr, &[]);
    for key in ["abs_rel", "sq_rel", "rmse", "rmse_log", "delta1"] {
        assert!((f(&p, key) - f(&e, key)).abs() < 1e-6, "{key}");
    }
    // Half a millimetre at most, relative to the depth.
    let bound = per_image(&truths, |t| mean_of(t, &|d| 0.0005 / d));
    assert!(f(&p, "abs_rel") > 0.0 && f(&p, "abs_rel") <= bound + 1e-9);

    // A missing view and non-finite predicted pixels are left out, counted and reported.
    let holes = dir.path().join("holes");
    for t in &truths[1..] {
        let mut z = times(t);
        let first: Vec<usize> = t.inside().take(7).collect();
        for &i in &first {
            z[i] = f32::NAN;
        }
        write_exr(&t.prediction(&holes, "depth.exr"), t.w, t.h, &[("Z", z)]);
    }
    let (o, h) = eval_partial(&data, &holes, &[]);
    assert_eq!(h["depth_counts"]["missing"], 1);
    assert_eq!(h["depth_counts"]["excluded_pixels"], 21);
    assert!(
        stderr(&o).contains(&format!(
            "warning: depth: 1 views not scored: no prediction (e.g. {})",
            truths[0].stem
        )),
        "{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("warning: depth: 21 pixels left out (not predicted"));
}

/// A binary little-endian PLY with double x, y, z and `list uchar int` faces.
fn ply(vertices: &[[f64; 3]], faces: &[[i32; 3]]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        vertices.len(),
        faces.len()
    )
    .into_bytes();
    for v in vertices {
        for c in v {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for face in faces {
        out.push(3);
        for i in face {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
}

/// A grid of n × n vertices over the unit square at height z, two triangles per cell.
fn grid(n: usize, z: f64) -> (Vec<[f64; 3]>, Vec<[i32; 3]>) {
    let step = 1.0 / (n - 1) as f64;
    let vertices = (0..n * n)
        .map(|k| [(k % n) as f64 * step, (k / n) as f64 * step, z])
        .collect();
    let mut faces = Vec::new();
    for r in 0..n - 1 {
        for c in 0..n - 1 {
            let k = (r * n + c) as i32;
            let n = n as i32;
            faces.push([k, k + 1, k + n + 1]);
            faces.push([k, k + n + 1, k + n]);
        }
    }
    (vertices, faces)
}

/// Adds `file` (relative) to sample `sample`'s line of the manifest, if it is not listed:
/// what a generator writing that output would have listed.
fn list_in_manifest(data: &Path, sample: u64, file: &str) {
    let path = data.join("manifest.jsonl");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = Vec::new();
    for line in text.lines() {
        let mut v: Value = serde_json::from_str(line).unwrap();
        let files = v["files"].as_array_mut().unwrap();
        if v_sample(line) == sample && !files.iter().any(|f| f == file) {
            files.push(Value::from(file));
        }
        lines.push(serde_json::to_string(&v).unwrap());
    }
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
}

fn v_sample(line: &str) -> u64 {
    serde_json::from_str::<Value>(line).unwrap()["sample"]
        .as_u64()
        .unwrap()
}

#[test]
fn chamfer_and_fscore_have_their_closed_forms() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=1"]);
    // The ground truth: an 11 × 11 grid over the unit square (0.1 m cells).
    let (vertices, faces) = grid(11, 0.0);
    write_file(
        &data.join("samples/0000/000000.mesh.ply"),
        &ply(&vertices, &faces),
    );
    list_in_manifest(&data, 0, "samples/0000/000000.mesh.ply");
    let surface = |name: &str, file: &str, bytes: Vec<u8>, extra: &[&str]| {
        let predictions = dir.path().join(name);
        write_file(&predictions.join("0000").join(file), &bytes);
        eval(&data, &predictions, extra).1["surface"].clone()
    };
    // The mesh itself.
    let s = surface("itself", "000000.ply", ply(&vertices, &faces), &[]);
    assert!(
        f(&s, "chamfer_l1") < 1e-12 && f(&s, "chamfer_l2") < 1e-20,
        "{s}"
    );
    assert_eq!(f(&s, "fscore"), 1.0);
    // Its own vertices as a point cloud: on the surface (accuracy 0); every point of a cell
    // is within half its diagonal of a corner.
    let cloud = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nend_header\n{}",
        vertices.len(),
        vertices
            .iter()
            .map(|v| format!("{} {} {}\n", v[0], v[1], v[2]))
            .collect::<String>()
    );
    let s = surface("vertices", "000000.ply", cloud.into_bytes(), &[]);
    assert!(f(&s, "accuracy") < 1e-9, "{s}");
    let half_diagonal = 0.1 * 2f64.sqrt() / 2.0;
    assert!(f(&s, "completeness") > 0.0 && f(&s, "completeness") <= half_diagonal);
    // Shifted by h along the normal: every point is h from the other surface, both ways.
    let h = 0.02;
    let (lifted, _) = grid(11, h);
    for (name, file, bytes) in [
        ("lifted", "000000.ply", ply(&lifted, &faces)),
        ("lifted_obj", "000000.obj", obj(&lifted, &faces)),
    ] {
        let s = surface(name, file, bytes, &["--fscore-threshold", "0.03"]);
        assert!((f(&s, "chamfer_l1") - h).abs() < 1e-12, "{s}");
        assert!((f(&s, "chamfer_l2") - 2.0 * h * h).abs() < 1e-12);
        assert_eq!(f(&s, "fscore"), 1.0);
    }
    let s = surface(
        "lifted_tight",
        "000000.ply",
        ply(&lifted, &faces),
        &["--fscore-threshold", "0.01"],
    );
    assert_eq!(
        (f(&s, "precision"), f(&s, "recall"), f(&s, "fscore")),
        (0.0, 0.0, 0.0)
    );
    // A cloud with a point 1e200 m out (a unit slip): its squared distances overflowed and the
    // report said "Chamfer-L1 inf m" (null in the JSON). Now refused when read, saying where.
    let far = "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nend_header\n0.5 0.5 0\n0.5 0.5 1e200\n";
    let predictions = dir.path().join("far");
    write_file(&predictions.join("0000/000000.ply"), far.as_bytes());
    let e = eval_err(&data, &predictions, &[]);
    assert!(
        e.contains("000000.ply: vertex 1 is too large: (0.5, 0.5, 1e200)") && !e.contains("inf"),
        "{e}"
    );
}

fn obj(vertices: &[[f64; 3]], faces: &[[i32; 3]]) -> Vec<u8> {
    let mut out = String::new();
    for v in vertices {
        out += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for t in faces {
        out += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    out.into_bytes()
}

#[test]
fn end_point_error_of_a_constant_offset_is_its_norm() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=2"]);
    let truths = truths(&data);
    let predictions = dir.path().join("predictions");
    for t in &truths {
        // Truth written here where the dataset has none yet: some field, valid on the mask,
        // under the channel names of shmgen.view/1 datasets (U V, X Y Z), which eval still
        // reads; the predictions too.
        let flow_u: Vec<f32> = (0..t.w * t.h).map(|i| (i % t.w) as f32 * 0.01).collect();
        let flow_v: Vec<f32> = (0..t.w * t.h).map(|i| -((i / t.w) as f32) * 0.02).collect();
        let disp: Vec<Vec<f32>> = (0..3)
            .map(|c| {
                t.depth
                    .iter()
                    .map(|&d| d * 0.001 * (c + 1) as f32)
                    .collect()
            })
            .collect();
        let file = |kind: &str| format!("samples/0000/{}.{kind}", t.stem);
        let missing = |kind: &str| {
            let absent = !data.join(file(kind)).exists();
            if absent {
                list_in_manifest(&data, t.sample, &file(kind));
            }
            absent
        };
        if missing("flow.exr") {
            let uv = [("U", flow_u), ("V", flow_v)];
            write_exr(&data.join(file("flow.exr")), t.w, t.h, &uv);
        }
        if missing("flow_valid.png") {
            let path = data.join(file("flow_valid.png"));
            write_png(&path, t.w, t.h, png::BitDepth::Eight, &t.mask);
        }
        if missing("displacement.exr") {
            let xyz: Vec<(&str, Vec<f32>)> = ["X", "Y", "Z"].into_iter().zip(disp).collect();
            write_exr(&data.join(file("displacement.exr")), t.w, t.h, &xyz);
        }
        let read = |kind: &str, names: &[&str]| -> Vec<Vec<f32>> {
            use exr::prelude::*;
            let image = read_first_flat_layer_from_file(
                data.join(format!("samples/0000/{}.{kind}", t.stem)),
            )
            .unwrap();
            names
                .iter()
                .map(|n| {
                    let c = image
                        .layer_data
                        .channel_data
                        .list
                        .iter()
                        .find(|c| c.name == **n)
                        .unwrap();
                    c.sample_data.values_as_f32().collect()
                })
                .collect()
        };
        let flow = read("flow.exr", &["U", "V"]);
        let offset = [3.0f32, 4.0];
        let shifted: Vec<(&str, Vec<f32>)> = ["U", "V"]
            .iter()
            .zip(&flow)
            .zip(offset)
            .map(|((n, c), o)| (*n, c.iter().map(|v| v + o).collect()))
            .collect();
        write_exr(&t.prediction(&predictions, "flow.exr"), t.w, t.h, &shifted);
        let disp = read("displacement.exr", &["X", "Y", "Z"]);
        let offset = [0.001f32, 0.002, 0.002];
        // Interleaved H × W × 3, as NumPy stores an image of vectors.
        let bytes: Vec<u8> = (0..t.w * t.h)
            .flat_map(|i| {
                let disp = &disp;
                (0..3).map(move |c| f64::from(disp[c][i]) + f64::from(offset[c]))
            })
            .flat_map(|v| v.to_le_bytes())
            .collect::<Vec<u8>>();
        write_npy(
            &t.prediction(&predictions, "displacement.npy"),
            "<f8",
            &[t.h, t.w, 3],
            &bytes,
        );
    }
    let (_, r) = eval(&data, &predictions, &[]);
    let flow = &r["flow"];
    assert!(
        (f(flow, "epe_mean") - 5.0).abs() < 1e-5 && (f(flow, "epe_median") - 5.0).abs() < 1e-5,
        "{flow}"
    );
    let valid: usize = truths
        .iter()
        .map(|t| {
            let (_, _, _, v) =
                read_png(&data.join(format!("samples/0000/{}.flow_valid.png", t.stem)));
            v.iter().filter(|&&x| x > 0).count()
        })
        .sum();
    assert_eq!(flow["counts"]["pixels"], valid);
    let disp = &r["displacement"];
    assert!((f(disp, "epe_mean") - 0.003).abs() < 1e-7, "{disp}");
    let seen: usize = truths
        .iter()
        .map(|t| t.depth.iter().filter(|&&d| d > 0.0).count())
        .sum();
    assert_eq!(disp["counts"]["pixels"], seen);
    assert!(
        r["abs_rel"].is_null(),
        "no depth predicted, no depth metrics"
    );
}

#[test]
fn wrong_predictions_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=1"]);
    let p = dir.path().join("p");
    std::fs::create_dir(&p).unwrap();
    assert!(eval_err(&data, &p, &[]).contains("no prediction found"));
    let stem = p.join("0000/000000_00");
    write_exr(
        &stem.with_extension("depth.exr"),
        4,
        3,
        &[("Z", vec![1.0; 12])],
    );
    assert!(eval_err(&data, &p, &[]).contains("4×3 pixels, the view has 960×960"));
    write_npy(
        &stem.with_extension("depth.npy"),
        "<f4",
        &[960, 960],
        &vec![0; 960 * 960 * 4],
    );
    assert!(eval_err(&data, &p, &[]).contains("predict the same thing"));
    std::fs::remove_file(stem.with_extension("depth.exr")).unwrap();
    write_npy(
        &stem.with_extension("depth.npy"),
        "<i4",
        &[960, 960],
        &vec![0; 960 * 960 * 4],
    );
    assert!(eval_err(&data, &p, &[]).contains("not float32 or float64"));
    std::fs::remove_file(stem.with_extension("depth.npy")).unwrap();
    write_png(
        &stem.with_extension("depth.png"),
        960,
        960,
        png::BitDepth::Eight,
        &vec![1; 960 * 960],
    );
    assert!(eval_err(&data, &p, &[]).contains("an 8-bit PNG cannot hold millimetres"));
    assert!(
        eval_err(&data, &p, &["--align", "mean"])
            .contains("expected none, median, lstsq or lstsq_shift")
    );
    assert!(eval_err(&data, &p, &["--fscore-threshold=-1"]).contains("--fscore-threshold -1"));
    let unfinished = dir.path().join("empty");
    std::fs::create_dir(&unfinished).unwrap();
    assert!(eval_err(&unfinished, &p, &[]).contains("not a shmgen dataset"));
}

/// Replaces the dataset file `relative` with `bytes`, recording its new size and BLAKE3 in
/// the manifest as the generator would have.
fn replace_in_dataset(data: &Path, relative: &str, bytes: &[u8]) {
    write_file(&data.join(relative), bytes);
    let path = data.join("manifest.jsonl");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = Vec::new();
    for line in text.lines() {
        let mut v: Value = serde_json::from_str(line).unwrap();
        if let Some(check) = v["hashes"].get_mut(relative) {
            *check = serde_json::json!({"blake3": blake3_hex(bytes), "bytes": bytes.len()});
        }
        lines.push(serde_json::to_string(&v).unwrap());
    }
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
}

/// Every view's true depth replaced, where there is a surface, by 1 m plus a sawtooth of 160
/// steps of an eighth of a metre: values an f32 EXR, an f64 and a millimetre PNG all hold
/// exactly (so a prediction equal to the truth is equal in every format), spread evenly so
/// that a tenth of the pixels predicted as 0 m moves the median by several steps.
fn eighths_of_a_metre(data: &Path) -> Vec<Truth> {
    for t in truths(data) {
        let depth: Vec<f32> = (0..t.depth.len())
            .map(|i| match t.depth[i] > 0.0 {
                true => 1.0 + ((i * 7) % 160) as f32 / 8.0,
                false => 0.0,
            })
            .collect();
        let file = format!("samples/0000/{}.depth.exr", t.stem);
        let scratch = data.with_extension("scratch.exr");
        write_exr(&scratch, t.w, t.h, &[("Y", depth)]);
        replace_in_dataset(data, &file, &std::fs::read(&scratch).unwrap());
    }
    truths(data)
}

/// `prediction` (metres, NaN = not predicted) written for view `t` as `kind`: an EXR or a
/// float64 `.npy` keep the NaN, a millimetre PNG writes its 0.
fn write_prediction(predictions: &Path, t: &Truth, kind: &str, prediction: &[f64]) {
    let path = t.prediction(predictions, kind);
    match kind {
        "depth.exr" => {
            let z = prediction.iter().map(|&p| p as f32).collect();
            write_exr(&path, t.w, t.h, &[("Z", z)]);
        }
        "depth.npy" => {
            let bytes: Vec<u8> = prediction.iter().flat_map(|p| p.to_le_bytes()).collect();
            write_npy(&path, "<f8", &[t.h, t.w], &bytes);
        }
        _ => {
            let bytes: Vec<u8> = prediction
                .iter()
                .map(|&p| {
                    if p.is_nan() {
                        0
                    } else {
                        (p * 1000.0).round() as u16
                    }
                })
                .flat_map(u16::to_be_bytes)
                .collect();
            write_png(&path, t.w, t.h, png::BitDepth::Sixteen, &bytes);
        }
    }
}

#[test]
fn a_pixel_marked_not_predicted_takes_no_part_in_any_alignment() {
    // A millimetre PNG's 0 was fitted as a 0 m prediction by `median` and `lstsq_shift`: the
    // truth itself with one pixel in ten left unpredicted scored AbsRel 0.0265 and 0.1115.
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=2"]);
    let truths = eighths_of_a_metre(&data);
    let inside: usize = truths.iter().map(|t| t.inside().count()).sum();
    let holes: usize = truths.iter().map(|t| t.inside().step_by(10).count()).sum();
    assert!(holes > 100, "{holes} holes");
    let predicted = |t: &Truth, f: &dyn Fn(f64) -> f64| -> Vec<f64> {
        let mut p: Vec<f64> = t.depth.iter().map(|&d| f(f64::from(d))).collect();
        for i in t.inside().step_by(10) {
            p[i] = f64::NAN;
        }
        p
    };
    let affine = |d: f64| 2.0 * d + 0.5;
    for kind in ["depth.exr", "depth.npy", "depth_mm.png"] {
        let same = dir.path().join(format!("same-{kind}"));
        let shifted = dir.path().join(format!("affine-{kind}"));
        for t in &truths {
            write_prediction(&same, t, kind, &predicted(t, &|d| d));
            write_prediction(&shifted, t, kind, &predicted(t, &affine));
        }
        let runs = [
            ("none", &same, 0.0),
            ("median", &same, 0.0),
            ("lstsq", &same, 0.0),
            ("lstsq_shift", &same, 0.0),
            // A fitted scale and shift carry rounding of the sums: zero to 1e-12.
            ("lstsq_shift", &shifted, 1e-12),
        ];
        for (align, predictions, tolerance) in runs {
            let (_, r) = eval(&data, predictions, &["--align", align]);
            let case = format!("{kind}, --align {align}, {}", predictions.display());
            for key in ["abs_rel", "sq_rel", "rmse", "rmse_log"] {
                assert!(f(&r, key) <= tolerance, "{case}: {key} = {}", f(&r, key));
            }
            for key in ["delta1", "delta2", "delta3"] {
                assert_eq!(f(&r, key), 1.0, "{case}: {key}");
            }
            assert_eq!(r["depth_counts"]["pixels"], inside - holes, "{case}");
            assert_eq!(r["depth_counts"]["excluded_pixels"], holes, "{case}");
        }
    }
}

#[test]
fn misnamed_predictions_are_reported_with_the_name_eval_reads() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=2"]);
    let truths = truths(&data);
    let depth = |t: &Truth| vec![("Z", t.depth.clone())];
    let t = &truths[0];

    // Flat, without the sample's folder: the message suggested this very path.
    let flat = dir.path().join("flat");
    write_exr(&flat.join("000000_00.depth.exr"), t.w, t.h, &depth(t));
    write_file(&flat.join("README.md"), b"predictions of run 3\n");
    let e = eval_err(&data, &flat, &[]);
    let expected = flat.join("0000/000000_00.depth.exr");
    assert!(
        e.contains(&format!("eval reads {} (or .depth.npy", expected.display())),
        "{e}"
    );
    assert!(
        e.contains(&format!("1 file under {} looks like", flat.display()))
            && e.contains("\n  000000_00.depth.exr → 0000/000000_00.depth.exr")
            && !e.contains("README"),
        "{e}"
    );

    // Beside a prediction read: a wrong stem, a wrong folder, an unknown kind, a format not
    // read, a view the dataset lacks, a surface of another sample, and one more.
    let p = dir.path().join("p");
    let read = p.join(format!("0000/{}.depth.exr", t.stem));
    write_exr(&read, t.w, t.h, &depth(t));
    let misnamed = [
        ("0000/000000_0.depth.exr", "0000/000000_00.depth.exr"),
        ("0000/000000_00.depth.tiff", "0000/000000_00.depth.exr"),
        ("0000/000000_00.dpth.exr", "0000/000000_00.depth.exr"),
        ("0000/000000_01.flow.exr.npy", "0000/000000_01.flow.exr"),
        ("0000/000001.ply", "0000/000000.ply"),
    ];
    for (file, _) in misnamed {
        write_file(&p.join(file), b"not read");
    }
    write_file(&p.join("0001/000000_01.depth.exr"), b"not read");
    write_file(&p.join("zz/000000_00.depth.npy"), b"not read");
    // Not predictions: a note, a hidden file, and the dataset's own image at its place.
    write_file(&p.join("0000/notes.txt"), b"");
    write_file(&p.join("0000/.000000_00.depth.exr.swp.exr"), b"");
    let rgb = std::fs::read(data.join("samples/0000/000000_00.rgb.png")).unwrap();
    write_file(&p.join("0000/000000_00.rgb.png"), &rgb);
    let (o, r) = eval_partial(&data, &p, &[]);
    let warned = stderr(&o);
    assert!(
        warned.contains(&format!("warning: 7 files under {} look like", p.display())),
        "{warned}"
    );
    for (file, nearest) in misnamed {
        assert!(
            warned.contains(&format!("\n  {file} → {nearest}\n")),
            "{file}: {warned}"
        );
    }
    assert!(warned.contains("\n  … and 2 more"), "{warned}");
    assert!(
        !warned.contains("rgb.png") && !warned.contains("notes"),
        "{warned}"
    );
    assert_eq!(r["misnamed_files"]["count"], 7);
    assert_eq!(
        r["misnamed_files"]["first"][0]["nearest"],
        "0000/000000_00.depth.exr"
    );
    assert_eq!(
        r["depth_counts"]["images"], 1,
        "the well-named file is read"
    );
}

/// Every view of `data` given the true depth 1 + i/8 m at pixel i (all pixels, so `--mask
/// valid` scores each): values an f32 EXR holds exactly. Returns the views' truths.
fn known_depth(data: &Path) -> Vec<Truth> {
    for t in truths(data) {
        let depth: Vec<f32> = (0..t.depth.len()).map(|i| 1.0 + i as f32 / 8.0).collect();
        let scratch = data.with_extension("scratch.exr");
        write_exr(&scratch, t.w, t.h, &[("Y", depth)]);
        let file = format!("samples/0000/{}.depth.exr", t.stem);
        replace_in_dataset(data, &file, &std::fs::read(&scratch).unwrap());
    }
    truths(data)
}

/// `prediction` as a float64 `.npy` depth prediction of view `t`.
fn write_depth_npy(predictions: &Path, t: &Truth, prediction: &[f64]) {
    let bytes: Vec<u8> = prediction.iter().flat_map(|p| p.to_le_bytes()).collect();
    write_npy(
        &t.prediction(predictions, "depth.npy"),
        "<f8",
        &[t.h, t.w],
        &bytes,
    );
}

#[test]
fn per_image_values_are_in_the_json_and_match_a_hand_computation() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=2", "size=4"]);
    let truths = known_depth(&data);
    assert_eq!((truths.len(), truths[0].w, truths[0].h), (2, 4, 4));
    let p = dir.path().join("p");
    // View 0: 10 % too far on even pixels, exact on odd ones: AbsRel ½ · 0.1 = 0.05.
    // View 1: twice the truth: AbsRel 1, RMSE √mean d*², δ1 0.
    let t0: Vec<f64> = truths[0].depth.iter().map(|&d| f64::from(d)).collect();
    let t1: Vec<f64> = truths[1].depth.iter().map(|&d| f64::from(d)).collect();
    let p0: Vec<f64> = t0
        .iter()
        .enumerate()
        .map(|(i, &d)| if i % 2 == 0 { 1.1 * d } else { d })
        .collect();
    let p1: Vec<f64> = t1.iter().map(|&d| 2.0 * d).collect();
    write_depth_npy(&p, &truths[0], &p0);
    write_depth_npy(&p, &truths[1], &p1);
    let (o, r) = eval(&data, &p, &["--mask", "valid"]);
    assert!(
        String::from_utf8_lossy(&o.stdout)
            .contains("complete: every prediction asked for was scored"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert_eq!(r["complete"], true);
    let images = r["images"].as_array().unwrap();
    assert_eq!(images.len(), 2, "{r}");
    assert_eq!(images[0]["stem"], truths[0].stem.as_str());
    assert_eq!(images[1]["view"], truths[1].view);
    let d0 = &images[0]["depth"];
    let d1 = &images[1]["depth"];
    assert!((f(d0, "abs_rel") - 0.05).abs() < 1e-12, "{d0}");
    assert!((f(d1, "abs_rel") - 1.0).abs() < 1e-12, "{d1}");
    let rms1 = (t1.iter().map(|d| d * d).sum::<f64>() / 16.0).sqrt();
    assert!((f(d1, "rmse") - rms1).abs() < 1e-12, "{d1} vs {rms1}");
    assert_eq!((f(d0, "delta1"), f(d1, "delta1")), (1.0, 0.0));
    assert_eq!(
        (d0["pixels"].as_u64(), d0["excluded_pixels"].as_u64()),
        (Some(16), Some(0))
    );
    assert_eq!(f(d0, "scale"), 1.0);
    // The report's mean is the mean of the images'.
    assert!((f(&r, "abs_rel") - 0.525).abs() < 1e-12, "{r}");
}

#[test]
fn a_stray_surface_without_true_meshes_is_skipped_and_depth_still_scored() {
    // A .ply beside the depth predictions, and a dataset without meshes: eval gave up
    // (exit 1, "has a predicted surface but the dataset has no 000000.mesh.ply").
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=1", "views=2", "size=4"]);
    let truths = known_depth(&data);
    let p = dir.path().join("p");
    for t in &truths {
        let d: Vec<f64> = t.depth.iter().map(|&d| 1.25 * f64::from(d)).collect();
        write_depth_npy(&p, t, &d);
    }
    let (vertices, faces) = grid(3, 0.0);
    write_file(&p.join("samples/0000/000000.ply"), &ply(&vertices, &faces));
    let (o, r) = eval_partial(&data, &p, &["--mask", "valid"]);
    assert!((f(&r, "abs_rel") - 0.25).abs() < 1e-12, "{r}");
    assert_eq!(r["depth_counts"]["images"], 2);
    assert!(r["surface"].is_null());
    let unscored = r["unscored"].as_array().unwrap();
    assert_eq!(unscored.len(), 1, "{r}");
    assert_eq!(unscored[0]["quantity"], "surface");
    assert_eq!(unscored[0]["count"], 1);
    assert_eq!(unscored[0]["first"][0], "sample 0");
    let reason = unscored[0]["reason"].as_str().unwrap();
    assert!(
        reason.contains("no 000000.mesh.ply") && reason.contains("\"mesh\""),
        "{reason}"
    );
    assert!(
        stderr(&o)
            .contains("warning: surface: 1 samples not scored: the dataset has no 000000.mesh.ply"),
        "{}",
        stderr(&o)
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("AbsRel") && stdout.contains("partial: 1 views or samples not scored"),
        "{stdout}"
    );
}

#[test]
fn missing_predictions_are_counted_named_and_make_the_evaluation_partial() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=2", "views=3", "size=4"]);
    let truths = known_depth(&data);
    let p = dir.path().join("p");
    // Every view but the first two of sample 0 and the last of sample 1.
    let missing = [0, 1, 5];
    for (k, t) in truths.iter().enumerate() {
        if !missing.contains(&k) {
            let d: Vec<f64> = t.depth.iter().map(|&d| f64::from(d)).collect();
            write_depth_npy(&p, t, &d);
        }
    }
    let (o, r) = eval_partial(&data, &p, &["--mask", "valid"]);
    assert_eq!(r["depth_counts"]["missing"], 3);
    assert_eq!(r["depth_counts"]["images"], 3);
    let names: Vec<&str> = missing.iter().map(|&k| truths[k].stem.as_str()).collect();
    assert_eq!(r["unscored"][0]["first"], serde_json::json!(names));
    assert_eq!(r["unscored"][0]["reason"], "no prediction");
    assert!(
        stderr(&o).contains(&format!(
            "warning: depth: 3 views not scored: no prediction (e.g. {})",
            names.join(", ")
        )),
        "{}",
        stderr(&o)
    );
    assert_eq!(r["images"].as_array().unwrap().len(), 3);
    // The same predictions, all of them: complete, exit 0.
    for &k in &missing {
        let d: Vec<f64> = truths[k].depth.iter().map(|&d| f64::from(d)).collect();
        write_depth_npy(&p, &truths[k], &d);
    }
    let (_, r) = eval(&data, &p, &["--mask", "valid"]);
    assert_eq!(
        (r["complete"].as_bool(), f(&r, "abs_rel")),
        (Some(true), 0.0)
    );
}

#[test]
fn where_scores_the_views_whose_record_field_matches() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/a1_beams.rhai");
    let data = dir.path().join("a1");
    let sets = ["samples=3", "views=1", "size=8", "textures=false"];
    let mut args = Vec::new();
    for set in sets {
        args.extend(["--set", set]);
    }
    ok(common::run(&recipe, &data, &args));
    // a1_beams gives sample k the prompt k mod 3: sample 2 is the cracked timber.
    let truths = truths(&data);
    let p = dir.path().join("p");
    for t in &truths {
        let factor = if t.sample == 2 { 2.0 } else { 1.0 };
        let d: Vec<f64> = t.depth.iter().map(|&d| factor * f64::from(d)).collect();
        write_depth_npy(&p, t, &d);
    }
    let (_, all) = eval(&data, &p, &[]);
    assert!((f(&all, "abs_rel") - 1.0 / 3.0).abs() < 1e-12, "{all}");
    let timber = "scene.structures.0.material.prompt=A photo of cracked timber for construction";
    let (_, r) = eval(&data, &p, &["--where", timber]);
    assert_eq!(f(&r, "abs_rel"), 1.0, "{r}");
    assert_eq!(r["selection"]["views"], 1);
    assert_eq!(r["selection"]["dataset_views"], 3);
    assert_eq!(r["selection"]["conditions"][0], timber);
    assert_eq!(r["images"][0]["stem"], "000002_00");
    // Two conditions, both must hold; a number matches by value.
    let (_, r) = eval(&data, &p, &["--where", "sample=1.0", "--where", "view=0"]);
    assert_eq!(
        (f(&r, "abs_rel"), r["selection"]["views"].as_u64()),
        (0.0, Some(1))
    );
    // Conditions on the same field are alternatives: samples 0 and 2, view 0.
    let (_, r) = eval(
        &data,
        &p,
        &[
            "--where", "sample=0", "--where", "sample=2", "--where", "view=0",
        ],
    );
    assert_eq!(r["selection"]["views"], 2);
    assert!((f(&r, "abs_rel") - 0.5).abs() < 1e-12, "{r}");
    // Views outside the selection are not missing: only the timber view predicted is complete.
    let only = dir.path().join("only");
    let t = &truths[2];
    write_depth_npy(
        &only,
        t,
        &t.depth.iter().map(|&d| f64::from(d)).collect::<Vec<_>>(),
    );
    let (_, r) = eval(&data, &only, &["--where", timber]);
    assert_eq!(r["complete"], true);
    // A field no view has is an error naming what the record has there.
    let e = eval_err(
        &data,
        &p,
        &["--where", "scene.structure.0.support=cantilever"],
    );
    assert!(
        e.contains(
            "no view's record has the field scene.structure.0.support; scene has: structures"
        ),
        "{e}"
    );
    let e = eval_err(&data, &p, &["--where", "sample=99"]);
    assert!(e.contains("no view of the dataset matches"), "{e}");
    let e = eval_err(&data, &p, &["--where", "sample"]);
    assert!(e.contains("expected FIELD=VALUE"), "{e}");
}
