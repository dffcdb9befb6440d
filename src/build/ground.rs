//! The ground as geometry: a flat disc under the structures, big enough that its rim lies at
//! the horizon, traced with them so that it receives their shadows.
//!
//! Owns: the disc's mesh and where it lies. Must not touch: how the ground looks (materials)
//! or which outputs see it (the pipeline decides from `GroundSpec::in_depth`).

use crate::geometry::Mesh;
use glam::DVec3;

/// Sides of the ground disc's polygon: its rim strays from a circle by 1 − cos(π/96) ≈ 0.05 %
/// of the radius, which moves the rim's dip below the horizon by as little.
const RIM_SEGMENTS: u32 = 96;

/// The ground disc centred under `centre` at height `z`, of `radius` metres: a fan of
/// triangles facing up (+z).
pub fn ground_disc(centre: DVec3, z: f64, radius: f64) -> Mesh {
    let mut positions = vec![DVec3::new(centre.x, centre.y, z)];
    positions.extend((0..RIM_SEGMENTS).map(|k| {
        let angle = std::f64::consts::TAU * f64::from(k) / f64::from(RIM_SEGMENTS);
        let (s, c) = (libm::sin(angle), libm::cos(angle));
        DVec3::new(centre.x + radius * c, centre.y + radius * s, z)
    }));
    let triangles = (0..RIM_SEGMENTS)
        .map(|k| [0, 1 + k, 1 + (k + 1) % RIM_SEGMENTS])
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_disc_is_flat_faces_up_and_covers_its_circle() {
        let disc = ground_disc(DVec3::new(3.0, -2.0, 7.0), -1.5, 500.0);
        assert!(disc.positions.iter().all(|p| p.z == -1.5));
        for t in 0..disc.triangles.len() {
            let [a, b, c] = disc.triangle(t);
            assert!((b - a).cross(c - a).z > 0.0);
        }
        // The polygon's area against the circle's: π r² · sin(2π/n) n / (2π).
        let n = f64::from(RIM_SEGMENTS);
        let expected = 0.5 * n * 500.0f64.powi(2) * (std::f64::consts::TAU / n).sin();
        assert!((disc.area() - expected).abs() < 1e-9 * expected);
        assert!(disc.area() > 0.999 * std::f64::consts::PI * 500.0f64.powi(2));
    }
}
