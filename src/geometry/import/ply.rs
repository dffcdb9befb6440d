//! The PLY reader (ASCII and both binary encodings, via ply-rs). The header is checked before
//! any data is read: a `face` element within the triangle budget and a `vertex` element with
//! scalar x, y and z. Vertex coordinates of any numeric type and index lists of any integer
//! type are accepted, under either name writers use for the index list; messages give the
//! 0-based vertex or face.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use glam::DVec3;

use super::validate::{Builder, check_triangle_count};

pub(super) fn read(path: &Path) -> Result<Builder, String> {
    read_with(path, false)
}

/// A mesh, or a point cloud: a file without a `face` element gives vertices only.
pub(super) fn read_points_or_mesh(path: &Path) -> Result<Builder, String> {
    read_with(path, true)
}

fn read_with(path: &Path, points_ok: bool) -> Result<Builder, String> {
    use ply_rs_bw::parser::{Parser, Reader};
    use ply_rs_bw::ply::DefaultElement;

    let file = File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let mut reader = Reader::new(BufReader::new(file));
    let parser = Parser::<DefaultElement>::new();
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| format!("bad PLY header: {e}"))?;
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
    for axis in ["x", "y", "z"] {
        match vertices.properties.get(axis).map(|p| &p.data_type) {
            Some(ply_rs_bw::ply::PropertyType::Scalar(_)) => {}
            _ => {
                return Err(format!(
                    "bad PLY header: vertex has no scalar property '{axis}'"
                ));
            }
        }
    }
    let payload = parser
        .read_payload(&mut reader, &header)
        .map_err(|e| format!("bad PLY data: {e}"))?;
    let mut builder = Builder::default();
    for (i, v) in payload
        .get("vertex")
        .map(Vec::as_slice)
        .unwrap_or_default()
        .iter()
        .enumerate()
    {
        let c = |axis| {
            ply_scalar(v.get(axis)).ok_or_else(|| format!("vertex {i} lacks a numeric '{axis}'"))
        };
        builder
            .mesh
            .positions
            .push(DVec3::new(c("x")?, c("y")?, c("z")?));
    }
    let mut corners = Vec::new();
    for (f, face) in payload
        .get("face")
        .map(Vec::as_slice)
        .unwrap_or_default()
        .iter()
        .enumerate()
    {
        ply_list(face.get(index_name), &mut corners)
            .ok_or_else(|| format!("face {f}: '{index_name}' is not a list of integers"))?;
        builder.push_face(f, &corners)?;
    }
    Ok(builder)
}

/// The name of the face's index list: the spec says vertex_indices, some writers vertex_index.
fn ply_index_property(faces: &ply_rs_bw::ply::ElementDef) -> Result<&'static str, String> {
    ["vertex_indices", "vertex_index"]
        .into_iter()
        .find(|n| {
            matches!(
                faces.properties.get(*n).map(|p| &p.data_type),
                Some(ply_rs_bw::ply::PropertyType::List(..))
            )
        })
        .ok_or_else(|| "bad PLY header: face has no list property 'vertex_indices'".into())
}

fn ply_scalar(p: Option<&ply_rs_bw::ply::Property>) -> Option<f64> {
    use ply_rs_bw::ply::Property as P;
    Some(match p? {
        P::Char(v) => *v as f64,
        P::UChar(v) => *v as f64,
        P::Short(v) => *v as f64,
        P::UShort(v) => *v as f64,
        P::Int(v) => *v as f64,
        P::UInt(v) => *v as f64,
        P::Float(v) => *v as f64,
        P::Double(v) => *v,
        _ => return None,
    })
}

fn ply_list(p: Option<&ply_rs_bw::ply::Property>, out: &mut Vec<i64>) -> Option<()> {
    use ply_rs_bw::ply::Property as P;
    out.clear();
    match p? {
        P::ListChar(v) => out.extend(v.iter().map(|&i| i as i64)),
        P::ListUChar(v) => out.extend(v.iter().map(|&i| i as i64)),
        P::ListShort(v) => out.extend(v.iter().map(|&i| i as i64)),
        P::ListUShort(v) => out.extend(v.iter().map(|&i| i as i64)),
        P::ListInt(v) => out.extend(v.iter().map(|&i| i as i64)),
        P::ListUInt(v) => out.extend(v.iter().map(|&i| i as i64)),
        _ => return None,
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use crate::geometry::import::export_ply;
    use crate::geometry::import::tests::{assert_mentions, corpus, cube, err, tetrahedron, write};

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
