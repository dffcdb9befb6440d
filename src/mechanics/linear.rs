//! Linear beam theory for any support case and any mix of loads: Euler–Bernoulli, or
//! Timoshenko when the shear flexibility is non-zero.
//!
//! The bending moment is written as M(x) = A + B·x + M_p(x), with M_p the Macaulay terms of
//! the span loads; bending rotation and deflection follow by integration:
//!   ψ(x) = ψ₀ − (1/EI)∫₀ˣ M,   v(x) = v₀ + ∫₀ˣ ψ + (M(x) − M(0))/(κGA).
//! The four unknowns (A, B, ψ₀, v₀) come from the two boundary conditions at each end.
//! Everything is solved in span units (ξ = x/L, loads rescaled), so the 4×4 system is well
//! conditioned for any length. v is positive downward; M is sagging-positive; V = dM/dx.

use super::Support;
use serde::Serialize;

/// A load on the span, in physical units (N, N/m, N·m), downward and sagging positive.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Load {
    /// A point force.
    Point {
        /// Where it acts: distance along the axis from x = 0, metres (0 to L).
        at: f64,
        /// Force, N, positive downward.
        force: f64,
    },
    /// A uniformly distributed load over part or all of the span.
    Distributed {
        /// Where it starts: distance along the axis from x = 0, metres.
        from: f64,
        /// Where it ends, metres (greater than `from`, at most L).
        to: f64,
        /// Load per unit length, N/m, positive downward.
        intensity: f64,
    },
    /// End moments, sagging positive (M(0) = start, M(L) = end where the end can rotate).
    EndMoments {
        /// Moment applied at x = 0, N·m, sagging positive (no effect where that end is clamped).
        start: f64,
        /// Moment applied at x = L, N·m, sagging positive (no effect where that end is clamped).
        end: f64,
    },
}

impl Load {
    /// Whether every number of the load is finite.
    pub fn is_finite(&self) -> bool {
        match *self {
            Load::Point { at, force } => at.is_finite() && force.is_finite(),
            Load::Distributed {
                from,
                to,
                intensity,
            } => from.is_finite() && to.is_finite() && intensity.is_finite(),
            Load::EndMoments { start, end } => start.is_finite() && end.is_finite(),
        }
    }
}

/// Positions on the span where the loads put kinks into the deflected shape: stations there
/// keep every mesh vertex on the exact curve.
pub fn kinks(loads: &[Load]) -> Vec<f64> {
    let mut k = Vec::new();
    for load in loads {
        match *load {
            Load::Point { at, .. } => k.push(at),
            Load::Distributed { from, to, .. } => k.extend([from, to]),
            Load::EndMoments { .. } => {}
        }
    }
    k
}

/// One station of a linear solution, for unit EI (divide by EI for physical values).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Station {
    /// Deflection for unit EI (divide by EI for metres), positive downward.
    pub v: f64,
    /// dv/dx, the slope of the axis.
    pub slope: f64,
    /// ψ, the bending rotation of the section (equals the slope without shear).
    pub rotation: f64,
    /// Bending moment M, N·m, sagging positive (independent of EI).
    pub moment: f64,
    /// Shear force V = dM/dx, N (independent of EI).
    pub shear: f64,
}

/// A solved linear beam (Euler–Bernoulli, or Timoshenko with shear flexibility), for unit EI:
/// evaluate it anywhere on the span with [`LinearBeam::at`].
#[derive(Clone, Debug)]
pub struct LinearBeam {
    length: f64,
    /// Span loads in span units: points (ξ, P), UDLs (ξ₀, ξ₁, q·L).
    points: Vec<(f64, f64)>,
    udls: Vec<(f64, f64, f64)>,
    /// EI/(κGA) / L², zero for Euler–Bernoulli.
    shear: f64,
    /// A, B, ψ₀, v₀ in span units.
    constants: [f64; 4],
    /// Σ|end force| + Σ|end moment|/L, for the natural deflection scale.
    end_scale: f64,
}

impl LinearBeam {
    /// `shear_flexibility` = EI/(κGA) in m² (0 for Euler–Bernoulli). Loads must lie on the span.
    pub fn solve(
        support: Support,
        length: f64,
        loads: &[Load],
        shear_flexibility: f64,
    ) -> LinearBeam {
        let l = length;
        let mut beam = LinearBeam {
            length,
            points: Vec::new(),
            udls: Vec::new(),
            shear: shear_flexibility / (l * l),
            constants: [0.0; 4],
            end_scale: 0.0,
        };
        let SpanLoads {
            points,
            udls,
            end_force,
            end_moments,
        } = SpanLoads::new(loads, l);
        (beam.points, beam.udls) = (points, udls);
        beam.end_scale = end_force.abs() + end_moments.0.abs() + end_moments.1.abs();
        let rows = [
            boundary(support, 0.0, &beam, 0.0, end_moments.0),
            boundary(support, 1.0, &beam, end_force, end_moments.1),
        ];
        let mut m = [[0.0; 5]; 4];
        for (i, row) in rows.iter().flatten().enumerate() {
            m[i] = *row;
        }
        beam.constants = solve4(m);
        beam
    }

    /// The deflection scale of the loads for unit EI (Σ|P|L³ + Σ|q|L⁴ + Σ|M|L²): a deflection
    /// far below it is round-off.
    pub fn natural_deflection(&self) -> f64 {
        let l3 = self.length.powi(3);
        (self.points.iter().map(|p| p.1.abs()).sum::<f64>()
            + self.udls.iter().map(|u| u.2.abs()).sum::<f64>()
            + self.end_scale)
            * l3
    }

    /// Solution at x ∈ [0, L] for unit EI: v in m per (N·m²/EI) etc.
    pub fn at(&self, x: f64) -> Station {
        let l = self.length;
        let xi = (x / l).clamp(0.0, 1.0);
        let [a, b, psi0, v0] = self.constants;
        let p = self.particular(xi);
        let moment = a + b * xi + p.m;
        let rotation = psi0 - (a * xi + b * xi * xi / 2.0 + p.im);
        let v = v0 + psi0 * xi - (a * xi * xi / 2.0 + b * xi.powi(3) / 6.0 + p.iim)
            + self.shear * (b * xi + p.m - self.particular(0.0).m);
        let shear = b + p.dm;
        let slope = rotation + self.shear * shear;
        // Back to physical units: ξ-space quantities carry powers of L.
        Station {
            v: v * l.powi(3),
            slope: slope * l * l,
            rotation: rotation * l * l,
            moment: moment * l,
            shear,
        }
    }

    /// Macaulay terms of the span loads at ξ: M_p, ∫M_p, ∫∫M_p and dM_p/dξ (from the left).
    fn particular(&self, xi: f64) -> Particular {
        let mut p = Particular::default();
        for &(a, force) in &self.points {
            let d = (xi - a).max(0.0);
            p.m -= force * d;
            p.im -= force * d * d / 2.0;
            p.iim -= force * d.powi(3) / 6.0;
            if xi > a {
                p.dm -= force;
            }
        }
        for &(s, e, q) in &self.udls {
            let (ds, de) = ((xi - s).max(0.0), (xi - e).max(0.0));
            p.m -= q * (ds * ds - de * de) / 2.0;
            p.im -= q * (ds.powi(3) - de.powi(3)) / 6.0;
            p.iim -= q * (ds.powi(4) - de.powi(4)) / 24.0;
            p.dm -= q * (ds - de);
        }
        p
    }
}

#[derive(Default)]
struct Particular {
    m: f64,
    im: f64,
    iim: f64,
    dm: f64,
}

/// The two boundary-condition rows [A, B, ψ₀, v₀ | rhs] at the end ξ = e.
fn boundary(
    support: Support,
    e: f64,
    beam: &LinearBeam,
    end_force: f64,
    end_moment: f64,
) -> [[f64; 5]; 2] {
    let p = beam.particular(e);
    let p0 = beam.particular(0.0);
    let s = beam.shear;
    let deflection = [
        -e * e / 2.0,
        -e.powi(3) / 6.0 + s * e,
        e,
        1.0,
        p.iim - s * (p.m - p0.m),
    ];
    let rotation = [-e, -e * e / 2.0, 1.0, 0.0, p.im];
    let moment = [1.0, e, 0.0, 0.0, end_moment - p.m];
    let shear = [0.0, 1.0, 0.0, 0.0, end_force - p.dm];
    use Support::*;
    let start = e == 0.0;
    match (support, start) {
        (Cantilever | FixedFixed | ProppedCantilever, true) | (FixedFixed, false) => {
            [deflection, rotation]
        }
        (SimplySupported, _) | (ProppedCantilever, false) => [deflection, moment],
        (Cantilever, false) => [moment, shear],
    }
}

/// Gaussian elimination with partial pivoting on an augmented 4×5 matrix.
/// Loads in span units (ξ = x/L), as the solvers take them.
pub(super) struct SpanLoads {
    /// Point loads strictly inside the span: (ξ, P).
    pub points: Vec<(f64, f64)>,
    /// Distributed loads: (ξ₀, ξ₁, q·L).
    pub udls: Vec<(f64, f64, f64)>,
    /// The point force exactly at x = L: it enters through that end's boundary condition
    /// (a free end's shear), not as a span term.
    pub end_force: f64,
    /// End moments at x = 0 and x = L, divided by L.
    pub end_moments: (f64, f64),
}

impl SpanLoads {
    /// `loads` on a span of `length` metres.
    pub fn new(loads: &[Load], length: f64) -> SpanLoads {
        let l = length;
        let mut span = SpanLoads {
            points: Vec::new(),
            udls: Vec::new(),
            end_force: 0.0,
            end_moments: (0.0, 0.0),
        };
        for load in loads {
            match *load {
                Load::Point { at, force } if at >= l => span.end_force += force,
                // Every support holds x = 0: a load there goes straight into it and bends
                // nothing. Kept out of the span terms, its reaction does not show as a shear
                // slope P/(κGA) at x = 0 either.
                Load::Point { at, .. } if at <= 0.0 => {}
                Load::Point { at, force } => span.points.push((at / l, force)),
                Load::Distributed {
                    from,
                    to,
                    intensity,
                } => span.udls.push((from / l, to / l, intensity * l)),
                Load::EndMoments { start, end } => {
                    span.end_moments.0 += start / l;
                    span.end_moments.1 += end / l;
                }
            }
        }
        span
    }
}

pub(super) fn solve4(mut m: [[f64; 5]; 4]) -> [f64; 4] {
    for col in 0..4 {
        let pivot = (col..4)
            .max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))
            .unwrap();
        m.swap(col, pivot);
        let pivot_row = m[col];
        for row in &mut m[col + 1..] {
            let f = row[col] / pivot_row[col];
            for (entry, &p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                *entry -= f * p;
            }
        }
    }
    let mut x = [0.0; 4];
    for row in (0..4).rev() {
        let sum: f64 = (row + 1..4).map(|k| m[row][k] * x[k]).sum();
        x[row] = (m[row][4] - sum) / m[row][row];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use Support::*;

    const L: f64 = 4.0;

    fn v(support: Support, loads: &[Load], x: f64) -> f64 {
        LinearBeam::solve(support, L, loads, 0.0).at(x).v
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1e-300)
    }

    #[test]
    fn point_load_closed_forms() {
        // Classical closed forms, docs/mechanics.md §2.2 (e.g. Gere & Goodno); unit EI.
        let (p, a) = (3.0, 1.1);
        let b = L - a;
        let loads = [Load::Point { at: a, force: p }];
        for i in 0..=40 {
            let x = L * f64::from(i) / 40.0;
            let ss = if x <= a {
                p * b * x * (L * L - b * b - x * x) / (6.0 * L)
            } else {
                let xb = L - x;
                p * a * xb * (L * L - a * a - xb * xb) / (6.0 * L)
            };
            let cant = if x <= a {
                p * x * x * (3.0 * a - x) / 6.0
            } else {
                p * a * a * (3.0 * x - a) / 6.0
            };
            let ff = if x <= a {
                p * b * b * x * x * (3.0 * a * L - (3.0 * a + b) * x) / (6.0 * L.powi(3))
            } else {
                let (xb, aa, bb) = (L - x, b, a);
                p * bb * bb * xb * xb * (3.0 * aa * L - (3.0 * aa + bb) * xb) / (6.0 * L.powi(3))
            };
            let r = p * a * a * (3.0 * L - a) / (2.0 * L.powi(3));
            let propped = cant - r * x * x * (3.0 * L - x) / 6.0;
            for (support, want) in [
                (SimplySupported, ss),
                (Cantilever, cant),
                (FixedFixed, ff),
                (ProppedCantilever, propped),
            ] {
                let got = v(support, &loads, x);
                assert!(
                    (got - want).abs() < 1e-12 * p * L.powi(3),
                    "{support:?} x={x}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn tip_load_on_the_free_end() {
        let s = LinearBeam::solve(Cantilever, L, &[Load::Point { at: L, force: 2.0 }], 0.0);
        assert!(close(s.at(L).v, 2.0 * L.powi(3) / 3.0, 1e-13));
        assert!(close(s.at(L).slope, 2.0 * L * L / 2.0, 1e-13));
        assert!(
            close(s.at(0.0).moment, -2.0 * L, 1e-13),
            "hogging moment at the clamp"
        );
    }

    #[test]
    fn distributed_load_closed_forms() {
        let q = 1.7;
        let udl = [Load::Distributed {
            from: 0.0,
            to: L,
            intensity: q,
        }];
        for i in 0..=20 {
            let x = L * f64::from(i) / 20.0;
            let cases = [
                (
                    SimplySupported,
                    q * x * (L - x) * (L * L + L * x - x * x) / 24.0,
                ),
                (
                    Cantilever,
                    q * x * x * (6.0 * L * L - 4.0 * L * x + x * x) / 24.0,
                ),
                (FixedFixed, q * x * x * (L - x).powi(2) / 24.0),
                (
                    ProppedCantilever,
                    q * x * x * (L - x) * (3.0 * L - 2.0 * x) / 48.0,
                ),
            ];
            for (support, want) in cases {
                let got = v(support, &udl, x);
                assert!(
                    (got - want).abs() < 1e-12 * q * L.powi(4),
                    "{support:?} x={x}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn end_moments_and_partial_loads() {
        // SS with end moments: v = [M_A x(L−x)(2L−x) + M_B x(L−x)(L+x)]/(6L)
        // (docs/mechanics.md §2.2).
        let (ma, mb) = (1.3, -0.4);
        let loads = [Load::EndMoments { start: ma, end: mb }];
        for i in 0..=10 {
            let x = L * f64::from(i) / 10.0;
            let want = (ma * x * (L - x) * (2.0 * L - x) + mb * x * (L - x) * (L + x)) / (6.0 * L);
            assert!(
                (v(SimplySupported, &loads, x) - want).abs() < 1e-13,
                "x={x}"
            );
        }
        // Cantilever tip moment: v = M x²/2, but with M sagging-positive at the free end the
        // beam curves upward: v = −M x²/2.
        assert!(close(
            v(
                Cantilever,
                &[Load::EndMoments {
                    start: 0.0,
                    end: 2.0
                }],
                L
            ),
            -2.0 * L * L / 2.0,
            1e-13
        ));
        // A partial UDL equals the superposition of two full-span-from-s loads.
        let part = [Load::Distributed {
            from: 1.0,
            to: 3.0,
            intensity: 2.0,
        }];
        let diff = [
            Load::Distributed {
                from: 1.0,
                to: L,
                intensity: 2.0,
            },
            Load::Distributed {
                from: 3.0,
                to: L,
                intensity: -2.0,
            },
        ];
        for support in [SimplySupported, Cantilever, FixedFixed, ProppedCantilever] {
            assert!((v(support, &part, 2.2) - v(support, &diff, 2.2)).abs() < 1e-12);
        }
    }

    #[test]
    fn combined_loads_superpose() {
        // Linear theory: the solution for several loads is the sum of the single-load solutions,
        // with and without shear flexibility.
        let loads = [
            Load::Point {
                at: 0.9,
                force: 2.0,
            },
            Load::Point {
                at: 3.2,
                force: -0.7,
            },
            Load::Distributed {
                from: 0.5,
                to: 2.5,
                intensity: 1.3,
            },
            Load::EndMoments {
                start: 0.4,
                end: -0.6,
            },
        ];
        for support in [SimplySupported, Cantilever, FixedFixed, ProppedCantilever] {
            for flex in [0.0, 0.05] {
                let all = LinearBeam::solve(support, L, &loads, flex);
                let parts: Vec<LinearBeam> = loads
                    .iter()
                    .map(|l| LinearBeam::solve(support, L, &[*l], flex))
                    .collect();
                for i in 0..=16 {
                    let x = L * f64::from(i) / 16.0;
                    let sum: f64 = parts.iter().map(|b| b.at(x).v).sum();
                    let msum: f64 = parts.iter().map(|b| b.at(x).moment).sum();
                    assert!(
                        (all.at(x).v - sum).abs() < 1e-12
                            && (all.at(x).moment - msum).abs() < 1e-12,
                        "{support:?} x={x}"
                    );
                }
            }
        }
    }

    #[test]
    fn maxwell_betti_reciprocity() {
        // Deflection at j from a unit load at i equals deflection at i from a unit load at j.
        for support in [SimplySupported, Cantilever, FixedFixed, ProppedCantilever] {
            for &(i, j) in &[(0.7, 3.1), (1.9, 2.4), (0.2, 3.9)] {
                let vij = v(support, &[Load::Point { at: i, force: 1.0 }], j);
                let vji = v(support, &[Load::Point { at: j, force: 1.0 }], i);
                // f64 round-off of the Macaulay form near a support: ~1e-12 relative.
                assert!(
                    (vij - vji).abs() < 1e-11 * vij.abs().max(1e-3),
                    "{support:?} {i},{j}: {vij} vs {vji}"
                );
            }
        }
    }

    #[test]
    fn equilibrium_and_symmetry() {
        // Shear jumps by the load; the moment is the integral of the shear.
        let loads = [
            Load::Point {
                at: 1.5,
                force: 4.0,
            },
            Load::Distributed {
                from: 0.0,
                to: L,
                intensity: 0.5,
            },
        ];
        for support in [SimplySupported, Cantilever, FixedFixed, ProppedCantilever] {
            let s = LinearBeam::solve(support, L, &loads, 0.0);
            let jump = s.at(1.5 - 1e-9).shear - s.at(1.5 + 1e-9).shear;
            assert!((jump - 4.0).abs() < 1e-6, "{support:?} jump {jump}");
            let h = 1e-6;
            let dm = (s.at(2.5 + h).moment - s.at(2.5 - h).moment) / (2.0 * h);
            assert!((dm - s.at(2.5).shear).abs() < 1e-6, "{support:?}");
        }
        // Symmetric beam, symmetric load: symmetric deflection.
        for support in [SimplySupported, FixedFixed] {
            let s = LinearBeam::solve(
                support,
                L,
                &[Load::Point {
                    at: L / 2.0,
                    force: 1.0,
                }],
                0.0,
            );
            for x in [0.3, 1.0, 1.7] {
                assert!((s.at(x).v - s.at(L - x).v).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn timoshenko_matches_the_published_shear_factors() {
        // δ_T/δ_EB = 1 + c(h/L)² with Φ = 12 EI/(κGA L²) (docs/mechanics.md §4.3): SS centre 1 + Φ,
        // cantilever tip 1 + Φ/4, SS UDL 1 + 0.8Φ, fixed–fixed centre 1 + 4Φ.
        let flex = 0.02 * L * L; // EI/(κGA) = Φ L²/12 with Φ = 0.24
        let phi = 12.0 * 0.02;
        let cases = [
            (
                SimplySupported,
                Load::Point {
                    at: L / 2.0,
                    force: 1.0,
                },
                L / 2.0,
                1.0 + phi,
            ),
            (
                Cantilever,
                Load::Point { at: L, force: 1.0 },
                L,
                1.0 + phi / 4.0,
            ),
            (
                SimplySupported,
                Load::Distributed {
                    from: 0.0,
                    to: L,
                    intensity: 1.0,
                },
                L / 2.0,
                1.0 + 0.8 * phi,
            ),
            (
                FixedFixed,
                Load::Point {
                    at: L / 2.0,
                    force: 1.0,
                },
                L / 2.0,
                1.0 + 4.0 * phi,
            ),
        ];
        for (support, load, x, ratio) in cases {
            let eb = LinearBeam::solve(support, L, &[load], 0.0).at(x).v;
            let t = LinearBeam::solve(support, L, &[load], flex).at(x).v;
            assert!(
                close(t / eb, ratio, 1e-12),
                "{support:?}: {} vs {ratio}",
                t / eb
            );
        }
        // Sections rotate by the bending rotation only: the clamp keeps ψ = 0 while the axis slopes.
        let s = LinearBeam::solve(Cantilever, L, &[Load::Point { at: L, force: 1.0 }], flex);
        assert!(s.at(0.0).rotation.abs() < 1e-14 && s.at(0.0).slope > 0.0);
    }
}
