//! The rectangular beam: dimensions, support, load and placement, plus derived labels.

use crate::geometry::{beam_mesh, BeamGeometry, Mesh};
use crate::materials::Material;
use crate::mechanics::{Mapping, PointLoadShape, Support, STEEL_FY};
use glam::{DMat3, DVec3};
use serde::Serialize;

/// A point load given by the deflection it causes: the beam's largest deflection is
/// `deflection` metres (positive downward), the load acting at `position` metres from the
/// axially fixed end (the pin, or the clamp).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PointLoad {
    pub position: f64,
    pub deflection: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BeamSpec {
    pub length: f64,
    pub width: f64,
    pub height: f64,
    /// Equal intervals along the length (the load point and the peak are added as stations).
    pub segments: u32,
    pub support: Support,
    pub load: PointLoad,
    pub mapping: Mapping,
    /// Young's modulus (Pa) used for the derived load and stress labels only.
    pub elastic_modulus: f64,
    pub material: Material,
    /// World position of the centre of the undeformed beam.
    pub centre: [f64; 3],
    /// Rotation about the world z axis (radians); 0 puts the beam axis along +x.
    pub yaw: f64,
}

impl BeamSpec {
    pub fn new(length: f64, width: f64, height: f64) -> Self {
        BeamSpec {
            length,
            width,
            height,
            segments: 32,
            support: Support::SimplySupported,
            load: PointLoad { position: 0.5 * length, deflection: 0.0 },
            mapping: Mapping::default(),
            elastic_modulus: crate::mechanics::STEEL_E,
            material: Material::default(),
            centre: [0.0; 3],
            yaw: 0.0,
        }
    }

    pub fn shape(&self) -> PointLoadShape {
        PointLoadShape::new(self.support, self.length, self.load.position, self.load.deflection)
    }

    pub fn mesh(&self) -> Mesh {
        let shape = self.shape();
        beam_mesh(&BeamGeometry {
            length: self.length,
            width: self.width,
            height: self.height,
            segments: self.segments,
            shape: &shape,
            mapping: self.mapping,
            rotation: DMat3::from_rotation_z(self.yaw),
            centre: DVec3::from_array(self.centre),
        })
    }

    /// Second moment of area of the rectangle about the bending axis (m⁴).
    pub fn second_moment(&self) -> f64 {
        self.width * self.height.powi(3) / 12.0
    }

    pub fn labels(&self) -> BeamLabels {
        let shape = self.shape();
        let loads = shape.labels(self.elastic_modulus * self.second_moment());
        let stress = loads.max_moment.map(|m| m.abs() * 0.5 * self.height / self.second_moment());
        BeamLabels {
            model: "euler_bernoulli_point_load",
            max_deflection: self.load.deflection,
            max_deflection_at: shape.peak_at(),
            load: loads.load,
            max_moment: loads.max_moment,
            max_bending_stress: stress,
            yield_strength: STEEL_FY,
            physically_plausible: stress.is_some_and(|s| s <= STEEL_FY),
        }
    }
}

/// Derived labels written next to each sample. `load`, `max_moment` and `max_bending_stress`
/// are null when the load sits on a support (no finite load gives a deflection there).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BeamLabels {
    pub model: &'static str,
    pub max_deflection: f64,
    pub max_deflection_at: f64,
    pub load: Option<f64>,
    pub max_moment: Option<f64>,
    pub max_bending_stress: Option<f64>,
    pub yield_strength: f64,
    /// Whether an elastic S355 steel beam of this section could take the load; otherwise the
    /// deflection is a visual exaggeration.
    pub physically_plausible: bool,
}
