//! Seeded noise over 3D space, in metres: fractal gradient noise (Perlin, from the `noise`
//! crate) and cellular noise (Worley, here, because the crate offers neither cell ids nor the
//! distance to a cell border, which rust patches, stone blocks and crack networks need).
//!
//! Both are continuous functions of position, so a texture evaluated on the undeformed surface
//! is continuous across every edge. Fractal octaves finer than the pixel footprint fade out,
//! so distant surfaces average their texture instead of aliasing it.

use glam::DVec3;
use noise::{NoiseFn, Perlin};

/// Noise generators for one seed.
#[derive(Clone, Debug)]
pub struct Noise {
    perlin: Perlin,
    seed: u64,
}

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

impl Noise {
    /// The generators for `seed`.
    pub fn new(seed: u64) -> Self {
        Noise {
            perlin: Perlin::new(seed as u32 ^ (seed >> 32) as u32),
            seed,
        }
    }

    /// Gradient noise with features about `wavelength` metres apart, roughly in [-1, 1].
    pub fn gradient(&self, p: DVec3, wavelength: f64) -> f64 {
        let q = p / wavelength;
        self.perlin.get([q.x, q.y, q.z])
    }

    /// Fractal sum of `octaves` gradient noises, the first `wavelength` metres, each next one
    /// half the size and half the amplitude. Octaves shorter than four pixel footprints fade
    /// out, and are gone at two (the Nyquist limit). Normalised to roughly [-1, 1].
    pub fn fractal(&self, p: DVec3, wavelength: f64, octaves: u32, footprint: f64) -> f64 {
        let (mut sum, mut amplitude, mut lambda) = (0.0, 1.0, wavelength);
        for octave in 0..octaves {
            let weight = (lambda / footprint / 2.0 - 1.0).clamp(0.0, 1.0);
            if weight == 0.0 {
                break;
            }
            // Shift each octave so their lattice points do not line up.
            let shift = DVec3::splat(17.31 * f64::from(octave));
            sum += amplitude * weight * self.perlin.get((p / lambda + shift).to_array());
            amplitude *= 0.5;
            lambda *= 0.5;
        }
        // Normalised by every octave, so octaves filtered out take their variance with them.
        let norm = 2.0 * (1.0 - 0.5f64.powi(octaves as i32));
        sum / norm * 1.4
    }

    /// Cellular noise with one jittered point per cube of side `size` metres.
    pub fn cells(&self, p: DVec3, size: f64) -> Cells {
        let q = p / size;
        let base = q.floor();
        let mut nearest = [(f64::INFINITY, DVec3::ZERO, 0u64); 2];
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let cell = base + DVec3::new(f64::from(dx), f64::from(dy), f64::from(dz));
                    let id = self.cell_hash(cell);
                    let point = cell + jitter(id);
                    let d = point.distance_squared(q);
                    if d < nearest[0].0 {
                        nearest[1] = nearest[0];
                        nearest[0] = (d, point, id);
                    } else if d < nearest[1].0 {
                        nearest[1] = (d, point, id);
                    }
                }
            }
        }
        let [(d1, a, id), (d2, b, neighbour)] = nearest;
        // Distance from q to the bisecting plane of the two nearest points.
        let border = (d2 - d1) / (2.0 * a.distance(b));
        Cells {
            f1: d1.sqrt() * size,
            border: border * size,
            id,
            neighbour,
        }
    }

    fn cell_hash(&self, cell: DVec3) -> u64 {
        let [x, y, z] = cell.to_array().map(|c| c as i64 as u64);
        mix(mix(mix(self.seed ^ 0x9e37_79b9_7f4a_7c15, x), y), z)
    }
}

/// A unit value in [0, 1) from a hash, for per-cell choices.
pub fn unit(hash: u64, salt: u64) -> f64 {
    (mix(hash, salt) >> 11) as f64 / (1u64 << 53) as f64
}

/// A symmetric hash of two cell ids: the same for the border seen from either side.
pub fn pair(a: u64, b: u64) -> u64 {
    mix(a.min(b), a.max(b))
}

fn jitter(id: u64) -> DVec3 {
    DVec3::new(unit(id, 1), unit(id, 2), unit(id, 3))
}

/// splitmix64 finaliser over a combined word.
fn mix(h: u64, v: u64) -> u64 {
    let mut z = h ^ v.wrapping_mul(0xbf58_476d_1ce4_e5b9).rotate_left(31);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// 0 below `lo`, 1 above `hi`, smooth between.
pub fn smoothstep(lo: f64, hi: f64, x: f64) -> f64 {
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(n: usize) -> impl Iterator<Item = DVec3> {
        (0..n).map(|i| {
            let t = i as f64;
            DVec3::new(
                (t * 0.618_034).fract() * 3.0,
                (t * 0.414_214).fract() * 3.0,
                (t * 0.732_051).fract() * 3.0,
            )
        })
    }

    #[test]
    fn same_seed_same_values_other_seed_other_values() {
        let (a, b, c) = (Noise::new(7), Noise::new(7), Noise::new(8));
        let p = DVec3::new(0.31, 1.7, -2.2);
        assert_eq!(a.fractal(p, 0.2, 5, 1e-4), b.fractal(p, 0.2, 5, 1e-4));
        assert_eq!(a.cells(p, 0.1), b.cells(p, 0.1));
        assert_ne!(a.fractal(p, 0.2, 5, 1e-4), c.fractal(p, 0.2, 5, 1e-4));
        assert_ne!(a.cells(p, 0.1).id, c.cells(p, 0.1).id);
    }

    #[test]
    fn fractal_noise_is_continuous_bounded_and_filtered() {
        let n = Noise::new(3);
        for p in points(2000) {
            let v = n.fractal(p, 0.3, 6, 1e-4);
            assert!(v.is_finite() && v.abs() <= 1.5, "{v}");
            let nearby = n.fractal(p + DVec3::splat(1e-7), 0.3, 6, 1e-4);
            assert!((v - nearby).abs() < 1e-3);
        }
        // A footprint larger than twice the first wavelength leaves nothing to see.
        assert_eq!(n.fractal(DVec3::new(0.1, 0.2, 0.3), 0.3, 6, 0.7), 0.0);
    }

    #[test]
    fn cell_border_distance_is_exact_against_brute_force() {
        // Recompute the two nearest cell points over a wide neighbourhood and compare.
        let n = Noise::new(11);
        let size = 0.25;
        for p in points(300) {
            let c = n.cells(p, size);
            let q = p / size;
            let mut all: Vec<(f64, DVec3)> = Vec::new();
            for dz in -2..=2 {
                for dy in -2..=2 {
                    for dx in -2..=2 {
                        let cell = q.floor() + DVec3::new(dx as f64, dy as f64, dz as f64);
                        let point = cell + jitter(n.cell_hash(cell));
                        all.push((point.distance(q), point));
                    }
                }
            }
            all.sort_by(|x, y| x.0.total_cmp(&y.0));
            let (a, b) = (all[0].1, all[1].1);
            let normal = (b - a).normalize();
            let expected = (0.5 * (a + b) - q).dot(normal) * size;
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
    fn pair_hash_is_symmetric() {
        assert_eq!(pair(3, 9), pair(9, 3));
        assert_ne!(pair(3, 9), pair(3, 10));
        assert!((0..1000).all(|i| (0.0..1.0).contains(&unit(i, 5))));
    }
}
