//! The lighting cache of one sample's mesh: what a surface point sees of the sun's disk and of
//! its hemisphere (`daylight::Openness`), traced only at the corners of a lattice laid on each
//! plane of the mesh, refined where a cell's corners disagree (shadow edges, penumbrae,
//! contacts), and read between corners bilinearly. Built lazily by the sample's views, shared
//! by all of them (and by their threads), dropped with the sample.
//!
//! Owns: the lattice (levels, cells, corners), the refinement test, the bilinear lookup and the
//! concurrent store of corner values. Must not touch: colours, materials or images; the corner
//! values come from `daylight::LightRays`. Every corner's value is a function of its key alone
//! (its plane, level and lattice position; the ray patterns are turned by an angle hashed from
//! the key), and which cell a lookup ends in is a function of the point and the pixel's
//! footprint, so what a view reads does not depend on which view or thread traced a corner
//! first: the bytes are the same on any thread count, shard or resume. See docs/daylight.md,
//! "The lighting cache".

use super::daylight::{DiskPattern, LightRays, Openness, hashed_turn, least_rise_facing_up};
use super::trace::TraceMesh;
use crate::materials::Lighting;
use glam::DVec3;
use std::cell::RefCell;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// How finely the cache samples the light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CacheSettings {
    /// Largest difference in any share (sun, sky above, ground below, all) between a cell's
    /// corners for the cell to be read by interpolation rather than split in four.
    pub tolerance: f64,
    /// Side of the coarsest cells (metres) where pixels are small: a shadow or contact
    /// narrower than this can hide between four corners that agree.
    pub coarsest: f64,
    /// Side of the finest cells of the sun's lattice, in pixels of the view looking up:
    /// splitting stops there.
    pub finest_pixels: f64,
    /// The same for the sky's lattice (occlusion changes more gently than a shadow's edge).
    pub sky_finest_pixels: f64,

    /// Shadow rays per corner, as a multiple of the recipe's per-pixel count.
    pub sun_ray_factor: u32,
    /// Hemisphere rays per corner, as a multiple of the recipe's per-pixel count: every
    /// corner of a plane casts the same directions, so each ray's fate draws its own sharp
    /// outline across the plane, and the share steps by one over the ray count there; more
    /// rays make the steps too small to see.
    pub sky_ray_factor: u32,
}

impl Default for CacheSettings {
    /// The default sits at the knee of outdoor.rhai's error against the per-pixel reference
    /// and its time: finer doubles the time, coarser doubles the error (docs/daylight.md,
    /// "Speed against error").
    fn default() -> Self {
        CacheSettings {
            tolerance: 0.1,
            coarsest: 0.25,
            finest_pixels: 2.0,
            sky_finest_pixels: 2.0,
            sun_ray_factor: 1,
            sky_ray_factor: 2,
        }
    }
}

impl CacheSettings {
    /// For previews (`watch`, contact sheets), whose small images are looked at, not measured:
    /// the coarsest row of the speed–error table (docs/daylight.md), twice the tolerance,
    /// cells twice as coarse at both ends, the sky's rays the per-pixel count. On outdoor.rhai
    /// (480²) its worst view is RMS 1.33 and p99 3 levels off the per-pixel reference, the
    /// default's 1.13 and 3.
    pub const PREVIEW: CacheSettings = CacheSettings {
        tolerance: 0.2,
        coarsest: 0.5,
        finest_pixels: 4.0,
        sky_finest_pixels: 4.0,
        sun_ray_factor: 1,
        sky_ray_factor: 1,
    };
}

/// A coarse cell spans at least this many pixels, so its four corners serve many pixels even
/// far from the camera (the ground towards the horizon).
const COARSE_CELL_PIXELS: f64 = 8.0;

/// Steps of the quantised plane of a corner key (2⁻²⁰ ≈ 10⁻⁶ of a unit normal, or of a metre):
/// the triangles of one flat face fall on one plane, and share its corners.
const PLANE_STEPS: f64 = (1u64 << 20) as f64;

/// How far a corner is lifted off its plane, in cells (see `Corner::point`).
const CORNER_LIFT: f64 = 1.0 / 64.0;

/// The coarsest level a corner of a finer level is named at when it is a lattice point there
/// too (`Corner::canonical`): that of the default's coarsest cells (¼ m), so a corner is never
/// lifted more than 1/64 of those (4 mm) however far its lattice point reaches up the levels.
const SHARED_LEVEL: i32 = 2;

/// Stores the corner values in this many independently locked maps, so threads rarely wait.
const SHARDS: usize = 16;

/// The corner values of one mesh under one lighting, filled as views look them up.
pub struct LightCache {
    settings: CacheSettings,
    sun_disk: DiskPattern,
    hemisphere: DiskPattern,
    /// `least_rise_facing_up` of the corners' rays (see `open_up_to_sky`).
    least_rise_up: Option<f64>,
    shards: Box<[Mutex<CornerMap>]>,
    /// Tells this cache's entries in a thread's `LAST_LEAVES` from another's.
    serial: u64,
}

type CornerMap = HashMap<Hashed, Record, BuildHasherDefault<MixedKeyHasher>>;

/// What a corner holds: its `Shares`, then `VALID`, or `INVALID` for a corner that looks
/// enclosed (`LightRays::enclosed`), whose shares are not the light of any visible point.
type Record = [f64; 4];
const VALID: f64 = 1.0;
const INVALID: f64 = 0.0;

/// The shares a corner holds: the sun's (then two unused zeros), or the sky's above, below
/// and all round.
type Shares = [f64; 3];

/// The terms cached, each on its own lattice.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Term {
    Sun = 0,
    Sky = 1,
}

static NEXT_SERIAL: AtomicU64 = AtomicU64::new(0);

impl LightCache {
    /// An empty cache for the light `lighting` (its ray counts times `settings.ray_factor`).
    pub fn new(lighting: &Lighting, settings: CacheSettings) -> Self {
        let rays = |n: u32, factor: u32| DiskPattern::new(n.saturating_mul(factor.max(1)));
        let shadow_rays = lighting.sun.map_or(0, |s| s.shadow_rays);
        let occlusion_rays = match &lighting.environment {
            Some(e) => e.occlusion_rays,
            None => lighting.sky.map_or(0, |s| s.occlusion_rays),
        };
        let sun_disk = rays(shadow_rays, settings.sun_ray_factor);
        let hemisphere = rays(occlusion_rays, settings.sky_ray_factor);
        let least_rise_up = least_rise_facing_up(lighting, &sun_disk, &hemisphere);
        LightCache {
            settings,
            sun_disk,
            hemisphere,
            least_rise_up,
            shards: (0..SHARDS).map(|_| Mutex::default()).collect(),
            serial: NEXT_SERIAL.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// Corners traced so far.
    pub fn corners(&self) -> usize {
        self.shards.iter().map(|s| lock(s).len()).sum()
    }

    /// What point `p` with facing `n`, seen with pixels `footprint` metres wide, sees of the
    /// lights: the sun's share and the sky's, each read from its own lattice (a shadow's edge
    /// splits the sun's cells, not the sky's).
    pub(super) fn openness(
        &self,
        mesh: &TraceMesh,
        lighting: &Lighting,
        p: DVec3,
        n: DVec3,
        footprint: f64,
    ) -> Openness {
        let rays = self.rays(mesh, lighting);
        if n == DVec3::Z && self.open_up_to_sky(mesh, p) {
            return Openness::OPEN;
        }
        let mut open = Openness::OPEN;
        let plane = PlaneKey::of(p, n);
        let at = plane.in_plane(p);
        let seen = (p, n);
        if rays.traces_sun(n) {
            let levels = self.levels(footprint, self.settings.finest_pixels);
            open.sun = self.lookup(&rays, Term::Sun, (plane, levels, at), seen)[0];
        }
        if rays.traces_sky() {
            let levels = self.levels(footprint, self.settings.sky_finest_pixels);
            [open.up, open.down, open.all] =
                self.lookup(&rays, Term::Sky, (plane, levels, at), seen);
        }
        open
    }

    /// The rays this cache's corners cast in `mesh` under `lighting`.
    fn rays<'a>(&'a self, mesh: &'a TraceMesh, lighting: &'a Lighting) -> LightRays<'a> {
        LightRays {
            mesh,
            lighting,
            sun_disk: &self.sun_disk,
            hemisphere: &self.hemisphere,
        }
    }

    /// Whether point `p`, facing straight up, surely sees all of the sun's disk and of the
    /// sky: every ray it casts rises at least `least_rise_up` and misses the structures
    /// (a ground far from them). Then `Openness::OPEN` is exactly what tracing gives, at the
    /// cost of one test instead of a lookup and the corners it would trace.
    fn open_up_to_sky(&self, mesh: &TraceMesh, p: DVec3) -> bool {
        self.least_rise_up
            .is_some_and(|rise| mesh.rises_clear_of_structures(p, rise))
    }

    /// The `term` at in-plane point `at` of `plane`: from the coarsest cell of `levels`
    /// down, the first whose corners are all valid and agree within the tolerance,
    /// interpolated. Where even the finest cell's corners disagree (a shadow's edge, a
    /// contact, a corner inside the structure), interpolating would blur what changes within
    /// it: the term is traced at the point `seen` itself (position and facing), as the
    /// per-pixel path does, so edges stay as sharp as the reference's.
    fn lookup(
        &self,
        rays: &LightRays,
        term: Term,
        (plane, levels, at): (PlaneKey, (i32, i32), (f64, f64)),
        seen: (DVec3, DVec3),
    ) -> Shares {
        let place = Place {
            serial: self.serial,
            plane,
            levels,
        };
        if let Some(found) = last_leaf(term, place, at) {
            return found;
        }
        for level in levels.0..=levels.1 {
            let finest = level == levels.1;
            let cell = cell_of(at, level);
            let corners = CELL_CORNERS.map(|(di, dj)| {
                let corner = Corner {
                    term,
                    plane,
                    level,
                    i: cell.0 + di,
                    j: cell.1 + dj,
                };
                self.corner(rays, corner)
            });
            let leaf = Leaf {
                place,
                level,
                cell,
                corners,
            };
            // A cell with a corner inside the structure is split down to the finest: its valid
            // corners may lie off the face, in the open (a face in a slot between two plates
            // would read the light outside the slot).
            let all_valid = corners.iter().all(|c| c[3] == VALID);
            let agree = all_valid && spread(&corners).is_some_and(|s| s <= self.settings.tolerance);
            // The sky's shares change over a finest cell by whole rays (each fixed direction
            // draws a sharp outline across the plane), not by a shadow's edge: tracing the
            // point would give the same steps a pixel aside, at the cost of every ray.
            let smooth_enough = finest && term == Term::Sky;
            if (agree || smooth_enough)
                && let Some(found) = leaf.interpolate(at)
            {
                LAST_LEAVES.with(|last| last.borrow_mut()[term as usize] = Some(leaf));
                return found;
            }
        }
        let turn = hashed_turn(plane.mix());
        trace(rays, term, seen, turn)
    }

    /// The levels a lookup with pixels `footprint` wide descends through: from cells of at
    /// least `coarsest` metres and `COARSE_CELL_PIXELS` pixels down to `finest` pixels.
    fn levels(&self, footprint: f64, finest: f64) -> (i32, i32) {
        let s = &self.settings;
        let coarse = level_within(s.coarsest.max(COARSE_CELL_PIXELS * footprint));
        let fine = level_within(finest * footprint);
        (coarse, fine.max(coarse))
    }

    /// The value at `corner`, traced on first use.
    fn corner(&self, rays: &LightRays, corner: Corner) -> Record {
        let corner = corner.canonical();
        let key = Hashed {
            hash: corner.mix(),
            corner,
        };
        let shard = &self.shards[(key.hash % SHARDS as u64) as usize];
        if let Some(value) = lock(shard).get(&key) {
            return *value;
        }
        // Traced outside the lock: another thread tracing the same corner meanwhile finds the
        // same value, whichever is kept. Every corner of a plane turns its patterns alike, so
        // neighbouring corners differ only where the geometry makes a ray's fate change, not
        // by sampling noise (which would split cells for nothing).
        let (point, normal) = corner.point();
        let turn = hashed_turn(corner.plane.mix());
        let value = if rays.enclosed(point, normal) {
            [0.0, 0.0, 0.0, INVALID]
        } else {
            let [a, b, c] = trace(rays, corner.term, (point, normal), turn);
            [a, b, c, VALID]
        };
        *lock(shard).entry(key).or_insert(value)
    }
}

/// The map of a shard; a panic elsewhere while it was held leaves only whole entries.
fn lock(shard: &Mutex<CornerMap>) -> std::sync::MutexGuard<'_, CornerMap> {
    shard
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

thread_local! {
    /// The leaf of each term this thread's last lookup ended in.
    static LAST_LEAVES: RefCell<[Option<Leaf>; 2]> = const { RefCell::new([None, None]) };
}

/// The lookup's answer when it ends in the leaf this thread's last lookup of `term` ended in
/// (consecutive pixels mostly do): the same cell, reached from the same place, interpolated
/// anew.
fn last_leaf(term: Term, place: Place, at: (f64, f64)) -> Option<Shares> {
    LAST_LEAVES.with(|last| {
        let last = last.borrow();
        let leaf = last[term as usize].as_ref()?;
        let same = leaf.place == place && cell_of(at, leaf.level) == leaf.cell;
        if !same {
            return None;
        }
        leaf.interpolate(at)
    })
}

/// The `term`'s shares at the point and facing `seen`, its patterns turned by `turn`.
fn trace(rays: &LightRays, term: Term, (p, n): (DVec3, DVec3), turn: (f64, f64)) -> Shares {
    match term {
        Term::Sun => [rays.sun_share(p, n, turn), 0.0, 0.0],
        Term::Sky => rays.sky_shares(p, n, turn),
    }
}

/// Where a lookup starts: the cache, the plane, and the levels it may descend through.
#[derive(Clone, Copy, PartialEq)]
struct Place {
    serial: u64,
    plane: PlaneKey,
    levels: (i32, i32),
}

/// A cell a lookup ended in, with its corners' records.
#[derive(Clone, Copy)]
struct Leaf {
    place: Place,
    level: i32,
    cell: (i64, i64),
    corners: [Record; 4],
}

impl Leaf {
    /// Bilinear between the valid corners at in-plane point `at`, the weights of the
    /// others left out (None when no corner is valid).
    fn interpolate(&self, at: (f64, f64)) -> Option<Shares> {
        let fx = at.0 * power_of_two(self.level) - self.cell.0 as f64;
        let fy = at.1 * power_of_two(self.level) - self.cell.1 as f64;
        let weights = [
            (1.0 - fx) * (1.0 - fy),
            fx * (1.0 - fy),
            (1.0 - fx) * fy,
            fx * fy,
        ];
        let mut sum = [0.0; 3];
        let mut total = 0.0;
        for (w, corner) in weights.into_iter().zip(self.corners) {
            let w = w * corner[3];
            total += w;
            for k in 0..3 {
                sum[k] += w * corner[k];
            }
        }
        (total > 0.0).then(|| sum.map(|s| s / total))
    }
}

/// The corners of a cell, as offsets from its lowest one, in the order `Leaf` reads them.
const CELL_CORNERS: [(i64, i64); 4] = [(0, 0), (1, 0), (0, 1), (1, 1)];

/// The largest difference between the valid corners in any share (None when none is).
fn spread(corners: &[Record; 4]) -> Option<f64> {
    let valid = || corners.iter().filter(|c| c[3] == VALID);
    valid().next()?;
    Some(
        (0..3)
            .map(|k| {
                let low = valid().map(|c| c[k]).fold(f64::INFINITY, f64::min);
                let high = valid().map(|c| c[k]).fold(f64::NEG_INFINITY, f64::max);
                high - low
            })
            .fold(0.0, f64::max),
    )
}

/// The level whose cells are the largest power of two metres no wider than `size` (> 0): level
/// ℓ has cells 2^−ℓ wide. Exact: frexp gives size = m·2^e with m in [½, 1), so 2^(e−1) ≤ size.
fn level_within(size: f64) -> i32 {
    let size = size.clamp(1e-9, 1e9);
    1 - libm::frexp(size).1
}

/// The cell of level `level` holding in-plane point `at`.
fn cell_of(at: (f64, f64), level: i32) -> (i64, i64) {
    (
        floor_to_i64(at.0 * power_of_two(level)),
        floor_to_i64(at.1 * power_of_two(level)),
    )
}

/// 2^`level` exactly, for the levels `level_within` gives (|level| < 64): multiplying by it is
/// `libm::scalbn`, exact, without the call (lookups do it for every pixel).
fn power_of_two(level: i32) -> f64 {
    debug_assert!(level.abs() < 64);
    f64::from_bits(((1023 + i64::from(level)) as u64) << 52)
}

/// `x.floor() as i64` (saturating the same way) without the call to libm's floor, which the
/// x86-64 baseline has no instruction for.
fn floor_to_i64(x: f64) -> i64 {
    let truncated = x as i64;
    if (truncated as f64) > x {
        truncated.saturating_sub(1)
    } else {
        truncated
    }
}

/// `x.round() as i64` (halves away from zero, saturating) without the call to libm's round.
fn round_to_i64(x: f64) -> i64 {
    let truncated = x as i64;
    // Exact: x and its truncation are within a factor two of each other, or the truncation is
    // 0, or x is already whole (|x| ≥ 2⁵²).
    let fraction = x - truncated as f64;
    if fraction >= 0.5 {
        truncated.saturating_add(1)
    } else if fraction <= -0.5 {
        truncated.saturating_sub(1)
    } else {
        truncated
    }
}

/// A plane of the mesh, quantised, facing where the camera saw it from, with the world axis
/// it is laid out along: its lattice runs over the two other axes (the axes closest to the
/// plane, as in triplanar mapping), projected onto the plane along the first.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
struct PlaneKey {
    axis: u8,
    normal: [i32; 3],
    offset: i64,
}

impl PlaneKey {
    fn of(p: DVec3, n: DVec3) -> Self {
        let a = n.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        PlaneKey {
            axis,
            normal: n.to_array().map(|c| {
                round_to_i64(c * PLANE_STEPS).clamp(i32::MIN.into(), i32::MAX.into()) as i32
            }),
            offset: round_to_i64(n.dot(p) * PLANE_STEPS),
        }
    }

    /// The key's fields mixed into one word (the turn of the plane's ray patterns).
    fn mix(self) -> u64 {
        let [x, y, z] = self.normal.map(|c| c as u64);
        mix_words(
            0x243f_6a88_85a3_08d3,
            [u64::from(self.axis), x, y, z, self.offset as u64],
        )
    }

    /// The two world axes the lattice runs along.
    fn lattice_axes(self) -> (usize, usize) {
        let a = usize::from(self.axis);
        ((a + 1) % 3, (a + 2) % 3)
    }

    /// `p`'s coordinates along the lattice's axes.
    fn in_plane(self, p: DVec3) -> (f64, f64) {
        let (b, c) = self.lattice_axes();
        (p[b], p[c])
    }

    /// The unit normal and offset the key stands for.
    fn plane(self) -> (DVec3, f64) {
        let n = DVec3::from_array(self.normal.map(|c| f64::from(c) / PLANE_STEPS));
        let length = n.length();
        (n / length, self.offset as f64 / PLANE_STEPS / length)
    }
}

/// A lattice corner of one term's lattice on a plane, at a level.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Corner {
    term: Term,
    plane: PlaneKey,
    level: i32,
    i: i64,
    j: i64,
}

impl Corner {
    /// The same lattice point named at the coarsest level where it is one, down to
    /// `SHARED_LEVEL`: corner (2i, 2j) of level ℓ + 1 is corner (i, j) of level ℓ. A cell
    /// split in four then reuses its own four corners, and a shadow edge or a contact
    /// refined over k levels traces each point of it once rather than once per level (along
    /// an edge, about half the corners). The lift off the plane follows the canonical level,
    /// so the point, and with it the value, is one per lattice point.
    fn canonical(self) -> Corner {
        let shared = i64::from(self.level - SHARED_LEVEL).max(0);
        let even = (self.i.trailing_zeros().min(self.j.trailing_zeros()) as i64).min(shared);
        Corner {
            level: self.level - even as i32,
            i: self.i >> even,
            j: self.j >> even,
            ..self
        }
    }

    /// The world point and the facing normal of the corner.
    fn point(self) -> (DVec3, DVec3) {
        let (n, offset) = self.plane.plane();
        let (b, c) = self.plane.lattice_axes();
        let a = usize::from(self.plane.axis);
        let mut p = DVec3::ZERO;
        p[b] = libm::scalbn(self.i as f64, -self.level);
        p[c] = libm::scalbn(self.j as f64, -self.level);
        p[a] = (offset - n[b] * p[b] - n[c] * p[c]) / n[a];
        // Off the plane by a share of the cell: a corner away from the pixels it serves may lie
        // where the plane runs inside the structure (a facet of a sagging face extended along
        // the neighbouring facets, a contact), and would see nothing.
        (p + n * libm::scalbn(CORNER_LIFT, -self.level), n)
    }

    /// The key's fields folded into one word, the map's hash and the shard: a multiply per
    /// field (as rustc's FxHasher) and one finaliser, a tenth of `mix_words` over them all.
    /// Only how the map spreads its keys depends on it, never a value.
    fn mix(self) -> u64 {
        let [x, y, z] = self.plane.normal.map(|c| c as u64);
        let words = [
            u64::from(self.plane.axis) | (self.term as u64) << 8 | (self.level as u64) << 32,
            x,
            y,
            z,
            self.plane.offset as u64,
            self.i as u64,
            self.j as u64,
        ];
        let folded = words.into_iter().fold(0, |h: u64, w| {
            (h.rotate_left(5) ^ w).wrapping_mul(0x517c_c1b7_2722_0a95)
        });
        splitmix_finaliser(folded)
    }
}

/// `words` folded into `seed` through splitmix64's finaliser (Steele, Lea & Flood 2014).
fn mix_words<const N: usize>(seed: u64, words: [u64; N]) -> u64 {
    words
        .into_iter()
        .fold(seed, |h, x| splitmix_finaliser(h ^ x))
}

/// splitmix64's finaliser: every bit of `word` reaches every bit of the result.
fn splitmix_finaliser(word: u64) -> u64 {
    let mut z = word.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A corner with its `Corner::mix`, computed once for the shard and the map.
#[derive(Clone, Copy, Debug)]
struct Hashed {
    hash: u64,
    corner: Corner,
}

impl PartialEq for Hashed {
    fn eq(&self, other: &Self) -> bool {
        self.corner == other.corner
    }
}

impl Eq for Hashed {}

impl Hash for Hashed {
    fn hash<H: Hasher>(&self, state: &mut H) {
        state.write_u64(self.hash);
    }
}

/// Passes on the word `Hashed::hash` writes, already mixed.
#[derive(Default)]
struct MixedKeyHasher(u64);

impl Hasher for MixedKeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = self.0.rotate_left(8) ^ u64::from(b);
        }
    }

    fn write_u64(&mut self, word: u64) {
        self.0 = word;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Mesh;
    use crate::materials::Sun;

    /// The call-free floor, round and power of two against libm's, on halves, integers,
    /// neighbours of both, values past 2⁵² and 2⁶³ (saturating), signed zeros and NaN.
    #[test]
    fn the_call_free_floor_round_and_scaling_are_libms() {
        let mut values = vec![0.0, -0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300];
        for base in [
            0.5f64,
            1.0,
            1.5,
            2.5,
            3.0,
            1e6 + 0.5,
            4503599627370496.0,
            9.3e18,
            1e19,
        ] {
            for x in [base, base.next_up(), base.next_down()] {
                values.extend([x, -x]);
            }
        }
        for k in -20_000..20_000 {
            values.push(f64::from(k) * 0.137_035_999);
        }
        for x in values {
            assert_eq!(floor_to_i64(x), x.floor() as i64, "floor of {x:e}");
            assert_eq!(round_to_i64(x), x.round() as i64, "round of {x:e}");
            for level in -40..40 {
                let scaled = x * power_of_two(level);
                let reference = libm::scalbn(x, level);
                assert!(
                    scaled.to_bits() == reference.to_bits() || (x.is_nan() && scaled.is_nan()),
                    "{x:e} scaled by 2^{level}"
                );
            }
        }
    }

    #[test]
    fn a_level_holds_the_largest_power_of_two_within_a_size() {
        for size in [1e-6, 0.003, 0.25, 0.3, 0.5, 0.75, 1.0, 1.5, 7.0, 1e5] {
            let cell = libm::scalbn(1.0, -level_within(size));
            assert!(cell <= size && size < 2.0 * cell, "{size}: cell {cell}");
        }
    }

    /// A unit cube standing on a 1 km ground square (its triangles after the cube's, as a
    /// sample's scene mesh is laid out), under a sun 50° high with a 0.53° disk and a sky.
    fn cube_on_ground_in_daylight() -> (TraceMesh, Lighting) {
        let mut mesh = crate::geometry::import::tests::cube();
        let core = mesh.triangles.len();
        let first = mesh.positions.len() as u32;
        mesh.positions.extend(
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(x, y)| DVec3::new(0.5 + 1000.0 * x, 0.5 + 1000.0 * y, 0.0)),
        );
        mesh.triangles
            .extend([[0, 1, 2], [0, 2, 3]].map(|t| t.map(|i| i + first)));
        let elevation = 50f64.to_radians();
        let lighting = Lighting {
            ambient: 0.0,
            studio: None,
            sun: Some(Sun {
                direction: DVec3::new(
                    0.6 * elevation.cos(),
                    0.8 * elevation.cos(),
                    elevation.sin(),
                ),
                colour: [1.0; 3],
                angular_diameter: 0.53f64.to_radians(),
                shadow_rays: 8,
            }),
            sky: Some(crate::materials::Sky {
                sky: [0.5; 3],
                ground: [0.2; 3],
                occlusion_rays: 16,
            }),
            environment: None,
            shadows: true,
            ground: None,
            film: Default::default(),
        };
        (TraceMesh::build_with_core(&mesh, core), lighting)
    }

    /// `n` points spread evenly over the ground square of side `side` centred under the cube
    /// (additive recurrences with irrational steps).
    fn ground_points_about_the_cube(n: u32, side: f64) -> impl Iterator<Item = DVec3> {
        (0..n).map(move |step| {
            let t = f64::from(step);
            DVec3::new(
                0.5 + side * ((t * 0.618_034).fract() - 0.5),
                0.5 + side * ((t * 0.414_214).fract() - 0.5),
                0.0,
            )
        })
    }

    /// Ground far from the structures sees the whole sun and sky: the cache answers so
    /// without tracing a corner, and tracing the point's own rays (the per-pixel path) agrees
    /// exactly. Near the cube (its shadow, its foot) the cache still traces.
    #[test]
    fn open_ground_far_from_the_structures_traces_no_corner() {
        let (mesh, lighting) = cube_on_ground_in_daylight();
        let cache = LightCache::new(&lighting, CacheSettings::default());
        let rays = cache.rays(&mesh, &lighting);
        for (x, y) in [(30.0, 0.5), (-25.0, -20.0), (0.5, 40.0), (300.0, -700.0)] {
            let p = DVec3::new(x, y, 0.0);
            let open = cache.openness(&mesh, &lighting, p, DVec3::Z, 1e-3);
            assert_eq!(open, Openness::OPEN, "at {p}");
            assert_eq!(
                rays.openness(p, DVec3::Z, || (0.6, 0.8)),
                Openness::OPEN,
                "{p}"
            );
        }
        assert_eq!(cache.corners(), 0, "corners traced for open ground");
        // In the cube's shadow (the sun is towards +x +y) and at its foot.
        let shadowed = DVec3::new(0.2, -0.1, 0.0);
        assert!(
            cache
                .openness(&mesh, &lighting, shadowed, DVec3::Z, 1e-3)
                .sun
                < 0.5
        );
        assert!(cache.corners() > 0);
    }

    /// A lattice point shared by levels is one corner, traced once: corner (4, −6) of level 5
    /// is corner (2, −3) of level 4 (and of no coarser level), while (2, −3) of level 5 is
    /// another point. Below the shared level, levels keep their own corners.
    #[test]
    fn a_lattice_point_of_several_levels_is_traced_once() {
        let (mesh, lighting) = cube_on_ground_in_daylight();
        let cache = LightCache::new(&lighting, CacheSettings::default());
        let rays = cache.rays(&mesh, &lighting);
        let plane = PlaneKey::of(DVec3::new(0.5, 0.5, 1.0), DVec3::Z);
        let corner = |level, i, j| Corner {
            term: Term::Sky,
            plane,
            level,
            i,
            j,
        };
        let fine = cache.corner(&rays, corner(5, 4, -6));
        assert_eq!(cache.corners(), 1);
        assert_eq!(cache.corner(&rays, corner(4, 2, -3)), fine);
        assert_eq!(cache.corners(), 1, "the same point traced twice");
        cache.corner(&rays, corner(5, 2, -3));
        assert_eq!(cache.corners(), 2);
        assert_eq!(corner(9, 0, 64).canonical(), corner(3, 0, 1));
        assert_eq!(corner(9, 0, 512).canonical(), corner(SHARED_LEVEL, 0, 4));
        assert_eq!(corner(1, 2, 4).canonical(), corner(1, 2, 4));
    }

    /// The preview's settings trace fewer corners than the default for the same lookups (a
    /// ground around the cube, its shadow, its foot, at a 1 cm footprint), and give shares
    /// within the tolerances' sum of the default's outside shadow edges.
    #[test]
    fn preview_settings_trace_fewer_corners() {
        let (mesh, lighting) = cube_on_ground_in_daylight();
        let (run, preview) = (
            LightCache::new(&lighting, CacheSettings::default()),
            LightCache::new(&lighting, CacheSettings::PREVIEW),
        );
        let mut far_apart = 0;
        for p in ground_points_about_the_cube(2000, 4.0) {
            let [a, b] = [&run, &preview].map(|c| c.openness(&mesh, &lighting, p, DVec3::Z, 0.01));
            far_apart += usize::from((a.all - b.all).abs() > 0.3);
        }
        assert!(far_apart < 20, "{far_apart} points far apart");
        assert!(
            3 * preview.corners() < 2 * run.corners(),
            "preview {} corners, run {}",
            preview.corners(),
            run.corners()
        );
    }

    /// Where the test says every ray rising at least so high misses the structures, rays at
    /// exactly that rise towards every azimuth (and steeper) are free; near the cube it
    /// says no, and rays there are blocked.
    #[test]
    fn rising_clear_of_the_structures_is_never_wrong() {
        let (mesh, lighting) = cube_on_ground_in_daylight();
        let rise = least_rise_facing_up(&lighting, &DiskPattern::new(8), &DiskPattern::new(32))
            .expect("the sun and sky are above the ground");
        assert!(rise > 0.05 && rise < 0.2, "{rise}");
        let (mut clear, mut blocked) = (0, 0);
        for p in ground_points_about_the_cube(400, 40.0) {
            let says_clear = mesh.rises_clear_of_structures(p, rise);
            clear += usize::from(says_clear);
            for k in 0..64 {
                let a = f64::from(k) * std::f64::consts::TAU / 64.0;
                for z in [rise, 0.5, 0.99] {
                    let flat = (1.0 - z * z).sqrt();
                    let d = DVec3::new(flat * a.cos(), flat * a.sin(), z);
                    let hit = mesh.occluded(p, DVec3::Z, d);
                    assert!(!(says_clear && hit), "{p} towards {d} is blocked");
                    blocked += usize::from(hit);
                }
            }
        }
        assert!(
            clear > 100 && blocked > 0,
            "{clear} points clear, {blocked} rays blocked"
        );
    }

    /// A horizontal plate over x < 0 at height H under an overhead sun of angular diameter θ:
    /// on the ground the share of the disk seen at x is one minus the circular segment the
    /// plate's edge cuts off the disk's image of radius H·tan(θ/2). Read from the cache at a
    /// 1 mm footprint, the penumbra keeps that shape: the cells split down to the edge.
    #[test]
    fn the_cached_penumbra_follows_the_circular_segment() {
        let height = 2.0;
        let mesh = TraceMesh::build(&Mesh {
            positions: vec![
                DVec3::new(-50.0, -50.0, height),
                DVec3::new(0.0, -50.0, height),
                DVec3::new(0.0, 50.0, height),
                DVec3::new(-50.0, 50.0, height),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        });
        let theta = 2.0_f64.to_radians();
        let lighting = Lighting {
            ambient: 0.0,
            studio: None,
            sun: Some(Sun {
                direction: DVec3::Z,
                colour: [1.0; 3],
                angular_diameter: theta,
                shadow_rays: 256,
            }),
            sky: None,
            environment: None,
            shadows: true,
            ground: None,
            film: Default::default(),
        };
        let cache = LightCache::new(&lighting, CacheSettings::default());
        let r = height * (0.5 * theta).tan();
        for step in -40..=40 {
            let x = f64::from(step) * r / 30.0;
            let p = DVec3::new(x, 0.3, 0.0);
            let seen = cache.openness(&mesh, &lighting, p, DVec3::Z, 1e-3).sun;
            let expected = if x >= r {
                1.0
            } else if x <= -r {
                0.0
            } else {
                let h = r - x;
                let segment = r * r * (1.0 - h / r).acos() - (r - h) * (2.0 * r * h - h * h).sqrt();
                1.0 - segment / (std::f64::consts::PI * r * r)
            };
            assert!(
                (seen - expected).abs() < 0.05,
                "x = {x:.4} m: the cache gives {seen:.3}, the segment {expected:.3}"
            );
        }
        assert!(cache.corners() > 0);
    }
}
