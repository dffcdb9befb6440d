//! A straight beam as a recipe declares it: section, supports, loads, theory, tessellation,
//! material and placement. Solving and meshing it is the build stage's work.

use super::{BeamMotion, SensorSpec, SourceSite, Tolerance};
use crate::materials::Material;
use crate::mechanics::damage::DamageRequest;
use crate::mechanics::{
    Axial, Load, Mapping, STEEL_E, STEEL_FY, STEEL_NU, Section, Support, Target, Theory,
};
use serde::Serialize;

/// How finely the beam is meshed along its length (sections get exactly the vertices their
/// shape needs, circles to the same chord tolerance).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", content = "value", rename_all = "snake_case")]
pub enum Tessellation {
    /// Equal intervals along the length (plus stations at the load positions and the peak).
    Segments(
        /// Number of equal intervals, 1–100000.
        u32,
    ),
    /// Chord (sagitta) error of the deformed surface at most this many metres.
    Chord(
        /// Largest chord error, metres.
        f64,
    ),
    /// Chord error at most this fraction of a pixel at the nearest camera the rig can place.
    Pixels(
        /// Largest chord error, as a fraction of the pixel footprint (e.g. 0.1).
        f64,
    ),
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

/// A straight prismatic beam as declared: section, supports, loads, theory, material and placement.
/// In its own frame the axis runs along x from 0 to L, y across and z up; deflection v is positive
/// downward (world −z).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct BeamSpec {
    /// Span L, metres: the axis runs from x = 0 (the pin or clamp) to x = L.
    pub length: f64,
    /// Cross-section shape and dimensions.
    pub section: Section,
    /// How the ends are supported.
    pub support: Support,
    /// Whether the supports hold the axis along its length, as the recipe asked; absent: as the
    /// supports give it (restrained for fixed_fixed, free otherwise). `labels.axial` says which
    /// applied.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axial: Option<Axial>,
    /// Loads on the span as declared; when `target` scales them, only their ratios matter
    /// (`labels.loads` holds the physical loads).
    pub loads: Vec<Load>,
    /// Whether the load magnitudes are physical or scaled to reach a target deflection.
    pub target: Target,
    /// The beam theory asked for; `auto` chooses by estimated error (`labels.theory` says which
    /// ran).
    pub theory: Theory,
    /// A vibration snapshot (mode number, amplitude in metres) instead of static loads.
    pub vibration: Vec<(u32, f64)>,
    /// Largest acceptable model error, as a fraction of the peak deflection.
    pub model_tolerance: f64,
    /// How points of the cross-section follow the deflected axis.
    pub mapping: Mapping,
    /// How finely the beam is meshed along its length.
    pub tessellation: Tessellation,
    /// Young's modulus E, Pa (default 210 GPa, structural steel).
    pub elastic_modulus: f64,
    /// Poisson's ratio ν (default 0.3); the shear modulus is G = E / (2 (1 + ν)).
    pub poisson: f64,
    /// Yield strength f_y, Pa (default 355 MPa, S355), against which `physically_plausible` is
    /// judged.
    pub yield_strength: f64,
    /// How the beam's surface looks.
    pub material: Material,
    /// World position of the centre of the undeformed beam, metres.
    pub centre: [f64; 3],
    /// Rotation about the world z axis (radians); 0 puts the beam axis along +x.
    pub yaw: f64,
    /// Whether the supports are drawn (`.supports_drawn(true)`): a pin or roller bearing on a
    /// concrete abutment under each supported end, a concrete wall each clamped end is built
    /// into, all reaching down to one level below the deflected beam. Absent: not drawn.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub supports_drawn: bool,
    /// Damage placed by the recipe, and whether the mechanics places more (reinforced concrete:
    /// cracks by stress; steel: corrosion by exposure). Absent: a sound beam. What was placed
    /// and what it did is in `damage` next to `labels`.
    #[serde(default, skip_serializing_if = "DamageRequest::is_empty")]
    pub damage_asked: DamageRequest,
    /// How the beam moves over the dataset's sequence (time loads, damping, modes); absent: it
    /// holds its static shape in every frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion: Option<BeamMotion>,
    /// In a frame of a sequence: the dynamic part of the deflection at the frame's instant,
    /// (mode number, amplitude in metres of the normalised mode shape), added to the static
    /// solution of `loads` (which then hold the loads acting at that instant). Empty otherwise.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub frame_modes: Vec<(u32, f64)>,
    /// Virtual sensors on the beam (`.sensor(#{…})`), recorded over the dataset's sequence.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sensors: Vec<SensorSpec>,
    /// The recipe call that last changed the beam's mechanics (its construction, supports,
    /// loads, target or material constants), where errors found when solving it point.
    #[serde(skip)]
    pub declared_at: Option<SourceSite>,
}

impl BeamSpec {
    /// A simply supported steel beam of `length` metres with `section`, no loads yet, in the
    /// default material at the origin along +x.
    pub fn new(length: f64, section: Section) -> Self {
        BeamSpec {
            length,
            section,
            support: Support::SimplySupported,
            axial: None,
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
            supports_drawn: false,
            damage_asked: DamageRequest::default(),
            motion: None,
            frame_modes: Vec::new(),
            sensors: Vec::new(),
            declared_at: None,
        }
    }

    /// How the supports hold the axis: as the recipe asked, or what the supports give.
    pub fn axial(&self) -> Axial {
        self.axial.unwrap_or(Axial::of(self.support))
    }

    /// [`BeamSpec::new`] with a solid rectangular section `width` × `height` metres.
    pub fn rectangular(length: f64, width: f64, height: f64) -> Self {
        Self::new(length, Section::Rectangle { width, height })
    }
}
