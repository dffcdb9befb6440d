//! The labels of an analysed frame, as written next to each sample: what an engineer checks by
//! hand (node displacements, reactions, member end forces, peak stress and utilisation).

use super::{FrameSolution, MemberResult, ModalLabels, NodeResult, Reaction};
use serde::Serialize;

/// What the analysis of a frame found.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FrameLabels {
    /// "linear_static": first-order elastic analysis by the direct stiffness method;
    /// "p_delta": second order, equilibrium in the displaced geometry; "vibration_snapshot":
    /// a sum of natural modes (forces and stresses are those that hold that shape);
    /// "modal_response": a frame of a sequence, the response in time to its loads by modal
    /// superposition (forces and stresses are the elastic ones holding that shape).
    pub analysis: &'static str,
    /// Each node's displacement and rotation, world axes, in the order of `model.nodes`.
    pub nodes: Vec<NodeResult>,
    /// Each supported node's reaction, world axes.
    pub reactions: Vec<Reaction>,
    /// Each member's end forces (local axes), peak moments, peak stress and utilisation, in the
    /// order of `model.members`.
    pub members: Vec<MemberResult>,
    /// The largest translation of any point of the members' axes, nodes included, metres: a
    /// continuous girder's nodes sit on supports, and its deflection is inside the spans.
    pub max_displacement: f64,
    /// The member where it occurs.
    pub max_displacement_member: usize,
    /// Where along that member, metres from its start node.
    pub max_displacement_position: f64,
    /// The largest member utilisation (peak stress / f_y).
    pub max_utilisation: f64,
    /// The member where it occurs.
    pub max_utilisation_member: usize,
    /// Whether every member stays elastic (utilisation at most 1). Buckling is not checked.
    pub physically_plausible: bool,
    /// For a vibration snapshot: the modes drawn, the lowest natural frequencies and their
    /// effective masses. Absent for a static analysis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modes: Option<ModalLabels>,
    /// The frame's damage (placed, cracked by the solved moment and shear, corroded by
    /// exposure) and what it left of each damaged member's stiffness; the fields above are the
    /// damaged frame's. Absent for a sound frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damage: Option<super::FrameDamage>,
}

impl FrameLabels {
    /// The labels of an analysis.
    pub fn new(solution: &FrameSolution) -> FrameLabels {
        let (max_displacement_member, max_displacement_position, max_displacement) =
            largest_translation_of(solution);
        let (max_utilisation_member, max_utilisation) =
            argmax(solution.members.iter().map(|m| m.utilisation));
        FrameLabels {
            analysis: if solution.modal.is_some() {
                "vibration_snapshot"
            } else if solution.second_order {
                "p_delta"
            } else {
                "linear_static"
            },
            nodes: solution.nodes.clone(),
            reactions: solution.reactions.clone(),
            members: solution.members.clone(),
            max_displacement,
            max_displacement_member,
            max_displacement_position,
            max_utilisation,
            max_utilisation_member,
            physically_plausible: max_utilisation <= 1.0,
            modes: solution.modal.clone(),
            damage: None,
        }
    }
}

/// The member, position along it (metres from its start) and size of the largest translation
/// of any point of the members' axes.
pub(super) fn largest_translation_of(solution: &FrameSolution) -> (usize, f64, f64) {
    let (member, (position, size)) = argmax_by(
        (0..solution.members.len()).map(|m| largest_translation(solution, m)),
        |&(_, d)| d,
    );
    (member, position, size)
}

/// Index and value of the largest of `values` (the first on ties; 0 and 0 when empty).
fn argmax(values: impl Iterator<Item = f64>) -> (usize, f64) {
    argmax_by(values, |&v| v)
}

/// Index and item of the item of `items` with the largest `key` (the first on ties; 0 and the
/// default when empty or when no key exceeds 0).
fn argmax_by<T: Default>(items: impl Iterator<Item = T>, key: impl Fn(&T) -> f64) -> (usize, T) {
    items
        .enumerate()
        .fold((0, T::default()), |best, (i, item)| {
            if key(&item) > key(&best.1) {
                (i, item)
            } else {
                best
            }
        })
}

/// Stations a member is sampled at before the largest is refined.
const STATIONS: usize = 64;

/// The position along member `m` (metres from its start) with the largest translation, and
/// that translation: the largest of `STATIONS` equal stations, its ends and its load kinks,
/// then refined by golden-section search between the neighbouring stations. The translation
/// is smooth between kinks and has one peak near a station once stations are this fine.
fn largest_translation(solution: &FrameSolution, m: usize) -> (f64, f64) {
    let length = solution.member_length(m);
    let at = |x: f64| solution.member_at(m, x).0.length();
    let step = length / STATIONS as f64;
    let stations = (0..=STATIONS).map(|i| i as f64 * step);
    let candidates = stations.chain(solution.member_kinks(m).iter().copied());
    let (_, best) = argmax_by(candidates.map(|x| (x, at(x))), |&(_, d)| d);
    let refined = golden_section_max(&at, (best.0 - step).max(0.0), (best.0 + step).min(length));
    if refined.1 > best.1 { refined } else { best }
}

/// The maximum of `f` on [a, b] by golden-section search (Kiefer 1953), to a bracket of
/// 10⁻⁹ of the interval: exact for a unimodal `f`, never worse than its end points.
fn golden_section_max(f: &impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> (f64, f64) {
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let tolerance = (b - a) * 1e-9;
    let mut c = b - ratio * (b - a);
    let mut d = a + ratio * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    while b - a > tolerance {
        if fc > fd {
            b = d;
            (d, fd) = (c, fc);
            c = b - ratio * (b - a);
            fc = f(c);
        } else {
            a = c;
            (c, fc) = (d, fd);
            d = a + ratio * (b - a);
            fd = f(d);
        }
    }
    let x = (a + b) / 2.0;
    (x, f(x))
}
