//! Encoders of the per-sample geometry: triangle meshes and point clouds as binary
//! little-endian PLY, and meshes as binary glTF 2.0 (GLB), each into memory.
//!
//! PLY keeps world coordinates in float64, so a structure far from the origin loses nothing.
//! GLB stores float32 positions relative to their node's translation (the centre of the
//! bounds, kept in the JSON as a float64 number), so precision is that of the structure's
//! size, not of its distance from the origin.

use anyhow::{Context, Result};
use glam::DVec3;
use serde_json::json;

/// A triangle mesh as the per-sample writers see it.
pub struct MeshLayer<'a> {
    /// Vertex positions, world axes (right-handed, +z up), metres.
    pub positions: &'a [DVec3],
    /// Vertex indices of each triangle, counter-clockwise seen from outside.
    pub triangles: &'a [[u32; 3]],
    /// Part id of each triangle, as in the view's `segmentation.part_ids` (from 1).
    pub parts: &'a [u32],
}

/// Points on a surface with their unit normals and colours.
pub struct PointLayer {
    /// Positions, world axes, metres.
    pub positions: Vec<DVec3>,
    /// Unit normal at each point, world axes.
    pub normals: Vec<[f32; 3]>,
    /// The surface's colour at each point, sRGB 8-bit (the material's albedo there).
    pub colours: Vec<[u8; 3]>,
}

/// The header of a binary little-endian PLY: each element with its count and properties
/// (`type name` or `list count item name`).
fn ply_header(elements: &[(&str, usize, &[&str])]) -> String {
    let mut header = String::from(
        "ply\nformat binary_little_endian 1.0\n\
         comment written by shmgen: world axes (right-handed, +z up), metres\n",
    );
    for (name, count, properties) in elements {
        header += &format!("element {name} {count}\n");
        for property in *properties {
            header += &format!("property {property}\n");
        }
    }
    header + "end_header\n"
}

/// Little-endian bytes of an f64 point.
fn point_bytes(out: &mut Vec<u8>, p: DVec3) {
    for c in p.to_array() {
        out.extend_from_slice(&c.to_le_bytes());
    }
}

/// A signed 32-bit PLY `int` (what most readers expect of indices).
fn int_bytes(out: &mut Vec<u8>, value: u32) -> Result<()> {
    let value = i32::try_from(value).context("a vertex index or part id beyond 2³¹ − 1")?;
    out.extend_from_slice(&value.to_le_bytes());
    Ok(())
}

/// Binary PLY of a mesh: vertex `double x, y, z`; face `list uchar int vertex_indices` and
/// `int part`.
pub fn mesh_ply(mesh: &MeshLayer) -> Result<Vec<u8>> {
    let header = ply_header(&[
        ("vertex", mesh.positions.len(), &VERTEX_XYZ),
        (
            "face",
            mesh.triangles.len(),
            &["list uchar int vertex_indices", "int part"],
        ),
    ]);
    let mut out =
        Vec::with_capacity(header.len() + 24 * mesh.positions.len() + 17 * mesh.triangles.len());
    out.extend_from_slice(header.as_bytes());
    for &p in mesh.positions {
        point_bytes(&mut out, p);
    }
    for (triangle, &part) in mesh.triangles.iter().zip(mesh.parts) {
        out.push(3);
        for &i in triangle {
            int_bytes(&mut out, i)?;
        }
        int_bytes(&mut out, part)?;
    }
    Ok(out)
}

const VERTEX_XYZ: [&str; 3] = ["double x", "double y", "double z"];

/// Binary PLY of a point cloud: vertex `double x, y, z`, `float nx, ny, nz` and `uchar red,
/// green, blue` (the names Open3D, trimesh and nerfstudio's splatfacto read colours by).
pub fn points_ply(points: &PointLayer) -> Vec<u8> {
    let header = ply_header(&[(
        "vertex",
        points.positions.len(),
        &[
            VERTEX_XYZ[0],
            VERTEX_XYZ[1],
            VERTEX_XYZ[2],
            "float nx",
            "float ny",
            "float nz",
            "uchar red",
            "uchar green",
            "uchar blue",
        ],
    )]);
    let mut out = Vec::with_capacity(header.len() + POINT_BYTES * points.positions.len());
    out.extend_from_slice(header.as_bytes());
    let each = points.positions.iter().zip(&points.normals);
    for ((&p, n), colour) in each.zip(&points.colours) {
        point_bytes(&mut out, p);
        for c in n {
            out.extend_from_slice(&c.to_le_bytes());
        }
        out.extend_from_slice(colour);
    }
    out
}

/// Bytes of one point of `points_ply`: three doubles, three floats, three bytes.
const POINT_BYTES: usize = 24 + 12 + 3;

/// glTF's `componentType` of float32 and uint32, and `target` of vertex and index buffers.
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
/// Turns shmgen's world (+z up) into glTF's (+y up): −90° about x, as a quaternion (x, y, z, w).
const Z_UP_TO_Y_UP: [f64; 4] = [
    -std::f64::consts::FRAC_1_SQRT_2,
    0.0,
    0.0,
    std::f64::consts::FRAC_1_SQRT_2,
];

/// Binary glTF 2.0 of a mesh: node "world" turns +z up into glTF's +y up, and its child
/// "structure" holds the mesh, translated to the centre of the bounds; that child's frame is
/// shmgen's world frame, so world position = translation + the float32 POSITION.
pub fn mesh_glb(mesh: &MeshLayer) -> Result<Vec<u8>> {
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let centre = 0.5 * (lo + hi);
    let local: Vec<[f32; 3]> = mesh
        .positions
        .iter()
        .map(|&p| (p - centre).as_vec3().to_array())
        .collect();
    let (min, max) = local.iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        |(lo, hi), p| {
            (
                std::array::from_fn(|k| lo[k].min(p[k])),
                std::array::from_fn(|k| hi[k].max(p[k])),
            )
        },
    );
    let mut bin = Vec::with_capacity(12 * (local.len() + mesh.triangles.len()));
    for c in local.iter().flatten() {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    let index_offset = bin.len();
    for i in mesh.triangles.iter().flatten() {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let json = json!({
        "asset": { "version": "2.0", "generator": "shmgen" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [
            { "name": "world (shmgen axes: +z up)", "rotation": Z_UP_TO_Y_UP, "children": [1] },
            { "name": "structure", "mesh": 0, "translation": centre.to_array() },
        ],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "mode": 4 }] }],
        "accessors": [
            { "bufferView": 0, "componentType": FLOAT, "count": local.len(), "type": "VEC3",
              "min": min, "max": max },
            { "bufferView": 1, "componentType": UNSIGNED_INT, "count": 3 * mesh.triangles.len(),
              "type": "SCALAR" },
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": index_offset, "target": ARRAY_BUFFER },
            { "buffer": 0, "byteOffset": index_offset, "byteLength": bin.len() - index_offset,
              "target": ELEMENT_ARRAY_BUFFER },
        ],
        "buffers": [{ "byteLength": bin.len() }],
    });
    glb(serde_json::to_vec(&json)?, bin)
}

/// The GLB container: a 12-byte header, the JSON chunk padded with spaces and the binary
/// chunk padded with zeros, each to 4 bytes (glTF 2.0 §4.4).
fn glb(mut json: Vec<u8>, mut bin: Vec<u8>) -> Result<Vec<u8>> {
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let length = |n: usize| u32::try_from(n).context("a GLB file beyond 4 GiB");
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&length(total)?.to_le_bytes());
    for (kind, chunk) in [(b"JSON", json), (b"BIN\0", bin)] {
        out.extend_from_slice(&length(chunk.len())?.to_le_bytes());
        out.extend_from_slice(kind);
        out.extend_from_slice(&chunk);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron of two parts, far from the origin.
    struct Tetrahedron {
        positions: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
        parts: Vec<u32>,
    }

    impl Tetrahedron {
        fn new() -> Self {
            let far = DVec3::new(5e6, -3e6, 120.0);
            let corners = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.25, 0.25, 1.0)];
            Tetrahedron {
                positions: corners.map(|p| p + far).to_vec(),
                triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
                parts: vec![1, 1, 2, 2],
            }
        }

        fn layer(&self) -> MeshLayer<'_> {
            MeshLayer {
                positions: &self.positions,
                triangles: &self.triangles,
                parts: &self.parts,
            }
        }
    }

    #[test]
    fn ply_header_lists_the_elements_and_the_body_has_their_size() {
        let bytes = mesh_ply(&Tetrahedron::new().layer()).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        let end = text.find("end_header\n").unwrap() + "end_header\n".len();
        assert!(text.starts_with("ply\nformat binary_little_endian 1.0\n"));
        assert!(text[..end].contains(
            "element face 4\nproperty list uchar int vertex_indices\nproperty int part\n"
        ));
        assert_eq!(bytes.len() - end, 4 * 24 + 4 * 17);
        // The first vertex is stored exactly, far from the origin as it is.
        let x = f64::from_le_bytes(bytes[end..end + 8].try_into().unwrap());
        assert_eq!(x, 5e6);
    }

    #[test]
    fn glb_chunks_are_aligned_and_sized() {
        let bytes = mesh_glb(&Tetrahedron::new().layer()).unwrap();
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        assert_eq!(&bytes[..4], b"glTF");
        assert_eq!(word(8), bytes.len());
        let json_length = word(12);
        assert_eq!(json_length % 4, 0);
        assert_eq!(&bytes[16..20], b"JSON");
        let bin_at = 20 + json_length;
        assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
        assert_eq!(word(bin_at), 4 * 12 + 12 * 4);
    }

    #[test]
    fn point_ply_vertices_carry_position_normal_and_colour() {
        let points = PointLayer {
            positions: vec![DVec3::new(1.0, -2.0, 3.5), DVec3::new(5e6, 0.0, 0.0)],
            normals: vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]],
            colours: vec![[255, 128, 7], [0, 1, 2]],
        };
        let bytes = points_ply(&points);
        let text = String::from_utf8_lossy(&bytes);
        let end = text.find("end_header\n").unwrap() + "end_header\n".len();
        assert!(text[..end].ends_with(
            "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
        ));
        assert_eq!(bytes.len() - end, 2 * 39);
        let second = end + 39;
        let x = f64::from_le_bytes(bytes[second..second + 8].try_into().unwrap());
        assert_eq!(x, 5e6);
        assert_eq!(&bytes[end + 36..end + 39], [255, 128, 7]);
        assert_eq!(&bytes[second + 36..second + 39], [0, 1, 2]);
    }
}
