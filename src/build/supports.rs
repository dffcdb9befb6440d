//! Drawn supports of a beam (`.supports_drawn(true)`): simple, honest shapes where the
//! mechanics puts the supports, so that a beam stands on something rather than floating.
//!
//! Owns: the shapes and their part names — a pin (a steel plate on a triangular prism on a
//! base plate), a roller (a steel plate on a cylinder on a base plate), each on a concrete
//! abutment, and a concrete wall for each clamped end, the end built into it — placed under the
//! deformed beam and reaching down to one level (where the ground will lie). Must not touch:
//! the beam's mesh or mechanics (it reads only the spec and the deformed mesh's lowest point),
//! materials' generators, or rays.

use super::tessellation::chord_tolerance;
use crate::geometry::Mesh;
use crate::geometry::primitives::Primitive;
use crate::mechanics::Support;
use crate::scene::BeamSpec;
use glam::{DAffine3, DMat3, DVec3};
use std::f64::consts::FRAC_PI_2;

/// What a drawn support piece is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SupportMaterial {
    /// Bearings: plates, prisms, rollers.
    Steel,
    /// Abutments and walls.
    Concrete,
}

/// One drawn piece of a support, in world coordinates.
pub struct SupportPiece {
    /// The piece's closed mesh.
    pub mesh: Mesh,
    /// Its part label: "pin", "roller", "clamp" or "abutment".
    pub part: &'static str,
    /// What it is made of.
    pub material: SupportMaterial,
}

/// The kind of support at one end of a beam, from the mechanics' support type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum End {
    Pin,
    Roller,
    Clamp,
    Free,
}

/// The supports at x = 0 and x = L of a beam with `support`.
fn ends(support: Support) -> [End; 2] {
    match support {
        Support::SimplySupported => [End::Pin, End::Roller],
        Support::Cantilever => [End::Clamp, End::Free],
        Support::FixedFixed => [End::Clamp, End::Clamp],
        Support::ProppedCantilever => [End::Clamp, End::Roller],
    }
}

/// Height of a pin or roller bearing (top plate, prism or roller, base plate), in units of
/// the support size.
const BEARING_HEIGHT: f64 = 0.46;

/// The drawn supports of `beam`, whose deformed mesh reaches down to `lowest` (world z), with
/// curved surfaces tessellated for `pixel_footprint` as the beam is. Every piece reaches down
/// to one level at least a fifth of the support size below both the lowest point of the beam
/// and the bearings' abutments' least height, so the beam clears the ground laid there.
pub fn drawn_supports(
    beam: &BeamSpec,
    lowest: f64,
    pixel_footprint: f64,
) -> Result<Vec<SupportPiece>, String> {
    let (h, b) = (beam.section.height(), beam.section.width());
    // The size the bearings scale with: the depth, or a share of the width for a flat plate.
    let unit = h.max(0.3 * b);
    let tolerance = chord_tolerance(beam.tessellation.tolerance(), pixel_footprint);
    let centre = DVec3::from_array(beam.centre);
    // Local frame: the beam's centre at the origin, its axis along x, z up.
    let bottom = -0.5 * h;
    let bearing_foot = bottom - BEARING_HEIGHT * unit;
    let level = (bearing_foot - 0.8 * unit).min(lowest - centre.z - 0.2 * unit);
    let width = b + 0.4 * unit;
    let place = DAffine3::from_mat3_translation(DMat3::from_rotation_z(beam.yaw), centre);
    let mut pieces = Vec::new();
    let mut add = |primitive: Primitive, at: DAffine3, part, material| -> Result<(), String> {
        let mut mesh = primitive.mesh(tolerance)?;
        mesh.transform(&(place * at));
        pieces.push(SupportPiece {
            mesh,
            part,
            material,
        });
        Ok(())
    };
    // A box from z0 to z1 (local), centred on (x, 0).
    let block = |x: f64, length: f64, across: f64, z0: f64, z1: f64| {
        (
            Primitive::Box {
                size: [length, across, z1 - z0],
            },
            DAffine3::from_translation(DVec3::new(x, 0.0, 0.5 * (z0 + z1))),
        )
    };
    // Turns a shape extruded along +z into one lying along y, centred across the beam.
    let across = |x: f64, z: f64| {
        DAffine3::from_translation(DVec3::new(x, 0.5 * width, z))
            * DAffine3::from_rotation_x(FRAC_PI_2)
    };
    let plate = 0.08 * unit;
    for (end, side) in ends(beam.support).into_iter().zip([-1.0, 1.0]) {
        let x = side * 0.5 * beam.length;
        match end {
            End::Free => {}
            End::Pin | End::Roller => {
                let part = if end == End::Pin { "pin" } else { "roller" };
                let steel = SupportMaterial::Steel;
                let (p, at) = block(x, 0.6 * unit, width, bottom - plate, bottom);
                add(p, at, part, steel)?;
                let (p, at) = block(x, 0.6 * unit, width, bearing_foot, bearing_foot + plate);
                add(p, at, part, steel)?;
                let core = (BEARING_HEIGHT - 2.0 * plate / unit) * unit;
                let (p, at) = if end == End::Pin {
                    let half = 0.2 * unit;
                    let profile = vec![[-half, 0.0], [half, 0.0], [0.0, core]];
                    (
                        Primitive::Extrusion {
                            profile,
                            length: width,
                        },
                        across(x, bearing_foot + plate),
                    )
                } else {
                    let r = 0.5 * core;
                    (
                        Primitive::Frustum {
                            bottom_radius: r,
                            top_radius: r,
                            height: width,
                        },
                        across(x, bearing_foot + plate + r),
                    )
                };
                add(p, at, part, steel)?;
                let (p, at) = block(x, 1.2 * unit, width + 0.4 * unit, level, bearing_foot);
                add(p, at, "abutment", SupportMaterial::Concrete)?;
            }
            End::Clamp => {
                // The wall stands beyond the end and takes the last twentieth of the depth of
                // the beam into it.
                let thick = 0.8 * unit;
                let (p, at) = block(
                    x + side * (0.5 * thick - 0.05 * unit),
                    thick,
                    width + 0.8 * unit,
                    level,
                    0.5 * h + 0.4 * unit,
                );
                add(p, at, "clamp", SupportMaterial::Concrete)?;
            }
        }
    }
    Ok(pieces)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lowest_z(pieces: &[SupportPiece]) -> f64 {
        pieces
            .iter()
            .flat_map(|p| p.mesh.positions.iter().map(|q| q.z))
            .fold(f64::INFINITY, f64::min)
    }

    /// Pin and roller sit exactly under the beam's bottom face at x = 0 and x = L (each top
    /// plate's top at the beam's underside, centred on the support), every piece is closed,
    /// and all reach the same level below the beam's lowest point.
    #[test]
    fn simply_supported_bearings_sit_under_the_ends_and_reach_below_the_sag() {
        let mut beam = BeamSpec::rectangular(4.0, 0.2, 0.4);
        beam.centre = [1.0, 2.0, 3.0];
        beam.yaw = 0.3;
        let lowest = 3.0 - 0.2 - 0.5;
        let pieces = drawn_supports(&beam, lowest, 0.001).unwrap();
        let parts: Vec<&str> = pieces.iter().map(|p| p.part).collect();
        assert_eq!(
            parts,
            [
                "pin", "pin", "pin", "abutment", "roller", "roller", "roller", "abutment"
            ]
        );
        for p in &pieces {
            assert!(p.mesh.is_closed_and_oriented(), "{}", p.part);
        }
        let axis = DVec3::new(0.3f64.cos(), 0.3f64.sin(), 0.0);
        for (first, end) in [(0, -2.0), (4, 2.0)] {
            let top = &pieces[first].mesh;
            let top_z = top.positions.iter().map(|q| q.z).fold(f64::MIN, f64::max);
            assert!((top_z - 2.8).abs() < 1e-12, "{top_z}");
            let (lo, hi) = top.bounds().unwrap();
            let mid = 0.5 * (lo + hi) - DVec3::new(1.0, 2.0, 0.0);
            assert!((mid.dot(axis) - end).abs() < 1e-12);
        }
        let level = lowest_z(&pieces);
        assert!(level < lowest - 0.2 * 0.4 + 1e-12, "{level}");
        for p in pieces.iter().filter(|p| p.part == "abutment") {
            let z = p
                .mesh
                .positions
                .iter()
                .map(|q| q.z)
                .fold(f64::INFINITY, f64::min);
            assert_eq!(z, level);
        }
    }

    #[test]
    fn a_cantilever_has_one_wall_and_its_free_end_nothing() {
        let beam = BeamSpec {
            support: Support::Cantilever,
            ..BeamSpec::rectangular(3.0, 0.2, 0.3)
        };
        let pieces = drawn_supports(&beam, -0.5, 0.001).unwrap();
        assert_eq!(pieces.len(), 1);
        assert_eq!(pieces[0].part, "clamp");
        let (lo, hi) = pieces[0].mesh.bounds().unwrap();
        // The wall holds the end at x = -1.5 and stands beyond it.
        assert!(lo.x < -1.5 && hi.x > -1.5 && hi.x < -1.4, "{lo} {hi}");
        assert!(hi.z > 0.15 && lo.z < -0.5);
    }
}
