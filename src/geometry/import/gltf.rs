//! The glTF reader, for .gltf (with its buffers in data URIs or files beside it) and .glb. It
//! takes the triangle primitives of every mesh a node of the default (or first) scene places,
//! in world coordinates, keeping the winding outward under mirroring transforms; other
//! primitive modes are skipped with a warning. The gltf crate can panic on some malformed
//! input, so the document and every accessor are checked here first; messages name the mesh
//! and primitive, then the accessor, buffer view or buffer at fault.

use std::path::Path;

use glam::{DMat4, DVec3};

use super::validate::{Builder, check_coordinate, check_file_size, check_triangle_count, read_all};

pub(super) fn read(path: &Path) -> Result<Builder, String> {
    let bytes = read_all(path)?;
    let mut builder = Builder::default();
    let (document, blob) = gltf_document(&bytes, &mut builder.warnings)?;
    let buffers = gltf_buffers(&document, blob, path)?;
    let instances = gltf_instances(&document, &mut builder.warnings)?;
    check_triangle_count(
        instances
            .iter()
            .map(|(mesh, _)| gltf_triangle_bound(mesh))
            .sum(),
    )?;
    for (mesh, transform) in &instances {
        for primitive in mesh.primitives() {
            let place = format!("mesh {} primitive {}", mesh.index(), primitive.index());
            gltf_primitive(&primitive, *transform, &buffers, &mut builder)
                .map_err(|e| format!("{place}: {e}"))?;
        }
    }
    Ok(builder)
}

/// Parses and validates the JSON (of a .gltf or inside a .glb), returning the GLB binary chunk.
fn gltf_document(
    bytes: &[u8],
    warnings: &mut Vec<String>,
) -> Result<(gltf::Document, Option<Vec<u8>>), String> {
    check_glb_length(bytes)?;
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| format!("invalid glTF: {e}"))?;
    let mut root = document.into_json();
    prepare_for_validation(&mut root, warnings)?;
    let document = gltf::Document::from_json(root).map_err(|e| e.to_string())?;
    Ok((document, blob))
}

/// A GLB file (magic "glTF") shorter than the length its header declares was cut short; the
/// gltf crate only says it "could not completely read the object".
fn check_glb_length(bytes: &[u8]) -> Result<(), String> {
    let Some(header) = bytes.get(..12).filter(|h| h.starts_with(b"glTF")) else {
        return Ok(());
    };
    let declared = u32::from_le_bytes([header[8], header[9], header[10], header[11]]);
    if (bytes.len() as u64) < u64::from(declared) {
        return Err(format!(
            "truncated GLB: the header declares {declared} bytes but the file has {}",
            bytes.len()
        ));
    }
    Ok(())
}

/// gltf-json's validation indexes the POSITION accessor without a bounds check (a panic on a
/// dangling index) and rejects a POSITION accessor without min/max, which we never use; so the
/// first is an error here and the second a warning with placeholder bounds.
fn prepare_for_validation(
    root: &mut gltf::json::Root,
    warnings: &mut Vec<String>,
) -> Result<(), String> {
    let positions = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
    let accessor_count = root.accessors.len();
    let mut position_accessors = Vec::new();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let Some(index) = primitive.attributes.get(&positions) else {
                continue;
            };
            if index.value() >= accessor_count {
                return Err(format!(
                    "mesh {m} primitive {p}: POSITION refers to accessor {}, but there are {accessor_count}",
                    index.value()
                ));
            }
            position_accessors.push(index.value());
        }
    }
    position_accessors.sort_unstable();
    position_accessors.dedup();
    for a in position_accessors {
        let accessor = &mut root.accessors[a];
        if accessor.min.is_none() || accessor.max.is_none() {
            warnings.push(format!(
                "POSITION accessor {a} lacks the min/max the glTF spec requires (ignored)"
            ));
            accessor
                .min
                .get_or_insert_with(|| serde_json::json!([0.0, 0.0, 0.0]));
            accessor
                .max
                .get_or_insert_with(|| serde_json::json!([0.0, 0.0, 0.0]));
        }
    }
    Ok(())
}

/// Loads every buffer's bytes: the GLB chunk, a base64 data URI or a file next to the glTF.
fn gltf_buffers(
    document: &gltf::Document,
    blob: Option<Vec<u8>>,
    path: &Path,
) -> Result<Vec<Vec<u8>>, String> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut blob = blob;
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            // The spec allows only buffer 0 to be the GLB chunk, so it can be moved out.
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                format!("buffer {i} refers to a GLB binary chunk, but there is none")
            })?,
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                decode_data_uri(uri).map_err(|e| format!("buffer {i}: {e}"))?
            }
            gltf::buffer::Source::Uri(uri) => {
                let file = dir.join(uri);
                check_file_size(&file)
                    .map_err(|e| format!("buffer {i} ({}): {e}", file.display()))?;
                read_all(&file).map_err(|e| format!("buffer {i} ({}): {e}", file.display()))?
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} has {} bytes, fewer than its byteLength {}",
                data.len(),
                buffer.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let (_, data) = uri.split_once(";base64,").ok_or("data URI is not base64")?;
    decode_base64(data).ok_or_else(|| "data URI holds invalid base64".into())
}

/// Plain base64 (RFC 4648, padding optional); the one place the glTF reader needs it does not
/// justify a dependency.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' | b'-' => Some(62),
        b'/' | b'_' => Some(63),
        _ => None,
    };
    let digits = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(digits.len() * 3 / 4);
    for chunk in digits.chunks(4) {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            acc |= (value(c)? as u32) << (18 - 6 * k);
        }
        let bytes = acc.to_be_bytes();
        match chunk.len() {
            4 => out.extend_from_slice(&bytes[1..4]),
            3 => out.extend_from_slice(&bytes[1..3]),
            2 => out.push(bytes[1]),
            _ => return None,
        }
    }
    Some(out)
}

/// Each mesh placed by a node, with the node's world transform. Without a scene, meshes are
/// taken as they are (with a warning), since nothing says where they go.
fn gltf_instances<'a>(
    doc: &'a gltf::Document,
    warnings: &mut Vec<String>,
) -> Result<Vec<(gltf::Mesh<'a>, DMat4)>, String> {
    let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        warnings.push("no scene: meshes taken without node transforms".into());
        return Ok(doc.meshes().map(|m| (m, DMat4::IDENTITY)).collect());
    };
    let mut out = Vec::new();
    let mut stack: Vec<_> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    let mut visits = 0;
    while let Some((node, parent)) = stack.pop() {
        // In a tree each node is reached once; more visits mean a cycle or shared children.
        visits += 1;
        if visits > doc.nodes().len() {
            return Err("the node hierarchy is not a tree (a node is reached twice)".into());
        }
        let local = node.transform().matrix().map(|col| col.map(f64::from));
        let world = parent * DMat4::from_cols_array_2d(&local);
        if let Some(mesh) = node.mesh() {
            out.push((mesh, world));
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    Ok(out)
}

/// Upper bound on a mesh's triangles from accessor counts alone, before any data is read.
fn gltf_triangle_bound(mesh: &gltf::Mesh) -> u64 {
    mesh.primitives()
        .map(
            |p| match p.indices().or_else(|| p.get(&gltf::Semantic::Positions)) {
                Some(a) => a.count() as u64,
                None => 0,
            },
        )
        .sum()
}

fn gltf_primitive(
    primitive: &gltf::Primitive,
    transform: DMat4,
    buffers: &[Vec<u8>],
    builder: &mut Builder,
) -> Result<(), String> {
    use gltf::mesh::Mode;
    let mode = primitive.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        builder.warnings.push(format!(
            "skipped a primitive of mode {mode:?} (not triangles)"
        ));
        return Ok(());
    }
    let accessor = primitive
        .get(&gltf::Semantic::Positions)
        .ok_or("no POSITION attribute")?;
    let positions = gltf_positions(&accessor, buffers)?;
    let indices = match primitive.indices() {
        Some(a) => gltf_indices(&a, buffers)?,
        None => (0..positions.len() as u32).collect(),
    };
    let base = builder.mesh.positions.len() as i64;
    builder
        .mesh
        .positions
        .extend(positions.iter().map(|&p| transform.transform_point3(p)));
    // A mirroring transform turns counter-clockwise into clockwise (glTF spec, 3.7.2.1).
    let mirrored = transform.determinant() < 0.0;
    for (t, corners) in gltf_triangles(mode, &indices).enumerate() {
        let mut c = corners.map(|i| base + i as i64);
        if mirrored {
            c.swap(1, 2);
        }
        builder
            .push_face(t, &c)
            .map_err(|e| e.replacen("face", "triangle", 1))?;
    }
    Ok(())
}

fn gltf_triangles(mode: gltf::mesh::Mode, idx: &[u32]) -> Box<dyn Iterator<Item = [u32; 3]> + '_> {
    use gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip => Box::new((0..idx.len().saturating_sub(2)).map(move |i| {
            // Every other strip triangle is stored the wrong way round.
            if i % 2 == 0 {
                [idx[i], idx[i + 1], idx[i + 2]]
            } else {
                [idx[i], idx[i + 2], idx[i + 1]]
            }
        })),
        Mode::TriangleFan => {
            Box::new((1..idx.len().saturating_sub(1)).map(move |i| [idx[i], idx[i + 1], idx[0]]))
        }
        _ => Box::new(idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]])),
    }
}

fn gltf_positions(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<DVec3>, String> {
    use gltf::accessor::{DataType, Dimensions};
    if accessor.data_type() != DataType::F32 || accessor.dimensions() != Dimensions::Vec3 {
        return Err(format!(
            "POSITION accessor {} is not float VEC3",
            accessor.index()
        ));
    }
    let items = accessor_items(accessor, buffers, 12)?;
    // Checked as stored, before a node's transform smears a NaN over all three coordinates.
    items
        .enumerate()
        .map(|(i, b)| {
            let f = |k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]) as f64;
            let p = DVec3::new(f(0), f(4), f(8));
            check_coordinate(p).map_err(|why| {
                format!("POSITION accessor {}, vertex {i} {why}", accessor.index())
            })?;
            Ok(p)
        })
        .collect()
}

fn gltf_indices(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    use gltf::accessor::{DataType, Dimensions};
    let size = match (accessor.data_type(), accessor.dimensions()) {
        (DataType::U8, Dimensions::Scalar) => 1,
        (DataType::U16, Dimensions::Scalar) => 2,
        (DataType::U32, Dimensions::Scalar) => 4,
        _ => {
            return Err(format!(
                "index accessor {} is not an unsigned integer scalar",
                accessor.index()
            ));
        }
    };
    let items = accessor_items(accessor, buffers, size)?;
    Ok(items
        .map(|b| match size {
            1 => b[0] as u32,
            2 => u16::from_le_bytes([b[0], b[1]]) as u32,
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        })
        .collect())
}

/// The byte slices of an accessor's elements, after checking that they all lie inside the
/// view and the buffer (the gltf crate's own reader can panic or misread otherwise).
fn accessor_items<'b>(
    accessor: &gltf::Accessor,
    buffers: &'b [Vec<u8>],
    size: usize,
) -> Result<impl Iterator<Item = &'b [u8]> + use<'b>, String> {
    let i = accessor.index();
    if accessor.sparse().is_some() {
        return Err(format!("accessor {i} is sparse, which is not supported"));
    }
    let view = accessor
        .view()
        .ok_or_else(|| format!("accessor {i} has no buffer view"))?;
    let count = accessor.count();
    if count == 0 {
        return Ok(None.into_iter().flatten());
    }
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "accessor {i}: byteStride {stride} is smaller than its {size}-byte elements"
        ));
    }
    let buffer = &buffers[view.buffer().index()];
    let view_end = view
        .offset()
        .checked_add(view.length())
        .filter(|&e| e <= buffer.len())
        .ok_or_else(|| {
            format!(
                "buffer view {} (bytes {}+{}) runs past the end of buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            )
        })?;
    let data = &buffer[view.offset()..view_end];
    let needed = (count - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(size))
        .and_then(|n| n.checked_add(accessor.offset()))
        .filter(|&n| n <= data.len())
        .ok_or_else(|| format!(
            "accessor {i} ({count} elements from byte {}) runs past the end of buffer view {} ({} bytes)",
            accessor.offset(), view.index(), data.len()
        ))?;
    let data = &data[accessor.offset()..needed];
    Ok(
        Some((0..count).map(move |k| &data[k * stride..k * stride + size]))
            .into_iter()
            .flatten(),
    )
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use crate::geometry::import::tests::{
        assert_mentions, corpus, cube, err, import, tetrahedron, write, write_gltf,
    };

    #[test]
    fn gltf_node_transforms_are_applied_and_mirroring_keeps_outward_winding() {
        let dir = tempfile::tempdir().unwrap();
        // Root scales by 2 and moves by 10 along x; its child mirrors in x.
        let nodes = r#"[{"translation":[10,0,0],"scale":[2,2,2],"mesh":0,"children":[1]},
                        {"scale":[-1,1,1],"mesh":0}]"#;
        let imported = import(&write_gltf(dir.path(), "two", &cube(), nodes)).unwrap();
        assert_eq!(
            imported.warnings,
            ["POSITION accessor 0 lacks the min/max the glTF spec requires (ignored)"]
        );
        let mesh = imported.mesh;
        assert_eq!(mesh.triangles.len(), 24);
        assert!(
            (mesh.signed_volume() - 16.0).abs() < 1e-12,
            "volume {}",
            mesh.signed_volume()
        );
        assert_eq!(
            mesh.bounds().unwrap(),
            (DVec3::new(8.0, 0.0, 0.0), DVec3::new(12.0, 2.0, 2.0))
        );
    }

    #[test]
    fn malformed_gltf_files_name_the_problem() {
        let e = err(&corpus("broken_accessor.gltf"));
        assert_mentions(
            &e,
            &[
                "mesh 0 primitive 0",
                "accessor 0 (40 elements",
                "runs past the end of buffer view 0 (48 bytes)",
            ],
        );
        let e = err(&corpus("invalid_json.gltf"));
        assert_mentions(&e, &["invalid glTF", "EOF"]);
        let dir = tempfile::tempdir().unwrap();
        let path = write_gltf(dir.path(), "short_bin", &cube(), r#"[{"mesh":0}]"#);
        std::fs::write(dir.path().join("short_bin.bin"), [0u8; 10]).unwrap();
        assert_mentions(
            &err(&path),
            &["buffer 0 has 10 bytes, fewer than its byteLength 168"],
        );
        std::fs::remove_file(dir.path().join("short_bin.bin")).unwrap();
        assert_mentions(&err(&path), &["buffer 0", "short_bin.bin", "cannot open"]);
        let mut glb = std::fs::read(corpus("tetra.glb")).unwrap();
        glb.truncate(100);
        assert_mentions(
            &err(&write(dir.path(), "cut.glb", &glb)),
            &["truncated GLB: the header declares 560 bytes but the file has 100"],
        );
        let cycle = r#"[{"mesh":0,"children":[1]},{"children":[0]}]"#;
        let e = err(&write_gltf(dir.path(), "cycle", &cube(), cycle));
        assert_mentions(&e, &["cycle.gltf", "the node hierarchy is not a tree"]);
        let mut bad_index = tetrahedron();
        bad_index.triangles[3] = [1, 2, 30];
        let e = err(&write_gltf(
            dir.path(),
            "bad_index",
            &bad_index,
            r#"[{"mesh":0}]"#,
        ));
        assert_mentions(
            &e,
            &["mesh 0 primitive 0: triangle 3 refers to vertex 30, out of range"],
        );
    }
}
