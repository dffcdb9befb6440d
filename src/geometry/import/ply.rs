//! The PLY reader (ASCII and both binary encodings, via ply-rs). The header is checked before
//! any data is read: a `face` element within the triangle budget and a `vertex` element with
//! scalar x, y and z. Vertex coordinates of any numeric type and index lists of any integer
//! type are accepted, under either name writers use for the index list; messages give the
//! 0-based vertex or face.
//!
//! Elements are read into our own small types (ply-rs' `PropertyAccess`), which keep the
//! coordinates and the index list and drop every other property as it is read. ply-rs' generic
//! element is a map from property names to values, one per vertex and face: a 10⁶-face file
//! took a second that way and a run that only imported it peaked at 650 MB; now 0.2 s and
//! 110 MB.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use glam::DVec3;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, PropertyAccess, PropertyAccessResult, PropertyType};

use super::validate::{Builder, check_triangle_count, first_bad_number};

pub(super) fn read(path: &Path) -> Result<Builder, String> {
    read_with(path, false)
}

/// A mesh, or a point cloud: a file without a `face` element gives vertices only.
pub(super) fn read_points_or_mesh(path: &Path) -> Result<Builder, String> {
    read_with(path, true)
}

fn read_with(path: &Path, points_ok: bool) -> Result<Builder, String> {
    let file = File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let mut reader = Reader::new(BufReader::new(file));
    let header = Parser::<Skipped>::new()
        .read_header(&mut reader)
        .map_err(|e| format!("bad PLY header: {}", ply_rs_summary(&e)))?;
    let faces = header.elements.get("face");
    if faces.is_none() && !points_ok {
        return Err("bad PLY header: no 'face' element".into());
    }
    let vertices = header
        .elements
        .get("vertex")
        .ok_or("bad PLY header: no 'vertex' element")?;
    // Every face yields at least one triangle, so the header count bounds the work up front.
    let index_name = match faces {
        Some(faces) => {
            check_triangle_count(faces.count as u64)?;
            ply_index_property(faces)?
        }
        None => "",
    };
    for axis in AXES {
        match vertices.properties.get(axis).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            _ => {
                return Err(format!(
                    "bad PLY header: vertex has no scalar property '{axis}'"
                ));
            }
        }
    }
    // Elements come in the header's order; faces are kept until every vertex is in.
    let mut builder = Builder::default();
    let mut face_lists = Vec::new();
    for element in header.elements.values() {
        match element.name.as_str() {
            "vertex" => {
                let vertices = read_elements::<PlyVertex, _>(&mut reader, element, &header)
                    .map_err(|e| locate_ascii_error(path, &header).unwrap_or(e))?;
                for (i, v) in vertices.into_iter().enumerate() {
                    builder.mesh.positions.push(v.position(i)?);
                }
            }
            "face" => {
                face_lists = read_elements::<PlyFace, _>(&mut reader, element, &header)
                    .map_err(|e| locate_ascii_error(path, &header).unwrap_or(e))?;
            }
            _ => {
                read_elements::<Skipped, _>(&mut reader, element, &header)
                    .map_err(|e| locate_ascii_error(path, &header).unwrap_or(e))?;
            }
        }
    }
    for (f, face) in face_lists.iter().enumerate() {
        let corners = face
            .corners(index_name)
            .ok_or_else(|| format!("face {f}: '{index_name}' is not a list of integers"))?;
        builder.push_face(f, corners)?;
    }
    Ok(builder)
}

/// Every instance of `element`, read into `E` (only the properties `E` keeps are stored).
fn read_elements<E: PropertyAccess, R: std::io::BufRead>(
    reader: &mut Reader<R>,
    element: &ElementDef,
    header: &ply_rs_bw::ply::Header,
) -> Result<Vec<E>, String> {
    Parser::<E>::new()
        .read_payload_for_element(reader, element, header)
        .map_err(|e| format!("bad PLY data: {}", ply_rs_summary(&e)))
}

/// ply-rs' message on one line: where, and the text it could not read, without the parser's
/// state and grammar that follow over several lines.
fn ply_rs_summary(e: &dyn std::fmt::Display) -> String {
    let text = e.to_string();
    let mut lines = text.lines().map(str::trim);
    let place = lines.next().unwrap_or_default();
    match lines.find(|l| l.starts_with("String:")) {
        Some(read) => format!("{place} {read}"),
        None => place.to_string(),
    }
}

/// In an ASCII file whose data ply-rs could not read, the first element line holding a word
/// that is not a finite number, named by element and index ("vertex 2 (line 12) has 'nan',
/// not a finite number: '0 nan 0'"); None for a binary file or a damage of another kind.
fn locate_ascii_error(path: &Path, header: &ply_rs_bw::ply::Header) -> Option<String> {
    if header.encoding != ply_rs_bw::ply::Encoding::Ascii {
        return None;
    }
    let text = std::fs::read_to_string(path).ok()?;
    let mut lines = text.lines().enumerate();
    lines
        .by_ref()
        .find(|(_, line)| line.trim() == "end_header")?;
    for element in header.elements.values() {
        for k in 0..element.count {
            let (n, line) = lines.next()?;
            if let Some((word, why)) = first_bad_number(line) {
                return Some(format!(
                    "{} {k} (line {}) has '{word}', {why}: '{}'",
                    element.name,
                    n + 1,
                    line.trim()
                ));
            }
        }
    }
    None
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// The names writers give the face's index list: the spec says vertex_indices, some writers
/// vertex_index.
const INDEX_NAMES: [&str; 2] = ["vertex_indices", "vertex_index"];

/// The index list the file's faces use, the spec's name first.
fn ply_index_property(faces: &ElementDef) -> Result<&'static str, String> {
    INDEX_NAMES
        .into_iter()
        .find(|n| {
            matches!(
                faces.properties.get(*n).map(|p| &p.data_type),
                Some(PropertyType::List(..))
            )
        })
        .ok_or_else(|| "bad PLY header: face has no list property 'vertex_indices'".into())
}

/// An element the mesh does not use: read past, nothing kept.
struct Skipped;

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Skipped
    }
}

/// A vertex's coordinates, of whatever numeric type the file stores.
struct PlyVertex([Option<f64>; 3]);

impl PlyVertex {
    fn set(&mut self, name: &str, value: impl Into<f64>) -> PropertyAccessResult {
        let value = value.into();
        match AXES.iter().position(|axis| *axis == name) {
            Some(k) => {
                self.0[k] = Some(value);
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }

    /// The position of vertex `i`.
    fn position(&self, i: usize) -> Result<DVec3, String> {
        let c =
            |k: usize| self.0[k].ok_or_else(|| format!("vertex {i} lacks a numeric '{}'", AXES[k]));
        Ok(DVec3::new(c(0)?, c(1)?, c(2)?))
    }
}

/// ply-rs' typed setters, each passing its value on to `self.$via` (which widens it).
macro_rules! setters {
    ($via:ident: $($setter:ident($t:ty)),*) => {
        $(fn $setter(&mut self, name: &str, v: $t) -> PropertyAccessResult {
            self.$via(name, v)
        })*
    };
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        PlyVertex([None; 3])
    }
    setters!(set: set_char(i8), set_uchar(u8), set_short(i16), set_ushort(u16), set_int(i32),
        set_uint(u32), set_float(f32), set_double(f64));
}

/// A face's index lists under either name, when they hold integers.
#[derive(Default)]
struct PlyFace([IndexList; 2]);

#[derive(Default)]
enum IndexList {
    #[default]
    Absent,
    Integers(Vec<i64>),
    NotIntegers,
}

impl PlyFace {
    fn set(&mut self, name: &str, list: IndexList) -> PropertyAccessResult {
        match INDEX_NAMES.iter().position(|n| *n == name) {
            Some(k) => {
                self.0[k] = list;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::Ignored,
        }
    }

    fn integers<T: Into<i64>>(&mut self, name: &str, v: Vec<T>) -> PropertyAccessResult {
        self.set(
            name,
            IndexList::Integers(v.into_iter().map(Into::into).collect()),
        )
    }

    /// The corners under `name`, if they are integers.
    fn corners(&self, name: &str) -> Option<&[i64]> {
        let k = INDEX_NAMES.iter().position(|n| *n == name)?;
        match &self.0[k] {
            IndexList::Integers(corners) => Some(corners),
            _ => None,
        }
    }
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        PlyFace::default()
    }
    setters!(integers: set_list_char(Vec<i8>), set_list_uchar(Vec<u8>), set_list_short(Vec<i16>),
        set_list_ushort(Vec<u16>), set_list_int(Vec<i32>), set_list_uint(Vec<u32>));
    fn set_list_float(&mut self, name: &str, _: Vec<f32>) -> PropertyAccessResult {
        self.set(name, IndexList::NotIntegers)
    }
    fn set_list_double(&mut self, name: &str, _: Vec<f64>) -> PropertyAccessResult {
        self.set(name, IndexList::NotIntegers)
    }
}

#[cfg(test)]
mod tests {
    use crate::geometry::import::export_ply;
    use crate::geometry::import::tests::{
        assert_mentions, assert_same_geometry, corpus, cube, err, import, tetrahedron, write,
    };

    /// The tetrahedron's faces as `tetrahedron()` winds them.
    const FACES: [[u8; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    const CORNERS: [[i16; 3]; 4] = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]];

    #[test]
    fn every_layout_writers_use_reads_the_same_tetrahedron() {
        let dir = tempfile::tempdir().unwrap();
        // Big-endian; coordinates of three types among other vertex properties; an element
        // the mesh does not use between the vertices and the faces; a scalar before the list.
        let mut big = b"ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty short x\n\
            property float y\nproperty uchar red\nproperty double z\nelement edge 1\n\
            property int vertex1\nproperty int vertex2\nelement face 4\nproperty uchar flags\n\
            property list uchar int vertex_indices\nend_header\n"
            .to_vec();
        for [x, y, z] in CORNERS {
            big.extend_from_slice(&x.to_be_bytes());
            big.extend_from_slice(&f32::from(y).to_be_bytes());
            big.push(200);
            big.extend_from_slice(&f64::from(z).to_be_bytes());
        }
        big.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 1]);
        for face in FACES {
            big.extend_from_slice(&[7, 3]);
            for i in face {
                big.extend_from_slice(&i32::from(i).to_be_bytes());
            }
        }
        // ASCII with the faces declared before the vertices, under the other index name.
        let mut faces_first = String::from(
            "ply\nformat ascii 1.0\nelement face 4\nproperty list uchar ushort vertex_index\n\
             element vertex 4\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
        );
        for [a, b, c] in FACES {
            faces_first += &format!("3 {a} {b} {c}\n");
        }
        for [x, y, z] in CORNERS {
            faces_first += &format!("{x} {y} {z}\n");
        }
        // Both names: the spec's is the one read.
        let mut both = String::from(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty uchar x\nproperty uchar y\n\
             property uchar z\nelement face 4\nproperty list uchar char vertex_index\n\
             property list uchar uint vertex_indices\nend_header\n",
        );
        for [x, y, z] in CORNERS {
            both += &format!("{x} {y} {z}\n");
        }
        for [a, b, c] in FACES {
            both += &format!("3 0 0 0 3 {a} {b} {c}\n");
        }
        for (name, bytes) in [
            ("big_endian.ply", big),
            ("faces_first.ply", faces_first.into_bytes()),
            ("both_names.ply", both.into_bytes()),
        ] {
            let imported =
                import(&write(dir.path(), name, &bytes)).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(
                imported.warnings.is_empty(),
                "{name}: {:?}",
                imported.warnings
            );
            assert_same_geometry(&imported.mesh, &tetrahedron(), 1.0 / 6.0, name);
        }
        let floats = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
            property float z\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n\
            0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        assert_mentions(
            &err(&write(dir.path(), "floats.ply", floats.as_bytes())),
            &["face 0: 'vertex_indices' is not a list of integers"],
        );
    }

    #[test]
    fn malformed_ply_files_name_the_problem() {
        let e = err(&corpus("bad_header.ply"));
        assert_mentions(&e, &["bad_header.ply", "bad PLY header", "Line 5"]);
        let e = err(&corpus("index_out_of_range.ply"));
        assert_mentions(
            &e,
            &["face 1 refers to vertex 7, out of range (the mesh has 3 vertices)"],
        );
        let dir = tempfile::tempdir().unwrap();
        let mut truncated = export_ply(&cube());
        truncated.truncate(truncated.len() - 7);
        assert_mentions(
            &err(&write(dir.path(), "truncated.ply", &truncated)),
            &["bad PLY data"],
        );
        let no_faces = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n";
        assert_mentions(
            &err(&write(dir.path(), "no_faces.ply", no_faces.as_bytes())),
            &["no 'face' element"],
        );
        let mut nan = export_ply(&tetrahedron());
        let at = nan.len() - 4 * 13 - 8; // z of the last vertex
        nan[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
        assert_mentions(
            &err(&write(dir.path(), "nan.ply", &nan)),
            &["vertex 3 is not finite"],
        );
        let huge = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                    element face 50000001\nproperty list uchar int vertex_indices\nend_header\n";
        assert_mentions(
            &err(&write(dir.path(), "huge.ply", huge.as_bytes())),
            &["50000001 triangles, over the limit"],
        );
    }
}
