//! What a member's cross-section gives a space frame beyond the beam module's strong-axis
//! properties: bending about the weak axis, torsion, and the extreme fibres for the stress.
//!
//! Local axes of a member: x along it, z along the section's height (the beam module's bending
//! plane), y along its width. The strong axis is y (I_y is the beam module's `second_moment`).

use crate::mechanics::Section;
use serde::Serialize;

/// Stiffness properties of a section for a space-frame member.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SpaceSection {
    /// Area A, m².
    pub area: f64,
    /// Second moment about local y (bending in the x–z plane, the section's height), m⁴.
    pub i_y: f64,
    /// Second moment about local z (bending in the x–y plane, across the width), m⁴.
    pub i_z: f64,
    /// St Venant torsion constant J, m⁴.
    pub torsion: f64,
    /// Shear area for forces along local z (κ_z A), m².
    pub shear_area_z: f64,
    /// Shear area for forces along local y (κ_y A), m².
    pub shear_area_y: f64,
    /// Half the height: the extreme fibre for bending about y, metres.
    pub fibre_z: f64,
    /// Half the width: the extreme fibre for bending about z, metres.
    pub fibre_y: f64,
}

impl SpaceSection {
    /// The properties of `section` with Poisson's ratio `poisson` (which enters the beam
    /// module's shear coefficients). Weak-axis shear areas: the flanges' 5/6 b t_f each for an
    /// I, the vertical walls' counterpart A·b/(b + h) for a box, the strong axis's κ for the
    /// symmetric rectangle (Cowper's κ holds about either axis) and the tube.
    pub fn of(section: &Section, poisson: f64) -> SpaceSection {
        let strong = section.properties(poisson);
        let a = strong.area;
        let (i_z, torsion, kappa_y) = match *section {
            Section::Rectangle { width, height } => (
                height * width.powi(3) / 12.0,
                rectangle_torsion(width, height),
                strong.shear_coefficient,
            ),
            Section::ISection {
                width: b,
                height: h,
                flange: tf,
                web: tw,
            } => (
                2.0 * tf * b.powi(3) / 12.0 + (h - 2.0 * tf) * tw.powi(3) / 12.0,
                // Thin open walls: Σ b t³ / 3 over the two flanges and the web between them.
                (2.0 * b * tf.powi(3) + (h - 2.0 * tf) * tw.powi(3)) / 3.0,
                2.0 * (5.0 / 6.0) * b * tf / a,
            ),
            Section::HollowBox {
                width: b,
                height: h,
                wall: t,
            } => (
                (h * b.powi(3) - (h - 2.0 * t) * (b - 2.0 * t).powi(3)) / 12.0,
                // Bredt: 4 A_m² t / perimeter of the mid-wall line.
                2.0 * t * (b - t).powi(2) * (h - t).powi(2) / ((b - t) + (h - t)),
                b / (b + h),
            ),
            Section::CircularHollow { .. } => (
                strong.second_moment,
                2.0 * strong.second_moment,
                strong.shear_coefficient,
            ),
        };
        SpaceSection {
            area: a,
            i_y: strong.second_moment,
            i_z,
            torsion,
            shear_area_z: strong.shear_coefficient * a,
            shear_area_y: kappa_y * a,
            fibre_z: section.height() / 2.0,
            fibre_y: section.width() / 2.0,
        }
    }
}

/// How much of its section a damaged member keeps, as uniform factors on its stiffness
/// properties: `area` on A and the shear areas, `strong` on I_y, `weak` on I_z and J. The
/// damage model sets them (`damage`); 1 everywhere is a sound member.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SectionScale {
    /// Factor on A and the shear areas.
    pub area: f64,
    /// Factor on I_y (bending in the x–z plane, the section's height).
    pub strong: f64,
    /// Factor on I_z and the torsion constant J.
    pub weak: f64,
}

impl SectionScale {
    /// A sound member's: every factor 1.
    pub const ONE: SectionScale = SectionScale {
        area: 1.0,
        strong: 1.0,
        weak: 1.0,
    };
}

impl Default for SectionScale {
    fn default() -> Self {
        SectionScale::ONE
    }
}

impl SpaceSection {
    /// The properties with `scale` applied; the extreme fibres stay (the outline is drawn
    /// whole).
    pub fn scaled(mut self, scale: SectionScale) -> SpaceSection {
        self.area *= scale.area;
        self.shear_area_y *= scale.area;
        self.shear_area_z *= scale.area;
        self.i_y *= scale.strong;
        self.i_z *= scale.weak;
        self.torsion *= scale.weak;
        self
    }
}

/// St Venant torsion constant of a solid rectangle, J = β a b³ with a ≥ b (Roark, Table 10.7:
/// β = 1/3 − 0.21 (b/a)(1 − b⁴/(12 a⁴)), within 0.5 % of the series solution).
fn rectangle_torsion(width: f64, height: f64) -> f64 {
    let (a, b) = (width.max(height), width.min(height));
    let r = b / a;
    a * b.powi(3) * (1.0 / 3.0 - 0.21 * r * (1.0 - r.powi(4) / 12.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torsion_constants_match_handbook_values() {
        // Square: J = 0.1406 a⁴ (Timoshenko & Goodier); Roark's fit gives 0.1408.
        let sq = SpaceSection::of(
            &Section::Rectangle {
                width: 0.2,
                height: 0.2,
            },
            0.3,
        );
        assert!((sq.torsion / 0.2f64.powi(4) - 0.1406).abs() < 0.001);
        assert_eq!(sq.i_y, sq.i_z);
        // Thin tube: J = 2I = 2π r³ t for r ≫ t.
        let tube = SpaceSection::of(
            &Section::CircularHollow {
                diameter: 1.0,
                wall: 0.001,
            },
            0.3,
        );
        let r: f64 = 0.4995;
        assert!(
            (tube.torsion / (2.0 * std::f64::consts::PI * r.powi(3) * 0.001) - 1.0).abs() < 1e-3
        );
        // Thin square box 0.2 × 0.2, t = 0.005: Bredt 4 A_m² t / s = t (b − t)³.
        let boxed = SpaceSection::of(
            &Section::HollowBox {
                width: 0.2,
                height: 0.2,
                wall: 0.005,
            },
            0.3,
        );
        assert!((boxed.torsion / (0.005 * 0.195f64.powi(3)) - 1.0).abs() < 1e-12);
    }
}
