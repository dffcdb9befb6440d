//! How a whole frame moves under loads that change in time: vehicles crossing a lane of
//! members (a bridge deck), hammer blows, ramps and sampled forces, by superposition of the
//! frame's natural modes with modal damping.
//!
//! Owns: the lane (a path over members that loads follow), the modal forces of loads on it,
//! and the frame's state at each output time as an ordinary [`FrameSolution`]. The integration
//! of each modal coordinate is the beam module's (`dynamics::integrate`: exact for forces
//! linear between time nodes), so the two cannot drift apart. Must not touch: meshes, Rhai,
//! cameras, files or random streams.
//!
//! Method (docs/frames.md, "Frames in time"): with M-orthonormal modes φ_n of K φ = ω² M φ,
//! each modal coordinate obeys q̈ + 2ζω q̇ + ω² q = f_n, f_n = φ_nᵀ F(t) = Σ F_i · φ_n(p_i)
//! for point forces F_i at points p_i of the members (the mode's field inside a member is
//! the element's Hermite field, which is what the consistent load vector means). The state
//! is recovered by the mode-acceleration method: the static solution of the loads acting at
//! that instant plus Σ (q_n − f_n/ω_n²) φ_n, so a slowly applied load gives the static
//! solver's answer whatever the number of modes, and the field inside each loaded member
//! keeps its exact static part. Loads the model already carries (self-weight, static member
//! and nodal loads) are a constant part: the structure starts at rest under them.

use super::results::FrameSolution;
use super::{Axes, FrameModel, MemberLoad, NaturalModes, solve};
use crate::mechanics::Load;
use crate::mechanics::dynamics::{Side, Snapshot, TimeLoad, integrate, time_nodes};
use glam::DVec3;

/// The world direction of every time load's force: positive forces act downward.
const DOWN: DVec3 = DVec3::NEG_Z;

/// One member of a lane, where it lies along the lane.
#[derive(Clone, Copy, Debug)]
struct LaneSegment {
    member: usize,
    /// Whether the lane runs from the member's end node to its start node.
    reversed: bool,
    /// Distance along the lane where the member begins, metres.
    begins: f64,
    length: f64,
}

/// A path over members that time loads follow: where each member lies along it.
#[derive(Clone, Debug)]
pub struct Lane {
    segments: Vec<LaneSegment>,
    length: f64,
}

/// A frame ready to respond to time loads on one lane: its modes and the lane resolved.
#[derive(Clone, Debug)]
pub struct FrameDynamics {
    model: FrameModel,
    lane: Lane,
    damping: f64,
    modes: NaturalModes,
    /// Each mode's field inside the members (the model without loads, displaced by φ_n).
    fields: Vec<FrameSolution>,
}

/// The frame at one output time.
#[derive(Clone, Debug)]
pub struct FrameState {
    /// The time, seconds.
    pub time: f64,
    /// Displacements, forces and member fields, as a static analysis gives them.
    pub solution: FrameSolution,
    /// Each node's translational velocity, world axes, m/s.
    pub velocity: Vec<[f64; 3]>,
    /// Each node's translational acceleration, world axes, m/s².
    pub acceleration: Vec<[f64; 3]>,
    /// Each mode's velocity q̇_n, then its acceleration q̈_n (unit modal mass).
    pub modal_rates: Vec<[f64; 2]>,
}

impl FrameModel {
    /// The frame's lowest `modes` modes with modal damping ratio `damping`, for time loads
    /// along `lane`: members in order, each sharing a node with the next (either direction).
    pub fn dynamics(
        &self,
        lane: &[usize],
        modes: usize,
        damping: f64,
    ) -> Result<FrameDynamics, String> {
        self.validate()?;
        if self.second_order || !self.vibration.is_empty() {
            return Err(
                "time loads act on a linear frame: second_order and vibration snapshots are refused with them"
                    .into(),
            );
        }
        if !(damping.is_finite() && (0.0..1.0).contains(&damping)) {
            return Err(format!("damping ratio must be in [0, 1), got {damping}"));
        }
        if modes == 0 {
            return Err("at least one mode is needed".into());
        }
        let lane = Lane::new(self, lane)?;
        let modes = self.natural_modes(modes)?;
        let unloaded = self.without_loads();
        let elements = unloaded.elements()?;
        let fields = modes
            .shapes
            .iter()
            .map(|shape| FrameSolution::new(&unloaded, elements.clone(), shape.clone()))
            .collect();
        Ok(FrameDynamics {
            model: self.clone(),
            lane,
            damping,
            modes,
            fields,
        })
    }

    /// The same structure with no loads at all: the members' fields of pure end motion.
    fn without_loads(&self) -> FrameModel {
        let mut m = self.clone();
        m.loads.clear();
        m.self_weight = false;
        for member in &mut m.members {
            member.loads.clear();
        }
        m
    }
}

impl Lane {
    /// The lane over `members` of `model`, in order; each must share a node with the next.
    pub fn new(model: &FrameModel, lane: &[usize]) -> Result<Lane, String> {
        let this = model;
        let Some(&first) = lane.first() else {
            return Err("a lane needs at least one member".into());
        };
        if let Some(&bad) = lane.iter().find(|&&m| m >= this.members.len()) {
            return Err(format!(
                "lane member {bad} does not exist (the frame has {} members)",
                this.members.len()
            ));
        }
        let ends = |m: usize| (this.members[m].start, this.members[m].end);
        // The lane enters the first member at the node it does not share with the second.
        let joins_next = |node: usize| {
            lane.get(1).is_some_and(|&next| {
                let (a, b) = ends(next);
                node == a || node == b
            })
        };
        let (s0, e0) = ends(first);
        let mut at = if joins_next(s0) && !joins_next(e0) {
            e0
        } else {
            s0
        };
        let mut segments = Vec::with_capacity(lane.len());
        let mut begins = 0.0;
        for (k, &m) in lane.iter().enumerate() {
            let (s, e) = ends(m);
            let reversed = match at {
                node if node == s => false,
                node if node == e => true,
                _ => {
                    return Err(format!(
                        "lane member {m} (position {k} in the lane) does not touch node {at}, where member {} ends",
                        lane[k - 1]
                    ));
                }
            };
            let length =
                DVec3::from_array(this.nodes[s]).distance(DVec3::from_array(this.nodes[e]));
            segments.push(LaneSegment {
                member: m,
                reversed,
                begins,
                length,
            });
            begins += length;
            at = if reversed { s } else { e };
        }
        Ok(Lane {
            segments,
            length: begins,
        })
    }

    /// Length of the lane, metres.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Point forces (lane position, N downward) of `loads` acting on that side of t.
    fn point_forces(&self, loads: &[TimeLoad], t: f64, side: Side) -> Vec<(f64, f64)> {
        let mut forces = Vec::new();
        for load in loads {
            load.forces_at(t, side, self.length, &mut forces);
        }
        forces
    }

    /// The member and the distance from its start node of lane position `s`.
    fn on_member(&self, s: f64) -> (usize, f64) {
        let k = self
            .segments
            .partition_point(|seg| seg.begins <= s)
            .saturating_sub(1);
        let seg = &self.segments[k];
        let along = (s - seg.begins).clamp(0.0, seg.length);
        let x = if seg.reversed {
            seg.length - along
        } else {
            along
        };
        (seg.member, x)
    }

    /// `model` with `loads` acting just after `t` added as member point loads.
    pub fn loaded(&self, model: &FrameModel, loads: &[TimeLoad], t: f64) -> FrameModel {
        let mut model = model.clone();
        for (s, force) in self.point_forces(loads, t, Side::After) {
            let (m, at) = self.on_member(s);
            model.members[m].loads.push(MemberLoad {
                load: Load::Point { at, force },
                direction: DOWN.to_array(),
                axes: Axes::Global,
            });
        }
        model
    }
}

impl FrameDynamics {
    /// Length of the lane, metres: positions of time loads run from 0 to this.
    pub fn lane_length(&self) -> f64 {
        self.lane.length
    }

    /// Natural frequencies of the kept modes, Hz.
    pub fn frequencies(&self) -> Vec<f64> {
        self.modes
            .omega
            .iter()
            .map(|w| w / std::f64::consts::TAU)
            .collect()
    }

    /// The frame at each of `times` (ascending, none before `from`), at rest under its own
    /// loads at `from`; `per_period` steps per period of the fastest modal force variation
    /// bound the only error, the forces' linear interpolation (about (π/per_period)²/2).
    pub fn respond(
        &self,
        loads: &[TimeLoad],
        from: f64,
        times: &[f64],
        per_period: u32,
    ) -> Result<Vec<FrameState>, String> {
        for load in loads {
            load.check(self.lane.length)
                .map_err(|e| format!("time load on the lane: {e}"))?;
        }
        let nodes = time_nodes(
            self.corners(loads),
            self.forcing(loads),
            from,
            times,
            per_period,
        );
        let snapshots = integrate(
            &self.modes.omega,
            self.damping,
            from,
            &nodes,
            times,
            |t, side| self.modal_forces(loads, t, side),
        );
        snapshots
            .iter()
            .map(|snap| self.state(loads, snap))
            .collect()
    }

    /// Force corners of every load, plus the instants an axle passes a joint of the lane,
    /// where the modal forces have kinks.
    fn corners(&self, loads: &[TimeLoad]) -> Vec<f64> {
        let mut corners = Vec::new();
        for load in loads {
            load.corners(self.lane.length, &mut corners);
            if let TimeLoad::Vehicle {
                axles,
                speed,
                enters,
            } = load
            {
                for axle in axles {
                    let on = enters + axle.behind / speed;
                    corners.extend(self.lane.segments.iter().map(|s| on + s.begins / speed));
                }
            }
        }
        corners
    }

    /// The fastest variation of any modal force, rad/s: an axle crosses the shortest lane
    /// member, where the modes' cubic fields bend most, in about that member's length.
    fn forcing(&self, loads: &[TimeLoad]) -> f64 {
        let shortest = self
            .lane
            .segments
            .iter()
            .map(|s| s.length)
            .fold(f64::MAX, f64::min);
        let modes = self.modes.omega.len();
        loads
            .iter()
            .map(|l| match l {
                TimeLoad::Vehicle { speed, .. } => (std::f64::consts::PI * speed / shortest)
                    .max(l.variation(self.lane.length, modes)),
                _ => l.variation(self.lane.length, modes),
            })
            .fold(0.0, f64::max)
    }

    /// f_n = Σ F · φ_n(p) for every mode (the modes are M-orthonormal: unit modal mass).
    fn modal_forces(&self, loads: &[TimeLoad], t: f64, side: Side) -> Vec<f64> {
        let forces = self.lane.point_forces(loads, t, side);
        self.fields
            .iter()
            .map(|field| {
                forces
                    .iter()
                    .map(|&(s, f)| {
                        let (m, x) = self.lane.on_member(s);
                        f * field.member_at(m, x).0.dot(DOWN)
                    })
                    .sum()
            })
            .collect()
    }

    /// The frame at one snapshot, by the mode-acceleration method.
    fn state(&self, loads: &[TimeLoad], snap: &Snapshot) -> Result<FrameState, String> {
        let model = self.lane.loaded(&self.model, loads, snap.time);
        let elements = model.elements()?;
        let mut displacements = solve::displacements(&model, &elements, super::Solver::Auto)?;
        let mut velocity = vec![[0.0; 3]; model.nodes.len()];
        let mut acceleration = vec![[0.0; 3]; model.nodes.len()];
        let mut modal_rates = Vec::with_capacity(self.modes.omega.len());
        let modes = self.modes.omega.iter().zip(&self.modes.shapes);
        for (((&omega, shape), [q, v]), &f) in modes.zip(&snap.state).zip(&snap.force) {
            let w2 = omega * omega;
            let dynamic = q - f / w2;
            let accel = f - 2.0 * self.damping * omega * v - w2 * q;
            modal_rates.push([*v, accel]);
            for (node, phi) in shape.iter().enumerate() {
                for (d, p) in displacements[node].iter_mut().zip(phi) {
                    *d += dynamic * p;
                }
                for i in 0..3 {
                    velocity[node][i] += v * phi[i];
                    acceleration[node][i] += accel * phi[i];
                }
            }
        }
        Ok(FrameState {
            time: snap.time,
            solution: FrameSolution::new(&model, elements, displacements),
            velocity,
            acceleration,
            modal_rates,
        })
    }

    /// The velocity (`rate` 0) or acceleration (`rate` 1) of the point at `x` along member
    /// `m` in `state`, world axes: Σ q̇_n φ_n(p) or Σ q̈_n φ_n(p), with each mode's field
    /// inside the member, so a point between nodes is as exact as a node.
    pub fn rate_at(&self, state: &FrameState, rate: usize, m: usize, x: f64) -> DVec3 {
        self.fields
            .iter()
            .zip(&state.modal_rates)
            .map(|(field, rates)| rates[rate] * field.member_at(m, x).0)
            .sum()
    }
}
