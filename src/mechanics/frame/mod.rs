//! Structures analysed as a whole: space frames and trusses by the direct stiffness method.
//!
//! Owns: the structural model (nodes, members with sections, material, releases and loads,
//! supports, nodal loads, self-weight), its linear static analysis in 3D with 6 DOF a node
//! (Euler–Bernoulli or Timoshenko members, releases by static condensation, fixed-end forces
//! from the beam module's member solution), the choice of dense or sparse Cholesky, the refusal
//! of a mechanism with the free DOFs named, and the results: node displacements, reactions,
//! member end forces, the deformed shape inside every member and its peak moment, stress and
//! utilisation; and the natural modes of the whole structure (member and nodal masses) with
//! vibration snapshots drawn from them, and the response in time to loads moving along a lane
//! of members by modal superposition. Must not touch: meshes, Rhai, cameras or files.
//!
//! Conventions (docs/frames.md): world frame, +Z up, metres, newtons. A member's local x runs
//! from its start node to its end node; local z is the section's height direction (the beam
//! module's bending plane), the component of world +Z normal to x (world +X for a vertical
//! member), turned by the member's `roll` about x; y = z × x. End forces are the forces the
//! nodes exert on the member, in local axes, [N, Vy, Vz, T, My, Mz] at the start then the end.

mod dynamics;
#[cfg(test)]
mod dynamics_tests;
mod element;
mod labels;
mod member_damage;
#[cfg(test)]
mod member_damage_tests;
mod modes;
#[cfg(test)]
mod modes_tests;
mod results;
mod section;
mod sensors;
mod solve;
#[cfg(test)]
mod tests;

pub use dynamics::{FrameDynamics, FrameState, Lane};
pub use labels::FrameLabels;
pub use member_damage::{FrameDamage, MemberDamage};
pub use modes::{DENSE_MODES_MAX_DOFS, FrameModeLabel, ModalLabels, NaturalModes};
pub use results::{FrameSolution, MemberResult, NodeResult, Reaction, StrongAxis};
pub use section::{SectionScale, SpaceSection};
pub use sensors::{FrameExcitation, MemberSensor, record_members};
pub use solve::{DENSE_MAX_DOFS, Solver};

use super::damage::DamageRequest;
use super::{Load, STEEL_E, STEEL_FY, STEEL_NU, Section};
use serde::Serialize;
use std::collections::BTreeMap;

/// Density of structural steel, kg/m³ (EN 1991-1-1 Table A.4).
pub const STEEL_DENSITY: f64 = 7850.0;
/// Standard gravity, m/s², for self-weight.
pub const GRAVITY: f64 = 9.80665;

/// Largest change of any displacement between two P-Δ passes, as a fraction of the largest
/// displacement, at which the iteration stops.
pub const P_DELTA_TOLERANCE: f64 = 1e-10;
/// Most P-Δ passes tried.
const P_DELTA_PASSES: usize = 100;

/// Names of the six DOFs of a node, in order: translations then rotations, world axes.
pub const DOF_NAMES: [&str; 6] = ["ux", "uy", "uz", "rx", "ry", "rz"];

/// A structure of nodes joined by members, with its supports and loads.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FrameModel {
    /// Node positions, world coordinates in metres; members and supports refer to them by index.
    pub nodes: Vec<[f64; 3]>,
    /// The members.
    pub members: Vec<Member>,
    /// How nodes are held; a node with no entry is free.
    pub supports: Vec<NodeSupport>,
    /// Forces and moments applied at nodes.
    pub loads: Vec<NodalLoad>,
    /// Whether every member carries its own weight (ρ g A per metre, world −Z).
    pub self_weight: bool,
    /// A plane the structure is analysed in: the three DOFs that leave it are held at every
    /// node (a plane frame or truss). Absent: a space structure.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plane: Option<Plane>,
    /// Second-order (P-Δ) analysis: equilibrium in the displaced geometry through the
    /// members' geometric stiffness, iterated on their axial forces.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub second_order: bool,
    /// Damage asked for on members, by member index: placed exactly, cracked by the
    /// mechanics (reinforced concrete) or corroded by exposure (`damage`, docs/damage.md).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub damage: BTreeMap<usize, DamageRequest>,
    /// Masses added at nodes (equipment, a deck's share carried by the node), for the natural
    /// modes; the members' own mass is ρ A per metre.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub masses: Vec<NodalMass>,
    /// How the members' mass is spread over their DOFs for the natural modes.
    #[serde(default, skip_serializing_if = "MassMatrix::is_consistent")]
    pub mass_matrix: MassMatrix,
    /// A snapshot of free vibration instead of static loads: (mode number from 1, amplitude in
    /// metres). The drawn shape is Σ A_n φ_n, each natural mode φ_n scaled so the largest
    /// translation of any point of the members' axes is 1.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub vibration: Vec<(u32, f64)>,
}

/// A mass added at a node: the same `mass` in each translation and a rotary inertia about
/// each world axis.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct NodalMass {
    /// The node carrying it.
    pub node: usize,
    /// Mass, kg.
    pub mass: f64,
    /// Rotary inertia about world x, y, z through the node, kg·m².
    pub inertia: [f64; 3],
}

/// How a member's mass is spread over its end DOFs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MassMatrix {
    /// The consistent matrix of the member's own displacement fields (linear along the axis
    /// and in twist, Hermite cubics in bending): frequencies converge from above as members
    /// are subdivided.
    #[default]
    Consistent,
    /// Half the member's mass at each end's translations (and half its rotary inertia about
    /// the axis on its twist); no rotary inertia in bending: frequencies converge from below.
    Lumped,
}

impl MassMatrix {
    /// Whether this is the default, consistent matrix (left out of the scene JSON).
    pub fn is_consistent(&self) -> bool {
        *self == MassMatrix::Consistent
    }
}

/// A coordinate plane a plane structure lies in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Plane {
    /// The x–z plane: uy, rx and rz are held.
    Xz,
    /// The y–z plane: ux, ry and rz are held.
    Yz,
    /// The x–y plane: uz, rx and ry are held.
    Xy,
}

impl Plane {
    /// The DOFs (0–5) a structure in this plane cannot use.
    pub fn held(self) -> [usize; 3] {
        match self {
            Plane::Xz => [1, 3, 5],
            Plane::Yz => [0, 4, 5],
            Plane::Xy => [2, 3, 4],
        }
    }
}

/// Which beam theory a member follows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MemberTheory {
    /// Sections stay normal to the axis: no shear deformation (the textbook frame formulas).
    #[default]
    EulerBernoulli,
    /// Adds shear deformation through the shear areas (exact for prismatic members).
    Timoshenko,
}

/// Which end moments a member does not take from a node: a hinge at that end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, schemars::JsonSchema)]
pub struct Release {
    /// Torsion (moment about local x) released.
    pub torsion: bool,
    /// Moment about local y (bending in the x–z plane, the strong axis) released.
    pub moment_y: bool,
    /// Moment about local z (bending in the x–y plane) released.
    pub moment_z: bool,
}

impl Release {
    /// A pin: both bending moments released, torsion kept.
    pub const PIN: Release = Release {
        torsion: false,
        moment_y: true,
        moment_z: true,
    };
    /// Every moment released.
    pub const ALL: Release = Release {
        torsion: true,
        moment_y: true,
        moment_z: true,
    };

    /// Released flags of the local rotational DOFs (rx, ry, rz).
    pub fn flags(self) -> [bool; 3] {
        [self.torsion, self.moment_y, self.moment_z]
    }
}

/// A straight prismatic member between two nodes.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Member {
    /// Index of the start node (local x = 0).
    pub start: usize,
    /// Index of the end node (local x = L).
    pub end: usize,
    /// Cross-section (the beam module's shapes).
    pub section: Section,
    /// Young's modulus E, Pa.
    pub elastic_modulus: f64,
    /// Poisson's ratio ν; G = E / (2 (1 + ν)).
    pub poisson: f64,
    /// Yield strength f_y, Pa, for the utilisation.
    pub yield_strength: f64,
    /// Density ρ, kg/m³, for self-weight.
    pub density: f64,
    /// Stiffness kept by a damaged member: E is multiplied by it (1 = intact).
    pub stiffness_factor: f64,
    /// What its damage leaves of its section's stiffness (set by the damaged analysis,
    /// `FrameModel::solve_damaged`; 1 = sound). Not part of the recipe's description.
    #[serde(skip)]
    pub section_scale: SectionScale,
    /// Beam theory of the member.
    pub theory: MemberTheory,
    /// Releases at the start and at the end.
    pub releases: [Release; 2],
    /// Turn of the section about the member axis, radians, from the default orientation.
    pub roll: f64,
    /// Loads along the member.
    pub loads: Vec<MemberLoad>,
    /// The name of the part the member is drawn as (for segmentation), e.g. "column".
    pub part: String,
}

impl Member {
    /// A rigidly connected steel member from node `start` to node `end` with `section`.
    pub fn new(start: usize, end: usize, section: Section) -> Member {
        Member {
            start,
            end,
            section,
            elastic_modulus: STEEL_E,
            poisson: STEEL_NU,
            yield_strength: STEEL_FY,
            density: STEEL_DENSITY,
            stiffness_factor: 1.0,
            section_scale: SectionScale::ONE,
            theory: MemberTheory::EulerBernoulli,
            releases: [Release::default(); 2],
            roll: 0.0,
            loads: Vec::new(),
            part: "member".into(),
        }
    }

    /// Pinned at both ends with torsion released at the end: an axial-force member (a truss
    /// bar). Its loads along it still bend it between its pins.
    pub fn bar(start: usize, end: usize, section: Section) -> Member {
        Member {
            releases: [Release::PIN, Release::ALL],
            ..Member::new(start, end, section)
        }
    }
}

/// Which axes a load's direction is given in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Axes {
    /// World axes.
    #[default]
    Global,
    /// The member's local axes (x along it, z along the section height).
    Local,
}

/// A load along a member: one of the beam module's kinds, acting along `direction`.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct MemberLoad {
    /// Kind, position and magnitude, as for a beam; positions are distances from the start
    /// node. For `end_moments` the magnitudes are moments about `direction` at each end.
    pub load: Load,
    /// Unit vector the force (or moment vector) acts along; magnitudes are multiplied by it.
    pub direction: [f64; 3],
    /// Whether `direction` is in world or member axes.
    pub axes: Axes,
}

/// How a node is held: which of its six DOFs are fixed, and springs on the others.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct NodeSupport {
    /// The node held.
    pub node: usize,
    /// The kind named in the recipe ("fixed", "pinned", "roller", "spring", ...).
    pub kind: String,
    /// Fixed DOFs, in the order of [`DOF_NAMES`].
    pub fixed: [bool; 6],
    /// Spring stiffness on each DOF (N/m for translations, N·m/rad for rotations); 0 = none.
    pub springs: [f64; 6],
}

impl NodeSupport {
    /// A support of `node` fixing `fixed`.
    pub fn new(node: usize, kind: &str, fixed: [bool; 6]) -> NodeSupport {
        NodeSupport {
            node,
            kind: kind.into(),
            fixed,
            springs: [0.0; 6],
        }
    }

    /// A clamp: every DOF fixed.
    pub fn fixed(node: usize) -> NodeSupport {
        NodeSupport::new(node, "fixed", [true; 6])
    }

    /// A pin: translations fixed, rotations free.
    pub fn pinned(node: usize) -> NodeSupport {
        NodeSupport::new(node, "pinned", [true, true, true, false, false, false])
    }

    /// A roller: only the vertical translation (uz) fixed.
    pub fn roller(node: usize) -> NodeSupport {
        NodeSupport::new(node, "roller", [false, false, true, false, false, false])
    }
}

/// A force and a moment applied at a node, world axes.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct NodalLoad {
    /// The node loaded.
    pub node: usize,
    /// Force, N.
    pub force: [f64; 3],
    /// Moment, N·m (right-hand rule).
    pub moment: [f64; 3],
}

impl FrameModel {
    /// A model with nothing in it.
    pub fn new() -> FrameModel {
        FrameModel {
            nodes: Vec::new(),
            members: Vec::new(),
            supports: Vec::new(),
            loads: Vec::new(),
            self_weight: false,
            plane: None,
            second_order: false,
            damage: BTreeMap::new(),
            masses: Vec::new(),
            mass_matrix: MassMatrix::Consistent,
            vibration: Vec::new(),
        }
    }

    /// Checks indices, lengths, sections, materials and loads; the message names the member or
    /// node and the value at fault.
    pub fn validate(&self) -> Result<(), String> {
        if self.members.is_empty() {
            return Err("the frame has no members".into());
        }
        for (n, p) in self.nodes.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(format!(
                    "node {n} lies at {p:?}: coordinates must be finite"
                ));
            }
        }
        let node = |what: &str, i: usize| {
            if i < self.nodes.len() {
                Ok(())
            } else {
                Err(format!(
                    "{what} refers to node {i}, but the frame has {} nodes",
                    self.nodes.len()
                ))
            }
        };
        for (m, member) in self.members.iter().enumerate() {
            let what = format!("member {m}");
            node(&what, member.start)?;
            node(&what, member.end)?;
            element::validate(self, member).map_err(|e| format!("{what}: {e}"))?;
        }
        for s in &self.supports {
            node("a support", s.node)?;
            if let Some(k) = s.springs.iter().find(|k| !(**k >= 0.0 && k.is_finite())) {
                return Err(format!(
                    "the support of node {}: spring stiffness {k} must be finite and not negative",
                    s.node
                ));
            }
        }
        for m in &self.masses {
            node("a nodal mass", m.node)?;
            if !m
                .inertia
                .iter()
                .chain([&m.mass])
                .all(|x| *x >= 0.0 && x.is_finite())
            {
                return Err(format!(
                    "the mass on node {}: mass {} kg and inertia {:?} kg·m² must be finite and not negative",
                    m.node, m.mass, m.inertia
                ));
            }
        }
        for l in &self.loads {
            node("a nodal load", l.node)?;
            if !l.force.iter().chain(&l.moment).all(|x| x.is_finite()) {
                return Err(format!(
                    "the load on node {}: values must be finite",
                    l.node
                ));
            }
        }
        Ok(())
    }

    /// Linear static analysis (`Solver::Auto` chooses dense or sparse by size).
    pub fn solve(&self) -> Result<FrameSolution, String> {
        self.solve_with(Solver::Auto)
    }

    /// Linear static analysis with the given linear solver.
    pub fn solve_with(&self, solver: Solver) -> Result<FrameSolution, String> {
        self.validate()?;
        if !self.vibration.is_empty() {
            return self.vibration_snapshot();
        }
        let elements = self.elements()?;
        let displacements = solve::displacements(self, &elements, solver)?;
        let first = results::FrameSolution::new(self, elements, displacements);
        if self.second_order {
            return self.p_delta(first, solver);
        }
        Ok(first)
    }

    /// The solution whose nodes have moved by `displacements` ([ux, uy, uz, rx, ry, rz] per
    /// node, from a response in time) under the loads of the model: member fields, end forces
    /// and peaks follow from them as in a static analysis.
    pub fn displaced_by(&self, displacements: Vec<[f64; 6]>) -> Result<FrameSolution, String> {
        self.validate()?;
        if displacements.len() != self.nodes.len() {
            return Err(format!(
                "{} node displacements given for {} nodes",
                displacements.len(),
                self.nodes.len()
            ));
        }
        Ok(results::FrameSolution::new(
            self,
            self.elements()?,
            displacements,
        ))
    }

    /// Iterates the analysis with each member's geometric stiffness for the axial force of the
    /// previous pass until no displacement changes by more than [`P_DELTA_TOLERANCE`] of the
    /// largest; refuses axial loads at or beyond the critical load (the stiffness loses
    /// positive definiteness, or the iteration does not settle).
    fn p_delta(
        &self,
        mut solution: FrameSolution,
        solver: Solver,
    ) -> Result<FrameSolution, String> {
        let largest = |s: &FrameSolution| {
            s.nodes
                .iter()
                .flat_map(|n| n.displacement)
                .fold(0.0f64, |m, d| m.max(d.abs()))
        };
        for _ in 0..P_DELTA_PASSES {
            let elements: Vec<element::Element> = self
                .members
                .iter()
                .zip(&solution.members)
                .map(|(m, r)| {
                    element::Element::new(self, m).map(|e| e.with_axial_force(r.axial_force))
                })
                .collect::<Result<_, _>>()?;
            let displacements = solve::displacements(self, &elements, solver).map_err(|e| {
                format!("second-order analysis: the axial forces reach the critical (buckling) load: {e}")
            })?;
            let next = results::FrameSolution::new(self, elements, displacements);
            let change = solution
                .nodes
                .iter()
                .zip(&next.nodes)
                .flat_map(|(a, b)| {
                    (0..3).map(move |i| (a.displacement[i] - b.displacement[i]).abs())
                })
                .fold(0.0f64, f64::max);
            let settled = change <= P_DELTA_TOLERANCE * largest(&next);
            solution = next;
            if settled {
                solution.second_order = true;
                return Ok(solution);
            }
        }
        Err(format!(
            "second-order analysis did not settle in {P_DELTA_PASSES} passes: the axial forces are at or near the critical (buckling) load"
        ))
    }
}

impl Default for FrameModel {
    fn default() -> Self {
        FrameModel::new()
    }
}

/// A triangular space truss of `panels` panels, 2 m each (two bottom chords, a top chord,
/// diagonals and cross bracing; 9 bars a panel), pinned at one end and on rollers at the
/// other, under its own weight: the model the tests and `benches/frames.rs` size the solvers on.
pub fn space_truss(panels: usize) -> FrameModel {
    let (a, h, b) = (2.0, 2.0, 2.0);
    let mut m = FrameModel::new();
    for i in 0..=panels {
        let x = a * i as f64;
        m.nodes.push([x, 0.0, 0.0]);
        m.nodes.push([x, b, 0.0]);
        m.nodes.push([x + a / 2.0, b / 2.0, h]);
    }
    let tube = Section::CircularHollow {
        diameter: 0.1,
        wall: 0.005,
    };
    let bar = |s: usize, e: usize| Member::bar(s, e, tube.clone());
    for i in 0..=panels {
        let (p, q, t) = (3 * i, 3 * i + 1, 3 * i + 2);
        m.members.push(bar(p, q));
        if i < panels {
            m.members.extend([
                bar(p, p + 3),
                bar(q, q + 3),
                bar(t, t + 3),
                bar(p, t),
                bar(q, t),
                bar(t, p + 3),
                bar(t, q + 3),
                bar(p, q + 3),
            ]);
        }
    }
    m.nodes.truncate(3 * panels + 2);
    m.members
        .retain(|b| b.start < m.nodes.len() && b.end < m.nodes.len());
    let last = 3 * panels;
    m.supports = vec![
        NodeSupport::pinned(0),
        NodeSupport::new(1, "roller", [true, false, true, false, false, false]),
        NodeSupport::new(last, "roller", [false, true, true, false, false, false]),
        NodeSupport::roller(last + 1),
    ];
    m.self_weight = true;
    m
}
