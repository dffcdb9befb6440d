//! Reading triangle meshes from OBJ, PLY, STL and glTF/GLB files, and writing PLY.
//!
//! Owns: turning a mesh file into a checked [`Mesh`] (finite vertices, indices in range,
//! polygons fan-triangulated, degenerate triangles dropped, optional normalisation) and the
//! exact binary PLY export.
//! Must not touch: rendering, recipes, materials or cameras; it knows nothing of what the mesh
//! is for. Colours, normals, texture coordinates and materials in the files are ignored.
//!
//! Every problem becomes a `String` error naming the file; vertex, face and triangle indices in
//! messages count from 0 (OBJ messages also give the line and the index as written).

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use glam::{DMat4, DVec3};

use super::Mesh;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImportOptions {
    /// The 3DGEN paper's normalisation: centre the axis-aligned bounding box on the origin and
    /// scale so its diagonal has length 1.
    pub normalize: bool,
}

/// A mesh read from a file, plus human-readable warnings for repairs made (e.g. "dropped 3 degenerate triangles").
pub struct Imported {
    pub mesh: Mesh,
    pub warnings: Vec<String>,
}

/// Larger files are refused before they are read, so a bad path cannot exhaust memory.
const MAX_FILE_BYTES: u64 = 1 << 30;
/// Larger meshes are refused as soon as a header or accessor announces them.
const MAX_TRIANGLES: u64 = 50_000_000;
/// Below this |cross| / longest edge² a triangle is treated as having zero area: collinear
/// corners only cancel to rounding error, never to exactly zero.
const DEGENERATE_RATIO: f64 = 1e-12;

const SUPPORTED: &str = ".obj, .ply, .stl, .gltf, .glb";

/// Reads OBJ (.obj), PLY (.ply), STL (.stl, ASCII or binary) or glTF (.gltf, .glb) by extension (case-insensitive).
/// Errors are plain Strings that name the file and say what is wrong (and where, e.g. the face index), never panics.
pub fn import_mesh(path: &std::path::Path, options: ImportOptions) -> Result<Imported, String> {
    import_unnamed(path, options).map_err(|e| format!("{}: {e}", path.display()))
}

/// Binary little-endian PLY with float64 vertex x, y, z and uint32 vertex_indices, so that export → import is exact.
pub fn export_ply(mesh: &Mesh) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by shmgen\n\
         element vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    let mut out =
        Vec::with_capacity(header.len() + 24 * mesh.positions.len() + 13 * mesh.triangles.len());
    out.extend_from_slice(header.as_bytes());
    for p in &mesh.positions {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for t in &mesh.triangles {
        out.push(3);
        for i in t {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Obj,
    Ply,
    Stl,
    Gltf,
}

fn format_of(path: &Path) -> Result<Format, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("obj") => Ok(Format::Obj),
        Some("ply") => Ok(Format::Ply),
        Some("stl") => Ok(Format::Stl),
        Some("gltf" | "glb") => Ok(Format::Gltf),
        Some(other) => Err(format!(
            "unsupported extension '.{other}' (supported: {SUPPORTED})"
        )),
        None => Err(format!("no file extension (supported: {SUPPORTED})")),
    }
}

/// Everything but the file name, which `import_mesh` prefixes once for all errors.
fn import_unnamed(path: &Path, options: ImportOptions) -> Result<Imported, String> {
    let format = format_of(path)?;
    check_file_size(path)?;
    let builder = match format {
        Format::Obj => read_obj(&read_all(path)?)?,
        Format::Ply => read_ply(path)?,
        Format::Stl => read_stl(path)?,
        Format::Gltf => read_gltf(path)?,
    };
    finish(builder, options)
}

fn check_file_size(path: &Path) -> Result<u64, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot open: {e}"))?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(format!(
            "file is {} bytes, over the 1 GiB limit",
            meta.len()
        ));
    }
    Ok(meta.len())
}

fn read_all(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("cannot read: {e}"))
}

fn check_triangle_count(count: u64) -> Result<(), String> {
    if count > MAX_TRIANGLES {
        return Err(format!(
            "{count} triangles, over the limit of {MAX_TRIANGLES}"
        ));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Shared checks and repairs

/// Collects faces from any reader, so index checks, triangulation and their messages are the
/// same for every format.
#[derive(Default)]
struct Builder {
    mesh: Mesh,
    fanned_polygons: usize,
    short_faces: usize,
    warnings: Vec<String>,
}

impl Builder {
    /// Adds one polygon whose corners index `mesh.positions`; `face` names it in errors.
    fn push_face(&mut self, face: usize, corners: &[i64]) -> Result<(), String> {
        let n = self.mesh.positions.len();
        if let Some(&bad) = corners.iter().find(|&&i| i < 0 || i as u64 >= n as u64) {
            return Err(format!(
                "face {face} refers to vertex {bad}, out of range (the mesh has {n} vertices)"
            ));
        }
        match corners.len() {
            0..=2 => self.short_faces += 1,
            3 => {}
            _ => self.fanned_polygons += 1,
        }
        // Fans keep the polygon's winding; only convex (or star-shaped from corner 0) polygons
        // come out right, which is what the formats' exporters write.
        for k in 2..corners.len() {
            let t = [corners[0], corners[k - 1], corners[k]].map(|i| i as u32);
            self.mesh.triangles.push(t);
        }
        Ok(())
    }

    fn repair_warnings(&self) -> Vec<String> {
        let mut w = self.warnings.clone();
        if self.fanned_polygons > 0 {
            w.push(format!(
                "fan-triangulated {} polygons with more than 3 vertices",
                self.fanned_polygons
            ));
        }
        if self.short_faces > 0 {
            w.push(format!(
                "dropped {} faces with fewer than 3 vertices",
                self.short_faces
            ));
        }
        w
    }
}

fn finish(builder: Builder, options: ImportOptions) -> Result<Imported, String> {
    let mut warnings = builder.repair_warnings();
    let mut mesh = builder.mesh;
    check_finite(&mesh)?;
    let dropped = drop_degenerate(&mut mesh);
    if dropped > 0 {
        warnings.push(format!(
            "dropped {dropped} degenerate triangles (repeated vertex or zero area)"
        ));
    }
    if mesh.triangles.is_empty() {
        return Err(if dropped > 0 {
            "no triangles left after dropping degenerate ones".into()
        } else {
            "the mesh has no triangles".into()
        });
    }
    if options.normalize {
        normalize(&mut mesh)?;
    }
    Ok(Imported { mesh, warnings })
}

fn check_finite(mesh: &Mesh) -> Result<(), String> {
    match mesh.positions.iter().position(|p| !p.is_finite()) {
        Some(i) => Err(format!(
            "vertex {i} is not finite: {}",
            show(mesh.positions[i])
        )),
        None => Ok(()),
    }
}

fn show(p: DVec3) -> String {
    format!("({}, {}, {})", p.x, p.y, p.z)
}

/// Removes triangles with a repeated corner or (relative to their size) zero area, which carry
/// no surface and break normals; returns how many went.
fn drop_degenerate(mesh: &mut Mesh) -> usize {
    let before = mesh.triangles.len();
    let positions = &mesh.positions;
    mesh.triangles
        .retain(|t| !is_degenerate(t.map(|i| positions[i as usize]), *t));
    before - mesh.triangles.len()
}

fn is_degenerate([a, b, c]: [DVec3; 3], [i, j, k]: [u32; 3]) -> bool {
    if i == j || j == k || k == i {
        return true;
    }
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    (b - a).cross(c - a).length() <= DEGENERATE_RATIO * longest
}

/// Centres the bounding box of all vertices (unused ones included) and scales its diagonal to 1.
fn normalize(mesh: &mut Mesh) -> Result<(), String> {
    let (lo, hi) = mesh.bounds().ok_or("cannot normalise an empty mesh")?;
    let diagonal = (hi - lo).length();
    // Vertices are finite by now, so an infinite diagonal can only be an overflow.
    if !diagonal.is_finite() {
        return Err("cannot normalise: the bounding box diagonal overflows".into());
    }
    if diagonal == 0.0 {
        return Err("cannot normalise: the bounding box has zero diagonal".into());
    }
    let centre = (lo + hi) * 0.5;
    for p in &mut mesh.positions {
        *p = (*p - centre) / diagonal;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// OBJ

fn read_obj(bytes: &[u8]) -> Result<Builder, String> {
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
    if !builder.mesh.is_finite() {
        // tobj renumbers vertices per object, so find the culprit in the file itself.
        return Err(locate_obj_error(bytes).unwrap_or_else(|| "a vertex is not finite".into()));
    }
    Ok(builder)
}

/// Finds the first unreadable or non-finite vertex or bad face index in OBJ text, for a message
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
                let xyz: Vec<f64> = words.take(3).map_while(|w| w.parse().ok()).collect();
                if xyz.len() < 3 {
                    return Some(format!(
                        "vertex {seen} (line {line_no}) is not three numbers: '{line}'"
                    ));
                }
                if xyz.iter().any(|c| !c.is_finite()) {
                    return Some(format!(
                        "vertex {seen} (line {line_no}) is not finite: '{line}'"
                    ));
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

// ---------------------------------------------------------------------------------------------
// PLY

fn read_ply(path: &Path) -> Result<Builder, String> {
    use ply_rs_bw::parser::{Parser, Reader};
    use ply_rs_bw::ply::DefaultElement;

    let file = File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let mut reader = Reader::new(BufReader::new(file));
    let parser = Parser::<DefaultElement>::new();
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| format!("bad PLY header: {e}"))?;
    let faces = header
        .elements
        .get("face")
        .ok_or("bad PLY header: no 'face' element")?;
    let vertices = header
        .elements
        .get("vertex")
        .ok_or("bad PLY header: no 'vertex' element")?;
    // Every face yields at least one triangle, so the header count bounds the work up front.
    check_triangle_count(faces.count as u64)?;
    let index_name = ply_index_property(faces)?;
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

// ---------------------------------------------------------------------------------------------
// STL

const STL_HEADER: usize = 84;
const STL_RECORD: u64 = 50;

fn read_stl(path: &Path) -> Result<Builder, String> {
    let mut bytes = read_stl_bytes(path)?;
    if stl_is_ascii(&bytes) {
        // stl_io insists on "solid " with a space; an unnamed "solid\n" is valid too.
        if bytes.get(5) != Some(&b' ') {
            bytes.insert(5, b' ');
        }
        return stl_triangles(&bytes);
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
            if !p.is_finite() {
                return Err(format!(
                    "vertex {k} of triangle {t} is not finite: {}",
                    show(p)
                ));
            }
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

// ---------------------------------------------------------------------------------------------
// glTF

fn read_gltf(path: &Path) -> Result<Builder, String> {
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
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| format!("invalid glTF: {e}"))?;
    let mut root = document.into_json();
    prepare_for_validation(&mut root, warnings)?;
    let document = gltf::Document::from_json(root).map_err(|e| e.to_string())?;
    Ok((document, blob))
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
    Ok(items
        .map(|b| {
            let f = |k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]) as f64;
            DVec3::new(f(0), f(4), f(8))
        })
        .collect())
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
    use super::*;
    use std::path::PathBuf;

    fn corpus(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/meshes")
            .join(name)
    }

    fn import(path: &Path) -> Result<Imported, String> {
        import_mesh(path, ImportOptions::default())
    }

    fn err(path: &Path) -> String {
        match import(path) {
            Ok(_) => panic!("{} imported, but should fail", path.display()),
            Err(e) => e,
        }
    }

    fn assert_mentions(e: &str, words: &[&str]) {
        for w in words {
            assert!(e.contains(w), "error {e:?} does not mention {w:?}");
        }
    }

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
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

    fn tetrahedron() -> Mesh {
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

    fn cube() -> Mesh {
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
    fn write_gltf(dir: &Path, name: &str, mesh: &Mesh, nodes: &str) -> PathBuf {
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

    fn assert_same_geometry(got: &Mesh, want: &Mesh, volume: f64, what: &str) {
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
    fn normalisation_centres_the_box_and_scales_its_diagonal_to_one() {
        let mut mesh = cube();
        for p in &mut mesh.positions {
            *p = *p * DVec3::new(3.0, 4.0, 12.0) + DVec3::new(-7.0, 100.0, 0.5);
        }
        let dir = tempfile::tempdir().unwrap();
        let path = write(dir.path(), "box.ply", &export_ply(&mesh));
        let out = import_mesh(&path, ImportOptions { normalize: true })
            .unwrap()
            .mesh;
        let (lo, hi) = out.bounds().unwrap();
        assert!((lo + hi).length() < 1e-15, "centre {}", (lo + hi) / 2.0);
        assert!(((hi - lo).length() - 1.0).abs() < 1e-15);
        // Uniform scaling: the box keeps its 3:4:12 proportions and the winding its sign.
        assert!(((hi - lo) - DVec3::new(3.0, 4.0, 12.0) / 13.0).length() < 1e-15);
        assert!(out.signed_volume() > 0.0);
    }

    #[test]
    fn zero_diagonal_cannot_be_normalised() {
        let mut mesh = tetrahedron();
        mesh.positions
            .iter_mut()
            .for_each(|p| *p = DVec3::splat(1e308));
        mesh.positions[1].x = -1e308; // a real triangle whose box diagonal overflows
        let mut m = Mesh {
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
        };
        assert_eq!(
            normalize(&mut m).unwrap_err(),
            "cannot normalise: the bounding box diagonal overflows"
        );
        let mut flat = Mesh {
            positions: vec![DVec3::ONE; 3],
            triangles: vec![[0, 1, 2]],
        };
        assert!(normalize(&mut flat).unwrap_err().contains("zero diagonal"));
    }

    #[test]
    fn obj_with_a_quad_and_a_degenerate_triangle_is_repaired_with_warnings() {
        let imported = import(&corpus("quad_and_degenerate.obj")).unwrap();
        assert_eq!(imported.mesh.triangles, [[0, 1, 2], [0, 2, 3]]);
        assert_eq!(
            imported.warnings,
            [
                "fan-triangulated 1 polygons with more than 3 vertices",
                "dropped 1 degenerate triangles (repeated vertex or zero area)"
            ]
        );
    }

    #[test]
    fn collinear_triangle_is_dropped_as_zero_area() {
        let dir = tempfile::tempdir().unwrap();
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0.1 0.2 0\nv 0.3 0.6 0\nf 1 2 3\nf 1 4 5\n";
        let imported = import(&write(dir.path(), "sliver.obj", obj.as_bytes())).unwrap();
        assert_eq!(imported.mesh.triangles.len(), 1);
        assert_eq!(imported.warnings.len(), 1);
    }

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
        assert_mentions(&e, &["nan_vertex.obj", "vertex 2 (line 3)", "not finite"]);
        let dir = tempfile::tempdir().unwrap();
        let e = err(&write(dir.path(), "garbage.obj", b"v 0 0 zero\nf 1 2 3\n"));
        assert_mentions(
            &e,
            &["vertex 0 (line 1) is not three numbers: 'v 0 0 zero'"],
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
        assert_mentions(&e, &["invalid STL at triangle 0", "finite"]);
        let dir = tempfile::tempdir().unwrap();
        let e = err(&write(dir.path(), "short.stl", b"not solid, too short"));
        assert_mentions(&e, &["truncated binary STL", "84-byte header"]);
        let mut huge = vec![0u8; 80];
        huge.extend_from_slice(&u32::MAX.to_le_bytes());
        let e = err(&write(dir.path(), "huge.stl", &huge));
        assert_mentions(&e, &["4294967295 triangles, over the limit of 50000000"]);
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
        assert_mentions(&err(&write(dir.path(), "cut.glb", &glb)), &["invalid glTF"]);
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
}
