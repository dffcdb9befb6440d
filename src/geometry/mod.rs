//! Triangle meshes of structures, in f64, in world coordinates.
//!
//! Owns: the indexed mesh type and the tessellation of structures (the rectangular beam here).
//! Must not touch: mechanics formulas (it asks `mechanics` where section points go), cameras,
//! rendering or files.

mod beam;

pub use beam::beam_mesh;

use glam::DVec3;

/// An indexed triangle mesh. Triangles wind counter-clockwise seen from outside.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Appends `other`, re-indexing its triangles.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }

    /// Axis-aligned bounds (min, max); None for an empty mesh.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.positions.first()?;
        Some(self.positions.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
    }

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

    /// Whether every vertex coordinate is finite.
    pub fn is_finite(&self) -> bool {
        self.positions.iter().all(|p| p.is_finite())
    }
}
