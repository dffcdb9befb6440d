//! Axially restrained beams (docs/mechanics.md §5.4–5.5): the membrane tension a linear
//! solution implies and the error of ignoring it, and the von Kármán solution where that error
//! is too large.

use super::Support;
use super::elastica::illinois;
use super::linear::{LinearBeam, Load, kinks};
use super::membrane::{TensionBeam, integrate};
use super::model::{
    Axis, BeamProblem, Deformation, Labels, Target, Theory, extreme, highest_mode, nonlinearity,
    reach, scaled,
};
use super::{Axial, range};

/// Membrane tension of a restrained snapshot, N = (EA/2L)∫v′², and its energy ratio to bending,
/// N∫v′² / (EI∫v″²): the relative stiffening one-term Galerkin gives for the shape (exact for a
/// sine, docs/mechanics.md §5.4). Panels follow the half-waves of the highest mode.
pub(super) fn modal_membrane(
    p: &BeamProblem,
    slope: &impl Fn(f64) -> f64,
    curvature: &impl Fn(f64) -> f64,
) -> (f64, f64) {
    let (ends, panels) = ([0.0, p.length], 2 * highest_mode(p));
    let slopes = integrate(&ends, panels, 0.0, |x| slope(x).powi(2));
    let bending = integrate(&ends, panels, 0.0, |x| curvature(x).powi(2));
    let force = stretch_force(p, slopes);
    let ei = p.elastic_modulus * p.section.second_moment;
    let error = if bending > 0.0 {
        force * slopes / (ei * bending)
    } else {
        0.0
    };
    (force, error)
}

/// The tension (EA/2L)∫v′² that holding both ends puts into a deflected axis, N.
fn stretch_force(p: &BeamProblem, slope_squared: f64) -> f64 {
    p.elastic_modulus * p.section.area / (2.0 * p.length) * slope_squared
}

/// 0, L, every kink of the loads and `extra`: where piecewise solutions change form.
fn breakpoints(p: &BeamProblem, extra: &[f64]) -> Vec<f64> {
    let mut b = vec![0.0, p.length];
    b.extend(kinks(&p.loads));
    b.extend_from_slice(extra);
    b
}

/// Membrane tension of a restrained linear solution, N = (EA/2L)∫v′², and the relative change
/// of the peak deflection it would cause, exact to first order in N (docs/mechanics.md §5.4):
/// the tension acts on the beam as a transverse load N v″, whose deflection at the peak x_p is,
/// by Maxwell's reciprocity and one integration by parts, −(N/EI)∫g′v′ dx with g the deflection
/// under a unit load at x_p for unit EI (the end terms vanish: g = 0 at both supports).
pub(super) fn linear_membrane(
    p: &BeamProblem,
    beam: &LinearBeam,
    scale: f64,
    flexibility: f64,
    (peak, peak_at): (f64, f64),
) -> (f64, f64) {
    let breaks = breakpoints(p, &[peak_at]);
    let slope = |x: f64| scale * beam.at(x).slope;
    let force = stretch_force(p, integrate(&breaks, 1, 0.0, |x| slope(x).powi(2)));
    let probe = [Load::Point {
        at: peak_at,
        force: 1.0,
    }];
    let unit = LinearBeam::solve(p.support, p.length, &probe, flexibility);
    let coupling = integrate(&breaks, 1, 0.0, |x| unit.at(x).slope * slope(x));
    let ei = p.elastic_modulus * p.section.second_moment;
    let error = if coupling == 0.0 {
        0.0
    } else {
        (force / ei * coupling / peak).abs()
    };
    (force, error)
}

/// The von Kármán beam (docs/mechanics.md §5.5). For a tension N the problem is linear and is
/// solved in closed form; N is then the root of its own stretch, N = (EA/2L)∫w′², found in
/// z = L√(N/EI) by a bracketed search. Targets scale the loads at every N, so the iteration
/// runs with the target held. Shear deformation is not modelled: the linear comparison's shear
/// error is reported instead.
pub(super) fn von_karman(
    p: &BeamProblem,
    xs: &[f64],
    shear_error: f64,
) -> Result<Deformation, String> {
    let l = p.length;
    let ei = p.elastic_modulus * p.section.second_moment;
    let breaks = breakpoints(p, &[]);
    let shape = |z: f64| -> Result<(TensionBeam, f64), String> {
        let beam = TensionBeam::solve(p.support, l, &p.loads, z);
        let factor = tension_factor(p, xs, &beam)?;
        Ok((beam, factor))
    };
    // z² = NL²/EI against (A L / 2I)∫w′², the same equation made dimensionless.
    let stretch = p.section.area * l / (2.0 * p.section.second_moment);
    let residual = |z: f64| match shape(z) {
        Ok((beam, factor)) => {
            let slope = |x: f64| factor / ei * beam.at(x).slope;
            z * z - stretch * integrate(&breaks, 1, boundary_layer(l, z), |x| slope(x).powi(2))
        }
        Err(_) => f64::NAN,
    };
    let z =
        tension_root(residual, range::tension_limit(p)).ok_or_else(|| range::overstretched(p))?;
    let (beam, factor) = shape(z)?;
    let scale = factor / ei;
    let (max_deflection, max_deflection_at) = extreme(xs, l, |x| scale * beam.at(x).v);
    let (max_moment, max_moment_at) = extreme(xs, l, |x| factor * beam.at(x).moment);
    let mut labels = Labels::new(
        p,
        Theory::VonKarman,
        (max_deflection, max_deflection_at),
        (max_moment, max_moment_at),
    );
    labels.shear_error = shear_error;
    labels.nonlinearity_error = nonlinearity(p.support) * (max_deflection / l).powi(2);
    labels.estimated_error = shear_error.max(labels.nonlinearity_error);
    labels.loads = p.loads.iter().map(|ld| scaled(*ld, factor)).collect();
    labels.set_membrane(p, ei * z * z / (l * l));
    Ok(Deformation {
        axis: Axis::Tension { beam, scale },
        labels,
    })
}

/// Width of the boundary layers of a tension beam, 1/k = L/z, where they are thinner than the
/// span (the series form, z ≤ 1, has none).
fn boundary_layer(length: f64, z: f64) -> f64 {
    if z > 1.0 { length / z } else { 0.0 }
}

/// Load factor that makes the tension beam reach the target (1 for physical loads): at a fixed
/// tension the shape does not depend on the load, so a target only scales it.
fn tension_factor(p: &BeamProblem, xs: &[f64], beam: &TensionBeam) -> Result<f64, String> {
    let ei = p.elastic_modulus * p.section.second_moment;
    let peak = || extreme(xs, p.length, |x| beam.at(x).v).0;
    match p.target {
        Target::Physical => Ok(1.0),
        Target::Peak { deflection } => {
            let peak = peak();
            reach(deflection, peak, peak.abs(), None).map(|f| f * ei)
        }
        Target::At { at, deflection } => {
            reach(deflection, beam.at(at).v, peak().abs(), Some(at)).map(|f| f * ei)
        }
    }
}

/// The root z of the von Kármán residual, which grows with z, in [0, z_max]; None when even
/// z_max leaves it negative (the tension needed lies beyond the theory's reach). The bracket is
/// halved from z_max down to within a factor of two of the root before false position runs,
/// so roots many decades below z_max converge as fast as any.
fn tension_root(residual: impl Fn(f64) -> f64, z_max: f64) -> Option<f64> {
    if !(residual(z_max) >= 0.0) {
        return None;
    }
    let mut hi = z_max;
    while hi > NEGLIGIBLE_TENSION && residual(0.5 * hi) > 0.0 {
        hi *= 0.5;
    }
    let lo = if hi > NEGLIGIBLE_TENSION {
        0.5 * hi
    } else {
        0.0
    };
    Some(illinois(residual, lo, hi))
}

/// z = kL below which the tension changes nothing in f64 (relative effect ~ z²/π² < 1e-18).
const NEGLIGIBLE_TENSION: f64 = 1e-9;

/// The axial condition must suit the supports and the theory asked for.
pub(super) fn check_axial(p: &BeamProblem) -> Result<(), String> {
    match (p.axial, p.support, p.theory) {
        (Axial::Restrained, Support::Cantilever, _) => Err(
            "axial \"restrained\" needs both ends held: a cantilever's free end cannot hold the axis"
                .into(),
        ),
        (Axial::Restrained, _, Theory::Elastica) => Err(
            "theory \"elastica\" is the inextensible rod on a roller or a free end and needs axial \"free\"; this beam's axis is restrained"
                .into(),
        ),
        (Axial::Free, _, Theory::VonKarman) => Err(
            "theory \"von_karman\" needs an axially restrained beam (axial \"restrained\", the default for fixed_fixed); this beam's axis is free"
                .into(),
        ),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const E: f64 = 210e9;

    /// A steel beam of span `length` and rectangular `width` × `height`, axis restrained.
    fn beam(support: Support, length: f64, height: f64, loads: Vec<Load>) -> BeamProblem {
        let p = crate::mechanics::model::steel_rectangle(
            support,
            length,
            (0.1, height),
            loads,
            Target::Physical,
        );
        BeamProblem {
            axial: Axial::Restrained,
            ..p
        }
    }

    fn udl(p: &BeamProblem, q: f64) -> Vec<Load> {
        vec![Load::Distributed {
            from: 0.0,
            to: p.length,
            intensity: q,
        }]
    }

    fn ei(p: &BeamProblem) -> f64 {
        E * p.section.second_moment
    }

    /// Closed forms for a uniform load q with tension N = 4EIu²/L² (u = kL/2), derived by
    /// integrating EI w'''' − N w'' = q with the end conditions and then w′² over the span
    /// (the mid-span factors are Timoshenko & Woinowsky-Krieger's f₀(u) and f₁(u) for a strip
    /// bent to a cylinder): (mid-span deflection per unit q, ∫w′² dx per unit q²).
    fn uniform_closed_form(p: &BeamProblem, u: f64) -> (f64, f64) {
        let (l, ei) = (p.length, ei(p));
        match p.support {
            Support::SimplySupported => (
                l.powi(4) * (u * u - 2.0 + 2.0 / u.cosh()) / (32.0 * ei * u.powi(4)),
                l.powi(7)
                    * (2.0 * u.powi(3) - 12.0 * u - 3.0 * u / u.cosh().powi(2) + 15.0 * u.tanh())
                    / (384.0 * ei * ei * u.powi(7)),
            ),
            Support::FixedFixed => (
                l.powi(4) * (u - 2.0 / u.tanh() + 2.0 / u.sinh()) / (32.0 * ei * u.powi(3)),
                l.powi(7)
                    * (2.0 * u * u - 3.0 * (u / u.sinh()).powi(2) - 9.0 * u / u.tanh() + 12.0)
                    / (384.0 * ei * ei * u.powi(6)),
            ),
            _ => unreachable!(),
        }
    }

    #[test]
    fn uniform_load_deflection_relation_matches_the_closed_form() {
        // Pick u, find the load that needs exactly that tension from the closed form
        // (N = (EA/2L)∫w′² with ∫w′² = q²·J(u)), and ask the solver for that load.
        for support in [Support::SimplySupported, Support::FixedFixed] {
            for u in [0.6, 1.5, 4.0, 12.0] {
                let mut p = beam(support, 2.0, 0.05, vec![]);
                let n = 4.0 * ei(&p) * u * u / (p.length * p.length);
                let (w_per_q, j_per_q2) = uniform_closed_form(&p, u);
                let q = (n * 2.0 * p.length / (E * p.section.area * j_per_q2)).sqrt();
                p.loads = udl(&p, q);
                let d = Deformation::solve(&p).unwrap();
                let l = &d.labels;
                assert_eq!(l.theory, Theory::VonKarman, "{support:?} u={u}");
                assert!(
                    (l.membrane_force / n - 1.0).abs() < 1e-9,
                    "{support:?} u={u}"
                );
                assert!((l.max_deflection / (w_per_q * q) - 1.0).abs() < 1e-9);
                assert!((l.max_deflection_at / p.length - 0.5).abs() < 1e-6);
                assert!((l.membrane_stress - n / p.section.area).abs() < 1e-6 * l.membrane_stress);
                // The same deflection as a target gives back the load.
                p.target = Target::Peak {
                    deflection: l.max_deflection,
                };
                p.loads = udl(&p, 1.0);
                let t = Deformation::solve(&p).unwrap().labels;
                let Load::Distributed { intensity, .. } = t.loads[0] else {
                    panic!()
                };
                assert!((intensity / q - 1.0).abs() < 1e-8, "{support:?} u={u}");
                assert!((t.membrane_force / n - 1.0).abs() < 1e-8);
            }
        }
    }

    #[test]
    fn small_deflections_are_linear_theory() {
        // Pure-bending limit: δ/h = 1e-4 stays linear under auto with membrane error
        // 0.7314 (δ/h)² (docs/mechanics.md §5.4), and von Kármán, pinned, gives the same beam.
        let mut p = beam(Support::FixedFixed, 4.0, 0.1, vec![]);
        p.loads = udl(&p, 1.0);
        p.target = Target::Peak { deflection: 1e-5 };
        p.theory = Theory::EulerBernoulli;
        let linear = Deformation::solve(&p).unwrap();
        assert_eq!(linear.labels.theory, Theory::EulerBernoulli);
        assert!((linear.labels.membrane_error / 1e-8 - 0.7314).abs() < 1e-3);
        p.theory = Theory::VonKarman;
        let vk = Deformation::solve(&p).unwrap();
        for i in 0..=20 {
            let x = p.length * f64::from(i) / 20.0;
            assert!((vk.at(x).v - linear.at(x).v).abs() < 1e-8 * 1e-5, "x={x}");
        }
        let load = |d: &Deformation| match d.labels.loads[0] {
            Load::Distributed { intensity, .. } => intensity,
            _ => panic!(),
        };
        // The load the tension saves is the membrane error, to first order.
        let saved = load(&vk) / load(&linear) - 1.0;
        assert!(
            (saved / linear.labels.membrane_error - 1.0).abs() < 1e-3,
            "{saved}"
        );
    }

    #[test]
    fn membrane_error_is_exact_to_first_order() {
        // Coefficients c in δ_linear/δ − 1 ≈ c (δ/h)² under a fixed load, rectangle (derived:
        // docs/mechanics.md §5.4): the estimate from the linear shape, and the relative change
        // von Kármán actually makes at δ/h = 0.01 (under the same physical load; the next term
        // is O(c²(δ/h)⁴)).
        let centre = |p: &BeamProblem| {
            vec![Load::Point {
                at: 0.5 * p.length,
                force: 1.0,
            }]
        };
        let cases: [(Support, bool, f64); 4] = [
            (Support::FixedFixed, true, 0.7314),
            (Support::SimplySupported, true, 3.0340),
            (Support::FixedFixed, false, 0.7200),
            (Support::SimplySupported, false, 2.8800),
        ];
        for (support, distributed, c) in cases {
            let h = 0.01;
            let mut p = beam(support, 20.0, h, vec![]);
            p.loads = if distributed {
                udl(&p, 1.0)
            } else {
                centre(&p)
            };
            p.theory = Theory::EulerBernoulli;
            p.target = Target::Peak {
                deflection: 0.01 * h,
            };
            let linear = Deformation::solve(&p).unwrap();
            let estimate = linear.labels.membrane_error / 1e-4;
            assert!((estimate / c - 1.0).abs() < 2e-4, "{support:?}: {estimate}");
            p.target = Target::Physical;
            p.loads = linear.labels.loads.clone();
            p.theory = Theory::VonKarman;
            let vk = Deformation::solve(&p).unwrap();
            let change = linear.labels.max_deflection / vk.labels.max_deflection - 1.0;
            assert!(
                (change / 1e-4 / c - 1.0).abs() < 1e-3,
                "{support:?}: {change}"
            );
        }
    }

    /// Finite-difference von Kármán solution on `n` intervals (n divisible by 20) for a clamp at
    /// 0 and an immovable pin at L, written as two second-order equations so that it keeps its
    /// digits on fine grids: m″ − (N/EI) m = −q for the bending moment m = −EI w″ (m(L) = 0)
    /// and w″ = −m/EI (w(0) = w(L) = 0), the clamp moment m(0) fixed by w′(0) = 0 through a
    /// ghost node; N by bisection on its own stretch. Second-order accurate. Returns (w at every
    /// node, N).
    fn finite_differences(p: &BeamProblem, n: usize) -> (Vec<f64>, f64) {
        let (l, ei) = (p.length, ei(p));
        let h = l / n as f64;
        let mut load = vec![0.0; n + 1];
        for ld in &p.loads {
            match *ld {
                Load::Point { at, force } => load[(at / h).round() as usize] += force / h,
                Load::Distributed {
                    from,
                    to,
                    intensity,
                } => {
                    let (i0, i1) = ((from / h).round() as usize, (to / h).round() as usize);
                    for (i, q) in load.iter_mut().enumerate().take(i1 + 1).skip(i0) {
                        // Trapezoid weights at the ends of the loaded stretch.
                        *q += if i == i0 || i == i1 { 0.5 } else { 1.0 } * intensity;
                    }
                }
                Load::EndMoments { .. } => unreachable!(),
            }
        }
        // (u_{i−1} − (2 + c h²) u_i + u_{i+1})/h² = f_i for i = 1 … n−1, u_0 and u_n given
        // (Thomas algorithm).
        let second_order = |c: f64, f: &[f64], ends: (f64, f64)| -> Vec<f64> {
            let mut u = vec![0.0; n + 1];
            (u[0], u[n]) = ends;
            let diag = -(2.0 + c * h * h);
            let (mut sub, mut rhs) = (vec![0.0; n], vec![0.0; n]);
            for i in 1..n {
                let mut r = f[i] * h * h - if i == 1 { u[0] } else { 0.0 };
                if i == n - 1 {
                    r -= u[n];
                }
                let (d, prev) = if i == 1 {
                    (diag, 0.0)
                } else {
                    (diag - sub[i - 1], rhs[i - 1])
                };
                sub[i] = 1.0 / d;
                rhs[i] = (r - prev) / d;
            }
            for i in (1..n).rev() {
                u[i] = rhs[i] - if i < n - 1 { sub[i] * u[i + 1] } else { 0.0 };
            }
            u
        };
        let deflection = |tension: f64| -> Vec<f64> {
            let minus_q: Vec<f64> = load.iter().map(|q| -q).collect();
            let zero = vec![0.0; n + 1];
            // m = m_p + M_A m_h; w = w_p + M_A w_h.
            let m_p = second_order(tension / ei, &minus_q, (0.0, 0.0));
            let m_h = second_order(tension / ei, &zero, (1.0, 0.0));
            let curvature = |m: &[f64]| -> Vec<f64> { m.iter().map(|m| -m / ei).collect() };
            let w_p = second_order(0.0, &curvature(&m_p), (0.0, 0.0));
            let w_h = second_order(0.0, &curvature(&m_h), (0.0, 0.0));
            // Clamp: with the ghost w₋₁ = w₁, w″(0) = 2w₁/h² = −M_A/EI.
            let clamp = -2.0 * w_p[1] / (h * h) / (2.0 * w_h[1] / (h * h) + 1.0 / ei);
            w_p.iter().zip(&w_h).map(|(p, q)| p + clamp * q).collect()
        };
        let stretch = |tension: f64| -> f64 {
            let w = deflection(tension);
            let slopes: f64 = w.windows(2).map(|s| ((s[1] - s[0]) / h).powi(2) * h).sum();
            tension - E * p.section.area / (2.0 * l) * slopes
        };
        let (mut lo, mut hi) = (0.0, E * p.section.area);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if stretch(mid) > 0.0 {
                hi = mid
            } else {
                lo = mid
            }
        }
        let tension = 0.5 * (lo + hi);
        (deflection(tension), tension)
    }

    #[test]
    fn asymmetric_loads_match_an_independent_finite_difference_solution() {
        // Propped cantilever with an immovable pin, a point load and a partial UDL, z ≈ 12.
        let mut p = beam(Support::ProppedCantilever, 2.0, 0.02, vec![]);
        p.loads = vec![
            Load::Point {
                at: 0.6,
                force: 3.0e4,
            },
            Load::Distributed {
                from: 1.0,
                to: 1.8,
                intensity: 2.0e4,
            },
        ];
        let d = Deformation::solve(&p).unwrap();
        assert_eq!(d.labels.theory, Theory::VonKarman);
        // Richardson extrapolation of two grids removes the h² error.
        let (w1, n1) = finite_differences(&p, 1000);
        let (w2, n2) = finite_differences(&p, 2000);
        let tension = (4.0 * n2 - n1) / 3.0;
        assert!((d.labels.membrane_force / tension - 1.0).abs() < 1e-9);
        let peak = d.labels.max_deflection;
        for i in 1..20 {
            let x = p.length * i as f64 / 20.0;
            let fd = (4.0 * w2[100 * i] - w1[50 * i]) / 3.0;
            assert!(
                (d.at(x).v - fd).abs() < 1e-8 * peak,
                "x={x}: {} vs {fd}",
                d.at(x).v
            );
        }
    }

    #[test]
    fn huge_deflections_tend_to_a_cable() {
        // L/h = 1000 with δ/h ≈ 35: the beam carries its UDL as a string, N³ = EA q² L²/24 and
        // δ = qL²/(8N); the bending layers at the clamps change this by O(1/(kL)).
        let mut p = beam(Support::FixedFixed, 10.0, 0.01, vec![]);
        let (q, ea) = (2.0e4, E * p.section.area);
        p.loads = udl(&p, q);
        let d = Deformation::solve(&p).unwrap();
        let cable = (ea * q * q * 100.0 / 24.0).cbrt();
        let sag = q * 100.0 / (8.0 * cable);
        let kl = 10.0 * (cable / ei(&p)).sqrt();
        let l = &d.labels;
        assert_eq!(l.theory, Theory::VonKarman);
        assert!(
            (l.membrane_force / cable - 1.0).abs() < 4.0 / kl,
            "{}",
            l.membrane_force
        );
        assert!(
            (l.max_deflection / sag - 1.0).abs() < 4.0 / kl,
            "{}",
            l.max_deflection
        );
        for i in 0..=1000 {
            let a = d.at(10.0 * f64::from(i) / 1000.0);
            assert!(a.v.is_finite() && a.slope.is_finite() && a.slope.abs() <= 0.5);
        }
    }

    #[test]
    fn slender_stocky_and_support_loads_stay_finite() {
        // L/h = 1000 and L/h = 2 under targets; a load on a support; a target beyond reach.
        for (l, h, delta) in [(10.0, 0.01, 0.5), (1.0, 0.5, 0.04)] {
            let mut p = beam(Support::FixedFixed, l, h, vec![]);
            p.loads = udl(&p, 1.0);
            p.theory = Theory::VonKarman;
            p.target = Target::Peak { deflection: delta };
            let d = Deformation::solve(&p).unwrap();
            assert_eq!(d.labels.theory, Theory::VonKarman);
            assert!((d.labels.max_deflection - delta).abs() < 1e-12 * delta);
            assert!(d.labels.estimated_error.is_finite());
        }
        // Stocky: where shear deformation, which von Kármán leaves out, matters more than the
        // tension, auto keeps Timoshenko and reports the membrane error; pinned, von Kármán
        // reports the shear error.
        let mut p = beam(Support::FixedFixed, 1.0, 0.5, vec![]);
        p.loads = udl(&p, 1.0);
        p.target = Target::Peak { deflection: 0.06 };
        let stocky = Deformation::solve(&p).unwrap().labels;
        assert_eq!(stocky.theory, Theory::Timoshenko);
        assert!(stocky.membrane_error > 0.01 && stocky.estimated_error >= stocky.membrane_error);
        p.theory = Theory::VonKarman;
        let pinned = Deformation::solve(&p).unwrap().labels;
        assert!(pinned.shear_error > stocky.membrane_error);
        assert!(pinned.estimated_error >= pinned.shear_error);
        for support in [
            Support::SimplySupported,
            Support::FixedFixed,
            Support::ProppedCantilever,
        ] {
            let mut p = beam(
                support,
                2.0,
                0.1,
                vec![Load::Point {
                    at: 0.0,
                    force: 1e9,
                }],
            );
            for theory in [Theory::Auto, Theory::VonKarman] {
                p.theory = theory;
                let d = Deformation::solve(&p).unwrap();
                assert!(
                    d.labels.max_deflection.abs() < 1e-15 && d.labels.membrane_force.abs() < 1e-9
                );
            }
            p.loads = vec![Load::Point {
                at: 1e-3,
                force: 1e7,
            }];
            let d = Deformation::solve(&p).unwrap();
            assert!(d.labels.max_deflection.is_finite() && d.labels.max_deflection > 0.0);
        }
        let mut p = beam(Support::FixedFixed, 2.0, 0.1, vec![]);
        p.loads = udl(&p, 1.0);
        p.target = Target::Peak { deflection: 1.0 };
        let e = Deformation::solve(&p).unwrap_err();
        assert!(e.contains("membrane strain N/EA above 0.125"), "{e}");
    }

    #[test]
    fn axial_conditions_suit_their_supports_and_theories() {
        let mut p = beam(
            Support::Cantilever,
            2.0,
            0.1,
            vec![Load::Point {
                at: 2.0,
                force: 1.0,
            }],
        );
        assert!(
            Deformation::solve(&p)
                .unwrap_err()
                .contains("a cantilever's free end")
        );
        p.support = Support::SimplySupported;
        p.theory = Theory::Elastica;
        assert!(
            Deformation::solve(&p)
                .unwrap_err()
                .contains("needs axial \"free\"")
        );
        p.axial = Axial::Free;
        p.theory = Theory::VonKarman;
        assert!(
            Deformation::solve(&p)
                .unwrap_err()
                .contains("needs an axially restrained beam")
        );
    }

    #[test]
    fn restrained_vibration_snapshots_report_their_membrane_tension() {
        // Mode 1 of pinned ends, v = A sin(πx/L): N = EA π² A²/(4L²), and the energy ratio is
        // A_s A²/(4I) = 3 (A/h)² for a rectangle (docs/mechanics.md §5.4).
        let mut p = beam(Support::SimplySupported, 4.0, 0.1, vec![]);
        p.vibration = vec![(1, 0.02)];
        let d = Deformation::solve(&p).unwrap();
        let want = E * p.section.area * std::f64::consts::PI.powi(2) * 4e-4 / (4.0 * 16.0);
        assert!((d.labels.membrane_force / want - 1.0).abs() < 1e-12);
        assert!((d.labels.membrane_error / (3.0 * 0.04) - 1.0).abs() < 1e-12);
        assert!(d.labels.estimated_error >= d.labels.membrane_error);
    }
}
