//! The OBJ reader. tobj parses the text (materials are never opened, points and lines are
//! skipped), and every object's vertices and polygons go into one [`Builder`]. tobj's errors
//! carry no position and it renumbers vertices per object, so on failure the text is scanned
//! again by [`locate_obj_error`] to name the line, the index as written and the 0-based vertex
//! or face.

use std::path::Path;

use glam::DVec3;

use super::validate::{
    Builder, check_coordinate, check_coordinates, check_triangle_count, first_bad_number,
};

pub(super) fn read(bytes: &[u8]) -> Result<Builder, String> {
    let load = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
    };
    // Materials are not ours to read; an mtllib line must not make us open other files.
    let no_materials = |_: &Path| Err(tobj::LoadError::OpenFileFailed);
    let (models, _) = tobj::load_obj_buf(&mut &bytes[..], &load, no_materials)
        .map_err(|e| locate_obj_error(bytes).unwrap_or_else(|| format!("invalid OBJ: {e}")))?;
    let mut builder = Builder::default();
    let mut face = 0;
    let mut corners = Vec::new();
    for model in &models {
        let base = builder.mesh.positions.len() as i64;
        let m = &model.mesh;
        builder.mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|c| DVec3::new(c[0], c[1], c[2])),
        );
        // tobj leaves the arities empty when every face is a triangle.
        let arities: Box<dyn Iterator<Item = usize>> = if m.face_arities.is_empty() {
            Box::new(std::iter::repeat_n(3, m.indices.len() / 3))
        } else {
            Box::new(m.face_arities.iter().map(|&a| a as usize))
        };
        let mut start = 0;
        for arity in arities {
            let slice = m
                .indices
                .get(start..start + arity)
                .ok_or("invalid OBJ: inconsistent face data")?;
            corners.clear();
            corners.extend(slice.iter().map(|&i| base + i as i64));
            builder.push_face(face, &corners)?;
            start += arity;
            face += 1;
        }
        check_triangle_count(builder.mesh.triangles.len() as u64)?;
    }
    if let Err(e) = check_coordinates(&builder.mesh.positions) {
        // tobj renumbers vertices per object, so find the culprit in the file itself.
        return Err(locate_obj_error(bytes).unwrap_or(e));
    }
    Ok(builder)
}

/// Finds the first unreadable, non-finite or too large vertex or bad face index in OBJ text, for a message
/// with a line number (tobj's errors carry neither).
fn locate_obj_error(bytes: &[u8]) -> Option<String> {
    let text = String::from_utf8_lossy(bytes);
    let total = text
        .lines()
        .filter(|l| l.split_whitespace().next() == Some("v"))
        .count() as i64;
    let (mut seen, mut face) = (0i64, 0usize);
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let line_no = n + 1;
        match words.next() {
            Some("v") => {
                let xyz: Vec<&str> = words.take(3).collect();
                if let Some((word, why)) = first_bad_number(&xyz.join(" ")) {
                    return Some(format!(
                        "vertex {seen} (line {line_no}) has '{word}', {why}: '{line}'"
                    ));
                }
                let numbers: Vec<f64> = xyz.iter().filter_map(|w| w.parse().ok()).collect();
                let [x, y, z] = numbers[..] else {
                    return Some(format!(
                        "vertex {seen} (line {line_no}) is not three numbers: '{line}'"
                    ));
                };
                if let Err(why) = check_coordinate(DVec3::new(x, y, z)) {
                    return Some(format!("vertex {seen} (line {line_no}) {why}"));
                }
                seen += 1;
            }
            Some("f") => {
                for word in words {
                    let Some(written) = word.split('/').next().and_then(|w| w.parse::<i64>().ok())
                    else {
                        return Some(format!(
                            "face {face} (line {line_no}): cannot read vertex index '{word}'"
                        ));
                    };
                    let index = if written < 0 {
                        seen + written
                    } else {
                        written - 1
                    };
                    if written == 0 || index < 0 || index >= total {
                        return Some(format!(
                            "face {face} (line {line_no}) refers to vertex {written}, out of range (the file has {total} vertices)"
                        ));
                    }
                }
                face += 1;
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use crate::geometry::import::tests::{assert_mentions, corpus, err, write};

    #[test]
    fn malformed_obj_files_name_the_problem() {
        let e = err(&corpus("face_out_of_range.obj"));
        assert_mentions(
            &e,
            &[
                "face_out_of_range.obj",
                "face 1 (line 5)",
                "vertex 9",
                "out of range",
            ],
        );
        let e = err(&corpus("nan_vertex.obj"));
        assert_mentions(
            &e,
            &[
                "nan_vertex.obj",
                "vertex 2 (line 3) has 'nan', not a finite number",
            ],
        );
        let dir = tempfile::tempdir().unwrap();
        let e = err(&write(dir.path(), "garbage.obj", b"v 0 0 zero\nf 1 2 3\n"));
        assert_mentions(
            &e,
            &["vertex 0 (line 1) has 'zero', not a number: 'v 0 0 zero'"],
        );
        let e = err(&write(
            dir.path(),
            "bad_face.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
        ));
        assert_mentions(&e, &["face 0 (line 4): cannot read vertex index 'x'"]);
        let e = err(&write(
            dir.path(),
            "degenerate_only.obj",
            b"v 0 0 0\nv 1 0 0\nf 1 2 2\n",
        ));
        assert_mentions(&e, &["no triangles left"]);
    }
}
