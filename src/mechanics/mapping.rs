//! Moving section points with the deflected axis.

use super::Axial;
use serde::Serialize;

/// The deflected axis at one station: deflection (down), slope dv/dx, and the tangent of the
/// section rotation ψ (equal to the slope without shear deformation). `axial` is the exact
/// deformed axial position where the theory knows it (the elastica); otherwise the mapping
/// integrates the shortening ½∫v′².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisPoint {
    /// Deflection v, metres, positive downward.
    pub v: f64,
    /// Slope dv/dx of the axis.
    pub slope: f64,
    /// tan ψ, ψ the rotation of the section (equals the slope without shear deformation).
    pub rotation: f64,
    /// Exact deformed axial position, metres, where the theory knows it (the elastica); None
    /// otherwise.
    pub axial: Option<f64>,
}

/// How a point of the undeformed cross-section follows the deflected axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Mapping {
    /// Plane sections stay plane and turn with the bending rotation; a free axis shortens by
    /// ½∫v′², a restrained one stretches by as much between its held ends.
    #[default]
    RotateSections,
    /// 3DGEN's mapping, kept for parity with the paper: every point moves vertically by the
    /// deflection v(x) (down for positive v); sections neither turn nor shorten the axis.
    AddDeflection,
}

/// Where a section lands: its axis point (x, −v) and its rotation (cos, sin).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectionFrame {
    /// Deformed axial position of the section's axis point, metres.
    pub x: f64,
    /// Its deflection, metres, positive downward.
    pub v: f64,
    /// Cosine of the section's rotation.
    pub cos: f64,
    /// Sine of the section's rotation (positive turns the section's top towards +x).
    pub sin: f64,
}

impl SectionFrame {
    /// Deformed (X, Z) of the section point at height z (y is unchanged).
    pub fn place(&self, z: f64) -> (f64, f64) {
        (self.x + z * self.sin, z * self.cos - self.v)
    }
}

/// Section frames at the given stations (which must include both ends and every kink). The
/// axial shortening u(x) = ½∫₀ˣ v′² is integrated with 3-point Gauss–Legendre per interval, exact
/// for the piecewise-quartic integrand of a piecewise-cubic deflection. A free axis keeps its
/// length, so its far end moves in by u(L); a restrained one is held at both ends and stretches
/// uniformly instead (membrane strain u(L)/L), so each section moves in by u(x) − (x/L)·u(L)
/// and the last station stays exactly where it was (docs/mechanics.md §5.4).
pub fn section_frames(
    stations: &[f64],
    mapping: Mapping,
    axial: Axial,
    axis: impl Fn(f64) -> AxisPoint,
) -> Vec<SectionFrame> {
    let shortening = match mapping {
        Mapping::RotateSections => shortening(stations, &axis),
        Mapping::AddDeflection => vec![0.0; stations.len()],
    };
    let total = shortening.last().copied().unwrap_or(0.0);
    let span = stations.last().copied().unwrap_or(0.0);
    stations
        .iter()
        .zip(&shortening)
        .map(|(&x, &u)| {
            let p = axis(x);
            match mapping {
                Mapping::AddDeflection => SectionFrame {
                    x,
                    v: p.v,
                    cos: 1.0,
                    sin: 0.0,
                },
                Mapping::RotateSections => {
                    let moved_in = match axial {
                        Axial::Free => u,
                        Axial::Restrained => u - x / span * total,
                    };
                    let inv = 1.0 / p.rotation.hypot(1.0);
                    SectionFrame {
                        x: p.axial.unwrap_or(x - moved_in),
                        v: p.v,
                        cos: inv,
                        sin: p.rotation * inv,
                    }
                }
            }
        })
        .collect()
}

/// u(x) = ½∫₀ˣ v′² at every station, accumulated interval by interval.
fn shortening(stations: &[f64], axis: &impl Fn(f64) -> AxisPoint) -> Vec<f64> {
    const GAUSS: [(f64, f64); 3] = [
        (-0.774_596_669_241_483_4, 5.0 / 9.0),
        (0.0, 8.0 / 9.0),
        (0.774_596_669_241_483_4, 5.0 / 9.0),
    ];
    let mut shortening = 0.0;
    let mut out = Vec::with_capacity(stations.len());
    for (i, &x) in stations.iter().enumerate() {
        if i > 0 {
            let (mid, half) = (0.5 * (stations[i - 1] + x), 0.5 * (x - stations[i - 1]));
            shortening += 0.5
                * half
                * GAUSS
                    .iter()
                    .map(|&(t, w)| w * axis(mid + half * t).slope.powi(2))
                    .sum::<f64>();
        }
        out.push(shortening);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SS beam, centre load, unit span: v = δ(3ξ − 4ξ³) for ξ ≤ ½, mirrored.
    fn ss_centre(delta: f64) -> impl Fn(f64) -> AxisPoint {
        move |x: f64| {
            let (xi, sign) = if x <= 0.5 { (x, 1.0) } else { (1.0 - x, -1.0) };
            let slope = sign * delta * (3.0 - 12.0 * xi * xi);
            AxisPoint {
                v: delta * (3.0 * xi - 4.0 * xi.powi(3)),
                slope,
                rotation: slope,
                axial: None,
            }
        }
    }

    #[test]
    fn shortening_matches_closed_form() {
        // ½∫v′² = 2.4 δ²/L for the SS centre load (docs/mechanics.md §5.2).
        let stations: Vec<f64> = (0..=6).map(|i| f64::from(i) / 6.0).collect();
        let frames = section_frames(
            &stations,
            Mapping::RotateSections,
            Axial::Free,
            ss_centre(0.1),
        );
        assert!((1.0 - frames[6].x - 2.4 * 0.01).abs() < 1e-14);
    }

    #[test]
    fn sections_stay_plane_and_normal_to_the_axis() {
        let stations: Vec<f64> = (0..=10).map(|i| f64::from(i) / 10.0).collect();
        let axis = ss_centre(0.15);
        for (f, &x) in section_frames(&stations, Mapping::RotateSections, Axial::Free, &axis)
            .iter()
            .zip(&stations)
        {
            let ((x0, z0), (x1, z1)) = (f.place(-0.2), f.place(0.3));
            assert!(((x1 - x0).hypot(z1 - z0) - 0.5).abs() < 1e-12);
            assert!(((x1 - x0) - axis(x).slope * (z1 - z0)).abs() < 1e-12);
        }
    }

    #[test]
    fn parity_mapping_adds_the_deflection() {
        let f = section_frames(
            &[0.0, 0.5],
            Mapping::AddDeflection,
            Axial::Free,
            ss_centre(0.2),
        )[1];
        assert_eq!(f.place(0.1), (0.5, 0.1 - 0.2));
    }
}
