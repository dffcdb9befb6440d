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

    /// Undistorted normalised coordinates whose distortion is (x_d, y_d), by Newton's method
    /// from (x_d, y_d); None when it does not converge (the lens folds the image there).
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        if self.is_none() {
            return Some((xd, yd));
        }
        let (mut x, mut y) = (xd, yd);
        for _ in 0..50 {
            let ((fx, fy), [[a, b], [c, d]]) = self.with_jacobian(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            let det = a * d - b * c;
            if !(det.is_finite() && det.abs() > 1e-300) {
                return None;
            }
            let (dx, dy) = ((d * ex - b * ey) / det, (a * ey - c * ex) / det);
            x -= dx;
            y -= dy;
            if dx.abs() + dy.abs() <= 1e-15 * (1.0 + x.abs() + y.abs()) {
                return (x.is_finite() && y.is_finite()).then_some((x, y));
            }
        }
        None
    }

    /// Checks that the distortion maps the frame one-to-one: along every direction the
    /// distorted radius must grow with the undistorted radius up to the farthest corner of
    /// the image (`reach`, in normalised distorted units), and each pixel must invert. The
    /// message names the coefficients.
    pub fn validate(&self, reach: f64) -> Result<(), String> {
        if self.is_none() {
            return Ok(());
        }
        let coefficients = [self.k1, self.k2, self.p1, self.p2, self.k3];
        if coefficients.iter().any(|c| !c.is_finite()) {
            return Err(format!(
                "dataset.camera.distortion {coefficients:?} must be finite"
            ));
        }
        let folds = || {
            Err(format!(
                "dataset.camera.distortion k1 = {}, k2 = {}, p1 = {}, p2 = {}, k3 = {} folds the image before its corners (distorted radius {reach:.3}): the lens model is not one-to-one there; use smaller coefficients",
                self.k1, self.k2, self.p1, self.p2, self.k3
            ))
        };
        for direction in 0..64 {
            let angle = std::f64::consts::TAU * f64::from(direction) / 64.0;
            let (c, s) = (angle.cos(), angle.sin());
            let mut previous = 0.0;
            let mut r: f64 = 0.0;
            // Walk outwards until the distorted radius passes the corners with a margin.
            loop {
                r += 1e-3 * reach.max(1e-3);
                let (xd, yd) = self.distort(r * c, r * s);
                let rd = xd.hypot(yd);
                if !(rd > previous) {
                    return folds();
                }
                previous = rd;
                if rd > 1.05 * reach {
                    break;
                }
                if r > 1e3 * reach.max(1.0) {
                    return folds();
                }
            }
        }
        Ok(())
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
    fn a_folding_lens_is_refused_and_a_usual_one_accepted() {
        assert!(lens().validate(0.8).is_ok());
        // Strong barrel: the distorted radius r(1 − 0.8 r²) peaks at r = 0.65 (0.43).
        let folding = Distortion {
            k1: -0.8,
            ..Distortion::default()
        };
        assert!(folding.validate(0.3).is_ok());
        assert!(
            folding
                .validate(0.6)
                .unwrap_err()
                .contains("folds the image")
        );
    }
}
