//! Triangle meshes of structures, in f64, in world coordinates.
//!
//! Owns: the indexed mesh type, section outlines, the sweep mesher, the tessellation of
//! primitives, and (in `import` alone) reading and writing mesh files. A leaf: it imports no
//! other module of the crate, so it knows nothing of mechanics (the build stage tells it where
//! each section goes), cameras, rendering or recipes.

pub mod import;
pub mod outline;
pub mod primitives;
mod solids;
mod sweep;

pub use outline::SectionOutline;
pub use solids::{NOT_SOLID, Solids};
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

/// `value`, a coordinate a recipe gives itself (a plane's height), if it lies within
/// [`MAX_COORDINATE`] of the origin on either side; else why not, naming the option `name`
/// and its value. The same limit as every vertex's, so a plane may lie wherever a structure
/// may stand and nowhere else.
pub fn coordinate_in_range(value: f64, name: &str) -> Result<f64, String> {
    if value.abs() <= MAX_COORDINATE {
        Ok(value)
    } else {
        Err(format!(
            "{name} = {value} m lies beyond ±{MAX_COORDINATE:e} m, the farthest any scene coordinate may reach"
        ))
    }
}

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

    /// `count` points uniformly distributed by area on the surface, each with the unit normal
    /// of its triangle (by its winding), made from the uniform numbers in [0, 1) `uniform`
    /// gives, three a point: a triangle by its share of the area, then a point uniform on it,
    /// (1 − √r₁)·a + √r₁(1 − r₂)·b + √r₁r₂·c (Osada et al., "Shape distributions", ACM TOG
    /// 2002, §4.2). Each point keeps its triangle, where its material is found. None when the
    /// surface has no area.
    pub fn sample_surface(
        &self,
        count: usize,
        mut uniform: impl FnMut() -> f64,
    ) -> Option<Vec<SurfaceSample>> {
        let mut total = 0.0;
        let cumulative: Vec<f64> = (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.triangle(t);
                total += (b - a).cross(c - a).length();
                total
            })
            .collect();
        if !(total > 0.0) {
            return None;
        }
        let points = (0..count)
            .map(|_| {
                let at = uniform() * total;
                let t = cumulative
                    .partition_point(|&c| c <= at)
                    .min(cumulative.len() - 1);
                let [a, b, c] = self.triangle(t);
                let (s, r) = (uniform().sqrt(), uniform());
                SurfaceSample {
                    position: (1.0 - s) * a + s * (1.0 - r) * b + s * r * c,
                    normal: (b - a).cross(c - a).normalize_or_zero(),
                    triangle: t,
                }
            })
            .collect();
        Some(points)
    }
}

/// A point drawn on a mesh's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSample {
    /// Where it lies.
    pub position: DVec3,
    /// The unit normal of its triangle, by the triangle's winding.
    pub normal: DVec3,
    /// The index of its triangle.
    pub triangle: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three right triangles of areas 1/8, 3/8 and 1/2 at heights 0, 1 and 2; the middle one
    /// wound clockwise seen from +z.
    fn uneven() -> Mesh {
        let mut positions = Vec::new();
        for (z, leg) in [(0.0, 0.25), (1.0, 0.75), (2.0, 1.0)] {
            positions.extend([
                DVec3::new(0.0, 0.0, z),
                DVec3::new(1.0, 0.0, z),
                DVec3::new(0.0, leg, z),
            ]);
        }
        Mesh {
            positions,
            triangles: vec![[0, 1, 2], [3, 5, 4], [6, 7, 8]],
        }
    }

    /// Van der Corput's sequence in base 2: evenly spread numbers in [0, 1).
    fn even_numbers() -> impl FnMut() -> f64 {
        let mut i = 0u32;
        move || {
            i += 1;
            f64::from(i.reverse_bits()) / 2f64.powi(32)
        }
    }

    #[test]
    fn surface_points_lie_on_their_triangles_in_proportion_to_area() {
        let mesh = uneven();
        let points = mesh.sample_surface(40_000, even_numbers()).unwrap();
        let mut counts = [0usize; 3];
        for SurfaceSample {
            position: p,
            normal: n,
            triangle,
        } in &points
        {
            let t = p.z.round() as usize;
            assert_eq!(*triangle, t, "the triangle it lies on");
            assert!((p.z - t as f64).abs() < 1e-12, "on a triangle's plane: {p}");
            let leg = [0.25, 0.75, 1.0][t];
            assert!(
                p.x >= 0.0 && p.y >= 0.0 && p.x + p.y / leg <= 1.0 + 1e-12,
                "{p}"
            );
            assert_eq!(
                *n,
                if t == 1 { -DVec3::Z } else { DVec3::Z },
                "by the winding"
            );
            counts[t] += 1;
        }
        for (count, area) in counts.iter().zip([0.125, 0.375, 0.5]) {
            let share = *count as f64 / 40_000.0;
            assert!((share - area).abs() < 0.005, "{counts:?}");
        }
        let flat = Mesh {
            positions: vec![DVec3::ZERO, DVec3::X, 2.0 * DVec3::X],
            triangles: vec![[0, 1, 2]],
        };
        assert!(flat.sample_surface(3, even_numbers()).is_none());
    }
}
