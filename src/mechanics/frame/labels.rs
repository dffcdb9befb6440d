//! The labels of an analysed frame, as written next to each sample: what an engineer checks by
//! hand (node displacements, reactions, member end forces, peak stress and utilisation).

use super::{FrameSolution, MemberResult, NodeResult, Reaction};
use serde::Serialize;

/// What the analysis of a frame found.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FrameLabels {
    /// "linear_static": first-order elastic analysis by the direct stiffness method;
    /// "p_delta": second order, equilibrium in the displaced geometry.
    pub analysis: &'static str,
    /// Each node's displacement and rotation, world axes, in the order of `model.nodes`.
    pub nodes: Vec<NodeResult>,
    /// Each supported node's reaction, world axes.
    pub reactions: Vec<Reaction>,
    /// Each member's end forces (local axes), peak moments, peak stress and utilisation, in the
    /// order of `model.members`.
    pub members: Vec<MemberResult>,
    /// The largest node translation, metres.
    pub max_displacement: f64,
    /// The node where it occurs.
    pub max_displacement_node: usize,
    /// The largest member utilisation (peak stress / f_y).
    pub max_utilisation: f64,
    /// The member where it occurs.
    pub max_utilisation_member: usize,
    /// Whether every member stays elastic (utilisation at most 1). Buckling is not checked.
    pub physically_plausible: bool,
}

impl FrameLabels {
    /// The labels of an analysis.
    pub fn new(solution: &FrameSolution) -> FrameLabels {
        let length = |n: &NodeResult| n.displacement.iter().map(|d| d * d).sum::<f64>().sqrt();
        let (max_displacement_node, max_displacement) = argmax(solution.nodes.iter().map(length));
        let (max_utilisation_member, max_utilisation) =
            argmax(solution.members.iter().map(|m| m.utilisation));
        FrameLabels {
            analysis: if solution.second_order {
                "p_delta"
            } else {
                "linear_static"
            },
            nodes: solution.nodes.clone(),
            reactions: solution.reactions.clone(),
            members: solution.members.clone(),
            max_displacement,
            max_displacement_node,
            max_utilisation,
            max_utilisation_member,
            physically_plausible: max_utilisation <= 1.0,
        }
    }
}

/// Index and value of the largest of `values` (the first on ties; 0 and 0 when empty).
fn argmax(values: impl Iterator<Item = f64>) -> (usize, f64) {
    values.enumerate().fold(
        (0, 0.0),
        |best, (i, v)| if v > best.1 { (i, v) } else { best },
    )
}
