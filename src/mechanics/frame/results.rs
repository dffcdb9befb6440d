//! What an analysed frame gives: node displacements, support reactions, member end forces,
//! each member's deformed axis and section rotation anywhere along it, and its peak moments,
//! stress and utilisation.
//!
//! Inside a member the field is exact for the theory: the clamped–clamped solution of its own
//! loads (the beam module's `LinearBeam`) plus the field its end displacements make in an
//! unloaded member (cubic for Euler–Bernoulli, with the Timoshenko shear terms otherwise; the
//! beam-column's field for an Euler–Bernoulli member carrying an axial force under P-Δ).

use super::element::{Element, Vec12};
use super::{FrameModel, NodeSupport};
use glam::DVec3;
use serde::Serialize;

/// Stations a member's internal forces are sampled at for its peaks, besides its ends and
/// the positions of its loads.
const PEAK_STATIONS: usize = 64;

/// The results of a linear analysis.
#[derive(Clone, Debug)]
pub struct FrameSolution {
    /// Per node.
    pub nodes: Vec<NodeResult>,
    /// Per supported node.
    pub reactions: Vec<Reaction>,
    /// Per member.
    pub members: Vec<MemberResult>,
    /// Whether the geometric stiffness of the axial forces was included (P-Δ).
    pub second_order: bool,
    /// For a vibration snapshot: its modes and the structure's lowest frequencies.
    pub modal: Option<super::ModalLabels>,
    elements: Vec<Element>,
    /// Local end displacements of every member (released rotations recovered).
    local: Vec<Vec12>,
}

/// How a node moved.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct NodeResult {
    /// Translation, world axes, metres.
    pub displacement: [f64; 3],
    /// Rotation vector, world axes, radians (0 where no member end resists it: a node of
    /// pinned bars).
    pub rotation: [f64; 3],
}

/// What a support gives back.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Reaction {
    /// The supported node.
    pub node: usize,
    /// Force of the support on the structure, world axes, N.
    pub force: [f64; 3],
    /// Moment of the support on the structure, world axes, N·m.
    pub moment: [f64; 3],
}

/// The forces in a member and how hard it works.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct MemberResult {
    /// Forces of the nodes on the member, local axes: [N, Vy, Vz, T, My, Mz] at the start,
    /// then at the end (N, N·m).
    pub end_forces: [f64; 12],
    /// Axial force at the start, N, tension positive.
    pub axial_force: f64,
    /// Largest |bending moment| about local y (the strong axis) along the member, N·m.
    pub peak_moment_y: f64,
    /// Largest |bending moment| about local z along the member, N·m.
    pub peak_moment_z: f64,
    /// Largest normal stress |N|/A + |My| c_z/I_y + |Mz| c_y/I_z along the member, Pa.
    pub peak_stress: f64,
    /// `peak_stress` / f_y.
    pub utilisation: f64,
}

/// Internal forces at a section, local axes, sign as a beam: N tension positive; moments as
/// the beam module's sagging-positive M of each plane.
#[derive(Clone, Copy, Debug, Default)]
struct Internal {
    axial: f64,
    /// About local y: bending in the x–z plane.
    about_y: f64,
    /// About local z: bending in the x–y plane.
    about_z: f64,
}

impl FrameSolution {
    pub(super) fn new(
        model: &FrameModel,
        elements: Vec<Element>,
        displacements: Vec<[f64; 6]>,
    ) -> FrameSolution {
        let nodes = displacements
            .iter()
            .map(|d| NodeResult {
                displacement: [d[0], d[1], d[2]],
                rotation: [d[3], d[4], d[5]],
            })
            .collect();
        let local: Vec<Vec12> = elements
            .iter()
            .zip(&model.members)
            .map(|(el, m)| el.local_displacements(&displacements[m.start], &displacements[m.end]))
            .collect();
        let members = elements
            .iter()
            .zip(&model.members)
            .zip(&local)
            .map(|((el, m), d)| member_result(el, m.yield_strength, d))
            .collect::<Vec<_>>();
        let reactions = reactions(model, &elements, &members);
        FrameSolution {
            nodes,
            reactions,
            members,
            second_order: false,
            modal: None,
            elements,
            local,
        }
    }

    /// Length of member `m`, metres.
    pub fn member_length(&self, m: usize) -> f64 {
        self.elements[m].length
    }

    /// Rows: member `m`'s local x, y, z axes in world coordinates.
    pub fn member_axes(&self, m: usize) -> glam::DMat3 {
        self.elements[m].axes
    }

    /// Positions along member `m` where its loads put kinks into its shape.
    pub fn member_kinks(&self, m: usize) -> &[f64] {
        &self.elements[m].kinks
    }

    /// Member `m` at distance `x` from its start: the axis point's displacement and the
    /// section's rotation vector, world axes (metres, radians).
    pub fn member_at(&self, m: usize, x: f64) -> (DVec3, DVec3) {
        let (u, r) = local_field(&self.elements[m], &self.local[m], x);
        let to_world = self.elements[m].axes.transpose();
        (to_world * u, to_world * r)
    }

    /// Member `m` at distance `x` from its start, in its local x–z plane (the strong axis):
    /// the section's rotation about local y (dv/dx of the deflection v along −z), the
    /// sagging-positive bending moment about local y (N·m), its flexural rigidity E·I_y and
    /// the distance of its extreme fibre from the neutral axis along z.
    pub fn strong_axis_at(&self, m: usize, x: f64) -> StrongAxis {
        let el = &self.elements[m];
        let d = &self.local[m];
        let (_, rotation) = local_field(el, d, x);
        let ends = el.k_full * d + el.fixed_full;
        let homogeneous = el.k_full * d;
        StrongAxis {
            rotation: rotation.y,
            moment: internal(el, &homogeneous, ends[0], x).about_y,
            rigidity: el.e * el.props.i_y,
            extreme_fibre: el.props.fibre_z,
        }
    }
}

/// A member's section in its strong plane of bending (`FrameSolution::strong_axis_at`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrongAxis {
    /// Rotation about local y, rad, positive where the deflection along −z grows with x.
    pub rotation: f64,
    /// Bending moment about local y, N·m, sagging positive (stretching the −z face).
    pub moment: f64,
    /// E·I_y, N·m².
    pub rigidity: f64,
    /// Distance of the extreme fibre along z from the neutral axis, m.
    pub extreme_fibre: f64,
}

/// Displacement and section rotation of a member at `x`, local axes.
fn local_field(el: &Element, d: &Vec12, x: f64) -> (DVec3, DVec3) {
    let l = el.length;
    let xi = (x / l).clamp(0.0, 1.0);
    let axial =
        d[0] * (1.0 - xi) + d[6] * xi + axial_particular(el, xi * l) / (el.e * el.props.area);
    let twist = d[3] * (1.0 - xi) + d[9] * xi;
    // x–y plane: v = y, θz = section rotation (counter-clockwise, x toward y).
    let ei_z = el.e * el.props.i_z;
    let (v, theta_z) = homogeneous(el, ei_z, xi, el.phi_y, [d[1], d[5], d[7], d[11]]);
    let py = el.beam_y.at(xi * l);
    // x–z plane: w = z, θy = −(rotation in the w sense).
    let ei_y = el.e * el.props.i_y;
    let (w, rot_w) = homogeneous(el, ei_y, xi, el.phi_z, [d[2], -d[4], d[8], -d[10]]);
    let pz = el.beam_z.at(xi * l);
    (
        DVec3::new(axial, v - py.v / ei_z, w - pz.v / ei_y),
        DVec3::new(
            twist,
            -(rot_w - pz.rotation / ei_y),
            theta_z - py.rotation / ei_z,
        ),
    )
}

/// Deflection and section rotation of a member from its end values [v₀, θ₀, v_L, θ_L] in a
/// plane of bending stiffness `ei`: the cubic of [`cubic`], or, for an Euler–Bernoulli member
/// carrying an axial force in a second-order analysis, the beam-column's exact field of
/// E I v⁗ = N v″ ([`beam_column`]), so the drawn shape inside the member is amplified as the
/// axial force amplifies it (the part of its own span loads stays first order).
fn homogeneous(el: &Element, ei: f64, xi: f64, phi: f64, ends: [f64; 4]) -> (f64, f64) {
    if el.tension == 0.0 || phi != 0.0 {
        return cubic(xi, el.length, phi, ends);
    }
    beam_column(xi, el.length, el.tension / ei, ends)
}

/// The field of E I v⁗ = N v″ (s = N / E I, tension positive) with end values
/// [v₀, θ₀, v_L, θ_L], θ = dv/dx: v = v₀ + θ₀ x + c g₂(x) + d g₃(x), where g₂″ = cos k x
/// (compression, k² = −s) or cosh k x (tension, k² = s), g₂(0) = g₂′(0) = 0, and g₃′ = g₂.
pub(super) fn beam_column(xi: f64, l: f64, s: f64, [v0, t0, v1, t1]: [f64; 4]) -> (f64, f64) {
    let x = xi * l;
    let (g2_l, g2_slope_l, g3_l) = (g2(l, s), g2_slope(l, s), g3(l, s));
    // v(L) = v_L and v′(L) = θ_L: [g₂ g₃; g₂′ g₂] [c d]ᵀ = [v_L − v₀ − θ₀ L, θ_L − θ₀]ᵀ.
    let (r0, r1) = (v1 - v0 - t0 * l, t1 - t0);
    let det = g2_l * g2_l - g3_l * g2_slope_l;
    let c = (r0 * g2_l - g3_l * r1) / det;
    let d = (g2_l * r1 - g2_slope_l * r0) / det;
    (
        v0 + t0 * x + c * g2(x, s) + d * g3(x, s),
        t0 + c * g2_slope(x, s) + d * g2(x, s),
    )
}

/// Where (k x)² is below this, g₂, g₂′ and g₃ are summed from their series (four terms,
/// truncation below 1e-14) instead of closed forms that would cancel.
const SERIES: f64 = 1e-2;

/// (1 − cos k x)/k² in compression, (cosh k x − 1)/k² in tension (s = ∓k²).
fn g2(x: f64, s: f64) -> f64 {
    let y2 = s * x * x;
    if y2.abs() < SERIES {
        return x * x / 2.0 * (1.0 + y2 / 12.0 + y2 * y2 / 360.0 + y2.powi(3) / 20160.0);
    }
    let k = s.abs().sqrt();
    if s < 0.0 {
        (1.0 - (k * x).cos()) / (k * k)
    } else {
        ((k * x).cosh() - 1.0) / (k * k)
    }
}

/// g₂′ = sin(k x)/k in compression, sinh(k x)/k in tension.
fn g2_slope(x: f64, s: f64) -> f64 {
    let y2 = s * x * x;
    if y2.abs() < SERIES {
        return x * (1.0 + y2 / 6.0 + y2 * y2 / 120.0 + y2.powi(3) / 5040.0);
    }
    let k = s.abs().sqrt();
    if s < 0.0 {
        (k * x).sin() / k
    } else {
        (k * x).sinh() / k
    }
}

/// g₃ = ∫ g₂: (k x − sin k x)/k³ in compression, (sinh k x − k x)/k³ in tension.
fn g3(x: f64, s: f64) -> f64 {
    let y2 = s * x * x;
    if y2.abs() < SERIES {
        return x.powi(3) / 6.0 * (1.0 + y2 / 20.0 + y2 * y2 / 840.0 + y2.powi(3) / 60480.0);
    }
    let k = s.abs().sqrt();
    if s < 0.0 {
        (k * x - (k * x).sin()) / k.powi(3)
    } else {
        ((k * x).sinh() - k * x) / k.powi(3)
    }
}

/// Deflection and section rotation of an unloaded member from its end values
/// [v₀, θ₀, v_L, θ_L] (θ = the section's rotation in the sense of dv/dx); Φ = 0 gives the
/// Hermite cubic (Przemieniecki's Timoshenko shape functions otherwise).
fn cubic(xi: f64, l: f64, phi: f64, [v0, t0, v1, t1]: [f64; 4]) -> (f64, f64) {
    let (x2, x3) = (xi * xi, xi.powi(3));
    let s = 1.0 / (1.0 + phi);
    let v = s
        * (v0 * (1.0 - 3.0 * x2 + 2.0 * x3 + phi * (1.0 - xi))
            + t0 * l * (xi - 2.0 * x2 + x3 + 0.5 * phi * (xi - x2))
            + v1 * (3.0 * x2 - 2.0 * x3 + phi * xi)
            + t1 * l * (-x2 + x3 - 0.5 * phi * (xi - x2)));
    let theta = s
        * ((v0 - v1) * 6.0 * (x2 - xi) / l
            + t0 * (1.0 - 4.0 * xi + 3.0 * x2 + phi * (1.0 - xi))
            + t1 * (-2.0 * xi + 3.0 * x2 + phi * xi));
    (v, theta)
}

/// EA times the axial displacement a clamped–clamped bar's own loads make at `x`.
fn axial_particular(el: &Element, x: f64) -> f64 {
    let mut applied = 0.0;
    for &(a, p) in &el.axial_points {
        applied += p * (x - a).max(0.0);
    }
    for &(s, e, q) in &el.axial_udls {
        let covered = (x - s).clamp(0.0, e - s);
        applied += q * (covered * covered / 2.0 + (e - s) * (x - e).max(0.0));
    }
    -el.bar_start * x - applied
}

/// End forces, internal forces along the member, peaks and utilisation.
fn member_result(el: &Element, yield_strength: f64, d: &Vec12) -> MemberResult {
    let f = el.k_full * d + el.fixed_full;
    let homogeneous = el.k_full * d;
    let mut stations: Vec<f64> = (0..=PEAK_STATIONS)
        .map(|i| el.length * i as f64 / PEAK_STATIONS as f64)
        .chain(el.kinks.iter().copied())
        .collect();
    stations.sort_by(f64::total_cmp);
    let (mut my, mut mz, mut stress) = (0.0f64, 0.0f64, 0.0f64);
    for &x in &stations {
        let s = internal(el, &homogeneous, f[0], x);
        let (m_y, m_z) = (s.about_y.abs(), s.about_z.abs());
        my = my.max(m_y);
        mz = mz.max(m_z);
        let p = &el.props;
        stress =
            stress.max(s.axial.abs() / p.area + m_y * p.fibre_z / p.i_y + m_z * p.fibre_y / p.i_z);
    }
    MemberResult {
        end_forces: f.as_slice().try_into().expect("12 end forces"),
        axial_force: -f[0],
        peak_moment_y: my,
        peak_moment_z: mz,
        peak_stress: stress,
        utilisation: stress / yield_strength,
    }
}

/// Internal forces at `x`: the clamped–clamped moments of the loads plus the linear moment of
/// the end forces the end displacements make.
fn internal(el: &Element, homogeneous: &Vec12, start_axial: f64, x: f64) -> Internal {
    let xi = x / el.length;
    let (py, pz) = (el.beam_y.at(x), el.beam_z.at(x));
    // Sagging moments of the homogeneous end forces (signs as in element::fixed_end_forces).
    let about_z = -homogeneous[5] * (1.0 - xi) + homogeneous[11] * xi;
    let about_y = homogeneous[4] * (1.0 - xi) - homogeneous[10] * xi;
    let mut applied = 0.0;
    for &(a, p) in &el.axial_points {
        if x > a {
            applied += p;
        }
    }
    for &(s, e, q) in &el.axial_udls {
        applied += q * (x - s).clamp(0.0, e - s);
    }
    Internal {
        axial: -start_axial - applied,
        about_y: pz.moment + about_y,
        about_z: py.moment + about_z,
    }
}

/// Reactions: at every supported node, what its members and springs take minus the loads
/// applied there (equilibrium of the node).
fn reactions(model: &FrameModel, elements: &[Element], members: &[MemberResult]) -> Vec<Reaction> {
    let mut held: Vec<usize> = model
        .supports
        .iter()
        .map(|s: &NodeSupport| s.node)
        .collect();
    held.sort_unstable();
    held.dedup();
    let mut total = vec![[0.0; 6]; model.nodes.len()];
    for ((el, m), r) in elements.iter().zip(&model.members).zip(members) {
        let f = Vec12::from_row_slice(&r.end_forces);
        let world = el.transformation().transpose() * f;
        for i in 0..6 {
            // The member pushes on the node with −(the node's force on the member).
            total[m.start][i] -= world[i];
            total[m.end][i] -= world[6 + i];
        }
    }
    for l in &model.loads {
        for i in 0..3 {
            total[l.node][i] += l.force[i];
            total[l.node][3 + i] += l.moment[i];
        }
    }
    held.into_iter()
        .map(|node| Reaction {
            node,
            force: [-total[node][0], -total[node][1], -total[node][2]],
            moment: [-total[node][3], -total[node][4], -total[node][5]],
        })
        .collect()
}
