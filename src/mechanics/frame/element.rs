//! One member as the stiffness method sees it: local axes, the 12 × 12 local stiffness
//! (Euler–Bernoulli or Timoshenko), releases by static condensation, fixed-end forces of its
//! loads from the beam module's clamped–clamped solution, the recovery of the released
//! end rotations, and its mass matrix (consistent or lumped) for the natural modes.

use super::{Axes, FrameModel, MassMatrix, Member, MemberLoad, MemberTheory, SpaceSection};
use crate::mechanics::{LinearBeam, Load, Support};
use glam::{DMat3, DVec3};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

pub(super) type Mat12 = SMatrix<f64, 12, 12>;
pub(super) type Vec12 = SVector<f64, 12>;

/// Condensed stiffness entries below this fraction of the largest are round-off of a released
/// DOF (e.g. the torsion of a bar released at one end) and are set to exactly zero, so a node
/// only such ends meet has no rotational stiffness and its rotation is left out.
const ROUND_OFF: f64 = 1e-12;

/// A member prepared for assembly and for evaluating its results.
#[derive(Clone, Debug)]
pub(super) struct Element {
    /// Rows: the local x, y, z axes in world coordinates.
    pub axes: DMat3,
    pub length: f64,
    pub props: SpaceSection,
    /// E with the damage factor, Pa.
    pub e: f64,
    /// Shear parameters Φ = 12 E I / (G A_s L²) of the x–y and x–z planes (0 for
    /// Euler–Bernoulli).
    pub phi_y: f64,
    pub phi_z: f64,
    /// Full local stiffness (no releases) and fixed-end forces (forces of clamps on the member).
    pub k_full: Mat12,
    pub fixed_full: Vec12,
    /// Local DOFs (0–11) released.
    pub released: [bool; 12],
    /// Condensed stiffness and fixed-end forces: rows and columns of released DOFs are zero.
    pub k: Mat12,
    pub fixed: Vec12,
    /// Clamped–clamped solutions of the span loads bending in the x–y and x–z planes (the beam
    /// module's convention: v downward = local −y or −z).
    pub beam_y: LinearBeam,
    pub beam_z: LinearBeam,
    /// Axial span loads along local x: points (a, P) and uniform (from, to, q).
    pub axial_points: Vec<(f64, f64)>,
    pub axial_udls: Vec<(f64, f64, f64)>,
    /// The axial force a clamp at the start exerts on the member under those loads, N.
    pub bar_start: f64,
    /// Positions of the span loads (where internal forces have kinks).
    pub kinks: Vec<f64>,
    /// The axial force (N, tension positive) whose geometric stiffness the member carries in a
    /// second-order analysis; 0 in a first-order one.
    pub tension: f64,
}

/// Local axes of a member from `a` to `b` turned by `roll`: rows x, y, z.
pub(super) fn local_axes(a: DVec3, b: DVec3, roll: f64) -> DMat3 {
    let x = (b - a).normalize();
    // A member within ~0.06° of vertical takes world X as its reference "up".
    let reference = if x.z.abs() > 1.0 - 1e-6 {
        DVec3::X
    } else {
        DVec3::Z
    };
    let z0 = (reference - reference.dot(x) * x).normalize();
    let y0 = z0.cross(x);
    let (s, c) = roll.sin_cos();
    let z = c * z0 - s * y0;
    let y = z.cross(x);
    DMat3::from_cols(x, y, z).transpose()
}

/// Checks one member's geometry, section, constants and loads.
pub(super) fn validate(model: &FrameModel, m: &Member) -> Result<(), String> {
    let (a, b) = (
        DVec3::from_array(model.nodes[m.start]),
        DVec3::from_array(model.nodes[m.end]),
    );
    let length = a.distance(b);
    if !(length > 1e-9 * (a.length() + b.length()).max(1.0)) {
        return Err(format!(
            "its nodes {} and {} coincide (length {length} m)",
            m.start, m.end
        ));
    }
    m.section.validate()?;
    let positive = |name: &str, x: f64| {
        if x > 0.0 && x.is_finite() {
            Ok(())
        } else {
            Err(format!("{name} = {x} must be positive and finite"))
        }
    };
    positive("elastic modulus", m.elastic_modulus)?;
    positive("yield strength", m.yield_strength)?;
    positive("stiffness factor", m.stiffness_factor)?;
    if !(m.poisson > -1.0 && m.poisson < 0.5) {
        return Err(format!("poisson = {} must lie in (−1, 0.5)", m.poisson));
    }
    if !(m.density >= 0.0 && m.density.is_finite()) {
        return Err(format!(
            "density = {} must be finite and not negative",
            m.density
        ));
    }
    if !m.roll.is_finite() {
        return Err(format!("roll = {} must be finite", m.roll));
    }
    if m.releases[0].torsion && m.releases[1].torsion {
        return Err("torsion is released at both ends: the member would spin freely about its axis (release it at one end at most)".into());
    }
    for l in &m.loads {
        validate_load(l, length)?;
    }
    Ok(())
}

fn validate_load(l: &MemberLoad, length: f64) -> Result<(), String> {
    if !l.load.is_finite() || !l.direction.iter().all(|d| d.is_finite()) {
        return Err(format!("load {:?}: values must be finite", l.load));
    }
    let d = DVec3::from_array(l.direction).length();
    if (d - 1.0).abs() > 1e-9 {
        return Err(format!(
            "load direction {:?} must be a unit vector (length {d})",
            l.direction
        ));
    }
    let on = |x: f64| (-1e-12 * length..=length * (1.0 + 1e-12)).contains(&x);
    match l.load {
        Load::Point { at, .. } if !on(at) => Err(format!(
            "point load at {at} m lies off the member (0 to {length} m)"
        )),
        Load::Distributed { from, to, .. } if !(on(from) && on(to) && from < to) => Err(format!(
            "distributed load from {from} m to {to} m must lie on the member (0 to {length} m) with from < to"
        )),
        _ => Ok(()),
    }
}

impl Element {
    pub fn new(model: &FrameModel, m: &Member) -> Result<Element, String> {
        let origin = DVec3::from_array(model.nodes[m.start]);
        let far = DVec3::from_array(model.nodes[m.end]);
        let length = origin.distance(far);
        let axes = local_axes(origin, far, m.roll);
        let sound = SpaceSection::of(&m.section, m.poisson);
        // A damaged member is stiffer or softer by its section scale; it weighs what the
        // sound member weighs (the loads stay the sound structure's).
        let props = sound.scaled(m.section_scale);
        let e = m.elastic_modulus * m.stiffness_factor;
        let g = e / (2.0 * (1.0 + m.poisson));
        let timoshenko = m.theory == MemberTheory::Timoshenko;
        let shear_param = |i: f64, shear_area: f64| {
            if timoshenko {
                12.0 * e * i / (g * shear_area * length * length)
            } else {
                0.0
            }
        };
        let (phi_y, phi_z) = (
            shear_param(props.i_z, props.shear_area_y),
            shear_param(props.i_y, props.shear_area_z),
        );
        let k_full = local_stiffness(&props, e, g, length, phi_y, phi_z);
        let mut loads = LocalLoads::default();
        for l in &m.loads {
            loads.add(l, &axes, length);
        }
        if model.self_weight && m.density > 0.0 {
            let weight = MemberLoad {
                load: Load::Distributed {
                    from: 0.0,
                    to: length,
                    intensity: m.density * super::GRAVITY * sound.area,
                },
                direction: [0.0, 0.0, -1.0],
                axes: Axes::Global,
            };
            loads.add(&weight, &axes, length);
        }
        // EI/(κGA) of each plane for the beam module (0 for Euler–Bernoulli).
        let flex_y = phi_y * length * length / 12.0;
        let flex_z = phi_z * length * length / 12.0;
        let beam_y = LinearBeam::solve(Support::FixedFixed, length, &loads.y, flex_y);
        let beam_z = LinearBeam::solve(Support::FixedFixed, length, &loads.z, flex_z);
        let fixed_full = loads.fixed_end_forces(&beam_y, &beam_z, length);
        let bar_start = loads.bar_reactions(length).0;
        let mut released = [false; 12];
        for (end, release) in m.releases.iter().enumerate() {
            for (r, flag) in release.flags().into_iter().enumerate() {
                released[6 * end + 3 + r] = flag;
            }
        }
        let (k, fixed) = condense(&k_full, &fixed_full, &released);
        Ok(Element {
            axes,
            length,
            props,
            e,
            phi_y,
            phi_z,
            k_full,
            fixed_full,
            released,
            k,
            fixed,
            beam_y,
            beam_z,
            axial_points: loads.axial_points,
            axial_udls: loads.axial_udls,
            bar_start,
            kinks: loads.kinks,
            tension: 0.0,
        })
    }

    /// The member with the geometric stiffness of an axial force `tension` (N, tension
    /// positive) added: the consistent matrix of a cubic deflection (Przemieniecki §15),
    /// bending terms only.
    pub fn with_axial_force(mut self, tension: f64) -> Element {
        self.k_full += geometric_stiffness(tension, self.length);
        self.tension = tension;
        (self.k, self.fixed) = condense(&self.k_full, &self.fixed_full, &self.released);
        self
    }

    /// The 12 × 12 rotation from world to local DOFs.
    pub fn transformation(&self) -> Mat12 {
        let mut t = Mat12::zeros();
        for block in 0..4 {
            for r in 0..3 {
                for c in 0..3 {
                    t[(3 * block + r, 3 * block + c)] = self.axes.col(c)[r];
                }
            }
        }
        t
    }

    /// Local end displacements from the two nodes' world displacements, with the released
    /// rotations recovered from the member's own equilibrium (zero end moment there).
    pub fn local_displacements(&self, start: &[f64; 6], end: &[f64; 6]) -> Vec12 {
        let mut global = Vec12::zeros();
        for i in 0..6 {
            global[i] = start[i];
            global[6 + i] = end[i];
        }
        let mut d = self.transformation() * global;
        let b: Vec<usize> = (0..12).filter(|&i| self.released[i]).collect();
        if b.is_empty() {
            return d;
        }
        for &i in &b {
            d[i] = 0.0;
        }
        // K_bb d_b = −(f_b + K_ba d_a): the released ends carry no moment.
        let kbb = DMatrix::from_fn(b.len(), b.len(), |r, c| self.k_full[(b[r], b[c])]);
        let rhs = DVector::from_fn(b.len(), |r, _| {
            -(self.fixed_full[b[r]] + (0..12).map(|c| self.k_full[(b[r], c)] * d[c]).sum::<f64>())
        });
        let db = kbb
            .lu()
            .solve(&rhs)
            .expect("a released block is invertible (validated)");
        for (r, &i) in b.iter().enumerate() {
            d[i] = db[r];
        }
        d
    }
}

/// The member's loads split into its local planes and its axis.
#[derive(Default)]
struct LocalLoads {
    /// Beam loads bending in x–y and x–z (downward-positive = toward local −y, −z).
    y: Vec<Load>,
    z: Vec<Load>,
    axial_points: Vec<(f64, f64)>,
    axial_udls: Vec<(f64, f64, f64)>,
    /// Forces and moments applied right at the ends (local), as [start, end] × 6.
    at_ends: [f64; 12],
    kinks: Vec<f64>,
}

impl LocalLoads {
    fn add(&mut self, l: &MemberLoad, axes: &DMat3, length: f64) {
        let dir = DVec3::from_array(l.direction);
        let local = match l.axes {
            Axes::Global => *axes * dir,
            Axes::Local => dir,
        };
        match l.load {
            Load::Point { at, force } => {
                let f = force * local;
                let at = at.clamp(0.0, length);
                if at <= 0.0 || at >= length {
                    let end = usize::from(at >= length);
                    for (i, c) in f.to_array().into_iter().enumerate() {
                        self.at_ends[6 * end + i] += c;
                    }
                    return;
                }
                self.kinks.push(at);
                self.y.push(Load::Point { at, force: -f.y });
                self.z.push(Load::Point { at, force: -f.z });
                self.axial_points.push((at, f.x));
            }
            Load::Distributed {
                from,
                to,
                intensity,
            } => {
                let q = intensity * local;
                let (from, to) = (from.clamp(0.0, length), to.clamp(0.0, length));
                self.kinks.extend([from, to]);
                self.y.push(Load::Distributed {
                    from,
                    to,
                    intensity: -q.y,
                });
                self.z.push(Load::Distributed {
                    from,
                    to,
                    intensity: -q.z,
                });
                self.axial_udls.push((from, to, q.x));
            }
            Load::EndMoments { start, end } => {
                for (e, m) in [start, end].into_iter().enumerate() {
                    for (i, c) in (m * local).to_array().into_iter().enumerate() {
                        self.at_ends[6 * e + 3 + i] += c;
                    }
                }
            }
        }
    }

    /// Forces of the clamps on the member (local): the beam solutions' end shears and moments,
    /// the bar's end reactions, and minus whatever acts right at the ends.
    fn fixed_end_forces(&self, beam_y: &LinearBeam, beam_z: &LinearBeam, length: f64) -> Vec12 {
        let mut f = Vec12::zeros();
        let (y0, y1) = (beam_y.at(0.0), beam_y.at(length));
        let (z0, z1) = (beam_z.at(0.0), beam_z.at(length));
        // x–y plane: v = −y, sagging M; a clamp's upward (+y) force is V(0) at the start and
        // −V(L) at the end, its moment about +z is −M(0) and M(L).
        f[1] = y0.shear;
        f[5] = -y0.moment;
        f[7] = -y1.shear;
        f[11] = y1.moment;
        // x–z plane: w = −v; a moment about +y turns z into x, the opposite sense.
        f[2] = z0.shear;
        f[4] = z0.moment;
        f[8] = -z1.shear;
        f[10] = -z1.moment;
        (f[0], f[6]) = self.bar_reactions(length);
        for i in 0..12 {
            f[i] -= self.at_ends[i];
        }
        f
    }
}

impl LocalLoads {
    /// The axial forces of clamps at the start and the end on a bar under the axial loads:
    /// the lever rule.
    fn bar_reactions(&self, length: f64) -> (f64, f64) {
        let (mut start, mut end) = (0.0, 0.0);
        let spans = self
            .axial_udls
            .iter()
            .map(|&(s, e, q)| (0.5 * (s + e), q * (e - s)));
        for (at, force) in self.axial_points.iter().copied().chain(spans) {
            start -= force * (length - at) / length;
            end -= force * at / length;
        }
        (start, end)
    }
}

impl Element {
    /// The member's mass matrix in local DOFs for a material of `density` (kg/m³): the
    /// Euler–Bernoulli consistent matrix or a lumped one, the released end rotations following
    /// the other DOFs as the static condensation of the stiffness has them (no end moment), so
    /// the rows and columns of released DOFs are zero.
    pub fn mass(&self, density: f64, kind: MassMatrix) -> Mat12 {
        let (per_length, polar) = (
            density * self.props.area,
            density * (self.props.i_y + self.props.i_z),
        );
        let m = match kind {
            MassMatrix::Consistent => consistent_mass(per_length, polar, self.length),
            MassMatrix::Lumped => lumped_mass(per_length, polar, self.length),
        };
        let t = self.condensation();
        t.transpose() * m * t
    }

    /// T with d = T d_a: the identity on the kept DOFs, and each released DOF from the kept
    /// ones by K_bb d_b = −K_ba d_a (columns of released DOFs zero).
    fn condensation(&self) -> Mat12 {
        let mut t = Mat12::identity();
        let b: Vec<usize> = (0..12).filter(|&i| self.released[i]).collect();
        if b.is_empty() {
            return t;
        }
        let kbb = DMatrix::from_fn(b.len(), b.len(), |r, c| self.k_full[(b[r], b[c])]);
        let inv = kbb
            .try_inverse()
            .expect("the released block of a member is invertible (validated)");
        for (r, &row) in b.iter().enumerate() {
            for j in 0..12 {
                t[(row, j)] = if self.released[j] {
                    0.0
                } else {
                    -(0..b.len())
                        .map(|c| inv[(r, c)] * self.k_full[(b[c], j)])
                        .sum::<f64>()
                };
            }
        }
        t
    }
}

/// Consistent mass of a prismatic member (Przemieniecki §11): linear axial and torsional
/// fields, Hermite cubics in bending (Euler–Bernoulli: the section's rotary inertia in
/// bending is left out, as is shear deformation for Timoshenko members). `per_length` ρA
/// kg/m, `polar` ρ(I_y + I_z) kg·m.
fn consistent_mass(per_length: f64, polar: f64, l: f64) -> Mat12 {
    let mut m = Mat12::zeros();
    let mut put = |a: usize, b: usize, v: f64| {
        m[(a, b)] += v;
        if a != b {
            m[(b, a)] += v;
        }
    };
    let (bar, twist) = (per_length * l / 6.0, polar * l / 6.0);
    for (a, b, c) in [(0, 6, bar), (3, 9, twist)] {
        put(a, a, 2.0 * c);
        put(b, b, 2.0 * c);
        put(a, b, c);
    }
    let c = per_length * l / 420.0;
    // x–y plane (v, θz): DOFs 1, 5, 7, 11; x–z plane (w, θy): 2, 4, 8, 10, where θy = −dw/dx
    // flips the couplings of a deflection with a rotation (as in the stiffness).
    for ([v0, t0, v1, t1], s) in [([1, 5, 7, 11], 1.0), ([2, 4, 8, 10], -1.0)] {
        put(v0, v0, 156.0 * c);
        put(v1, v1, 156.0 * c);
        put(v0, v1, 54.0 * c);
        put(t0, t0, 4.0 * l * l * c);
        put(t1, t1, 4.0 * l * l * c);
        put(t0, t1, -3.0 * l * l * c);
        put(v0, t0, s * 22.0 * l * c);
        put(v0, t1, -s * 13.0 * l * c);
        put(t0, v1, s * 13.0 * l * c);
        put(v1, t1, -s * 22.0 * l * c);
    }
    m
}

/// Lumped mass: half the member's mass on each end's translations and half its rotary inertia
/// about its axis on each end's twist; none on the bending rotations.
fn lumped_mass(per_length: f64, polar: f64, l: f64) -> Mat12 {
    let mut m = Mat12::zeros();
    for end in [0, 6] {
        for d in 0..3 {
            m[(end + d, end + d)] = per_length * l / 2.0;
        }
        m[(end + 3, end + 3)] = polar * l / 2.0;
    }
    m
}

/// Local stiffness of a prismatic space-frame member (Przemieniecki 1968, §5.6; Φ = 0 gives
/// Euler–Bernoulli). DOFs: [u, v, w, θx, θy, θz] at the start, then at the end.
fn local_stiffness(p: &SpaceSection, e: f64, g: f64, l: f64, phi_y: f64, phi_z: f64) -> Mat12 {
    let mut k = Mat12::zeros();
    let mut put = |a: usize, b: usize, v: f64| {
        k[(a, b)] += v;
        if a != b {
            k[(b, a)] += v;
        }
    };
    let ea = e * p.area / l;
    put(0, 0, ea);
    put(6, 6, ea);
    put(0, 6, -ea);
    let gj = g * p.torsion / l;
    put(3, 3, gj);
    put(9, 9, gj);
    put(3, 9, -gj);
    // Bending in x–y (v, θz): DOFs 1, 5, 7, 11; about z with I_z.
    let c = e * p.i_z / ((1.0 + phi_y) * l.powi(3));
    put(1, 1, 12.0 * c);
    put(7, 7, 12.0 * c);
    put(1, 7, -12.0 * c);
    put(1, 5, 6.0 * l * c);
    put(1, 11, 6.0 * l * c);
    put(5, 7, -6.0 * l * c);
    put(7, 11, -6.0 * l * c);
    put(5, 5, (4.0 + phi_y) * l * l * c);
    put(11, 11, (4.0 + phi_y) * l * l * c);
    put(5, 11, (2.0 - phi_y) * l * l * c);
    // Bending in x–z (w, θy): DOFs 2, 4, 8, 10; about y with I_y; θy = −dw/dx flips the
    // coupling signs.
    let c = e * p.i_y / ((1.0 + phi_z) * l.powi(3));
    put(2, 2, 12.0 * c);
    put(8, 8, 12.0 * c);
    put(2, 8, -12.0 * c);
    put(2, 4, -6.0 * l * c);
    put(2, 10, -6.0 * l * c);
    put(4, 8, 6.0 * l * c);
    put(8, 10, 6.0 * l * c);
    put(4, 4, (4.0 + phi_z) * l * l * c);
    put(10, 10, (4.0 + phi_z) * l * l * c);
    put(4, 10, (2.0 - phi_z) * l * l * c);
    k
}

/// Geometric stiffness of a member of length `l` carrying axial force `n` (tension positive).
fn geometric_stiffness(n: f64, l: f64) -> Mat12 {
    let mut k = Mat12::zeros();
    let c = n / (30.0 * l);
    // x–y plane (v, θz): DOFs 1, 5, 7, 11; x–z plane (w, θy): DOFs 2, 4, 8, 10, where
    // θy = −dw/dx flips the coupling signs.
    for ([v0, t0, v1, t1], s) in [([1, 5, 7, 11], 1.0), ([2, 4, 8, 10], -1.0)] {
        let entries = [
            (v0, v0, 36.0),
            (v1, v1, 36.0),
            (v0, v1, -36.0),
            (v0, t0, 3.0 * l * s),
            (v0, t1, 3.0 * l * s),
            (t0, v1, -3.0 * l * s),
            (v1, t1, -3.0 * l * s),
            (t0, t0, 4.0 * l * l),
            (t1, t1, 4.0 * l * l),
            (t0, t1, -l * l),
        ];
        for (a, b, v) in entries {
            k[(a, b)] += c * v;
            if a != b {
                k[(b, a)] += c * v;
            }
        }
    }
    k
}

/// Static condensation of the released DOFs b: K* = K_aa − K_ab K_bb⁻¹ K_ba and
/// f* = f_a − K_ab K_bb⁻¹ f_b, with zero rows and columns at b.
fn condense(k: &Mat12, f: &Vec12, released: &[bool; 12]) -> (Mat12, Vec12) {
    let b: Vec<usize> = (0..12).filter(|&i| released[i]).collect();
    if b.is_empty() {
        return (*k, *f);
    }
    let kbb = DMatrix::from_fn(b.len(), b.len(), |r, c| k[(b[r], b[c])]);
    let inv = kbb
        .try_inverse()
        .expect("the released block of a member is invertible (validated)");
    let mut kc = *k;
    let mut fc = *f;
    for i in 0..12 {
        for j in 0..12 {
            let mut s = 0.0;
            for (r, &br) in b.iter().enumerate() {
                for (c, &bc) in b.iter().enumerate() {
                    s += k[(i, br)] * inv[(r, c)] * k[(bc, j)];
                }
            }
            kc[(i, j)] -= s;
        }
        let mut s = 0.0;
        for (r, &br) in b.iter().enumerate() {
            for (c, &bc) in b.iter().enumerate() {
                s += k[(i, br)] * inv[(r, c)] * f[bc];
            }
        }
        fc[i] -= s;
    }
    let scale = kc.amax();
    for i in 0..12 {
        for j in 0..12 {
            if released[i] || released[j] || kc[(i, j)].abs() < ROUND_OFF * scale {
                kc[(i, j)] = 0.0;
            }
        }
        if released[i] {
            fc[i] = 0.0;
        }
    }
    (kc, fc)
}
