//! The checks and repairs every format shares: the file size and triangle count budgets, the
//! [`Builder`] that readers fill face by face (index range checks, fan triangulation), and the
//! finishing steps (finite and in-range coordinates, dropping degenerate triangles, optional normalisation). They
//! live in one place so that a mesh is held to the same rules, with the same messages, whatever
//! file it came from.

use std::path::Path;

use glam::DVec3;

use super::{ImportOptions, Imported};
use crate::geometry::Mesh;

/// Larger files are refused before they are read, so a bad path cannot exhaust memory.
const MAX_FILE_BYTES: u64 = 1 << 30;
/// Larger meshes are refused as soon as a header or accessor announces them: the budget of
/// any mesh (`geometry::MAX_TRIANGLES`).
const MAX_TRIANGLES: u64 = crate::geometry::MAX_TRIANGLES as u64;
/// Larger vertex coordinates are refused, in whatever unit the file uses (a scene's own limit
/// in metres, `geometry::MAX_COORDINATE`, applies after placement). Below it, the squared
/// lengths and areas computed from vertices stay far inside f64 (a coordinate of 3e38, valid
/// in f32, made every area overflow and every triangle look degenerate); far above any
/// sensible scan, even in millimetres.
const MAX_IMPORTED_COORDINATE: f64 = 1e15;
/// Below this |cross| / longest edge² a triangle is treated as having zero area: collinear
/// corners only cancel to rounding error, never to exactly zero.
const DEGENERATE_RATIO: f64 = 1e-12;

pub(super) fn check_file_size(path: &Path) -> Result<u64, String> {
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

pub(super) fn read_all(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("cannot read: {e}"))
}

pub(super) fn check_triangle_count(count: u64) -> Result<(), String> {
    if count > MAX_TRIANGLES {
        return Err(format!(
            "{count} triangles, over the limit of {MAX_TRIANGLES}"
        ));
    }
    Ok(())
}

/// Collects faces from any reader, so index checks, triangulation and their messages are the
/// same for every format.
#[derive(Default)]
pub(super) struct Builder {
    pub(super) mesh: Mesh,
    fanned_polygons: usize,
    short_faces: usize,
    pub(super) warnings: Vec<String>,
}

impl Builder {
    /// Adds one polygon whose corners index `mesh.positions`; `face` names it in errors.
    pub(super) fn push_face(&mut self, face: usize, corners: &[i64]) -> Result<(), String> {
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

pub(super) fn finish(builder: Builder, options: ImportOptions) -> Result<Imported, String> {
    let mut warnings = builder.repair_warnings();
    let mut mesh = builder.mesh;
    check_coordinates(&mesh.positions)?;
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

/// Refuses the first vertex that is not finite or lies beyond [`MAX_IMPORTED_COORDINATE`].
pub(super) fn check_coordinates(points: &[DVec3]) -> Result<(), String> {
    for (i, &p) in points.iter().enumerate() {
        check_coordinate(p).map_err(|why| format!("vertex {i} {why}"))?;
    }
    Ok(())
}

/// Why one point cannot be a vertex ("is not finite: (…)", "is too large: (…) …"), to follow
/// the reader's name for it.
pub(super) fn check_coordinate(p: DVec3) -> Result<(), String> {
    if !p.is_finite() {
        return Err(format!("is not finite: {}", show(p)));
    }
    if p.abs().max_element() > MAX_IMPORTED_COORDINATE {
        return Err(format!(
            "is too large: {}; coordinates beyond ±{MAX_IMPORTED_COORDINATE:e} overflow areas and squared distances (is the file in metres?)",
            show(p)
        ));
    }
    Ok(())
}

/// The first word of a line of numbers that is not a finite number, and why, for a message
/// that quotes what the file says rather than what a parser expected.
pub(super) fn first_bad_number(line: &str) -> Option<(&str, &'static str)> {
    line.split_whitespace()
        .find_map(|word| match word.parse::<f64>() {
            Err(_) => Some((word, "not a number")),
            Ok(v) if !v.is_finite() => Some((word, "not a finite number")),
            Ok(_) => None,
        })
}

/// Every digit: where messages are shown, long numbers are put in short form (`words`).
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::import::tests::{corpus, cube, import, tetrahedron, write};
    use crate::geometry::import::{export_ply, import_mesh};

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
}
