//! One point load on a simply supported beam or a cantilever, in shape form.

use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Support {
    /// Pin at x = 0, roller at x = L.
    SimplySupported,
    /// Clamped at x = 0, free at x = L.
    Cantilever,
}

impl Support {
    pub fn name(self) -> &'static str {
        match self {
            Support::SimplySupported => "simply_supported",
            Support::Cantilever => "cantilever",
        }
    }
}

/// Deflection, slope and curvature of the axis at one station (v positive downward).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deflection {
    pub v: f64,
    pub slope: f64,
    pub curvature: f64,
}

/// The deflected shape of a beam under one point load P at x = a, scaled so that the
/// largest deflection is `peak`.
///
/// Internally every unit-load quantity is divided by the factor that vanishes as the load
/// approaches a support (a for a simply supported beam with a ≤ L/2, a² for a cantilever).
/// The normalised shape therefore stays finite and exact up to a = 0 and a = L, where it
/// becomes the limit shape; only the physical load diverges there.
#[derive(Clone, Copy, Debug)]
pub struct PointLoadShape {
    pub support: Support,
    pub length: f64,
    pub load_at: f64,
    pub peak: f64,
    /// Simply supported only: the problem is solved mirrored so that the load is in the left half.
    mirrored: bool,
    /// Load position in the (possibly mirrored) solving frame.
    a: f64,
    /// max |v| of the reduced unit-load solution (unit P, unit EI, divided by the small factor).
    reduced_max: f64,
    reduced_max_at: f64,
}

impl PointLoadShape {
    /// `load_at` must lie in [0, L], `length` must be positive; both are checked by the caller.
    pub fn new(support: Support, length: f64, load_at: f64, peak: f64) -> Self {
        let l = length;
        let (mirrored, a) = match support {
            Support::SimplySupported if load_at > 0.5 * l => (true, l - load_at),
            _ => (false, load_at),
        };
        let (reduced_max, reduced_max_at) = match support {
            Support::SimplySupported => {
                let b = l - a;
                let s = b * (l + a);
                (s * s.sqrt() / (9.0 * 3f64.sqrt() * l), l - (s / 3.0).sqrt())
            }
            Support::Cantilever => ((3.0 * l - a) / 6.0, l),
        };
        PointLoadShape { support, length, load_at, peak, mirrored, a, reduced_max, reduced_max_at }
    }

    /// Where the largest deflection occurs, in the beam frame.
    pub fn peak_at(&self) -> f64 {
        self.unmirror(self.reduced_max_at)
    }

    /// Deflection, slope and curvature at x ∈ [0, L].
    pub fn at(&self, x: f64) -> Deflection {
        let xs = self.unmirror(x);
        let (v, slope, curvature) = self.reduced(xs);
        let scale = self.peak / self.reduced_max;
        let sign = if self.mirrored { -1.0 } else { 1.0 };
        Deflection { v: scale * v, slope: sign * scale * slope, curvature: scale * curvature }
    }

    /// Largest bending moment for the unit-EI solution that produces the peak, times EI:
    /// M_max = EI · max|v''|. The physical load is P = EI · peak / (small factor · reduced_max).
    pub fn labels(&self, ei: f64) -> LoadLabels {
        let l = self.length;
        let a = self.a;
        let small = match self.support {
            Support::SimplySupported => a,
            Support::Cantilever => a * a,
        };
        // Unit-load peak deflection and moment per unit load.
        let unit_peak = small * self.reduced_max;
        let unit_moment = match self.support {
            Support::SimplySupported => a * (l - a) / l,
            Support::Cantilever => a,
        };
        if unit_peak == 0.0 {
            return LoadLabels { load: None, max_moment: None };
        }
        let load = ei * self.peak / unit_peak;
        LoadLabels { load: Some(load), max_moment: Some(load * unit_moment) }
    }

    fn unmirror(&self, x: f64) -> f64 {
        if self.mirrored { self.length - x } else { x }
    }

    /// Reduced unit-load solution (v, v', |v''|) at x in the solving frame.
    fn reduced(&self, x: f64) -> (f64, f64, f64) {
        let l = self.length;
        let a = self.a;
        match self.support {
            Support::SimplySupported => {
                let b = l - a;
                if x <= a && a > 0.0 {
                    let r = x / a;
                    let c = a * (l + b);
                    (b * r * (c - x * x) / (6.0 * l), b * (c - 3.0 * x * x) / (6.0 * l * a), b * r / l)
                } else {
                    let xb = l - x;
                    let c = b * (l + a);
                    (xb * (c - xb * xb) / (6.0 * l), -(c - 3.0 * xb * xb) / (6.0 * l), xb / l)
                }
            }
            Support::Cantilever => {
                if x <= a && a > 0.0 {
                    let r = x / a;
                    (r * r * (3.0 * a - x) / 6.0, r * (2.0 * a - x) / (2.0 * a), (a - x) / (a * a))
                } else {
                    ((3.0 * x - a) / 6.0, 0.5, 0.0)
                }
            }
        }
    }
}

/// Physical quantities that would produce the requested shape (None where no finite load does).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadLabels {
    pub load: Option<f64>,
    pub max_moment: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Textbook (unsafe but exact for moderate a) unit-load deflection, used as independent truth.
    fn textbook(support: Support, l: f64, a: f64, x: f64) -> f64 {
        match support {
            Support::SimplySupported => {
                let b = l - a;
                if x <= a {
                    b * x * (l * l - b * b - x * x) / (6.0 * l)
                } else {
                    let xb = l - x;
                    a * xb * (l * l - a * a - xb * xb) / (6.0 * l)
                }
            }
            Support::Cantilever => {
                if x <= a { x * x * (3.0 * a - x) / 6.0 } else { a * a * (3.0 * x - a) / 6.0 }
            }
        }
    }

    fn sampled_peak(support: Support, l: f64, a: f64) -> f64 {
        (0..=20_000).map(|i| textbook(support, l, a, l * i as f64 / 20_000.0).abs()).fold(0.0, f64::max)
    }

    #[test]
    fn shape_matches_textbook_formulas_everywhere() {
        for support in [Support::SimplySupported, Support::Cantilever] {
            for &(l, a) in &[(1.0, 0.5), (4.0, 1.0), (4.0, 3.0), (2.5, 2.5), (3.0, 0.3)] {
                let shape = PointLoadShape::new(support, l, a, 0.02);
                let peak = sampled_peak(support, l, a);
                if peak == 0.0 {
                    continue; // load on a support: covered by the limit test below
                }
                for i in 0..=200 {
                    let x = l * i as f64 / 200.0;
                    let want = 0.02 * textbook(support, l, a, x) / peak;
                    let got = shape.at(x).v;
                    assert!((got - want).abs() < 1e-6 * 0.02, "{support:?} L={l} a={a} x={x}: {got} vs {want}");
                }
            }
        }
    }

    #[test]
    fn peak_is_the_requested_deflection_at_the_closed_form_location() {
        // Centre load: peak at L/2; cantilever: at the tip.
        let ss = PointLoadShape::new(Support::SimplySupported, 2.0, 1.0, 0.05);
        assert!((ss.peak_at() - 1.0).abs() < 1e-12);
        assert!((ss.at(1.0).v - 0.05).abs() < 1e-15);
        let c = PointLoadShape::new(Support::Cantilever, 2.0, 0.7, 0.05);
        assert_eq!(c.peak_at(), 2.0);
        assert!((c.at(2.0).v - 0.05).abs() < 1e-15);
        // Off-centre: x_m = sqrt(a(L+b)/3) for a ≥ b.
        let off = PointLoadShape::new(Support::SimplySupported, 4.0, 3.0, 0.01);
        assert!((off.peak_at() - (3.0f64 * 5.0 / 3.0).sqrt()).abs() < 1e-12);
        assert!((off.at(off.peak_at()).v - 0.01).abs() < 1e-15);
    }

    #[test]
    fn slope_and_curvature_are_derivatives_of_the_deflection() {
        for support in [Support::SimplySupported, Support::Cantilever] {
            let shape = PointLoadShape::new(support, 3.0, 2.1, 0.04);
            let h = 1e-5;
            for i in 1..60 {
                let x = 3.0 * i as f64 / 60.0 + 0.013;
                let d = shape.at(x);
                let fd_slope = (shape.at(x + h).v - shape.at(x - h).v) / (2.0 * h);
                let fd_curv = (shape.at(x + h).v - 2.0 * d.v + shape.at(x - h).v) / (h * h);
                assert!((d.slope - fd_slope).abs() < 1e-8, "{support:?} slope at {x}");
                assert!((d.curvature - fd_curv.abs()).abs() < 1e-4, "{support:?} curvature at {x}");
            }
        }
    }

    #[test]
    fn supports_hold_and_clamp_has_zero_slope() {
        let ss = PointLoadShape::new(Support::SimplySupported, 3.0, 0.9, 0.03);
        assert_eq!(ss.at(0.0).v, 0.0);
        assert!(ss.at(3.0).v.abs() < 1e-18);
        let c = PointLoadShape::new(Support::Cantilever, 3.0, 0.9, 0.03);
        assert_eq!(c.at(0.0).v, 0.0);
        assert_eq!(c.at(0.0).slope, 0.0);
        // Beyond the load the cantilever is straight.
        assert!((c.at(2.0).slope - c.at(2.9).slope).abs() < 1e-15);
    }

    #[test]
    fn loads_at_and_near_supports_stay_finite_and_converge() {
        for support in [Support::SimplySupported, Support::Cantilever] {
            let ends: &[f64] = match support {
                Support::SimplySupported => &[0.0, 3.0],
                Support::Cantilever => &[0.0],
            };
            for &end in ends {
                let limit = PointLoadShape::new(support, 3.0, end, 0.01);
                let near = PointLoadShape::new(support, 3.0, (end - 1e-9).abs().min(3.0).max(1e-9), 0.01);
                for i in 0..=30 {
                    let x = 0.1 * i as f64;
                    let (dl, dn) = (limit.at(x), near.at(x));
                    assert!(dl.v.is_finite() && dl.slope.is_finite() && dl.curvature.is_finite());
                    assert!((dl.v - dn.v).abs() < 1e-8, "{support:?} end={end} x={x}: {} vs {}", dl.v, dn.v);
                }
                assert!((limit.at(limit.peak_at()).v - 0.01).abs() < 1e-15);
                assert_eq!(limit.labels(1.0).load, None, "a load on a support has no finite value");
            }
        }
    }

    #[test]
    fn labels_match_closed_form_loads() {
        // Centre load on SS: δ = PL³/48EI, M = PL/4. Cantilever tip load: δ = PL³/3EI, M = PL.
        let ei = 2.1e11 * 8.33e-6;
        let ss = PointLoadShape::new(Support::SimplySupported, 4.0, 2.0, 0.01).labels(ei);
        let p = 48.0 * ei * 0.01 / 64.0;
        assert!((ss.load.unwrap() / p - 1.0).abs() < 1e-12);
        assert!((ss.max_moment.unwrap() / (p * 1.0) - 1.0).abs() < 1e-12);
        let c = PointLoadShape::new(Support::Cantilever, 4.0, 4.0, 0.01).labels(ei);
        let p = 3.0 * ei * 0.01 / 64.0;
        assert!((c.load.unwrap() / p - 1.0).abs() < 1e-12);
        assert!((c.max_moment.unwrap() / (p * 4.0) - 1.0).abs() < 1e-12);
    }
}
