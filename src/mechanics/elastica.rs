//! Large-deflection cantilever under one dead point load: the Euler elastica.
//!
//! Owns: the exact shape of an inextensible Euler–Bernoulli rod of length L, clamped
//! horizontally at arc length s = 0, under a vertical point load at arc length a ∈ (0, L]
//! (`docs/mechanics.md` §6). Between 0 and a it is the tip-loaded elastica of
//! length a with load parameter α = P a²/EI; beyond a the rod is straight at the angle θ₀
//! reached at a. Must not touch: meshes, cameras or files; it works on plain numbers in the
//! beam's own frame (x along the undeformed axis, v and θ positive downward).
//!
//! How, and why this way:
//! * The tip angle comes from a closed form in Carlson's symmetric integrals, parametrised by
//!   m = sin θ₀ and q = 1 − m. The classical Bisshopp–Drucker form subtracts O(1) elliptic
//!   integrals to get O(α) results and fails for small α (docs/mechanics.md §6.2); writing
//!   K − F(φ₁) as the single integral F(ψ₁) over the complementary amplitude, and the tip drop
//!   as an R_D integral of a positive integrand, leaves no difference of large numbers: every
//!   α from 1e-300 up is solved to full relative precision, so the shape needs no series
//!   branch.
//!   Only `linear_error` (an O(α²) difference of the two theories) uses a series, below
//!   [`LINEAR_ERROR_SERIES_BELOW`].
//! * The shape is integrated once, backwards from the free end where (θ₀, θ′ = 0) are known,
//!   by a high-order Taylor method on (sin θ, cos θ, θ′). Backwards is the stable direction
//!   (the solution grows towards the clamp), and carrying sin θ and cos θ separately keeps both
//!   the tiny angles of a light load and the tiny 1 − |sin θ| of a heavy one to full relative
//!   precision. The Taylor polynomials of each step are kept, so `at` is one Horner sweep.
//! * For α above [`SEPARATRIX_ALPHA`] the complementary modulus k′ ≈ 4 e^(−u₁−√α) is below
//!   1e-12 and the elastica is the separatrix (k = 1) in closed form; at the switch it differs
//!   from the integrated table by < 1e-13·a in position (measured). This keeps the cost bounded
//!   for any α, where a step table would need ~√α steps.

use std::f64::consts::FRAC_1_SQRT_2;

/// A point of the deformed centreline, in the beam frame: `x` along the undeformed axis
/// from the clamp, `v` the downward deflection, `theta` the rotation (positive when the
/// axis turns downward), all at arc length s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Centreline {
    pub x: f64,
    pub v: f64,
    pub theta: f64,
}

/// The deformed cantilever. Immutable once built; `at` is cheap.
#[derive(Clone, Debug)]
pub struct Elastica {
    length: f64,
    load_at: f64,
    /// Signed: negative for an upward load, solved as the mirror image of |α|.
    alpha: f64,
    /// The loaded part s ∈ [0, a] for the downward load |α|, in units of a.
    segment: Segment,
    /// Where the loaded part ends, in units of a, with the sine and cosine of θ₀ that carry
    /// the straight part beyond it.
    end: Centreline,
    end_sin: f64,
    end_cos: f64,
}

impl Elastica {
    /// Load parameter α = P a²/EI ≥ 0 for a downward load at arc length `load_at` ∈ (0, length].
    ///
    /// A negative α is an upward load (the mirror image). Out-of-range inputs are made safe
    /// rather than rejected: a non-positive or non-finite length gives an empty rod, `load_at`
    /// is clamped into [0, length] (0 being the limit of a vanishing loaded part, i.e. a kink of
    /// θ₀(α) at the clamp; NaN puts the load at the tip), NaN α counts as 0 and infinite α as
    /// the largest finite one.
    pub fn from_load_parameter(length: f64, load_at: f64, alpha: f64) -> Elastica {
        let (length, load_at) = sanitise(length, load_at);
        let alpha = if alpha.is_nan() {
            0.0
        } else {
            alpha.clamp(-f64::MAX, f64::MAX)
        };
        let magnitude = alpha.abs();
        let shape = if magnitude > SEPARATRIX_ALPHA {
            Shape::Separatrix
        } else {
            Shape::Carlson(TipAngle::for_alpha(magnitude))
        };
        Elastica::build(length, load_at, alpha, shape)
    }

    /// The elastica whose tip (s = length) deflects downward by `tip_deflection` metres.
    /// Negative values mean an upward load (mirror image). Err with a clear message naming the
    /// value if it cannot be reached (|δ| must stay below the length an inextensible rod allows).
    pub fn from_tip_deflection(
        length: f64,
        load_at: f64,
        tip_deflection: f64,
    ) -> Result<Elastica, String> {
        if !(length.is_finite() && length > 0.0) {
            return Err(format!(
                "elastica: the length must be positive and finite, got {length}"
            ));
        }
        let (length, load_at) = sanitise(length, load_at);
        let target = tip_deflection.abs();
        if target.is_nan() || target >= length {
            return Err(format!(
                "elastica: tip deflection {tip_deflection} cannot be reached: an inextensible rod of \
                 length {length} deflects by less than its length"
            ));
        }
        let (magnitude, shape) = solve_tip_deflection(length, load_at, target);
        Ok(Elastica::build(
            length,
            load_at,
            magnitude.copysign(tip_deflection),
            shape,
        ))
    }

    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Centreline at arc length s ∈ [0, length] (s outside is clamped into range).
    pub fn at(&self, s: f64) -> Centreline {
        let s = if s.is_nan() {
            0.0
        } else {
            s.clamp(0.0, self.length)
        };
        let a = self.load_at;
        let down = if s <= a && a > 0.0 {
            let p = self.segment.at(s / a);
            Centreline {
                x: a * p.x,
                v: a * p.v,
                theta: p.theta,
            }
        } else {
            let beyond = s - a;
            Centreline {
                x: a * self.end.x + beyond * self.end_cos,
                v: a * self.end.v + beyond * self.end_sin,
                theta: self.end.theta,
            }
        };
        if self.alpha < 0.0 {
            Centreline {
                v: -down.v,
                theta: -down.theta,
                ..down
            }
        } else {
            down
        }
    }

    /// Relative error |δ_linear − δ_exact| / δ_exact of linear theory's tip deflection for the
    /// same load (0 for α = 0). Saturates at `f64::MAX` for loads whose linear deflection
    /// itself overflows.
    pub fn linear_error(&self) -> f64 {
        let (l, a, alpha) = (self.length, self.load_at, self.alpha.abs());
        let exact = a * self.end.v + (l - a) * self.end_sin;
        if alpha == 0.0 || exact == 0.0 {
            return 0.0;
        }
        // Below the switch the difference is O(α³) and would be lost in the rounding of two
        // O(α) numbers; its series is exact there to ~α⁴ relative.
        let excess = if alpha < LINEAR_ERROR_SERIES_BELOW {
            a * polynomial(alpha, &DROP_DEFICIT) + (l - a) * polynomial(alpha, &SIN_TIP_DEFICIT)
        } else {
            alpha * (3.0 * l - a) / 6.0 - exact
        };
        (excess / exact).abs().min(f64::MAX)
    }

    fn build(length: f64, load_at: f64, alpha: f64, shape: Shape) -> Elastica {
        let magnitude = alpha.abs();
        let segment = if magnitude == 0.0 {
            Segment::Straight
        } else {
            match shape {
                Shape::Separatrix => Segment::Separatrix {
                    root_alpha: magnitude.sqrt(),
                },
                Shape::Carlson(tip) => Segment::Table(Table::integrate(magnitude, tip)),
            }
        };
        let end = segment.at(1.0);
        let (end_sin, end_cos) = segment.end_direction();
        Elastica {
            length,
            load_at,
            alpha,
            segment,
            end,
            end_sin,
            end_cos,
        }
    }
}

/// Above this α the separatrix is used; k′ < 1e-12 there (see the module notes).
const SEPARATRIX_ALPHA: f64 = 800.0;

/// Where `linear_error` switches from its series to the direct difference. At 0.05 the
/// series' next term is ~2e-13 relative and the direct difference loses ~1e-12 to rounding.
const LINEAR_ERROR_SERIES_BELOW: f64 = 0.05;

/// α/3 − δ_v/a of the tip-loaded elastica: coefficients of α³, α⁵, α⁷, α⁹ of the exact
/// perturbation series (rational arithmetic; the first two are the 4/105 and 0.0081385 of
/// docs/mechanics.md §6.4).
const DROP_DEFICIT: [f64; 4] = [
    4.0 / 105.0,
    -47.0 / 5775.0,
    21584.0 / 10135125.0,
    -2837452.0 / 4583103525.0,
];
/// α/2 − sin θ₀, same form (from θ₀ = α/2 − 11α³/240 + 3601α⁵/403200 − …).
const SIN_TIP_DEFICIT: [f64; 4] = [
    1.0 / 15.0,
    -47.0 / 3150.0,
    2698.0 / 675675.0,
    -1418726.0 / 1206079875.0,
];

/// Σ c_i α^(2i+3), the shape of both deficit series.
fn polynomial(alpha: f64, coefficients: &[f64]) -> f64 {
    let a2 = alpha * alpha;
    alpha * a2 * coefficients.iter().rev().fold(0.0, |acc, c| acc * a2 + c)
}

fn sanitise(length: f64, load_at: f64) -> (f64, f64) {
    let length = if length.is_finite() && length > 0.0 {
        length
    } else {
        0.0
    };
    let load_at = if load_at.is_nan() {
        length
    } else {
        load_at.clamp(0.0, length)
    };
    (length, load_at)
}

/// How the loaded part is to be computed.
#[derive(Clone, Copy, Debug)]
enum Shape {
    Carlson(TipAngle),
    Separatrix,
}

/// |α| and shape of the elastica whose tip deflects by `target` ∈ [0, l).
///
/// The tip deflection a·(δ_v/a)(m) + (l − a)·m is explicit in m = sin θ₀ and increases with it,
/// so the root is bracketed in m (light loads) or in ln q (heavy ones, where m → 1 carries no
/// precision); only the separatrix beyond needs α itself, and it is explicit there.
fn solve_tip_deflection(l: f64, a: f64, target: f64) -> (f64, Shape) {
    if target == 0.0 {
        return (0.0, Shape::Carlson(TipAngle::from_m(0.0)));
    }
    let deflection = |tip: TipAngle| a * tip.tip_drop() + (l - a) * tip.m;
    let half = TipAngle::from_m(0.5);
    let last = TipAngle::for_alpha(SEPARATRIX_ALPHA);
    let tip = if target <= deflection(half) {
        TipAngle::from_m(illinois(
            |m| deflection(TipAngle::from_m(m)) - target,
            0.0,
            0.5,
        ))
    } else if target <= deflection(last) {
        let ln_q = illinois(
            |ln_q| target - deflection(TipAngle::from_q(ln_q.exp())),
            last.q.ln(),
            0.5f64.ln(),
        );
        TipAngle::from_q(ln_q.exp())
    } else {
        // Separatrix: l − δ = 2a(tanh(u₁ + √α) − 1/√2)/√α, and tanh is 1 to f64 precision
        // for √α > √SEPARATRIX_ALPHA; the straight part's own 1 − sin θ₀ ~ 1e-24 is negligible.
        let root_alpha = 2.0 * a * (1.0 - FRAC_1_SQRT_2) / (l - target);
        return (
            (root_alpha * root_alpha).clamp(SEPARATRIX_ALPHA, f64::MAX),
            Shape::Separatrix,
        );
    };
    (tip.alpha(), Shape::Carlson(tip))
}

/// The tip angle as m = sin θ₀ and q = 1 − m, each to full relative precision: the light load
/// needs m (≈ α/2), the heavy one q (≈ 2k′², ~1e-24 at α = 800).
#[derive(Clone, Copy, Debug)]
struct TipAngle {
    m: f64,
    q: f64,
}

impl TipAngle {
    fn from_m(m: f64) -> TipAngle {
        TipAngle { m, q: 1.0 - m }
    }

    fn from_q(q: f64) -> TipAngle {
        TipAngle { m: 1.0 - q, q }
    }

    /// Solves α(m) = α for α ≤ [`SEPARATRIX_ALPHA`], bracketed (α increases with m).
    fn for_alpha(alpha: f64) -> TipAngle {
        if alpha <= 0.0 {
            return TipAngle::from_m(0.0);
        }
        if alpha <= TipAngle::from_m(0.5).alpha() {
            // α ≈ 2m(1 + O(m)): nearly linear in m, so false position converges fast.
            TipAngle::from_m(illinois(|m| TipAngle::from_m(m).alpha() - alpha, 0.0, 0.5))
        } else {
            // √α ≈ ln(4/k′) − u₁ is nearly linear in ln q (and decreasing).
            let root = alpha.sqrt();
            let ln_q = illinois(
                |ln_q| root - TipAngle::from_q(ln_q.exp()).alpha().sqrt(),
                LN_Q_MIN,
                0.5f64.ln(),
            );
            TipAngle::from_q(ln_q.exp())
        }
    }

    /// With ψ₁ the amplitude complementary to φ₁ (sin²ψ₁ = 2m/(1+m), k² sin²ψ₁ = m):
    /// √α = K(k) − F(φ₁, k) = F(ψ₁, k) = sin ψ₁ · R_F(cos²ψ₁, 1 − m, 1).
    fn alpha(self) -> f64 {
        let rf = self.rf();
        2.0 * self.m / (1.0 + self.m) * rf * rf
    }

    /// δ_v/a at the load. From θ′² = 2α(m − sin θ) (in s/a), ∫θ′² = 2α(m − δ_v/a), and that
    /// integral is an R_D over ψ: δ_v/a = m (1 − q R_D(cos²ψ₁, 1, q) / (3 R_F)). The
    /// subtracted part is below 1/3, so nothing cancels.
    fn tip_drop(self) -> f64 {
        let rd = carlson_rd(self.q / (1.0 + self.m), 1.0, self.q);
        self.m * (1.0 - self.q * rd / (3.0 * self.rf()))
    }

    /// cos θ₀ = √((1 − m)(1 + m)), exact for θ₀ near π/2 where √(1 − m²) is not.
    fn cos(self) -> f64 {
        (self.q * (1.0 + self.m)).sqrt()
    }

    fn rf(self) -> f64 {
        carlson_rf(self.q / (1.0 + self.m), self.q, 1.0)
    }
}

/// ln q at the bracket's heavy end: α(q = e^-200) ≈ 1e4, well past [`SEPARATRIX_ALPHA`].
const LN_Q_MIN: f64 = -200.0;

/// The loaded part s ∈ [0, a] in units of a, for a downward load.
#[derive(Clone, Debug)]
enum Segment {
    Straight,
    Table(Table),
    Separatrix { root_alpha: f64 },
}

impl Segment {
    /// Position and angle at ξ = s/a ∈ [0, 1].
    fn at(&self, xi: f64) -> Centreline {
        match self {
            Segment::Straight => Centreline {
                x: xi,
                v: 0.0,
                theta: 0.0,
            },
            Segment::Table(table) => table.at(xi),
            Segment::Separatrix { root_alpha } => separatrix(*root_alpha, xi).0,
        }
    }

    /// (sin θ₀, cos θ₀) at the load, taken from the segment itself so that the straight part
    /// continues it without a kink.
    fn end_direction(&self) -> (f64, f64) {
        match self {
            Segment::Straight => (0.0, 1.0),
            Segment::Table(table) => (table.end_sin, table.end_cos),
            Segment::Separatrix { root_alpha } => separatrix(*root_alpha, 1.0).1,
        }
    }
}

/// u₁ = F(π/4, 1) = asinh 1: the elliptic argument of the clamp on the separatrix.
const SEPARATRIX_U1: f64 = 0.881_373_587_019_543;

/// The separatrix elastica (k = 1): with w = u₁ + ξ√α, sn = tanh w, cn = dn = sech w, so
/// x/a = 2(cn u₁ − cn w)/√α, v/a = ξ − 2(tanh w − tanh u₁)/√α, sin θ = 2 tanh² w − 1 and
/// cos θ = 2 tanh w sech w. Returns the point and (sin θ, cos θ).
fn separatrix(root_alpha: f64, xi: f64) -> (Centreline, (f64, f64)) {
    let w = SEPARATRIX_U1 + xi * root_alpha;
    // cosh overflows to ∞ for w > 710 and sech becomes the correct 0.
    let (tanh, sech) = (w.tanh(), 1.0 / w.cosh());
    // tanh u₁ = sech u₁ = 1/√2, but evaluated the same way as at w so that the clamp lands
    // exactly on the origin.
    let (tanh_clamp, sech_clamp) = (SEPARATRIX_U1.tanh(), 1.0 / SEPARATRIX_U1.cosh());
    let (sin, cos) = (2.0 * tanh * tanh - 1.0, 2.0 * tanh * sech);
    let point = Centreline {
        x: 2.0 * (sech_clamp - sech) / root_alpha,
        v: xi - 2.0 * (tanh - tanh_clamp) / root_alpha,
        theta: sin.atan2(cos),
    };
    (point, (sin, cos))
}

/// Number of Taylor coefficients kept per step (degree TERMS − 1).
const TERMS: usize = 25;

/// Largest step in the natural length a/√α. The solution's complex singularities (poles of the
/// Jacobi functions) lie K′(k) ≥ π/2 such units off the real axis, so a step of 0.5 is a third
/// of the Taylor radius; with degree 24 the truncation then stays below rounding (measured
/// ≤ 2e-15 at the tip for α from 0.3 to 1000; degree 16 or a step of 0.8 lose three digits).
const STEP: f64 = 0.5;

/// The loaded part as piecewise Taylor polynomials on a uniform grid in ξ = s/a.
#[derive(Clone, Debug)]
struct Table {
    /// Step i covers ξ ∈ [i/n, (i+1)/n], expanded about its right end in τ = (i+1) − nξ ∈ [0, 1].
    steps: Vec<Step>,
    end_sin: f64,
    end_cos: f64,
}

#[derive(Clone, Debug)]
struct Step {
    theta: [f64; TERMS],
    x: [f64; TERMS],
    v: [f64; TERMS],
}

/// sin θ, cos θ and dθ/dξ at one node.
#[derive(Clone, Copy, Debug)]
struct State {
    sin: f64,
    cos: f64,
    bend: f64,
}

impl Table {
    /// θ″ = −α cos θ in ξ, integrated from the free end (θ₀, θ′ = 0) to the clamp.
    fn integrate(alpha: f64, tip: TipAngle) -> Table {
        let n = (alpha.sqrt() / STEP).ceil().max(1.0) as usize;
        let h = 1.0 / n as f64;
        let end = State {
            sin: tip.m,
            cos: tip.cos(),
            bend: 0.0,
        };
        let mut state = end;
        let mut steps = Vec::with_capacity(n);
        for _ in 0..n {
            let (step, next) = Step::expand(state, alpha, h);
            steps.push(step);
            state = next;
        }
        steps.reverse();
        anchor_at_clamp(&mut steps);
        Table {
            steps,
            end_sin: end.sin,
            end_cos: end.cos,
        }
    }

    fn at(&self, xi: f64) -> Centreline {
        let n = self.steps.len();
        let scaled = xi * n as f64;
        let i = (scaled.floor().max(0.0) as usize).min(n - 1);
        self.steps[i].at((i + 1) as f64 - scaled)
    }
}

/// The expansions know only the shape of x and v within each step; fixing x = v = 0 at the
/// clamp and chaining the increments towards the tip makes positions exact there and
/// continuous across steps (rather than inheriting the accumulated error at the clamp).
fn anchor_at_clamp(steps: &mut [Step]) {
    let (mut x, mut v) = (0.0, 0.0);
    for step in steps {
        // τ = 1 is the step's left end, where the position is already known.
        step.x[0] = x - step.x[1..].iter().sum::<f64>();
        step.v[0] = v - step.v[1..].iter().sum::<f64>();
        (x, v) = (step.x[0], step.v[0]);
    }
}

impl Step {
    /// Taylor coefficients about the node `start`, in τ = (ξ_node − ξ)/h, and the state at
    /// τ = 1. In τ the system is polynomial, d(sin θ) = −h cos θ·θ′, d(cos θ) = h sin θ·θ′,
    /// d(θ′) = h α cos θ, so each coefficient follows from Cauchy products of earlier ones.
    fn expand(start: State, alpha: f64, h: f64) -> (Step, State) {
        let (mut sin, mut cos, mut bend) = ([0.0; TERMS], [0.0; TERMS], [0.0; TERMS]);
        (sin[0], cos[0], bend[0]) = (start.sin, start.cos, start.bend);
        for j in 0..TERMS - 1 {
            let (mut cos_bend, mut sin_bend) = (0.0, 0.0);
            for i in 0..=j {
                cos_bend += cos[i] * bend[j - i];
                sin_bend += sin[i] * bend[j - i];
            }
            let k = h / (j + 1) as f64;
            sin[j + 1] = -k * cos_bend;
            cos[j + 1] = k * sin_bend;
            bend[j + 1] = k * alpha * cos[j];
        }
        let (mut theta, mut x, mut v) = ([0.0; TERMS], [0.0; TERMS], [0.0; TERMS]);
        theta[0] = start.sin.atan2(start.cos);
        for j in 0..TERMS - 1 {
            let k = -h / (j + 1) as f64;
            theta[j + 1] = k * bend[j];
            x[j + 1] = k * cos[j];
            v[j + 1] = k * sin[j];
        }
        let (s, c) = (sin.iter().sum::<f64>(), cos.iter().sum::<f64>());
        // The truncated series drifts off the unit circle by its truncation error; putting it
        // back keeps sin² + cos² = 1 exact without touching the relative precision of either.
        let norm = s.hypot(c);
        let next = State {
            sin: s / norm,
            cos: c / norm,
            bend: bend.iter().sum(),
        };
        (Step { theta, x, v }, next)
    }

    fn at(&self, tau: f64) -> Centreline {
        let (mut x, mut v, mut theta) = (0.0, 0.0, 0.0);
        for j in (0..TERMS).rev() {
            x = x * tau + self.x[j];
            v = v * tau + self.v[j];
            theta = theta * tau + self.theta[j];
        }
        Centreline { x, v, theta }
    }
}

/// False position with the Illinois modification on a bracket [lo, hi] where f changes sign
/// (f increasing). Converges superlinearly and can never leave the bracket, unlike an
/// unbracketed secant, which can diverge for large α (docs/mechanics.md §11).
pub(super) fn illinois(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let (mut f_lo, mut f_hi) = (f(lo), f(hi));
    if f_lo >= 0.0 {
        return lo;
    }
    if f_hi <= 0.0 {
        return hi;
    }
    let mut kept = 0i8;
    for _ in 0..200 {
        let mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        if !(mid > lo && mid < hi) || hi - lo <= 4.0 * f64::EPSILON * (lo.abs() + hi.abs()) {
            return mid.clamp(lo, hi);
        }
        let f_mid = f(mid);
        if f_mid == 0.0 {
            return mid;
        } else if f_mid < 0.0 {
            (lo, f_lo) = (mid, f_mid);
            if kept == 1 {
                f_hi *= 0.5;
            }
            kept = 1;
        } else {
            (hi, f_hi) = (mid, f_mid);
            if kept == -1 {
                f_lo *= 0.5;
            }
            kept = -1;
        }
    }
    0.5 * (lo + hi)
}

/// Carlson's R_F(x, y, z) (Carlson 1995, duplication plus 5th-order series), for x, y, z ≥ 0
/// with at most one zero. Relative error ~1e-16.
fn carlson_rf(x0: f64, y0: f64, z0: f64) -> f64 {
    let (mut x, mut y, mut z) = (x0, y0, z0);
    let a0 = (x0 + y0 + z0) / 3.0;
    let mut a = a0;
    let q = (3.0 * DUPLICATION_TOLERANCE).powf(-1.0 / 6.0)
        * (a0 - x0).abs().max((a0 - y0).abs()).max((a0 - z0).abs());
    let mut scale = 1.0;
    while scale * q >= a.abs() {
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lambda = sx * sy + sy * sz + sz * sx;
        (x, y, z, a) = (
            (x + lambda) / 4.0,
            (y + lambda) / 4.0,
            (z + lambda) / 4.0,
            (a + lambda) / 4.0,
        );
        scale /= 4.0;
    }
    let dx = (a0 - x0) * scale / a;
    let dy = (a0 - y0) * scale / a;
    let dz = -(dx + dy);
    let e2 = dx * dy - dz * dz;
    let e3 = dx * dy * dz;
    (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / a.sqrt()
}

/// Carlson's R_D(x, y, z) = R_J(x, y, z, z) (Carlson 1995), for x, y ≥ 0 (at most one zero), z > 0.
fn carlson_rd(x0: f64, y0: f64, z0: f64) -> f64 {
    let (mut x, mut y, mut z) = (x0, y0, z0);
    let a0 = (x0 + y0 + 3.0 * z0) / 5.0;
    let mut a = a0;
    let q = (DUPLICATION_TOLERANCE / 4.0).powf(-1.0 / 6.0)
        * (a0 - x0).abs().max((a0 - y0).abs()).max((a0 - z0).abs());
    let (mut scale, mut sum) = (1.0, 0.0);
    while scale * q >= a.abs() {
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lambda = sx * sy + sy * sz + sz * sx;
        sum += scale / (sz * (z + lambda));
        (x, y, z, a) = (
            (x + lambda) / 4.0,
            (y + lambda) / 4.0,
            (z + lambda) / 4.0,
            (a + lambda) / 4.0,
        );
        scale /= 4.0;
    }
    let dx = (a0 - x0) * scale / a;
    let dy = (a0 - y0) * scale / a;
    let dz = -(dx + dy) / 3.0;
    let (xy, z2) = (dx * dy, dz * dz);
    let e2 = xy - 6.0 * z2;
    let e3 = (3.0 * xy - 8.0 * z2) * dz;
    let e4 = 3.0 * (xy - z2) * z2;
    let e5 = xy * z2 * dz;
    let series = 1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0
        - 3.0 * e4 / 22.0
        - 9.0 * e2 * e3 / 52.0
        + 3.0 * e5 / 26.0;
    scale * series / (a * a.sqrt()) + 3.0 * sum
}

/// Carlson's r: the duplication stops when the 5th-order series is accurate to about this.
const DUPLICATION_TOLERANCE: f64 = 1e-16;

#[cfg(test)]
mod tests {
    use super::*;

    /// Tip values of the Bisshopp–Drucker closed form, `docs/mechanics.md` §6.4: α, δ_v/L, u/L,
    /// θ₀ in degrees, as printed there.
    const BISSHOPP_DRUCKER: [(f64, f64, f64, f64); 14] = [
        (0.10, 0.03330, 0.00067, 2.86),
        (0.25, 0.08275, 0.00412, 7.12),
        (0.5, 0.16214, 0.01592, 14.01),
        (1.0, 0.30172, 0.05643, 26.43),
        (1.5, 0.41098, 0.10794, 36.64),
        (2.0, 0.49346, 0.16064, 44.79),
        (3.0, 0.60325, 0.25442, 56.50),
        (4.0, 0.66996, 0.32894, 64.24),
        (5.0, 0.71379, 0.38763, 69.64),
        (6.0, 0.74457, 0.43459, 73.55),
        (8.0, 0.78498, 0.50483, 78.75),
        (10.0, 0.81061, 0.55500, 81.95),
        (15.0, 0.84772, 0.63529, 86.05),
        (20.0, 0.86870, 0.68389, 87.83),
    ];

    /// (δ_v/L, u/L, θ₀ in degrees) at the tip of a tip-loaded cantilever.
    fn tip_values(length: f64, alpha: f64) -> (f64, f64, f64) {
        let tip = Elastica::from_load_parameter(length, length, alpha).at(length);
        (tip.v / length, 1.0 - tip.x / length, tip.theta.to_degrees())
    }

    fn assert_close(what: &str, got: f64, want: f64, tolerance: f64) {
        assert!(
            (got - want).abs() <= tolerance,
            "{what}: got {got:e}, want {want:e} ± {tolerance:e}"
        );
    }

    fn assert_finite(e: &Elastica, context: &str) {
        assert!(
            e.alpha().is_finite() && e.linear_error().is_finite(),
            "{context}: {e:?}"
        );
        for i in -2..=102 {
            let s = e.length * i as f64 / 100.0;
            let c = e.at(s);
            assert!(
                c.x.is_finite() && c.v.is_finite() && c.theta.is_finite(),
                "{context}, s = {s}: {c:?}"
            );
        }
    }

    fn log_sweep(from: f64, to: f64, n: usize) -> impl Iterator<Item = f64> {
        (0..=n).map(move |i| from * (to / from).powf(i as f64 / n as f64))
    }

    #[test]
    fn carlson_integrals_match_published_values() {
        // Carlson (1995), Numer. Algorithms 10, §3 test values; 13–14 digits printed.
        assert_close(
            "R_F(1,2,0)",
            carlson_rf(1.0, 2.0, 0.0),
            1.311_028_777_146_1,
            1e-13,
        );
        assert_close(
            "R_F(2,3,4)",
            carlson_rf(2.0, 3.0, 4.0),
            0.584_082_841_677_15,
            1e-13,
        );
        assert_close(
            "R_D(0,2,1)",
            carlson_rd(0.0, 2.0, 1.0),
            1.797_210_352_103_4,
            1e-13,
        );
        assert_close(
            "R_D(2,3,4)",
            carlson_rd(2.0, 3.0, 4.0),
            0.165_105_272_942_61,
            1e-13,
        );
    }

    #[test]
    fn bisshopp_drucker_tip_values_for_alpha_1_2_5() {
        // δ_v/L and u/L to 1e-5 (the table's 5 significant digits); θ₀ is printed in degrees
        // to 0.01°, so it is held to half of that.
        for (alpha, drop, shortening, angle) in BISSHOPP_DRUCKER
            .into_iter()
            .filter(|r| [1.0, 2.0, 5.0].contains(&r.0))
        {
            let (d, u, t) = tip_values(2.5, alpha);
            assert_close(&format!("δ_v/L at α = {alpha}"), d, drop, 1e-5);
            assert_close(&format!("u/L at α = {alpha}"), u, shortening, 1e-5);
            assert_close(&format!("θ₀ at α = {alpha}"), t, angle, 0.005);
        }
    }

    #[test]
    fn whole_reference_table_at_its_printed_precision() {
        // Half a unit in the last printed digit for δ_v/L and u/L. θ₀ gets one unit (0.01°):
        // the α = 3 row prints 56.50° where the exact value is 56.4946°, a rounding slip of the
        // table, while its δ_v/L and u/L agree to all digits.
        for (alpha, drop, shortening, angle) in BISSHOPP_DRUCKER {
            let (d, u, t) = tip_values(1.0, alpha);
            assert_close(&format!("δ_v/L at α = {alpha}"), d, drop, 5.0e-6 + 1e-12);
            assert_close(
                &format!("u/L at α = {alpha}"),
                u,
                shortening,
                5.0e-6 + 1e-12,
            );
            assert_close(&format!("θ₀ at α = {alpha}"), t, angle, 0.01);
        }
    }

    #[test]
    fn interior_points_match_a_50_digit_ode_solution() {
        type Row = (f64, f64, f64, f64);
        // mpmath (dps = 50) Taylor integration of θ″ = −α cos θ from the clamp with
        // θ′(0) = √(2α sin θ₀); its θ′(1) vanished to < 1e-47, confirming the shooting
        // condition independently. Rows: s/a, x/a, v/a, θ. Held to 1e-14 (relative to a).
        let cases: [(f64, [Row; 5]); 3] = [
            (
                0.5,
                [
                    (
                        0.1,
                        0.09996266584225813,
                        0.0023764405137488213,
                        0.04670452599541612,
                    ),
                    (
                        0.25,
                        0.24948377172852895,
                        0.014060968009844167,
                        0.10740195077224755,
                    ),
                    (
                        0.5,
                        0.4966850336577463,
                        0.05095414333233582,
                        0.18374739223208564,
                    ),
                    (
                        0.75,
                        0.7412180623552035,
                        0.10284520217277733,
                        0.22936404137025346,
                    ),
                    (
                        1.0,
                        0.9840810375291625,
                        0.1621435756583696,
                        0.24453364713321832,
                    ),
                ],
            ),
            (
                5.0,
                [
                    (
                        0.1,
                        0.09862729878843858,
                        0.014381979794186563,
                        0.2813620975100102,
                    ),
                    (
                        0.25,
                        0.23263666980908373,
                        0.08021138491788601,
                        0.6150519389756615,
                    ),
                    (
                        0.5,
                        0.40345713793575705,
                        0.26089090765423445,
                        0.9762173083539804,
                    ),
                    (
                        0.75,
                        0.5210908448914229,
                        0.4810885045996703,
                        1.1596595560405007,
                    ),
                    (
                        1.0,
                        0.6123716392755701,
                        0.7137915236119128,
                        1.215368117611681,
                    ),
                ],
            ),
            (
                50.0,
                [
                    (
                        0.1,
                        0.08909304993475807,
                        0.039808376565405895,
                        0.7649340839970408,
                    ),
                    (
                        0.25,
                        0.16019890184669738,
                        0.16997138903881293,
                        1.288411488088395,
                    ),
                    (
                        0.5,
                        0.19317772082798448,
                        0.4172388578782992,
                        1.5224715932049435,
                    ),
                    (
                        0.75,
                        0.19886783225155596,
                        0.6671583426657225,
                        1.562313003470528,
                    ),
                    (
                        1.0,
                        0.19999960395040237,
                        0.9171554473035874,
                        1.5679819015714367,
                    ),
                ],
            ),
        ];
        // Also with a < L and a ≠ 1, so that the scaling by a is exercised.
        for (length, a) in [(1.0, 1.0), (7.0, 3.0)] {
            for (alpha, rows) in cases {
                let e = Elastica::from_load_parameter(length, a, alpha);
                for (xi, x, v, theta) in rows {
                    let c = e.at(xi * a);
                    let at = format!("α = {alpha}, a = {a}, s/a = {xi}");
                    assert_close(&format!("x {at}"), c.x / a, x, 1e-14);
                    assert_close(&format!("v {at}"), c.v / a, v, 1e-14);
                    assert_close(&format!("θ {at}"), c.theta, theta, 1e-14);
                }
            }
        }
    }

    #[test]
    fn integrated_shape_reproduces_the_closed_form_tip() {
        // The Taylor table and the Carlson closed form are independent routes to the tip.
        for alpha in log_sweep(1e-10, SEPARATRIX_ALPHA, 60) {
            let tip = TipAngle::for_alpha(alpha);
            let end = Elastica::from_load_parameter(1.0, 1.0, alpha).at(1.0);
            let reach = (1.0 + tip.m).sqrt() / tip.rf();
            assert_close(&format!("x_tip at α = {alpha}"), end.x, reach, 1e-14);
            assert_close(
                &format!("v_tip/δ at α = {alpha}"),
                end.v / tip.tip_drop(),
                1.0,
                4e-15,
            );
            assert_close(
                &format!("θ₀ at α = {alpha}"),
                end.theta / tip.m.atan2(tip.cos()),
                1.0,
                4e-15,
            );
            assert_close(
                &format!("α(m) at α = {alpha}"),
                tip.alpha() / alpha,
                1.0,
                4e-15,
            );
        }
    }

    #[test]
    fn small_loads_follow_the_series_to_full_precision() {
        // δ_v/L = α/3 − (4/105)α³ + 0.0081385 α⁵ and θ₀ = α/2 − (11/240)α³ (docs/mechanics.md
        // §6.4), the latter with its α⁵ term 3601/403200 (exact perturbation series, rational
        // arithmetic): the dropped terms are < 1e-17 relative for α ≤ 1e-4 and < 1e-14 at 0.01.
        for (alpha, tolerance) in [(1e-8, 1e-15), (1e-4, 1e-15), (0.01, 1e-13)] {
            let (d, _, t) = tip_values(3.0, alpha);
            let series = alpha / 3.0 - 4.0 / 105.0 * alpha.powi(3) + 0.0081385 * alpha.powi(5);
            assert_close(&format!("δ_v/L at α = {alpha}"), d / series, 1.0, tolerance);
            let angle =
                alpha / 2.0 - 11.0 / 240.0 * alpha.powi(3) + 3601.0 / 403200.0 * alpha.powi(5);
            assert_close(
                &format!("θ₀ at α = {alpha}"),
                t.to_radians() / angle,
                1.0,
                tolerance,
            );
        }
        // u/L = α²/15 − (4/315)α⁴ (+ 2126/675675 α⁶, same derivation) is a difference L − x,
        // so it is held absolutely, to 1e-15.
        for alpha in [1e-4, 0.01] {
            let (_, u, _) = tip_values(1.0, alpha);
            let a2 = alpha * alpha;
            assert_close(
                &format!("u/L at α = {alpha}"),
                u,
                a2 / 15.0 - 4.0 / 315.0 * a2 * a2 + 2126.0 / 675675.0 * a2 * a2 * a2,
                1e-15,
            );
        }
    }

    #[test]
    fn shape_is_continuous_across_the_separatrix_switch() {
        // Just below the switch the table is integrated, just above the closed form is used.
        let below = Elastica::from_load_parameter(2.0, 2.0, SEPARATRIX_ALPHA);
        let above =
            Elastica::from_load_parameter(2.0, 2.0, SEPARATRIX_ALPHA * (1.0 + f64::EPSILON));
        assert!(
            matches!(below.segment, Segment::Table(_))
                && matches!(above.segment, Segment::Separatrix { .. })
        );
        for i in 0..=2000 {
            let s = 2.0 * i as f64 / 2000.0;
            let (p, q) = (below.at(s), above.at(s));
            assert_close(&format!("x at s = {s}"), p.x, q.x, 2e-13);
            assert_close(&format!("v at s = {s}"), p.v, q.v, 2e-13);
            assert_close(&format!("θ at s = {s}"), p.theta, q.theta, 2e-12);
        }
    }

    #[test]
    fn linear_error_matches_the_table_and_is_continuous_at_its_switch() {
        // The last column of docs/mechanics.md §6.4: (α/3)/δ_v − 1, printed to 0.01 % or 1 %.
        for (alpha, percent, printed) in [
            (0.1, 0.11, 0.01),
            (0.5, 2.79, 0.01),
            (1.0, 10.5, 0.1),
            (2.0, 35.1, 0.1),
            (4.0, 99.0, 1.0),
            (10.0, 311.0, 1.0),
        ] {
            let e = Elastica::from_load_parameter(1.0, 1.0, alpha);
            assert_close(
                &format!("linear error at α = {alpha}"),
                100.0 * e.linear_error(),
                percent,
                printed / 2.0,
            );
        }
        // docs/mechanics.md §6.5: ≈ (4/35)α² for small α, to relative α².
        for alpha in [1e-6, 1e-3] {
            let e = Elastica::from_load_parameter(1.0, 1.0, alpha);
            assert_close(
                "small-α linear error",
                e.linear_error() / (4.0 / 35.0 * alpha * alpha),
                1.0,
                alpha * alpha,
            );
        }
        for (length, a) in [(1.0, 1.0), (1.0, 0.3), (4.0, 1e-6)] {
            let series = Elastica::from_load_parameter(
                length,
                a,
                LINEAR_ERROR_SERIES_BELOW * (1.0 - f64::EPSILON),
            );
            let direct = Elastica::from_load_parameter(length, a, LINEAR_ERROR_SERIES_BELOW);
            assert_close(
                &format!("switch, a = {a}"),
                series.linear_error() / direct.linear_error(),
                1.0,
                1e-10,
            );
        }
        assert_eq!(
            Elastica::from_load_parameter(1.0, 0.5, 0.0).linear_error(),
            0.0
        );
    }

    #[test]
    fn slope_of_the_centreline_is_cos_and_sin_theta() {
        // Five-point differences with h = 1e-4 L: truncation h⁴κ⁴/30 < 1e-10 for the curvatures
        // κ ≤ 63/L met here, rounding ~1e-12; stencils across the load (where θ″ jumps) are skipped.
        let h = 1e-4;
        for alpha in [0.01, 1.0, 5.0, 50.0, 500.0, 2000.0] {
            for a in [1.0, 0.4] {
                let e = Elastica::from_load_parameter(1.0, a, alpha);
                for i in 1..100 {
                    let s = i as f64 / 100.0;
                    if (s - a).abs() < 2.5 * h {
                        continue;
                    }
                    let p = [-2.0, -1.0, 1.0, 2.0].map(|k| e.at(s + k * h));
                    let dx = (p[0].x - 8.0 * p[1].x + 8.0 * p[2].x - p[3].x) / (12.0 * h);
                    let dv = (p[0].v - 8.0 * p[1].v + 8.0 * p[2].v - p[3].v) / (12.0 * h);
                    let theta = e.at(s).theta;
                    assert_close(
                        &format!("x′ at α = {alpha}, a = {a}, s = {s}"),
                        dx,
                        theta.cos(),
                        1e-9,
                    );
                    assert_close(
                        &format!("v′ at α = {alpha}, a = {a}, s = {s}"),
                        dv,
                        theta.sin(),
                        1e-9,
                    );
                }
            }
        }
    }

    #[test]
    fn angle_rises_monotonically_up_to_a_right_angle_then_the_rod_is_straight() {
        for alpha in [1e-6, 0.3, 3.0, 30.0, 300.0, 3000.0, 1e8] {
            let (length, a) = (5.0, 2.0);
            let e = Elastica::from_load_parameter(length, a, alpha);
            let end = e.at(a);
            let mut previous = 0.0;
            for i in 0..=1000 {
                let s = length * i as f64 / 1000.0;
                let c = e.at(s);
                assert!(
                    c.theta >= previous - 1e-15 && c.theta <= std::f64::consts::FRAC_PI_2,
                    "α = {alpha}, s = {s}: {c:?}"
                );
                previous = c.theta;
                if s > a {
                    // Exactly the continuation of the load point along θ₀.
                    let beyond = s - a;
                    assert_eq!(c.theta, end.theta);
                    assert_close(
                        "straight x",
                        c.x,
                        end.x + beyond * end.theta.cos(),
                        1e-14 * length,
                    );
                    assert_close(
                        "straight v",
                        c.v,
                        end.v + beyond * end.theta.sin(),
                        1e-14 * length,
                    );
                }
            }
            let clamp = e.at(0.0);
            assert!(
                clamp.x.abs().max(clamp.v.abs()) < 1e-15 * length && clamp.theta.abs() < 1e-14,
                "α = {alpha}: {clamp:?}"
            );
        }
    }

    #[test]
    fn arc_length_is_preserved() {
        // Chord sums fall short of the arc by (h²/24)∫κ²; Richardson extrapolation over n and 2n
        // chords removes that term, leaving O(h⁴) < 1e-11 for these curvatures.
        let chords = |e: &Elastica, n: usize| -> f64 {
            (0..n)
                .map(|i| {
                    let (p, q) = (
                        e.at(e.length * i as f64 / n as f64),
                        e.at(e.length * (i + 1) as f64 / n as f64),
                    );
                    (q.x - p.x).hypot(q.v - p.v)
                })
                .sum()
        };
        for alpha in [0.1, 2.0, 20.0, 200.0, 2000.0] {
            for a in [3.0, 1.2] {
                let e = Elastica::from_load_parameter(3.0, a, alpha);
                let (coarse, fine) = (chords(&e, 20_000), chords(&e, 40_000));
                assert_close(
                    &format!("arc length at α = {alpha}, a = {a}"),
                    (4.0 * fine - coarse) / 3.0,
                    3.0,
                    1e-11,
                );
            }
        }
    }

    #[test]
    fn tip_deflection_round_trips() {
        // The tip lands on the target to 1e-13 relative (the solve works in sin θ₀ directly,
        // so tiny targets keep full precision), and rebuilding from the reported α gives the
        // same shape.
        for length in [1.0, 6.0] {
            for load_at in [length, 0.5 * length, 1e-3 * length, 0.0] {
                for fraction in [1e-9, 1e-6, 0.01, 0.1, 0.3, 0.5, 0.8, 0.95, 0.99, 0.999_999] {
                    for sign in [1.0, -1.0] {
                        let target = sign * fraction * length;
                        let e = Elastica::from_tip_deflection(length, load_at, target).unwrap();
                        let at = format!("L = {length}, a = {load_at}, δ = {target}");
                        assert_close(&at, e.at(length).v / target, 1.0, 1e-13);
                        assert_eq!(e.alpha().signum(), sign, "{at}");
                        let again =
                            Elastica::from_load_parameter(length, load_at, e.alpha()).at(length);
                        assert_close(&format!("rebuilt {at}"), again.v / target, 1.0, 1e-13);
                    }
                }
            }
        }
        let zero = Elastica::from_tip_deflection(2.0, 1.0, 0.0).unwrap();
        assert_eq!(
            (zero.alpha(), zero.at(2.0)),
            (
                0.0,
                Centreline {
                    x: 2.0,
                    v: 0.0,
                    theta: 0.0
                }
            )
        );
    }

    #[test]
    fn unreachable_tip_deflections_are_errors_naming_the_value() {
        for bad in [2.0, -2.0, 2.5, f64::INFINITY, f64::NAN] {
            let message = Elastica::from_tip_deflection(2.0, 1.0, bad).unwrap_err();
            assert!(message.contains(&bad.to_string()), "{message}");
        }
        assert!(
            Elastica::from_tip_deflection(0.0, 0.0, 0.1)
                .unwrap_err()
                .contains('0')
        );
        assert!(
            Elastica::from_tip_deflection(-1.0, 0.5, 0.1)
                .unwrap_err()
                .contains("-1")
        );
    }

    #[test]
    fn no_load_is_the_straight_rod_and_an_upward_load_the_mirror_image() {
        let straight = Elastica::from_load_parameter(3.0, 1.0, 0.0);
        for s in [0.0, 0.5, 1.0, 2.9, 3.0] {
            assert_eq!(
                straight.at(s),
                Centreline {
                    x: s,
                    v: 0.0,
                    theta: 0.0
                }
            );
        }
        let (down, up) = (
            Elastica::from_load_parameter(3.0, 1.0, 7.0),
            Elastica::from_load_parameter(3.0, 1.0, -7.0),
        );
        for s in [0.0, 0.5, 1.0, 2.9, 3.0] {
            let (d, u) = (down.at(s), up.at(s));
            assert_eq!(
                u,
                Centreline {
                    x: d.x,
                    v: -d.v,
                    theta: -d.theta
                }
            );
        }
        assert_eq!(up.linear_error(), down.linear_error());
    }

    #[test]
    fn no_nan_or_infinity_anywhere() {
        let alphas = [
            0.0,
            -0.0,
            1e-300,
            5e-324,
            1e4,
            1e6,
            1e12,
            1e300,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ]
        .into_iter()
        .chain(log_sweep(1e-12, 1e3, 90))
        .chain(log_sweep(1e-12, 1e3, 15).map(|a| -a));
        let loads = [
            1e-6,
            1e-4,
            0.01,
            0.1,
            0.5,
            0.9,
            1.0,
            0.0,
            -1.0,
            2.0,
            f64::NAN,
        ];
        for alpha in alphas {
            for load in loads {
                let e = Elastica::from_load_parameter(2.0, 2.0 * load, alpha);
                assert_finite(&e, &format!("α = {alpha}, a/L = {load}"));
            }
        }
        for length in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e-300, 1e300] {
            assert_finite(
                &Elastica::from_load_parameter(length, 0.5, 3.0),
                &format!("L = {length}"),
            );
        }
        for fraction in log_sweep(1e-12, 1.0 - 1e-15, 40) {
            for load in [1e-6, 0.3, 1.0] {
                let e = Elastica::from_tip_deflection(2.0, 2.0 * load, 2.0 * fraction).unwrap();
                assert_finite(&e, &format!("δ/L = {fraction}, a/L = {load}"));
            }
        }
    }
}
