//! `shmgen export` end to end: a dataset exported to every format and read back with parsers
//! written here (transforms.json against the view records, COLMAP's quaternions rebuilt into
//! rotation matrices, tar shards through the `tar` crate's reader, 16-bit PNG through `png`),
//! plus the refusals and a killed export.

use serde_json::Value;
use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::io::Read;
use std::path::Path;
use std::process::Output;
use std::time::Duration;

mod common;

use common::{
    distort, files_with_extension, hashes, manifest_files, ok, quickstart, read_exr, read_json,
    read_ply, read_png, read_png16, run, run_limited, sample_path, shmgen, stderr, transform,
    view_path, write,
};

fn export(dataset: &Path, format: &str, out: &Path, extra: &[&str]) -> Output {
    let mut args: Vec<&OsStr> = vec![
        OsStr::new("export"),
        dataset.as_os_str(),
        OsStr::new("--format"),
        OsStr::new(format),
        OsStr::new("--out"),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(OsStr::new));
    shmgen(&args)
}

/// The views of a dataset as its manifest lists them: file stem → files (relative paths).
fn views(out: &Path) -> BTreeMap<String, Vec<String>> {
    let mut views: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for file in manifest_files(out) {
        let name = file.rsplit('/').next().unwrap();
        let stem = name.split('.').next().unwrap();
        if stem.contains('_') {
            views.entry(stem.to_string()).or_default().push(file);
        }
    }
    views
}

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

/// Sample and view of a stem `SSSSSS_VV[aK]`.
fn indices(stem: &str) -> (u64, u32, Option<u32>) {
    let (s, rest) = stem.split_once('_').unwrap();
    let (v, copy) = match rest.split_once('a') {
        Some((v, c)) => (v, Some(c.parse().unwrap())),
        None => (rest, None),
    };
    (s.parse().unwrap(), v.parse().unwrap(), copy)
}

/// Whole millimetres of depth in metres, rounded to nearest: what a millimetre PNG must hold.
fn millimetres(depth: &[f32]) -> Vec<u16> {
    depth
        .iter()
        .map(|&d| (f64::from(d) * 1000.0).round().min(65535.0) as u16)
        .collect()
}

/// Rotation matrix of a unit Hamilton quaternion (w, x, y, z), the textbook formula.
fn rotation_of(w: f64, x: f64, y: f64, z: f64) -> [[f64; 3]; 3] {
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// Data lines of a COLMAP text file (comments dropped, empty lines kept).
fn data_lines(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(str::to_string)
        .collect()
}

/// Checks a COLMAP model against the records; returns the camera model names used.
fn check_colmap(data: &Path, scene: &Path, stems: &[&String]) -> Vec<String> {
    let cameras: BTreeMap<u32, Vec<String>> = data_lines(&scene.join("sparse/0/cameras.txt"))
        .iter()
        .map(|l| {
            let f: Vec<String> = l.split(' ').map(str::to_string).collect();
            (f[0].parse().unwrap(), f[1..].to_vec())
        })
        .collect();
    let lines = data_lines(&scene.join("sparse/0/images.txt"));
    assert_eq!(lines.len(), 2 * stems.len(), "two lines per image");
    let mut models = Vec::new();
    for (pair, stem) in lines.chunks(2).zip(stems) {
        let f: Vec<&str> = pair[0].split(' ').collect();
        assert_eq!(f.len(), 10);
        let n: Vec<f64> = f[1..8].iter().map(|x| x.parse().unwrap()).collect();
        assert_eq!(f[9], format!("{stem}.png"));
        let (s, v, copy) = indices(stem);
        let record = read_json(&view_path(data, s, v, copy, "json"));
        let w2c = matrix(&record["camera"]["w2c_opencv"]);
        let r = rotation_of(n[0], n[1], n[2], n[3]);
        for i in 0..3 {
            for j in 0..3 {
                assert!((r[i][j] - w2c[i][j]).abs() < 1e-12, "{stem}: R[{i}][{j}]");
            }
            assert_eq!(n[4 + i], w2c[i][3], "{stem}: t is w2c's, to the bit");
        }
        let camera = &cameras[&f[8].parse::<u32>().unwrap()];
        let k = matrix(&record["camera"]["K"]);
        let size = [&record["camera"]["width"], &record["camera"]["height"]].map(|v| v.to_string());
        assert_eq!(camera[1..3], size);
        let p: Vec<f64> = camera[3..].iter().map(|x| x.parse().unwrap()).collect();
        assert_eq!(p[..4], [k[0][0], k[1][1], k[0][2], k[1][2]], "{stem}");
        if camera[0] != "PINHOLE" {
            let d = &record["camera"]["distortion"];
            let c = |n: &str| d[n].as_f64().unwrap();
            assert_eq!(p[4..8], [c("k1"), c("k2"), c("p1"), c("p2")]);
            if camera[0] == "FULL_OPENCV" {
                assert_eq!(p[8..], [c("k3"), 0.0, 0.0, 0.0]);
            } else {
                assert_eq!((camera[0].as_str(), p.len(), c("k3")), ("OPENCV", 8, 0.0));
            }
        }
        let image = std::fs::read(scene.join("images").join(f[9])).unwrap();
        assert_eq!(
            image,
            std::fs::read(view_path(data, s, v, copy, "rgb.png")).unwrap()
        );
        models.push(camera[0].clone());
    }
    check_points(data, scene, stems, &lines);
    models
}

/// One image of a COLMAP model as the test sees it: its view's camera, depth and RGB from
/// the dataset, and the 2-D points of its images.txt line (x, y, POINT3D_ID).
struct Frame {
    w2c: [[f64; 4]; 4],
    centre: [f64; 3],
    k: [[f64; 3]; 3],
    lens: [f64; 5],
    width: usize,
    depth: Vec<f32>,
    rgb: Vec<u8>,
    mask: Vec<u8>,
    points2d: Vec<([f64; 2], u64)>,
}

impl Frame {
    fn new(data: &Path, stem: &str, points2d_line: &str) -> Frame {
        let (s, v, copy) = indices(stem);
        let record = read_json(&view_path(data, s, v, copy, "json"));
        let camera = &record["camera"];
        let c2w: [[f64; 4]; 4] = common::matrix(&camera["c2w_opencv"]);
        let lens = match camera["distortion"].is_null() {
            true => [0.0; 5],
            false => {
                ["k1", "k2", "p1", "p2", "k3"].map(|k| camera["distortion"][k].as_f64().unwrap())
            }
        };
        let words: Vec<&str> = points2d_line.split_whitespace().collect();
        assert!(words.len().is_multiple_of(3), "X Y POINT3D_ID triples");
        let (width, _, _, rgb) = read_png(&view_path(data, s, v, copy, "rgb.png"));
        Frame {
            w2c: common::matrix(&camera["w2c_opencv"]),
            centre: [c2w[0][3], c2w[1][3], c2w[2][3]],
            k: common::matrix(&camera["K"]),
            lens,
            width,
            depth: read_exr(&view_path(data, s, v, copy, "depth.exr")),
            rgb,
            mask: read_png(&view_path(data, s, v, copy, "mask.png")).3,
            points2d: words
                .chunks(3)
                .map(|t| {
                    (
                        [t[0].parse().unwrap(), t[1].parse().unwrap()],
                        t[2].parse().unwrap(),
                    )
                })
                .collect(),
        }
    }

    /// Where `p` projects (OpenCV's lens model, independent of shmgen's) and its depth.
    fn project(&self, p: [f64; 3]) -> ([f64; 2], f64) {
        let c = transform(&self.w2c, p);
        let (x, y) = distort(&self.lens, c[0] / c[2], c[1] / c[2]);
        let k = self.k;
        ([k[0][0] * x + k[0][2], k[1][1] * y + k[1][2]], c[2])
    }

    fn pixel(&self, xy: [f64; 2]) -> usize {
        xy[1].floor() as usize * self.width + xy[0].floor() as usize
    }

    /// Whether the unit `normal` at `p` faces the camera at least as much as `cos`.
    fn faces(&self, p: [f64; 3], normal: [f64; 3], cos: f64) -> bool {
        let to: [f64; 3] = std::array::from_fn(|i| self.centre[i] - p[i]);
        let length = to.iter().map(|c| c * c).sum::<f64>().sqrt();
        (0..3).map(|i| normal[i] * to[i]).sum::<f64>() > cos * length
    }

    /// Whether the 3 × 3 pixels around `xy` all see the structure, away from the border.
    fn well_inside(&self, xy: [f64; 2]) -> bool {
        let (col, row) = (xy[0].floor() as usize, xy[1].floor() as usize);
        let height = self.mask.len() / self.width;
        (2..self.width - 2).contains(&col)
            && (2..height - 2).contains(&row)
            && (row - 1..=row + 1)
                .all(|r| (col - 1..=col + 1).all(|c| self.mask[r * self.width + c] == 255))
    }
}

/// The points of a sample's points.ply: position → unit normal.
fn ply_points(path: &Path) -> Vec<([f64; 3], [f64; 3])> {
    let ply = read_ply(path);
    let value = |e: &ply_rs_bw::ply::DefaultElement, name: &str| match e[name] {
        ply_rs_bw::ply::Property::Double(v) => v,
        ply_rs_bw::ply::Property::Float(v) => f64::from(v),
        ref other => panic!("{name}: {other:?}"),
    };
    ply["vertex"]
        .iter()
        .map(|e| {
            (
                ["x", "y", "z"].map(|n| value(e, n)),
                ["nx", "ny", "nz"].map(|n| value(e, n)),
            )
        })
        .collect()
}

/// points3D.txt against the images' 2-D points (each referenced by one track entry, with its
/// point's id), the views' cameras (each 2-D point the projection of its 3-D point through
/// them), depth (the point seen: its pixel's depth is its own, its face turned to the camera)
/// and RGB (its colour the mean of its pixels'), and the sample's points.ply (every point one
/// of its points, and each of its points facing a camera well inside the box's image seen).
fn check_points(data: &Path, scene: &Path, stems: &[&String], lines: &[String]) {
    let frames: Vec<Frame> = lines
        .chunks(2)
        .zip(stems)
        .map(|(pair, stem)| Frame::new(data, stem, &pair[1]))
        .collect();
    let points = data_lines(&scene.join("sparse/0/points3D.txt"));
    let ply = sample_path(data, indices(stems[0]).0, "points.ply");
    if !ply.exists() {
        assert!(points.is_empty() && frames.iter().all(|f| f.points2d.is_empty()));
        return;
    }
    let ply = ply_points(&ply);
    let normal_of: std::collections::HashMap<[u64; 3], [f64; 3]> =
        ply.iter().map(|(p, n)| (p.map(f64::to_bits), *n)).collect();
    let mut observed = std::collections::HashSet::new();
    for (line, id) in points.iter().zip(1u64..) {
        let f: Vec<&str> = line.split(' ').collect();
        assert_eq!(f[0], id.to_string(), "ids count from 1");
        let xyz: [f64; 3] = std::array::from_fn(|i| f[1 + i].parse().unwrap());
        let rgb: [f64; 3] = std::array::from_fn(|i| f[4 + i].parse().unwrap());
        assert_eq!(f[7], "0", "exact projections: no reprojection error");
        let normal = normal_of[&xyz.map(f64::to_bits)];
        let track = &f[8..];
        assert!(!track.is_empty() && track.len().is_multiple_of(2), "{line}");
        let mut sum = [0.0; 3];
        for pair in track.chunks(2) {
            let image: usize = pair[0].parse().unwrap();
            let index: usize = pair[1].parse().unwrap();
            let frame = &frames[image - 1];
            let (xy, point) = frame.points2d[index];
            assert_eq!(point, id, "the 2-D point names its 3-D point");
            let (expected, z) = frame.project(xyz);
            assert!(
                (xy[0] - expected[0]).abs() < 1e-3 && (xy[1] - expected[1]).abs() < 1e-3,
                "point {id} in image {image}: {xy:?} vs {expected:?}"
            );
            let pixel = frame.pixel(xy);
            // Seen: the box is convex, so its face turns towards the camera, and the pixel
            // it falls in sees a surface no farther than a pixel's footprint at a slant.
            assert!(
                frame.faces(xyz, normal, 0.0),
                "point {id} seen from behind in image {image}"
            );
            let depth = f64::from(frame.depth[pixel]);
            let footprint = z / frame.k[0][0].min(frame.k[1][1]);
            assert!(
                depth > 0.0 && (depth - z).abs() < 10.0 * footprint,
                "point {id} in image {image}: depth {depth} vs {z}"
            );
            for (c, total) in sum.iter_mut().enumerate() {
                *total += f64::from(frame.rgb[3 * pixel + c]);
            }
            assert!(
                observed.insert((image, index)),
                "one track entry per 2-D point"
            );
        }
        let n = (track.len() / 2) as f64;
        assert_eq!(
            rgb,
            sum.map(|s| (s / n).round()),
            "point {id}: the mean of its pixels"
        );
    }
    let all: usize = frames.iter().map(|f| f.points2d.len()).sum();
    assert_eq!(observed.len(), all, "every 2-D point is in a track");
    // The box is convex and alone: a point on a face turned towards the camera, projecting
    // well inside its image, is seen there.
    for (image, frame) in (1..).zip(&frames) {
        let seen: std::collections::HashSet<[u64; 3]> = frame
            .points2d
            .iter()
            .map(|(_, id)| {
                let f: Vec<&str> = points[*id as usize - 1].split(' ').collect();
                std::array::from_fn(|i| f[1 + i].parse::<f64>().unwrap().to_bits())
            })
            .collect();
        let mut expected = 0;
        for (p, n) in &ply {
            let (xy, z) = frame.project(*p);
            if z > 0.0 && frame.faces(*p, *n, 0.2) && frame.well_inside(xy) {
                expected += 1;
                assert!(
                    seen.contains(&p.map(f64::to_bits)),
                    "{p:?} unseen in image {image}"
                );
            }
        }
        assert!(expected > 20, "image {image}: {expected} points to see");
    }
}

/// Checks a nerfstudio scene against the records; returns its camera model and frame stems.
fn check_nerfstudio(data: &Path, scene: &Path) -> (String, Vec<String>) {
    let t = read_json(&scene.join("transforms.json"));
    let mut stems = Vec::new();
    for frame in t["frames"].as_array().unwrap() {
        let file = frame["file_path"].as_str().unwrap();
        let stem = file
            .strip_prefix("images/")
            .unwrap()
            .strip_suffix(".png")
            .unwrap();
        let (s, v, copy) = indices(stem);
        let record = read_json(&view_path(data, s, v, copy, "json"));
        let camera = &record["camera"];
        let k = matrix(&camera["K"]);
        let got = ["fl_x", "fl_y", "cx", "cy"].map(|n| frame[n].as_f64().unwrap());
        assert_eq!(got, [k[0][0], k[1][1], k[0][2], k[1][2]], "{stem}");
        assert_eq!(
            (&frame["w"], &frame["h"]),
            (&camera["width"], &camera["height"])
        );
        // OpenGL axes: the OpenCV camera-to-world with its y and z columns negated.
        let cv = matrix(&camera["c2w_opencv"]);
        let gl = matrix(&frame["transform_matrix"]);
        for i in 0..4 {
            let sign = [1.0, -1.0, -1.0, 1.0];
            for j in 0..4 {
                assert_eq!(
                    gl[i][j],
                    cv[i][j] * sign[j],
                    "{stem}: transform_matrix[{i}][{j}]"
                );
            }
        }
        if t["camera_model"] == "OPENCV" {
            for n in ["k1", "k2", "k3", "p1", "p2"] {
                let expected = camera["distortion"][n].as_f64().unwrap_or(0.0);
                assert_eq!(frame[n].as_f64().unwrap(), expected, "{stem}: {n}");
            }
        }
        let same = |exported: &str, kind: &str| {
            assert_eq!(
                std::fs::read(scene.join(exported)).unwrap(),
                std::fs::read(view_path(data, s, v, copy, kind)).unwrap(),
                "{exported}"
            );
        };
        same(file, "rgb.png");
        same(frame["mask_path"].as_str().unwrap(), "mask.png");
        let depth = read_exr(&view_path(data, s, v, copy, "depth.exr"));
        let (_, _, mm) = read_png16(&scene.join(frame["depth_file_path"].as_str().unwrap()));
        assert_eq!(mm, millimetres(&depth), "{stem}: depth in millimetres");
        stems.push(stem.to_string());
    }
    // The surface points go with the scene when the dataset has them, byte for byte.
    let sample = scene.file_name().unwrap().to_string_lossy().to_string();
    let points = data.join(format!("samples/0000/{sample}.points.ply"));
    match t["ply_file_path"].as_str() {
        Some(file) => assert_eq!(
            std::fs::read(scene.join(file)).unwrap(),
            std::fs::read(&points).unwrap()
        ),
        None => assert!(!points.exists(), "{} is not named", points.display()),
    }
    (t["camera_model"].as_str().unwrap().to_string(), stems)
}

/// Every tar member of the gzipped shards in `dir`, in order: (name, bytes), with its header
/// checked, and the gzip header's (no time stamp, no name: bytes that depend on the contents).
fn shard_members(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let shards = files_with_extension(dir, "gz");
    assert!(!shards.is_empty(), "no shard-*.tar.gz in {}", dir.display());
    let mut members = Vec::new();
    for shard in shards {
        let gzip = flate2::read::GzDecoder::new(std::fs::File::open(&shard).unwrap());
        let header = gzip.header().expect("a gzip header").clone();
        assert_eq!((header.mtime(), header.filename()), (0, None));
        let mut archive = tar::Archive::new(gzip);
        for entry in archive.entries().unwrap() {
            let mut entry = entry.unwrap();
            let h = entry.header();
            assert_eq!(
                (
                    h.mode().unwrap(),
                    h.uid().unwrap(),
                    h.gid().unwrap(),
                    h.mtime().unwrap()
                ),
                (0o644, 0, 0, 0)
            );
            let name = entry.path().unwrap().to_string_lossy().to_string();
            let mut bytes = Vec::new();
            entry.read_to_end(&mut bytes).unwrap();
            members.push((name, bytes));
        }
    }
    members
}

#[test]
fn every_format_holds_the_datasets_files_and_cameras() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=2", "views=3"]);
    let views = views(&data);
    assert_eq!(views.len(), 6);

    let ns = dir.path().join("ns");
    ok(export(&data, "nerfstudio", &ns, &[]));
    for sample in 0..2u64 {
        let (model, stems) = check_nerfstudio(&data, &ns.join(format!("{sample:06}")));
        assert_eq!(model, "PINHOLE");
        let expected: Vec<String> = (0..3).map(|v| format!("{sample:06}_{v:02}")).collect();
        assert_eq!(stems, expected);
    }

    let colmap = dir.path().join("colmap");
    ok(export(&data, "colmap", &colmap, &[]));
    for sample in 0..2u64 {
        let stems: Vec<&String> = views.keys().filter(|k| indices(k).0 == sample).collect();
        let models = check_colmap(&data, &colmap.join(format!("{sample:06}")), &stems);
        assert_eq!(models, ["PINHOLE"; 3]);
    }

    let wds = dir.path().join("wds");
    ok(export(&data, "webdataset", &wds, &["--shard-size", "4"]));
    let members = shard_members(&wds);
    let mut expected = Vec::new();
    for files in views.values() {
        let mut files = files.clone();
        files.sort();
        for file in files {
            let name = file.rsplit('/').next().unwrap().to_string();
            let (stem, kind) = name.split_once('.').unwrap();
            expected.push(match kind {
                "rgb.png" | "json" => name.clone(),
                _ => format!("{stem}.{}.npy", kind.split('.').next().unwrap()),
            });
        }
    }
    let names: Vec<&String> = members.iter().map(|(name, _)| name).collect();
    assert_eq!(
        names,
        expected.iter().collect::<Vec<_>>(),
        "every layer of every view, in key order"
    );
    for (name, bytes) in &members {
        let file = data
            .join(&views[name.split('.').next().unwrap()][0])
            .with_file_name(name);
        if name.ends_with(".depth.npy") {
            // NumPy's header for a (960, 960) float32 array, then the EXR's values.
            let depth = read_exr(&file.with_extension("exr"));
            let values: Vec<u8> = depth.iter().flat_map(|v| v.to_le_bytes()).collect();
            assert!(bytes.starts_with(b"\x93NUMPY\x01\x00"));
            let header = String::from_utf8_lossy(&bytes[10..bytes.len() - values.len()]);
            assert!(header.contains("'descr': '<f4'") && header.contains("'shape': (960, 960)"));
            assert!(bytes.ends_with(&values), "{name}: the depth's values");
        } else if !name.ends_with(".npy") {
            assert!(
                *bytes == std::fs::read(&file).unwrap(),
                "{name} byte-identical"
            );
        }
    }
    let shards = read_json(&wds.join("export.json"))["shards"].clone();
    let counts: Vec<u64> = shards
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["views"].as_u64().unwrap())
        .collect();
    assert_eq!(counts, [4, 2]);
    let again = dir.path().join("wds2");
    ok(export(&data, "webdataset", &again, &["--shard-size", "4"]));
    assert_eq!(hashes(&wds), hashes(&again), "deterministic shards");

    let png16 = dir.path().join("png16");
    ok(export(&data, "png16", &png16, &[]));
    for stem in views.keys() {
        let (s, v, _) = indices(stem);
        let depth = read_exr(&view_path(&data, s, v, None, "depth.exr"));
        let (w, h, mm) = read_png16(&view_path(&png16, s, v, None, "depth_mm.png"));
        assert_eq!((w, h), (960, 960));
        assert_eq!(mm, millimetres(&depth), "{stem}");
    }
}

/// A box seen through a drawn lens, with one augmented copy of each view.
const LENS: &str = r#"
dataset(#{ name: "lens", seed: 3, samples: 1, views: 2, outputs: ["rgb", "depth", "mask", "points"], points: 500,
    camera: #{ width: 64, height: 48,
        distortion: #{ k1: [-0.15, -0.1], k2: 0.02, p1: 0.001, p2: -0.001, k3: [0.0, param("k3", 0.004)] } },
    augment: #{ copies: 1, operations: [#{ op: "gamma", gamma: [0.8, 1.2], probability: 1.0 }] },
    scene: |rng| assembly("box", [shape::box(2.0, 1.0, 0.5)]),
})
"#;

#[test]
fn distorted_lenses_and_augmented_copies_export_with_their_cameras() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(dir.path(), "lens.rhai", LENS);
    let data = dir.path().join("data");
    ok(run(&recipe, &data, &[]));
    let no_k3 = dir.path().join("no_k3");
    ok(run(&recipe, &no_k3, &["--set", "k3=0.0"]));

    let ns = dir.path().join("ns");
    ok(export(&data, "nerfstudio", &ns, &[]));
    let (model, stems) = check_nerfstudio(&data, &ns.join("000000"));
    assert_eq!(
        (model.as_str(), stems),
        ("OPENCV", vec!["000000_00".into(), "000000_01".into()])
    );
    let all = dir.path().join("ns_all");
    ok(export(&data, "nerfstudio", &all, &["--with-copies"]));
    let (_, stems) = check_nerfstudio(&data, &all.join("000000"));
    assert_eq!(
        stems,
        ["000000_00", "000000_00a0", "000000_01", "000000_01a0"]
    );

    let colmap = dir.path().join("colmap");
    ok(export(&data, "colmap", &colmap, &["--with-copies"]));
    let stems: Vec<String> = ["000000_00", "000000_00a0", "000000_01", "000000_01a0"]
        .map(String::from)
        .to_vec();
    let refs: Vec<&String> = stems.iter().collect();
    assert_eq!(
        check_colmap(&data, &colmap.join("000000"), &refs),
        ["FULL_OPENCV"; 4]
    );
    let plain = dir.path().join("colmap_no_k3");
    ok(export(&no_k3, "colmap", &plain, &[]));
    let clean = [&stems[0], &stems[2]];
    assert_eq!(
        check_colmap(&no_k3, &plain.join("000000"), &clean),
        ["OPENCV"; 2]
    );

    let wds = dir.path().join("wds");
    ok(export(&data, "webdataset", &wds, &[]));
    let keys: Vec<String> = shard_members(&wds)
        .into_iter()
        .map(|(name, _)| name.split('.').next().unwrap().to_string())
        .collect();
    let mut runs = keys.clone();
    runs.dedup();
    assert_eq!(
        runs, stems,
        "each key's members adjacent, copies as keys of their own"
    );
}

#[test]
fn depth_beyond_16_bit_millimetres_saturates_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(
        dir.path(),
        "far.rhai",
        r#"dataset(#{ name: "far", seed: 1, samples: 1, views: 1, outputs: ["rgb", "depth", "mask"],
            camera: #{ width: 32, height: 24, fov_y: deg(2), distance: 80.0 },
            scene: |rng| assembly("box", [shape::box(2.0, 1.0, 0.5)]) })"#,
    );
    let data = dir.path().join("data");
    ok(run(&recipe, &data, &[]));
    let out = dir.path().join("png16");
    let done = ok(export(&data, "png16", &out, &[]));
    let depth = read_exr(&view_path(&data, 0, 0, None, "depth.exr"));
    let far = depth
        .iter()
        .filter(|&&d| f64::from(d) * 1000.0 >= 65535.5)
        .count();
    assert!(far > 0);
    assert!(
        stderr(&done).contains(&format!("warning: {far} depth pixels beyond 65.535 m")),
        "{}",
        stderr(&done)
    );
    let (_, _, mm) = read_png16(&view_path(&out, 0, 0, None, "depth_mm.png"));
    for (d, m) in depth.iter().zip(mm) {
        assert_eq!(m, if *d == 0.0 { 0 } else { 65535 });
    }
    assert_eq!(
        read_json(&out.join("export.json"))["depth_mm"]["saturated_pixels"],
        far
    );
}

#[test]
fn unfinished_foreign_and_occupied_folders_are_refused_and_nothing_is_left() {
    let dir = tempfile::tempdir().unwrap();
    let half = dir.path().join("half");
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/quickstart.rhai");
    ok(run(
        &recipe,
        &half,
        &["--set", "samples=2", "--set", "views=1", "--shard", "0/2"],
    ));
    let out = dir.path().join("out");
    let refused = |dataset: &Path, out: &Path, expect: &str| {
        let o = export(dataset, "webdataset", out, &[]);
        assert!(!o.status.success());
        assert!(stderr(&o).contains(expect), "{}", stderr(&o));
    };
    refused(
        &half,
        &out,
        "not finished: manifest.jsonl lists 1 of 2 samples",
    );
    std::fs::create_dir(dir.path().join("foreign")).unwrap();
    refused(&dir.path().join("foreign"), &out, "not a shmgen dataset");
    assert!(!out.exists());
    let whole = quickstart(dir.path(), "whole", &["samples=1", "views=1"]);
    std::fs::create_dir(&out).unwrap();
    refused(&whole, &out, "already exists");
    refused(&whole, &whole.join("exports"), "inside the dataset");
    let o = export(&whole, "tiff", &dir.path().join("t"), &[]);
    assert!(stderr(&o).contains("expected nerfstudio, colmap, webdataset, png16 or flow"));
    let o = export(&whole, "flow", &dir.path().join("f"), &[]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains(
            "view 000000_00 has no flow.exr file; flow needs the dataset's \"flow\" output"
        ),
        "{}",
        stderr(&o)
    );
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        names.len(),
        4,
        "half, foreign, whole, out; no temporaries: {names:?}"
    );
}

#[test]
fn a_killed_export_never_leaves_a_folder_that_looks_complete() {
    let dir = tempfile::tempdir().unwrap();
    let data = quickstart(dir.path(), "data", &["samples=2", "views=3"]);
    let whole = dir.path().join("whole");
    ok(export(&data, "nerfstudio", &whole, &[]));
    let complete = hashes(&whole);
    std::fs::remove_dir_all(&whole).unwrap();
    let out = dir.path().join("ns");
    for limit in [5, 20, 60, 150] {
        let args = ["export", "--format", "nerfstudio", "--out"].map(OsStr::new);
        let (_, finished) = run_limited(
            Duration::from_millis(limit),
            &[
                args[0],
                data.as_os_str(),
                args[1],
                args[2],
                args[3],
                out.as_os_str(),
            ],
        );
        assert!(
            out.exists() || !finished,
            "a finished export left no {}",
            out.display()
        );
        // A kill may land after the final rename, before the process exits: then the folder
        // is there, and it must be the whole export, byte for byte.
        if out.exists() {
            assert_eq!(
                hashes(&out),
                complete,
                "{} exists after a run (finished: {finished}, limit {limit} ms) but is not the whole export",
                out.display()
            );
            std::fs::remove_dir_all(&out).unwrap();
        }
    }
    // A later export cleans up what killed ones left beside --out, and succeeds.
    ok(export(&data, "nerfstudio", &out, &[]));
    let hidden: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(hidden.is_empty(), "{hidden:?}");
}
