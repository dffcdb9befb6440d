//! Free-vibration mode shapes of a uniform Euler–Bernoulli beam.
//!
//! Owns: the eigenvalues λ_n = β_nL and the mode shapes φ_n(ξ), ξ = x/L, with their first two
//! derivatives in ξ, for four support cases, normalised to max |φ| = 1 on [0, 1]. Must not touch:
//! meshes, cameras or files; it works on the dimensionless coordinate alone and knows nothing of
//! the beam's length, section or material (ω_n = λ_n² √(EI/(ρA L⁴)) is the caller's business).
//!
//! Formulas: `docs/mechanics.md` §7 (after Tang 2003). The textbook clamped-end mode
//! cosh λξ − cos λξ − σ(sinh λξ − sin λξ) subtracts numbers of size e^λ to leave a result of
//! size 1, so in f64 it is useless from mode 13 on and NaN from mode 227. Every case clamped at
//! ξ = 0 is written instead as the exact rewrite
//!
//! ```text
//! φ(ξ) = ½(1 + σ) e^{−λξ} + ½(1 − σ) e^{λ} e^{−λ(1−ξ)} − cos λξ + σ sin λξ
//! ```
//!
//! with σ and ½(1 − σ) e^λ computed from e^{−λ} only, so no exponential ever grows and the
//! exponentially small 1 − σ is never formed by subtraction. The eigenvalues solve the
//! characteristic equations divided by cosh λ, which leaves bounded, well-conditioned functions,
//! by Newton from their asymptotes.

use super::Support;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// One vibration mode, ready to be evaluated anywhere on the span.
///
/// Normalisation: max |φ| over [0, 1] is 1. Sign: φ is positive just right of ξ = 0 (its first
/// non-vanishing derivative there is positive), so every mode starts with a positive lobe.
#[derive(Clone, Debug)]
pub struct ModeShape {
    terms: Terms,
}

impl ModeShape {
    /// Mode `n` of a beam with the given supports, counted from 1.
    ///
    /// Panics if `n` is 0. Costs a root solve and a search for the peak over the end zones
    /// (a few hundred evaluations, independent of `n`).
    pub fn new(ends: Support, n: u32) -> ModeShape {
        assert!(n >= 1, "vibration modes are numbered from 1");
        let lambda = eigenvalue(ends, n);
        let shape = unnormalised(ends, lambda);
        // sin λξ peaks at exactly 1 at ξ = 1/(2n); the clamped cases have to be searched.
        let peak = match ends {
            Support::SimplySupported => 1.0,
            _ => peak_magnitude(&shape),
        };
        ModeShape {
            terms: shape.scaled(1.0 / peak),
        }
    }

    /// The eigenvalue β_nL (ω_n = (β_nL)² √(EI/(ρA L⁴))).
    pub fn beta_l(&self) -> f64 {
        self.terms.lambda
    }

    /// (φ, dφ/dξ, d²φ/dξ²) at ξ = x/L ∈ [0, 1]. Outside that range the formula is continued
    /// analytically and grows like e^{λ|ξ|}; callers should not ask there.
    pub fn at(&self, xi: f64) -> (f64, f64, f64) {
        let [phi, slope, curvature, _] = self.terms.eval(xi);
        (phi, slope, curvature)
    }
}

/// φ(ξ) = p e^{−λξ} + q e^{−λ(1−ξ)} + c cos λξ + s sin λξ.
///
/// On [0, 1] each term is bounded by its coefficient, so evaluation cannot overflow or cancel
/// beyond the size of the coefficients, whatever λ is.
#[derive(Clone, Copy, Debug)]
struct Terms {
    lambda: f64,
    p: f64,
    q: f64,
    c: f64,
    s: f64,
}

impl Terms {
    /// [φ, φ′, φ″, φ‴] at ξ, derivatives in ξ.
    fn eval(&self, xi: f64) -> [f64; 4] {
        let l = self.lambda;
        let t = l * xi;
        let (sin, cos) = t.sin_cos();
        let left = self.p * (-t).exp();
        // 1 − ξ is exact for ξ ≥ ½, which keeps the right-end boundary layer accurate.
        let right = self.q * (-l * (1.0 - xi)).exp();
        let wave = self.c * cos + self.s * sin;
        let wave_slope = self.s * cos - self.c * sin;
        [
            left + right + wave,
            l * (right - left + wave_slope),
            l * l * (left + right - wave),
            l * l * l * (right - left - wave_slope),
        ]
    }

    fn scaled(&self, factor: f64) -> Terms {
        Terms {
            lambda: self.lambda,
            p: factor * self.p,
            q: factor * self.q,
            c: factor * self.c,
            s: factor * self.s,
        }
    }
}

/// The mode before normalisation: sin λξ, or the clamped-at-0 form of the module comment.
fn unnormalised(ends: Support, lambda: f64) -> Terms {
    match ends {
        Support::SimplySupported => Terms {
            lambda,
            p: 0.0,
            q: 0.0,
            c: 0.0,
            s: 1.0,
        },
        Support::Cantilever => clamped_at_zero(lambda, RightEnd::Free),
        Support::FixedFixed | Support::ProppedCantilever => {
            clamped_at_zero(lambda, RightEnd::Supported)
        }
    }
}

/// The right-end condition used to fix σ: φ″(1) = 0 at a free end, φ(1) = 0 at a supported one.
/// (The second right-end condition is what the eigenvalue satisfies.)
#[derive(Clone, Copy)]
enum RightEnd {
    Free,
    Supported,
}

/// cosh λξ − cos λξ − σ(sinh λξ − sin λξ), with σ = (cosh λ ± cos λ)/(sinh λ ± sin λ)
/// (+ for a free right end, − for a supported one), in bounded form.
///
/// Multiplying numerator and denominator of σ by 2e^{−λ} leaves only e = e^{−λ} ≤ 1. Then
/// 1 − σ = 2e(±(sin λ − cos λ) − e)/den exactly, so the coefficient of the right-end boundary
/// layer, ½(1 − σ)e^λ, is (±(sin λ − cos λ) − e)/den without any cancellation.
fn clamped_at_zero(lambda: f64, right_end: RightEnd) -> Terms {
    let sign = match right_end {
        RightEnd::Free => 1.0,
        RightEnd::Supported => -1.0,
    };
    let e = (-lambda).exp();
    let (sin, cos) = lambda.sin_cos();
    // den ≥ 1 − e² − 2e > 0.67 for every eigenvalue (λ ≥ 1.87).
    let den = 1.0 - e * e + 2.0 * sign * e * sin;
    let sigma = (1.0 + e * e + 2.0 * sign * e * cos) / den;
    Terms {
        lambda,
        p: 0.5 * (1.0 + sigma),
        q: (sign * (sin - cos) - e) / den,
        c: -1.0,
        s: sigma,
    }
}

/// λ_n = β_nL, the n-th positive root of the case's characteristic equation.
///
/// Each equation is divided by cosh λ so that it stays bounded; the roots then sit close to the
/// zeros of a trigonometric function, and the first correction of that asymptote starts Newton
/// within 6 % for n = 1 and to full precision from n ≈ 10 on.
fn eigenvalue(ends: Support, n: u32) -> f64 {
    let n_odd = n % 2 == 1;
    let n = f64::from(n);
    let alternating = if n_odd { 1.0 } else { -1.0 };
    match ends {
        Support::SimplySupported => n * PI,
        Support::Cantilever => {
            // cos λ cosh λ = −1  ⇔  cos λ + sech λ = 0.
            let x0 = (2.0 * n - 1.0) * FRAC_PI_2;
            let start = x0 + alternating * 2.0 * (-x0).exp();
            newton(start, |x| {
                let (sech, tanh) = sech_tanh(x);
                (x.cos() + sech, -x.sin() - sech * tanh)
            })
        }
        Support::FixedFixed => {
            // cos λ cosh λ = 1  ⇔  cos λ − sech λ = 0.
            let x0 = (2.0 * n + 1.0) * FRAC_PI_2;
            let start = x0 + alternating * 2.0 * (-x0).exp();
            newton(start, |x| {
                let (sech, tanh) = sech_tanh(x);
                (x.cos() - sech, -x.sin() + sech * tanh)
            })
        }
        Support::ProppedCantilever => {
            // tan λ = tanh λ  ⇔  sin λ − cos λ tanh λ = 0, free of the poles of tan.
            let x0 = n * PI + FRAC_PI_4;
            let start = x0 - (-2.0 * x0).exp();
            newton(start, |x| {
                let (sech, tanh) = sech_tanh(x);
                let (sin, cos) = x.sin_cos();
                (sin - cos * tanh, cos + sin * tanh - cos * sech * sech)
            })
        }
    }
}

/// (sech x, tanh x) for x ≥ 0 from e^{−x}, so neither overflows.
fn sech_tanh(x: f64) -> (f64, f64) {
    let e = (-x).exp();
    let e2 = e * e;
    (2.0 * e / (1.0 + e2), (1.0 - e2) / (1.0 + e2))
}

/// Newton's method on a function given as x ↦ (f, f′), from a start inside the root's basin.
fn newton(start: f64, f: impl Fn(f64) -> (f64, f64)) -> f64 {
    let mut x = start;
    for _ in 0..50 {
        let (value, slope) = f(x);
        let step = value / slope;
        x -= step;
        // Below two ulps the iterate only dithers in the last bit.
        if step.abs() <= 2.0 * f64::EPSILON * x.abs() {
            break;
        }
    }
    x
}

/// How many half-waves from each end are searched for the peak. Beyond them the boundary layers
/// have decayed below e^{−4π} ≈ 3.5e-6 of their coefficients.
const END_ZONE_HALF_WAVES: f64 = 4.0;
/// Sampling density of the peak search; fine enough that each lobe's top is bracketed by its
/// neighbouring samples and the refinement starts inside its basin.
const SAMPLES_PER_HALF_WAVE: f64 = 16.0;

/// max |φ| over [0, 1].
///
/// Away from both ends φ is a sinusoid of amplitude √(c² + s²) plus boundary layers that have
/// decayed, so the peak is searched only near the ends: the search costs the same for every n.
/// The middle is searched too whenever the bound on it does not rule it out, which keeps the
/// result exact for any coefficients (and covers low modes, where the end zones overlap anyway).
fn peak_magnitude(terms: &Terms) -> f64 {
    let zone = END_ZONE_HALF_WAVES * PI / terms.lambda;
    if 2.0 * zone >= 1.0 {
        return largest_magnitude_on(terms, 0.0, 1.0);
    }
    let ends =
        largest_magnitude_on(terms, 0.0, zone).max(largest_magnitude_on(terms, 1.0 - zone, 1.0));
    let decayed = (-terms.lambda * zone).exp();
    let middle_bound = terms.c.hypot(terms.s) + (terms.p.abs() + terms.q.abs()) * decayed;
    if ends >= middle_bound {
        ends
    } else {
        ends.max(largest_magnitude_on(terms, zone, 1.0 - zone))
    }
}

/// max |φ| over [lo, hi]: dense samples, then every sampled local maximum refined to the
/// stationary point it brackets.
fn largest_magnitude_on(terms: &Terms, lo: f64, hi: f64) -> f64 {
    let intervals = ((hi - lo) * terms.lambda / PI * SAMPLES_PER_HALF_WAVE)
        .ceil()
        .max(1.0) as usize;
    let xs: Vec<f64> = (0..=intervals)
        .map(|i| lo + (hi - lo) * i as f64 / intervals as f64)
        .collect();
    let magnitudes: Vec<f64> = xs.iter().map(|&x| terms.eval(x)[0].abs()).collect();
    let mut best = magnitudes.iter().copied().fold(0.0, f64::max);
    for i in 0..=intervals {
        let (before, after) = (i.saturating_sub(1), (i + 1).min(intervals));
        let is_local_max =
            magnitudes[before] <= magnitudes[i] && magnitudes[after] <= magnitudes[i];
        if is_local_max && let Some(x) = stationary_point(terms, xs[before], xs[after]) {
            best = best.max(terms.eval(x)[0].abs());
        }
    }
    best
}

/// The zero of φ′ in [a, b], if φ′ changes sign there: Newton on φ′, falling back to bisection
/// whenever a step would leave the bracket.
fn stationary_point(terms: &Terms, mut a: f64, mut b: f64) -> Option<f64> {
    let slope_at_a = terms.eval(a)[1];
    if slope_at_a * terms.eval(b)[1] >= 0.0 {
        return None;
    }
    let mut x = 0.5 * (a + b);
    for _ in 0..100 {
        let [_, slope, curvature, _] = terms.eval(x);
        if (slope > 0.0) == (slope_at_a > 0.0) {
            a = x;
        } else {
            b = x;
        }
        let newton = x - slope / curvature;
        let next = if newton > a.min(b) && newton < a.max(b) {
            newton
        } else {
            0.5 * (a + b)
        };
        let done = (next - x).abs() <= 4.0 * f64::EPSILON;
        x = next;
        if done {
            break;
        }
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Support; 4] = [
        Support::SimplySupported,
        Support::Cantilever,
        Support::FixedFixed,
        Support::ProppedCantilever,
    ];
    const CLAMPED: [Support; 3] = [
        Support::Cantilever,
        Support::FixedFixed,
        Support::ProppedCantilever,
    ];

    /// Double-double arithmetic (≈ 32 significant digits): enough to evaluate the textbook
    /// cosh/sinh forms for λ ≤ 40 without their f64 cancellation, as independent truth.
    mod dd {
        #[derive(Clone, Copy, Debug)]
        pub struct Dd(pub f64, pub f64);

        fn two_sum(a: f64, b: f64) -> (f64, f64) {
            let s = a + b;
            let bb = s - a;
            (s, (a - (s - bb)) + (b - bb))
        }

        fn quick_two_sum(a: f64, b: f64) -> Dd {
            let s = a + b;
            Dd(s, b - (s - a))
        }

        /// π/2 to double-double precision.
        const HALF_PI: Dd = Dd(std::f64::consts::FRAC_PI_2, 6.123233995736766e-17);

        impl Dd {
            pub fn new(x: f64) -> Dd {
                Dd(x, 0.0)
            }
            pub fn to_f64(self) -> f64 {
                self.0 + self.1
            }
            pub fn neg(self) -> Dd {
                Dd(-self.0, -self.1)
            }
            pub fn add(self, o: Dd) -> Dd {
                let (s, e) = two_sum(self.0, o.0);
                let (t, f) = two_sum(self.1, o.1);
                let r = quick_two_sum(s, e + t);
                quick_two_sum(r.0, r.1 + f)
            }
            pub fn sub(self, o: Dd) -> Dd {
                self.add(o.neg())
            }
            pub fn mul(self, o: Dd) -> Dd {
                let p = self.0 * o.0;
                let e = self.0.mul_add(o.0, -p) + (self.0 * o.1 + self.1 * o.0);
                quick_two_sum(p, e)
            }
            pub fn scale(self, k: f64) -> Dd {
                self.mul(Dd::new(k))
            }
            pub fn div(self, o: Dd) -> Dd {
                let q1 = self.0 / o.0;
                let r = self.sub(o.scale(q1));
                let q2 = r.0 / o.0;
                let r = r.sub(o.scale(q2));
                let q3 = r.0 / o.0;
                quick_two_sum(q1, q2).add(Dd::new(q3))
            }

            /// e^x by Taylor series on x/4096, squared back twelve times (|x| ≲ 700).
            pub fn exp(self) -> Dd {
                let r = Dd(self.0 / 4096.0, self.1 / 4096.0);
                let (mut sum, mut term) = (Dd::new(1.0), Dd::new(1.0));
                for j in 1..30 {
                    term = term.mul(r).div(Dd::new(j as f64));
                    sum = sum.add(term);
                }
                (0..12).fold(sum, |acc, _| acc.mul(acc))
            }

            /// (sin x, cos x) after reduction by the nearest multiple of π/2.
            pub fn sin_cos(self) -> (Dd, Dd) {
                let k = (self.0 / HALF_PI.0).round();
                let r = self.sub(HALF_PI.scale(k));
                let r2 = r.mul(r);
                let (mut sin, mut cos) = (r, Dd::new(1.0));
                let (mut s_term, mut c_term) = (r, Dd::new(1.0));
                for j in 1..30 {
                    let j = j as f64;
                    s_term = s_term.mul(r2).div(Dd::new(-(2.0 * j) * (2.0 * j + 1.0)));
                    c_term = c_term.mul(r2).div(Dd::new(-(2.0 * j - 1.0) * (2.0 * j)));
                    sin = sin.add(s_term);
                    cos = cos.add(c_term);
                }
                match (k as i64).rem_euclid(4) {
                    0 => (sin, cos),
                    1 => (cos, sin.neg()),
                    2 => (sin.neg(), cos.neg()),
                    _ => (cos.neg(), sin),
                }
            }

            pub fn cosh_sinh(self) -> (Dd, Dd) {
                let up = self.exp();
                let down = Dd::new(1.0).div(up);
                (up.add(down).scale(0.5), up.sub(down).scale(0.5))
            }
        }
    }
    use dd::Dd;

    /// The textbook mode cosh λξ − cos λξ − σ(sinh λξ − sin λξ) in double-double, σ from φ″(1) = 0
    /// (free right end) or φ(1) = 0 (supported right end), unnormalised.
    fn textbook_dd(lambda: f64, xi: f64, free_right_end: bool) -> f64 {
        let l = Dd::new(lambda);
        let (ch_l, sh_l) = l.cosh_sinh();
        let (s_l, c_l) = l.sin_cos();
        let sigma = if free_right_end {
            ch_l.add(c_l).div(sh_l.add(s_l))
        } else {
            ch_l.sub(c_l).div(sh_l.sub(s_l))
        };
        let t = l.mul(Dd::new(xi));
        let (ch, sh) = t.cosh_sinh();
        let (s, c) = t.sin_cos();
        ch.sub(c).sub(sigma.mul(sh.sub(s))).to_f64()
    }

    /// The same textbook mode in plain f64, as it is usually coded.
    fn textbook_f64(lambda: f64, xi: f64) -> f64 {
        let sigma = (lambda.cosh() + lambda.cos()) / (lambda.sinh() + lambda.sin());
        let t = lambda * xi;
        t.cosh() - t.cos() - sigma * (t.sinh() - t.sin())
    }

    /// Characteristic function in textbook (cosh-multiplied) form and its derivative, in
    /// double-double, so that f/f′ at a candidate root measures its distance to the true root.
    fn characteristic_dd(ends: Support, x: f64) -> (f64, f64) {
        let x = Dd::new(x);
        let (ch, sh) = x.cosh_sinh();
        let (s, c) = x.sin_cos();
        let one = Dd::new(1.0);
        let (f, df) = match ends {
            // cos x cosh x + 1, derivative cos x sinh x − sin x cosh x.
            Support::Cantilever => (c.mul(ch).add(one), c.mul(sh).sub(s.mul(ch))),
            // cos x cosh x − 1.
            Support::FixedFixed => (c.mul(ch).sub(one), c.mul(sh).sub(s.mul(ch))),
            // sin x cosh x − cos x sinh x = cos x cosh x (tan x − tanh x), derivative 2 sin x sinh x.
            Support::ProppedCantilever => (s.mul(ch).sub(c.mul(sh)), s.mul(sh).scale(2.0)),
            Support::SimplySupported => (s, c),
        };
        (f.to_f64(), df.to_f64())
    }

    /// Distance of x from the nearest root, from one double-double Newton step.
    fn root_error_dd(ends: Support, x: f64) -> f64 {
        let (f, df) = characteristic_dd(ends, x);
        (f / df).abs()
    }

    fn relative(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn cantilever_roots_match_high_precision_values() {
        // Roots of cos λ cosh λ = −1 computed with 80–250-digit arithmetic
        // (docs/mechanics.md §7.2), written with the reference's digits.
        #[expect(
            clippy::excessive_precision,
            reason = "the digits are the reference's; each literal parses to its nearest double"
        )]
        let roots = [
            1.8751040687119612,
            4.6940911329741746,
            7.8547574382376126,
            10.995540734875467,
            14.137168391046471,
            17.278759532088236,
            20.420352251041251,
            23.561944901806444,
            26.703537555518299,
            29.845130209102817,
        ];
        for (i, &root) in roots.iter().enumerate() {
            let n = i as u32 + 1;
            let lambda = ModeShape::new(Support::Cantilever, n).beta_l();
            // Tolerance 1e-15 relative: the solver should land on the root's nearest double.
            assert!(
                relative(lambda, root) <= 1e-15,
                "n = {n}: {lambda} vs {root}"
            );
            // The quoted values themselves are roots to their 17 printed digits.
            assert!(root_error_dd(Support::Cantilever, root) <= 4e-15, "n = {n}");
        }
    }

    #[test]
    fn fixed_fixed_and_propped_roots_match_published_values() {
        let published = [
            (
                Support::FixedFixed,
                [4.730040744862704, 7.853204624095838, 10.99560783800167],
            ),
            (
                Support::ProppedCantilever,
                [3.926602312047919, 7.068582745628732, 10.21017612281303],
            ),
        ];
        for (ends, roots) in published {
            for (i, &root) in roots.iter().enumerate() {
                // Verify the published value from the characteristic equation itself (double-double,
                // so cos x cosh x ∓ 1 does not cancel): it is a root to its 16 printed digits.
                assert!(
                    root_error_dd(ends, root) <= 1e-14,
                    "{ends:?} published root {root}"
                );
                let lambda = ModeShape::new(ends, i as u32 + 1).beta_l();
                // Tolerance 1e-14 relative: the published digits limit the comparison.
                assert!(
                    relative(lambda, root) <= 1e-14,
                    "{ends:?} n = {}: {lambda} vs {root}",
                    i + 1
                );
            }
        }
    }

    #[test]
    fn roots_are_exact_to_the_last_bits() {
        // Double-double residual of the cosh-multiplied equation, converted to a distance in x;
        // tolerance 2 ε λ (about two ulps). λ ≤ 630 keeps cosh λ inside the f64 range.
        for ends in CLAMPED {
            for n in (1..=20).chain([50, 99, 100, 150, 200]) {
                let lambda = ModeShape::new(ends, n).beta_l();
                let error = root_error_dd(ends, lambda);
                assert!(
                    error <= 2.0 * f64::EPSILON * lambda,
                    "{ends:?} n = {n}: {error:e}"
                );
            }
        }
    }

    #[test]
    fn roots_follow_their_asymptotes() {
        // Asymptote x0 + δ1; the next term is O(δ1²), so tolerance 4 ε x + 10 δ1².
        let asymptote = |ends, n: u32| -> (f64, f64) {
            let sign = if n % 2 == 1 { 1.0 } else { -1.0 };
            let n = f64::from(n);
            let (x0, delta) = match ends {
                Support::Cantilever => {
                    let x0 = (2.0 * n - 1.0) * FRAC_PI_2;
                    (x0, sign * 2.0 * (-x0).exp())
                }
                Support::FixedFixed => {
                    let x0 = (2.0 * n + 1.0) * FRAC_PI_2;
                    (x0, sign * 2.0 * (-x0).exp())
                }
                Support::ProppedCantilever => {
                    let x0 = (4.0 * n + 1.0) * FRAC_PI_4;
                    (x0, -(-2.0 * x0).exp())
                }
                Support::SimplySupported => (n * PI, 0.0),
            };
            (x0 + delta, delta)
        };
        for ends in ALL {
            for n in (2..=60).chain([99, 100, 227, 500, 1000, 10_000, u32::MAX]) {
                let lambda = ModeShape::new(ends, n).beta_l();
                let (expected, delta) = asymptote(ends, n);
                let tolerance = 4.0 * f64::EPSILON * expected + 10.0 * delta * delta;
                assert!(
                    (lambda - expected).abs() <= tolerance,
                    "{ends:?} n = {n}: {lambda} vs {expected}"
                );
            }
        }
    }

    /// Largest |value| of the named derivatives, each divided by λ^k so that all are O(1).
    fn boundary_residual(mode: &ModeShape, xi: f64, orders: &[usize]) -> f64 {
        let values = mode.terms.eval(xi);
        orders
            .iter()
            .map(|&k| (values[k] / mode.beta_l().powi(k as i32)).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn boundary_conditions_hold() {
        // Orders of the derivatives that vanish at ξ = 0 and ξ = 1. Tolerance 1e-12 on φ^(k)/λ^k
        // (φ normalised), for the free end including φ‴ from the analytic third derivative.
        let conditions = |ends| -> (&[usize], &[usize]) {
            match ends {
                Support::SimplySupported => (&[0, 2], &[0, 2]),
                Support::Cantilever => (&[0, 1], &[2, 3]),
                Support::FixedFixed => (&[0, 1], &[0, 1]),
                Support::ProppedCantilever => (&[0, 1], &[0, 2]),
            }
        };
        for ends in ALL {
            let (left, right) = conditions(ends);
            for n in [1, 2, 10, 50, 100] {
                let mode = ModeShape::new(ends, n);
                let residual =
                    boundary_residual(&mode, 0.0, left).max(boundary_residual(&mode, 1.0, right));
                assert!(residual <= 1e-12, "{ends:?} n = {n}: residual {residual:e}");
            }
            // Beyond n = 100 the rounding of λξ (ulp(λ) ≈ 2e-13 λ/1000) dominates; still small.
            let mode = ModeShape::new(ends, 1000);
            let residual =
                boundary_residual(&mode, 0.0, left).max(boundary_residual(&mode, 1.0, right));
            assert!(
                residual <= 1e-11,
                "{ends:?} n = 1000: residual {residual:e}"
            );
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        // Fourth-order central differences with λh = 1e-3: truncation ≈ (λh)⁴/30, rounding ≈ ε/(λh);
        // tolerance 1e-10 relative to λ^k.
        for ends in ALL {
            for n in [1, 3, 10, 100] {
                let mode = ModeShape::new(ends, n);
                let lambda = mode.beta_l();
                let h = 1e-3 / lambda;
                for i in 1..40 {
                    let xi = i as f64 / 40.0;
                    let f = |x: f64| mode.terms.eval(x);
                    let (m2, m1, p1, p2) = (f(xi - 2.0 * h), f(xi - h), f(xi + h), f(xi + 2.0 * h));
                    let exact = f(xi);
                    for k in 0..3 {
                        let difference = (m2[k] - 8.0 * m1[k] + 8.0 * p1[k] - p2[k]) / (12.0 * h);
                        let error = (difference - exact[k + 1]).abs() / lambda.powi(k as i32 + 1);
                        assert!(
                            error <= 1e-10,
                            "{ends:?} n = {n} ξ = {xi} order {}: {error:e}",
                            k + 1
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn mode_satisfies_the_beam_equation() {
        // φ'''' = λ⁴ φ, with φ'''' from the 7-point second difference of φ″ at λh = 0.1:
        // truncation ≈ (λh)⁶/560 ≈ 2e-9, rounding ≈ 6 ε_eval/(λh)². Tolerance 1e-8 on φ'''' / λ⁴.
        for ends in ALL {
            for n in [1, 2, 5, 10, 50, 100] {
                let mode = ModeShape::new(ends, n);
                let lambda = mode.beta_l();
                let h = 0.1 / lambda;
                let curvature = |x: f64| mode.at(x).2;
                let weights = [2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0];
                for i in 1..50 {
                    let xi = i as f64 / 50.0;
                    let second: f64 = weights
                        .iter()
                        .enumerate()
                        .map(|(j, w)| w * curvature(xi + (j as f64 - 3.0) * h))
                        .sum::<f64>()
                        / (180.0 * h * h);
                    let error = (second / lambda.powi(4) - mode.at(xi).0).abs();
                    assert!(error <= 1e-8, "{ends:?} n = {n} ξ = {xi}: {error:e}");
                }
            }
        }
    }

    /// Gauss–Legendre nodes and weights on [−1, 1] by Newton on P_m.
    fn gauss_legendre(m: usize) -> Vec<(f64, f64)> {
        (1..=m)
            .map(|i| {
                let mut x = (PI * (i as f64 - 0.25) / (m as f64 + 0.5)).cos();
                let mut derivative = 0.0;
                for _ in 0..100 {
                    let (mut p0, mut p1) = (1.0, x);
                    for k in 2..=m {
                        let k = k as f64;
                        (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                    }
                    derivative = m as f64 * (x * p1 - p0) / (x * x - 1.0);
                    let step = p1 / derivative;
                    x -= step;
                    if step.abs() < 1e-16 {
                        break;
                    }
                }
                (x, 2.0 / ((1.0 - x * x) * derivative * derivative))
            })
            .collect()
    }

    /// ∫₀¹ f over `panels` equal panels of 16-point Gauss–Legendre.
    fn integrate(f: impl Fn(f64) -> f64, panels: usize) -> f64 {
        let rule = gauss_legendre(16);
        let width = 1.0 / panels as f64;
        (0..panels)
            .map(|p| {
                let start = p as f64 * width;
                rule.iter()
                    .map(|&(x, w)| 0.5 * width * w * f(start + 0.5 * width * (x + 1.0)))
                    .sum::<f64>()
            })
            .sum()
    }

    #[test]
    fn modes_are_orthogonal() {
        // 4(m + n) panels of 16 points resolve both the waves and the boundary layers of width 1/λ
        // far beyond 1e-15. Tolerance 1e-12 on ∫φ_m φ_n, against ∫φ_n² of order 0.3–0.5.
        for ends in ALL {
            for (m, n) in [
                (1, 2),
                (1, 3),
                (3, 7),
                (10, 11),
                (1, 100),
                (49, 50),
                (99, 100),
            ] {
                let (a, b) = (ModeShape::new(ends, m), ModeShape::new(ends, n));
                let panels = 4 * (m + n) as usize;
                let cross = integrate(|x| a.at(x).0 * b.at(x).0, panels);
                let norm = integrate(|x| b.at(x).0.powi(2), panels);
                assert!(
                    cross.abs() <= 1e-12,
                    "{ends:?} ({m}, {n}): ∫φmφn = {cross:e}"
                );
                assert!(norm > 0.2, "{ends:?} n = {n}: ∫φ² = {norm}");
            }
        }
    }

    #[test]
    fn stable_form_equals_textbook_form() {
        // Unnormalised shapes at the same λ, the textbook one in double-double: the rewrite is an
        // identity for any λ, so they must agree to rounding. Tolerance 1e-13 on an amplitude ≈ 2.
        for ends in CLAMPED {
            let free = ends == Support::Cantilever;
            for n in 1..=12 {
                let lambda = eigenvalue(ends, n);
                let stable = unnormalised(ends, lambda);
                for i in 0..=200 {
                    let xi = i as f64 / 200.0;
                    let error = (stable.eval(xi)[0] - textbook_dd(lambda, xi, free)).abs();
                    assert!(error <= 1e-13, "{ends:?} n = {n} ξ = {xi}: {error:e}");
                }
            }
        }
    }

    #[test]
    fn stable_cantilever_matches_f64_textbook_while_that_is_accurate() {
        // The plain f64 textbook form loses about ε e^λ: below 1e-12 only for n ≤ 3 (4e-12 at
        // n = 4, 1e-10 at n = 5 after normalisation), and nothing is left at n = 13.
        for n in 1..=3 {
            let mode = ModeShape::new(Support::Cantilever, n);
            let lambda = mode.beta_l();
            let tip = textbook_f64(lambda, 1.0).abs();
            for i in 0..=200 {
                let xi = i as f64 / 200.0;
                let error = (mode.at(xi).0 - textbook_f64(lambda, xi) / tip).abs();
                assert!(error <= 1e-12, "n = {n} ξ = {xi}: {error:e}");
            }
        }
        let lambda = eigenvalue(Support::Cantilever, 13);
        let naive_tip = textbook_f64(lambda, 1.0);
        let stable_tip = unnormalised(Support::Cantilever, lambda).eval(1.0)[0];
        assert!(
            (naive_tip - stable_tip).abs() > 0.1,
            "n = 13: {naive_tip} vs {stable_tip}"
        );
    }

    #[test]
    fn high_modes_are_finite_and_bounded() {
        // Beyond n = 227 cosh λ overflows; the bounded form must stay finite with |φ| ≤ 1
        // (tolerance 1e-12) at 8 points per half-wave, and the cantilever tip stays at ±1.
        for ends in ALL {
            for n in [100, 227, 1000, 5000] {
                let mode = ModeShape::new(ends, n);
                let points = 8 * n as usize;
                for i in 0..=points {
                    let (phi, slope, curvature) = mode.at(i as f64 / points as f64);
                    assert!(phi.is_finite() && slope.is_finite() && curvature.is_finite());
                    assert!(
                        phi.abs() <= 1.0 + 1e-12,
                        "{ends:?} n = {n}: |φ| = {}",
                        phi.abs()
                    );
                }
                if ends == Support::Cantilever {
                    assert!((mode.at(1.0).0.abs() - 1.0).abs() <= 1e-12, "n = {n}");
                }
            }
        }
        let extreme = ModeShape::new(Support::Cantilever, u32::MAX);
        assert!(extreme.beta_l().is_finite() && extreme.at(0.5).0.is_finite());
    }

    #[test]
    fn antisymmetric_fixed_fixed_modes_are_propped_cantilevers_of_half_the_span() {
        // An antisymmetric clamped–clamped mode vanishes at midspan with zero moment, so each half
        // is a clamped–pinned beam: λ_FF(2k) = 2 λ_CP(k) and φ_FF,2k(ξ/2) = φ_CP,k(ξ). Both shapes are
        // normalised to max 1 and start positive, so they must coincide. Tolerances 4 ε λ on the
        // eigenvalue, 1e-12 on the shape.
        for k in [1, 2, 5, 25, 50] {
            let whole = ModeShape::new(Support::FixedFixed, 2 * k);
            let half = ModeShape::new(Support::ProppedCantilever, k);
            let lambda = whole.beta_l();
            assert!(
                (lambda - 2.0 * half.beta_l()).abs() <= 4.0 * f64::EPSILON * lambda,
                "k = {k}"
            );
            for i in 0..=400 {
                let xi = i as f64 / 400.0;
                let error = (whole.at(0.5 * xi).0 - half.at(xi).0).abs();
                assert!(error <= 1e-12, "k = {k} ξ = {xi}: {error:e}");
            }
        }
    }

    /// max |φ| by dense sampling and golden-section refinement of the best sample, using values
    /// only (independent of the derivative-based search in `peak_magnitude`).
    fn sampled_peak(mode: &ModeShape) -> f64 {
        let points = 64 * (mode.beta_l() / PI).ceil() as usize;
        let step = 1.0 / points as f64;
        let magnitude = |x: f64| mode.at(x.clamp(0.0, 1.0)).0.abs();
        let best = (0..=points)
            .max_by(|&i, &j| magnitude(i as f64 * step).total_cmp(&magnitude(j as f64 * step)));
        let centre = best.unwrap() as f64 * step;
        let (mut a, mut b) = (centre - step, centre + step);
        let golden = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..80 {
            let (x1, x2) = (b - golden * (b - a), a + golden * (b - a));
            if magnitude(x1) < magnitude(x2) {
                a = x1;
            } else {
                b = x2;
            }
        }
        magnitude(0.5 * (a + b)).max(magnitude(centre))
    }

    #[test]
    fn peak_magnitude_is_one() {
        // Tolerance 1e-12: the golden-section search locates the peak to ~1e-9/λ, where the
        // quadratic loss in |φ| is ~1e-18.
        for ends in ALL {
            for n in [1, 2, 3, 5, 7, 8, 10, 25, 50, 100] {
                let peak = sampled_peak(&ModeShape::new(ends, n));
                assert!(
                    (peak - 1.0).abs() <= 1e-12,
                    "{ends:?} n = {n}: max |φ| = {peak}"
                );
            }
        }
    }

    #[test]
    fn every_mode_starts_with_a_positive_lobe() {
        for ends in ALL {
            for n in [1, 2, 3, 10, 100, 1000] {
                let mode = ModeShape::new(ends, n);
                let (phi, _, _) = mode.at(0.5 / mode.beta_l());
                assert!(phi > 0.0, "{ends:?} n = {n}: φ = {phi}");
            }
        }
    }

    #[test]
    #[should_panic(expected = "numbered from 1")]
    fn mode_zero_is_rejected() {
        ModeShape::new(Support::Cantilever, 0);
    }
}
