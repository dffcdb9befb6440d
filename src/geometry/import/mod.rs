//! Reading triangle meshes from OBJ, PLY, STL and glTF/GLB files, and writing PLY.
//!
//! Owns: turning a mesh file into a checked [`Mesh`] (finite vertices within ±1e15, indices in range,
//! polygons fan-triangulated, degenerate triangles dropped, optional normalisation) and the
//! exact binary PLY export. Each format's reader has its own module and hands its faces to
//! `validate`, so the checks, repairs and their messages are the same for every format.
//! Must not touch: mechanics, cameras, rendering, recipes or materials, nor any file but the one
//! named (and a glTF's own buffers); it knows nothing of what the mesh is for. Colours, normals,
//! texture coordinates and materials in the files are ignored.
//!
//! Every problem becomes a `String` error naming the file; vertex, face and triangle indices in
//! messages count from 0 (OBJ messages also give the line and the index as written).

mod gltf;
mod obj;
mod ply;
mod stl;
#[cfg(test)]
pub(crate) mod tests;
mod validate;

use std::path::Path;

use super::Mesh;
use validate::{check_file_size, finish, read_all};

/// How a mesh file is read.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImportOptions {
    /// The 3DGEN paper's normalisation: centre the axis-aligned bounding box on the origin and
    /// scale so its diagonal has length 1.
    pub normalize: bool,
}

/// A mesh read from a file, plus human-readable warnings for repairs made (e.g. "dropped 3 degenerate triangles").
pub struct Imported {
    /// The checked mesh, in the file's units (metres assumed) and axes.
    pub mesh: Mesh,
    /// What was repaired, one message each.
    pub warnings: Vec<String>,
}

const SUPPORTED: &str = ".obj, .ply, .stl, .gltf, .glb";

/// Reads OBJ (.obj), PLY (.ply), STL (.stl, ASCII or binary) or glTF (.gltf, .glb) by extension (case-insensitive).
/// Errors are plain Strings that name the file and say what is wrong (and where, e.g. the face index), never panics.
pub fn import_mesh(path: &std::path::Path, options: ImportOptions) -> Result<Imported, String> {
    import_unnamed(path, options).map_err(|e| format!("{}: {e}", path.display()))
}

/// What a mesh or point-cloud file holds.
pub enum Surface {
    /// Triangles (any format, or a PLY with faces), checked as [`import_mesh`] checks them.
    Mesh(Imported),
    /// Points alone: a PLY without faces (or with none listed). Every point is finite and within
    /// ±1e15.
    Points(Vec<glam::DVec3>),
}

/// Reads a mesh as [`import_mesh`] does, except that a PLY without faces is a point cloud.
pub fn import_surface(path: &Path) -> Result<Surface, String> {
    let named = |e: String| format!("{}: {e}", path.display());
    if format_of(path).map_err(named)? != Format::Ply {
        return import_mesh(path, ImportOptions::default()).map(Surface::Mesh);
    }
    check_file_size(path).map_err(named)?;
    let builder = ply::read_points_or_mesh(path).map_err(named)?;
    if builder.mesh.triangles.is_empty() {
        validate::check_coordinates(&builder.mesh.positions).map_err(named)?;
        return Ok(Surface::Points(builder.mesh.positions));
    }
    finish(builder, ImportOptions::default())
        .map(Surface::Mesh)
        .map_err(named)
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
        Format::Obj => obj::read(&read_all(path)?)?,
        Format::Ply => ply::read(path)?,
        Format::Stl => stl::read(path)?,
        Format::Gltf => gltf::read(path)?,
    };
    finish(builder, options)
}
