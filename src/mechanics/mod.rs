//! Beam mechanics: deflected shapes of a straight beam and how they move the material.
//!
//! Owns: the Euler–Bernoulli closed forms for a point load, parametrised by shape
//! (v = δ·φ(x), φ normalised to max |φ| = 1, so no load is ever inverted from a displacement),
//! the derived labels (load, moment, stress) and the mapping of section points onto the
//! deformed axis. Must not touch: meshes, cameras or files; it works on plain numbers in the
//! beam's own frame (axis along x from 0 to L, deflection v positive downward).
//!
//! Formulas: `shared/research/mechanics.md` §1.2, §1.3 and §3, written in their safe forms
//! (every bracket a sum of positive terms, the small factor divided out analytically).

mod mapping;
mod point_load;

pub use mapping::{Mapping, SectionMapper};
pub use point_load::{Deflection, PointLoadShape, Support};

/// Young's modulus and yield strength of the structural steel used for plausibility labels
/// (EN 1993-1-1, S355).
pub const STEEL_E: f64 = 210e9;
pub const STEEL_FY: f64 = 355e6;
