//! The graded tube grid of a shell with local patterns (dents, buckle patches): rings and
//! segments dense around each local pattern, as its curvature needs for the chord tolerance,
//! and as coarse as the rest of the shell allows elsewhere.
//!
//! Owns: the stations along the height and around the circumference (a tensor-product grid:
//! every ring has every segment, so the mesh is swept like any tube and stays closed with no
//! T-junctions), and the step rule inside a pattern's window. The step grows linearly away
//! from each window (by `GROWTH` of the distance), so neighbouring intervals differ by at most
//! that share and the grid is graded, not stepped. Shells without local patterns are meshed
//! uniformly as before (`build::assembly`).

use crate::geometry::outline::{annulus, circle_segments};
use crate::geometry::primitives::Primitive;
use crate::geometry::{Frame3, Mesh, sweep};
use crate::mechanics::{Shell, ShellPattern};
use glam::{DVec2, DVec3};
use std::f64::consts::TAU;

/// How much a step may grow per metre of distance from a dense window (dimensionless: the
/// step field's slope). Below 1 so the march never steps over a window; 0.25 keeps
/// neighbouring intervals within 25 % of each other.
const GROWTH: f64 = 0.25;

/// The most steps across a window's diameter, as the uniform rule caps its counts at 4096:
/// an absurd pattern (a buckle wavelength of 1e-12 m) gives a bounded grid, which the sweep's
/// triangle budget then refuses or meshes, instead of an endless march.
const MAX_WINDOW_STEPS: f64 = 4096.0;

/// A stretch of a coordinate (height or arc) that needs steps of at most `step` metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// Centre, metres.
    pub centre: f64,
    /// Half width, metres.
    pub half: f64,
    /// The largest step inside, metres.
    pub step: f64,
}

/// The local patterns' windows, height and arc, for a shell whose surface may deviate from the
/// mesh by `tolerance` metres. Inside a window the step h keeps k h²/4 ≤ tolerance, with k the
/// bound on the surface's curvature there (the pattern's, the other patterns', and the
/// circle's 1/r): the error of linear interpolation over a right triangle with legs h, whose
/// circumradius is h/√2, for a surface whose Hessian is bounded by k in every direction.
pub fn local_windows(
    shell: &Shell,
    patterns: &[ShellPattern],
    tolerance: f64,
) -> (Vec<Window>, Vec<Window>) {
    let (gz, gs) = global_curvatures(shell, patterns);
    let mut heights = Vec::new();
    let mut arcs = Vec::new();
    for p in patterns {
        let Some((angle, height, radius)) = local_extent(p) else {
            continue;
        };
        let (kz, ks) = p.curvatures(shell);
        let k = kz.max(ks) + gz.max(gs) + 1.0 / shell.radius;
        let step = (4.0 * tolerance / k)
            .sqrt()
            .max(2.0 * radius / MAX_WINDOW_STEPS);
        heights.push(Window {
            centre: height,
            half: radius,
            step,
        });
        arcs.push(Window {
            centre: shell.radius * angle.rem_euclid(TAU),
            half: radius,
            step,
        });
    }
    (heights, arcs)
}

/// The centre (angle, height) and radius of a local pattern; None for the global ones.
pub fn local_extent(p: &ShellPattern) -> Option<(f64, f64, f64)> {
    p.local_patch()
}

/// Summed curvature bounds (height, circumference) of the global patterns.
fn global_curvatures(shell: &Shell, patterns: &[ShellPattern]) -> (f64, f64) {
    patterns
        .iter()
        .filter(|p| local_extent(p).is_none())
        .map(|p| p.curvatures(shell))
        .fold((0.0, 0.0), |(a, b), (z, s)| (a + z, b + s))
}

/// Distance from `x` to the window (0 inside), on a line or, with `period`, on a circle of
/// that circumference.
fn distance_to(w: &Window, x: f64, period: Option<f64>) -> f64 {
    let mut d = (x - w.centre).abs();
    if let Some(p) = period {
        d = d.rem_euclid(p);
        d = d.min(p - d);
    }
    (d - w.half).max(0.0)
}

/// Stations from 0 to `length` (both ends included): steps of at most `base`, at most each
/// window's step inside it, growing by `GROWTH` of the distance outside. With `periodic`
/// the coordinate wraps (the circumference: the last station is `length`, the first 0, the
/// same place). The last step is cut at `length`; when that leaves a sliver (under half the
/// step before it), the two last steps are split evenly instead.
pub fn graded_stations(length: f64, base: f64, windows: &[Window], periodic: bool) -> Vec<f64> {
    let period = periodic.then_some(length);
    let step_at = |x: f64| {
        windows
            .iter()
            .map(|w| w.step + GROWTH * distance_to(w, x, period))
            .fold(base, f64::min)
    };
    let mut stations = vec![0.0];
    let mut x = 0.0;
    loop {
        // The field falls by at most GROWTH·h over a step h, so h = f(x)/(1 + GROWTH) stays
        // within the field everywhere along the step, including where it enters a window.
        x += step_at(x) / (1.0 + GROWTH);
        if x >= length {
            break;
        }
        stations.push(x);
    }
    let n = stations.len();
    if n >= 2 && length - stations[n - 1] < 0.5 * (stations[n - 1] - stations[n - 2]) {
        // Two halves of (previous + sliver) < 0.75 of the previous step, where the field is
        // still at least (1 − GROWTH/2) of it: both stay within the field.
        stations[n - 1] = 0.5 * (stations[n - 2] + length);
    }
    stations.push(length);
    stations
}

/// The tube `tube` swept through rings at `heights` (from its base) with outline vertices at
/// `angles` (radians, increasing in [0, 2π)), on both its outer and inner surfaces.
pub fn tube_on_grid(tube: &Primitive, heights: &[f64], angles: &[f64]) -> Result<Mesh, String> {
    let Primitive::Tube { radius, wall, .. } = *tube else {
        return Err("shell patterns apply to tubes".to_string());
    };
    let ring =
        |r: f64| -> Vec<DVec2> { angles.iter().map(|&a| DVec2::from_angle(a) * r).collect() };
    let frames: Vec<Frame3> = heights
        .iter()
        .map(|&z| Frame3 {
            origin: DVec3::new(0.0, 0.0, z),
            u: DVec3::X,
            v: DVec3::Y,
        })
        .collect();
    sweep(&annulus(ring(radius), ring(radius - wall)), &frames)
}

/// The graded mesh of `tube` for `patterns` (at least one local) within `tolerance` metres.
/// Away from the windows the rings follow the global patterns' curvature (even count, one at
/// mid-height, as the uniform grid) and the segments the circle's chord rule.
pub fn graded_tube(
    tube: &Primitive,
    shell: &Shell,
    patterns: &[ShellPattern],
    tolerance: f64,
) -> Result<Mesh, String> {
    let (gz, gs) = global_curvatures(shell, patterns);
    let need = |length: f64, k: f64| super::segments_for_chord(length, k, tolerance).min(4096);
    let circumference = TAU * shell.radius;
    let rings = need(shell.height, gz).next_multiple_of(2);
    let segments = need(circumference, gs).max(circle_segments(shell.radius, tolerance));
    let (heights, arcs) = local_windows(shell, patterns, tolerance);
    let z = graded_stations(shell.height, shell.height / rings as f64, &heights, false);
    let s = graded_stations(circumference, circumference / segments as f64, &arcs, true);
    let angles: Vec<f64> = s[..s.len() - 1]
        .iter()
        .map(|&arc| arc / shell.radius)
        .collect();
    tube_on_grid(tube, &z, &angles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stations_are_dense_in_windows_graded_outside_and_cover_the_length() {
        let w = Window {
            centre: 5.0,
            half: 0.6,
            step: 0.01,
        };
        let s = graded_stations(16.0, 0.5, &[w], false);
        assert_eq!((s[0], *s.last().unwrap()), (0.0, 16.0));
        let steps: Vec<(f64, f64)> = s
            .windows(2)
            .map(|p| (0.5 * (p[0] + p[1]), p[1] - p[0]))
            .collect();
        for &(mid, h) in &steps {
            assert!(h > 0.0 && h <= 0.5 + 1e-12, "{mid}: {h}");
            if (mid - 5.0).abs() < 0.6 {
                assert!(h <= 0.01 + 1e-12, "inside the window at {mid}: {h}");
            }
        }
        // Graded: neighbours within the growth (the last step may be evened with a sliver).
        for p in steps[..steps.len() - 2].windows(2) {
            let ratio = p[1].1 / p[0].1;
            assert!((0.7..1.35).contains(&ratio), "steps {p:?} jump");
        }
        // 1.2 m at 8 mm (the step over 1 + GROWTH), two ramps from 1 cm to 0.5 m growing by a
        // quarter a step (about 20 steps each), the rest at 0.4 m: a few hundred stations, not
        // the 1600 of a uniform 1 cm grid.
        assert!(s.len() < 300, "{}", s.len());
        // Periodic: a window across the seam is dense on both sides of it.
        let seam = Window {
            centre: 0.1,
            half: 0.3,
            step: 0.01,
        };
        let c = graded_stations(10.0, 0.5, &[seam], true);
        let last = c[c.len() - 1] - c[c.len() - 2];
        assert!(
            last <= 0.01 + 1e-12 && c[1] <= 0.01 + 1e-12,
            "{last} {}",
            c[1]
        );
    }
}
