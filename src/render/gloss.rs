//! The glossy lobe: Blinn's half-vector highlight (J. F. Blinn, "Models of light reflection
//! for computer synthesized pictures", SIGGRAPH 1977), normalised so that it reflects the
//! same energy at any sharpness ((e + 8) / 8π, Akenine-Möller et al., *Real-Time Rendering*,
//! 4th ed., §9.8), with Schlick's Fresnel approximation (C. Schlick, "An inexpensive BRDF
//! model for physically-based rendering", Computer Graphics Forum 13(3), 1994), and the power
//! x^e it needs at every lit glossy point.
//!
//! The power is libm's exp2(e · log2 x), not the platform's `pow`: glibc picks an FMA or a
//! plain version by CPU, which may round differently, and the image must be the same on
//! every x86-64 machine; libm's own `pow` is three times slower, a tenth of a textured view's
//! time. (A power from short series of our own was tried: no faster than libm's tables.)
//!
//! Owns: the lobe and its power. Must not touch: lights, shadows, materials.

use crate::materials::Surface;
use glam::DVec3;
use std::f64::consts::PI;

/// The highlight of a glossy surface, its exponent worked out once per shaded point rather
/// than once per light.
pub(super) struct Lobe {
    /// Reflectance at normal incidence.
    specular: f64,
    /// Blinn–Phong exponent of the surface's roughness.
    exponent: f64,
}

impl Lobe {
    /// The lobe of `surface`, if it has one (a specular reflectance above zero). Roughness r
    /// maps to α = r² and the exponent 2/α² − 2 (Walter et al., EGSR 2007, eq. 30's
    /// Beckmann–Phong correspondence), α kept above 10⁻³.
    pub(super) fn of(surface: &Surface) -> Option<Lobe> {
        (surface.specular > 0.0).then(|| {
            let alpha = (surface.roughness * surface.roughness).max(1e-3);
            let exponent = (2.0 / (alpha * alpha) - 2.0).max(0.0);
            Lobe {
                specular: surface.specular,
                exponent,
            }
        })
    }

    /// The share of a light along unit `l` reflected towards unit `to_eye` by a surface with
    /// unit normal `n` (per unit irradiance).
    pub(super) fn glint(&self, n: DVec3, l: DVec3, to_eye: DVec3) -> f64 {
        let h = (l + to_eye).normalize_or_zero();
        let fresnel =
            self.specular + (1.0 - self.specular) * (1.0 - to_eye.dot(h).max(0.0)).powi(5);
        // (e + 8) / 8π: the lobe reflects the same energy however sharp it is.
        fresnel * (self.exponent + 8.0) / (8.0 * PI) * power(n.dot(h).max(0.0), self.exponent)
    }
}

/// x^e for x in [0, 1] and e ≥ 0, as 2^(e log₂ x): relative error below
/// 5·10⁻¹⁶ (1 + |e log₂ x|), far below an 8-bit step.
fn power(x: f64, e: f64) -> f64 {
    if x == 0.0 {
        return if e == 0.0 { 1.0 } else { 0.0 };
    }
    libm::exp2(e * libm::log2(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `power` is within its stated bound of libm's pow (itself within an ulp).
    fn within_bound(x: f64, e: f64) -> bool {
        let exact = libm::pow(x, e);
        if exact < 1e-300 {
            return power(x, e) < 1e-300;
        }
        let y = (e * libm::log2(x)).abs();
        ((power(x, e) - exact) / exact).abs() < 5e-16 * (1.0 + y)
    }

    #[test]
    fn power_agrees_with_pow_across_the_lobes() {
        // From nearly matte (roughness 0.99) to the sharpest lobe (α = 10⁻³).
        let exponents = [
            1e-3,
            0.082,
            0.5,
            1.0,
            2.9,
            30.0,
            317.5,
            1000.0,
            2.0 / 1e-6 - 2.0,
        ];
        let mut xs: Vec<f64> = (1..=20_000).map(|i| f64::from(i) / 20_000.0).collect();
        // Near 1 (a highlight's peak), tiny and subnormal.
        xs.extend((1..2000).map(|i| 1.0 - f64::from(i) * 1e-9));
        xs.extend((1..200).map(|i| 1.0 - f64::from(i) * f64::EPSILON));
        xs.extend([1e-5, 1e-100, 1e-300, 3e-310, 5e-324]);
        for e in exponents {
            for &x in &xs {
                assert!(within_bound(x, e), "{x}^{e}: {}", power(x, e));
            }
        }
    }

    #[test]
    fn edges_of_the_domain() {
        assert_eq!(power(1.0, 1e6), 1.0);
        assert_eq!(power(0.3, 0.0), 1.0);
        assert_eq!(power(0.0, 0.0), 1.0);
        assert_eq!(power(0.0, 5.0), 0.0);
        assert_eq!(power(0.5, 1.0), 0.5);
        assert_eq!(power(0.25, 0.5), 0.5);
        assert!(power(1e-200, 2.0) == 0.0 && power(0.9, 1e5) == 0.0);
    }

    #[test]
    fn the_lobe_reflects_where_the_half_vector_meets_the_normal() {
        let glossy = Surface {
            albedo: [0.5; 3],
            roughness: 0.3,
            specular: 0.04,
            crack: false,
        };
        let lobe = Lobe::of(&glossy).unwrap();
        let n = DVec3::Z;
        let (l, eye) = (DVec3::new(0.6, 0.0, 0.8), DVec3::new(-0.6, 0.0, 0.8));
        // Mirror geometry: h = n, so the lobe is Fresnel at the half angle times (e + 8)/8π.
        let alpha: f64 = 0.09;
        let exponent = 2.0 / (alpha * alpha) - 2.0;
        let fresnel = 0.04 + 0.96 * (1.0f64 - 0.8).powi(5);
        let expected = fresnel * (exponent + 8.0) / (8.0 * PI);
        assert!((lobe.glint(n, l, eye) - expected).abs() < 1e-12 * expected);
        // Off the mirror direction it falls as cos^e of the half-vector's tilt.
        let off = DVec3::new(0.0, 0.6, 0.8);
        let h = (l + off).normalize();
        let tilted = (0.04 + 0.96 * (1.0 - off.dot(h)).powi(5)) * (exponent + 8.0) / (8.0 * PI)
            * libm::pow(h.z, exponent);
        assert!((lobe.glint(n, l, off) - tilted).abs() < 1e-12 * expected);
        let matte = Surface {
            specular: 0.0,
            ..glossy
        };
        assert!(Lobe::of(&matte).is_none());
    }
}
