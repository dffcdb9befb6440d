//! What each theory can represent (docs/mechanics.md §5.3). A solved beam is refused before
//! anything is meshed or written from it, naming the quantity, its value and the limit:
//! everything must be finite, the linear theories, vibration snapshots and von Kármán stop at a
//! slope of 0.5, and every theory at a bending strain of 0.5 at the extreme fibre.

use super::model::{BeamProblem, Deformation, Target, Theory};

/// Largest slope |dv/dx| (and tangent of the section rotation) that the small-rotation
/// theories accept: 0.5, about 26.6°. There the cantilever's linear tip deflection is already
/// 10 % off the elastica (docs/mechanics.md §6.5), and the axis shortening ½∫v′² is at most L/8,
/// so the deformed axis can never fold back on itself.
pub const MAX_SLOPE: f64 = 0.5;

/// Largest bending strain κc at the extreme fibre that any theory accepts: the radius of
/// curvature must be at least the section depth h = 2c. Plane sections turning about the axis
/// run into each other on the inside of the bend at κc = 1.
pub const MAX_FIBRE_STRAIN: f64 = 0.5;

/// Ok when the solved beam lies within what its theory represents; `xs` are the stations its
/// extremes were searched at (512 plus every load point, or 32 per mode number), where the
/// shape is sampled once for all checks.
pub(super) fn check(p: &BeamProblem, d: &Deformation, xs: &[f64]) -> Result<(), String> {
    let sampled = Sampled::new(d, xs);
    finite(p, d, &sampled)?;
    // The elastica is geometrically exact: any rotation is within its reach.
    if d.labels.theory != Theory::Elastica {
        // Under Timoshenko theory a steep axis with sections that barely turn is shear strain,
        // which a load close to a support concentrates next to it.
        let shear = d.labels.theory == Theory::Timoshenko && sampled.rotation.0 <= MAX_SLOPE;
        let hint = if shear { SHEAR_HINT } else { "" };
        let (slope, at) = sampled.slope;
        within_small_rotations(p, d, ("slope of the axis |dv/dx|", hint), slope, at)?;
        let (rotation, at) = sampled.rotation;
        within_small_rotations(p, d, ("section rotation |tan ψ|", ""), rotation, at)?;
    }
    fibre_strain(p, d)
}

/// The deflected axis sampled at the search stations: whether every deflection is finite, and
/// the largest |slope| and |tan ψ| with where they occur (NaN, once met, is kept, so that the
/// limit refuses it).
struct Sampled {
    finite: bool,
    slope: (f64, f64),
    rotation: (f64, f64),
}

impl Sampled {
    fn new(d: &Deformation, xs: &[f64]) -> Sampled {
        let mut s = Sampled {
            finite: true,
            slope: (0.0, 0.0),
            rotation: (0.0, 0.0),
        };
        for &x in xs {
            let a = d.at(x);
            s.finite &= a.v.is_finite();
            keep_largest(&mut s.slope, a.slope.abs(), x);
            keep_largest(&mut s.rotation, a.rotation.abs(), x);
        }
        s
    }
}

fn keep_largest(best: &mut (f64, f64), value: f64, x: f64) {
    if !best.0.is_nan() && !(value <= best.0) {
        *best = (value, x);
    }
}

/// The largest z = L√(N/EI) von Kármán may need: slopes within MAX_SLOPE everywhere keep the
/// membrane strain N/EA = (1/2L)∫w′² below MAX_SLOPE²/2, so N ≤ EA·MAX_SLOPE²/2.
pub(super) fn tension_limit(p: &BeamProblem) -> f64 {
    let ratio = p.section.area / p.section.second_moment;
    p.length * (0.5 * ratio).sqrt() * MAX_SLOPE
}

/// Why a von Kármán beam needing more than [`tension_limit`] is refused.
pub(super) fn overstretched(p: &BeamProblem) -> String {
    format!(
        "von_karman theory cannot represent this deflection: carrying it needs a membrane strain N/EA above {}, which no axis with slopes within {MAX_SLOPE} reaches (docs/mechanics.md §5.3); reduce the {}",
        0.5 * MAX_SLOPE * MAX_SLOPE,
        remedy(p)
    )
}

fn finite(p: &BeamProblem, d: &Deformation, sampled: &Sampled) -> Result<(), String> {
    let l = &d.labels;
    let labels = [
        l.max_deflection,
        l.max_moment,
        l.max_bending_stress,
        l.membrane_force,
    ];
    if sampled.finite
        && labels.iter().all(|v| v.is_finite())
        && l.loads.iter().all(|l| l.is_finite())
    {
        return Ok(());
    }
    Err(format!(
        "{} theory gives a shape that is not finite (largest deflection {} m, moment {} N·m, bending stress {} Pa): no beam theory represents these loads; reduce the {}",
        l.theory.name(),
        shown(l.max_deflection),
        shown(l.max_moment),
        shown(l.max_bending_stress),
        remedy(p)
    ))
}

/// What to do about a slope that is Timoshenko's shear strain rather than rotation.
const SHEAR_HINT: &str = "; this is shear strain next to a load close to a support (the sections themselves turn less): move the load away from the support, pin theory(\"euler_bernoulli\") or";

/// `what`: the quantity, and a hint that replaces the usual "; reduce the …".
fn within_small_rotations(
    p: &BeamProblem,
    d: &Deformation,
    (what, hint): (&str, &str),
    value: f64,
    at: f64,
) -> Result<(), String> {
    if value.abs() <= MAX_SLOPE {
        return Ok(());
    }
    let advice = if hint.is_empty() { ";" } else { hint };
    Err(format!(
        "{} theory cannot represent this deflection: the largest {what} = {} at x = {} m exceeds {MAX_SLOPE}, the limit of small rotations (docs/mechanics.md §5.3; the largest deflection would be {} m){advice} reduce the {}",
        d.labels.theory.name(),
        shown(value.abs()),
        shown(at),
        shown(d.labels.max_deflection),
        remedy(p)
    ))
}

fn fibre_strain(p: &BeamProblem, d: &Deformation) -> Result<(), String> {
    let strain = d.labels.max_bending_stress / p.elastic_modulus;
    if strain <= MAX_FIBRE_STRAIN {
        return Ok(());
    }
    Err(format!(
        "{} theory cannot represent this deflection: the bending strain at the extreme fibre κc = {} at x = {} m exceeds {MAX_FIBRE_STRAIN}, a radius of curvature below the section depth, where plane sections turning about the axis run into each other (docs/mechanics.md §5.3); reduce the {}",
        d.labels.theory.name(),
        shown(strain),
        shown(d.labels.max_moment_at),
        remedy(p)
    ))
}

/// What the recipe can change to bring the beam back into range.
fn remedy(p: &BeamProblem) -> &'static str {
    if !p.vibration.is_empty() {
        "mode amplitudes"
    } else if p.target == Target::Physical {
        "loads"
    } else {
        "target deflection"
    }
}

/// A computed value to three significant digits, in exponent form outside 1e-3 … 1e6.
fn shown(x: f64) -> String {
    let magnitude = x.abs();
    if !x.is_finite() || magnitude == 0.0 {
        format!("{x}")
    } else if (1e-3..1e6).contains(&magnitude) {
        let decimals = (2 - magnitude.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::{Load, Section, Support};

    /// A 2 m steel beam, 0.2 m wide and 0.3 m deep.
    fn beam(support: Support, loads: Vec<Load>, target: Target) -> BeamProblem {
        crate::mechanics::model::steel_rectangle(support, 2.0, (0.2, 0.3), loads, target)
    }

    fn refused(p: &BeamProblem, words: &[&str]) {
        let e = Deformation::solve(p)
            .map(|d| d.labels.max_deflection)
            .unwrap_err();
        for w in words {
            assert!(e.contains(w), "{w:?} missing from: {e}");
        }
    }

    #[test]
    fn loads_far_beyond_small_rotations_are_refused_naming_the_slope() {
        // end_moments(1e28, 0): a 2.7e19 m deflection, slope 1.4e20 at the pin.
        let mut p = beam(
            Support::SimplySupported,
            vec![Load::EndMoments {
                start: 1e28,
                end: 0.0,
            }],
            Target::Physical,
        );
        refused(
            &p,
            &[
                "euler_bernoulli theory",
                "slope of the axis |dv/dx| = 7.05e19",
                "exceeds 0.5",
                "reduce the loads",
            ],
        );
        // Each theory pinned says so in its own name.
        for (theory, name) in [
            (Theory::EulerBernoulli, "euler_bernoulli"),
            (Theory::Timoshenko, "timoshenko"),
        ] {
            p.theory = theory;
            refused(&p, &[name, "exceeds 0.5"]);
        }
        // A target 1e-12 m from the pin scales a mid-span load by 1e9.
        let p = beam(
            Support::SimplySupported,
            vec![Load::Point {
                at: 1.0,
                force: 1.0,
            }],
            Target::At {
                at: 1e-12,
                deflection: 1e-3,
            },
        );
        refused(&p, &["slope of the axis", "reduce the target deflection"]);
        // Too large to be finite at all (the stress overflows).
        let mut p = beam(
            Support::SimplySupported,
            vec![Load::Point {
                at: 1.0,
                force: 1e308,
            }],
            Target::Physical,
        );
        p.theory = Theory::EulerBernoulli;
        refused(&p, &["not finite"]);
    }

    #[test]
    fn the_slope_limit_is_sharp() {
        // Cantilever with a tip moment: slope M L/EI at the tip (linear theory runs, as the
        // elastica takes point loads only).
        let p = |slope: f64| {
            let b = beam(Support::Cantilever, vec![], Target::Physical);
            let ei = b.elastic_modulus * b.section.second_moment;
            let mut b = b;
            b.loads = vec![Load::EndMoments {
                start: 0.0,
                end: -slope * ei / b.length,
            }];
            b
        };
        let d = Deformation::solve(&p(0.499)).unwrap();
        assert!((d.at(2.0).slope.abs() - 0.499).abs() < 1e-12);
        refused(&p(0.501), &["0.501", "exceeds 0.5"]);
    }

    #[test]
    fn vibration_snapshots_stay_within_small_rotations_and_fibre_strain() {
        // Modes 1, 5 and 20 at 0.3 m on a 2 m beam: slope 3.9 near the pins.
        let mut p = beam(Support::SimplySupported, vec![], Target::Physical);
        p.vibration = vec![(1, 0.3), (5, 0.3), (20, 0.3)];
        refused(&p, &["slope of the axis", "reduce the mode amplitudes"]);
        // Mode 300 with slope 0.3: κc = A (nπ/L)² c = 0.3 · (300π/2) · 0.15 = 21.
        p.vibration = vec![(300, 0.3 * 2.0 / (300.0 * std::f64::consts::PI))];
        refused(
            &p,
            &[
                "bending strain at the extreme fibre κc = 21.",
                "exceeds 0.5",
            ],
        );
    }

    #[test]
    fn the_elastica_reaches_any_rotation_but_not_any_curvature() {
        // Tip load α = PL²/EI = 10 on a rod with L/c = 400: 82° at the tip, and at the clamp
        // κc = α (x_tip/L)(c/L) = 10 · 0.445 / 400 = 0.011 (docs/mechanics.md §6.4).
        let mut p = beam(Support::Cantilever, vec![], Target::Physical);
        p.section = Section::Rectangle {
            width: 0.2,
            height: 0.01,
        }
        .properties(0.3);
        let ei = p.elastic_modulus * p.section.second_moment;
        let tip = |alpha: f64| {
            vec![Load::Point {
                at: 2.0,
                force: alpha * ei / 4.0,
            }]
        };
        p.loads = tip(10.0);
        let d = Deformation::solve(&p).unwrap();
        assert_eq!(d.labels.theory, Theory::Elastica);
        let strain = d.labels.max_bending_stress / p.elastic_modulus;
        assert!(
            (strain / (10.0 * (1.0 - 0.555) / 400.0) - 1.0).abs() < 1e-4,
            "{strain}"
        );
        // α = 1e6 bends the clamp to a radius below the depth (κc ≈ 3.5).
        p.loads = tip(1e6);
        refused(
            &p,
            &["elastica theory", "bending strain at the extreme fibre"],
        );
    }
}
