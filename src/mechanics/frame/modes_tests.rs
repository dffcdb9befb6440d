//! The natural modes of whole frames against closed forms: beams modelled as chains of members
//! converge to the Euler–Bernoulli frequencies at the rate the Hermite elements promise, a
//! bar's axial modes bracket from above (consistent mass) and below (lumped), a portal with a
//! rigid girder on massless columns sways at √(24 E I / (h³ M)); the modes are M-orthonormal
//! and solve K φ = ω² M φ; moving and turning the model changes no frequency; snapshots draw
//! the mode shape and refuse what they cannot draw.

use super::tests::space_frame;
use super::*;
use crate::mechanics::{ModeShape, Support};
use glam::{DMat3, DVec3};
use std::f64::consts::PI;

/// β₁L and β₂L of a cantilever (roots of cos βL cosh βL = −1).
const CANTILEVER_BETA_L: [f64; 2] = [1.875_104_068_711_961, 4.694_091_132_974_175];

/// A 10 m plane (x–z) beam of `n` equal members of a 0.1 × 0.2 m steel rectangle (height
/// along z), held as `ends` says, and its (E I / (ρ A L⁴))^½.
pub(super) fn chain(n: usize, ends: Support) -> (FrameModel, f64) {
    let length = 10.0;
    let section = Section::Rectangle {
        width: 0.1,
        height: 0.2,
    };
    let mut m = FrameModel::new();
    m.nodes = (0..=n)
        .map(|i| [length * i as f64 / n as f64, 0.0, 0.0])
        .collect();
    m.members = (0..n)
        .map(|i| Member::new(i, i + 1, section.clone()))
        .collect();
    m.plane = Some(Plane::Xz);
    m.supports = match ends {
        Support::SimplySupported => vec![NodeSupport::pinned(0), NodeSupport::roller(n)],
        Support::Cantilever => vec![NodeSupport::fixed(0)],
        other => panic!("no chain for {other:?}"),
    };
    let (area, inertia) = (0.1 * 0.2, 0.1 * 0.2f64.powi(3) / 12.0);
    let scale = (STEEL_E * inertia / (STEEL_DENSITY * area * length.powi(4))).sqrt();
    (m, scale)
}

/// Relative error of the lowest frequencies of a chain of `n` members against (β_k L)² scale.
fn chain_errors(n: usize, ends: Support, beta_l: &[f64]) -> Vec<f64> {
    let (m, scale) = chain(n, ends);
    let modes = m.natural_modes(beta_l.len()).unwrap();
    beta_l
        .iter()
        .zip(&modes.omega)
        .map(|(b, w)| w / (b * b * scale) - 1.0)
        .collect()
}

#[test]
fn beams_of_frame_members_converge_to_the_euler_bernoulli_frequencies() {
    // Hermite cubics with the consistent mass: Rayleigh–Ritz, so every frequency is above the
    // exact one, and the error falls as h⁴ (16× a halving; asked at least 10×), its leading
    // term (β h)⁴ / 1440 for a member of length h.
    let cases: [(Support, Vec<f64>); 2] = [
        (Support::SimplySupported, vec![PI, 2.0 * PI, 3.0 * PI]),
        (Support::Cantilever, CANTILEVER_BETA_L.to_vec()),
    ];
    for (ends, beta_l) in cases {
        let mut previous: Option<Vec<f64>> = None;
        for n in [4, 8, 16] {
            let errors = chain_errors(n, ends, &beta_l);
            for (k, e) in errors.iter().enumerate() {
                assert!(*e > 0.0, "{ends:?} n = {n} mode {}: error {e}", k + 1);
                if let Some(p) = &previous {
                    assert!(
                        *e < p[k] / 10.0,
                        "{ends:?} n = {n} mode {}: {e} after {}",
                        k + 1,
                        p[k]
                    );
                }
            }
            previous = Some(errors);
        }
        // Sixteen members: the error is the cubic element's leading term (βh)⁴/1440, h = L/16,
        // within 5 % (1e-6 for the fundamental of the simply supported beam).
        let last = previous.unwrap();
        for (k, e) in last.iter().enumerate() {
            let leading = (beta_l[k] / 16.0).powi(4) / 1440.0;
            assert!(
                (e / leading - 1.0).abs() < 0.05,
                "{ends:?} mode {}: {e} vs {leading}",
                k + 1
            );
        }
    }
}

/// A fixed–free steel bar of `n` members along x, only its axial DOFs free.
fn axial_bar(n: usize, mass: MassMatrix) -> FrameModel {
    let mut m = FrameModel::new();
    m.nodes = (0..=n).map(|i| [2.0 * i as f64, 0.0, 0.0]).collect();
    let tube = Section::CircularHollow {
        diameter: 0.2,
        wall: 0.01,
    };
    m.members = (0..n)
        .map(|i| Member::new(i, i + 1, tube.clone()))
        .collect();
    m.supports = (1..=n)
        .map(|i| NodeSupport::new(i, "guide", [false, true, true, true, true, true]))
        .collect();
    m.supports.push(NodeSupport::fixed(0));
    m.mass_matrix = mass;
    m
}

#[test]
fn axial_modes_of_a_fixed_free_bar_are_bracketed_by_consistent_and_lumped_mass() {
    // ω_k = (2k − 1) π / (2L) √(E/ρ); linear elements err as h² (4× a halving), the consistent
    // mass from above, the lumped mass from below.
    for (mass, above) in [(MassMatrix::Consistent, true), (MassMatrix::Lumped, false)] {
        let mut previous: Option<Vec<f64>> = None;
        for n in [8, 16, 32] {
            let length = 2.0 * n as f64;
            let modes = axial_bar(n, mass).natural_modes(3).unwrap();
            let errors: Vec<f64> = (1..=3)
                .map(|k| {
                    let exact =
                        (2 * k - 1) as f64 * PI / (2.0 * length) * (STEEL_E / STEEL_DENSITY).sqrt();
                    modes.omega[k - 1] / exact - 1.0
                })
                .collect();
            for (k, e) in errors.iter().enumerate() {
                assert_eq!(*e > 0.0, above, "{mass:?} n = {n} mode {}: {e}", k + 1);
                if let Some(p) = &previous {
                    let ratio = p[k] / e;
                    assert!(
                        (3.5..4.5).contains(&ratio),
                        "{mass:?} n = {n} mode {}: ratio {ratio}",
                        k + 1
                    );
                }
            }
            previous = Some(errors);
        }
    }
}

#[test]
fn a_portal_with_a_rigid_girder_on_massless_columns_sways_at_the_closed_form() {
    // ω² = 24 E I_c / (h³ M) for fixed bases and a girder that neither bends nor stretches:
    // here I_b/I_c = 10⁶ (the finite girder lowers the stiffness by ~1e-6) and the columns'
    // axial shortening is ~I/(A h²) = 4e-7 of the sway.
    let (h, span, girder_mass) = (40.0, 60.0, 2.0e4);
    let column = Section::Rectangle {
        width: 0.2,
        height: 0.1,
    };
    let girder = Section::Rectangle {
        width: 0.2,
        height: 10.0,
    };
    let mut m = FrameModel::new();
    m.nodes = vec![[0.0; 3], [0.0, 0.0, h], [span, 0.0, h], [span, 0.0, 0.0]];
    m.members = vec![
        Member::new(0, 1, column.clone()),
        Member::new(1, 2, girder),
        Member::new(3, 2, column),
    ];
    for member in &mut m.members {
        member.density = 0.0;
    }
    m.masses = [1, 2]
        .map(|node| NodalMass {
            node,
            mass: girder_mass / 2.0,
            inertia: [0.0; 3],
        })
        .to_vec();
    m.supports = vec![NodeSupport::fixed(0), NodeSupport::fixed(3)];
    m.plane = Some(Plane::Xz);
    let i_c = 0.2 * 0.1f64.powi(3) / 12.0;
    let exact = (24.0 * STEEL_E * i_c / (h.powi(3) * girder_mass)).sqrt();
    for mass in [MassMatrix::Consistent, MassMatrix::Lumped] {
        m.mass_matrix = mass;
        let modes = m.natural_modes(1).unwrap();
        assert!(
            (modes.omega[0] / exact - 1.0).abs() < 1e-5,
            "{mass:?}: {} vs {exact}",
            modes.omega[0]
        );
        // The whole girder mass sways: effective mass along x = M.
        assert!((modes.effective_mass[0][0] / girder_mass - 1.0).abs() < 1e-5);
    }
}

/// The physical M and K on the free DOFs of `m`.
fn matrices(m: &FrameModel) -> (Vec<usize>, nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>) {
    let elements = m.elements().unwrap();
    let assembled = solve::assemble(m, &elements).unwrap();
    let scaled_mass = m
        .scaled_mass(&elements, &assembled.free, &assembled.scale)
        .dense();
    let scaled_stiffness = assembled.system.dense(0.0);
    let s = &assembled.scale;
    let unscale = |a: nalgebra::DMatrix<f64>| {
        nalgebra::DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)] / (s[i] * s[j]))
    };
    (
        assembled.free,
        unscale(scaled_mass),
        unscale(scaled_stiffness),
    )
}

#[test]
fn modes_are_mass_orthonormal_and_solve_the_eigenproblem() {
    let mut m = space_frame();
    m.masses.push(NodalMass {
        node: 4,
        mass: 500.0,
        inertia: [20.0, 30.0, 40.0],
    });
    let count = 10;
    let modes = m.natural_modes(count).unwrap();
    let (free, mass, stiffness) = matrices(&m);
    let vector = |k: usize| {
        nalgebra::DVector::from_iterator(
            free.len(),
            free.iter().map(|&d| modes.shapes[k][d / 6][d % 6]),
        )
    };
    for i in 0..count {
        let phi = vector(i);
        let residual = &stiffness * &phi - &mass * &phi * modes.omega[i].powi(2);
        let size = (&stiffness * &phi).amax();
        assert!(residual.amax() < 1e-8 * size, "mode {i}");
        for j in 0..count {
            let product = phi.dot(&(&mass * vector(j)));
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((product - want).abs() < 1e-9, "modes {i}, {j}: {product}");
        }
    }
    assert!(modes.omega.windows(2).all(|w| w[0] <= w[1]));
}

#[test]
fn effective_masses_of_all_modes_add_up_to_the_moving_mass() {
    // Completeness: Σ_k (φ_kᵀ M r)² = rᵀ M r for M-orthonormal φ_k spanning the free DOFs.
    let (m, _) = chain(4, Support::SimplySupported);
    let dofs = 4 + 3 + 5; // ux of nodes 1–4, uz of 1–3, ry of all five
    let modes = m.natural_modes(dofs).unwrap();
    for k in [0, 2] {
        let sum: f64 = modes.effective_mass.iter().map(|e| e[k]).sum();
        assert!(
            (sum / modes.moving_mass[k] - 1.0).abs() < 1e-9,
            "axis {k}: {sum} vs {}",
            modes.moving_mass[k]
        );
    }
    assert!(
        m.natural_modes(dofs + 1)
            .unwrap_err()
            .contains("only 12 modes")
    );
}

#[test]
fn moving_and_turning_the_model_changes_no_frequency() {
    let m = space_frame();
    let turn = DMat3::from_rotation_z(0.7);
    let shift = DVec3::new(1e4, -2e4, 300.0);
    let mut moved = m.clone();
    for p in &mut moved.nodes {
        *p = (turn * DVec3::from_array(*p) + shift).to_array();
    }
    let (a, b) = (m.natural_modes(8).unwrap(), moved.natural_modes(8).unwrap());
    for (x, y) in a.omega.iter().zip(&b.omega) {
        assert!((x / y - 1.0).abs() < 1e-9, "{x} vs {y}");
    }
}

/// A cantilever chain of `n` members drawing its first mode at `amplitude`.
fn cantilever_snapshot(n: usize, amplitude: f64) -> (FrameModel, FrameSolution) {
    let (mut m, _) = chain(n, Support::Cantilever);
    m.vibration = vec![(1, amplitude)];
    let s = m.solve().unwrap();
    (m, s)
}

/// Largest distance between the snapshot's axis and A φ₁(x/L) of the beam module's cantilever.
fn shape_error(n: usize, amplitude: f64) -> f64 {
    let (m, s) = cantilever_snapshot(n, amplitude);
    let exact = ModeShape::new(Support::Cantilever, 1);
    let tip_sign = exact.at(1.0).0.signum();
    let mut worst = 0.0f64;
    for member in 0..m.members.len() {
        let start = m.nodes[m.members[member].start][0];
        for i in 0..=20 {
            let x = s.member_length(member) * i as f64 / 20.0;
            let (u, _) = s.member_at(member, x);
            let want = amplitude * tip_sign * exact.at((start + x) / 10.0).0;
            worst = worst.max((u - DVec3::new(0.0, 0.0, want)).length());
        }
    }
    worst
}

#[test]
fn a_snapshot_draws_the_mode_shape_inside_the_members() {
    // The cantilever's first mode, drawn through the members' cubic fields, approaches the
    // closed-form shape as members are added (h⁴ at the nodes; inside a member the static
    // cubic differs from the dynamic shape by O((βh)⁴)).
    let amplitude = 0.3;
    let errors: Vec<f64> = [2, 4, 8]
        .iter()
        .map(|&n| shape_error(n, amplitude))
        .collect();
    assert!(
        errors[1] < errors[0] / 8.0 && errors[2] < errors[1] / 8.0,
        "{errors:?}"
    );
    assert!(errors[2] < 1e-5 * amplitude, "{errors:?}");
    // Its largest translation is the amplitude, at the tip, upward; the labels say so.
    let (m, s) = cantilever_snapshot(8, amplitude);
    let labels = FrameLabels::new(&s);
    assert_eq!(labels.analysis, "vibration_snapshot");
    assert!((labels.max_displacement / amplitude - 1.0).abs() < 1e-12);
    assert!((s.nodes[8].displacement[2] / amplitude - 1.0).abs() < 1e-12);
    let modal = labels.modes.unwrap();
    let modes = m.natural_modes(6).unwrap();
    assert_eq!(modal.frequencies.len(), 6);
    assert_eq!(modal.snapshot[0].frequency, modes.omega[0] / (2.0 * PI));
    assert_eq!(modal.snapshot[0].amplitude, amplitude);
}

#[test]
fn a_snapshot_refuses_loads_and_modes_the_model_lacks() {
    let (mut m, _) = cantilever_snapshot(2, 0.1);
    m.vibration = vec![(99, 0.1)];
    let e = m.solve().unwrap_err();
    assert!(e.contains("mode 99 was asked for"), "{e}");
    m.vibration = vec![(1, 0.1)];
    m.self_weight = true;
    let e = m.solve().unwrap_err();
    assert!(
        e.contains("either static loads or a vibration snapshot"),
        "{e}"
    );
    m.self_weight = false;
    m.masses.push(NodalMass {
        node: 1,
        mass: -1.0,
        inertia: [0.0; 3],
    });
    let e = m.solve().unwrap_err();
    assert!(e.contains("the mass on node 1"), "{e}");
}

#[test]
fn subspace_iteration_finds_the_dense_eigensolvers_modes() {
    // A space chain (both bending planes, torsion, axial) small enough for both paths.
    let (mut m, _) = chain(30, Support::Cantilever);
    m.plane = None;
    let elements = m.elements().unwrap();
    let assembled = solve::assemble(&m, &elements).unwrap();
    let mass = m.scaled_mass(&elements, &assembled.free, &assembled.scale);
    let dense = modes::dense_modes(&assembled.system, &mass, &assembled.free, 8).unwrap();
    let subspace = modes::subspace_modes(&assembled.system, &mass, &assembled.free, 8).unwrap();
    for ((w_dense, phi_dense), (w_sub, phi_sub)) in dense.iter().zip(&subspace) {
        assert!(
            (w_sub / w_dense - 1.0).abs() < 1e-10,
            "{w_sub} vs {w_dense}"
        );
        // Mass-normalised shapes agree up to sign.
        let same = (phi_sub - phi_dense)
            .amax()
            .min((phi_sub + phi_dense).amax());
        assert!(same < 1e-5 * phi_dense.amax(), "{same}");
    }
}

#[test]
fn a_chain_above_the_dense_limit_vibrates_at_the_euler_bernoulli_frequencies() {
    // 600 members in the x–z plane: 1,801 free DOFs, beyond `DENSE_MODES_MAX_DOFS`, so the
    // modes come from subspace iteration. At h = L/600 the discretisation error (βh)⁴/1440 is
    // 5e-13, below round-off: K's condition grows as n⁴, and the dense path's error is already
    // 2e-8 at 390 members, 3e-9 at 200.
    let (m, scale) = chain(600, Support::SimplySupported);
    let modes = m.natural_modes(3).unwrap();
    for (k, w) in modes.omega.iter().enumerate() {
        let exact = ((k + 1) as f64 * PI).powi(2) * scale;
        assert!(
            (w / exact - 1.0).abs() < 1e-6,
            "mode {}: {w} vs {exact}",
            k + 1
        );
    }
}
