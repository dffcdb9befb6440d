//! Assemblies: structures built in recipes from labelled, transformed primitives.

use crate::geometry::primitives::Primitive;
use crate::geometry::Mesh;
use crate::materials::Material;
use glam::{DAffine3, DMat3, DVec3};
use serde::Serialize;

/// A primitive placed in its assembly, with the part it belongs to (for segmentation).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShapeSpec {
    pub primitive: Primitive,
    /// Affine map from the primitive's frame to the assembly's: rows of a 3 × 4 matrix.
    pub transform: [[f64; 4]; 3],
    pub part: String,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AssemblySpec {
    pub name: String,
    pub shapes: Vec<ShapeSpec>,
    pub material: Material,
}

impl ShapeSpec {
    pub fn new(primitive: Primitive) -> Self {
        ShapeSpec { primitive, transform: to_rows(DAffine3::IDENTITY), part: "body".into() }
    }

    pub fn affine(&self) -> DAffine3 {
        let r = &self.transform;
        DAffine3 {
            matrix3: DMat3::from_cols(
                DVec3::new(r[0][0], r[1][0], r[2][0]),
                DVec3::new(r[0][1], r[1][1], r[2][1]),
                DVec3::new(r[0][2], r[1][2], r[2][2]),
            ),
            translation: DVec3::new(r[0][3], r[1][3], r[2][3]),
        }
    }

    /// Applies `m` after the current placement.
    pub fn then(&mut self, m: DAffine3) {
        self.transform = to_rows(m * self.affine());
    }

    /// Largest stretch of the placement (for tolerances and bounds).
    fn stretch(&self) -> f64 {
        let m = self.affine().matrix3;
        m.x_axis.length().max(m.y_axis.length()).max(m.z_axis.length())
    }
}

fn to_rows(m: DAffine3) -> [[f64; 4]; 3] {
    let (c, t) = (m.matrix3, m.translation);
    [[c.x_axis.x, c.y_axis.x, c.z_axis.x, t.x], [c.x_axis.y, c.y_axis.y, c.z_axis.y, t.y], [c.x_axis.z, c.y_axis.z, c.z_axis.z, t.z]]
}

impl AssemblySpec {
    /// Radius of a sphere about the origin containing every shape.
    pub fn radius(&self) -> f64 {
        self.shapes.iter().map(|s| s.affine().translation.length() + s.stretch() * s.primitive.bounding_radius()).fold(0.0, f64::max)
    }

    /// The meshes of the shapes with their part labels. Chords stay within `tolerance` metres
    /// after placement (a scaled shape is tessellated more finely).
    pub fn build(&self, tolerance: f64) -> Result<Vec<(Mesh, &str)>, String> {
        if self.shapes.is_empty() {
            return Err(format!("assembly \"{}\" has no shapes", self.name));
        }
        self.shapes
            .iter()
            .map(|s| {
                s.primitive.validate()?;
                let m = s.affine();
                if !m.is_finite() || m.matrix3.determinant().abs() < 1e-300 {
                    return Err(format!("assembly \"{}\": a shape of part \"{}\" has a degenerate placement", self.name, s.part));
                }
                let mut mesh = s.primitive.mesh(tolerance / s.stretch());
                mesh.transform(&m);
                Ok((mesh, s.part.as_str()))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placements_compose_and_keep_volumes() {
        let mut s = ShapeSpec::new(Primitive::Box { size: [1.0, 2.0, 3.0] });
        s.then(DAffine3::from_rotation_z(0.7));
        s.then(DAffine3::from_scale(DVec3::splat(2.0)));
        s.then(DAffine3::from_translation(DVec3::new(10.0, 0.0, 0.0)));
        let a = AssemblySpec { name: "a".into(), shapes: vec![s], material: Material::default() };
        let (mesh, part) = &a.build(1e-3).unwrap()[0];
        assert_eq!(*part, "body");
        assert!((mesh.signed_volume() - 6.0 * 8.0).abs() < 1e-9, "{}", mesh.signed_volume());
        let (lo, hi) = mesh.bounds().unwrap();
        assert!(((lo + hi) / 2.0 - DVec3::new(10.0, 0.0, 0.0)).length() < 1e-12);
        assert!(mesh.positions.iter().all(|p| p.length() <= a.radius() + 1e-12), "every vertex within the bounding radius");
        // A mirror keeps the mesh outward-facing.
        let mut m = ShapeSpec::new(Primitive::Box { size: [1.0, 1.0, 1.0] });
        m.then(DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0)));
        let mirrored = AssemblySpec { name: "m".into(), shapes: vec![m], material: Material::default() };
        assert!(mirrored.build(1e-3).unwrap()[0].0.signed_volume() > 0.0);
    }
}
