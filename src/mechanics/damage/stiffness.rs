//! A beam whose bending stiffness varies along its length, or with its moment (a cracked
//! reinforced-concrete member): the deflected axis by integrating the curvature, and the
//! moment by compatibility where the supports are statically indeterminate.
//!
//! Curvature v″ = −κ(x, M(x)) (v down, M sagging-positive). On each interval of a fine grid
//! (with nodes at every load, stiffness break and support) κ is taken linear between its end
//! values, and slope and deflection are integrated exactly for that: exact wherever EI is
//! piecewise constant and M piecewise linear (point loads), second order otherwise. The
//! determinate cases integrate once: a cantilever from its clamp, a simply supported beam from
//! x = 0 with the chord through both supports removed. The indeterminate ones use the force
//! method with the same integrals: a propped cantilever is a cantilever plus the prop's
//! reaction, a fixed–fixed beam a simply supported one plus its two end moments, the
//! redundants found by Newton's method on the compatibility conditions (end deflection, end
//! slopes); Newton converges in one step when κ is linear in M, and iterates for cracking.
//! Shear deformation is left out (Euler–Bernoulli).

use crate::mechanics::{AxisPoint, LinearBeam, Load, Support, kinks};

/// Uniform intervals of the integration grid (stiffness breaks and loads come on top).
const GRID: usize = 2048;
/// Newton iterations allowed for the redundants.
const MAX_ITERATIONS: usize = 60;

/// One interval of the integrated axis: start, length, slope and deflection at its start, and
/// v″ at both ends.
#[derive(Clone, Copy, Debug)]
struct Interval {
    x: f64,
    h: f64,
    v: f64,
    slope: f64,
    k0: f64,
    k1: f64,
}

impl Interval {
    fn at(&self, x: f64) -> (f64, f64) {
        let t = (x - self.x).clamp(0.0, self.h);
        let dk = (self.k1 - self.k0) / self.h;
        let slope = self.slope + self.k0 * t + dk * t * t / 2.0;
        let v = self.v + self.slope * t + self.k0 * t * t / 2.0 + dk * t.powi(3) / 6.0;
        (v, slope)
    }
}

/// The deflected axis of a beam with varying stiffness, and its moment field.
#[derive(Clone, Debug)]
pub struct SteppedBeam {
    length: f64,
    intervals: Vec<Interval>,
    /// Rigid rotation removed after integration (the chord of a simply supported base).
    tilt: f64,
    base: LinearBeam,
    redundant: Redundant,
    values: [f64; 2],
    /// Whether the base is simply supported (its chord through the supports is removed).
    chord_removed: bool,
}

/// Which redundants the support case adds to its determinate base.
#[derive(Clone, Copy, Debug)]
enum Redundant {
    None,
    /// The prop's upward reaction at x = L on a cantilever.
    Prop,
    /// End moments (sagging-positive) at x = 0 and x = L on a simply supported beam.
    EndMoments,
}

impl SteppedBeam {
    /// Solves the beam of `length` under physical `loads` with curvature `curvature(x, M)`
    /// (sagging-positive, i.e. M / EI(x) for a linear member; `x` is the interval's midpoint so
    /// a jump in stiffness sits on a node), with extra nodes at `breaks`.
    pub fn solve(
        support: Support,
        length: f64,
        loads: &[Load],
        breaks: &[f64],
        curvature: &dyn Fn(f64, f64) -> f64,
    ) -> Result<SteppedBeam, String> {
        let (base_support, redundant) = match support {
            Support::SimplySupported => (Support::SimplySupported, Redundant::None),
            Support::Cantilever => (Support::Cantilever, Redundant::None),
            Support::ProppedCantilever => (Support::Cantilever, Redundant::Prop),
            Support::FixedFixed => (Support::SimplySupported, Redundant::EndMoments),
        };
        let mut nodes: Vec<f64> = (0..=GRID)
            .map(|i| length * i as f64 / GRID as f64)
            .collect();
        nodes.extend(kinks(loads).into_iter().chain(breaks.iter().copied()));
        nodes.retain(|x| (0.0..=length).contains(x));
        nodes.sort_by(f64::total_cmp);
        nodes.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * length);
        let mut beam = SteppedBeam {
            length,
            intervals: Vec::new(),
            tilt: 0.0,
            base: LinearBeam::solve(base_support, length, loads, 0.0),
            redundant,
            values: [0.0; 2],
            chord_removed: base_support == Support::SimplySupported,
        };
        beam.integrate(&nodes, curvature);
        beam.find_redundants(&nodes, curvature)?;
        Ok(beam)
    }

    /// Bending moment at x, N·m, sagging-positive.
    pub fn moment(&self, x: f64) -> f64 {
        let base = self.base.at(x).moment;
        let l = self.length;
        match self.redundant {
            Redundant::None => base,
            Redundant::Prop => base + self.values[0] * (l - x),
            Redundant::EndMoments => base + self.values[0] * (1.0 - x / l) + self.values[1] * x / l,
        }
    }

    /// Shear force V = dM/dx at x, N.
    pub fn shear(&self, x: f64) -> f64 {
        let base = self.base.at(x).shear;
        let l = self.length;
        match self.redundant {
            Redundant::None => base,
            Redundant::Prop => base - self.values[0],
            Redundant::EndMoments => base + (self.values[1] - self.values[0]) / l,
        }
    }

    /// The deflected axis at x (no shear deformation: the section turns with the slope).
    pub fn at(&self, x: f64) -> AxisPoint {
        let (v, slope) = self.raw(x);
        AxisPoint {
            v: v - self.tilt * x,
            slope: slope - self.tilt,
            rotation: slope - self.tilt,
            axial: None,
        }
    }

    /// Largest |v″| on the grid, 1/m.
    pub fn max_curvature(&self) -> f64 {
        self.intervals
            .iter()
            .map(|i| i.k0.abs().max(i.k1.abs()))
            .fold(0.0, f64::max)
    }

    /// The deflection of largest magnitude on the grid's nodes and where it is.
    pub fn peak(&self) -> (f64, f64) {
        let mut best: (f64, f64) = (0.0, 0.0);
        for i in &self.intervals {
            for x in [i.x, i.x + i.h] {
                let v = self.at(x).v;
                if v.abs() > best.0.abs() {
                    best = (v, x);
                }
            }
        }
        best
    }

    fn raw(&self, x: f64) -> (f64, f64) {
        let k = self
            .intervals
            .partition_point(|i| i.x + i.h < x)
            .min(self.intervals.len() - 1);
        self.intervals[k].at(x)
    }

    /// Integrates v″ = −κ from a clamp at x = 0 (v = v′ = 0), then removes the chord for a
    /// simply supported base.
    fn integrate(&mut self, nodes: &[f64], curvature: &dyn Fn(f64, f64) -> f64) {
        self.intervals.clear();
        let (mut v, mut slope) = (0.0, 0.0);
        for w in nodes.windows(2) {
            let (a, b) = (w[0], w[1]);
            let mid = 0.5 * (a + b);
            let interval = Interval {
                x: a,
                h: b - a,
                v,
                slope,
                k0: -curvature(mid, self.moment(a)),
                k1: -curvature(mid, self.moment(b)),
            };
            (v, slope) = interval.at(b);
            self.intervals.push(interval);
        }
        self.tilt = if self.chord_removed {
            v / self.length
        } else {
            0.0
        };
    }

    /// How far the axis is from meeting the supports the redundants stand for.
    fn compatibility(&self) -> [f64; 2] {
        let end = self.at(self.length);
        match self.redundant {
            Redundant::None => [0.0; 2],
            Redundant::Prop => [end.v, 0.0],
            Redundant::EndMoments => [self.at(0.0).slope, end.slope],
        }
    }

    /// Newton's method on the compatibility conditions, the Jacobian by finite differences
    /// (exact when κ is linear in M, so one step then suffices).
    fn find_redundants(
        &mut self,
        nodes: &[f64],
        curvature: &dyn Fn(f64, f64) -> f64,
    ) -> Result<(), String> {
        let n = match self.redundant {
            Redundant::None => return Ok(()),
            Redundant::Prop => 1,
            Redundant::EndMoments => 2,
        };
        let l = self.length;
        let moment_scale = (0..=64)
            .map(|i| self.base.at(l * i as f64 / 64.0).moment.abs())
            .fold(0.0, f64::max);
        if moment_scale == 0.0 {
            // Unloaded: the redundants are zero and the axis straight.
            return Ok(());
        }
        // Unknowns in moment units: the prop's reaction times L.
        let unit = match self.redundant {
            Redundant::Prop => [1.0 / l, 0.0],
            _ => [1.0, 1.0],
        };
        let step = 1e-3 * moment_scale;
        for _ in 0..MAX_ITERATIONS {
            let r0 = self.compatibility();
            let mut jacobian = [[0.0; 2]; 2];
            let start = self.values;
            for j in 0..n {
                self.values[j] += step * unit[j];
                self.integrate(nodes, curvature);
                let r = self.compatibility();
                for i in 0..n {
                    jacobian[i][j] = (r[i] - r0[i]) / step;
                }
                self.values = start;
            }
            let delta = solve_small(n, jacobian, r0)
                .ok_or("the damaged beam's compatibility equations are singular")?;
            for j in 0..n {
                self.values[j] -= delta[j] * unit[j];
            }
            self.integrate(nodes, curvature);
            if delta.iter().all(|d| d.abs() <= 1e-12 * moment_scale) {
                return Ok(());
            }
        }
        Err(format!(
            "the damaged beam's redundants did not converge in {MAX_ITERATIONS} iterations"
        ))
    }
}

/// Solves the n×n (n ≤ 2) system J d = r.
fn solve_small(n: usize, j: [[f64; 2]; 2], r: [f64; 2]) -> Option<[f64; 2]> {
    let d = if n == 1 {
        [r[0] / j[0][0], 0.0]
    } else {
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        [
            (r[0] * j[1][1] - r[1] * j[0][1]) / det,
            (j[0][0] * r[1] - j[1][0] * r[0]) / det,
        ]
    };
    d.iter().all(|v| v.is_finite()).then_some(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    const EI: f64 = 2.0e7;

    fn point(at: f64, force: f64) -> Vec<Load> {
        vec![Load::Point { at, force }]
    }

    /// EI on [from, to] divided by `ratio`, EI elsewhere.
    fn stepped(from: f64, to: f64, ratio: f64) -> impl Fn(f64, f64) -> f64 {
        move |x, m| {
            if (from..to).contains(&x) {
                m * ratio / EI
            } else {
                m / EI
            }
        }
    }

    #[test]
    fn simply_supported_beam_with_a_soft_middle_segment_matches_the_unit_load_method() {
        // L = 6 m, P = 50 kN at mid-span, EI/4 on [a, L − a] with a = 2 m. Unit load at the
        // centre: m = x/2 on the left half, M = P x/2, so by symmetry
        // δ = 2∫₀^{L/2} (x/2)(P x/2)/EI(x) dx = (P/2)[a³/(3EI) + ((L/2)³ − a³)·4/(3EI)].
        let (l, p, a) = (6.0, 5e4, 2.0);
        let beam = SteppedBeam::solve(
            Support::SimplySupported,
            l,
            &point(l / 2.0, p),
            &[a, l - a],
            &stepped(a, l - a, 4.0),
        )
        .unwrap();
        let exact =
            p / 2.0 * (a.powi(3) / (3.0 * EI) + ((l / 2.0).powi(3) - a.powi(3)) * 4.0 / (3.0 * EI));
        let got = beam.at(l / 2.0).v;
        assert!((got / exact - 1.0).abs() < 1e-12, "{got} vs {exact}");
        // The sound beam: PL³/(48EI).
        let sound = SteppedBeam::solve(
            Support::SimplySupported,
            l,
            &point(l / 2.0, p),
            &[],
            &stepped(0.0, 0.0, 1.0),
        )
        .unwrap();
        assert!((sound.at(l / 2.0).v / (p * l.powi(3) / (48.0 * EI)) - 1.0).abs() < 1e-12);
        assert!(got > 2.0 * sound.at(l / 2.0).v);
        // Supports stay put.
        assert!(beam.at(0.0).v.abs() < 1e-15 && beam.at(l).v.abs() < 1e-15);
    }

    #[test]
    fn cantilever_with_a_soft_root_matches_the_unit_load_method() {
        // L = 3 m, tip load P, EI/2 on the root [0, a], a = 0.75 m. Unit load at the tip:
        // m = M/P = (L − x), δ = P[(L³ − (L − a)³)·2/(3EI) + (L − a)³/(3EI)].
        let (l, p, a) = (3.0, 1e4, 0.75);
        let beam = SteppedBeam::solve(
            Support::Cantilever,
            l,
            &point(l, p),
            &[a],
            &stepped(0.0, a, 2.0),
        )
        .unwrap();
        let exact =
            p * ((l.powi(3) - (l - a).powi(3)) * 2.0 / (3.0 * EI) + (l - a).powi(3) / (3.0 * EI));
        assert!(
            (beam.at(l).v / exact - 1.0).abs() < 1e-12,
            "{} vs {exact}",
            beam.at(l).v
        );
        // The clamp holds.
        assert_eq!((beam.at(0.0).v, beam.at(0.0).slope), (0.0, 0.0));
        // Tip slope: θ = P[(L² − (L − a)²)·2/(2EI) + (L − a)²/(2EI)].
        let slope = p * ((l * l - (l - a).powi(2)) / EI + (l - a).powi(2) / (2.0 * EI));
        assert!((beam.at(l).slope / slope - 1.0).abs() < 1e-12);
    }

    #[test]
    fn an_unloaded_beam_stays_straight_on_any_supports() {
        // No load: no moment to scale the compatibility system by, and nothing to solve.
        for support in [Support::FixedFixed, Support::ProppedCantilever] {
            let idle =
                SteppedBeam::solve(support, 3.0, &[], &[1.0], &stepped(0.0, 1.0, 2.0)).unwrap();
            assert_eq!(idle.peak(), (0.0, 0.0));
        }
    }

    #[test]
    fn indeterminate_beams_by_compatibility_match_the_closed_forms() {
        let (l, p) = (4.0, 2e4);
        let uniform = stepped(0.0, 0.0, 1.0);
        // Fixed–fixed, centre load: δ = PL³/(192EI), end moments −PL/8.
        let ff =
            SteppedBeam::solve(Support::FixedFixed, l, &point(l / 2.0, p), &[], &uniform).unwrap();
        assert!((ff.at(l / 2.0).v / (p * l.powi(3) / (192.0 * EI)) - 1.0).abs() < 1e-9);
        assert!((ff.moment(0.0) / (-p * l / 8.0) - 1.0).abs() < 1e-9);
        assert!(ff.at(0.0).slope.abs() < 1e-12 && ff.at(l).slope.abs() < 1e-12);
        // Propped cantilever, centre load: δ(L/2) = 7PL³/(768EI), prop reaction 5P/16.
        let pc = SteppedBeam::solve(
            Support::ProppedCantilever,
            l,
            &point(l / 2.0, p),
            &[],
            &uniform,
        )
        .unwrap();
        assert!((pc.at(l / 2.0).v / (7.0 * p * l.powi(3) / (768.0 * EI)) - 1.0).abs() < 1e-9);
        assert!((pc.shear(0.99 * l) / (-5.0 * p / 16.0) - 1.0).abs() < 1e-9);
        // A fixed–fixed beam softened symmetrically in the middle: M at the ends grows in
        // magnitude (stiffness draws moment), δ grows. Unit-load method on the released
        // (simply supported) beam with the end moments as redundants gives, by symmetry,
        // M_end = −P/2 ∫₀^{L/2} x/EI dx / ∫₀^{L/2} 1/EI dx over the left half.
        let (a, r) = (1.0, 3.0);
        let soft = SteppedBeam::solve(
            Support::FixedFixed,
            l,
            &point(l / 2.0, p),
            &[a, l - a],
            &stepped(a, l - a, r),
        )
        .unwrap();
        let int_x = a * a / 2.0 + r * ((l / 2.0).powi(2) - a * a) / 2.0;
        let int_1 = a + r * (l / 2.0 - a);
        let m_end = -p / 2.0 * int_x / int_1;
        assert!(
            (soft.moment(0.0) / m_end - 1.0).abs() < 1e-9,
            "{} vs {m_end}",
            soft.moment(0.0)
        );
    }
}
