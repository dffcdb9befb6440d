//! Scene descriptions: plain data produced by recipes and consumed by everything downstream.
//!
//! Owns: what a dataset and one of its samples *are* (structures, supports, loads,
//! materials, camera distribution, outputs), with every value resolved and validated, and the
//! derived mechanical labels. Must not touch: Rhai (recipes build these), tracing or files.
//! Everything here serialises into the per-view JSON.

mod assembly;
mod beam;
mod light;

pub use assembly::{AssemblySpec, Bending, BuiltShape, LabelledPattern, ShapeSpec};
pub use beam::{BeamSpec, BuiltBeam, Tessellation};
pub use light::{
    Background, ImageRecord, LightSpec, OUTDOOR_AMBIENT, SkyGradient, SkySpec, SunSpec,
};

use crate::cameras::CameraRig;
use serde::Serialize;

/// Default chord tolerance of every curved surface, beams and primitives alike: this fraction of
/// a pixel at the nearest camera the rig can place.
pub const PIXEL_TOLERANCE: f64 = 0.1;

/// Dataset-wide settings declared by a recipe.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DatasetSpec {
    pub name: String,
    pub seed: u64,
    pub samples: u64,
    pub views: u32,
    pub camera: CameraRig,
    pub outputs: Outputs,
    /// What RGB shows behind the structures; black as in the paper.
    pub background: Background,
    pub light: LightSpec,
    /// Anti-alias RGB where the image changes (silhouettes, creases); labels never are.
    pub antialias: bool,
}

/// Which per-view files are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Outputs {
    pub rgb: bool,
    pub depth: bool,
    /// Per-pixel crack mask (for materials with cracks).
    pub cracks: bool,
    pub mask: bool,
    /// Per-pixel part ids (see the id table in each view's JSON).
    pub parts: bool,
    /// Per-pixel structure (instance) ids.
    pub instances: bool,
}

impl Outputs {
    pub const NAMES: [&'static str; 6] = ["rgb", "depth", "mask", "parts", "instances", "cracks"];
}

/// A structure in a scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Structure {
    Beam(BeamSpec),
    Assembly(AssemblySpec),
}

impl Structure {
    pub fn material(&self) -> &crate::materials::Material {
        match self {
            Structure::Beam(b) => &b.material,
            Structure::Assembly(a) => &a.material,
        }
    }
}

/// One sample: the structures in the scene, already deformed by their loads.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneSpec {
    pub structures: Vec<Structure>,
}
