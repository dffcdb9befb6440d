//! Radial deformation patterns of cylindrical shells (silos, tanks), with explicit amplitudes
//! and the amplitude a physical load would plausibly give (docs/mechanics.md §8).
//!
//! Patterns are functions w(θ, z) of the angle about the shell axis and the height above its
//! base, outward positive, in metres. They are labelled damage or load states, not solutions:
//! physical responses of real silos are sub-millimetre and invisible at survey distances, so a
//! visible deformation is stated, and labelled with what a real load would have done.

use serde::Serialize;
use std::f64::consts::PI;

/// A radial deformation pattern of a tube, tagged by `pattern`: w(θ, z) in metres, outward
/// positive, with θ the angle about the tube's axis from its own +x towards +y (radians) and z the
/// height above its base (metres).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "pattern", rename_all = "snake_case")]
pub enum ShellPattern {
    /// Uniform hoop expansion under internal pressure.
    HoopExpansion {
        /// Uniform outward radial displacement, metres.
        amplitude: f64,
    },
    /// Wind-type ovalisation (lobing): A sin(πz/H) cos(n(θ − θ₀)), ends kept circular by the
    /// base and the roof.
    Ovalisation {
        /// Peak radial displacement A at mid-height, metres; outward at θ = `towards`.
        amplitude: f64,
        /// Circumferential wave number n, 1–64: 2 ovalises the section, 1 shifts it sideways,
        /// higher n give more lobes.
        n: u32,
        /// Angle θ₀ of an outward lobe, radians.
        towards: f64,
    },
    /// A local inward dimple (positive amplitude = inward): −A cos²(πd/(2R)) within surface
    /// distance d < R of the point (θ₀, z₀).
    Dimple {
        /// Inward depth A at the centre, metres (negative bulges outward).
        amplitude: f64,
        /// Angle θ₀ of the centre about the tube's axis, radians.
        angle: f64,
        /// Height z₀ of the centre above the base, metres.
        height: f64,
        /// Radius R of the dimple, measured along the surface, metres (less than half the
        /// circumference).
        radius: f64,
    },
    /// Elephant's-foot bulge just above the base: A (z/z₀) e^{1 − z/z₀}, peak A at z₀, zero at
    /// the base.
    ElephantFoot {
        /// Peak outward bulge A, metres.
        amplitude: f64,
        /// Height z₀ of the peak above the base, metres (inside the shell).
        height: f64,
    },
    /// A buckle patch: a checkerboard of inward and outward half-waves of length `wavelength / 2`
    /// in both directions, centred inward at (θ₀, z₀), under a cos² window of radius R
    /// (the Koiter-circle eigenshapes of axial buckling, confined to a patch).
    Buckle {
        /// Displacement A at the centre, metres, inward for positive A; neighbouring half-waves
        /// alternate in sign and fade under the window.
        amplitude: f64,
        /// Angle θ₀ of the centre about the tube's axis, radians.
        angle: f64,
        /// Height z₀ of the centre above the base, metres.
        height: f64,
        /// Radius R of the patch, measured along the surface, metres (less than half the
        /// circumference).
        radius: f64,
        /// Full wavelength of the checkerboard in both directions, metres (at most 2R).
        wavelength: f64,
    },
}

/// The shell the patterns act on: radius, wall thickness, height; steel (for the plausible
/// amplitudes).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Shell {
    /// Outer radius, metres.
    pub radius: f64,
    /// Wall thickness, metres.
    pub wall: f64,
    /// Height from base to top, metres.
    pub height: f64,
}

/// The largest summed peak |w| of the patterns on one shell, as a share of its radius. The
/// patterns are labelled damage and load states of a thin shell: real ones are millimetres to
/// decimetres on radii of metres. Half the radius leaves every exaggeration a study could want
/// while keeping r + w well away from the axis, where the radial parametrisation would fold.
pub const MAX_PEAK_SHARE: f64 = 0.5;

const E: f64 = super::STEEL_E;
const NU: f64 = super::STEEL_NU;

impl ShellPattern {
    /// Checks the parameters against `shell`; the message names the pattern, the parameter and its
    /// value.
    pub fn validate(&self, shell: &Shell) -> Result<(), String> {
        let finite = |name: &str, x: f64| {
            if x.is_finite() {
                Ok(())
            } else {
                Err(format!("{name} = {x} is not a finite number"))
            }
        };
        match *self {
            ShellPattern::HoopExpansion { amplitude } => {
                finite("hoop_expansion amplitude", amplitude)
            }
            ShellPattern::Ovalisation {
                amplitude,
                n,
                towards,
            } => {
                finite("ovalisation amplitude", amplitude)?;
                finite("ovalisation towards", towards)?;
                if (1..=64).contains(&n) {
                    Ok(())
                } else {
                    Err(format!("ovalisation n = {n} must be between 1 and 64"))
                }
            }
            ShellPattern::Dimple {
                amplitude,
                angle,
                height,
                radius,
            } => {
                finite("dimple amplitude", amplitude)?;
                finite("dimple angle", angle)?;
                if !(0.0..=shell.height).contains(&height) {
                    return Err(format!(
                        "dimple height = {height} m lies outside the shell (0 to {} m)",
                        shell.height
                    ));
                }
                if radius > 0.0 && radius < PI * shell.radius {
                    Ok(())
                } else {
                    Err(format!(
                        "dimple radius = {radius} m must be positive and less than half the circumference"
                    ))
                }
            }
            ShellPattern::ElephantFoot { amplitude, height } => {
                finite("elephant_foot amplitude", amplitude)?;
                if height > 0.0 && height < shell.height {
                    Ok(())
                } else {
                    Err(format!(
                        "elephant_foot height = {height} m must lie inside the shell"
                    ))
                }
            }
            ShellPattern::Buckle {
                amplitude,
                angle,
                height,
                radius,
                wavelength,
            } => {
                ShellPattern::Dimple {
                    amplitude,
                    angle,
                    height,
                    radius,
                }
                .validate(shell)?;
                if wavelength > 0.0 && wavelength <= 2.0 * radius {
                    Ok(())
                } else {
                    Err(format!(
                        "buckle wavelength = {wavelength} m must be positive and at most the patch diameter"
                    ))
                }
            }
        }
    }

    /// The centre (angle θ₀, height z₀) and radius R of a local pattern (dimple, buckle
    /// patch); None for the patterns that span the whole shell.
    pub fn local_patch(&self) -> Option<(f64, f64, f64)> {
        match *self {
            ShellPattern::Dimple {
                angle,
                height,
                radius,
                ..
            }
            | ShellPattern::Buckle {
                angle,
                height,
                radius,
                ..
            } => Some((angle, height, radius)),
            _ => None,
        }
    }

    /// The largest |w| the pattern reaches, metres.
    pub fn peak(&self) -> f64 {
        match *self {
            ShellPattern::HoopExpansion { amplitude }
            | ShellPattern::Ovalisation { amplitude, .. }
            | ShellPattern::Dimple { amplitude, .. }
            | ShellPattern::ElephantFoot { amplitude, .. }
            | ShellPattern::Buckle { amplitude, .. } => amplitude.abs(),
        }
    }

    /// Checks `patterns`, applied together to `shell`: each one's parameters, and their summed
    /// peaks against [`MAX_PEAK_SHARE`] of the radius.
    pub fn validate_together(patterns: &[ShellPattern], shell: &Shell) -> Result<(), String> {
        patterns.iter().try_for_each(|p| p.validate(shell))?;
        let limit = MAX_PEAK_SHARE * shell.radius;
        let beyond = |what: String| {
            Err(format!(
                "{what}, beyond what a radial pattern of this shell represents: at most {limit} m, {MAX_PEAK_SHARE} of the radius {} m (a wall pushed that far towards the axis is a collapse, not a deformation state)",
                shell.radius
            ))
        };
        if let Some(p) = patterns.iter().find(|p| p.peak() > limit) {
            return beyond(format!("{} amplitude = {} m", p.name(), p.peak()));
        }
        let total: f64 = patterns.iter().map(ShellPattern::peak).sum();
        if total > limit {
            return beyond(format!("the shell patterns reach {total} m together"));
        }
        Ok(())
    }

    /// The pattern's name in the recipe API.
    pub fn name(&self) -> &'static str {
        match self {
            ShellPattern::HoopExpansion { .. } => "hoop_expansion",
            ShellPattern::Ovalisation { .. } => "ovalise",
            ShellPattern::Dimple { .. } => "dimple",
            ShellPattern::ElephantFoot { .. } => "elephant_foot",
            ShellPattern::Buckle { .. } => "buckle",
        }
    }

    /// w(θ, z), outward positive.
    pub fn at(&self, shell: &Shell, theta: f64, z: f64) -> f64 {
        match *self {
            ShellPattern::HoopExpansion { amplitude } => amplitude,
            ShellPattern::Ovalisation {
                amplitude,
                n,
                towards,
            } => {
                amplitude * (PI * z / shell.height).sin() * (f64::from(n) * (theta - towards)).cos()
            }
            ShellPattern::Dimple {
                amplitude,
                angle,
                height,
                radius,
            } => {
                let arc = shell.radius * angle_between(theta, angle);
                let d = arc.hypot(z - height);
                if d < radius {
                    -amplitude * (PI * d / (2.0 * radius)).cos().powi(2)
                } else {
                    0.0
                }
            }
            ShellPattern::ElephantFoot { amplitude, height } => {
                let s = z / height;
                amplitude * s * (1.0 - s).exp()
            }
            ShellPattern::Buckle {
                amplitude,
                angle,
                height,
                radius,
                wavelength,
            } => {
                let arc = shell.radius * signed_angle(theta, angle);
                let d = arc.hypot(z - height);
                if d >= radius {
                    return 0.0;
                }
                let k = 2.0 * PI / wavelength;
                -amplitude
                    * (k * arc).cos()
                    * (k * (z - height)).cos()
                    * (PI * d / (2.0 * radius)).cos().powi(2)
            }
        }
    }

    /// Largest second derivative of w along the height and around the circumference
    /// (per metre of arc), for tessellation.
    pub fn curvatures(&self, shell: &Shell) -> (f64, f64) {
        match *self {
            ShellPattern::HoopExpansion { .. } => (0.0, 0.0),
            ShellPattern::Ovalisation { amplitude, n, .. } => (
                amplitude.abs() * (PI / shell.height).powi(2),
                amplitude.abs() * (f64::from(n) / shell.radius).powi(2),
            ),
            ShellPattern::Dimple {
                amplitude, radius, ..
            } => {
                let k = amplitude.abs() * 0.5 * (PI / radius).powi(2);
                (k, k)
            }
            ShellPattern::ElephantFoot { amplitude, height } => {
                (amplitude.abs() / (height * height), 0.0)
            }
            ShellPattern::Buckle {
                amplitude,
                wavelength,
                ..
            } => {
                let k = amplitude.abs() * (2.0 * PI / wavelength).powi(2);
                (k, k)
            }
        }
    }

    /// What a physical load would plausibly give, and on what basis.
    pub fn plausible(&self, shell: &Shell) -> (f64, &'static str) {
        let (r, t, h) = (shell.radius, shell.wall, shell.height);
        match *self {
            ShellPattern::HoopExpansion { .. } => (
                9810.0 * h * r * r / (E * t),
                "membrane hoop expansion p r²/(E t) at the base of a full water silo (p = ρ g H)",
            ),
            ShellPattern::Ovalisation { n, .. } => (
                wind_harmonic(shell, n),
                "shell response to 1 kPa peak wind pressure, AS/NZS 1170.2 Fourier harmonic n, ends held circular",
            ),
            ShellPattern::Dimple { .. } => (
                0.010 * 4.0 * (r * t).sqrt(),
                "EN 1993-1-6 class B dimple tolerance U₀ = 0.010 over the gauge 4√(rt)",
            ),
            ShellPattern::ElephantFoot { .. } | ShellPattern::Buckle { .. } => (
                (r / t).sqrt() * t / 25.0,
                "EN 1993-1-6 class B characteristic imperfection √(r/t)·t/Q, Q = 25",
            ),
        }
    }
}

/// Harmonic n of the wind pressure coefficient for a silo of height/diameter ≈ 1.
fn wind_harmonic(shell: &Shell, n: u32) -> f64 {
    let c = [0.4, 0.8, 0.3, -0.1, -0.05];
    let Some(&cn) = c.get(n as usize - 1) else {
        return 0.0;
    };
    let (r, t) = (shell.radius, shell.wall);
    let p = 1000.0 * cn;
    if n == 1 {
        // Global sway of a cantilever tube under c_f q 2r per metre: qH⁴/(8EI), I = π r³ t.
        return 0.6 * 1000.0 * 2.0 * r * shell.height.powi(4) / (8.0 * E * PI * r.powi(3) * t);
    }
    let d = E * t.powi(3) / (12.0 * (1.0 - NU * NU));
    let lambda2 = (PI / shell.height).powi(2);
    let mu2 = (f64::from(n * n) - 1.0) / (r * r);
    p * (lambda2 + mu2).powi(2)
        / (d * (lambda2 + mu2).powi(4) + E * t / (r * r) * lambda2 * lambda2)
}

fn angle_between(a: f64, b: f64) -> f64 {
    signed_angle(a, b).abs()
}

/// a − b wrapped into (−π, π].
fn signed_angle(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI { d - 2.0 * PI } else { d }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SILO: Shell = Shell {
        radius: 3.0,
        wall: 0.006,
        height: 15.0,
    };

    #[test]
    fn patterns_reaching_towards_the_axis_are_refused_alone_and_together() {
        let shell = Shell {
            radius: 2.0,
            wall: 0.01,
            height: 6.0,
        };
        let hoop = |amplitude| ShellPattern::HoopExpansion { amplitude };
        let foot = |amplitude| ShellPattern::ElephantFoot {
            amplitude,
            height: 0.5,
        };
        assert!(ShellPattern::validate_together(&[hoop(1.0)], &shell).is_ok());
        assert!(ShellPattern::validate_together(&[hoop(-0.6), foot(0.4)], &shell).is_ok());
        let alone = ShellPattern::validate_together(&[hoop(0.1), foot(-1.5)], &shell);
        assert!(
            alone
                .unwrap_err()
                .starts_with("elephant_foot amplitude = 1.5 m")
        );
        let together = ShellPattern::validate_together(&[hoop(0.6), foot(0.6)], &shell);
        assert!(together.unwrap_err().contains("reach 1.2 m together"));
        assert!(ShellPattern::validate_together(&[hoop(f64::NAN)], &shell).is_err());
    }

    #[test]
    fn plausible_amplitudes_match_the_worked_examples() {
        // docs/mechanics.md §8.3 (r = 3 m, t = 6 mm, H = 15 m, q = 1 kPa, AS/NZS 1170.2 wind
        // harmonics): W₂ = 0.42 mm, W₃ = 0.96 mm, W₄ = −0.96 mm, W₅ = −0.74 mm, global sway
        // 0.21 mm; EN 1993-1-6 class B: dimple tolerance 5.4 mm and Δw_k = 5.4 mm.
        let oval = |n| {
            ShellPattern::Ovalisation {
                amplitude: 0.0,
                n,
                towards: 0.0,
            }
            .plausible(&SILO)
            .0 * 1e3
        };
        for (n, mm) in [(2, 0.42), (3, 0.96), (4, -0.96), (5, -0.74), (1, 0.21)] {
            assert!(
                (oval(n) - mm).abs() < 0.01 + 0.02 * mm.abs(),
                "n = {n}: {} mm",
                oval(n)
            );
        }
        let dimple = ShellPattern::Dimple {
            amplitude: 0.0,
            angle: 0.0,
            height: 1.0,
            radius: 0.3,
        }
        .plausible(&SILO)
        .0;
        assert!((dimple * 1e3 - 5.4).abs() < 0.05);
        let foot = ShellPattern::ElephantFoot {
            amplitude: 0.0,
            height: 0.5,
        }
        .plausible(&SILO)
        .0;
        assert!((foot * 1e3 - 5.4).abs() < 0.05);
    }

    #[test]
    fn patterns_reach_their_amplitude_where_they_should() {
        let oval = ShellPattern::Ovalisation {
            amplitude: 0.05,
            n: 3,
            towards: 0.4,
        };
        assert!((oval.at(&SILO, 0.4, 7.5) - 0.05).abs() < 1e-15);
        assert!(
            oval.at(&SILO, 0.4, 0.0).abs() < 1e-15 && oval.at(&SILO, 0.4, 15.0).abs() < 1e-15,
            "ends stay circular"
        );
        let dimple = ShellPattern::Dimple {
            amplitude: 0.02,
            angle: 6.2,
            height: 4.0,
            radius: 0.5,
        };
        assert_eq!(dimple.at(&SILO, 6.2, 4.0), -0.02);
        assert_eq!(dimple.at(&SILO, 6.2 + 0.5, 4.0), 0.0);
        assert!(
            dimple.at(&SILO, 6.2 - 2.0 * PI, 4.1) < 0.0,
            "the angle wraps around"
        );
        let foot = ShellPattern::ElephantFoot {
            amplitude: 0.03,
            height: 0.4,
        };
        assert!((foot.at(&SILO, 1.0, 0.4) - 0.03).abs() < 1e-15 && foot.at(&SILO, 1.0, 0.0) == 0.0);
        let buckle = ShellPattern::Buckle {
            amplitude: 0.04,
            angle: 1.0,
            height: 6.0,
            radius: 1.0,
            wavelength: 0.5,
        };
        assert_eq!(buckle.at(&SILO, 1.0, 6.0), -0.04, "inward at the centre");
        assert!(
            (buckle.at(&SILO, 1.0, 6.25) - 0.04 * (PI * 0.25 / 2.0).cos().powi(2)).abs() < 1e-15,
            "outward half a wave up"
        );
        assert_eq!(buckle.at(&SILO, 1.0, 7.1), 0.0, "nothing outside the patch");
        assert!(
            ShellPattern::Ovalisation {
                amplitude: 0.1,
                n: 0,
                towards: 0.0
            }
            .validate(&SILO)
            .is_err()
        );
        assert!(
            ShellPattern::Dimple {
                amplitude: 0.1,
                angle: 0.0,
                height: 20.0,
                radius: 0.3
            }
            .validate(&SILO)
            .unwrap_err()
            .contains("height = 20")
        );
    }
}
