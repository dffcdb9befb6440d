//! Fixtures shared by the readers' tests, and the tests that cover every format at once or the
//! entry point itself (dispatch by extension, export, robustness to damaged files).

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::{ImportOptions, Imported, export_ply, import_mesh};
use crate::geometry::Mesh;

pub(super) fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/meshes")
        .join(name)
}

pub(super) fn import(path: &Path) -> Result<Imported, String> {
    import_mesh(path, ImportOptions::default())
}

pub(super) fn err(path: &Path) -> String {
    match import(path) {
        Ok(_) => panic!("{} imported, but should fail", path.display()),
        Err(e) => e,
    }
}

pub(super) fn assert_mentions(e: &str, words: &[&str]) {
    for w in words {
        assert!(e.contains(w), "error {e:?} does not mention {w:?}");
    }
}

pub(super) fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// Positions as an order-free set of exact bit patterns.
fn position_set(mesh: &Mesh) -> Vec<[u64; 3]> {
    let mut v: Vec<_> = mesh
        .positions
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect();
    v.sort();
    v.dedup();
    v
}

pub(super) fn tetrahedron() -> Mesh {
    Mesh {
        positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    }
}

const CUBE_CORNERS: [[f32; 3]; 8] = [
    [0., 0., 0.],
    [1., 0., 0.],
    [1., 1., 0.],
    [0., 1., 0.],
    [0., 0., 1.],
    [1., 0., 1.],
    [1., 1., 1.],
    [0., 1., 1.],
];
/// Outward counter-clockwise quads of the unit cube.
const CUBE_QUADS: [[u32; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [2, 3, 7, 6],
    [1, 2, 6, 5],
    [0, 4, 7, 3],
];

/// The unit cube [0, 1]³, wound outwards.
pub(crate) fn cube() -> Mesh {
    Mesh {
        positions: CUBE_CORNERS
            .iter()
            .map(|c| DVec3::from_array(c.map(f64::from)))
            .collect(),
        triangles: CUBE_QUADS
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect(),
    }
}

fn cube_obj() -> String {
    let mut s = String::from("o one\n");
    for c in CUBE_CORNERS {
        s += &format!("v {} {} {}\n", c[0], c[1], c[2]);
    }
    for (k, q) in CUBE_QUADS.iter().enumerate() {
        if k == 3 {
            s += "o two\n"; // a second object, merged with the first
        }
        s += &format!("f {} {} {} {}\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
    }
    s
}

fn cube_ascii_ply() -> String {
    let mut s = String::from(
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n\
         element face 6\nproperty list uchar uint vertex_index\nend_header\n",
    );
    for c in CUBE_CORNERS {
        s += &format!("{} {} {}\n", c[0], c[1], c[2]);
    }
    for q in CUBE_QUADS {
        s += &format!("4 {} {} {} {}\n", q[0], q[1], q[2], q[3]);
    }
    s
}

fn binary_stl(mesh: &Mesh) -> Vec<u8> {
    let mut b = b"solid-looking header of a binary STL".to_vec();
    b.resize(80, 0);
    b.extend_from_slice(&(mesh.triangles.len() as u32).to_le_bytes());
    for t in 0..mesh.triangles.len() {
        b.extend_from_slice(&[0; 12]); // normals are ignored on reading
        for p in mesh.triangle(t) {
            for c in p.to_array() {
                b.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        b.extend_from_slice(&[0, 0]);
    }
    b
}

/// A glTF with an external .bin next to it; `nodes` is the JSON of the node list, whose
/// first node is the scene's root.
pub(super) fn write_gltf(dir: &Path, name: &str, mesh: &Mesh, nodes: &str) -> PathBuf {
    let mut bin: Vec<u8> = mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array().map(|c| c as f32))
        .flat_map(f32::to_le_bytes)
        .collect();
    let pos_len = bin.len();
    bin.extend(
        mesh.triangles
            .iter()
            .flatten()
            .flat_map(|&i| (i as u16).to_le_bytes()),
    );
    std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":{nodes},
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3"}},
                     {{"bufferView":1,"componentType":5123,"count":{},"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},
                       {{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}],
        "buffers":[{{"uri":"{name}.bin","byteLength":{}}}]}}"#,
        mesh.positions.len(),
        3 * mesh.triangles.len(),
        bin.len() - pos_len,
        bin.len()
    );
    write(dir, &format!("{name}.gltf"), json.as_bytes())
}

pub(super) fn assert_same_geometry(got: &Mesh, want: &Mesh, volume: f64, what: &str) {
    assert_eq!(position_set(got), position_set(want), "{what}: positions");
    assert_eq!(
        got.triangles.len(),
        want.triangles.len(),
        "{what}: triangle count"
    );
    assert!(
        (got.signed_volume() - volume).abs() < 1e-12,
        "{what}: volume {} != {volume}",
        got.signed_volume()
    );
}

#[test]
fn tetrahedron_reads_the_same_in_every_format() {
    let files = [
        "tetra.obj",
        "tetra.ply",
        "tetra_ascii.stl",
        "tetra_binary.stl",
        "tetra_binary_solid_header.stl",
        "tetra.gltf",
        "tetra.glb",
    ];
    for name in files {
        let imported = import(&corpus(name)).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            imported.warnings.is_empty(),
            "{name}: {:?}",
            imported.warnings
        );
        assert_same_geometry(&imported.mesh, &tetrahedron(), 1.0 / 6.0, name);
    }
}

#[test]
fn cube_reads_the_same_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let want = cube();
    let files = [
        write(d, "cube.OBJ", cube_obj().as_bytes()),
        write(d, "cube.ply", cube_ascii_ply().as_bytes()),
        write(d, "cube_binary.ply", &export_ply(&want)),
        write(d, "cube.Stl", &binary_stl(&want)),
        write_gltf(d, "cube", &want, r#"[{"mesh":0}]"#),
    ];
    for path in &files {
        let imported = import(path).unwrap_or_else(|e| panic!("{e}"));
        assert_same_geometry(&imported.mesh, &want, 1.0, &path.display().to_string());
    }
    let quads = import(&files[0]).unwrap();
    assert_eq!(
        quads.warnings,
        ["fan-triangulated 6 polygons with more than 3 vertices"]
    );
}

#[test]
fn export_then_import_is_exact() {
    let mut mesh = cube();
    // Values that do not survive a round trip through f32 or decimal text.
    mesh.positions[6] = DVec3::new(1.0 + 1e-15, 1.0 / 3.0 + 1.0, 0.1 + 0.2 + 0.7);
    mesh.positions.push(DVec3::new(0.1, -1e-300, 5e-324)); // unused vertices stay
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "round.ply", &export_ply(&mesh));
    let back = import(&path).unwrap();
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);
    let bits = |m: &Mesh| {
        m.positions
            .iter()
            .map(|p| p.to_array().map(f64::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&back.mesh), bits(&mesh));
    assert_eq!(back.mesh.triangles, mesh.triangles);
}

#[test]
fn empty_missing_and_unknown_files_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    for (ext, words) in [
        ("obj", &["the mesh has no triangles"][..]),
        ("ply", &["bad PLY header"]),
        ("stl", &["empty STL file"]),
        ("gltf", &["invalid glTF"]),
        ("glb", &["invalid glTF"]),
    ] {
        let path = write(dir.path(), &format!("empty.{ext}"), b"");
        let e = err(&path);
        assert_mentions(&e, &[&format!("empty.{ext}")]);
        assert_mentions(&e, words);
    }
    let e = err(&dir.path().join("missing.stl"));
    assert_mentions(&e, &["missing.stl", "cannot open"]);
    let e = err(&write(dir.path(), "mesh.3ds", b"x"));
    assert_mentions(
        &e,
        &[
            "mesh.3ds",
            "unsupported extension '.3ds'",
            ".obj, .ply, .stl, .gltf, .glb",
        ],
    );
    assert_mentions(
        &err(&write(dir.path(), "noext", b"x")),
        &["no file extension"],
    );
}

/// Random damage to every valid file must give Ok or Err, never a panic.
#[test]
fn corrupted_files_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = 0x9e3779b97f4a7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for name in [
        "tetra.obj",
        "tetra.ply",
        "tetra_ascii.stl",
        "tetra_binary.stl",
        "tetra.gltf",
        "tetra.glb",
    ] {
        let original = std::fs::read(corpus(name)).unwrap();
        let ext = name.rsplit('.').next().unwrap();
        for round in 0..300 {
            let mut bytes = original.clone();
            for _ in 0..1 + next() % 4 {
                let at = (next() % bytes.len() as u64) as usize;
                match next() % 3 {
                    0 => bytes[at] = next() as u8,
                    1 => bytes.truncate(at),
                    _ => bytes[at] = b"0123456789-.e \n/"[(next() % 16) as usize],
                }
                if bytes.is_empty() {
                    break;
                }
            }
            let path = write(dir.path(), &format!("fuzz{round}.{ext}"), &bytes);
            let _ = import(&path);
        }
    }
}

/// The tetrahedron with vertex 2's y written as `y`, in each format (text formats write the
/// word as given; binary ones store the value).
fn tetrahedron_with_y(dir: &Path, y: &str) -> Vec<PathBuf> {
    let mut mesh = tetrahedron();
    mesh.positions[2].y = y.parse().unwrap();
    let corner = |i: usize| {
        let p = tetrahedron().positions[i];
        if i == 2 {
            format!("{} {y} {}", p.x, p.z)
        } else {
            format!("{} {} {}", p.x, p.y, p.z)
        }
    };
    let mut obj = String::new();
    let mut ply = String::from(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
         element face 4\nproperty list uchar int vertex_indices\nend_header\n",
    );
    for i in 0..4 {
        obj += &format!("v {}\n", corner(i));
        ply += &format!("{}\n", corner(i));
    }
    let mut stl = String::from("solid t\n");
    for t in &mesh.triangles {
        obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        ply += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
        stl += "facet normal 0 0 0\nouter loop\n";
        for &i in t {
            stl += &format!("vertex {}\n", corner(i as usize));
        }
        stl += "endloop\nendfacet\n";
    }
    stl += "endsolid t\n";
    let mut glb_mesh = mesh.clone();
    glb_mesh.positions[2].y = y.parse::<f32>().unwrap() as f64;
    vec![
        write(dir, "bad.obj", obj.as_bytes()),
        write(dir, "bad_ascii.ply", ply.as_bytes()),
        write(dir, "bad_binary.ply", &export_ply(&mesh)),
        write(dir, "bad_ascii.stl", stl.as_bytes()),
        write(dir, "bad_binary.stl", &binary_stl(&glb_mesh)),
        // A scaling node: the value is checked as stored, not as the transform leaves it.
        write_gltf(dir, "bad", &glb_mesh, r#"[{"mesh":0,"scale":[2,2,2]}]"#),
    ]
}

/// How a reader names the tetrahedron's vertex 2: STL has no shared vertices, only corners
/// (vertex 2 is the first triangle's second corner).
fn vertex_2(name: &str) -> &'static str {
    if name.ends_with(".stl") {
        "vertex 1 of triangle 0"
    } else {
        "vertex 2"
    }
}

#[test]
fn bad_numbers_name_the_file_the_vertex_and_the_value() {
    let dir = tempfile::tempdir().unwrap();
    for word in ["nan", "inf", "-inf"] {
        for path in tetrahedron_with_y(dir.path(), word) {
            let e = err(&path);
            let name = path.file_name().unwrap().to_str().unwrap();
            assert_mentions(&e, &[name, vertex_2(name)]);
            // The value as the file has it (binary files: as the number it stores).
            let value = word.replace("nan", "NaN");
            assert!(
                e.contains(&format!("'{word}'")) || e.contains(&format!(", {value}, ")),
                "{name}: {e:?} does not show {word}"
            );
            assert!(e.contains("finite"), "{name}: {e:?}");
            assert!(
                !e.contains('\n') && !e.contains("expected"),
                "{name}: {e:?}"
            );
        }
    }
    // Finite, even in f32, but so large that areas overflow: every triangle looked degenerate.
    for path in tetrahedron_with_y(dir.path(), "3e38") {
        let e = err(&path);
        let name = path.file_name().unwrap().to_str().unwrap();
        // 3e38 in all its digits (f32 formats widen it to 300000000549775580000…); messages are
        // put in short form where they are shown.
        assert_mentions(&e, &[vertex_2(name), "is too large: (0, 3000000", "±1e15"]);
    }
}
/// A file cut short says so on one line, in every binary encoding and wherever the cut falls.
#[test]
fn truncated_files_say_so_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let ply = export_ply(&cube());
    let glb = std::fs::read(corpus("tetra.glb")).unwrap();
    for share in [0.3, 0.7, 0.99] {
        let cut = |bytes: &[u8]| bytes[..(bytes.len() as f64 * share) as usize].to_vec();
        let e = err(&write(dir.path(), "cut.ply", &cut(&ply)));
        assert_mentions(&e, &["cut.ply", "bad PLY"]);
        assert!(!e.contains('\n') && !e.contains("ParseError"), "{e:?}");
        let e = err(&write(dir.path(), "cut.glb", &cut(&glb)));
        assert_mentions(&e, &["cut.glb", "truncated GLB", "declares 560 bytes"]);
    }
}
