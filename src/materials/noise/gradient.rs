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
//! their ragged edges, the rust tone…) reads its lane from them. Up to four neighbouring
//! pixels of a row share one `SpanLadder`, whose lanes run across the points instead: a rung
//! then costs only the lanes the material reads, and gives each point the bits its own
//! `Ladder` would.
//!
//! Owns: gradient noise, fractal sums, the ladders. Must not touch: cellular noise, materials.

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
        let [(cx, fx), (cy, fy), (cz, fz)] = [q.x, q.y, q.z].map(cell);
        let axes = [fx, fy, fz].map(|f| Axis::new(F4::splat(f as f32)));
        CELL_MEMO.with_borrow_mut(|memo| {
            let memo = memo.cell(slot, key, [cx, cy, cz]);
            interpolate(&memo.gradients, &axes).to_array()
        })
    }

    /// The lattice cells of rung `index` of lane group `group` (lattice `scale` cells per
    /// metre) around each of four points: what `octave` finds at each point before it
    /// interpolates (the same IEEE operations on the same operands).
    fn cells_across(
        &self,
        points: &[DVec3; LANES],
        (scale, index): (f64, u32),
        group: usize,
        out: &mut MaybeUninit<CellsAcross>,
    ) {
        let shift = OCTAVE_SHIFT * f64::from(index);
        let key = self.keys[group];
        let slot = ladder_slot(group, index);
        let mut offsets = [[0f32; LANES]; 3];
        let out = out.as_mut_ptr();
        // SAFETY: a place in `out`, written below before anything reads it.
        let hashes = unsafe { &raw mut (*out).hashes }.cast::<u64>();
        CELL_MEMO.with_borrow_mut(|memo| {
            for (k, p) in points.iter().enumerate() {
                let q = *p * scale + DVec3::splat(shift);
                let [(cx, fx), (cy, fy), (cz, fz)] = [q.x, q.y, q.z].map(cell);
                for (axis, f) in offsets.iter_mut().zip([fx, fy, fz]) {
                    axis[k] = f as f32;
                }
                let memo = memo.cell(slot, key, [cx, cy, cz]);
                for (corner, &h) in memo.hashes.iter().enumerate() {
                    // SAFETY: corner < 8 and k < LANES index within `hashes`, [[u64; LANES]; 8].
                    unsafe { hashes.add(corner * LANES + k).write(h) };
                }
            }
        });
        let axes = offsets.map(|f| Axis::new(F4::from_array(f)));
        // SAFETY: as above; with the hashes written, every field of `out` is.
        unsafe { (&raw mut (*out).axes).write(axes) };
    }
}

/// The lattice cells of one rung around four points, lanes across the points.
struct CellsAcross {
    /// The points' positions in their cells along x, y and z.
    axes: [Axis; 3],
    /// The hash of each corner of each point's cell, corner by corner.
    hashes: [[u64; LANES]; 8],
}

impl CellsAcross {
    /// Lane `lane` of the rung's noises at each of the points: the value `octave` gives that
    /// lane at each point, to the bit.
    #[inline(always)]
    fn lane(&self, lane: usize) -> [f32; LANES] {
        let shift = 16 * lane;
        let mut gradients = [Gradient::NONE; 8];
        for (g, h) in gradients.iter_mut().zip(&self.hashes) {
            let words = [0, 1, 2, 3].map(|k| (h[k] >> shift) as u32 & 0xffff);
            *g = Gradient::of_words(U4::from_array(words));
        }
        interpolate(&gradients, &self.axes).to_array()
    }
}

/// Gradient noise in four lanes from the corner gradients of a cell and the position in it
/// along each axis: the dot products interpolated with the fade, scaled by `SCALE`.
#[inline(always)]
fn interpolate(g: &[Gradient; 8], [x, y, z]: &[Axis; 3]) -> F4 {
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
    lerp(near, far, z.fade).mul(F4::splat(SCALE))
}

/// The position in a lattice cell along one axis, in every lane.
struct Axis {
    /// Offsets from the cell's two faces (the position in the cell, and that less one), as
    /// lane bits.
    offsets: [U4; 2],
    /// The fade of the position in the cell.
    fade: F4,
}

impl Axis {
    /// At position `f` in the cell (in [0, 1]).
    #[inline(always)]
    fn new(f: F4) -> Axis {
        Axis {
            offsets: [f.bits(), f.sub(F4::splat(1.0)).bits()],
            fade: fade(f),
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
        Self::of_words(U4::words(h))
    }

    /// The gradients whose 16-bit hash words are the lanes of `w`.
    #[inline(always)]
    fn of_words(w: U4) -> Gradient {
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
    /// The hash of corner (a, b, c) ∈ {0, 1}³ at index a + 2b + 4c.
    hashes: [u64; 8],
    /// The gradients those hashes give, corner by corner.
    gradients: [Gradient; 8],
}

impl MemoCell {
    const EMPTY: MemoCell = MemoCell {
        tag: MemoTag::EMPTY,
        hashes: [0; 8],
        gradients: [Gradient::NONE; 8],
    };
}

impl CellMemo {
    /// The corner hashes and gradients of lattice cell `cell` under `key`, from `slot` or
    /// hashed into it.
    #[inline(always)]
    fn cell(&mut self, slot: usize, key: u64, cell: [i64; 3]) -> &MemoCell {
        let memo = &mut self.cells[slot];
        if !memo.tag.holds(key, cell) {
            let words: [[u64; 2]; 3] = std::array::from_fn(|k| {
                [axis_word(cell[k], k, key), axis_word(cell[k] + 1, k, key)]
            });
            memo.hashes = std::array::from_fn(|i| {
                corner_hash(words[0][i & 1], words[1][(i >> 1) & 1], words[2][i >> 2])
            });
            memo.gradients = memo.hashes.map(Gradient::of);
            memo.tag = MemoTag {
                key,
                cell,
                filled: true,
            };
        }
        memo
    }
}

thread_local! {
    static CELL_MEMO: std::cell::RefCell<CellMemo> = const {
        std::cell::RefCell::new(CellMemo {
            cells: [MemoCell::EMPTY; SLOTS],
        })
    };
}

/// Perlin's quintic fade 6t⁵ − 15t⁴ + 10t³ (Horner form), lane by lane.
#[inline(always)]
fn fade(t: F4) -> F4 {
    let inner = t.mul(F4::splat(6.0)).sub(F4::splat(15.0));
    t.mul(t).mul(t).mul(t.mul(inner).add(F4::splat(10.0)))
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

    /// A word that tells fields apart, never 0.
    fn key(self) -> u32 {
        1 << 24 | u32::from(self.lane) << 16 | u32::from(self.first) << 8 | u32::from(self.octaves)
    }

    /// The field's lane group, and its lane in the group.
    fn group_and_lane(self) -> (usize, usize) {
        (self.lane as usize / LANES, self.lane as usize % LANES)
    }

    /// The field's octaves summed and normalised as `Noise::fractal`, at a point whose top
    /// rung has [`resolution`] `resolved_top`, reading the lane at rung `index` (lattice
    /// `scale` cells per metre) through `rung`.
    #[inline(always)]
    fn sum(self, resolved_top: f64, mut rung: impl FnMut(u32, f64) -> f32) -> f64 {
        let first = u32::from(self.first);
        let octaves = u32::from(self.octaves);
        let scale = rung_scale(first);
        // 2^−first: the top rung's resolution halved `first` times, exactly.
        let resolved = resolved_top * f64::from_bits((1023 - u64::from(first)) << 52);
        let mut sum = 0f32;
        for octave in Octaves::from_index(first, scale, octaves, resolved) {
            sum += octave.weight * rung(octave.index, octave.scale);
        }
        f64::from(sum) * normaliser(octaves)
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
        let (group, lane) = field.group_and_lane();
        field.sum(self.resolved_top, |index, scale| {
            self.rung(group, index, scale)[lane]
        })
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

/// The octave ladders of up to four points of one material seen side by side (neighbouring
/// pixels of a row), evaluated together: the lattice cells of a rung are found once for the
/// four points (`Noise::cells_across`), and each lane a field reads is then interpolated at
/// all four points at once, where a point's own `Ladder` interpolates all four lanes of the
/// rung at that point. Materials mostly read one or two of a rung's four lanes, so this does
/// less of the lattice work, and shares the rest between the points. Every value is the bit
/// its point's own `Ladder` gives.
pub struct SpanLadder<'a> {
    noise: &'a Noise,
    /// The points (metres); a span of fewer than four repeats its last point in the rest.
    points: [DVec3; LANES],
    /// [`resolution`] of the top rung at each point's footprint.
    resolved_top: [f64; LANES],
    /// Per lane group, a bit for every rung whose cells are found.
    found: [Cell<u16>; GROUPS],
    /// Per lane group, the cells of every rung (only those marked in `found` are written;
    /// see `Ladder::rungs`).
    cells: [[Cell<MaybeUninit<CellsAcross>>; RUNGS]; GROUPS],
    /// Per lane group and lane, a bit for every rung evaluated.
    done: [[Cell<u16>; LANES]; GROUPS],
    /// Per lane group, lane and rung, the values at the points (only those marked in `done`
    /// are written).
    rungs: [[[SpanValues; RUNGS]; LANES]; GROUPS],
    /// The `Field::key`s of the fields summed so far, in the order first asked for; 0 after
    /// the last.
    field_keys: [Cell<u32>; SPAN_FIELDS],
    /// Their values at every point (only those with a key are written).
    field_values: [Cell<MaybeUninit<[f64; LANES]>>; SPAN_FIELDS],
}

/// One lane of one rung at the points of a span, once evaluated.
type SpanValues = Cell<MaybeUninit<[f32; LANES]>>;

/// Fields a span keeps (a material reads at most a dozen; more are summed again when asked).
const SPAN_FIELDS: usize = 16;

impl<'a> SpanLadder<'a> {
    /// The ladders of `noise` at `points` (metres, one to four), seen with pixels
    /// `footprints` metres wide.
    pub fn new(noise: &'a Noise, points: &[DVec3], footprints: &[f64]) -> Self {
        assert!(
            (1..=LANES).contains(&points.len()) && points.len() == footprints.len(),
            "a span of one to four points, each with its footprint"
        );
        let last = points.len() - 1;
        SpanLadder {
            noise,
            points: std::array::from_fn(|k| points[k.min(last)]),
            resolved_top: std::array::from_fn(|k| {
                resolution(rung_scale(0), footprints[k.min(last)])
            }),
            found: [const { Cell::new(0) }; GROUPS],
            cells: [const { [const { Cell::new(MaybeUninit::uninit()) }; RUNGS] }; GROUPS],
            done: [const { [const { Cell::new(0) }; LANES] }; GROUPS],
            rungs: [const { [const { [const { Cell::new(MaybeUninit::uninit()) }; RUNGS] }; LANES] };
                GROUPS],
            field_keys: [const { Cell::new(0) }; SPAN_FIELDS],
            field_values: [const { Cell::new(MaybeUninit::uninit()) }; SPAN_FIELDS],
        }
    }

    /// The field's value at point `k`, normalised as `Noise::fractal`: what
    /// `Ladder::get` gives at that point. The points of a span read the same fields (one
    /// material), so the first to ask for a field sums it at every point.
    pub fn get(&self, k: usize, field: Field) -> f64 {
        let key = field.key();
        for (slot, values) in self.field_keys.iter().zip(&self.field_values) {
            let held = slot.get();
            if held == key {
                // SAFETY: a slot's key is set only once its values are written.
                return unsafe { (*values.as_ptr()).assume_init_ref()[k] };
            }
            if held == 0 {
                let sums = self.sums(field);
                values.set(MaybeUninit::new(sums));
                slot.set(key);
                return sums[k];
            }
        }
        self.sums(field)[k]
    }

    /// The field at every point: `Field::sum` at each, the rungs read once for all. A point
    /// whose octaves have faded out by a rung others still read adds nothing from it
    /// (0 · v is a zero, and adding a zero leaves a sum that is never −0 unchanged), and
    /// a fade is 0 from the first octave it is 0 on, where `Octaves` stops.
    fn sums(&self, field: Field) -> [f64; LANES] {
        let (group, lane) = field.group_and_lane();
        let first = u32::from(field.first);
        let octaves = u32::from(field.octaves);
        let mut scale = rung_scale(first);
        // 2^−first: the top rung's resolution halved `first` times, exactly.
        let halvings = f64::from_bits((1023 - u64::from(first)) << 52);
        let mut resolved = self.resolved_top.map(|r| r * halvings);
        let mut weight = 1f32;
        let mut sum = [0f32; LANES];
        for index in first..first + octaves {
            let fades = resolved.map(|r| (r - 1.0).clamp(0.0, 1.0));
            if fades.iter().all(|&f| f == 0.0) {
                break;
            }
            let values = self.rung(group, lane, index, scale);
            for k in 0..LANES {
                sum[k] += weight * fades[k] as f32 * values[k];
            }
            scale *= 2.0;
            weight *= 0.5;
            resolved = resolved.map(|r| r * 0.5);
        }
        sum.map(|s| f64::from(s) * normaliser(octaves))
    }

    /// Lane `lane` of group `group` at rung `index` (lattice `scale` cells per metre), at
    /// every point.
    fn rung(&self, group: usize, lane: usize, index: u32, scale: f64) -> [f32; LANES] {
        let bit = 1 << index;
        let done = &self.done[group][lane];
        let value = &self.rungs[group][lane][index as usize];
        if done.get() & bit == 0 {
            let found = &self.found[group];
            let cells = self.cells[group][index as usize].as_ptr();
            if found.get() & bit == 0 {
                // SAFETY: `cells` points into `self`, borrowed by no one else (these `Cell`s
                // are read and written here only, through this pointer).
                let out = unsafe { &mut *cells };
                self.noise
                    .cells_across(&self.points, (scale, index), group, out);
                found.set(found.get() | bit);
            }
            // SAFETY: the rung's bit in `found` is set only once its cells are written.
            let values = unsafe { (*cells).assume_init_ref() }.lane(lane);
            value.set(MaybeUninit::new(values));
            done.set(done.get() | bit);
        }
        // SAFETY: the rung's bit in `done` is set only once the rung has been written.
        unsafe { value.get().assume_init() }
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
    fn span_ladders_give_each_points_own_ladder_bits() {
        // Spans of one to four points: neighbours 1 mm apart (mostly in one cell of the
        // coarse rungs, in different cells of the fine ones) and scattered points, with
        // footprints from 10 µm to 4 cm (every octave shown, to most faded out, and faded at
        // different rungs at different points of one span), over every lane of both groups.
        let n = Noise::new(17);
        let fields: Vec<Field> = (0..8u8)
            .flat_map(|lane| {
                [
                    Field::new(lane, 1.28, 16),
                    Field::new(lane, 0.32, 4),
                    Field::new(lane, 0.02, 3),
                ]
            })
            .collect();
        let scattered: Vec<DVec3> = spread_points(40, DVec3::new(-3.0, 2.0, 0.5)).collect();
        for (i, start) in spread_points(120, DVec3::ZERO).enumerate() {
            let len = 1 + i % 4;
            let footprints: Vec<f64> = (0..len)
                .map(|k| 1e-5 * 2f64.powi((i % 12) as i32) * (1.0 + 0.7 * k as f64))
                .collect();
            let row: Vec<DVec3> = (0..len)
                .map(|k| start + DVec3::new(1e-3 * k as f64, 0.0, 0.0))
                .collect();
            let chunk = i % 9 * 4;
            for points in [&row[..], &scattered[chunk..chunk + len]] {
                let span = SpanLadder::new(&n, points, &footprints);
                // In an order that differs from point to point, so each reads rungs and
                // fields that another point of the span evaluated first, or not.
                for (k, (&p, &footprint)) in points.iter().zip(&footprints).enumerate() {
                    let own = Ladder::new(&n, p, footprint);
                    for j in 0..fields.len() {
                        let field = fields[(j * 7 + k * 5) % fields.len()];
                        assert_eq!(
                            span.get(k, field).to_bits(),
                            own.get(field).to_bits(),
                            "{field:?} at {p} ({footprint} m)"
                        );
                    }
                }
            }
        }
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
