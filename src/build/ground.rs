//! The ground as geometry: a flat square under the structures, big enough that its edge lies
//! at the horizon, traced with them so that it receives their shadows.
//!
//! Owns: the ground's mesh and where it lies. Must not touch: how the ground looks (materials)
//! or which outputs see it (the pipeline decides from `GroundSpec::in_depth`).

use crate::geometry::Mesh;
use glam::DVec3;

/// The ground square centred under `centre` at height `z`, reaching `half_side` metres from
/// it along x and y: two triangles facing up (+z). Two, not a finely cut disc: a ray near the
/// structures then meets two ground boxes in the BVH rather than every slice of a fan (a fan of
/// 96 made a view four times slower).
pub fn ground_square(centre: DVec3, z: f64, half_side: f64) -> Mesh {
    let corner =
        |sx: f64, sy: f64| DVec3::new(centre.x + sx * half_side, centre.y + sy * half_side, z);
    Mesh {
        positions: vec![
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(1.0, 1.0),
            corner(-1.0, 1.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_square_is_flat_faces_up_and_covers_its_side() {
        let square = ground_square(DVec3::new(3.0, -2.0, 7.0), -1.5, 500.0);
        assert!(square.positions.iter().all(|p| p.z == -1.5));
        for t in 0..square.triangles.len() {
            let [a, b, c] = square.triangle(t);
            assert!((b - a).cross(c - a).z > 0.0);
        }
        assert_eq!(square.area(), 1000.0 * 1000.0);
        let (lo, hi) = square.bounds().unwrap();
        assert_eq!((lo.x, hi.x, lo.y, hi.y), (-497.0, 503.0, -502.0, 498.0));
    }
}
