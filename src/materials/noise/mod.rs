//! Seeded noise over 3D space, in metres: fractal gradient noise (`gradient`) and cellular
//! noise (`cellular`), both written here so that they are cheap, exact where patterns need it,
//! and the same on every machine.
//!
//! Both are continuous functions of position, so a texture evaluated on the undeformed surface
//! is continuous across every edge. Fractal octaves finer than the pixel footprint fade out,
//! so distant surfaces average their texture instead of aliasing it.
//!
//! Lattice points are hashed, not looked up in a permutation table: a seed changes every
//! value, and there is no period (a 256-entry table repeats every 256 cells).
//!
//! Neighbouring pixels mostly fall into the same lattice cell of every octave coarser than a
//! few pixels, so each thread keeps what it hashed for the cells it last evaluated (the corner
//! gradients of gradient noise, the 27 points around a cube of cellular noise). A memo entry
//! is a function of the cell's integer coordinates and the lattice key, which it is checked
//! against, so it gives exactly what hashing anew would: it saves a quarter of a gradient
//! octave's time and half of a cellular search's, and changes no value.
//!
//! Determinism: integer hashing and IEEE additions, multiplications and divisions only (no
//! fused multiply-add, no libm call, no CPU-dependent path), so every value is bit-identical
//! on every x86-64 CPU, thread count and shard, in whatever order points are evaluated.
//!
//! Owns: the noise functions and their hashes. Must not touch: what a material does with them
//! (`procedural`), geometry or shading.

mod cellular;
mod gradient;
mod lanes;

pub use cellular::Cells;
pub use gradient::{Field, LANES, Ladder, SpanLadder};

/// Noise generators for one seed.
#[derive(Clone, Debug)]
pub struct Noise {
    /// Hash key of the gradient lattice, one per lane group of a ladder (see `Ladder`).
    keys: [u64; gradient::GROUPS],
    /// Hash key of the cellular lattice.
    cell_key: u64,
}

impl Noise {
    /// The generators for `seed`.
    pub fn new(seed: u64) -> Self {
        Noise {
            keys: std::array::from_fn(|g| mix(seed, 0x6772_6164 + g as u64)),
            cell_key: mix(seed ^ 0x9e37_79b9_7f4a_7c15, 0x6365_6c6c),
        }
    }
}

/// Multipliers of the three lattice axes: odd, with unrelated bit patterns.
const AXES: [u64; 3] = [
    0x9e37_79b9_7f4a_7c15,
    0xc2b2_ae3d_27d4_eb4f,
    0x1656_67b1_9e37_79f9,
];

/// A random word for integer coordinate `i` along `axis`: a multiply–xorshift round of the
/// coordinate. Computed once per coordinate and shared by the corners on that side of a cell.
#[inline(always)]
fn axis_word(i: i64, axis: usize, key: u64) -> u64 {
    let w = (i as u64).wrapping_mul(AXES[axis]).wrapping_add(key);
    let w = (w ^ (w >> 32)).wrapping_mul(0xd6e8_feb8_6659_fd93);
    w ^ (w >> 29)
}

/// The hash of a lattice corner from its three axis words: xor (a step along one axis cannot
/// cancel a step along another, as in a sum of multiples), then a multiply–xorshift round so
/// that every bit of every word reaches every bit used (the splitmix64 finaliser's constants,
/// Steele, Lea & Flood 2014).
#[inline(always)]
fn corner_hash(x: u64, y: u64, z: u64) -> u64 {
    let h = (x ^ y ^ z).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h ^ (h >> 32)
}

/// The integer cell of `x` and the position in it, in [0, 1] (1 only when a tiny negative `x`
/// rounds up to its cell's end). Floors by conversion rather than
/// `f64::floor`, which is a library call on the x86-64 baseline (no SSE4.1 rounding).
#[inline(always)]
fn cell(x: f64) -> (i64, f64) {
    let i = x as i64;
    let i = i - i64::from(x < i as f64);
    (i, x - i as f64)
}

/// The lattice cell a memo entry holds: the lattice's key and the cell's integer coordinates.
#[derive(Clone, Copy)]
struct MemoTag {
    key: u64,
    cell: [i64; 3],
    /// Whether the entry holds a cell yet (a fresh one holds none).
    filled: bool,
}

impl MemoTag {
    const EMPTY: MemoTag = MemoTag {
        key: 0,
        cell: [0; 3],
        filled: false,
    };

    /// Whether the entry holds cell `cell` of the lattice under `key`.
    #[inline(always)]
    fn holds(&self, key: u64, cell: [i64; 3]) -> bool {
        // One test of the xors, on registers: comparing the arrays as wholes reads the
        // coordinates back from the stack in one wide load, which stalls store forwarding.
        let differs = (self.key ^ key)
            | (self.cell[0] ^ cell[0]) as u64
            | (self.cell[1] ^ cell[1]) as u64
            | (self.cell[2] ^ cell[2]) as u64;
        self.filled && differs == 0
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

/// `n` points spread evenly through the 3 m cube whose lowest corner is `corner` (additive
/// recurrences with irrational steps), for the noise modules' tests.
#[cfg(test)]
fn spread_points(n: usize, corner: glam::DVec3) -> impl Iterator<Item = glam::DVec3> {
    (0..n).map(move |i| {
        let t = i as f64;
        corner
            + 3.0
                * glam::DVec3::new(
                    (t * 0.618_034).fract(),
                    (t * 0.414_214).fract(),
                    (t * 0.732_051).fract(),
                )
    })
}

/// Checks that a thread's memo of lattice cells changes no value: `value` at points of a fine
/// grid (where neighbours share cells, so the memo is used) is the same as at the same points
/// visited in a scrambled order (the next point a row and a column away: another cell along
/// some axes only), every third just after the same point under another seed (the same cells
/// under another key). A memo that ignored the key or any coordinate would answer wrongly.
#[cfg(test)]
fn memo_changes_nothing<T: PartialEq + std::fmt::Debug>(value: impl Fn(&Noise, glam::DVec3) -> T) {
    let (noise, other) = (Noise::new(21), Noise::new(22));
    let grid: Vec<glam::DVec3> = (0..60)
        .flat_map(|row| {
            (0..60).map(move |col| {
                glam::DVec3::new(
                    0.37 + 1e-3 * f64::from(col),
                    -2.1 + 7e-4 * f64::from(row),
                    0.5,
                )
            })
        })
        .collect();
    let in_order: Vec<T> = grid.iter().map(|&p| value(&noise, p)).collect();
    for k in 0..grid.len() {
        let i = (k * 1019) % grid.len();
        if k % 3 == 0 {
            let _ = value(&other, grid[i]);
        }
        assert_eq!(value(&noise, grid[i]), in_order[i], "at {}", grid[i]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_floor_like_f64_floor() {
        for x in [
            -2.5,
            -1.0,
            -1e-300,
            -0.0,
            0.0,
            0.3,
            1.0,
            7.999_999,
            1e15 + 0.5,
            -1e15 - 0.5,
        ] {
            let (i, f) = cell(x);
            assert_eq!(i as f64, x.floor(), "{x}");
            // A tiny negative x rounds up to the next cell's start: 1.0, continuous all the same.
            assert!((0.0..=1.0).contains(&f), "{x}: {f}");
        }
    }

    #[test]
    fn pair_hash_is_symmetric() {
        assert_eq!(pair(3, 9), pair(9, 3));
        assert_ne!(pair(3, 9), pair(3, 10));
        assert!((0..1000).all(|i| (0.0..1.0).contains(&unit(i, 5))));
    }

    #[test]
    fn corner_hashes_are_uniform_and_independent_between_neighbours() {
        // Four bits pick a lane's gradient (bits 12–15 for the first): over a block of lattice points each of the 16
        // values, and each of the 256 pairs of a point and its neighbour along every axis and
        // diagonal, must be about equally frequent (chi-square near its degrees of freedom).
        let key = Noise::new(5).keys[0];
        let hash = |x: i64, y: i64, z: i64| {
            let h = corner_hash(
                axis_word(x, 0, key),
                axis_word(y, 1, key),
                axis_word(z, 2, key),
            );
            (h >> 12) as usize & 15
        };
        let n = 40i64;
        let block =
            || (-n..n).flat_map(move |x| (-n..n).flat_map(move |y| (0..n).map(move |z| (x, y, z))));
        let chi2 = |counts: &[f64]| {
            let total: f64 = counts.iter().sum();
            let expected = total / counts.len() as f64;
            counts
                .iter()
                .map(|c| (c - expected).powi(2) / expected)
                .sum::<f64>()
        };
        let mut single = [0.0; 16];
        for (x, y, z) in block() {
            single[hash(x, y, z)] += 1.0;
        }
        assert!(chi2(&single) < 45.0, "{single:?}");
        for step in [
            (1, 0, 0),
            (0, 1, 0),
            (0, 0, 1),
            (1, 1, 0),
            (1, -1, 1),
            (2, 0, 0),
        ] {
            let mut joint = [0.0; 256];
            for (x, y, z) in block() {
                let other = hash(x + step.0, y + step.1, z + step.2);
                joint[16 * hash(x, y, z) + other] += 1.0;
            }
            // 255 degrees of freedom: the 99.9th percentile is about 330.
            assert!(chi2(&joint) < 330.0, "{step:?}: {}", chi2(&joint));
        }
    }
}
