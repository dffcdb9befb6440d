//! Fractal gradient noise: Perlin's improved noise (K. Perlin, "Improving Noise", ACM
//! Transactions on Graphics 21(3), SIGGRAPH 2002: the quintic fade 6t⁵ − 15t⁴ + 10t³, whose
//! first and second derivatives vanish at cell faces, and gradients towards the 12 edges of a
//! cube) on a hashed lattice, evaluated in lanes: one lattice cell (its corners, their hashes
//! and the fade) gives up to four independent noises, each from its own four bits of the
//! corner hashes. Arithmetic is f32 inside a cell (a position within a cell needs no more) and
//! f64 for finding the cell (texture coordinates reach 10⁵ cells).
//!
//! Fractal sums halve the wavelength and the amplitude octave by octave. A material's fields
//! share one octave ladder (`Ladder`, rungs 1.28 m halved again and again): the rungs a point
//! needs are each evaluated once, and every field of the material (steel mottle, rust patches,
//! their ragged edges, the rust tone…) reads its lane from them.
//!
//! Owns: gradient noise, fractal sums, the ladder. Must not touch: cellular noise, materials.

use super::lanes::{F4, U4};
use super::{MemoTag, Noise, axis_word, cell, corner_hash};
use glam::DVec3;
use std::cell::Cell;
use std::mem::MaybeUninit;

/// Noises one lattice evaluation gives (lanes of a group).
pub const LANES: usize = 4;
/// Lane groups of a ladder: lanes 0–3 and 4–7, each group its own lattice evaluation.
pub(super) const GROUPS: usize = 2;
/// Wavelength of the ladder's first rung, metres (at material scale 1).
const TOP: f64 = 1.28;
/// Rungs of the ladder: 1.28 m down to 0.04 mm.
const RUNGS: usize = 16;

/// 2/√3: the interpolated dot products of these gradients span (−√3/2, √3/2); scaled to
/// about [−1, 1], as the `noise` crate's Perlin was, so fractal statistics stay where the
/// materials' thresholds expect them.
const SCALE: f32 = 1.154_700_5;

/// Fractal sums divided by the sum of their octaves' amplitudes, times this: a standard
/// deviation near 0.35 (see `procedural::coverage_threshold`).
const FRACTAL_GAIN: f64 = 1.4;

/// Shift between the lattices of successive octaves (lattice units), so their lattice points,
/// where gradient noise vanishes, do not line up.
const OCTAVE_SHIFT: f64 = 17.31;

impl Noise {
    /// Gradient noise with features about `wavelength` metres apart, in [−1, 1].
    pub fn gradient(&self, p: DVec3, wavelength: f64) -> f64 {
        f64::from(
            self.lanes(
                p / wavelength,
                self.keys[0],
                free_slot(wavelength, u32::MAX),
            )[0],
        )
    }

    /// Fractal sum of `octaves` gradient noises, the first `wavelength` metres, each next one
    /// half the size and half the amplitude. Octaves shorter than four pixel footprints fade
    /// out, and are gone at two (the Nyquist limit). Normalised to roughly [−1, 1].
    pub fn fractal(&self, p: DVec3, wavelength: f64, octaves: u32, footprint: f64) -> f64 {
        self.fractals::<1>(p, wavelength, octaves, footprint)[0]
    }

    /// `N` (at most `LANES`) independent fractal sums at `p`, as `fractal`, for the price of
    /// little more than one.
    pub fn fractals<const N: usize>(
        &self,
        p: DVec3,
        wavelength: f64,
        octaves: u32,
        footprint: f64,
    ) -> [f64; N] {
        let mut sum = [0f32; N];
        for octave in Octaves::new(wavelength, octaves, footprint) {
            let slot = free_slot(octave.scale, octave.index);
            let values = self.octave(p, octave.scale, octave.index, self.keys[0], slot);
            for (s, v) in sum.iter_mut().zip(values) {
                *s += octave.weight * v;
            }
        }
        sum.map(|s| f64::from(s) * normaliser(octaves))
    }

    /// One octave's noises at `p`: lattice coordinates `p · scale`, shifted by the octave's
    /// `index` so that octaves do not share lattice points.
    #[inline(always)]
    fn octave(&self, p: DVec3, scale: f64, index: u32, key: u64, slot: usize) -> [f32; LANES] {
        let shift = OCTAVE_SHIFT * f64::from(index);
        self.lanes(p * scale + DVec3::splat(shift), key, slot)
    }

    /// Four independent gradient noises at lattice coordinates `q` under hash `key`, the
    /// cell's corner gradients memoised in `slot` of the thread's `CellMemo`.
    #[inline(always)]
    fn lanes(&self, q: DVec3, key: u64, slot: usize) -> [f32; LANES] {
        let (x, y, z) = (Axis::new(q.x), Axis::new(q.y), Axis::new(q.z));
        CELL_MEMO.with_borrow_mut(|memo| {
            let g = memo.gradients(slot, key, [x.cell, y.cell, z.cell]);
            let corner = |a: usize, b: usize, c: usize| {
                g[a + 2 * b + 4 * c].dot([x.offsets[a], y.offsets[b], z.offsets[c]])
            };
            let near = lerp(
                lerp(corner(0, 0, 0), corner(1, 0, 0), x.fade),
                lerp(corner(0, 1, 0), corner(1, 1, 0), x.fade),
                y.fade,
            );
            let far = lerp(
                lerp(corner(0, 0, 1), corner(1, 0, 1), x.fade),
                lerp(corner(0, 1, 1), corner(1, 1, 1), x.fade),
                y.fade,
            );
            lerp(near, far, z.fade).mul(F4::splat(SCALE)).to_array()
        })
    }
}

/// A lattice cell along one axis.
struct Axis {
    /// Integer coordinate of the cell's lower face.
    cell: i64,
    /// Offsets from the two faces (the position in the cell, and that less one), as lane bits.
    offsets: [U4; 2],
    /// The fade of the position in the cell, in every lane.
    fade: F4,
}

impl Axis {
    /// Along lattice coordinate `t`.
    #[inline(always)]
    fn new(t: f64) -> Axis {
        let (i, f) = cell(t);
        let f = f as f32;
        Axis {
            cell: i,
            offsets: [F4::splat(f).bits(), F4::splat(f - 1.0).bits()],
            fade: F4::splat(fade(f)),
        }
    }
}

/// Perlin's edge gradient of one lattice corner in every lane, kept as the sign flips and
/// masks that take its dot product with an offset without a multiplication. Lane k reads the
/// k-th 16-bit word of the corner's hash: bits 12–13 name the axis the gradient lacks (z, y,
/// x, and z again: Perlin's 12 edges, four of them twice), bits 14–15 the signs of its two ±1
/// components.
#[derive(Clone, Copy)]
struct Gradient {
    flip_x: U4,
    flip_y: U4,
    flip_z: U4,
    drop_x: U4,
    drop_y: U4,
    keep_z: U4,
}

impl Gradient {
    /// A placeholder for a memo slot not yet filled.
    const NONE: Gradient = Gradient {
        flip_x: U4::ZERO,
        flip_y: U4::ZERO,
        flip_z: U4::ZERO,
        drop_x: U4::ZERO,
        drop_y: U4::ZERO,
        keep_z: U4::ZERO,
    };

    /// The gradients of the corner whose hash is `h`.
    #[inline(always)]
    fn of(h: u64) -> Gradient {
        let w = U4::words(h);
        let missing = w.shr::<12>().and(U4::splat(3));
        let sign = U4::splat(0x8000_0000);
        let flip_x = w.shl::<17>().and(sign);
        let flip_y = w.shl::<16>().and(sign);
        let drop_x = missing.eq(U4::splat(2));
        let drop_y = missing.eq(U4::splat(1));
        Gradient {
            flip_x,
            flip_y,
            flip_z: flip_x.xor(flip_y),
            drop_x,
            drop_y,
            keep_z: drop_x.or(drop_y),
        }
    }

    /// Dot products with the offset `d` (lane bits of x, y, z) from the corner: a sum of the
    /// offsets with their sign bits flipped and one of them masked out.
    #[inline(always)]
    fn dot(&self, d: [U4; 3]) -> F4 {
        let x = F4::from_bits(d[0].xor(self.flip_x).and_not(self.drop_x));
        let y = F4::from_bits(d[1].xor(self.flip_y).and_not(self.drop_y));
        let z = F4::from_bits(d[2].xor(self.flip_z).and(self.keep_z));
        x.add(y).add(z)
    }
}

/// Slots of the thread's `CellMemo`: one per rung of each lane group of a ladder, then a few
/// shared by the fractal sums and single noises outside ladders.
const LADDER_SLOTS: usize = GROUPS * RUNGS;
const SLOTS: usize = LADDER_SLOTS + 16;

/// The slot of rung `index` of lane group `group`.
fn ladder_slot(group: usize, index: u32) -> usize {
    group * RUNGS + index as usize
}

/// A slot outside ladders for octave `index` of a lattice with `scale` cells per metre.
fn free_slot(scale: f64, index: u32) -> usize {
    let h = (scale.to_bits() ^ u64::from(index)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    LADDER_SLOTS + (h >> 60) as usize
}

/// The corner gradients of the lattice cell each slot last needed. Neighbouring pixels mostly
/// fall into the same cell of every octave coarser than a few pixels, and a cell's gradients
/// are a function of its integer coordinates and the lattice key alone: a slot holding the
/// cell asked for gives exactly the gradients hashing would. The memo saves time and changes
/// no value, whatever the order of points, threads or slots.
struct CellMemo {
    cells: [MemoCell; SLOTS],
}

#[derive(Clone, Copy)]
struct MemoCell {
    tag: MemoTag,
    /// Corner (a, b, c) ∈ {0, 1}³ at index a + 2b + 4c.
    gradients: [Gradient; 8],
}

impl MemoCell {
    const EMPTY: MemoCell = MemoCell {
        tag: MemoTag::EMPTY,
        gradients: [Gradient::NONE; 8],
    };
}

impl CellMemo {
    /// The corner gradients of lattice cell `cell` under `key`, from `slot` or hashed into it.
    #[inline(always)]
    fn gradients(&mut self, slot: usize, key: u64, cell: [i64; 3]) -> &[Gradient; 8] {
        let memo = &mut self.cells[slot];
        if !memo.tag.holds(key, cell) {
            let words: [[u64; 2]; 3] = std::array::from_fn(|k| {
                [axis_word(cell[k], k, key), axis_word(cell[k] + 1, k, key)]
            });
            memo.gradients = std::array::from_fn(|i| {
                let h = corner_hash(words[0][i & 1], words[1][(i >> 1) & 1], words[2][i >> 2]);
                Gradient::of(h)
            });
            memo.tag = MemoTag {
                key,
                cell,
                filled: true,
            };
        }
        &memo.gradients
    }
}

thread_local! {
    static CELL_MEMO: std::cell::RefCell<CellMemo> = const {
        std::cell::RefCell::new(CellMemo {
            cells: [MemoCell::EMPTY; SLOTS],
        })
    };
}

/// Perlin's quintic fade 6t⁵ − 15t⁴ + 10t³ (Horner form).
#[inline(always)]
fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline(always)]
fn lerp(a: F4, b: F4, t: F4) -> F4 {
    a.add(b.sub(a).mul(t))
}

/// What a sum of `octaves` octaves is multiplied by: the inverse of their amplitudes' sum
/// 2 (1 − 2^−octaves), times the gain. Octaves filtered out take their variance with them.
fn normaliser(octaves: u32) -> f64 {
    NORMALISERS[octaves.min(63) as usize]
}

/// `normaliser` for 0–63 octaves, divided out when compiling rather than at every point.
const NORMALISERS: [f64; 64] = {
    let mut table = [0.0; 64];
    let mut octaves = 0;
    while octaves < 64 {
        let tail = 1.0 / (1u64 << octaves) as f64;
        table[octaves] = FRACTAL_GAIN / (2.0 * (1.0 - tail));
        octaves += 1;
    }
    table
};

/// One octave of a fractal sum.
struct Octave {
    /// Counted from the ladder's top (ladder fields) or the sum's first octave.
    index: u32,
    /// Lattice cells per metre.
    scale: f64,
    /// Amplitude times the fade below the pixel footprint.
    weight: f32,
}

/// The octaves of a fractal sum that are visible at a footprint: amplitudes halving from 1,
/// each faded from full weight at four footprints per wavelength to none at two.
struct Octaves {
    next: Octave,
    end: u32,
    /// Half the next octave's wavelength over the pixel footprint, 0.5 / (scale · footprint):
    /// halved from octave to octave, which gives the same bits as dividing anew (a power of
    /// two scales a correctly rounded quotient exactly), without a division per octave.
    resolved: f64,
}

impl Octaves {
    fn new(wavelength: f64, octaves: u32, footprint: f64) -> Self {
        Self::from_index(
            0,
            1.0 / wavelength,
            octaves,
            resolution(1.0 / wavelength, footprint),
        )
    }

    /// Octaves numbered from `index`, the first with `scale` lattice cells per metre and
    /// `resolved` = [`resolution`]`(scale, footprint)`.
    fn from_index(index: u32, scale: f64, octaves: u32, resolved: f64) -> Self {
        Octaves {
            next: Octave {
                index,
                scale,
                weight: 1.0,
            },
            end: index + octaves,
            resolved,
        }
    }
}

/// Half the wavelength of a lattice with `scale` cells per metre, in pixel footprints.
fn resolution(scale: f64, footprint: f64) -> f64 {
    0.5 / (scale * footprint)
}

impl Iterator for Octaves {
    type Item = Octave;

    fn next(&mut self) -> Option<Octave> {
        let o = &mut self.next;
        // Wavelength over twice the footprint, less one: 1 at four footprints, 0 at two.
        let fade = (self.resolved - 1.0).clamp(0.0, 1.0);
        if o.index >= self.end || fade == 0.0 {
            return None;
        }
        let out = Octave {
            index: o.index,
            scale: o.scale,
            weight: o.weight * fade as f32,
        };
        o.index += 1;
        o.scale *= 2.0;
        o.weight *= 0.5;
        self.resolved *= 0.5;
        Some(out)
    }
}

/// A fractal field of a material, read from the ladder: `octaves` octaves of one lane, the
/// first on the rung of its wavelength.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    lane: u8,
    first: u8,
    octaves: u8,
}

impl Field {
    /// Lane `lane` (0–7; fields of different lanes are independent, fields of one lane share
    /// their common octaves), from `wavelength` metres down over `octaves` octaves.
    /// `wavelength` must be a rung, 1.28 m halved a whole number of times: a constant that is
    /// not fails to compile.
    pub const fn new(lane: u8, wavelength: f64, octaves: u8) -> Field {
        assert!((lane as usize) < LANES * GROUPS, "8 lanes");
        let mut first = 0;
        let mut rung = TOP;
        while rung > wavelength && first < RUNGS {
            rung /= 2.0;
            first += 1;
        }
        assert!(
            rung == wavelength,
            "the wavelength is not a rung of the ladder"
        );
        assert!(
            first + octaves as usize <= RUNGS,
            "beyond the ladder's last rung"
        );
        Field {
            lane,
            first: first as u8,
            octaves,
        }
    }
}

/// The rungs of the octave ladder at one point of a surface, each evaluated (for all four lanes
/// of its group) when a field first needs it.
pub struct Ladder<'a> {
    noise: &'a Noise,
    p: DVec3,
    /// [`resolution`] of the top rung at the point's footprint (lower rungs: halved).
    resolved_top: f64,
    /// Per lane group, a bit for every rung evaluated.
    done: [Cell<u32>; GROUPS],
    /// The rungs evaluated so far (the others are never read: a ladder is made for every
    /// shaded point, and filling 512 bytes it mostly does not use cost more than reading them).
    rungs: [[Cell<MaybeUninit<[f32; LANES]>>; RUNGS]; GROUPS],
}

impl<'a> Ladder<'a> {
    /// The ladder of `noise` at `p` (metres), seen with pixels `footprint` metres wide.
    pub fn new(noise: &'a Noise, p: DVec3, footprint: f64) -> Self {
        Ladder {
            noise,
            p,
            resolved_top: resolution(rung_scale(0), footprint),
            done: [const { Cell::new(0) }; GROUPS],
            rungs: [const { [const { Cell::new(MaybeUninit::uninit()) }; RUNGS] }; GROUPS],
        }
    }

    /// The field's value here, normalised as `Noise::fractal`.
    pub fn get(&self, field: Field) -> f64 {
        let (group, lane) = (field.lane as usize / LANES, field.lane as usize % LANES);
        let first = u32::from(field.first);
        let octaves = u32::from(field.octaves);
        let scale = rung_scale(first);
        // 2^−first: the top rung's resolution halved `first` times, exactly.
        let resolved = self.resolved_top * f64::from_bits((1023 - u64::from(first)) << 52);
        let mut sum = 0f32;
        for octave in Octaves::from_index(first, scale, octaves, resolved) {
            sum += octave.weight * self.rung(group, octave.index, octave.scale)[lane];
        }
        f64::from(sum) * normaliser(octaves)
    }

    /// The four noises of a group at rung `index` (lattice `scale` cells per metre).
    fn rung(&self, group: usize, index: u32, scale: f64) -> [f32; LANES] {
        let bit = 1 << index;
        let cell = &self.rungs[group][index as usize];
        if self.done[group].get() & bit == 0 {
            let key = self.noise.keys[group];
            let slot = ladder_slot(group, index);
            cell.set(MaybeUninit::new(
                self.noise.octave(self.p, scale, index, key, slot),
            ));
            self.done[group].set(self.done[group].get() | bit);
        }
        // SAFETY: the rung's bit in `done` is set only once the rung has been written.
        unsafe { cell.get().assume_init() }
    }
}

/// Lattice cells per metre of rung `index`: 2^index / 1.28.
fn rung_scale(index: u32) -> f64 {
    (1u64 << index) as f64 / TOP
}

#[cfg(test)]
mod tests {
    use super::super::spread_points;
    use super::*;

    /// Perlin's noise at lattice coordinates `q` from its definition, in f64: each corner's
    /// gradient read from its hash (lane `lane`'s 16-bit word: bits 12–13 the axis it lacks,
    /// bits 14 and 15 the signs of x and y, z's sign their product), dotted with the offset
    /// from the corner, interpolated with the quintic fade, scaled by 2/√3.
    fn perlin(q: DVec3, key: u64, lane: usize) -> f64 {
        let base = q.floor();
        let f = q - base;
        let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let mut sum = 0.0;
        for corner in 0..8usize {
            let c = [corner & 1, (corner >> 1) & 1, corner >> 2];
            let words: [u64; 3] =
                std::array::from_fn(|k| axis_word(base[k] as i64 + c[k] as i64, k, key));
            let w = (corner_hash(words[0], words[1], words[2]) >> (16 * lane)) & 0xffff;
            let sign = |bit: u64| if w >> bit & 1 == 1 { -1.0 } else { 1.0 };
            let (sx, sy) = (sign(14), sign(15));
            let g = match (w >> 12) & 3 {
                2 => DVec3::new(0.0, sy, sx * sy),
                1 => DVec3::new(sx, 0.0, sx * sy),
                _ => DVec3::new(sx, sy, 0.0),
            };
            let offset = f - DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64);
            let weight: f64 = (0..3)
                .map(|k| {
                    if c[k] == 1 {
                        fade(f[k])
                    } else {
                        1.0 - fade(f[k])
                    }
                })
                .product();
            sum += weight * g.dot(offset);
        }
        sum * 2.0 / 3f64.sqrt()
    }

    #[test]
    fn lanes_are_perlin_noise_by_its_definition() {
        let n = Noise::new(13);
        for q in spread_points(3000, DVec3::new(-1.7, 40.2, -3.3)) {
            let q = q * 3.0;
            let lanes = n.lanes(q, n.keys[1], 0);
            for (lane, got) in lanes.iter().enumerate() {
                let want = perlin(q, n.keys[1], lane);
                assert!(
                    (f64::from(*got) - want).abs() < 2e-6,
                    "{q} lane {lane}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn the_cell_memo_changes_no_value() {
        super::super::memo_changes_nothing(|n, p| n.fractals::<4>(p, 0.02, 4, 1e-5));
        super::super::memo_changes_nothing(|n, p| {
            let ladder = Ladder::new(n, p, 2e-4);
            [Field::new(2, 0.32, 6), Field::new(5, 0.01, 3)].map(|f| ladder.get(f))
        });
    }

    #[test]
    fn same_seed_same_values_other_seed_other_values() {
        let (a, b, c) = (Noise::new(7), Noise::new(7), Noise::new(8));
        let p = DVec3::new(0.31, 1.7, -2.2);
        assert_eq!(a.fractal(p, 0.2, 5, 1e-4), b.fractal(p, 0.2, 5, 1e-4));
        assert_ne!(a.fractal(p, 0.2, 5, 1e-4), c.fractal(p, 0.2, 5, 1e-4));
        let lanes = a.fractals::<4>(p, 0.2, 5, 1e-4);
        assert_eq!(lanes[0], a.fractal(p, 0.2, 5, 1e-4), "lane 0 is `fractal`");
        assert!(lanes.iter().zip(&lanes[1..]).all(|(x, y)| x != y));
    }

    #[test]
    fn fractal_noise_is_continuous_bounded_and_filtered() {
        let n = Noise::new(3);
        for p in spread_points(2000, DVec3::ZERO) {
            let v = n.fractal(p, 0.3, 6, 1e-4);
            assert!(v.is_finite() && v.abs() <= 1.5, "{v}");
            let nearby = n.fractal(p + DVec3::splat(1e-7), 0.3, 6, 1e-4);
            assert!((v - nearby).abs() < 1e-3);
        }
        // A footprint larger than twice the first wavelength leaves nothing to see.
        assert_eq!(n.fractal(DVec3::new(0.1, 0.2, 0.3), 0.3, 6, 0.7), 0.0);
    }

    #[test]
    fn ladder_fields_are_fractal_sums_of_their_rungs() {
        let n = Noise::new(9);
        for p in spread_points(200, DVec3::ZERO) {
            let ladder = Ladder::new(&n, p, 1e-3);
            // Lane 0 of group 0 on rungs 2… is `fractal` with the octaves counted from rung 2.
            let field = Field::new(0, 0.32, 5);
            let mut direct = 0f32;
            for o in Octaves::from_index(2, rung_scale(2), 5, resolution(rung_scale(2), 1e-3)) {
                direct += o.weight * n.octave(p, o.scale, o.index, n.keys[0], 0)[0];
            }
            assert_eq!(ladder.get(field), f64::from(direct) * normaliser(5));
            // Asking again reads the same rungs.
            assert_eq!(ladder.get(field), ladder.get(field));
            assert_ne!(ladder.get(field), ladder.get(Field::new(4, 0.32, 5)));
        }
    }
}
