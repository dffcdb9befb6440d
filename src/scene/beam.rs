//! A straight beam as a recipe declares it: section, supports, loads, theory, tessellation,
//! material and placement. Solving and meshing it is the build stage's work.

use super::{SourceSite, Tolerance};
use crate::materials::Material;
use crate::mechanics::{
    Load, Mapping, STEEL_E, STEEL_FY, STEEL_NU, Section, Support, Target, Theory,
};
use serde::Serialize;

/// How finely the beam is meshed along its length (sections get exactly the vertices their
/// shape needs, circles to the same chord tolerance).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
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

/// Chord tolerance of a section's circles when the count along the length is fixed
/// (`Segments`, `Paper`), as a fraction of a pixel at the nearest camera.
const FIXED_COUNT_PIXEL_TOLERANCE: f64 = 0.25;

impl Tessellation {
    /// The chord rule for whatever the tessellation does not fix by count.
    pub fn tolerance(self) -> Tolerance {
        match self {
            Tessellation::Chord(metres) => Tolerance::Chord(metres),
            Tessellation::Pixels(fraction) => Tolerance::Pixels(fraction),
            Tessellation::Segments(_) | Tessellation::Paper => {
                Tolerance::Pixels(FIXED_COUNT_PIXEL_TOLERANCE)
            }
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
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
    /// The recipe call that last changed the beam's mechanics (its construction, supports,
    /// loads, target or material constants), where errors found when solving it point.
    #[serde(skip)]
    pub declared_at: Option<SourceSite>,
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
            declared_at: None,
        }
    }

    pub fn rectangular(length: f64, width: f64, height: f64) -> Self {
        Self::new(length, Section::Rectangle { width, height })
    }
}
