//! Dents and local buckles of cylindrical shells (silos, tanks) as damage records: the
//! shell's local patterns (`dimple`, `buckle`) read as an inspector's list, with where they
//! are, how big and deep, how bad, and how far they lie outside the fabrication tolerance of
//! EN 1993-1-6 §8.4.4 (docs/damage.md, "Dents and local buckles on shells").

use super::{Cause, Severity};
use crate::mechanics::{Shell, ShellPattern};
use serde::Serialize;

/// What a shell damage is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ShellDamageKind {
    /// A dent: the wall pushed in as one smooth bowl (the `dimple` pattern).
    Dent,
    /// A local buckle: a patch of inward and outward half-waves (the `buckle` pattern).
    Buckle,
}

/// A point on a shell's undeformed surface.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ShellPoint {
    /// Angle about the shell's own axis from its +x towards +y, radians in [0, 2π).
    pub angle: f64,
    /// Height above the shell's base, metres.
    pub height: f64,
}

/// The dimple tolerance measure of EN 1993-1-6 §8.4.4 for a dent: its depth over the
/// meridional gauge length, against the recommended limits of the three fabrication
/// tolerance quality classes (Table 8.4).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct DimpleTolerance {
    /// Meridional gauge length ℓ_gx = 4√(r t), metres.
    pub gauge_length: f64,
    /// Dimple parameter U₀ = depth / ℓ_gx.
    pub dimple_parameter: f64,
    /// The best quality class whose limit U₀,max the dent still meets ("A" 0.006, "B" 0.010,
    /// "C" 0.016), or "none" beyond class C.
    pub class_met: &'static str,
    /// U₀ / 0.016: how many times the class C (normal quality) limit the dent is.
    pub times_class_c: f64,
}

/// One dent or local buckle of a shell.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ShellDamage {
    /// What it is.
    #[serde(rename = "type")]
    pub kind: ShellDamageKind,
    /// The part of the assembly it is on (the shell's part name).
    pub member: String,
    /// Its centre, on the undeformed surface.
    pub position: ShellPoint,
    /// Its extent around the circumference (arc) and along the height, metres.
    pub size: [f64; 2],
    /// Its radius on the surface, metres.
    pub radius: f64,
    /// Largest inward displacement, metres (negative: it bulges outward).
    pub depth: f64,
    /// A buckle's full wavelength, metres; absent for a dent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wavelength: Option<f64>,
    /// How bad it is: by depth, as a beam's dents (below 10 mm, up to 25 mm, deeper).
    pub severity: Severity,
    /// Why it is there (a shell pattern in a recipe: "placed").
    pub cause: Cause,
    /// The depth against EN 1993-1-6's dimple tolerance.
    pub tolerance: DimpleTolerance,
}

/// The dents and local buckles of one structure, in the order of its shapes and their
/// patterns: a pixel's `damage_instance` is index + 1 here.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ShellDamageLabels {
    /// Every dent and local buckle of the structure's shells.
    pub items: Vec<ShellDamage>,
}

/// The limits U₀,max of EN 1993-1-6 Table 8.4 (recommended values), best class first.
const DIMPLE_CLASSES: [(&str, f64); 3] = [("A", 0.006), ("B", 0.010), ("C", 0.016)];

/// The dimple tolerance of a dent `depth` metres deep on `shell`.
pub fn dimple_tolerance(shell: &Shell, depth: f64) -> DimpleTolerance {
    let gauge_length = 4.0 * (shell.radius * shell.wall).sqrt();
    let u = depth.abs() / gauge_length;
    let class_met = DIMPLE_CLASSES
        .iter()
        .find(|(_, limit)| u <= *limit)
        .map_or("none", |(name, _)| name);
    DimpleTolerance {
        gauge_length,
        dimple_parameter: u,
        class_met,
        times_class_c: u / DIMPLE_CLASSES[2].1,
    }
}

/// The damage record of a local pattern on the shell part `member`; None for the global
/// patterns (hoop expansion, ovalisation, elephant's foot are load states, not damage).
pub fn shell_damage(shell: &Shell, pattern: &ShellPattern, member: &str) -> Option<ShellDamage> {
    let (angle, height, radius) = pattern.local_patch()?;
    let (kind, amplitude, wavelength) = match *pattern {
        ShellPattern::Dimple { amplitude, .. } => (ShellDamageKind::Dent, amplitude, None),
        ShellPattern::Buckle {
            amplitude,
            wavelength,
            ..
        } => (ShellDamageKind::Buckle, amplitude, Some(wavelength)),
        _ => return None,
    };
    Some(ShellDamage {
        kind,
        member: member.to_string(),
        position: ShellPoint {
            angle: angle.rem_euclid(std::f64::consts::TAU),
            height,
        },
        size: [2.0 * radius, 2.0 * radius],
        radius,
        depth: amplitude,
        wavelength,
        severity: Severity::grade(amplitude.abs(), 0.010, 0.025),
        cause: Cause::Placed,
        tolerance: dimple_tolerance(shell, amplitude),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dent_is_graded_against_the_dimple_tolerance_classes() {
        // r = 3 m, t = 8 mm: ℓ_gx = 4√(0.024) = 0.61968 m; a 62 mm dent has U₀ = 0.10005,
        // 6.25 times class C's 0.016; a 5 mm one U₀ = 0.0080688, within B but not A.
        let shell = Shell {
            radius: 3.0,
            wall: 0.008,
            height: 8.0,
        };
        let dent = |amplitude| ShellPattern::Dimple {
            amplitude,
            angle: -0.5,
            height: 4.0,
            radius: 0.6,
        };
        let big = shell_damage(&shell, &dent(0.062), "shell").unwrap();
        assert!((big.tolerance.gauge_length - 0.619677).abs() < 1e-6);
        assert!((big.tolerance.dimple_parameter - 0.100052).abs() < 1e-6);
        assert!((big.tolerance.times_class_c - 6.25325).abs() < 1e-5);
        assert_eq!(
            (big.kind, big.tolerance.class_met, big.severity),
            (ShellDamageKind::Dent, "none", Severity::Severe)
        );
        assert!((big.position.angle - (std::f64::consts::TAU - 0.5)).abs() < 1e-15);
        assert_eq!(
            (big.size, big.depth, big.cause.clone()),
            ([1.2, 1.2], 0.062, Cause::Placed)
        );
        let small = shell_damage(&shell, &dent(0.005), "shell").unwrap();
        assert_eq!(
            (small.tolerance.class_met, small.severity),
            ("B", Severity::Light)
        );
        let buckle = ShellPattern::Buckle {
            amplitude: 0.02,
            angle: 1.0,
            height: 5.0,
            radius: 0.8,
            wavelength: 0.4,
        };
        let b = shell_damage(&shell, &buckle, "shell").unwrap();
        assert_eq!(
            (b.kind, b.wavelength, b.severity),
            (ShellDamageKind::Buckle, Some(0.4), Severity::Moderate)
        );
        let hoop = ShellPattern::HoopExpansion { amplitude: 0.02 };
        assert!(shell_damage(&shell, &hoop, "shell").is_none());
    }
}
