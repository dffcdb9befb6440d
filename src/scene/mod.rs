//! Scene descriptions: plain data produced by recipes and consumed by everything downstream.
//!
//! Owns: what a dataset and one of its samples *are* (structures, supports, loads,
//! materials, camera distribution, light, outputs), with every value resolved and validated.
//! Must not touch: Rhai (recipes build these), meshing, drawing random values, tracing or
//! files: the build stage turns a scene into meshes, and everything here serialises into the
//! records of a dataset.

mod assembly;
mod augment;
mod beam;
mod frame;
mod ground;
mod light;
mod sensors;
mod sequence;

pub use assembly::{AssemblySpec, Bending, LabelledPattern, ShapeSpec};
pub use augment::{
    AugmentSpec, BlurSpec, ColourJitterSpec, CropSpec, ErasingSpec, ExposureSpec, Fill, GammaSpec,
    GeometryMode, JpegSpec, NoiseSpec, OPERATION_NAMES, Operation, Range, SigmaUnit, VignetteSpec,
    WarpSpec, operation_path,
};
pub use beam::{BeamSpec, Tessellation};
pub use frame::FrameSpec;
pub use ground::{GROUND_PART, GroundSpec, ground_radius};
pub use light::{
    Background, EnvironmentLightSpec, EnvironmentSpec, GroundBounceSpec, ImageRecord, LightSpec,
    OUTDOOR_AMBIENT, SUN_DIAMETER, SkyGradient, SkySpec, SunSpec, Tone,
};
pub use sensors::{SensorQuantity, SensorSpec, modal_beam, record_frame_sensors, record_sensors};
pub use sequence::{
    BeamMotion, CameraPath, DEFAULT_DAMPING, DEFAULT_EXPOSURE_FRACTION, DEFAULT_MODES,
    DEFAULT_TRACK_STRIDE, MAX_FRAMES, MAX_MOTION_BLUR, MAX_TRACK_STRIDE, MountShake, STEEL_DENSITY,
    SequenceSpec, Waypoint,
};

use crate::cameras::CameraRig;
use serde::Serialize;
use std::collections::BTreeMap;

/// Default chord tolerance of every curved surface, beams and primitives alike: this fraction of
/// a pixel at the nearest camera the rig can place.
pub const PIXEL_TOLERANCE: f64 = 0.1;

/// Where in a recipe's sources something was declared: errors found when it is built later
/// point back there.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SourceSite {
    /// The source's label in diagnostics (the recipe's or a module's path).
    pub source: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
}

/// How closely a tessellated surface follows the true one: the largest chord (sagitta) error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", content = "value", rename_all = "snake_case")]
pub enum Tolerance {
    /// An absolute chord error, in metres.
    Chord(
        /// Largest chord error, metres.
        f64,
    ),
    /// As a fraction of a pixel at the nearest camera the rig can place.
    Pixels(
        /// Largest chord error, as a fraction of the pixel footprint (e.g. 0.1).
        f64,
    ),
}

/// Dataset-wide settings declared by a recipe.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct DatasetSpec {
    /// The dataset's name, as the recipe gives it.
    pub name: String,
    /// The run seed (≥ 0): every random value of the dataset comes from a stream derived from it.
    pub seed: u64,
    /// Number of samples (scenes drawn from the recipe's `scene`), indexed from 0.
    pub samples: u64,
    /// Camera views rendered of each sample.
    pub views: u32,
    /// The distribution the cameras of the views are drawn from.
    pub camera: CameraRig,
    /// Which files are written, by output name: per view, and per sample for meshes and points.
    pub outputs: Outputs,
    /// What RGB shows behind the structures; black as in the paper.
    pub background: Background,
    /// The light as declared; ranges are drawn once per sample.
    pub light: LightSpec,
    /// Anti-alias RGB where the image changes (silhouettes, creases); labels never are.
    pub antialias: bool,
    /// How RGB evaluates what does not depend on the view: the light's shadow and occlusion
    /// rays once per sample where the light changes, shared by its views (`cached`), or at
    /// every pixel (`per_pixel`, the reference). Materials are evaluated at every pixel under
    /// either (measured in docs/materials.md). Labels are the same either way.
    pub shading: Shading,
    /// Augmented copies of every view.
    pub augment: AugmentSpec,
    /// What the camera's sensor and lens do to every clean image (vignetting, noise, blur,
    /// ...): photometric operations drawn once per view, before any augmentation.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sensor: Vec<Operation>,
    /// The axes the `normals` output is written in.
    pub normals: NormalsFrame,
    /// Points the `points` output draws on each sample's surface.
    pub points: u32,
    /// The ground the structures stand on, if any (none by default, as in the paper).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground: Option<GroundSpec>,
    /// The frames every sample films (`dataset.sequence`); absent: one still snapshot per view.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sequence: Option<SequenceSpec>,
}

/// How RGB evaluates the light that does not depend on the view (the recipe's
/// `dataset.shading`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Shading {
    /// What changes slowly over a surface (sun visibility with its penumbra, sky occlusion,
    /// ground bounce) traced once per sample where it changes, shared by its views
    /// (docs/daylight.md, "The lighting cache"); the materials still at every pixel, where a
    /// cache of their fields was measured not to pay (docs/materials.md).
    #[default]
    Cached,
    /// Every pixel traces its own shadow and occlusion rays: the reference the cache is
    /// measured against.
    PerPixel,
}

impl Shading {
    /// The recipe's words for the values.
    pub const NAMES: [&str; 2] = ["cached", "per_pixel"];

    /// The value named `name` (one of `NAMES`).
    pub fn named(name: &str) -> Option<Shading> {
        match name {
            "cached" => Some(Shading::Cached),
            "per_pixel" => Some(Shading::PerPixel),
            _ => None,
        }
    }
}

/// The axes surface normals are written in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum NormalsFrame {
    /// The view's camera axes, OpenCV's: x right, y down, z forward (a normal facing the
    /// camera has z < 0).
    #[default]
    Camera,
    /// World axes: right-handed, +z up.
    World,
}

/// Points the `points` output draws by default.
pub const DEFAULT_POINTS: u32 = 100_000;

impl DatasetSpec {
    /// Camera views per sample: one per view, two with a stereo rig.
    pub fn cameras_per_sample(&self) -> u32 {
        u32::try_from(self.camera.images(self.views)).unwrap_or(u32::MAX)
    }

    /// Images written per sample: every camera view, clean and augmented, in every frame of a
    /// sequence (saturating at u32::MAX).
    pub fn images_per_sample(&self) -> u32 {
        let frames = self.sequence.as_ref().map_or(1, SequenceSpec::frames);
        let images = u64::from(self.cameras_per_sample())
            * u64::from(self.augment.per_view())
            * u64::from(frames);
        u32::try_from(images).unwrap_or(u32::MAX)
    }
}

/// Which outputs are written (per view, or per sample for meshes and points): every output
/// shmgen knows, by name, with whether this dataset writes it.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(transparent)]
pub struct Outputs(BTreeMap<String, bool>);

impl Outputs {
    /// Of the outputs named in `known`, those in `chosen` are on.
    pub fn new(known: &[&str], chosen: &[&str]) -> Self {
        Outputs(
            known
                .iter()
                .map(|name| (name.to_string(), chosen.contains(name)))
                .collect(),
        )
    }

    /// Whether the output called `name` is written.
    pub fn wants(&self, name: &str) -> bool {
        self.0.get(name).copied().unwrap_or(false)
    }

    /// The names of the outputs written, in alphabetical order.
    pub fn chosen(&self) -> impl Iterator<Item = &str> {
        self.0
            .iter()
            .filter(|(_, on)| **on)
            .map(|(k, _)| k.as_str())
    }
}

/// A structure in a scene.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Structure {
    /// A straight beam, deformed by beam theory.
    Beam(BeamSpec),
    /// An assembly of placed primitives (silos, frames, imported meshes), optionally bent or
    /// shell-deformed shape by shape.
    Assembly(AssemblySpec),
    /// Members analysed together (a frame, a truss, a continuous girder), each drawn deformed.
    Frame(FrameSpec),
}

impl Structure {
    /// The material the structure is drawn in.
    pub fn material(&self) -> &crate::materials::Material {
        match self {
            Structure::Beam(b) => &b.material,
            Structure::Assembly(a) => &a.material,
            Structure::Frame(f) => &f.material,
        }
    }

    /// Where the recipe declared what building this structure depends on, if known.
    pub fn declared_at(&self) -> Option<&SourceSite> {
        match self {
            Structure::Beam(b) => b.declared_at.as_ref(),
            Structure::Assembly(a) => a.declared_at.as_ref(),
            Structure::Frame(f) => f.declared_at.as_ref(),
        }
    }
}

/// One sample: the structures in the scene, with their loads (not yet applied).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SceneSpec {
    /// The structures of the sample, in the order the recipe returned them.
    pub structures: Vec<Structure>,
}
