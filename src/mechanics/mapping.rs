//! Moving section points with the deflected axis.

use super::PointLoadShape;
use serde::Serialize;

/// How a point of the undeformed cross-section follows the deflected axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mapping {
    /// Plane sections stay plane and normal to the axis; the axis shortens by ½∫v′².
    #[default]
    RotateSections,
    /// 3DGEN's mapping, kept for parity with the paper: add v(x) to the vertical coordinate.
    AddDeflection,
}

impl Mapping {
    pub fn name(self) -> &'static str {
        match self {
            Mapping::RotateSections => "rotate_sections",
            Mapping::AddDeflection => "add_deflection",
        }
    }
}

/// Maps (x, z) of the undeformed beam (x along the axis from the axially fixed end, z upward
/// from the neutral axis) to the deformed (X, Z). The y coordinate is unchanged.
///
/// The axial shortening u(x) = ½∫₀ˣ v′² is integrated exactly over the given stations
/// (v′² is a polynomial of degree ≤ 4 between kinks, and every kink is a station), so it is
/// only available at those stations.
pub struct SectionMapper<'a> {
    shape: &'a PointLoadShape,
    mapping: Mapping,
    stations: &'a [f64],
    shortening: Vec<f64>,
}

impl<'a> SectionMapper<'a> {
    pub fn new(shape: &'a PointLoadShape, mapping: Mapping, stations: &'a [f64]) -> Self {
        let shortening = match mapping {
            Mapping::RotateSections => cumulative_shortening(shape, stations),
            Mapping::AddDeflection => vec![0.0; stations.len()],
        };
        SectionMapper { shape, mapping, stations, shortening }
    }

    /// Deformed (X, Z) of the point at height `z` in the section at station `i`.
    pub fn map(&self, i: usize, z: f64) -> (f64, f64) {
        let x = self.stations[i];
        let d = self.shape.at(x);
        match self.mapping {
            Mapping::AddDeflection => (x, z - d.v),
            Mapping::RotateSections => {
                // Unit normal of the deflected axis (pointing up): (v′, 1)/√(1 + v′²).
                let inv = 1.0 / d.slope.hypot(1.0);
                (x - self.shortening[i] + z * d.slope * inv, z * inv - d.v)
            }
        }
    }

    pub fn shortening_at_end(&self) -> f64 {
        self.shortening.last().copied().unwrap_or(0.0)
    }
}

/// ½∫₀^{x_i} v′² at every station, with 3-point Gauss–Legendre per interval (exact for the
/// degree-4 integrand of a piecewise-cubic deflection).
fn cumulative_shortening(shape: &PointLoadShape, stations: &[f64]) -> Vec<f64> {
    const NODES: [(f64, f64); 3] = [(-0.774_596_669_241_483_4, 5.0 / 9.0), (0.0, 8.0 / 9.0), (0.774_596_669_241_483_4, 5.0 / 9.0)];
    let mut out = Vec::with_capacity(stations.len());
    let mut total = 0.0;
    out.push(0.0);
    for w in stations.windows(2) {
        let (mid, half) = (0.5 * (w[0] + w[1]), 0.5 * (w[1] - w[0]));
        let integral: f64 = NODES.iter().map(|&(t, wt)| wt * shape.at(mid + half * t).slope.powi(2)).sum();
        total += 0.5 * half * integral;
        out.push(total);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::Support;

    fn stations(l: f64, a: f64, n: usize) -> Vec<f64> {
        let mut s: Vec<f64> = (0..=n).map(|i| l * i as f64 / n as f64).collect();
        s.push(a);
        s.sort_by(f64::total_cmp);
        s.dedup();
        s
    }

    #[test]
    fn shortening_matches_closed_form() {
        // SS, centre load: ½∫v′² = 2.4 δ²/L (mechanics.md §3); cantilever tip load: 0.6 δ²/L.
        for (support, a, k) in [(Support::SimplySupported, 1.0, 2.4), (Support::Cantilever, 2.0, 0.6)] {
            let shape = PointLoadShape::new(support, 2.0, a, 0.1);
            let st = stations(2.0, a, 7);
            let m = SectionMapper::new(&shape, Mapping::RotateSections, &st);
            let want = k * 0.1 * 0.1 / 2.0;
            assert!((m.shortening_at_end() / want - 1.0).abs() < 1e-12, "{support:?}: {} vs {want}", m.shortening_at_end());
        }
    }

    #[test]
    fn sections_stay_plane_and_normal_to_the_axis() {
        let shape = PointLoadShape::new(Support::SimplySupported, 3.0, 0.8, 0.15);
        let st = stations(3.0, 0.8, 11);
        let m = SectionMapper::new(&shape, Mapping::RotateSections, &st);
        for i in 0..st.len() {
            let (x0, z0) = m.map(i, -0.2);
            let (x1, z1) = m.map(i, 0.3);
            // Section keeps its depth …
            assert!(((x1 - x0).hypot(z1 - z0) - 0.5).abs() < 1e-12);
            // … and is perpendicular to the axis tangent (1, −v′).
            let slope = shape.at(st[i]).slope;
            assert!(((x1 - x0) - slope * (z1 - z0)).abs() < 1e-12);
        }
    }

    #[test]
    fn parity_mapping_adds_the_deflection() {
        let shape = PointLoadShape::new(Support::Cantilever, 3.0, 3.0, 0.2);
        let st = stations(3.0, 3.0, 5);
        let m = SectionMapper::new(&shape, Mapping::AddDeflection, &st);
        let (x, z) = m.map(st.len() - 1, 0.1);
        assert_eq!((x, z), (3.0, 0.1 - 0.2));
    }
}
