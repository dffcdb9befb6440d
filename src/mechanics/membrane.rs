//! Beams whose ends cannot move towards each other: for a given axial tension N the deflection
//! obeys EI w'''' − N w'' = q, which is linear in the loads; the von Kármán condition
//! N = (EA/2L)∫₀ᴸ w′² dx then fixes N (docs/mechanics.md §5.4–5.5).
//!
//! Integrating twice, EI w'' − N w = −M₀(x), with M₀ = A + B·x + M_p(x) the moment of the
//! transverse loads alone (Macaulay form, as in `linear.rs`). In span units (ξ = x/L, unit EI,
//! z = kL with k² = N/EI) this is w'' − z² w = −m(ξ). Two exact forms of the same solution are
//! used, each where it cannot lose digits:
//!
//! * z ≤ 1: power series in z², w = v₀ S₀ + θ₀ S₁ − (A S₂ + B S₃) + load terms, with
//!   S_p(ξ) = Σ z^{2m} ξ^{p+2m}/(p+2m)!; at z = 0 these are the polynomials of linear theory;
//! * z > 1: decaying exponentials only, w = C₁ e^{−zξ} + C₂ e^{−z(1−ξ)} + (A + Bξ)/z² + load terms
//!   bounded on the span, so nothing grows like cosh zξ and no large kL overflows.

use super::Support;
use super::linear::{Load, SpanLoads, solve4};

/// Below this z = kL the series form is used, above it the exponential form: on either side
/// the rounding error stays within a few hundred ulps of the deflection (docs/mechanics.md §5.5).
const SERIES_LIMIT: f64 = 1.0;
/// Terms of the S_p series: for z ≤ 1 on [0, 1] the next term is below 1e-19 of the sum.
const SERIES_TERMS: usize = 28;

/// A solved beam under axial tension N = EI k² (k = z/L), for unit EI: evaluate it anywhere on
/// the span with [`TensionBeam::at`].
#[derive(Clone, Debug)]
pub struct TensionBeam {
    length: f64,
    /// z = kL = L √(N/EI).
    z: f64,
    /// Span loads in span units: points (ξ, P), UDLs (ξ₀, ξ₁, q·L).
    points: Vec<(f64, f64)>,
    udls: Vec<(f64, f64, f64)>,
    /// Series form: A, B, θ₀, v₀; exponential form: A, B, C₁, C₂ (span units).
    constants: [f64; 4],
}

/// Deflection and its first two ξ-derivatives at one point (span units, unit EI).
#[derive(Clone, Copy, Debug, Default)]
struct Jet {
    w: f64,
    d1: f64,
    d2: f64,
}

impl Jet {
    fn scaled(self, c: f64) -> Jet {
        Jet {
            w: c * self.w,
            d1: c * self.d1,
            d2: c * self.d2,
        }
    }

    fn add(self, o: Jet) -> Jet {
        Jet {
            w: self.w + o.w,
            d1: self.d1 + o.d1,
            d2: self.d2 + o.d2,
        }
    }
}

/// One station of a tension beam, for unit EI (divide by EI for physical values).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TensionStation {
    /// Deflection for unit EI, positive downward.
    pub v: f64,
    /// dv/dx, the slope (and the section rotation: shear deformation is not modelled).
    pub slope: f64,
    /// Bending moment −EI w'', N·m, sagging positive (independent of EI).
    pub moment: f64,
}

impl TensionBeam {
    /// Solves the beam under tension z = kL for the loads (which must lie on the span). The
    /// support must hold both ends (not a cantilever): clamps give w = w′ = 0, pins w = 0 and
    /// the applied end moment.
    pub fn solve(support: Support, length: f64, loads: &[Load], z: f64) -> TensionBeam {
        let l = length;
        let mut beam = TensionBeam {
            length,
            z,
            points: Vec::new(),
            udls: Vec::new(),
            constants: [0.0; 4],
        };
        // Both ends are held, so a point load at either end goes into its support.
        let SpanLoads {
            points,
            udls,
            end_moments,
            ..
        } = SpanLoads::new(loads, l);
        (beam.points, beam.udls) = (points, udls);
        let rows = [
            beam.boundary(support, 0.0, end_moments.0),
            beam.boundary(support, 1.0, end_moments.1),
        ];
        let mut m = [[0.0; 5]; 4];
        for (i, row) in rows.iter().flatten().enumerate() {
            m[i] = *row;
        }
        beam.constants = solve4(m);
        beam
    }

    /// Solution at x ∈ [0, L] for unit EI.
    pub fn at(&self, x: f64) -> TensionStation {
        let l = self.length;
        let xi = (x / l).clamp(0.0, 1.0);
        let (columns, particular) = self.columns(xi);
        let jet = columns
            .iter()
            .zip(self.constants)
            .fold(particular, |sum, (c, k)| sum.add(c.scaled(k)));
        TensionStation {
            v: jet.w * l.powi(3),
            slope: jet.d1 * l * l,
            moment: -jet.d2 * l,
        }
    }

    fn series(&self) -> bool {
        self.z <= SERIES_LIMIT
    }

    /// The solution at ξ as columns (one per constant) and the particular part of the loads.
    fn columns(&self, xi: f64) -> ([Jet; 4], Jet) {
        if self.series() {
            self.series_columns(xi)
        } else {
            self.exponential_columns(xi)
        }
    }

    /// Series form: A → −S₂, B → −S₃, θ₀ → S₁, v₀ → S₀; a point load P at a adds P·S₃(ξ − a),
    /// a UDL q over [s, e] adds q·(S₄(ξ − s) − S₄(ξ − e)), each zero before its start.
    fn series_columns(&self, xi: f64) -> ([Jet; 4], Jet) {
        let y = self.z * self.z;
        let s = SeriesJets::new(xi, y);
        let columns = [
            s.jet(2).scaled(-1.0),
            s.jet(3).scaled(-1.0),
            s.jet(1),
            s.jet(0),
        ];
        let mut particular = Jet::default();
        for &(a, force) in &self.points {
            if xi > a {
                particular = particular.add(SeriesJets::new(xi - a, y).jet(3).scaled(force));
            }
        }
        for &(start, end, q) in &self.udls {
            for (from, sign) in [(start, 1.0), (end, -1.0)] {
                if xi > from {
                    particular =
                        particular.add(SeriesJets::new(xi - from, y).jet(4).scaled(sign * q));
                }
            }
        }
        (columns, particular)
    }

    /// Exponential form: A → 1/z², B → ξ/z², C₁ → e^{−zξ}, C₂ → e^{−z(1−ξ)}; a point load P at a
    /// adds −P·Y₁(ξ − a), a UDL q over [s, e] adds −q·(Y₂(ξ − s) − Y₂(ξ − e)).
    fn exponential_columns(&self, xi: f64) -> ([Jet; 4], Jet) {
        let z = self.z;
        let z2 = z * z;
        let (left, right) = ((-z * xi).exp(), (-z * (1.0 - xi)).exp());
        let columns = [
            Jet {
                w: 1.0 / z2,
                d1: 0.0,
                d2: 0.0,
            },
            Jet {
                w: xi / z2,
                d1: 1.0 / z2,
                d2: 0.0,
            },
            Jet {
                w: left,
                d1: -z * left,
                d2: z2 * left,
            },
            Jet {
                w: right,
                d1: z * right,
                d2: z2 * right,
            },
        ];
        let mut particular = Jet::default();
        for &(a, force) in &self.points {
            particular = particular.add(bounded_kink(xi - a, z).scaled(-force));
        }
        for &(start, end, q) in &self.udls {
            let step = bounded_bend(xi - start, z).add(bounded_bend(xi - end, z).scaled(-1.0));
            particular = particular.add(step.scaled(-q));
        }
        (columns, particular)
    }

    /// Moment of the transverse loads M_p at ξ (span units), as in the linear solver.
    fn load_moment(&self, xi: f64) -> f64 {
        let points: f64 = self
            .points
            .iter()
            .map(|&(a, force)| -force * (xi - a).max(0.0))
            .sum();
        let udls: f64 = self
            .udls
            .iter()
            .map(|&(s, e, q)| -q * ((xi - s).max(0.0).powi(2) - (xi - e).max(0.0).powi(2)) / 2.0)
            .sum();
        points + udls
    }

    /// The two boundary-condition rows [c₁, c₂, c₃, c₄ | rhs] at the end ξ = e.
    fn boundary(&self, support: Support, e: f64, end_moment: f64) -> [[f64; 5]; 2] {
        let (columns, particular) = self.columns(e);
        let deflection = [
            columns[0].w,
            columns[1].w,
            columns[2].w,
            columns[3].w,
            -particular.w,
        ];
        let slope = [
            columns[0].d1,
            columns[1].d1,
            columns[2].d1,
            columns[3].d1,
            -particular.d1,
        ];
        // At a pin w = 0, so the bending moment −EI w'' equals M₀ = A + B·e + M_p(e).
        let moment = [1.0, e, 0.0, 0.0, end_moment - self.load_moment(e)];
        let clamped = match support {
            Support::FixedFixed => true,
            Support::ProppedCantilever | Support::Cantilever => e == 0.0,
            Support::SimplySupported => false,
        };
        if clamped {
            [deflection, slope]
        } else {
            [deflection, moment]
        }
    }
}

/// S_p(x) = Σ_m y^m x^{p+2m}/(p+2m)! for p = 0…4 at one x (y = z²): S_p″ − y S_p = x^{p−2}/(p−2)!
/// for p ≥ 2, S_p′ = S_{p−1}, S₀′ = y S₁. All terms are positive, so nothing cancels.
struct SeriesJets {
    s: [f64; 5],
    y: f64,
}

impl SeriesJets {
    fn new(x: f64, y: f64) -> SeriesJets {
        // t_k = x^k/k!, then S_p = t_p + y·S_{p+2} summed from the smallest terms up.
        let mut t = [0.0; SERIES_TERMS];
        t[0] = 1.0;
        for k in 1..SERIES_TERMS {
            t[k] = t[k - 1] * x / k as f64;
        }
        let mut sums = [0.0; SERIES_TERMS + 2];
        for k in (0..SERIES_TERMS).rev() {
            sums[k] = t[k] + y * sums[k + 2];
        }
        let mut s = [0.0; 5];
        s.copy_from_slice(&sums[..5]);
        SeriesJets { s, y }
    }

    /// (S_p, S_p′, S_p″).
    fn jet(&self, p: usize) -> Jet {
        let s = |i: isize| -> f64 {
            if i >= 0 {
                self.s[i as usize]
            } else {
                // S₋₁ = S₀′ = y S₁ and S₋₂ = S₀″ = y S₀ close the recursion.
                self.y * self.s[(i + 2) as usize]
            }
        };
        let p = p as isize;
        Jet {
            w: s(p),
            d1: s(p - 1),
            d2: s(p - 2),
        }
    }
}

/// Bounded solution Y₁ of Y″ − z²Y = −⟨d⟩ (a point load's kink), C² at d = 0:
/// d ≥ 0: d/z² + e^{−zd}/(2z³); d < 0: e^{zd}/(2z³).
fn bounded_kink(d: f64, z: f64) -> Jet {
    let (z2, z3) = (z * z, z * z * z);
    let e = (-z * d.abs()).exp();
    if d >= 0.0 {
        Jet {
            w: d / z2 + e / (2.0 * z3),
            d1: 1.0 / z2 - e / (2.0 * z2),
            d2: e / (2.0 * z),
        }
    } else {
        Jet {
            w: e / (2.0 * z3),
            d1: e / (2.0 * z2),
            d2: e / (2.0 * z),
        }
    }
}

/// Bounded solution Y₂ of Y″ − z²Y = −⟨d⟩²/2 (where a distributed load starts), C³ at d = 0:
/// d ≥ 0: d²/(2z²) + 1/z⁴ − e^{−zd}/(2z⁴); d < 0: e^{zd}/(2z⁴).
fn bounded_bend(d: f64, z: f64) -> Jet {
    let (z2, z3, z4) = (z * z, z * z * z, z * z * z * z);
    let e = (-z * d.abs()).exp();
    if d >= 0.0 {
        Jet {
            w: d * d / (2.0 * z2) + 1.0 / z4 - e / (2.0 * z4),
            d1: d / z2 + e / (2.0 * z3),
            d2: 1.0 / z2 - e / (2.0 * z2),
        }
    } else {
        Jet {
            w: e / (2.0 * z4),
            d1: e / (2.0 * z3),
            d2: e / (2.0 * z2),
        }
    }
}

/// ∫ f over [0, L] for a function smooth between `breaks` (which include 0 and L) but with
/// boundary layers of width `layer` at each break (0: none): 16-point Gauss–Legendre on panels
/// that double in width away from every break, `panels` equal panels per interval beyond the
/// layers. Exact for polynomials of degree 31 per panel; for e^{−x/layer} terms the panel
/// error is below 1e-18 of the integral (docs/mechanics.md §5.5).
pub fn integrate(breaks: &[f64], panels: usize, layer: f64, f: impl Fn(f64) -> f64) -> f64 {
    let mut sorted: Vec<f64> = breaks.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    sorted
        .windows(2)
        .map(|w| {
            panel_edges(w[0], w[1], panels, layer)
                .windows(2)
                .map(|p| gauss16(p[0], p[1], &f))
                .sum::<f64>()
        })
        .sum()
}

/// Panel edges on [a, b]: geometric from both ends starting at `layer`, then `panels` equal
/// panels over what remains.
fn panel_edges(a: f64, b: f64, panels: usize, layer: f64) -> Vec<f64> {
    let half = 0.5 * (b - a);
    let mut grading = Vec::new();
    if layer > 0.0 {
        let mut d = layer;
        while d < half {
            grading.push(d);
            d *= 2.0;
        }
    }
    let inner = grading.last().copied().unwrap_or(0.0);
    let mut edges: Vec<f64> = std::iter::once(a)
        .chain(grading.iter().map(|d| a + d))
        .collect();
    let n = panels.max(1);
    let (lo, hi) = (a + inner, b - inner);
    edges.extend((1..n).map(|i| lo + (hi - lo) * i as f64 / n as f64));
    edges.extend(grading.iter().rev().map(|d| b - d));
    edges.push(b);
    edges
}

/// 16-point Gauss–Legendre on [a, b].
fn gauss16(a: f64, b: f64, f: &impl Fn(f64) -> f64) -> f64 {
    const NODES: [(f64, f64); 8] = [
        (0.095_012_509_837_637_44, 0.189_450_610_455_068_64),
        (0.281_603_550_779_258_9, 0.182_603_415_044_923_64),
        (0.458_016_777_657_227_37, 0.169_156_519_395_002_65),
        (0.617_876_244_402_643_8, 0.149_595_988_816_576_7),
        (0.755_404_408_355_003, 0.124_628_971_255_534_07),
        (0.865_631_202_387_831_8, 0.095_158_511_682_492_6),
        (0.944_575_023_073_232_6, 0.062_253_523_938_647_456),
        (0.989_400_934_991_649_9, 0.027_152_459_411_754_176),
    ];
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    half * NODES
        .iter()
        .map(|&(t, w)| w * (f(mid - half * t) + f(mid + half * t)))
        .sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::LinearBeam;
    use Support::*;

    const L: f64 = 4.0;

    fn mixed_loads() -> Vec<Load> {
        vec![
            Load::Point {
                at: 0.3 * L,
                force: 2.0,
            },
            Load::Point {
                at: 0.85 * L,
                force: -0.7,
            },
            Load::Distributed {
                from: 0.1 * L,
                to: 0.6 * L,
                intensity: 1.5,
            },
            Load::EndMoments {
                start: 0.4,
                end: -0.9,
            },
        ]
    }

    fn stations() -> impl Iterator<Item = f64> {
        (0..=40).map(|i| L * f64::from(i) / 40.0)
    }

    #[test]
    fn without_tension_it_is_linear_theory() {
        // z = 0 is the pure-bending limit: the series reduces to the Macaulay polynomials.
        for support in [SimplySupported, FixedFixed, ProppedCantilever] {
            let linear = LinearBeam::solve(support, L, &mixed_loads(), 0.0);
            let scale = linear.natural_deflection();
            for z in [0.0, 1e-9] {
                let tension = TensionBeam::solve(support, L, &mixed_loads(), z);
                for x in stations() {
                    let (a, b) = (tension.at(x), linear.at(x));
                    assert!((a.v - b.v).abs() < 1e-14 * scale, "{support:?} z={z} x={x}");
                    assert!((a.slope - b.slope).abs() < 1e-14 * scale / L);
                    assert!((a.moment - b.moment).abs() < 1e-13 * scale / (L * L));
                }
            }
        }
    }

    #[test]
    fn series_and_exponential_forms_agree_at_the_switch() {
        for support in [SimplySupported, FixedFixed, ProppedCantilever] {
            let series = TensionBeam::solve(support, L, &mixed_loads(), SERIES_LIMIT);
            let above = SERIES_LIMIT * (1.0 + f64::EPSILON);
            let exponential = TensionBeam::solve(support, L, &mixed_loads(), above);
            let scale = (0..=100)
                .map(|i| series.at(L * f64::from(i) / 100.0).v.abs())
                .fold(0.0, f64::max);
            for x in stations() {
                let (a, b) = (series.at(x), exponential.at(x));
                assert!((a.v - b.v).abs() < 1e-12 * scale, "{support:?} x={x}");
                assert!((a.slope - b.slope).abs() < 1e-12 * scale);
                assert!((a.moment - b.moment).abs() < 1e-11 * scale);
            }
        }
    }

    /// Closed forms under a uniform load q with tension N = EI k², u = kL/2, unit EI (derived by
    /// integrating EI w'''' − N w'' = q with the end conditions; the mid-span values are
    /// Timoshenko & Woinowsky-Krieger's f₀(u) and f₁(u) for a strip bent to a cylinder):
    /// pins:   w = q/k⁴ (cosh k(x − L/2)/cosh u − 1) + q x(L − x)/(2k²),
    ///         w(L/2) = (5qL⁴/384)·24(sech u − 1 + u²/2)/(5u⁴);
    /// clamps: w = q x(L − x)/(2k²) + qL (cosh k(x − L/2) − cosh u)/(2k³ sinh u),
    ///         w(L/2) = (qL⁴/384)·24(u²/2 + u/sinh u − u/tanh u)/u⁴.
    fn uniform_load_closed_form(support: Support, k: f64, x: f64) -> f64 {
        let u = 0.5 * k * L;
        let d = x - 0.5 * L;
        let string = x * (L - x) / (2.0 * k * k);
        match support {
            SimplySupported => ((k * d).cosh() / u.cosh() - 1.0) / k.powi(4) + string,
            FixedFixed => string + L * ((k * d).cosh() - u.cosh()) / (2.0 * k.powi(3) * u.sinh()),
            _ => unreachable!(),
        }
    }

    #[test]
    fn uniform_load_matches_the_closed_forms() {
        let udl = [Load::Distributed {
            from: 0.0,
            to: L,
            intensity: 1.0,
        }];
        for support in [SimplySupported, FixedFixed] {
            for z in [0.9, 1.0, 2.5, 10.0, 60.0, 300.0] {
                let k = z / L;
                let beam = TensionBeam::solve(support, L, &udl, z);
                let scale = uniform_load_closed_form(support, k, 0.5 * L);
                for x in stations() {
                    let want = uniform_load_closed_form(support, k, x);
                    let got = beam.at(x).v;
                    assert!(
                        (got - want).abs() < 1e-12 * scale,
                        "{support:?} z={z} x={x}: {got} vs {want}"
                    );
                }
                // Mid-span values in Timoshenko's form.
                let u = 0.5 * z;
                let f = match support {
                    SimplySupported => {
                        24.0 * (1.0 / u.cosh() - 1.0 + u * u / 2.0) / (5.0 * u.powi(4))
                    }
                    _ => 24.0 * (u * u / 2.0 + u / u.sinh() - u / u.tanh()) / u.powi(4),
                };
                let linear = if support == SimplySupported { 5.0 } else { 1.0 } * L.powi(4) / 384.0;
                assert!(
                    (beam.at(0.5 * L).v / (linear * f) - 1.0).abs() < 1e-9,
                    "{support:?} z={z}"
                );
            }
        }
    }

    #[test]
    fn centre_point_load_matches_the_closed_form() {
        // Pins, load P at L/2 under tension: w = P/(2N) (x − sinh kx/(k cosh u)) for x ≤ L/2
        // (unit EI, N = k²).
        let load = [Load::Point {
            at: 0.5 * L,
            force: 1.0,
        }];
        for z in [0.5, 3.0, 40.0, 700.0, 5000.0] {
            let k = z / L;
            let beam = TensionBeam::solve(SimplySupported, L, &load, z);
            let want = |x: f64| {
                // sinh kx / cosh u written with decaying exponentials only (x ≤ L/2).
                let ratio =
                    ((k * x - 0.5 * z).exp() - (-k * x - 0.5 * z).exp()) / (1.0 + (-z).exp());
                (x - ratio / k) / (2.0 * k * k)
            };
            for x in stations().filter(|&x| x <= 0.5 * L) {
                assert!(
                    (beam.at(x).v - want(x)).abs() < 1e-12 * want(0.5 * L),
                    "z={z} x={x}"
                );
            }
        }
    }

    #[test]
    fn huge_tension_is_a_finite_string() {
        // k L = 1e7: the beam is a string, w → q x (L − x)/(2N) except in layers of width 1/k.
        let udl = [Load::Distributed {
            from: 0.0,
            to: L,
            intensity: 1.0,
        }];
        let z = 1e7;
        let k = z / L;
        for support in [SimplySupported, FixedFixed, ProppedCantilever] {
            let beam = TensionBeam::solve(support, L, &udl, z);
            for x in stations() {
                let s = beam.at(x);
                let string = x * (L - x) / (2.0 * k * k);
                assert!(s.v.is_finite() && s.slope.is_finite() && s.moment.is_finite());
                assert!((s.v - string).abs() <= 1e-6 * (0.125 * L * L / (k * k)));
            }
        }
    }

    #[test]
    fn gauss_panels_integrate_polynomials_and_layers() {
        // Degree 31 exactly on one panel; e^{−x/ε} on graded panels to 1e-15.
        let p31 = integrate(&[0.0, 2.0], 1, 0.0, |x| x.powi(31));
        assert!((p31 / (2f64.powi(32) / 32.0) - 1.0).abs() < 1e-14);
        for eps in [1e-3, 1e-7, 1e-12] {
            let got = integrate(&[0.0, 0.3, 1.0], 1, eps, |x| (-x / eps).exp() + 1.0);
            let want = eps * (1.0 - (-1.0 / eps).exp()) + 1.0;
            assert!(
                (got - want).abs() < 1e-15 * want,
                "eps={eps}: {got} vs {want}"
            );
        }
    }
}
