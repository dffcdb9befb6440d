//! Triangle meshes of structures, in f64, in world coordinates.
//!
//! Owns: the indexed mesh type, section outlines, the sweep mesher, the tessellation of
//! primitives, and (in `import` alone) reading and writing mesh files. A leaf: it imports no
//! other module of the crate, so it knows nothing of mechanics (the build stage tells it where
//! each section goes), cameras, rendering or recipes.

pub mod import;
pub mod outline;
pub mod primitives;
mod sweep;

pub use outline::SectionOutline;
pub use sweep::{Frame3, sweep};

use glam::DVec3;

/// The most triangles a mesh may have: one swept shape, one imported file or a whole scene.
/// It bounds the memory a sample takes (about 100 bytes a triangle with its BVH).
pub const MAX_TRIANGLES: usize = 10_000_000;

/// The largest coordinate, in metres, a vertex of a scene may have (10,000 km, the size of
/// the Earth). Inside it f64 positions resolve 2 nm, far finer than any depth is written;
/// beyond it they quantise structures visibly, and the BVH's single-precision areas
/// (extent squared) approach overflow. No civil structure comes near it, so a vertex beyond
/// it means a magnitude in the recipe is wrong.
pub const MAX_COORDINATE: f64 = 1e7;

/// Axis-aligned bounds (min, max) of some points; None for none.
pub fn bounds(points: &[DVec3]) -> Option<(DVec3, DVec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
    )
}

/// An indexed triangle mesh. Triangles wind counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, metres.
    pub positions: Vec<DVec3>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Appends `other`, re-indexing its triangles.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }

    /// Axis-aligned bounds (min, max); None for an empty mesh.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        bounds(&self.positions)
    }

    /// A sphere around the bounding box's centre holding every vertex; None for an empty mesh.
    /// Cameras aim at its centre and frame its radius.
    pub fn bounding_sphere(&self) -> Option<(DVec3, f64)> {
        let (lo, hi) = self.bounds()?;
        let centre = 0.5 * (lo + hi);
        let radius = self
            .positions
            .iter()
            .map(|p| p.distance(centre))
            .fold(0.0, f64::max);
        Some((centre, radius))
    }

    /// The corners of triangle `t`.
    pub fn triangle(&self, t: usize) -> [DVec3; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// Enclosed volume by the divergence theorem (positive for outward winding).
    pub fn signed_volume(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.triangle(t);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.triangle(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// Applies an affine map to every vertex.
    pub fn transform(&mut self, m: &glam::DAffine3) {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        // A mirroring map turns the winding inside out: restore outward orientation.
        if m.matrix3.determinant() < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
        }
    }

    /// Whether the surface is closed and consistently oriented: every directed edge appears
    /// exactly once and its reverse exactly once.
    pub fn is_closed_and_oriented(&self) -> bool {
        let mut edges = std::collections::HashMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        edges
            .iter()
            .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
    }

    /// Whether every vertex coordinate is finite.
    pub fn is_finite(&self) -> bool {
        self.positions.iter().all(|p| p.is_finite())
    }

    /// The first vertex that is not finite or lies beyond [`MAX_COORDINATE`] of the origin
    /// along some axis, if any.
    pub fn vertex_out_of_range(&self) -> Option<DVec3> {
        self.positions
            .iter()
            .copied()
            .find(|p| !(p.abs().max_element() <= MAX_COORDINATE))
    }
}
