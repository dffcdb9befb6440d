//! Lens distortion in OpenCV's Brown–Conrady model (Brown 1966, "Decentering distortion of
//! lenses"; Conrady 1919; OpenCV's `calib3d` documentation): radial k1, k2, k3 and tangential
//! p1, p2 act on normalised image coordinates (x, y) = (X/Z, Y/Z):
//!
//! ```text
//! r² = x² + y²,  radial = 1 + k1 r² + k2 r⁴ + k3 r⁶
//! x_d = x·radial + 2 p1 x y + p2 (r² + 2x²)
//! y_d = y·radial + p1 (r² + 2y²) + 2 p2 x y
//! ```
//!
//! A distorted image is rendered exactly by tracing, for each pixel, the ray of the undistorted
//! coordinates that distort onto it: the inverse is solved by Newton's method on this 2 × 2
//! system, to full precision. Calibration code that undistorts with OpenCV then recovers the
//! pinhole image.

use serde::Serialize;

/// Why a lens leaves some pixels without a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LensFault {
    /// It stops being one-to-one at this distorted radius (normalised).
    Folds {
        /// The distorted radius it is one-to-one out to.
        at: f64,
    },
    /// Its inverse fails at this distorted point (normalised).
    NoInverse {
        /// The point.
        at: (f64, f64),
    },
}

impl std::fmt::Display for LensFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LensFault::Folds { at } => write!(f, "is one-to-one only out to {at:.3}"),
            LensFault::NoInverse { at: (x, y) } => write!(
                f,
                "has no inverse at the distorted point ({x:.3}, {y:.3}) (coefficients far beyond any real lens')"
            ),
        }
    }
}

/// Brown–Conrady coefficients, in OpenCV's order and meaning (all zero: a pinhole camera).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Distortion {
    /// First radial coefficient (negative: barrel, positive: pincushion).
    pub k1: f64,
    /// Second radial coefficient.
    pub k2: f64,
    /// First tangential (decentering) coefficient.
    pub p1: f64,
    /// Second tangential (decentering) coefficient.
    pub p2: f64,
    /// Third radial coefficient.
    pub k3: f64,
}

impl Distortion {
    /// Whether the lens is an ideal pinhole.
    pub fn is_none(&self) -> bool {
        *self == Distortion::default()
    }

    /// Distorted normalised coordinates of undistorted (x, y).
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        (
            x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        )
    }

    /// The distortion and its Jacobian ∂(x_d, y_d)/∂(x, y) at (x, y).
    fn with_jacobian(&self, x: f64, y: f64) -> ((f64, f64), [[f64; 2]; 2]) {
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        // d(radial)/d(r²)
        let slope = self.k1 + r2 * (2.0 * self.k2 + 3.0 * self.k3 * r2);
        let dxx = radial + 2.0 * x * x * slope + 2.0 * self.p1 * y + 6.0 * self.p2 * x;
        let dxy = 2.0 * x * y * slope + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
        let dyx = 2.0 * x * y * slope + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
        let dyy = radial + 2.0 * y * y * slope + 6.0 * self.p1 * y + 2.0 * self.p2 * x;
        (self.distort(x, y), [[dxx, dxy], [dyx, dyy]])
    }

    /// Undistorted normalised coordinates whose distortion is (x_d, y_d): Newton's method from
    /// (x_d, y_d), and where that does not converge, the same solution followed out from the
    /// centre (where the inverse is the identity) in small steps. None when neither converges:
    /// the lens folds the image there, and (x_d, y_d) has no ray.
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        if self.is_none() {
            return Some((xd, yd));
        }
        self.newton((xd, yd), (xd, yd))
            .or_else(|| self.continued(xd, yd))
    }

    /// Newton's method on distort(x, y) = `target` from `start`, to full precision.
    ///
    /// Where the lens is nearly flat radially (the distorted radius barely grows, as towards
    /// the corners of a wide-angle barrel lens), rounding in the residual moves the steps by
    /// several ulps of x without end, so converging is judged by the residual as well: a point
    /// that reproduces the target to rounding is the inverse.
    fn newton(&self, (xd, yd): (f64, f64), (mut x, mut y): (f64, f64)) -> Option<(f64, f64)> {
        let rounding = 8.0 * f64::EPSILON * (1.0 + xd.abs() + yd.abs());
        let mut residual = f64::INFINITY;
        for _ in 0..50 {
            let ((fx, fy), [[a, b], [c, d]]) = self.with_jacobian(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            residual = ex.abs() + ey.abs();
            let det = a * d - b * c;
            if !(det.is_finite() && det.abs() > 1e-300) {
                return None;
            }
            let (dx, dy) = ((d * ex - b * ey) / det, (a * ey - c * ex) / det);
            x -= dx;
            y -= dy;
            let settled = dx.abs() + dy.abs() <= 1e-15 * (1.0 + x.abs() + y.abs());
            if settled || residual <= rounding {
                break;
            }
        }
        let (fx, fy) = self.distort(x, y);
        residual = residual.min((fx - xd).abs() + (fy - yd).abs());
        (x.is_finite() && y.is_finite() && residual <= 64.0 * rounding).then_some((x, y))
    }

    /// The inverse at (x_d, y_d) by continuation along the segment from the centre: each
    /// step's solution starts Newton's method for the next, so it stays on the one-to-one
    /// branch even where a start at (x_d, y_d) would not converge.
    fn continued(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        const STEPS: u32 = 32;
        (1..=STEPS).try_fold((0.0, 0.0), |at, step| {
            let t = f64::from(step) / f64::from(STEPS);
            self.newton((t * xd, t * yd), at)
        })
    }

    /// How far out (distorted radius, normalised units) the lens maps the image one-to-one,
    /// when that is short of `reach` (the farthest point a camera images, with a 5 % margin):
    /// along each of 64 directions the distorted radius must grow with the undistorted one
    /// until it passes 1.05 × `reach`. None when it does along every direction.
    pub fn fold_within(&self, reach: f64) -> Option<f64> {
        if self.is_none() {
            return None;
        }
        let step = 1e-3 * reach.max(1e-3);
        let limit = 1.05 * reach;
        let folds = (0..64).filter_map(|direction| {
            let angle = std::f64::consts::TAU * f64::from(direction) / 64.0;
            let (s, c) = angle.sin_cos();
            let (mut r, mut reached) = (0.0f64, 0.0f64);
            // Walk outwards until the distorted radius passes the limit, or stops growing.
            while reached <= limit {
                r += step;
                let (xd, yd) = self.distort(r * c, r * s);
                let rd = xd.hypot(yd);
                if !(rd > reached) || r > 1e3 * reach.max(1.0) {
                    return Some(reached);
                }
                reached = rd;
            }
            None
        });
        folds.reduce(f64::min)
    }

    /// What keeps some distorted point within `reach` (normalised units; the 5 % margin of
    /// [`Distortion::fold_within`] included) from having a ray, if anything: the lens folds,
    /// or, with coefficients far beyond any real lens' (k1 = 10³⁰, say), floating point
    /// leaves its inverse nothing to converge to. The inverse is tried on 64 directions × 32
    /// radii and must reproduce each point.
    pub fn fault_within(&self, reach: f64) -> Option<LensFault> {
        if let Some(at) = self.fold_within(reach) {
            return Some(LensFault::Folds { at });
        }
        if self.is_none() {
            return None;
        }
        let limit = 1.05 * reach;
        let points = (0..64).flat_map(|direction| {
            let (s, c) = (std::f64::consts::TAU * f64::from(direction) / 64.0).sin_cos();
            (1..=32).map(move |k| {
                (
                    limit * c * f64::from(k) / 32.0,
                    limit * s * f64::from(k) / 32.0,
                )
            })
        });
        let misses = |&(xd, yd): &(f64, f64)| match self.undistort(xd, yd) {
            None => true,
            Some((x, y)) => {
                let (u, v) = self.distort(x, y);
                (u - xd).hypot(v - yd) > 1e-12 * (1.0 + xd.hypot(yd))
            }
        };
        points
            .filter(misses)
            .map(|at| LensFault::NoInverse { at })
            .next()
    }

    /// The lens of a camera turned about its optical axis by `angle` (the turn of
    /// [`Camera`](super::Camera) an image-plane rotation R(θ) makes, x towards y), seen in the
    /// turned camera's axes: D′(x) = R(θ)·D(R(θ)ᵀx). The radial part commutes with rotations;
    /// the tangential part is |x|²q + 2(q·x)x with q = (p2, p1), which turns as a vector:
    /// q′ = R(θ)q.
    pub fn turned(&self, angle: f64) -> Distortion {
        // libm, as the warp's own rotation: the same bits on every CPU.
        let (s, c) = libm::sincos(angle);
        Distortion {
            p2: c * self.p2 - s * self.p1,
            p1: s * self.p2 + c * self.p1,
            ..*self
        }
    }

    /// The coefficients as messages show them.
    pub fn describe(&self) -> String {
        let n = crate::words::number;
        format!(
            "k1 = {}, k2 = {}, p1 = {}, p2 = {}, k3 = {}",
            n(self.k1),
            n(self.k2),
            n(self.p1),
            n(self.p2),
            n(self.k3)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens() -> Distortion {
        Distortion {
            k1: -0.28,
            k2: 0.07,
            p1: 1.2e-3,
            p2: -8e-4,
            k3: -0.01,
        }
    }

    #[test]
    fn undistort_inverts_distort_to_full_precision() {
        let d = lens();
        for (x, y) in [
            (0.0, 0.0),
            (0.3, -0.2),
            (-0.55, 0.41),
            (0.62, 0.6),
            (1e-9, -2e-9),
        ] {
            let (xd, yd) = d.distort(x, y);
            let (u, v) = d.undistort(xd, yd).unwrap();
            assert!((u - x).abs() < 1e-14 && (v - y).abs() < 1e-14, "{x},{y}");
        }
    }

    #[test]
    fn a_wide_angle_lens_inverts_where_it_is_nearly_flat_radially() {
        // Common wide-angle barrel coefficients: at the corner of a 60° view the distorted
        // radius grows only 0.14 times as fast as the undistorted one.
        let wide = Distortion {
            k1: -0.2,
            k2: 0.02,
            p1: 0.001,
            p2: -0.001,
            k3: 0.0,
        };
        assert_eq!(wide.fault_within(0.962), None);
        let (x, y) = wide.undistort(0.904, 0.375).unwrap();
        let (u, v) = wide.distort(x, y);
        assert!((u - 0.904).abs() < 1e-14 && (v - 0.375).abs() < 1e-14);
        // The inverse found independently (Newton with a finite-difference Jacobian).
        assert!(
            (x - 1.4228286).abs() < 1e-6 && (y - 0.5849658).abs() < 1e-6,
            "{x}, {y}"
        );
    }

    #[test]
    fn the_jacobian_matches_finite_differences() {
        let d = lens();
        let (x, y, h) = (0.37, -0.21, 1e-6);
        let (_, j) = d.with_jacobian(x, y);
        let dx = |f: &dyn Fn(f64, f64) -> (f64, f64)| {
            let (a, b) = (f(x + h, y), f(x - h, y));
            ((a.0 - b.0) / (2.0 * h), (a.1 - b.1) / (2.0 * h))
        };
        let dy = |f: &dyn Fn(f64, f64) -> (f64, f64)| {
            let (a, b) = (f(x, y + h), f(x, y - h));
            ((a.0 - b.0) / (2.0 * h), (a.1 - b.1) / (2.0 * h))
        };
        let distort = |x: f64, y: f64| d.distort(x, y);
        let (ax, ay) = dx(&distort);
        let (bx, by) = dy(&distort);
        for (got, want) in [(j[0][0], ax), (j[1][0], ay), (j[0][1], bx), (j[1][1], by)] {
            assert!((got - want).abs() < 1e-8, "{got} vs {want}");
        }
    }

    #[test]
    fn a_folding_lens_is_found_and_a_usual_one_accepted() {
        assert_eq!(lens().fold_within(0.8), None);
        // Strong barrel: the distorted radius r(1 − 0.8 r²) peaks at r = 1/√2.4 (0.430).
        let folding = Distortion {
            k1: -0.8,
            ..Distortion::default()
        };
        assert_eq!(folding.fold_within(0.3), None);
        let peak = (1.0 / 2.4f64).sqrt() * (1.0 - 0.8 / 2.4);
        let fold = folding.fold_within(0.6).unwrap();
        assert!((fold - peak).abs() < 1e-5, "{fold} vs {peak}");
    }

    /// Rotates (x, y) by `angle`, x towards y.
    fn rotate(angle: f64, (x, y): (f64, f64)) -> (f64, f64) {
        let (s, c) = angle.sin_cos();
        (c * x - s * y, s * x + c * y)
    }

    #[test]
    fn a_lens_whose_inverse_fails_in_floating_point_is_found() {
        // Pincushion so strong that the undistorted radius of a corner is about 10⁻¹⁰: the
        // lens is monotone, but nothing converges to full precision.
        let absurd = Distortion {
            k1: 1e30,
            ..Distortion::default()
        };
        assert_eq!(absurd.fold_within(0.8), None);
        assert!(matches!(
            absurd.fault_within(0.8),
            Some(LensFault::NoInverse { .. })
        ));
        assert_eq!(lens().fault_within(0.8), None);
    }

    #[test]
    fn a_turned_lens_is_the_lens_seen_from_the_turned_camera() {
        let d = lens();
        for angle in [0.3, -1.9, 2.7] {
            let turned = d.turned(angle);
            for (x, y) in [(0.31, -0.2), (-0.5, 0.44), (0.05, 0.6)] {
                // The point seen at (x, y) by the turned camera is at Rᵀ(x, y) for the
                // original one; its image, turned back into the new axes, must match.
                let (u, v) = d.distort(rotate(-angle, (x, y)).0, rotate(-angle, (x, y)).1);
                let want = rotate(angle, (u, v));
                let got = turned.distort(x, y);
                assert!((got.0 - want.0).abs() < 1e-15 && (got.1 - want.1).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn every_pixel_of_a_lens_at_the_fold_limit_inverts() {
        // Barrel lenses whose fold lies just past the corners (the margin the checks keep),
        // with decentering: each pixel's inverse exists and reproduces it.
        for (k1, p1, p2) in [(-0.195, 0.0, 0.0), (-0.3, 4e-3, -3e-3), (0.4, -2e-3, 1e-3)] {
            let d = Distortion {
                k1,
                p1,
                p2,
                ..Distortion::default()
            };
            // The largest corner reach the check accepts for this lens, to 1 %.
            let mut reach = 0.05;
            while d.fault_within(reach * 1.01).is_none() && reach < 3.0 {
                reach *= 1.01;
            }
            let n = 120;
            for i in 0..=n {
                for j in 0..=n {
                    let (xd, yd) = (
                        reach * (2.0 * f64::from(j) / f64::from(n) - 1.0) / 2f64.sqrt(),
                        reach * (2.0 * f64::from(i) / f64::from(n) - 1.0) / 2f64.sqrt(),
                    );
                    let (x, y) = d.undistort(xd, yd).expect("an inverse");
                    let (u, v) = d.distort(x, y);
                    assert!((u - xd).abs() < 1e-13 && (v - yd).abs() < 1e-13, "{k1}");
                }
            }
        }
    }
}
