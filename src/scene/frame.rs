//! A structure analysed as a whole (a frame, a truss, a continuous girder) as a recipe declares
//! it: the structural model, its material and how finely it is meshed. Analysing and meshing
//! it is the build stage's work.

use super::{BeamMotion, PIXEL_TOLERANCE, SensorSpec, SourceSite, Tolerance};
use crate::materials::Material;
use crate::mechanics::frame::FrameModel;
use serde::Serialize;

/// A frame or truss: members between nodes, analysed together by the direct stiffness method.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FrameSpec {
    /// The structure's name (in the instance table and in messages).
    pub name: String,
    /// Nodes, members, supports and loads, world coordinates (the frame is built in place).
    pub model: FrameModel,
    /// The drawn displacements are the analysed ones times this (1 = as analysed); the labels
    /// stay physical. Real frames deflect span/300 or less: a scale makes that visible, and the
    /// per-pixel displacement and flow follow the drawn geometry.
    pub display_scale: f64,
    /// The material of every member.
    pub material: Material,
    /// How closely the deformed members are followed.
    pub tessellation: Tolerance,
    /// Members in order that time loads move along (a lane of a deck), each sharing a node
    /// with the next; positions of time loads are distances along it. Empty: no lane.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lane: Vec<usize>,
    /// The forces it carries in time along `lane` and its modal model, in a sequence (its
    /// `density` is unused: each member has its own).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion: Option<BeamMotion>,
    /// Virtual sensors on its members (`.sensor(#{ member, … })`), recorded over the dataset's
    /// sequence.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sensors: Vec<SensorSpec>,
    /// In a frame of a sequence: every node's displacement at the frame's instant, from the
    /// response in time; the members' fields follow from them and the loads acting then.
    #[serde(skip)]
    pub displaced: Option<Vec<[f64; 6]>>,
    /// The recipe call that last changed the model, where errors found when analysing it point.
    #[serde(skip)]
    pub declared_at: Option<SourceSite>,
}

impl FrameSpec {
    /// An empty frame called `name`, in the default material and tessellation.
    pub fn new(name: &str) -> FrameSpec {
        FrameSpec {
            name: name.into(),
            model: FrameModel::new(),
            display_scale: 1.0,
            material: Material::default(),
            tessellation: Tolerance::Pixels(PIXEL_TOLERANCE),
            lane: Vec::new(),
            motion: None,
            sensors: Vec::new(),
            displaced: None,
            declared_at: None,
        }
    }
}
