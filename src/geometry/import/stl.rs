//! The STL reader, ASCII or binary (via stl_io). Binary headers may begin "solid" too, so a
//! file counts as ASCII only if its size does not also fit the binary layout. A binary file's
//! declared triangle count is checked against the budget before the rest of the file is read,
//! and against the file's length before it is parsed. STL repeats each corner per triangle, so
//! equal corners are merged into one vertex; messages give the 0-based triangle and corner.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use glam::DVec3;

use super::validate::{Builder, check_coordinate, check_triangle_count, first_bad_number};

const STL_HEADER: usize = 84;
const STL_RECORD: u64 = 50;

pub(super) fn read(path: &Path) -> Result<Builder, String> {
    let mut bytes = read_stl_bytes(path)?;
    if stl_is_ascii(&bytes) {
        // stl_io insists on "solid " with a space; an unnamed "solid\n" is valid too.
        if bytes.get(5) != Some(&b' ') {
            bytes.insert(5, b' ');
        }
        return stl_triangles(&bytes).map_err(|e| locate_ascii_error(&bytes).unwrap_or(e));
    }
    let declared = stl_declared_count(&bytes)?;
    let needed = STL_HEADER as u64 + STL_RECORD * declared;
    if (bytes.len() as u64) < needed {
        return Err(format!(
            "truncated binary STL: the header declares {declared} triangles ({needed} bytes) but the file has {} bytes",
            bytes.len()
        ));
    }
    // stl_io picks ASCII for any file starting "solid "; some binary exporters write that in the
    // free-form header, so blank it once the size has shown the file is binary.
    bytes[..5].fill(0);
    stl_triangles(&bytes)
}

/// Reads the whole file, but refuses an over-large binary triangle count after the header only.
fn read_stl_bytes(path: &Path) -> Result<Vec<u8>, String> {
    let mut file = File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let mut head = Vec::with_capacity(STL_HEADER);
    (&mut file)
        .take(STL_HEADER as u64)
        .read_to_end(&mut head)
        .map_err(|e| format!("cannot read: {e}"))?;
    if head.is_empty() {
        return Err("empty STL file".into());
    }
    if head.len() == STL_HEADER && !head.starts_with(b"solid") {
        check_triangle_count(stl_declared_count(&head)?)?;
    }
    file.read_to_end(&mut head)
        .map_err(|e| format!("cannot read: {e}"))?;
    Ok(head)
}

fn stl_declared_count(bytes: &[u8]) -> Result<u64, String> {
    let count = bytes.get(80..84).ok_or_else(|| {
        format!(
            "truncated binary STL: {} bytes, shorter than the 84-byte header",
            bytes.len()
        )
    })?;
    Ok(u32::from_le_bytes(count.try_into().unwrap_or_default()) as u64)
}

/// ASCII unless the size matches the binary layout exactly: binary headers may begin "solid".
fn stl_is_ascii(bytes: &[u8]) -> bool {
    let binary_size = stl_declared_count(bytes).map(|n| STL_HEADER as u64 + STL_RECORD * n);
    bytes.starts_with(b"solid") && binary_size != Ok(bytes.len() as u64)
}

/// In ASCII STL text stl_io could not read, the first `vertex` line with a word that is not a
/// finite number, or not one a 32-bit float (what STL stores) can hold; stl_io's own message
/// ("invalid float literal") names neither the vertex nor the word.
fn locate_ascii_error(bytes: &[u8]) -> Option<String> {
    let text = String::from_utf8_lossy(bytes);
    let vertex_lines = text
        .lines()
        .enumerate()
        .filter(|(_, line)| line.split_whitespace().next() == Some("vertex"));
    for (seen, (n, line)) in vertex_lines.enumerate() {
        let (t, k) = (seen / 3, seen % 3);
        let numbers = line.trim_start().trim_start_matches("vertex");
        let problem = first_bad_number(numbers).or_else(|| {
            let too_large = |w: &&str| w.parse::<f32>().is_ok_and(|v| v.is_infinite());
            let word = numbers.split_whitespace().find(too_large)?;
            Some((word, "beyond the range of the 32-bit floats STL holds"))
        });
        if let Some((word, why)) = problem {
            return Some(format!(
                "vertex {k} of triangle {t} (line {}) has '{word}', {why}: '{}'",
                n + 1,
                line.trim()
            ));
        }
    }
    None
}

/// STL stores each triangle's corners separately; equal corners (bit for bit) become one vertex
/// so that the mesh is connected.
fn stl_triangles(bytes: &[u8]) -> Result<Builder, String> {
    let mut cursor = std::io::Cursor::new(bytes);
    let triangles =
        stl_io::create_stl_reader(&mut cursor).map_err(|e| format!("invalid STL: {e}"))?;
    let mut builder = Builder::default();
    let mut index_of = std::collections::HashMap::new();
    for (t, triangle) in triangles.enumerate() {
        let triangle = triangle.map_err(|e| format!("invalid STL at triangle {t}: {e}"))?;
        let mut corners = [0i64; 3];
        for (k, v) in triangle.vertices.iter().enumerate() {
            let p = DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
            check_coordinate(p).map_err(|why| format!("vertex {k} of triangle {t} {why}"))?;
            let positions = &mut builder.mesh.positions;
            corners[k] = *index_of.entry(v.0.map(f32::to_bits)).or_insert_with(|| {
                positions.push(p);
                positions.len() as i64 - 1
            });
        }
        builder.push_face(t, &corners)?;
    }
    Ok(builder)
}

#[cfg(test)]
mod tests {
    use crate::geometry::import::tests::{assert_mentions, corpus, err, import, write};

    #[test]
    fn malformed_stl_files_name_the_problem() {
        let e = err(&corpus("truncated_binary.stl"));
        assert_mentions(
            &e,
            &[
                "truncated binary STL",
                "declares 4 triangles (284 bytes)",
                "254 bytes",
            ],
        );
        let e = err(&corpus("nan_binary.stl"));
        assert_mentions(&e, &["vertex 1 of triangle 2 is not finite: (NaN, 0, 0)"]);
        let e = err(&corpus("nan_ascii.stl"));
        assert_mentions(
            &e,
            &["vertex 2 of triangle 0 (line 6) has 'nan', not a finite number: 'vertex nan 0 0'"],
        );
        let dir = tempfile::tempdir().unwrap();
        let e = err(&write(dir.path(), "short.stl", b"not solid, too short"));
        assert_mentions(&e, &["truncated binary STL", "84-byte header"]);
        let mut huge = vec![0u8; 80];
        huge.extend_from_slice(&u32::MAX.to_le_bytes());
        let e = err(&write(dir.path(), "huge.stl", &huge));
        assert_mentions(&e, &["4294967295 triangles, over the limit of 10000000"]);
        let unnamed = std::fs::read_to_string(corpus("tetra_ascii.stl"))
            .unwrap()
            .replace("solid tetra", "solid");
        assert_eq!(
            import(&write(dir.path(), "unnamed.stl", unnamed.as_bytes()))
                .unwrap()
                .mesh
                .triangles
                .len(),
            4
        );
    }
}
