//! Damage of a beam member as data, placed by a recipe or by the mechanics, and what it does to
//! the member's stiffness; dents and local buckles of shells as data (`shell`).
//!
//! Owns: the damage records (cracks as polylines on the undeformed surface, map cracking,
//! corrosion regions with section loss, spalls as cavities, dents; and `shell`: dents and
//! local buckles of cylindrical shells), the reinforced-concrete
//! crack and curvature model (`concrete`, EN 1992-1-1 §7.3–7.4), the rules that place damage
//! where the stresses or the exposure put it (`placement`), and the deflected axis of a member
//! whose stiffness varies (`stiffness`). Works on plain numbers in the beam's own frame (axis
//! along x from 0 to L, y across, z up, origin on the centroid axis); drawing is the
//! renderer's. Formulas and clauses: docs/damage.md.

mod concrete;
mod placement;
mod shell;
mod stiffness;

pub use concrete::{ConcreteSection, REBAR_E, Reinforcement, concrete_modulus, tensile_strength};
pub use placement::{
    DamageLabels, DamageRequest, DamagedMember, ExposureRules, InternalForces, crack_width_mm,
    exposed_corrosion, section_loss_regions, solve_damage, stress_cracks,
};
pub use shell::{
    DimpleTolerance, ShellDamage, ShellDamageKind, ShellDamageLabels, ShellPoint, dimple_tolerance,
    shell_damage,
};
pub use stiffness::SteppedBeam;

use serde::Serialize;

/// A face of a member's undeformed surface, in the beam's own frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Face {
    /// The underside (z = −h/2).
    Bottom,
    /// The top (z = +h/2).
    Top,
    /// The side facing −y.
    SideNegY,
    /// The side facing +y.
    SidePosY,
}

impl Face {
    /// The face a recipe names.
    pub fn named(name: &str) -> Result<Face, String> {
        match name {
            "bottom" => Ok(Face::Bottom),
            "top" => Ok(Face::Top),
            "side_neg_y" => Ok(Face::SideNegY),
            "side_pos_y" => Ok(Face::SidePosY),
            other => Err(format!(
                "face = \"{other}\" is unknown (known: \"bottom\", \"top\", \"side_neg_y\", \"side_pos_y\")"
            )),
        }
    }

    /// Whether the face is one of the sides (its surface coordinate is z) rather than top or
    /// bottom (its surface coordinate is y).
    pub fn is_side(self) -> bool {
        matches!(self, Face::SideNegY | Face::SidePosY)
    }
}

/// A point on a member's undeformed surface, in material coordinates: it moves with the
/// member when it deflects.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SurfacePoint {
    /// Distance along the axis from x = 0, metres.
    pub along: f64,
    /// The face it lies on.
    pub face: Face,
    /// Position on the face across the axis, metres from the centroid axis: z (up) on the
    /// sides, y on the top and bottom.
    pub height: f64,
}

/// Why a damage is where it is.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Cause {
    /// The recipe placed it.
    Placed,
    /// A solved stress or force exceeded the material's cracking resistance there.
    Stress {
        /// Which quantity: "bending_moment" (N·m) or "shear_force" (N).
        quantity: String,
        /// Its value at the damage, signed (sagging-positive moment).
        value: f64,
        /// The resistance it exceeded: the cracking moment M_cr, or the web-shear cracking
        /// force (2/3) b h f_ctm.
        limit: f64,
    },
    /// An exposure rule put it there (where water collects or runs).
    Exposure {
        /// The rule: "support_end" (within `end_length` of a supported end) or
        /// "bottom_flange" (the underside along the span).
        rule: String,
    },
}

/// How bad a damage is, on an inspector's three-step scale (cracks by width: below 0.2 mm,
/// up to 0.4 mm, wider; section loss below 5 %, up to 15 %, more; spalls and dents by depth:
/// below 10 mm, up to 25 mm, deeper).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// Hairline, superficial.
    Light,
    /// Needs watching.
    Moderate,
    /// Structurally significant.
    Severe,
}

impl Severity {
    /// The step `value` falls in, given the two thresholds.
    pub fn grade(value: f64, moderate: f64, severe: f64) -> Severity {
        if value >= severe {
            Severity::Severe
        } else if value >= moderate {
            Severity::Moderate
        } else {
            Severity::Light
        }
    }
}

/// What a damage is, with the geometry a renderer needs.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum DamageShape {
    /// A flexural crack: normal to the axis, rising from the tension face to the cracked
    /// section's neutral axis.
    FlexuralCrack {
        /// The crack's line on the surface, in order.
        path: Vec<SurfacePoint>,
        /// Its width, millimetres.
        width_mm: f64,
    },
    /// An inclined shear crack in the web (the sides), normal to the principal tension.
    ShearCrack {
        /// The crack's line on the surface, in order.
        path: Vec<SurfacePoint>,
        /// Its width, millimetres.
        width_mm: f64,
    },
    /// A net of fine cracks in cells over a region of one face.
    MapCracking {
        /// Start of the region along the axis, metres.
        from: f64,
        /// End of the region, metres.
        to: f64,
        /// The face it covers.
        face: Face,
        /// Typical cell size, metres.
        cell: f64,
        /// Crack width, millimetres.
        width_mm: f64,
    },
    /// Corrosion over a length of the member: staining, pitting and a loss of section.
    Corrosion {
        /// Start of the region along the axis, metres.
        from: f64,
        /// End of the region, metres.
        to: f64,
        /// The faces it covers.
        faces: Vec<Face>,
        /// Fraction of the cross-section lost (0–0.9); A and I scale by (1 − loss) there.
        section_loss: f64,
        /// Direction the rust stains run, beam frame (always down: [0, 0, −1]).
        stain_direction: [f64; 3],
        /// How far the stains run from the region, metres.
        stain_length: f64,
    },
    /// Concrete broken out of the surface: a cavity.
    Spall {
        /// The cavity's outline on the surface (a closed polygon, last point joined to the
        /// first).
        outline: Vec<SurfacePoint>,
        /// Its depth below the surface, metres.
        depth: f64,
    },
    /// A dent: the surface pushed in.
    Dent {
        /// Its depth, metres.
        depth: f64,
        /// Its radius on the surface, metres.
        radius: f64,
    },
}

/// One damage of a member.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Damage {
    /// What it is and its geometry (`type` names it).
    #[serde(flatten)]
    pub shape: DamageShape,
    /// The member it is on: the part name of the member ("beam").
    pub member: String,
    /// Its centre, on the undeformed surface.
    pub position: SurfacePoint,
    /// Its extent along the axis and across it on the face, metres.
    pub size: [f64; 2],
    /// Angle of its main direction on the face from the member axis, radians (π/2: normal to
    /// the axis; a shear crack ±π/4).
    pub orientation: f64,
    /// How bad it is.
    pub severity: Severity,
    /// Why it is there.
    pub cause: Cause,
}
