//! Assembling the structure's stiffness and solving it: dense Cholesky for small models,
//! sparse Cholesky in a reverse Cuthill–McKee order for large ones, and the refusal of a
//! mechanism with the DOFs that move freely named.
//!
//! The system is solved equilibrated, D K D (D d') = D F with D = diag(K)^(-1/2), so its
//! diagonal is 1 whatever the units of a DOF (metres or radians, a stiff bar or a soft
//! spring): a pivot that collapses below [`PIVOT`] then means a mechanism, not a scale.

use super::element::{Element, Vec12};
use super::{DOF_NAMES, FrameModel};
use nalgebra::{DMatrix, DVector};
use nalgebra_sparse::{CooMatrix, CscMatrix, factorization::CscCholesky};

/// The largest number of free DOFs solved dense; above it the sparse Cholesky is faster
/// (`benches/frames.rs`, docs/frames.md: a whole analysis of 99 free DOFs takes 0.62 ms dense
/// and 0.65 ms sparse, of 297 DOFs 2.6 ms and 2.0 ms, of 999 DOFs 74 ms and 11 ms).
pub const DENSE_MAX_DOFS: usize = 150;

/// Smallest squared pivot of the equilibrated system (unit diagonal) accepted: the stiffness
/// left at a DOF after elimination, as a fraction of its own. A mechanism leaves round-off,
/// which cancellation between stiff axial and soft bending terms lifts well above 1e-16 (4e-11
/// measured for a pinned portal of members with E A h² / E I = 2·10⁶); a slender but stable
/// frame of the same members keeps 1e-5.
const PIVOT: f64 = 1e-9;

/// Which linear solver to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solver {
    /// Dense up to [`DENSE_MAX_DOFS`] free DOFs, sparse above.
    Auto,
    /// Dense Cholesky (nalgebra).
    Dense,
    /// Sparse Cholesky (nalgebra-sparse) after a reverse Cuthill–McKee ordering.
    Sparse,
}

/// The structure's free DOFs and its equilibrated stiffness and load on them.
pub(super) struct Assembled {
    /// The global DOF (6 × node + dof) of each free DOF.
    pub free: Vec<usize>,
    /// D: each free DOF's scale, diag(K)^(-1/2); physical = scaled × D.
    pub scale: Vec<f64>,
    /// D K D and D F.
    pub system: System,
}

/// The world displacements of every node, [ux, uy, uz, rx, ry, rz]; a rotation no member end
/// resists (a node of pinned bars only) is 0.
pub(super) fn displacements(
    model: &FrameModel,
    elements: &[Element],
    solver: Solver,
) -> Result<Vec<[f64; 6]>, String> {
    let Assembled {
        free,
        scale,
        system,
    } = assemble(model, elements)?;
    let dense = match solver {
        Solver::Auto => system.size <= DENSE_MAX_DOFS,
        Solver::Dense => true,
        Solver::Sparse => false,
    };
    let order = if dense {
        (0..system.size).collect()
    } else {
        reverse_cuthill_mckee(&system)
    };
    let solved = if dense {
        system.solve_dense()
    } else {
        system.solve_sparse(&order)
    };
    let scaled = solved.map_err(|()| system.mechanism(&free, dense, &order))?;
    Ok(to_nodes(model.nodes.len(), &free, &scale, &scaled))
}

/// Node displacements [ux, uy, uz, rx, ry, rz] from a scaled free-DOF vector; DOFs not free
/// are 0.
pub(super) fn to_nodes(
    nodes: usize,
    free: &[usize],
    scale: &[f64],
    scaled: &[f64],
) -> Vec<[f64; 6]> {
    let mut out = vec![[0.0; 6]; nodes];
    for (i, &d) in free.iter().enumerate() {
        out[d / 6][d % 6] = scaled[i] * scale[i];
    }
    out
}

/// The free DOFs, their scales and the equilibrated system; refuses DOFs nothing resists.
pub(super) fn assemble(model: &FrameModel, elements: &[Element]) -> Result<Assembled, String> {
    let n = model.nodes.len() * 6;
    let mut fixed = vec![false; n];
    let mut springs = vec![0.0; n];
    for s in &model.supports {
        for d in 0..6 {
            fixed[6 * s.node + d] |= s.fixed[d];
            springs[6 * s.node + d] += s.springs[d];
        }
    }
    if let Some(plane) = model.plane {
        for node in 0..model.nodes.len() {
            for d in plane.held() {
                fixed[6 * node + d] = true;
            }
        }
    }
    let mut entries: Vec<(usize, usize, f64)> = Vec::new();
    let mut load = vec![0.0; n];
    for l in &model.loads {
        for i in 0..3 {
            load[6 * l.node + i] += l.force[i];
            load[6 * l.node + 3 + i] += l.moment[i];
        }
    }
    let mut diagonal = springs.clone();
    for (el, m) in elements.iter().zip(&model.members) {
        let t = el.transformation();
        let k = t.transpose() * el.k * t;
        let f: Vec12 = t.transpose() * el.fixed;
        let dof = |i: usize| 6 * if i < 6 { m.start } else { m.end } + i % 6;
        for i in 0..12 {
            load[dof(i)] -= f[i];
            for j in 0..12 {
                if k[(i, j)] != 0.0 {
                    entries.push((dof(i), dof(j), k[(i, j)]));
                    if i == j {
                        diagonal[dof(i)] += k[(i, j)];
                    }
                }
            }
        }
    }
    for (d, &k) in springs.iter().enumerate() {
        if k > 0.0 {
            entries.push((d, d, k));
        }
    }
    // Free DOFs: not fixed, and not a rotation nothing resists and nothing loads.
    let mut index = vec![usize::MAX; n];
    let mut free = Vec::new();
    let mut unresisted = Vec::new();
    for d in 0..n {
        if fixed[d] {
            continue;
        }
        if diagonal[d] == 0.0 {
            if d % 6 >= 3 && load[d] == 0.0 {
                continue;
            }
            unresisted.push(d);
            continue;
        }
        index[d] = free.len();
        free.push(d);
    }
    if !unresisted.is_empty() {
        return Err(mechanism(&unresisted, "nothing resists them"));
    }
    let scale: Vec<f64> = free.iter().map(|&d| diagonal[d].sqrt().recip()).collect();
    let system = System {
        size: free.len(),
        entries: entries
            .into_iter()
            .filter(|&(i, j, _)| index[i] != usize::MAX && index[j] != usize::MAX)
            .map(|(i, j, k)| {
                let (a, b) = (index[i], index[j]);
                (a, b, k * scale[a] * scale[b])
            })
            .collect(),
        rhs: free.iter().zip(&scale).map(|(&d, s)| load[d] * s).collect(),
    };
    Ok(Assembled {
        free,
        scale,
        system,
    })
}

/// The message refusing a mechanism: the DOFs that move, by node and name.
fn mechanism(dofs: &[usize], why: &str) -> String {
    let names: Vec<String> = dofs
        .iter()
        .take(12)
        .map(|&d| format!("node {} {}", d / 6, DOF_NAMES[d % 6]))
        .collect();
    let more = if dofs.len() > 12 {
        format!(" and {} more", dofs.len() - 12)
    } else {
        String::new()
    };
    format!(
        "the frame is a mechanism: {why}; free DOFs {}{more} (add a support, a member, or remove a release)",
        names.join(", ")
    )
}

/// The equilibrated free-DOF system: symmetric entries (duplicates add) and its right side.
pub(super) struct System {
    pub size: usize,
    entries: Vec<(usize, usize, f64)>,
    rhs: Vec<f64>,
}

impl System {
    /// The refusal of a system that failed to factor: the free DOFs (global numbers `free`)
    /// that move in its mechanism.
    pub fn mechanism(&self, free: &[usize], dense: bool, order: &[usize]) -> String {
        let moving = self.null_vector(dense, order);
        mechanism(
            &moving.iter().map(|&i| free[i]).collect::<Vec<_>>(),
            "the structure can move without straining its members",
        )
    }

    /// Dense Cholesky factor of the system, refused (None) at a pivot that marks a mechanism.
    pub fn dense_cholesky(&self) -> Option<nalgebra::Cholesky<f64, nalgebra::Dyn>> {
        let chol = self.dense(0.0).cholesky()?;
        if chol.l_dirty().diagonal().iter().any(|p| !(p * p > PIVOT)) {
            return None;
        }
        Some(chol)
    }

    pub fn dense(&self, shift: f64) -> DMatrix<f64> {
        let mut k = DMatrix::from_diagonal_element(self.size, self.size, shift);
        for &(i, j, v) in &self.entries {
            k[(i, j)] += v;
        }
        k
    }

    fn solve_dense(&self) -> Result<Vec<f64>, ()> {
        let chol = self.dense_cholesky().ok_or(())?;
        Ok(chol
            .solve(&DVector::from_vec(self.rhs.clone()))
            .as_slice()
            .to_vec())
    }

    /// The matrix in `order` (row r of the result is DOF order[r]), plus `shift` on the diagonal.
    fn sparse(&self, order: &[usize], shift: f64) -> CscMatrix<f64> {
        let mut position = vec![0; self.size];
        for (r, &d) in order.iter().enumerate() {
            position[d] = r;
        }
        let mut coo = CooMatrix::new(self.size, self.size);
        for &(i, j, v) in &self.entries {
            coo.push(position[i], position[j], v);
        }
        if shift != 0.0 {
            for i in 0..self.size {
                coo.push(i, i, shift);
            }
        }
        CscMatrix::from(&coo)
    }

    fn solve_sparse(&self, order: &[usize]) -> Result<Vec<f64>, ()> {
        let factor = self.sparse_factor(order).ok_or(())?;
        let x = factor.solve(&DMatrix::from_column_slice(self.size, 1, &self.rhs));
        Ok(x.as_slice().to_vec())
    }

    /// Sparse Cholesky factor of the system in `order`, refused (None) at a pivot that marks a
    /// mechanism.
    pub fn sparse_factor(&self, order: &[usize]) -> Option<SparseFactor> {
        let chol = CscCholesky::factor(&self.sparse(order, 0.0)).ok()?;
        let l = chol.l();
        for c in 0..self.size {
            let col = l.col(c);
            let pivot = col
                .row_indices()
                .iter()
                .position(|&r| r == c)
                .map_or(0.0, |k| col.values()[k]);
            if !(pivot * pivot > PIVOT) {
                return None;
            }
        }
        Some(SparseFactor {
            chol,
            order: order.to_vec(),
        })
    }

    /// A bandwidth-reducing order for [`System::sparse_factor`].
    pub fn fill_reducing_order(&self) -> Vec<usize> {
        reverse_cuthill_mckee(self)
    }

    /// DOFs that move in the mechanism: two steps of inverse iteration on the system shifted
    /// by 1e-8 (positive definite, and its near-null vectors dominate the solution), keeping
    /// the DOFs within a tenth of the largest motion.
    fn null_vector(&self, dense: bool, order: &[usize]) -> Vec<usize> {
        const SHIFT: f64 = 1e-8;
        let mut x: Vec<f64> = (0..self.size)
            .map(|i| 1.0 + 0.1 * ((i * 7919) % 13) as f64)
            .collect();
        for _ in 0..2 {
            x = if dense {
                match self.dense(SHIFT).cholesky() {
                    Some(c) => c.solve(&DVector::from_vec(x)).as_slice().to_vec(),
                    None => return Vec::new(),
                }
            } else {
                let Ok(c) = CscCholesky::factor(&self.sparse(order, SHIFT)) else {
                    return Vec::new();
                };
                let b = DMatrix::from_fn(self.size, 1, |r, _| x[order[r]]);
                let y = c.solve(&b);
                let mut out = vec![0.0; self.size];
                for (r, &d) in order.iter().enumerate() {
                    out[d] = y[(r, 0)];
                }
                out
            };
            let top = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            x.iter_mut().for_each(|v| *v /= top);
        }
        (0..self.size).filter(|&i| x[i].abs() > 0.1).collect()
    }
}

/// The sparse Cholesky factor of a system, with the order its rows were permuted to.
pub(super) struct SparseFactor {
    chol: CscCholesky<f64>,
    order: Vec<usize>,
}

impl SparseFactor {
    /// X with K X = B, for every column of B (rows in the system's own numbering).
    pub fn solve(&self, b: &DMatrix<f64>) -> DMatrix<f64> {
        let permuted = DMatrix::from_fn(b.nrows(), b.ncols(), |r, c| b[(self.order[r], c)]);
        let y = self.chol.solve(&permuted);
        let mut x = DMatrix::zeros(b.nrows(), b.ncols());
        for (r, &d) in self.order.iter().enumerate() {
            x.row_mut(d).copy_from(&y.row(r));
        }
        x
    }
}

/// A bandwidth-reducing order of the DOFs: reverse Cuthill–McKee (breadth first from a
/// low-degree DOF, neighbours by increasing degree, reversed), each connected part in turn.
fn reverse_cuthill_mckee(system: &System) -> Vec<usize> {
    let n = system.size;
    let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); n];
    for &(i, j, _) in &system.entries {
        if i != j {
            adjacent[i].push(j);
        }
    }
    for a in &mut adjacent {
        a.sort_unstable();
        a.dedup();
    }
    let degree: Vec<usize> = adjacent.iter().map(Vec::len).collect();
    let mut seen = vec![false; n];
    let mut order = Vec::with_capacity(n);
    let mut starts: Vec<usize> = (0..n).collect();
    starts.sort_by_key(|&i| (degree[i], i));
    for start in starts {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        let mut head = order.len();
        order.push(start);
        while head < order.len() {
            let v = order[head];
            head += 1;
            let mut next: Vec<usize> = adjacent[v].iter().copied().filter(|&w| !seen[w]).collect();
            next.sort_by_key(|&w| (degree[w], w));
            for w in next {
                seen[w] = true;
                order.push(w);
            }
        }
    }
    order.reverse();
    order
}
