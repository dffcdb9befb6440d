//! Structural mechanics: how a straight beam deflects, how its material moves with it, and how
//! a cylindrical shell may be deformed.
//!
//! Owns: the linear theories (Euler–Bernoulli, Timoshenko) for four support cases and any mix
//! of loads, the cantilever elastica, the von Kármán beam with axially restrained ends,
//! vibration mode shapes, the choice of theory by estimated error, the range each theory can
//! represent, the derived labels (load, moment, stress, membrane force, plausibility), the
//! mapping of section points onto the deformed axis, cross-section properties, silo shell
//! patterns with their plausible amplitudes; structures analysed as a whole (`frame`: space
//! frames and trusses by the direct stiffness method); damage (`damage`: cracks, corrosion,
//! spalls and dents as data, placed by a recipe or by the stresses, and the damaged stiffness);
//! and beams in time (`dynamics`: moving axles, blows and sampled forces by modal
//! superposition), and the virtual sensors that record it (`sensors`: displacement,
//! velocity, acceleration, rotation and strain series at their own rates). Must not touch: meshes, cameras or files; it works on plain numbers in the
//! beam's own frame (axis along x from 0 to L, deflection v positive downward).
//!
//! Formulas, reference values, floating-point traps and the primary literature:
//! `docs/mechanics.md`.

pub mod damage;
pub mod dynamics;
mod elastica;
pub mod frame;
mod linear;
mod mapping;
mod membrane;
mod model;
mod modes;
mod range;
mod restrained;
mod section;
pub mod sensors;
mod shell;

pub use linear::{LinearBeam, Load, Station, kinks};
pub use mapping::{AxisPoint, Mapping, SectionFrame, section_frames};
pub use model::{BeamProblem, Deformation, Labels, Target, Theory};
pub use modes::ModeShape;
pub use range::{MAX_FIBRE_STRAIN, MAX_SLOPE};
#[cfg(test)]
pub(crate) use section::examples as section_examples;
pub use section::{Section, SectionProperties};
pub use shell::{Shell, ShellPattern};

use serde::Serialize;

/// Young's modulus E of structural steel, Pa. With [`STEEL_NU`] and [`STEEL_FY`] (S355,
/// EN 1993-1-1), the defaults for labels and shear flexibility.
pub const STEEL_E: f64 = 210e9;
/// Poisson's ratio ν of structural steel.
pub const STEEL_NU: f64 = 0.3;
/// Yield strength f_y of S355 steel, Pa.
pub const STEEL_FY: f64 = 355e6;

/// How a beam's ends are held. Positions along the span are measured from x = 0, the pin or clamp.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Support {
    /// Pin at x = 0, roller at x = L.
    SimplySupported,
    /// Clamped at x = 0, free at x = L.
    Cantilever,
    /// Clamped at both ends.
    FixedFixed,
    /// Clamped at x = 0, pinned (on a roller) at x = L.
    ProppedCantilever,
}

/// Whether a beam's supports hold its axis along its length. Ends that cannot move towards each
/// other make a deflecting beam stretch and carry membrane tension (docs/mechanics.md §5.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Axial {
    /// Both ends held along the axis (two clamps, or a clamp or pin at each end that cannot
    /// slide): the axis stretches by ½∫v′² and carries the membrane tension that takes.
    Restrained,
    /// One end free to move along the axis (a roller or a free end): the axis keeps its length
    /// and that end moves in by ½∫v′².
    Free,
}

impl Axial {
    /// What the supports give unless the recipe says otherwise: two clamps hold the axis
    /// (fixed–fixed); a roller or a free end lets it slide (simply supported, propped
    /// cantilever, cantilever).
    pub fn of(support: Support) -> Axial {
        match support {
            Support::FixedFixed => Axial::Restrained,
            Support::SimplySupported | Support::Cantilever | Support::ProppedCantilever => {
                Axial::Free
            }
        }
    }
}
