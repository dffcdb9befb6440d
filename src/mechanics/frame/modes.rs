//! Natural modes of a whole frame and the vibration snapshots drawn from them.
//!
//! Owns: the structure's mass matrix (each member's consistent or lumped matrix, ρ A per metre
//! and ρ (I_y + I_z) about its axis, plus masses added at nodes), the generalised eigenproblem
//! K φ = ω² M φ on the free DOFs with the supports applied, the effective modal masses, and a
//! snapshot Σ A_n φ_n as a [`FrameSolution`] (its member fields, end forces and stresses are
//! those of that shape).
//!
//! Method: K (equilibrated, as the static solve has it) = L Lᵀ by Cholesky, which also
//! refuses a mechanism with its DOFs named. Up to [`DENSE_MODES_MAX_DOFS`] free DOFs, the
//! symmetric eigenproblem of C = L⁻¹ M L⁻ᵀ (eigenvalues 1/ω²), so a singular M (lumped mass,
//! massless DOFs) is fine: its null space gives infinite frequencies, which are dropped. Above,
//! subspace iteration on the sparse factor (the wanted modes only). Inside a member a mode's shape
//! is the static field of its end displacements (Hermite cubics): exact at the nodes of the
//! discrete model, and the member's own dynamic shape differs from it by terms of order
//! (ω/ω₁ of the member clamped)², so members should be subdivided where a mode has more than
//! about a half wave in one member (the tests show the convergence).

use super::element::Element;
use super::results::FrameSolution;
use super::{FrameModel, MassMatrix, labels, solve};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// The largest number of free DOFs whose modes are solved dense. The dense symmetric
/// eigensolver costs O(n³): `cargo bench --bench frames` measured 32 ms at 300 DOFs, 0.28 s
/// at 600 and 2.2 s at 1,200 (one core); larger models go to subspace iteration on the
/// sparse factor.
pub const DENSE_MODES_MAX_DOFS: usize = 1200;

/// Modes reported in the labels of a vibration snapshot besides those it draws.
const REPORTED_MODES: usize = 6;

/// An eigenvalue 1/ω² below this fraction of the largest belongs to a DOF without mass
/// (infinite frequency) and is not a mode.
const MASSLESS: f64 = 1e-12;

/// Subspace iteration stops when every wanted eigenvalue ω² changes by less than this
/// fraction in one iteration (the mode shapes are then accurate to about its square root).
const SUBSPACE_TOLERANCE: f64 = 1e-13;

/// Iterations after which subspace iteration gives up.
const SUBSPACE_ITERATIONS: usize = 500;

/// The lowest natural modes of a frame.
#[derive(Clone, Debug)]
pub struct NaturalModes {
    /// Angular frequencies ω, rad/s, ascending.
    pub omega: Vec<f64>,
    /// Mode shapes: each node's [ux, uy, uz, rx, ry, rz], normalised to φᵀ M φ = 1 (kg).
    pub shapes: Vec<Vec<[f64; 6]>>,
    /// Each mode's effective mass along world x, y, z, kg: (φᵀ M r)² with r a unit rigid
    /// translation of every free DOF.
    pub effective_mass: Vec<[f64; 3]>,
    /// The mass that moves in a rigid translation along x, y, z (rᵀ M r), kg.
    pub moving_mass: [f64; 3],
}

/// What a vibration snapshot of a frame is made of, in its labels.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ModalLabels {
    /// How member mass was spread: "consistent" or "lumped".
    pub mass_matrix: MassMatrix,
    /// The mass that moves with the free DOFs along world x, y, z, kg (members and added
    /// masses; what the supports hold does not count).
    pub moving_mass: [f64; 3],
    /// Natural frequencies of the lowest modes, Hz, ascending (at least the modes drawn, and
    /// six where the model has them).
    pub frequencies: Vec<f64>,
    /// For each of those modes, its effective mass along world x, y, z as a fraction of
    /// `moving_mass` (0 where nothing moves that way); they sum to 1 over all modes.
    pub effective_mass_ratio: Vec<[f64; 3]>,
    /// The modes drawn.
    pub snapshot: Vec<FrameModeLabel>,
}

/// One mode of a frame's vibration snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FrameModeLabel {
    /// Mode number n, from 1 (the fundamental).
    pub mode: u32,
    /// Its natural frequency, Hz.
    pub frequency: f64,
    /// Its amplitude, metres: the largest translation of any point of the members' axes in
    /// its contribution. Sign: the node translation component of largest magnitude in the mode
    /// is positive.
    pub amplitude: f64,
}

impl FrameModel {
    /// The lowest `count` natural modes with the supports applied; refuses a mechanism (as
    /// the static analysis does) and a model with fewer than `count` DOFs that carry mass.
    pub fn natural_modes(&self, count: usize) -> Result<NaturalModes, String> {
        self.validate()?;
        let modes = self.lowest_modes(count)?;
        if modes.omega.len() < count {
            return Err(format!(
                "mode {count} was asked for, but the frame has only {} modes with mass (add members, nodes or nodal masses)",
                modes.omega.len()
            ));
        }
        Ok(modes)
    }

    /// Up to `count` of the lowest modes (fewer when fewer DOFs carry mass).
    fn lowest_modes(&self, count: usize) -> Result<NaturalModes, String> {
        let elements = self.elements()?;
        let solve::Assembled {
            free,
            scale,
            system,
        } = solve::assemble(self, &elements)?;
        let mass = self.scaled_mass(&elements, &free, &scale);
        let found = if free.len() <= DENSE_MODES_MAX_DOFS {
            dense_modes(&system, &mass, &free, count)?
        } else {
            subspace_modes(&system, &mass, &free, count)?
        };
        let translation = |k: usize| -> DVector<f64> {
            DVector::from_fn(free.len(), |i, _| {
                if free[i] % 6 == k {
                    1.0 / scale[i]
                } else {
                    0.0
                }
            })
        };
        let rigid: Vec<DVector<f64>> = (0..3).map(translation).collect();
        let moving_mass = [0, 1, 2].map(|k| rigid[k].dot(&mass.times(&rigid[k])));
        let mut modes = NaturalModes {
            omega: Vec::new(),
            shapes: Vec::new(),
            effective_mass: Vec::new(),
            moving_mass,
        };
        for (omega, shape) in found {
            let m_shape = mass.times(&shape);
            modes.omega.push(omega);
            modes
                .effective_mass
                .push([0, 1, 2].map(|k| m_shape.dot(&rigid[k]).powi(2)));
            modes.shapes.push(solve::to_nodes(
                self.nodes.len(),
                &free,
                &scale,
                shape.as_slice(),
            ));
        }
        Ok(modes)
    }

    /// The members' elements (stiffness, axes, fields), in the order of the members.
    pub(super) fn elements(&self) -> Result<Vec<Element>, String> {
        self.members.iter().map(|m| Element::new(self, m)).collect()
    }

    /// D M D on the free DOFs: the members' mass matrices in world axes and the nodal masses.
    pub(super) fn scaled_mass(
        &self,
        elements: &[Element],
        free: &[usize],
        scale: &[f64],
    ) -> ScaledMass {
        let mut index = vec![usize::MAX; self.nodes.len() * 6];
        for (i, &d) in free.iter().enumerate() {
            index[d] = i;
        }
        let mut entries = Vec::new();
        let mut add = |a: usize, b: usize, v: f64| {
            let (i, j) = (index[a], index[b]);
            if i != usize::MAX && j != usize::MAX && v != 0.0 {
                entries.push((i, j, v * scale[i] * scale[j]));
            }
        };
        for (el, member) in elements.iter().zip(&self.members) {
            let t = el.transformation();
            let m = t.transpose() * el.mass(member.density, self.mass_matrix) * t;
            let dof = |i: usize| 6 * if i < 6 { member.start } else { member.end } + i % 6;
            for i in 0..12 {
                for j in 0..12 {
                    add(dof(i), dof(j), m[(i, j)]);
                }
            }
        }
        for nodal in &self.masses {
            for k in 0..3 {
                let d = 6 * nodal.node + k;
                add(d, d, nodal.mass);
                add(d + 3, d + 3, nodal.inertia[k]);
            }
        }
        ScaledMass {
            size: free.len(),
            entries,
        }
    }

    /// The snapshot Σ A_n φ_n of `vibration` as a solution: each mode scaled so the largest
    /// translation of any point of the members' axes is 1, the node translation component of
    /// largest magnitude positive.
    pub(super) fn vibration_snapshot(&self) -> Result<FrameSolution, String> {
        self.refuse_loads_with_vibration()?;
        let highest = self.vibration.iter().map(|v| v.0).max().unwrap_or(1) as usize;
        let modes = self.lowest_modes(highest.max(REPORTED_MODES))?;
        if modes.omega.len() < highest {
            return Err(format!(
                "vibration: mode {highest} was asked for, but the frame has only {} modes with mass (add members, nodes or nodal masses)",
                modes.omega.len()
            ));
        }
        let elements = self.elements()?;
        let mut sum = vec![[0.0; 6]; self.nodes.len()];
        let mut snapshot = Vec::new();
        for &(n, amplitude) in &self.vibration {
            let shape = &modes.shapes[n as usize - 1];
            let drawn = FrameSolution::new(self, elements.clone(), shape.clone());
            let factor = amplitude * sign(shape) / labels::largest_translation_of(&drawn).2;
            for (total, node) in sum.iter_mut().zip(shape) {
                for (t, d) in total.iter_mut().zip(node) {
                    *t += factor * d;
                }
            }
            snapshot.push(FrameModeLabel {
                mode: n,
                frequency: modes.omega[n as usize - 1] / std::f64::consts::TAU,
                amplitude,
            });
        }
        let mut solution = FrameSolution::new(self, elements, sum);
        let ratio = |m: &[f64; 3]| {
            [0, 1, 2].map(|k| {
                if modes.moving_mass[k] > 0.0 {
                    m[k] / modes.moving_mass[k]
                } else {
                    0.0
                }
            })
        };
        solution.modal = Some(ModalLabels {
            mass_matrix: self.mass_matrix,
            moving_mass: modes.moving_mass,
            frequencies: modes
                .omega
                .iter()
                .map(|w| w / std::f64::consts::TAU)
                .collect(),
            effective_mass_ratio: modes.effective_mass.iter().map(ratio).collect(),
            snapshot,
        });
        Ok(solution)
    }

    /// A snapshot is free vibration: loads would be drawn as if absent, so they are refused.
    fn refuse_loads_with_vibration(&self) -> Result<(), String> {
        let member_loads = self.members.iter().filter(|m| !m.loads.is_empty()).count();
        if self.loads.is_empty() && member_loads == 0 && !self.self_weight {
            return Ok(());
        }
        Err(format!(
            "a frame takes either static loads or a vibration snapshot, not both ({} nodal loads, {member_loads} loaded members, self_weight {}); the members' mass counts without self_weight",
            self.loads.len(),
            self.self_weight
        ))
    }
}

/// +1 or −1: the sign that makes the node translation component of largest magnitude positive
/// (the first of equal ones).
fn sign(shape: &[[f64; 6]]) -> f64 {
    let largest = shape
        .iter()
        .flat_map(|d| d[..3].iter().copied())
        .fold(
            0.0f64,
            |best, v| if v.abs() > best.abs() { v } else { best },
        );
    if largest < 0.0 { -1.0 } else { 1.0 }
}

/// The scaled mass matrix D M D on the free DOFs, as entries (duplicates add).
pub(super) struct ScaledMass {
    size: usize,
    entries: Vec<(usize, usize, f64)>,
}

impl ScaledMass {
    /// The matrix, dense.
    pub fn dense(&self) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(self.size, self.size);
        for &(i, j, v) in &self.entries {
            m[(i, j)] += v;
        }
        m
    }

    /// The diagonal of M.
    fn diagonal(&self) -> DVector<f64> {
        let mut d = DVector::zeros(self.size);
        for &(i, j, v) in &self.entries {
            if i == j {
                d[i] += v;
            }
        }
        d
    }

    /// M x.
    fn times(&self, x: &DVector<f64>) -> DVector<f64> {
        let mut y = DVector::zeros(self.size);
        for &(i, j, v) in &self.entries {
            y[i] += v * x[j];
        }
        y
    }

    /// M X, column by column.
    fn times_block(&self, x: &DMatrix<f64>) -> DMatrix<f64> {
        let mut y = DMatrix::zeros(self.size, x.ncols());
        for &(i, j, v) in &self.entries {
            for c in 0..x.ncols() {
                y[(i, c)] += v * x[(j, c)];
            }
        }
        y
    }
}

/// The lowest modes as (ω, mass-normalised shape in scaled DOFs), dense: K = L Lᵀ, then the
/// symmetric eigenproblem of C = L⁻¹ M L⁻ᵀ (eigenvalues 1/ω²).
pub(super) fn dense_modes(
    system: &solve::System,
    mass: &ScaledMass,
    free: &[usize],
    count: usize,
) -> Result<Vec<(f64, DVector<f64>)>, String> {
    let order: Vec<usize> = (0..system.size).collect();
    let chol = system
        .dense_cholesky()
        .ok_or_else(|| system.mechanism(free, true, &order))?;
    let l = chol.l();
    let eigen = reduced(&l, &mass.dense()).symmetric_eigen();
    let mut pairs: Vec<usize> = (0..eigen.eigenvalues.len()).collect();
    pairs.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
    let largest = pairs.first().map_or(0.0, |&i| eigen.eigenvalues[i]);
    let mut found = Vec::new();
    for &i in pairs.iter().take(count) {
        let mu = eigen.eigenvalues[i];
        if !(mu > MASSLESS * largest) {
            break;
        }
        // φ' = L⁻ᵀ y has φ'ᵀ M φ' = yᵀ C y = μ: divided by √μ it is mass-normalised.
        let shape = l
            .tr_solve_lower_triangular(&eigen.eigenvectors.column(i).into_owned())
            .expect("a Cholesky factor has a nonzero diagonal")
            / mu.sqrt();
        found.push((mu.sqrt().recip(), shape));
    }
    Ok(found)
}

/// The lowest modes by subspace iteration (Bathe, *Finite Element Procedures*, §11.6) on the
/// sparse factor of K: p = max(2q, q + 8) vectors, X̄ = K⁻¹ M X, the projected problem
/// K̃ Q = M̃ Q Λ solved dense, X = X̄ Q, until the q wanted ω² settle. Starting vectors: the mass
/// diagonal, then unit vectors at the DOFs of largest m_ii/k_ii (k_ii is 1 in scaled DOFs).
pub(super) fn subspace_modes(
    system: &solve::System,
    mass: &ScaledMass,
    free: &[usize],
    count: usize,
) -> Result<Vec<(f64, DVector<f64>)>, String> {
    let n = system.size;
    let order = system.fill_reducing_order();
    let factor = system
        .sparse_factor(&order)
        .ok_or_else(|| system.mechanism(free, false, &order))?;
    let q = count.min(n);
    let p = (2 * q).max(q + 8).min(n);
    let diagonal = mass.diagonal();
    let mut heaviest: Vec<usize> = (0..n).collect();
    heaviest.sort_by(|&a, &b| diagonal[b].total_cmp(&diagonal[a]).then(a.cmp(&b)));
    let mut x = DMatrix::zeros(n, p);
    x.column_mut(0).copy_from(&diagonal);
    for c in 1..p {
        x[(heaviest[c - 1], c)] = 1.0;
    }
    let mut previous = vec![f64::INFINITY; q];
    for _ in 0..SUBSPACE_ITERATIONS {
        let y = mass.times_block(&x);
        let xbar = factor.solve(&y);
        let k_small = symmetric(xbar.transpose() * &y);
        let m_small = symmetric(xbar.transpose() * mass.times_block(&xbar));
        let Some(lm) = m_small.clone().cholesky() else {
            return Err(format!(
                "natural modes: fewer than {p} DOFs of the frame carry mass (add nodal masses or use the consistent mass matrix)"
            ));
        };
        let l = lm.l();
        let eigen = reduced(&l, &k_small).symmetric_eigen();
        let mut ranks: Vec<usize> = (0..p).collect();
        ranks.sort_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
        let vectors = DMatrix::from_fn(p, p, |r, k| eigen.eigenvectors[(r, ranks[k])]);
        let basis = l
            .tr_solve_lower_triangular(&vectors)
            .expect("a Cholesky factor has a nonzero diagonal");
        x = xbar * basis;
        let lambda: Vec<f64> = ranks
            .iter()
            .take(q)
            .map(|&k| eigen.eigenvalues[k])
            .collect();
        let settled = lambda
            .iter()
            .zip(&previous)
            .all(|(l, was)| (l - was).abs() <= SUBSPACE_TOLERANCE * l.abs());
        previous = lambda;
        if settled {
            return Ok(previous
                .iter()
                .enumerate()
                .map(|(k, l)| (l.sqrt(), x.column(k).into_owned()))
                .collect());
        }
    }
    Err(format!(
        "natural modes: subspace iteration did not settle in {SUBSPACE_ITERATIONS} iterations ({n} free DOFs, {q} modes)"
    ))
}

/// L⁻¹ A L⁻ᵀ for a Cholesky factor L and a symmetric A, made exactly symmetric: the standard
/// form of the pencil (A, L Lᵀ).
fn reduced(l: &DMatrix<f64>, a: &DMatrix<f64>) -> DMatrix<f64> {
    let half = l
        .solve_lower_triangular(a)
        .expect("a Cholesky factor has a nonzero diagonal");
    let c = l
        .solve_lower_triangular(&half.transpose())
        .expect("a Cholesky factor has a nonzero diagonal");
    symmetric(c)
}

/// (A + Aᵀ)/2: a product that is symmetric in exact arithmetic, made exactly so.
fn symmetric(a: DMatrix<f64>) -> DMatrix<f64> {
    (&a + a.transpose()) * 0.5
}
