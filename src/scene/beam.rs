//! A straight beam: section, supports, loads, theory, tessellation and placement.

use crate::geometry::{Mesh, beam_mesh};
use crate::materials::Material;
use crate::mechanics::{
    BeamProblem, Deformation, Load, Mapping, STEEL_E, STEEL_FY, STEEL_NU, Section, SectionFrame,
    Support, Target, Theory, kinks, section_frames,
};
use glam::{DMat3, DVec3};
use serde::Serialize;

/// How finely the beam is meshed along its length (sections get exactly the vertices their
/// shape needs, circles to the same chord tolerance).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", content = "value", rename_all = "snake_case")]
pub enum Tessellation {
    /// Equal intervals along the length.
    Segments(u32),
    /// Chord (sagitta) error of the deformed surface at most this many metres.
    Chord(f64),
    /// Chord error at most this fraction of a pixel at the nearest camera the rig can place.
    Pixels(f64),
    /// The 3DGEN mesh: every face of the cuboid split into a 32 × 32 grid (12,288 triangles).
    Paper,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BeamSpec {
    pub length: f64,
    pub section: Section,
    pub support: Support,
    pub loads: Vec<Load>,
    pub target: Target,
    pub theory: Theory,
    /// A vibration snapshot (mode number, amplitude in metres) instead of static loads.
    pub vibration: Vec<(u32, f64)>,
    /// Largest acceptable model error, as a fraction of the peak deflection.
    pub model_tolerance: f64,
    pub mapping: Mapping,
    pub tessellation: Tessellation,
    pub elastic_modulus: f64,
    pub poisson: f64,
    pub yield_strength: f64,
    pub material: Material,
    /// World position of the centre of the undeformed beam.
    pub centre: [f64; 3],
    /// Rotation about the world z axis (radians); 0 puts the beam axis along +x.
    pub yaw: f64,
}

/// A beam's mesh and the mechanics behind it.
pub struct BuiltBeam {
    pub mesh: Mesh,
    /// Where each vertex of `mesh` lies on the undeformed beam (textures are fixed there).
    pub rest: Vec<DVec3>,
    pub deformation: Deformation,
    pub segments: usize,
}

impl BeamSpec {
    pub fn new(length: f64, section: Section) -> Self {
        BeamSpec {
            length,
            section,
            support: Support::SimplySupported,
            loads: Vec::new(),
            target: Target::Physical,
            theory: Theory::Auto,
            vibration: Vec::new(),
            model_tolerance: 0.01,
            mapping: Mapping::default(),
            tessellation: Tessellation::Pixels(super::PIXEL_TOLERANCE),
            elastic_modulus: STEEL_E,
            poisson: STEEL_NU,
            yield_strength: STEEL_FY,
            material: Material::default(),
            centre: [0.0; 3],
            yaw: 0.0,
        }
    }

    pub fn rectangular(length: f64, width: f64, height: f64) -> Self {
        Self::new(length, Section::Rectangle { width, height })
    }

    pub fn problem(&self) -> BeamProblem {
        BeamProblem {
            support: self.support,
            length: self.length,
            loads: self.loads.clone(),
            target: self.target,
            section: self.section.properties(self.poisson),
            elastic_modulus: self.elastic_modulus,
            poisson: self.poisson,
            yield_strength: self.yield_strength,
            theory: self.theory,
            tolerance: self.model_tolerance,
            vibration: self.vibration.clone(),
        }
    }

    /// Radius of the undeformed beam's bounding sphere.
    pub fn radius(&self) -> f64 {
        0.5 * (self.length.powi(2) + self.section.width().powi(2) + self.section.height().powi(2))
            .sqrt()
    }

    /// Solves the mechanics and meshes the deformed beam. `pixel_footprint` is the size of a
    /// pixel (metres) at the nearest distance a camera can be from this beam.
    pub fn build(&self, pixel_footprint: f64) -> Result<BuiltBeam, String> {
        let deformation = Deformation::solve(&self.problem())?;
        let tolerance = match self.tessellation {
            Tessellation::Chord(metres) => metres,
            Tessellation::Pixels(fraction) => fraction * pixel_footprint,
            // A fixed count along the length still leaves the section's circles to the rule.
            Tessellation::Segments(_) | Tessellation::Paper => 0.25 * pixel_footprint,
        };
        let segments = match self.tessellation {
            Tessellation::Segments(n) => n as usize,
            Tessellation::Paper => crate::mechanics::PAPER_DIVISIONS,
            Tessellation::Chord(_) | Tessellation::Pixels(_) => segments_for_chord(
                self.length,
                deformation.max_curvature(self.length),
                tolerance,
            ),
        };
        let outline = match self.tessellation {
            Tessellation::Paper => self
                .section
                .paper_outline()
                .ok_or("the paper's mesh exists only for the rectangular section")?,
            _ => self.section.outline(tolerance),
        };
        let stations = stations(self.length, segments, &self.kinks(&deformation));
        let frames = section_frames(&stations, self.mapping, |x| deformation.at(x));
        let unloaded: Vec<SectionFrame> = stations
            .iter()
            .map(|&x| SectionFrame {
                x,
                v: 0.0,
                cos: 1.0,
                sin: 0.0,
            })
            .collect();
        let place = |frames: &[SectionFrame]| {
            beam_mesh(
                self.length,
                frames,
                &outline,
                DMat3::from_rotation_z(self.yaw),
                DVec3::from_array(self.centre),
            )
        };
        let mesh = place(&frames);
        Ok(BuiltBeam {
            rest: place(&unloaded).positions,
            mesh,
            deformation,
            segments,
        })
    }

    /// Where the deflected shape has kinks or its peak: these become stations.
    fn kinks(&self, d: &Deformation) -> Vec<f64> {
        let mut k = kinks(&self.loads);
        k.push(d.labels.max_deflection_at);
        k
    }
}

/// Uniform intervals whose chord error h²κ/8 stays below `tolerance`.
pub fn segments_for_chord(length: f64, curvature: f64, tolerance: f64) -> usize {
    let n = (length * (curvature / (8.0 * tolerance)).sqrt()).ceil();
    if n.is_finite() {
        (n as usize).clamp(1, 100_000)
    } else {
        100_000
    }
}

/// `segments` equal intervals plus the kinks, without slivers closer than 1e-9 L.
pub fn stations(length: f64, segments: usize, kinks: &[f64]) -> Vec<f64> {
    let n = segments.max(1);
    let mut s: Vec<f64> = (0..=n).map(|i| length * i as f64 / n as f64).collect();
    s.extend(kinks.iter().copied().filter(|k| *k > 0.0 && *k < length));
    s.sort_by(f64::total_cmp);
    let min_gap = length * 1e-9;
    let mut out: Vec<f64> = Vec::with_capacity(s.len());
    for x in s {
        match out.last() {
            Some(&prev) if x - prev <= min_gap => {}
            _ => out.push(x),
        }
    }
    *out.last_mut().expect("at least two stations") = length;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::Load;

    #[test]
    fn every_section_gives_a_closed_mesh_with_the_section_volume() {
        for section in crate::mechanics::section_examples() {
            let mut b = BeamSpec::new(4.0, section.clone());
            b.tessellation = Tessellation::Chord(1e-5);
            let mesh = b.build(1e-3).unwrap().mesh;
            assert!(mesh.is_closed_and_oriented());
            let area = section.properties(0.3).area;
            // Circles are inscribed polygons: their area is short by O(tolerance/r).
            let tol = if matches!(section, Section::CircularHollow { .. }) {
                1e-3
            } else {
                1e-12
            };
            assert!(
                (mesh.signed_volume() / (4.0 * area) - 1.0).abs() < tol,
                "{section:?}: {}",
                mesh.signed_volume() / (4.0 * area)
            );
        }
    }

    #[test]
    fn paper_mesh_has_the_papers_face_count() {
        let mut b = BeamSpec::rectangular(2.0, 0.2, 0.1);
        b.tessellation = Tessellation::Paper;
        let mesh = b.build(1e-3).unwrap().mesh;
        assert_eq!(mesh.triangles.len(), 12_288);
        assert!(mesh.is_closed_and_oriented());
        assert!((mesh.signed_volume() - 2.0 * 0.2 * 0.1).abs() < 1e-12);
    }

    #[test]
    fn deformed_axis_passes_through_the_target_deflection() {
        let mut b = BeamSpec::rectangular(3.0, 0.3, 0.5);
        b.support = Support::Cantilever;
        b.loads = vec![Load::Point {
            at: 3.0,
            force: 1.0,
        }];
        b.target = Target::Peak { deflection: 0.12 };
        let built = b.build(1e-3).unwrap();
        let n = built.mesh.positions.len();
        let tip: glam::DVec3 = built.mesh.positions[n - 4..].iter().sum::<glam::DVec3>() / 4.0;
        assert!((tip.z + 0.12).abs() < 1e-12, "{tip}");
        assert!(built.mesh.is_closed_and_oriented());
        // Bending keeps the volume to second order in the rotation.
        assert!((built.mesh.signed_volume() / (3.0 * 0.15) - 1.0).abs() < 1e-4);
    }

    #[test]
    fn stations_include_kinks_and_both_ends() {
        assert_eq!(
            stations(2.0, 4, &[0.3, 1.0, 2.0, 0.0]),
            vec![0.0, 0.3, 0.5, 1.0, 1.5, 2.0]
        );
    }

    #[test]
    fn chord_rule_gives_the_error_it_promises() {
        // SS centre load: κ_max = 12δ/L², e_N = 1.5 δ/N² (mechanics.md §8.1).
        let (l, delta, tol) = (4.0, 0.2, 1e-3);
        let n = segments_for_chord(l, 12.0 * delta / (l * l), tol);
        assert!(
            1.5 * delta / (n * n) as f64 <= tol && 1.5 * delta / ((n - 1) * (n - 1)) as f64 > tol,
            "n = {n}"
        );
    }
}
