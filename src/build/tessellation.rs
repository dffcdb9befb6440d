//! The one tessellation rule of every surface, beams and primitives alike: chords stay within
//! a tolerance of the true surface, given in metres or as a fraction of a pixel at the nearest
//! camera the rig can place; intervals follow from the curvature (sagitta h²κ/8).

use crate::scene::Tolerance;

/// The chord tolerance in metres, where a pixel at the nearest camera covers `pixel_footprint`
/// metres of the structure.
pub fn chord_tolerance(tolerance: Tolerance, pixel_footprint: f64) -> f64 {
    match tolerance {
        Tolerance::Chord(metres) => metres,
        Tolerance::Pixels(fraction) => fraction * pixel_footprint,
    }
}

/// Uniform intervals over `length` whose chord error h²κ/8 stays below `tolerance` where the
/// curvature is `curvature`.
pub fn segments_for_chord(length: f64, curvature: f64, tolerance: f64) -> usize {
    let n = (length * (curvature / (8.0 * tolerance)).sqrt()).ceil();
    if n.is_finite() {
        (n as usize).clamp(1, 100_000)
    } else {
        100_000
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chord_rule_gives_the_error_it_promises() {
        // Simply supported, centre load: κ_max = 12δ/L², so N equal intervals leave a chord
        // error of L²κ/(8N²) = 1.5 δ/N² (docs/mechanics.md §9.2).
        let (l, delta, tol) = (4.0, 0.2, 1e-3);
        let n = segments_for_chord(l, 12.0 * delta / (l * l), tol);
        assert!(
            1.5 * delta / (n * n) as f64 <= tol && 1.5 * delta / ((n - 1) * (n - 1)) as f64 > tol,
            "n = {n}"
        );
    }

    #[test]
    fn pixels_scale_with_the_footprint_and_metres_do_not() {
        assert_eq!(chord_tolerance(Tolerance::Pixels(0.1), 2e-3), 2e-4);
        assert_eq!(chord_tolerance(Tolerance::Chord(5e-4), 2e-3), 5e-4);
    }
}
