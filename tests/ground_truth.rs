//! The ground-truth outputs against independent truth, read back from written datasets:
//! normals against the analytic faces of a box and against normals from depth gradients;
//! displacement and flow against the closed-form deflection of a simply supported beam
//! (projected with the written K and pose); the unloaded image against a separate render of
//! the unloaded beam; ray distance against depth and K; meshes and points through readers that
//! are not ours (ply-rs, gltf); hard cases (the structure leaving the frame or hidden behind
//! another when loaded, a grazing view, a damaged silo through a distorting lens) with every
//! float of every new file finite; and how augmented copies carry the new layers.

mod common;

use common::{
    View, load, off_box, ok, read_exr, read_exr_channels, read_json, read_ply, read_png, render,
    run, sample_path, view_path, write,
};
use ply_rs_bw::ply::Property;
use std::path::Path;

/// Every output this test file reads.
const ALL: &str = r#"["rgb", "depth", "mask", "parts", "normals", "displacement", "flow", "rest_rgb", "rest_depth", "ray_distance", "mesh", "mesh_gltf", "points"]"#;

/// The simply supported beam the tests bend: span `length` along world x centred on `centre`,
/// a `width` × `height` rectangle, a midspan point load making the midspan deflect `delta`,
/// Euler–Bernoulli theory, sections turning with the axis, 400 equal intervals.
struct Beam {
    length: f64,
    width: f64,
    height: f64,
    delta: f64,
    centre: [f64; 3],
}

const BEAM: Beam = Beam {
    length: 4.0,
    width: 0.2,
    height: 0.4,
    delta: 0.1,
    centre: [0.0, 0.0, 0.0],
};

impl Beam {
    /// The Rhai expression of the beam, loaded or not.
    fn rhai(&self, loaded: bool) -> String {
        let [x, y, z] = self.centre;
        let load = if loaded {
            format!(".point_load({:?}, {:?})", 0.5 * self.length, self.delta)
        } else {
            String::new()
        };
        format!(
            "beam(#{{ length: {:?}, width: {:?}, height: {:?} }}).simply_supported().theory(\"euler_bernoulli\").segments(400).at({x:?}, {y:?}, {z:?}){load}",
            self.length, self.width, self.height
        )
    }

    /// Deflection v (downward) and slope v′ at x from the pin: v = δ(3ξ − 4ξ³) for ξ = x/L ≤ ½,
    /// mirrored beyond.
    fn axis(&self, x: f64) -> (f64, f64) {
        let (l, d) = (self.length, self.delta);
        let (xi, sign) = if x <= 0.5 * l {
            (x / l, 1.0)
        } else {
            (1.0 - x / l, -1.0)
        };
        (
            d * (3.0 * xi - 4.0 * xi.powi(3)),
            sign * d / l * (3.0 - 12.0 * xi * xi),
        )
    }

    /// Axial shortening ½∫₀ˣ v′² dx = (δ²/2L)(9ξ − 24ξ³ + 28.8ξ⁵) on the first half, and by
    /// symmetry on the second.
    fn shortening(&self, x: f64) -> f64 {
        let (l, d) = (self.length, self.delta);
        let half = |xi: f64| 0.5 * d * d / l * (9.0 * xi - 24.0 * xi.powi(3) + 28.8 * xi.powi(5));
        if x <= 0.5 * l {
            half(x / l)
        } else {
            2.0 * half(0.5) - half(1.0 - x / l)
        }
    }

    /// World displacement of the unloaded beam's point `p`: its section moves down by v, back
    /// by the shortening, and turns by ψ = atan v′ (the top towards +x), so a point z above the
    /// axis moves by (−u + z sin ψ, 0, −v + z (cos ψ − 1)).
    fn displacement(&self, p: [f64; 3]) -> [f64; 3] {
        let x = p[0] - self.centre[0] + 0.5 * self.length;
        let z = p[2] - self.centre[2];
        let (v, slope) = self.axis(x);
        let psi = slope.atan();
        [
            -self.shortening(x) + z * psi.sin(),
            0.0,
            -v + z * (psi.cos() - 1.0),
        ]
    }

    /// How far `p` is from the surface of the unloaded beam, metres.
    fn off_surface(&self, p: [f64; 3]) -> f64 {
        let half = [0.5 * self.length, 0.5 * self.width, 0.5 * self.height];
        off_box(std::array::from_fn(|i| p[i] - self.centre[i]), half)
    }
}

/// A one-sample recipe: `outputs`, a camera block, extra dataset options and a scene
/// expression.
fn recipe(outputs: &str, camera: &str, extra: &str, scene: &str) -> String {
    format!(
        "import \"silo\" as silo;\ndataset(#{{ name: \"ground truth\", seed: 7, samples: 1, views: 3,
            outputs: {outputs},
            camera: #{{ {camera} }},
            {extra}
            scene: |rng| {scene},
        }})\n"
    )
}

/// Three fixed cameras around the beam: from below, from above, and along it, obliquely.
const AROUND: &str = "width: 240, height: 180, fixed: [
    #{ position: [1.0, -6.0, -2.0], target: [0.0, 0.0, 0.0] },
    #{ position: [-1.5, -5.5, 2.5], target: [0.3, 0.0, 0.0] },
    #{ position: [6.0, -2.5, -0.8], target: [0.0, 0.0, 0.0] }]";

/// The channels of a vector EXR, per pixel, in the order given.
fn vectors<const N: usize>(path: &Path, names: [&str; N]) -> Vec<[f32; N]> {
    let (_, channels) = read_exr_channels(path);
    let mut keys: Vec<&String> = channels.keys().collect();
    keys.sort();
    let mut want: Vec<&str> = names.to_vec();
    want.sort();
    assert_eq!(keys, want, "{}", path.display());
    let columns = names.map(|n| &channels[n]);
    (0..columns[0].len())
        .map(|i| columns.map(|c| c[i]))
        .collect()
}

/// The unit camera-axis ray (x, y, 1) of pixel (row, col) with the written K (pinhole).
fn ray(view: &View, row: usize, col: usize) -> [f64; 3] {
    let k = view.k();
    [
        (col as f64 + 0.5 - k[0][2]) / k[0][0],
        (row as f64 + 0.5 - k[1][2]) / k[1][1],
        1.0,
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| a[i] * b[i]).sum()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn wide<const N: usize>(v: [f32; N]) -> [f64; N] {
    v.map(f64::from)
}

/// The camera-axis rotation of a view: world → camera is Rᵀ, the upper-left 3 × 3 of w2c.
fn to_camera(view: &View, n: [f64; 3]) -> [f64; 3] {
    let w2c = view.w2c();
    std::array::from_fn(|i| (0..3).map(|j| w2c[i][j] * n[j]).sum())
}

/// Every float of every EXR, PLY (x, y, z, normals) and GLB position in `out` is finite.
fn assert_every_float_finite(out: &Path) {
    let mut checked = 0;
    for entry in walk(out) {
        let name = entry.to_string_lossy().to_string();
        if name.ends_with(".exr") {
            let (_, channels) = read_exr_channels(&entry);
            for (channel, values) in channels {
                assert!(values.iter().all(|v| v.is_finite()), "{name} {channel}");
            }
            checked += 1;
        } else if name.ends_with(".ply") {
            for (element, rows) in read_ply(&entry) {
                for row in rows {
                    for (key, value) in row {
                        let finite = match value {
                            Property::Double(x) => x.is_finite(),
                            Property::Float(x) => x.is_finite(),
                            _ => true,
                        };
                        assert!(finite, "{name} {element}.{key}");
                    }
                }
            }
            checked += 1;
        } else if name.ends_with(".glb") {
            let glb = Glb::read(&entry);
            assert!(
                glb.positions.iter().flatten().all(|c| c.is_finite()),
                "{name}"
            );
            checked += 1;
        }
    }
    assert!(checked > 0, "no file checked in {}", out.display());
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(walk(&path));
        } else {
            files.push(path);
        }
    }
    files
}

/// Median and the given quantile of some values.
fn quantiles(mut values: Vec<f64>, q: f64) -> (f64, f64) {
    values.sort_by(f64::total_cmp);
    let at = |f: f64| values[((values.len() - 1) as f64 * f).round() as usize];
    (at(0.5), at(q))
}

#[test]
fn normals_are_the_analytic_faces_of_a_box_in_either_frame_and_in_exact_copies() {
    // The box of tests/cameras.rs: 2 × 1 × 0.5 m on the origin; views and rotated, zoomed
    // copies re-rendered through their own cameras.
    let half = [1.0, 0.5, 0.25];
    let augment = "augment: #{ copies: 1, operations: [#{ op: \"warp\", zoom: [0.8, 1.3], rotation: [-3.0, 3.0], shift_x: [-0.1, 0.1], shift_y: 0.0, probability: 1.0 }] },";
    let scene = "assembly(\"box\", [shape::box(2.0, 1.0, 0.5)])";
    let camera = "width: 160, height: 120, pitch: [-0.9, 0.9], yaw: [0.2, 1.3]";
    let outputs = r#"["depth", "mask", "normals"]"#;
    let (_a, in_camera) = render(&recipe(outputs, camera, augment, scene), &[]);
    let world_extra = format!("{augment} normals: \"world\",");
    let (_b, in_world) = render(&recipe(outputs, camera, &world_extra, scene), &[]);
    for view in 0..3 {
        for copy in [None, Some(0)] {
            let v = load(&in_camera, view, copy);
            assert_eq!(load(&in_world, view, copy).json["camera"], v.json["camera"]);
            assert_eq!(v.json["normals"]["axes"], "camera_opencv");
            let cam = vectors(
                &view_path(&in_camera, 0, view, copy, "normals.exr"),
                ["R", "G", "B"],
            );
            let world = vectors(
                &view_path(&in_world, 0, view, copy, "normals.exr"),
                ["R", "G", "B"],
            );
            let c2w = v.c2w();
            let (mut hits, mut on_edges) = (0, 0);
            for row in 0..v.height {
                for col in 0..v.width {
                    let i = row * v.width + col;
                    if v.depth[i] == 0.0 {
                        assert!(cam[i] == [0.0; 3] && world[i] == [0.0; 3]);
                        continue;
                    }
                    // The face the pixel's ray enters the box through, by the slab method.
                    let r = ray(&v, row, col);
                    let d: [f64; 3] =
                        std::array::from_fn(|a| dot([c2w[a][0], c2w[a][1], c2w[a][2]], r));
                    let o = [c2w[0][3], c2w[1][3], c2w[2][3]];
                    let mut entries: Vec<(f64, usize)> = (0..3)
                        .filter(|&a| d[a] != 0.0)
                        .map(|a| (((-half[a] - o[a]) / d[a]).min((half[a] - o[a]) / d[a]), a))
                        .collect();
                    entries.sort_by(|x, y| y.0.total_cmp(&x.0));
                    let (t, axis) = entries[0];
                    if entries.len() > 1 && t - entries[1].0 < 1e-6 * t {
                        on_edges += 1; // the ray passes within rounding of an edge
                        continue;
                    }
                    let mut n = [0.0; 3];
                    n[axis] = -d[axis].signum();
                    hits += 1;
                    assert_eq!(wide(world[i]), n, "view {view} {copy:?} ({row},{col})");
                    let expected = to_camera(&v, n);
                    let got = wide(cam[i]);
                    assert!(
                        (0..3).all(|k| (got[k] - expected[k]).abs() < 1e-6),
                        "{got:?} vs {expected:?}"
                    );
                    assert!(dot(got, r) < 0.0, "faces the camera");
                }
            }
            assert!(
                hits > 1000 && on_edges * 1000 < hits,
                "{hits} hits, {on_edges} on edges"
            );
        }
    }
}

#[test]
fn normals_of_a_bent_beam_agree_with_normals_from_its_depth() {
    let bent = Beam { delta: 0.3, ..BEAM };
    // Narrower than the other views, so faces are many pixels wide between creases.
    let camera = AROUND.replace(
        "width: 240, height: 180,",
        "width: 320, height: 240, fov_y: 0.45,",
    );
    let outputs = r#"["depth", "mask", "normals"]"#;
    let (_dir, out) = render(&recipe(outputs, &camera, "", &bent.rhai(true)), &[]);
    let mut angles = Vec::new();
    for view in 0..3 {
        let v = load(&out, view, None);
        let normals = vectors(
            &view_path(&out, 0, view, None, "normals.exr"),
            ["R", "G", "B"],
        );
        let point = |row: usize, col: usize| {
            let z = f64::from(v.depth[row * v.width + col]);
            ray(&v, row, col).map(|c| c * z)
        };
        for row in 1..v.height - 1 {
            for col in 1..v.width - 1 {
                let i = row * v.width + col;
                if v.depth[i] == 0.0 {
                    continue;
                }
                let n = wide(normals[i]);
                assert!((norm(n) - 1.0).abs() < 1e-6);
                assert!(dot(n, point(row, col)) < 0.0, "({row},{col}) faces away");
                if !v.inside(row, col) {
                    continue;
                }
                // Central differences of the back-projected depth, turned to face the camera.
                let dx: [f64; 3] =
                    std::array::from_fn(|k| point(row, col + 1)[k] - point(row, col - 1)[k]);
                let dy: [f64; 3] =
                    std::array::from_fn(|k| point(row + 1, col)[k] - point(row - 1, col)[k]);
                let g = cross(dx, dy);
                let g = g.map(|c| c / norm(g));
                let facing = if dot(g, point(row, col)) > 0.0 {
                    -1.0
                } else {
                    1.0
                };
                let g = g.map(|c| facing * c);
                angles.push(norm(cross(g, n)).atan2(dot(g, n)).to_degrees());
            }
        }
    }
    // Creases and silhouettes mix two faces in the differences: a tail, not the bulk.
    assert!(angles.len() > 5000, "{}", angles.len());
    let (median, p90) = quantiles(angles, 0.9);
    assert!(
        median < 0.01 && p90 < 0.1,
        "median {median}°, 90th percentile {p90}°"
    );
}

#[test]
fn displacement_and_flow_follow_the_closed_form_deflection() {
    let (mut worst_d, mut worst_flow, mut valid, mut in_frame) = (0.0f64, 0.0f64, 0, 0);
    let lens = ", distortion: #{ k1: -0.15, k2: 0.03, p1: 0.001, p2: -0.0005, k3: 0.002 }";
    for camera in [AROUND.to_string(), format!("{AROUND}{lens}")] {
        let (_dir, out) = render(&recipe(ALL, &camera, "points: 20,", &BEAM.rhai(true)), &[]);
        for view in 0..3 {
            // Loaded view: the point seen minus its displacement is a point of the unloaded
            // beam, displaced as the closed form says.
            let v = load(&out, view, None);
            let d = vectors(
                &view_path(&out, 0, view, None, "displacement.exr"),
                ["R", "G", "B"],
            );
            assert_eq!(v.json["displacement"]["axes"], "world");
            // Flow needs the unloaded image, and its validity the occlusion rays; a lens's
            // curved rays are traced, a pinhole's rasterised.
            let path = if camera.contains("distortion") {
                "traced"
            } else {
                "rasterised"
            };
            let image = serde_json::json!({ "primary": path, "edge_rays": path });
            assert_eq!(
                v.json["visibility"],
                serde_json::json!({
                    "primary": path, "edge_rays": path,
                    "unloaded": image, "secondary": ["flow_occlusion"],
                })
            );
            for row in 0..v.height {
                for col in 0..v.width {
                    let i = row * v.width + col;
                    let Some(p) = v.point_through_lens(row, col) else {
                        assert_eq!(d[i], [0.0; 3]);
                        continue;
                    };
                    let di = wide(d[i]);
                    let rest = std::array::from_fn(|k| p[k] - di[k]);
                    assert!(BEAM.off_surface(rest) < 2e-6, "{rest:?}");
                    let truth = BEAM.displacement(rest);
                    worst_d = worst_d.max(norm(std::array::from_fn(|k| di[k] - truth[k])));
                }
            }
            // Unloaded view: each pixel's point, displaced by the closed form and projected
            // through the written camera and lens, lands at the pixel plus its flow.
            let mut rest = load(&out, view, None);
            rest.depth = read_exr(&view_path(&out, 0, view, None, "rest_depth.exr"));
            let flow = vectors(&view_path(&out, 0, view, None, "flow.exr"), ["R", "G"]);
            let (_, _, _, ok_flow) = read_png(&view_path(&out, 0, view, None, "flow_valid.png"));
            for row in 0..rest.height {
                for col in 0..rest.width {
                    let i = row * rest.width + col;
                    let Some(r) = rest.point_through_lens(row, col) else {
                        assert!(ok_flow[i] == 0 && flow[i] == [0.0; 2]);
                        continue;
                    };
                    let truth = BEAM.displacement(r);
                    let [u, w] =
                        rest.project_through_lens(std::array::from_fn(|k| r[k] + truth[k]));
                    let inside = (1.0..rest.width as f64 - 1.0).contains(&u)
                        && (1.0..rest.height as f64 - 1.0).contains(&w);
                    in_frame += usize::from(inside);
                    if ok_flow[i] == 0 {
                        assert_eq!(flow[i], [0.0; 2]);
                        continue;
                    }
                    valid += 1;
                    let f = wide(flow[i]);
                    let error = (col as f64 + 0.5 + f[0] - u).hypot(row as f64 + 0.5 + f[1] - w);
                    worst_flow = worst_flow.max(error);
                }
            }
        }
        assert_every_float_finite(&out);
    }
    // The mesh is exact at its vertices; inside a triangle the displacement is interpolated
    // linearly. A side face between stations Δx apart is a twisted quad (its sections turn by
    // Δx·κ), so the axial term z·sin ψ is off by up to Δx·H·κ/4 there, κ ≤ 12δ/L².
    let kappa = 12.0 * BEAM.delta / BEAM.length.powi(2);
    let twist = BEAM.length / 400.0 * BEAM.height * kappa / 4.0;
    assert!(
        worst_d < twist + 2e-6,
        "displacement off the closed form by {worst_d} m"
    );
    assert!(
        worst_d > 0.1 * twist,
        "the bound is tight: {worst_d} vs {twist}"
    );
    assert!(
        worst_flow < 0.01,
        "flow off the projection by {worst_flow} px"
    );
    // Nothing hides a point of this beam from these cameras: only silhouette pixels fail.
    assert!(valid * 100 >= in_frame * 97, "{valid} valid of {in_frame}");
}

#[test]
fn the_unloaded_image_is_the_unloaded_beam_rendered_and_ray_distance_is_depth_along_the_ray() {
    let outputs = r#"["rgb", "depth", "mask", "rest_rgb", "rest_depth", "ray_distance", "mesh"]"#;
    let (_a, loaded) = render(&recipe(outputs, AROUND, "", &BEAM.rhai(true)), &[]);
    let (_b, unloaded) = render(&recipe(outputs, AROUND, "", &BEAM.rhai(false)), &[]);
    let read = |out: &Path, view, kind| std::fs::read(view_path(out, 0, view, None, kind)).unwrap();
    for view in 0..3 {
        assert!(read(&loaded, view, "rest_depth.exr") == read(&unloaded, view, "depth.exr"));
        assert!(read(&loaded, view, "rest_rgb.png") == read(&unloaded, view, "rgb.png"));
        assert!(read(&loaded, view, "depth.exr") != read(&unloaded, view, "depth.exr"));
        for out in [&loaded, &unloaded] {
            let v = load(out, view, None);
            let (size, channels) =
                read_exr_channels(&view_path(out, 0, view, None, "ray_distance.exr"));
            assert_eq!(size, (v.width, v.height));
            let distance = &channels["Y"];
            assert_eq!(channels.len(), 1);
            for row in 0..v.height {
                for col in 0..v.width {
                    let i = row * v.width + col;
                    let expected = f64::from(v.depth[i]) * norm(ray(&v, row, col));
                    let got = f64::from(distance[i]);
                    assert!(
                        (got - expected).abs() <= 1e-6 * expected,
                        "{got} vs {expected}"
                    );
                }
            }
        }
    }
    let rest = std::fs::read(sample_path(&loaded, 0, "rest.ply")).unwrap();
    assert!(rest == std::fs::read(sample_path(&unloaded, 0, "mesh.ply")).unwrap());
}

/// A GLB read through the gltf crate: the node holding the mesh, its translation (read from
/// the JSON as a double: the gltf crate keeps node transforms in f32), the root's rotation,
/// and the float32 positions and triangles.
struct Glb {
    translation: [f64; 3],
    root_rotation: [f64; 4],
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl Glb {
    fn read(path: &Path) -> Glb {
        let bytes = std::fs::read(path).unwrap();
        let gltf = gltf::Gltf::from_slice(&bytes).expect("a valid glTF 2.0");
        let blob = gltf.blob.as_ref().expect("a binary chunk");
        let node = gltf.nodes().find(|n| n.mesh().is_some()).unwrap();
        let json_length = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_length]).unwrap();
        let vector = |v: &serde_json::Value| -> Vec<f64> {
            v.as_array()
                .unwrap()
                .iter()
                .map(|c| c.as_f64().unwrap())
                .collect()
        };
        let translation = vector(&json["nodes"][node.index()]["translation"]);
        let root = gltf.scenes().next().unwrap().nodes().next().unwrap();
        let rotation = vector(&json["nodes"][root.index()]["rotation"]);
        assert!(root.children().any(|c| c.index() == node.index()));
        let primitive = node.mesh().unwrap().primitives().next().unwrap();
        let words = |accessor: gltf::Accessor| -> Vec<[u8; 4]> {
            let view = accessor.view().unwrap();
            let start = view.offset() + accessor.offset();
            let n = accessor.count() * accessor.dimensions().multiplicity();
            (0..n)
                .map(|k| blob[start + 4 * k..start + 4 * k + 4].try_into().unwrap())
                .collect()
        };
        let positions = words(primitive.get(&gltf::Semantic::Positions).unwrap());
        let indices = words(primitive.indices().unwrap());
        Glb {
            translation: [translation[0], translation[1], translation[2]],
            root_rotation: [rotation[0], rotation[1], rotation[2], rotation[3]],
            positions: positions
                .chunks(3)
                .map(|c| std::array::from_fn(|k| f32::from_le_bytes(c[k])))
                .collect(),
            triangles: indices
                .chunks(3)
                .map(|c| std::array::from_fn(|k| u32::from_le_bytes(c[k])))
                .collect(),
        }
    }
}

/// The faces of a mesh PLY: vertex indices and part id.
type Faces = Vec<([u32; 3], i32)>;

/// Vertices (x, y, z) and faces of a mesh PLY.
fn ply_mesh(path: &Path) -> (Vec<[f64; 3]>, Faces) {
    let ply = read_ply(path);
    let double = |p: &Property| match p {
        Property::Double(x) => *x,
        other => panic!("{other:?} is not a double"),
    };
    let vertices = ply["vertex"]
        .iter()
        .map(|v| [double(&v["x"]), double(&v["y"]), double(&v["z"])])
        .collect();
    let faces = ply["face"]
        .iter()
        .map(|f| match (&f["vertex_indices"], &f["part"]) {
            (Property::ListInt(i), Property::Int(part)) => {
                assert_eq!(i.len(), 3);
                ([i[0] as u32, i[1] as u32, i[2] as u32], *part)
            }
            other => panic!("{other:?}"),
        })
        .collect();
    (vertices, faces)
}

/// Distance from `p` to triangle (a, b, c), by its closest point (Ericson, Real-Time
/// Collision Detection, §5.1.5).
fn triangle_distance(p: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> f64 {
    let sub = |x: [f64; 3], y: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| x[k] - y[k]) };
    let along =
        |o: [f64; 3], e: [f64; 3], t: f64| -> [f64; 3] { std::array::from_fn(|k| o[k] + t * e[k]) };
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let closest = {
        let (d1, d2) = (dot(ab, ap), dot(ac, ap));
        let bp = sub(p, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        let cp = sub(p, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        let (va, vb, vc) = (d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2);
        if d1 <= 0.0 && d2 <= 0.0 {
            a
        } else if d3 >= 0.0 && d4 <= d3 {
            b
        } else if d6 >= 0.0 && d5 <= d6 {
            c
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            along(a, ab, d1 / (d1 - d3))
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            along(a, ac, d2 / (d2 - d6))
        } else if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
            along(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)))
        } else {
            let denominator = 1.0 / (va + vb + vc);
            let (v, w) = (vb * denominator, vc * denominator);
            std::array::from_fn(|k| a[k] + ab[k] * v + ac[k] * w)
        }
    };
    norm(sub(p, closest))
}

#[test]
fn meshes_and_points_read_back_through_other_readers() {
    // Far from the origin, where float32 world coordinates would be off by centimetres.
    let far = Beam {
        centre: [3.0e5, -2.0e5, 40.0],
        ..BEAM
    };
    let camera = "width: 96, height: 64, fixed: [#{ position: [300001.0, -200006.0, 39.0] }, #{ position: [299998.0, -200005.0, 43.0] }, #{ position: [300006.0, -200002.0, 40.0] }]";
    let scene = far.rhai(true).replace(".segments(400)", ".segments(40)");
    let text = recipe(ALL, camera, "points: 3000,", &scene);
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "far.rhai", &text);
    let out = dir.path().join("out");
    ok(run(&path, &out, &[]));
    // The mesh the build stage made, through the library.
    let built =
        shmgen::pipeline::prepare(&shmgen::recipe::Recipe::load(&path, &[]).unwrap(), 0).unwrap();
    let (vertices, faces) = ply_mesh(&sample_path(&out, 0, "mesh.ply"));
    let (rest, rest_faces) = ply_mesh(&sample_path(&out, 0, "rest.ply"));
    assert_eq!(vertices.len(), built.mesh.positions.len());
    assert!(
        vertices
            .iter()
            .zip(&built.mesh.positions)
            .all(|(v, p)| *v == p.to_array())
    );
    assert!(
        rest.iter()
            .zip(&built.rest)
            .all(|(v, p)| *v == p.to_array())
    );
    assert_eq!(faces, rest_faces, "the same faces in the same order");
    let triangles: Vec<[u32; 3]> = faces.iter().map(|f| f.0).collect();
    assert_eq!(triangles, built.mesh.triangles);
    assert!(faces.iter().all(|f| f.1 == 1), "one part, id 1");
    // The unloaded mesh is the analytic box, to its corners.
    assert!(rest.iter().all(|&p| far.off_surface(p) < 1e-9));
    let bounds = |points: &[[f64; 3]]| {
        points.iter().fold(
            ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |(lo, hi), p| {
                (
                    std::array::from_fn(|k| lo[k].min(p[k])),
                    std::array::from_fn(|k| hi[k].max(p[k])),
                )
            },
        )
    };
    let (lo, hi) = bounds(&rest);
    for k in 0..3 {
        let half = [far.length, far.width, far.height][k] / 2.0;
        assert_eq!((lo[k], hi[k]), (far.centre[k] - half, far.centre[k] + half));
    }
    // The loaded vertices moved as the closed form says.
    for (v, r) in vertices.iter().zip(&rest) {
        let d = far.displacement(*r);
        assert!(
            (0..3).all(|k| (v[k] - r[k] - d[k]).abs() < 1e-9),
            "{v:?} from {r:?}"
        );
    }

    // GLB: float32 positions about a double translation give the world mesh to float32 of the
    // beam's size, and the root turns +z up into glTF's +y up.
    let glb = Glb::read(&sample_path(&out, 0, "mesh.glb"));
    assert_eq!(glb.triangles, triangles);
    for (p, v) in glb.positions.iter().zip(&vertices) {
        let world: [f64; 3] = std::array::from_fn(|k| glb.translation[k] + f64::from(p[k]));
        assert!(
            (0..3).all(|k| (world[k] - v[k]).abs() < 1e-6),
            "{world:?} vs {v:?}"
        );
    }
    let [x, y, z, w] = glb.root_rotation;
    // The rotated +z axis: the third column of the quaternion's matrix.
    let up = [
        2.0 * (x * z + w * y),
        2.0 * (y * z - w * x),
        1.0 - 2.0 * (x * x + y * y),
    ];
    assert!((up[0]).abs() < 1e-12 && (up[1] - 1.0).abs() < 1e-12 && up[2].abs() < 1e-12);

    // Points: as many as asked, on the loaded surface, with the normal of the face they lie on,
    // spread by area (each face class holds its share of the points, within 4.5 σ).
    let ply = read_ply(&sample_path(&out, 0, "points.ply"));
    let points = &ply["vertex"];
    assert_eq!(points.len(), 3000);
    let corner = |t: [u32; 3]| t.map(|i| vertices[i as usize]);
    let normal = |t: [u32; 3]| {
        let [a, b, c] = corner(t);
        let n = cross(
            std::array::from_fn(|k| b[k] - a[k]),
            std::array::from_fn(|k| c[k] - a[k]),
        );
        n.map(|x| x / norm(n))
    };
    let class = |n: [f64; 3]| {
        (0..3)
            .max_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
            .unwrap()
    };
    let mut counted = [0usize; 3];
    for point in points {
        let get = |key: &str| match &point[key] {
            Property::Double(x) => *x,
            Property::Float(x) => f64::from(*x),
            other => panic!("{other:?}"),
        };
        let p = [get("x"), get("y"), get("z")];
        let n = [get("nx"), get("ny"), get("nz")];
        let (distance, nearest) = triangles
            .iter()
            .map(|&t| (triangle_distance(p, corner(t)), t))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap();
        assert!(distance < 1e-8, "{p:?} is {distance} m off the mesh");
        assert!(dot(n, normal(nearest)) > 1.0 - 1e-6, "{n:?}");
        counted[class(n)] += 1;
    }
    let mut area = [0.0; 3];
    for &t in &triangles {
        let [a, b, c] = corner(t);
        let n = cross(
            std::array::from_fn(|k| b[k] - a[k]),
            std::array::from_fn(|k| c[k] - a[k]),
        );
        area[class(n)] += 0.5 * norm(n);
    }
    let total: f64 = area.iter().sum();
    for k in 0..3 {
        let share = area[k] / total;
        let expected = 3000.0 * share;
        let sigma = (3000.0 * share * (1.0 - share)).sqrt();
        assert!(
            (counted[k] as f64 - expected).abs() < 4.5 * sigma.max(1.0),
            "{counted:?} vs {area:?}"
        );
    }
    assert_every_float_finite(&out);
}

#[test]
fn flow_is_invalid_where_the_loaded_beam_leaves_the_frame_or_goes_behind_a_box() {
    // The camera looks down at the beam; loaded by 0.6 m its middle drops out of the bottom of
    // the frame, and part of it behind a box standing in front of it.
    let beam = Beam { delta: 0.6, ..BEAM };
    let box_centre = [0.75, -1.0, 0.05];
    let box_half = [0.25, 0.1, 0.1];
    let scene = format!(
        "[{}, assembly(\"box\", [shape::box(0.5, 0.2, 0.2).translate({:?}, {:?}, {:?})])]",
        beam.rhai(true),
        box_centre[0],
        box_centre[1],
        box_centre[2]
    );
    let camera = "width: 200, height: 150, fixed: [#{ position: [0.0, -3.5, 1.3], target: [0.0, 0.0, 1.3] }]";
    let text = recipe(ALL, camera, "points: 10,", &scene).replace("views: 3", "views: 1");
    let (_dir, out) = render(&text, &[]);
    let mut rest = load(&out, 0, None);
    rest.depth = read_exr(&view_path(&out, 0, 0, None, "rest_depth.exr"));
    let flow = vectors(&view_path(&out, 0, 0, None, "flow.exr"), ["R", "G"]);
    let (_, _, _, ok_flow) = read_png(&view_path(&out, 0, 0, None, "flow_valid.png"));
    let eye = rest.json["camera"]["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect::<Vec<_>>();
    // Whether the segment from the camera to `q` passes through the box (slab method).
    let behind_box = |q: [f64; 3], margin: f64| {
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for k in 0..3 {
            let (o, d) = (eye[k] - box_centre[k], q[k] - eye[k]);
            let h = box_half[k] + margin;
            if d == 0.0 {
                if o.abs() > h {
                    return false;
                }
                continue;
            }
            let (a, b) = ((-h - o) / d, (h - o) / d);
            (t0, t1) = (t0.max(a.min(b)), t1.min(a.max(b)));
        }
        t0 < t1
    };
    let (mut left, mut hidden, mut seen, mut disagree) = (0, 0, 0, 0);
    for row in 0..rest.height {
        for col in 0..rest.width {
            let i = row * rest.width + col;
            let Some(r) = rest.point(row, col) else {
                continue;
            };
            if beam.off_surface(r) > 1e-5 {
                continue; // the box, which does not move
            }
            let d = beam.displacement(r);
            let q = std::array::from_fn(|k| r[k] + d[k]);
            let ([u, w], _) = rest.project(q);
            let outside =
                !(0.0..rest.width as f64).contains(&u) || !(0.0..rest.height as f64).contains(&w);
            let far_outside = !(-0.01..rest.width as f64 + 0.01).contains(&u)
                || !(-0.01..rest.height as f64 + 0.01).contains(&w);
            if far_outside || behind_box(q, -1e-4) {
                assert!(
                    ok_flow[i] == 0 && flow[i] == [0.0; 2],
                    "({row},{col}) {u} {w}"
                );
                if far_outside {
                    left += 1;
                } else {
                    hidden += 1;
                }
            } else if !outside && !behind_box(q, 1e-4) {
                seen += 1;
                disagree += usize::from(ok_flow[i] == 0);
            }
        }
    }
    assert!(
        left > 100 && hidden > 100 && seen > 1000,
        "{left} left, {hidden} hidden, {seen} seen"
    );
    // Only the beam's own silhouette can hide a point no analytic test above catches.
    assert!(disagree * 100 < seen, "{disagree} of {seen}");
    assert_every_float_finite(&out);
}

#[test]
fn a_grazing_view_keeps_normals_facing_and_flow_on_the_closed_form() {
    // 5 cm above the top face's plane at 5 m: the top face is seen at 0.6°.
    let camera = "width: 240, height: 120, fov_y: 0.5, fixed: [#{ position: [0.5, -5.0, 0.25], target: [0.0, 0.0, 0.2] }]";
    let text = recipe(ALL, camera, "points: 10,", &BEAM.rhai(true)).replace("views: 3", "views: 1");
    let (_dir, out) = render(&text, &[]);
    let v = load(&out, 0, None);
    let normals = vectors(&view_path(&out, 0, 0, None, "normals.exr"), ["R", "G", "B"]);
    let mut top = 0;
    for row in 0..v.height {
        for col in 0..v.width {
            let i = row * v.width + col;
            if v.depth[i] > 0.0 {
                let n = wide(normals[i]);
                assert!((norm(n) - 1.0).abs() < 1e-6 && dot(n, ray(&v, row, col)) < 0.0);
                top += usize::from(n[1] < -0.9); // camera y is down: the top face
            }
        }
    }
    assert!(top > 20, "{top} pixels of the top face");
    let mut rest = load(&out, 0, None);
    rest.depth = read_exr(&view_path(&out, 0, 0, None, "rest_depth.exr"));
    let flow = vectors(&view_path(&out, 0, 0, None, "flow.exr"), ["R", "G"]);
    let (_, _, _, ok_flow) = read_png(&view_path(&out, 0, 0, None, "flow_valid.png"));
    let mut valid = 0;
    for row in 0..rest.height {
        for col in 0..rest.width {
            let i = row * rest.width + col;
            if ok_flow[i] == 0 {
                continue;
            }
            let r = rest.point(row, col).unwrap();
            let d = BEAM.displacement(r);
            let ([u, w], _) = rest.project(std::array::from_fn(|k| r[k] + d[k]));
            let f = wide(flow[i]);
            let error = (col as f64 + 0.5 + f[0] - u).hypot(row as f64 + 0.5 + f[1] - w);
            assert!(error < 0.01, "({row},{col}) {error} px");
            valid += 1;
        }
    }
    assert!(valid > 1000, "{valid}");
    assert_every_float_finite(&out);
}

#[test]
fn a_damaged_silo_moves_its_shell_only_and_radially_through_a_distorting_lens() {
    let damage = "ovalisation: [0.12, 3, 0.3], dimple: [0.1, 1.0, 4.0, 0.8]";
    let scene = format!("silo::water_silo(#{{ {damage} }})");
    let camera = "width: 160, height: 120, distortion: #{ k1: -0.2, k2: 0.05, p1: 0.001, p2: -0.001, k3: 0.0 }, pitch: [-0.2, 0.6]";
    let augment = "augment: #{ copies: 1, operations: [#{ op: \"warp\", zoom: [0.9, 1.1], rotation: [-1.0, 1.0], shift_x: 0.0, shift_y: 0.0, probability: 1.0 }] },";
    let (_dir, out) = render(
        &recipe(ALL, camera, &format!("{augment} points: 500,"), &scene),
        &[],
    );
    let json = read_json(&view_path(&out, 0, 0, None, "json"));
    let parts = json["segmentation"]["part_ids"].as_array().unwrap();
    let shell = parts.iter().position(|p| p == "shell").unwrap() as u8;
    let mut moved = 0;
    for view in 0..3 {
        for copy in [None, Some(0)] {
            let d = vectors(
                &view_path(&out, 0, view, copy, "displacement.exr"),
                ["R", "G", "B"],
            );
            let (_, _, _, part) = read_png(&view_path(&out, 0, view, copy, "parts.png"));
            for (i, d) in d.iter().enumerate() {
                // Shell patterns act in the horizontal plane; nothing else is damaged.
                assert_eq!(d[2], 0.0);
                let horizontal = f64::from(d[0]).hypot(f64::from(d[1]));
                if part[i] == shell {
                    assert!(horizontal <= 0.12 + 0.1 + 1e-6, "{d:?}");
                    moved += usize::from(horizontal > 1e-3);
                } else {
                    assert_eq!(*d, [0.0; 3], "part {}", part[i]);
                }
            }
        }
    }
    assert!(moved > 500, "{moved}");
    assert_every_float_finite(&out);
}

#[test]
fn photometric_copies_keep_every_geometric_layer_byte_identical() {
    let augment = "augment: #{ copies: 2, operations: [
        #{ op: \"colour_jitter\", brightness: [0.8, 1.2], contrast: [0.8, 1.2], saturation: [0.8, 1.2], hue: [-0.1, 0.1], probability: 1.0 },
        #{ op: \"noise\", model: \"gaussian\", sigma: 5.0, probability: 1.0 },
        #{ op: \"erase\", count: 2, area: [0.05, 0.1], aspect: [0.5, 2.0], probability: 1.0 }] },";
    let camera = "width: 96, height: 72, fixed: [#{ position: [1.0, -6.0, -2.0] }, #{ position: [-1.5, -5.5, 2.5] }, #{ position: [6.0, -2.5, -0.8] }]";
    let (_dir, out) = render(
        &recipe(
            ALL,
            camera,
            &format!("{augment} points: 10,"),
            &BEAM.rhai(true),
        ),
        &[],
    );
    for view in 0..3 {
        let read = |copy, kind| std::fs::read(view_path(&out, 0, view, copy, kind)).unwrap();
        for kind in [
            "normals.exr",
            "displacement.exr",
            "flow.exr",
            "flow_valid.png",
            "rest_depth.exr",
            "ray_distance.exr",
        ] {
            for copy in [0, 1] {
                assert!(
                    read(None, kind) == read(Some(copy), kind),
                    "view {view} copy {copy}: {kind}"
                );
            }
        }
        // The unloaded image goes through the same photometric operations as the loaded one.
        assert!(read(None, "rest_rgb.png") != read(Some(0), "rest_rgb.png"));
    }
}

#[test]
fn image_space_warps_turn_camera_normals_and_carry_the_other_layers_but_refuse_flow() {
    let operations = "operations: [#{ op: \"warp\", zoom: [0.9, 1.2], rotation: [-0.8, 0.8], shift_x: [-0.05, 0.05], shift_y: 0.0, probability: 1.0 }]";
    let camera = "width: 160, height: 120, fov_y: 0.6, fixed: [#{ position: [1.0, -6.0, -2.0] }, #{ position: [-1.5, -5.5, 2.5] }, #{ position: [6.0, -2.5, -0.8] }]";
    let outputs =
        r#"["depth", "mask", "normals", "displacement", "rest_depth", "ray_distance", "rest_rgb"]"#;
    let image = recipe(
        outputs,
        camera,
        &format!("augment: #{{ copies: 1, mode: \"image\", {operations} }},"),
        &BEAM.rhai(true),
    );
    let exact = recipe(
        outputs,
        camera,
        &format!("augment: #{{ copies: 1, {operations} }},"),
        &BEAM.rhai(true),
    );
    let (_a, warped) = render(&image, &[]);
    let (_b, rendered) = render(&exact, &[]);
    for view in 0..3 {
        let (w, e) = (load(&warped, view, Some(0)), load(&rendered, view, Some(0)));
        assert_eq!(
            w.json["camera"], e.json["camera"],
            "the same draws, the same camera"
        );
        let layer =
            |out: &Path, kind| vectors(&view_path(out, 0, view, Some(0), kind), ["R", "G", "B"]);
        let (nw, ne) = (
            layer(&warped, "normals.exr"),
            layer(&rendered, "normals.exr"),
        );
        let (dw, de) = (
            layer(&warped, "displacement.exr"),
            layer(&rendered, "displacement.exr"),
        );
        let (mut compared, mut agree) = (0, 0);
        for row in 0..w.height {
            for col in 0..w.width {
                if !(w.inside(row, col) && e.inside(row, col)) {
                    continue;
                }
                // Nearest-neighbour sampling may pick the face next door at a crease; the bulk
                // of the pixels agrees with the exact render to rounding.
                let i = row * w.width + col;
                compared += 1;
                let close = |a: [f32; 3], b: [f32; 3], tol: f64| {
                    (0..3).all(|k| (f64::from(a[k]) - f64::from(b[k])).abs() < tol)
                };
                agree += usize::from(close(nw[i], ne[i], 1e-5) && close(dw[i], de[i], 2e-3));
            }
        }
        assert!(
            compared > 300 && agree * 100 > compared * 90,
            "view {view}: {agree}/{compared}"
        );
    }
    let with_flow = image.replace("\"normals\"", "\"normals\", \"flow\"");
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "flow.rhai", with_flow);
    let output = run(&path, &dir.path().join("out"), &[]);
    let text = common::stderr(&output);
    assert!(
        !output.status.success() && text.contains("flow is not defined on a warped image"),
        "{text}"
    );
    // A bad frame for normals is named with what is accepted.
    let bad = recipe(outputs, camera, "normals: \"sideways\",", &BEAM.rhai(true));
    let path = write(dir.path(), "bad.rhai", bad);
    let output = run(&path, &dir.path().join("bad"), &[]);
    let text = common::stderr(&output);
    assert!(
        !output.status.success()
            && text.contains("dataset.normals = \"sideways\"")
            && text.contains("\"world\""),
        "{text}"
    );
}

#[test]
fn view_records_name_the_sample_files_and_the_conventions() {
    let (_dir, out) = render(
        &recipe(
            ALL,
            AROUND,
            "normals: \"world\", points: 10,",
            &BEAM.rhai(true),
        ),
        &[],
    );
    let json = read_json(&view_path(&out, 0, 1, None, "json"));
    for kind in ["mesh.ply", "rest.ply", "mesh.glb", "points.ply"] {
        let file = json["sample_files"][kind].as_str().unwrap();
        assert!(out.join(file).is_file(), "{file}");
    }
    assert_eq!(json["normals"]["axes"], "world");
    assert_eq!(json["flow"]["channels"], serde_json::json!(["R", "G"]));
    assert_eq!(
        json["normals"]["channels"],
        serde_json::json!(["R", "G", "B"])
    );
    assert_eq!(
        json["displacement"]["channels"],
        serde_json::json!(["R", "G", "B"])
    );
    assert_eq!(json["depth"]["channel"], "Y");
    assert_eq!(json["ray_distance"]["channel"], "Y");
    let manifest = std::fs::read_to_string(out.join("manifest.jsonl")).unwrap();
    assert!(manifest.contains("samples/0000/000000.points.ply"));
}

#[test]
fn the_rest_mesh_is_the_unbent_shape_for_bent_imports_and_the_still_beam_for_vibrations() {
    // A box and an imported tetrahedron bent as beams: their rest mesh is the mesh of the same
    // assembly unbent, vertex for vertex and face for face.
    let dir = tempfile::tempdir().unwrap();
    let tetra = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/tetra.obj");
    std::fs::copy(tetra, dir.path().join("tetra.obj")).unwrap();
    let bend = |length: f64| {
        format!(
            ".deform_as_beam(\"x\", \"-z\", beam(#{{ length: {length:?}, width: 0.2, height: 0.2 }}).point_load({:?}, 0.05))",
            0.5 * length
        )
    };
    let assembly = |bent: bool| {
        let (box_bend, tetra_bend) = if bent {
            (bend(2.0), bend(1.0))
        } else {
            (String::new(), String::new())
        };
        format!(
            "assembly(\"bent\", [shape::box(2.0, 0.2, 0.2){box_bend}.translate(0.0, 0.0, 1.0), shape::mesh(\"tetra.obj\"){tetra_bend}.translate(2.0, 0.0, 0.0)])"
        )
    };
    let camera = "width: 32, height: 24";
    let mut meshes = Vec::new();
    for bent in [true, false] {
        let path = write(
            dir.path(),
            &format!("bent_{bent}.rhai"),
            recipe(r#"["mesh"]"#, camera, "", &assembly(bent)),
        );
        let out = dir.path().join(format!("out_{bent}"));
        ok(run(&path, &out, &[]));
        let read = |kind| std::fs::read(sample_path(&out, 0, kind)).unwrap();
        meshes.push((read("mesh.ply"), read("rest.ply")));
    }
    let ((bent, bent_rest), (still, still_rest)) = (&meshes[0], &meshes[1]);
    assert!(bent_rest == still && still_rest == still && bent != still);

    // A vibration snapshot moves the beam about its still position: the rest mesh is the
    // analytic box.
    let vibrating = BEAM.rhai(false).replace(
        ".segments(400)",
        ".segments(60).vibration([[1, 0.05], [3, 0.02]])",
    );
    let (_dir, out) = render(&recipe(r#"["mesh"]"#, camera, "", &vibrating), &[]);
    let (rest, _) = ply_mesh(&sample_path(&out, 0, "rest.ply"));
    let (loaded, _) = ply_mesh(&sample_path(&out, 0, "mesh.ply"));
    assert!(rest.iter().all(|&p| BEAM.off_surface(p) < 1e-12));
    assert!(loaded.iter().any(|&p| BEAM.off_surface(p) > 0.01));
    for k in 0..3 {
        let extent = rest.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(extent, 0.5 * [BEAM.length, BEAM.width, BEAM.height][k]);
    }
}
