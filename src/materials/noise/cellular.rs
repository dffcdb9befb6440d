//! Cellular noise (S. Worley, "A Cellular Texture Basis Function", SIGGRAPH 1996): one
//! jittered point per cube of the lattice; a position is described by its nearest point (the
//! cell it lies in, its id) and the second nearest (the border between the two). Rust patches,
//! pores, zinc spangle, stone blocks and crack networks are drawn from it; crack masks need the
//! exact distance to a border, so this stays f64.
//!
//! The 27 cubes around the position are visited nearest first, and a cube whose closest face
//! lies farther than the second-nearest point found so far is skipped without hashing it
//! (Worley's own early-out, on squared distances).
//!
//! Owns: cellular noise. Must not touch: gradient noise, materials.

use super::{MemoTag, Noise, axis_word, cell, corner_hash};
use glam::DVec3;

/// The two nearest cell points of a cellular pattern.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cells {
    /// Distance to the nearest cell point.
    pub f1: f64,
    /// Distance to the border between the nearest and the second-nearest cell.
    pub border: f64,
    /// Hash of the nearest cell.
    pub id: u64,
    /// Hash of the second-nearest cell.
    pub neighbour: u64,
}

/// The 27 neighbouring cubes as offsets 0–2 (for −1, 0, +1) along x, y, z: the cube itself,
/// then its 6 faces, 12 edges and 8 corners, so the nearest points are usually found first and
/// most of the rest skipped.
const NEAREST_FIRST: [[usize; 3]; 27] = {
    let mut out = [[0; 3]; 27];
    let mut n = 0;
    let mut distance = 0;
    while distance <= 3 {
        let mut i = 0;
        while i < 27 {
            let o = [i % 3, (i / 3) % 3, i / 9];
            let away = (o[0] != 1) as usize + (o[1] != 1) as usize + (o[2] != 1) as usize;
            if away == distance {
                out[n] = o;
                n += 1;
            }
            i += 1;
        }
        distance += 1;
    }
    out
};

/// A point found by the search: squared distance, position relative to the cube holding the
/// position, and the cell's id.
#[derive(Clone, Copy)]
struct Found {
    d2: f64,
    point: DVec3,
    id: u64,
}

impl Noise {
    /// Cellular noise with one jittered point per cube of side `size` metres.
    pub fn cells(&self, p: DVec3, size: f64) -> Cells {
        let q = p / size;
        let axes = [cell(q.x), cell(q.y), cell(q.z)];
        let f = DVec3::new(axes[0].1, axes[1].1, axes[2].1);
        // Squared distance from the position to the slab of each offset, per axis.
        let slab: [[f64; 3]; 3] =
            std::array::from_fn(|k| [f[k] * f[k], 0.0, (1.0 - f[k]) * (1.0 - f[k])]);
        let none = Found {
            d2: f64::INFINITY,
            point: DVec3::ZERO,
            id: 0,
        };
        let (mut first, mut second) = (none, none);
        CUBE_MEMO.with_borrow_mut(|memo| {
            let slot = (size.to_bits().wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 62) as usize;
            let around = memo[slot].points(self.cell_key, [axes[0].0, axes[1].0, axes[2].0]);
            for (o, &(point, id)) in NEAREST_FIRST.iter().zip(around) {
                if slab[0][o[0]] + slab[1][o[1]] + slab[2][o[2]] >= second.d2 {
                    continue;
                }
                let d2 = point.distance_squared(f);
                let found = Found { d2, point, id };
                if d2 < first.d2 {
                    (first, second) = (found, first);
                } else if d2 < second.d2 {
                    second = found;
                }
            }
        });
        // Distance from the position to the bisecting plane of the two nearest points.
        let border = (second.d2 - first.d2) / (2.0 * first.point.distance(second.point));
        Cells {
            f1: first.d2.sqrt() * size,
            border: border * size,
            id: first.id,
            neighbour: second.id,
        }
    }
}

/// The points of the 27 cubes around one cube of a cellular lattice, in `NEAREST_FIRST`
/// order, relative to that cube, with their ids. Neighbouring pixels mostly fall into the
/// same cube, and the points are a function of the cube's integer coordinates and the lattice
/// key alone: a memo holding the cube asked for gives exactly the points hashing would, so it
/// saves time and changes no value, whatever the order of points or threads.
#[derive(Clone, Copy)]
struct CubeMemo {
    tag: MemoTag,
    points: [(DVec3, u64); 27],
}

impl CubeMemo {
    const EMPTY: CubeMemo = CubeMemo {
        tag: MemoTag::EMPTY,
        points: [(DVec3::ZERO, 0); 27],
    };

    /// The points around cube `cube` of the lattice under `key`, from the memo or hashed.
    #[inline(always)]
    fn points(&mut self, key: u64, cube: [i64; 3]) -> &[(DVec3, u64); 27] {
        if !self.tag.holds(key, cube) {
            let words: [[u64; 3]; 3] = std::array::from_fn(|k| {
                let i = cube[k];
                [i - 1, i, i + 1].map(|i| axis_word(i, k, key))
            });
            self.points = NEAREST_FIRST.map(|o| {
                let id = corner_hash(words[0][o[0]], words[1][o[1]], words[2][o[2]]);
                let corner = DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64) - DVec3::ONE;
                (corner + jitter(id), id)
            });
            self.tag = MemoTag {
                key,
                cell: cube,
                filled: true,
            };
        }
        &self.points
    }
}

thread_local! {
    /// A few memos, picked by the cell size: a material draws at most a few patterns.
    static CUBE_MEMO: std::cell::RefCell<[CubeMemo; 4]> =
        const { std::cell::RefCell::new([CubeMemo::EMPTY; 4]) };
}

/// The cell's point within its cube, from three 21-bit fields of its id.
#[inline(always)]
fn jitter(id: u64) -> DVec3 {
    const BITS: u64 = (1 << 21) - 1;
    const UNIT: f64 = 1.0 / (1u64 << 21) as f64;
    DVec3::new(
        (id >> 43) as f64,
        ((id >> 22) & BITS) as f64,
        ((id >> 1) & BITS) as f64,
    ) * UNIT
}

#[cfg(test)]
mod tests {
    use super::super::spread_points;
    use super::*;

    /// The point of the cell at integer lattice coordinates `c` (absolute lattice units).
    fn cell_point(n: &Noise, c: [i64; 3]) -> (DVec3, u64) {
        let w: [u64; 3] = std::array::from_fn(|k| axis_word(c[k], k, n.cell_key));
        let id = corner_hash(w[0], w[1], w[2]);
        let corner = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64);
        (corner + jitter(id), id)
    }

    #[test]
    fn the_cube_memo_changes_no_value() {
        super::super::memo_changes_nothing(|n, p| n.cells(p, 0.01));
    }

    #[test]
    fn nearest_first_visits_every_neighbour_once() {
        let mut seen = NEAREST_FIRST.to_vec();
        seen.sort();
        seen.dedup();
        assert_eq!(seen.len(), 27);
        assert_eq!(NEAREST_FIRST[0], [1, 1, 1]);
    }

    #[test]
    fn same_seed_same_cells_other_seed_other_cells() {
        let (a, b, c) = (Noise::new(7), Noise::new(7), Noise::new(8));
        let p = DVec3::new(0.31, 1.7, -2.2);
        assert_eq!(a.cells(p, 0.1), b.cells(p, 0.1));
        assert_ne!(a.cells(p, 0.1).id, c.cells(p, 0.1).id);
    }

    #[test]
    fn cell_border_distance_is_exact_against_brute_force() {
        // Recompute the two nearest cell points over a wide neighbourhood and compare.
        let n = Noise::new(11);
        let size = 0.25;
        for p in spread_points(2000, DVec3::new(-1.0, -1.5, 0.0)) {
            let c = n.cells(p, size);
            let q = p / size;
            let base = q.floor().as_i64vec3();
            let mut all: Vec<(f64, DVec3, u64)> = Vec::new();
            for dz in -2..=2 {
                for dy in -2..=2 {
                    for dx in -2..=2 {
                        let c = base + glam::I64Vec3::new(dx, dy, dz);
                        let (point, id) = cell_point(&n, c.to_array());
                        all.push((point.distance(q), point, id));
                    }
                }
            }
            all.sort_by(|x, y| x.0.total_cmp(&y.0));
            let (a, b) = (all[0].1, all[1].1);
            let normal = (b - a).normalize();
            let expected = (0.5 * (a + b) - q).dot(normal) * size;
            assert_eq!((c.id, c.neighbour), (all[0].2, all[1].2));
            assert!((c.f1 - all[0].0 * size).abs() < 1e-12);
            assert!(
                (c.border - expected).abs() < 1e-12,
                "{} {expected}",
                c.border
            );
            assert!(c.border >= 0.0);
        }
    }

    #[test]
    fn cell_points_are_uniform_in_their_cubes() {
        // Jitter from 21-bit fields: each coordinate's mean near 1/2, variance near 1/12, and
        // the three uncorrelated.
        let n = Noise::new(4);
        let pts: Vec<DVec3> = (0..20_000)
            .map(|i| {
                let c = [i % 31, (i / 31) % 29, i / 899];
                let (p, _) = cell_point(&n, c);
                p - DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)
            })
            .collect();
        let count = pts.len() as f64;
        let mean = pts.iter().sum::<DVec3>() / count;
        let var = pts.iter().map(|p| (*p - mean) * (*p - mean)).sum::<DVec3>() / count;
        let cov = pts
            .iter()
            .map(|p| (p.x - mean.x) * (p.y - mean.y))
            .sum::<f64>()
            / count;
        assert!(
            (mean - DVec3::splat(0.5)).abs().max_element() < 0.01,
            "{mean}"
        );
        assert!(
            (var - DVec3::splat(1.0 / 12.0)).abs().max_element() < 0.003,
            "{var}"
        );
        assert!(cov.abs() < 0.003, "{cov}");
    }
}
