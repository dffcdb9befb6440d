//! Material fields cached per sample in surface space, shared by all the sample's views.
//!
//! A material's fields (albedo, roughness, specular; crack coverage and every other pattern
//! are folded into the albedo) are functions of the undeformed surface point and of the pixel
//! footprint they are filtered for, not of the camera. A sample's views see each surface
//! point several times over (5–6 on A1), so the fields are evaluated once on a lattice laid
//! on each plane of the undeformed surface and every view reads them back with filtering:
//!
//! - *Where*: each plane (a piece's triangles sharing a normal and an offset, quantised to
//!   2⁻²⁰, about a micrometre: the two triangles of a box face share one) carries a square
//!   lattice in the two world axes other than its normal's dominant one; a lattice point is
//!   lifted along that axis onto the plane. Blocks of `CELLS`² cells are evaluated whole,
//!   when a pixel first needs one, and kept for the sample.
//! - *How fine*: a mipmap. Level `L` has lattice spacing 2^L m and is evaluated at the
//!   footprint for which it is the finer level exactly; a pixel of footprint `f` blends the
//!   two levels whose texels (stretched by at most 1/|n_a| on a slanted plane) are no larger
//!   than `fraction · f` (the coarser) and `fraction · f / 2` (the finer), linearly in the
//!   footprint within the octave, bilinearly within each level. The material's own filter
//!   (octaves fading below two footprints, lines covering their share of a pixel) therefore
//!   sees about the footprint the pixel has, so the anti-aliasing is today's, and the level
//!   changes continuously with distance: no shimmer between views, no step within a face.
//!   The resolution a sample gets is thus the one its nearest view needs, and no finer.
//! - *Seams*: every lattice point is a function of its plane, level and indices alone, and
//!   the fields are continuous in 3D, so two planes meeting at an edge (two faces of a box,
//!   two members) both interpolate the same continuous field there: they differ by the
//!   interpolation error, not by a pattern break.
//! - *Determinism*: a block's values depend on its key alone, never on which view or thread
//!   asked first (two threads asking at once compute the same bits and one copy is kept), so
//!   the RGB is the same on any thread count, shard or resume.
//! - *Memory*: the cache belongs to the sample's renderer and is dropped with it; a thread
//!   keeps handles to its last few blocks (`RECENT`, bounded), so peak memory does not grow
//!   with the number of samples.
//!
//! The per-pixel path (`Shader::surface` at each pixel) is the reference this is measured
//! against, and what runs use under either `shading`: measured on A1 and A2 (docs/materials.md,
//! "Caching material fields"), no texel bound pays at an error worth having. The materials'
//! own filters leave detail up to half the footprint's frequency, and their thresholds (rust
//! pits, crack lines) make sharper detail still, so the bilinear reconstruction needs texels
//! well below the footprint to stay within a few levels: more lattice points than a sample's
//! views have pixels. `SampleRenderer::with_texel_fraction` turns it on for the benchmark
//! and the tests that keep those measurements honest.
//!
//! Owns: the lattice, its blocks and their lookup. Must not touch: what a material computes
//! (`procedural`), geometry, shading.

use super::{Grain, Shader, Surface, SurfacePoint};
use glam::DVec3;
use std::cell::RefCell;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, RwLock};

/// Lattice cells along each side of a block.
const CELLS: i64 = 4;
/// Lattice points along each side of a block: its cells' corners, the far edge included, so a
/// bilinear lookup reads one block (neighbouring blocks share their edge points, same bits).
const POINTS: usize = CELLS as usize + 1;

/// Quantum of plane normals and offsets: 2⁻²⁰ (a micrometre for offsets in metres).
const QUANTUM: f64 = 1.0 / (1u64 << 20) as f64;

/// A plane of a piece's undeformed surface, quantised so that coplanar triangles share it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    key: PlaneKey,
    /// Unit normal rebuilt from the quantised one (what the material sees).
    normal: DVec3,
    /// Offset along `normal`, metres, quantised.
    offset: f64,
    /// The normal's dominant axis, along which lattice points are lifted onto the plane.
    axis: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct PlaneKey {
    piece: u32,
    normal: [i64; 3],
    offset: i64,
}

impl Plane {
    /// The plane of piece `piece` with unit normal `normal` through `point`; None for a
    /// degenerate normal.
    pub fn new(piece: u32, normal: DVec3, point: DVec3) -> Option<Plane> {
        let quantised = normal.to_array().map(|c| (c / QUANTUM).round() as i64);
        let unit = DVec3::from_array(quantised.map(|q| q as f64 * QUANTUM)).normalize_or_zero();
        if unit == DVec3::ZERO || !point.is_finite() {
            return None;
        }
        let offset = (unit.dot(point) / QUANTUM).round() as i64;
        let abs = unit.abs();
        let axis = if abs.x >= abs.y && abs.x >= abs.z {
            0
        } else if abs.y >= abs.z {
            1
        } else {
            2
        };
        Some(Plane {
            key: PlaneKey {
                piece,
                normal: quantised,
                offset,
            },
            normal: unit,
            offset: offset as f64 * QUANTUM,
            axis,
        })
    }

    /// The two in-plane lattice axes (world axes other than the dominant one).
    fn lattice_axes(&self) -> (usize, usize) {
        ((self.axis + 1) % 3, (self.axis + 2) % 3)
    }

    /// Lattice coordinates (metres along the two lattice axes) of a point.
    fn project(&self, p: DVec3) -> (f64, f64) {
        let (b, c) = self.lattice_axes();
        (p[b], p[c])
    }

    /// The point of the plane at lattice coordinates (u, v).
    fn lift(&self, u: f64, v: f64) -> DVec3 {
        let (b, c) = self.lattice_axes();
        let n = self.normal;
        let mut p = DVec3::ZERO;
        p[b] = u;
        p[c] = v;
        p[self.axis] = (self.offset - n[b] * u - n[c] * v) / n[self.axis];
        p
    }

    /// |n_a|: the lattice's texels are stretched by at most its inverse on the plane.
    fn cos_dominant(&self) -> f64 {
        self.normal[self.axis].abs()
    }
}

/// One block of one level of one plane's lattice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct BlockKey {
    plane: PlaneKey,
    level: i32,
    block: [i64; 2],
}

/// The fields at a block's lattice points, row by row: albedo (3), roughness, specular.
type Block = [[f32; FIELDS]; POINTS * POINTS];
const FIELDS: usize = 5;

/// Every lattice block of one sample evaluated so far.
pub struct FieldCache {
    /// Identifies this cache in the threads' `RECENT` handles (a new cache never matches an
    /// old one's handles).
    id: u64,
    fraction: f64,
    blocks: RwLock<HashMap<BlockKey, Arc<Block>, BuildHasherDefault<WordHasher>>>,
}

/// A multiply–rotate hash of the key's words (FxHash's round): block keys are small integers,
/// hashed at every block a thread first reads; the map's order is never observed.
#[derive(Default)]
struct WordHasher(u64);

impl Hasher for WordHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    fn write_u64(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x517c_c1b7_2722_0a95);
    }

    fn write_u32(&mut self, word: u32) {
        self.write_u64(u64::from(word));
    }

    fn write_i64(&mut self, word: i64) {
        self.write_u64(word as u64);
    }

    fn write_i32(&mut self, word: i32) {
        self.write_u64(word as u64);
    }
}

/// Source of cache ids.
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// Blocks a thread keeps handles to: the few a row of pixels is reading.
const RECENT_BLOCKS: usize = 8;

struct Recent {
    entries: [Option<(u64, BlockKey, Arc<Block>)>; RECENT_BLOCKS],
    next: usize,
}

impl Recent {
    /// The block `key` of cache `id`, if the thread holds it.
    fn find(&self, id: u64, key: &BlockKey) -> Option<&Block> {
        self.entries
            .iter()
            .flatten()
            .find(|(i, k, _)| *i == id && k == key)
            .map(|(_, _, block)| &**block)
    }

    /// Holds `block` in place of the oldest handle.
    fn keep(&mut self, id: u64, key: BlockKey, block: Arc<Block>) -> &Block {
        let slot = self.next;
        self.next = (slot + 1) % RECENT_BLOCKS;
        &self.entries[slot].insert((id, key, block)).2
    }
}

thread_local! {
    /// The cache, triangle and plane a thread last asked `FieldCache::plane` for.
    static LAST_PLANE: std::cell::Cell<Option<(u64, u32, Plane)>> = const { std::cell::Cell::new(None) };
    static RECENT: RefCell<Recent> = const {
        RefCell::new(Recent {
            entries: [const { None }; RECENT_BLOCKS],
            next: 0,
        })
    };
}

/// The two levels a footprint blends and the weight of the coarser.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Levels {
    finer: i32,
    coarser_weight: f64,
}

/// Levels far beyond any surface or pixel (2⁻⁴⁰ m to 2⁴⁰ m): outside, the per-pixel path.
const LEVEL_RANGE: std::ops::RangeInclusive<i32> = -40..=40;

impl FieldCache {
    /// An empty cache whose texels are at most `fraction` of a pixel's footprint: the coarser
    /// of the two levels a pixel blends (the finer, half of it).
    pub fn new(fraction: f64) -> FieldCache {
        assert!(
            fraction.is_finite() && fraction > 0.0,
            "texel fraction {fraction}"
        );
        FieldCache {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            fraction,
            blocks: RwLock::new(HashMap::default()),
        }
    }

    /// The plane of triangle `triangle`, made by `make` unless it is the one this thread last
    /// asked this cache for (consecutive pixels mostly see one triangle).
    pub fn plane(&self, triangle: u32, make: impl FnOnce() -> Option<Plane>) -> Option<Plane> {
        LAST_PLANE.with(|last| match last.get() {
            Some((id, t, plane)) if id == self.id && t == triangle => Some(plane),
            _ => {
                let plane = make()?;
                last.set(Some((self.id, triangle, plane)));
                Some(plane)
            }
        })
    }

    /// Lattice points evaluated so far (each 20 bytes).
    pub fn points(&self) -> usize {
        self.blocks.read().expect("cache lock").len() * POINTS * POINTS
    }

    /// The surface of `shader` on piece `grain` at undeformed point `rest` of `plane`, for a
    /// pixel `footprint` metres wide: the cached fields, filtered. The crack flag is false:
    /// the crack label is `Shader::crack`'s, per pixel.
    pub fn surface(
        &self,
        shader: &Shader,
        grain: &Grain,
        plane: &Plane,
        rest: DVec3,
        footprint: f64,
    ) -> Surface {
        let Some(levels) = self.levels(plane, footprint) else {
            return shader.surface(
                &SurfacePoint {
                    rest,
                    rest_normal: plane.normal,
                    footprint,
                },
                grain,
            );
        };
        let (u, v) = plane.project(rest);
        let source = Source {
            cache: self,
            shader,
            grain,
            plane,
        };
        let fine = source.bilinear(levels.finer, u, v);
        let t = levels.coarser_weight;
        let fields = if t == 0.0 {
            fine
        } else {
            let coarse = source.bilinear(levels.finer + 1, u, v);
            std::array::from_fn(|k| fine[k] + (coarse[k] - fine[k]) * t)
        };
        Surface {
            albedo: [fields[0], fields[1], fields[2]],
            roughness: fields[3],
            specular: fields[4],
            crack: false,
        }
    }

    /// The levels a pixel of `footprint` on `plane` blends: x = fraction · footprint · |n_a| / 2
    /// = 2^L · m with m in [1, 2) gives the finer level L and the coarser's weight m − 1
    /// (linear in the footprint within the octave, read off the bits: exact and cheap).
    fn levels(&self, plane: &Plane, footprint: f64) -> Option<Levels> {
        let x = self.fraction * footprint * plane.cos_dominant() * 0.5;
        if !(x.is_finite() && x >= f64::MIN_POSITIVE) {
            return None;
        }
        let bits = x.to_bits();
        let finer = ((bits >> 52) & 0x7ff) as i32 - 1023;
        let mantissa = f64::from_bits((bits & ((1 << 52) - 1)) | (1023 << 52));
        (LEVEL_RANGE.contains(&finer) && LEVEL_RANGE.contains(&(finer + 1))).then_some(Levels {
            finer,
            coarser_weight: mantissa - 1.0,
        })
    }

    /// The footprint level `level` is evaluated for: that of a pixel for which it is the finer
    /// level with no weight on the coarser (see `levels`).
    fn footprint_of(&self, plane: &Plane, level: i32) -> f64 {
        2.0 * spacing(level) / (self.fraction * plane.cos_dominant())
    }
}

/// How far an RGB image is from a reference over the pixels that see a surface: the largest
/// channel difference of each pixel, in 8-bit levels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RgbError {
    /// Root mean square.
    pub rms: f64,
    /// 99th percentile.
    pub p99: u8,
    /// Pixels compared.
    pub pixels: usize,
}

impl RgbError {
    /// `image` against `reference` (sRGB, three bytes a pixel) where `seen` is true.
    pub fn of(image: &[u8], reference: &[u8], seen: &[bool]) -> RgbError {
        let mut d: Vec<u8> = image
            .chunks(3)
            .zip(reference.chunks(3))
            .zip(seen)
            .filter(|(_, seen)| **seen)
            .map(|((p, q), _)| (0..3).map(|k| p[k].abs_diff(q[k])).max().unwrap_or(0))
            .collect();
        if d.is_empty() {
            return RgbError::default();
        }
        let squares: f64 = d.iter().map(|&x| f64::from(x).powi(2)).sum();
        d.sort_unstable();
        // Nearest rank: the ⌈0.99 n⌉-th smallest.
        let rank = (d.len() * 99).div_ceil(100);
        RgbError {
            rms: (squares / d.len() as f64).sqrt(),
            p99: d[rank - 1],
            pixels: d.len(),
        }
    }

    /// The worse of two, measure by measure (the worst view of several).
    pub fn worst(self, other: RgbError) -> RgbError {
        RgbError {
            rms: self.rms.max(other.rms),
            p99: self.p99.max(other.p99),
            pixels: self.pixels.min(other.pixels),
        }
    }
}

/// ⌊x⌋ and x − ⌊x⌋, by conversion (`f64::floor` is a library call on the x86-64 baseline);
/// |x| stays far below 2⁶³ (lattice indices of a structure's surface).
fn floor(x: f64) -> (i64, f64) {
    let i = x as i64;
    let i = i - i64::from(x < i as f64);
    (i, x - i as f64)
}

/// Lattice spacing of level `level`, metres: 2^level, exact.
fn spacing(level: i32) -> f64 {
    f64::from_bits(((1023 + level as i64) as u64) << 52)
}

/// Where a lookup's blocks come from: the cache, and the material to fill it from.
struct Source<'a> {
    cache: &'a FieldCache,
    shader: &'a Shader,
    grain: &'a Grain,
    plane: &'a Plane,
}

impl Source<'_> {
    /// The fields at lattice coordinates (u, v) of level `level`, bilinear between the four
    /// lattice points around.
    fn bilinear(&self, level: i32, u: f64, v: f64) -> [f64; FIELDS] {
        // Scaling by a power of two is exact: lattice indices are the same bits for every
        // point that shares them.
        let inverse = spacing(-level);
        let (gu, gv) = (u * inverse, v * inverse);
        let ((iu, fu), (iv, fv)) = (floor(gu), floor(gv));
        let block = [iu.div_euclid(CELLS), iv.div_euclid(CELLS)];
        let (lu, lv) = (
            (iu - block[0] * CELLS) as usize,
            (iv - block[1] * CELLS) as usize,
        );
        let key = BlockKey {
            plane: self.plane.key,
            level,
            block,
        };
        let id = self.cache.id;
        RECENT.with_borrow_mut(|recent| {
            let values = match recent.find(id, &key) {
                Some(found) => found,
                None => recent.keep(id, key, self.fetch(key)),
            };
            let at = |du: usize, dv: usize| values[(lv + dv) * POINTS + lu + du];
            let (a, b, c, d) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
            std::array::from_fn(|k| {
                let low = f64::from(a[k]) + (f64::from(b[k]) - f64::from(a[k])) * fu;
                let high = f64::from(c[k]) + (f64::from(d[k]) - f64::from(c[k])) * fu;
                low + (high - low) * fv
            })
        })
    }

    /// The block `key`: from the cache, or evaluated and kept there.
    fn fetch(&self, key: BlockKey) -> Arc<Block> {
        let known = self
            .cache
            .blocks
            .read()
            .expect("cache lock")
            .get(&key)
            .cloned();
        known.unwrap_or_else(|| {
            let fresh = Arc::new(self.evaluate(key));
            // Another thread may have evaluated it meanwhile: the same bits, keep one copy.
            self.cache
                .blocks
                .write()
                .expect("cache lock")
                .entry(key)
                .or_insert(fresh)
                .clone()
        })
    }

    /// The material at every lattice point of block `key`, evaluated for its level's footprint.
    fn evaluate(&self, key: BlockKey) -> Block {
        let step = spacing(key.level);
        let footprint = self.cache.footprint_of(self.plane, key.level);
        let first = key.block.map(|b| b * CELLS);
        let mut block = [[0f32; FIELDS]; POINTS * POINTS];
        for (row, line) in block.chunks_mut(POINTS).enumerate() {
            let v = (first[1] + row as i64) as f64 * step;
            for (col, point) in line.iter_mut().enumerate() {
                let u = (first[0] + col as i64) as f64 * step;
                let s = self.shader.surface(
                    &SurfacePoint {
                        rest: self.plane.lift(u, v),
                        rest_normal: self.plane.normal,
                        footprint,
                    },
                    self.grain,
                );
                *point = [
                    s.albedo[0] as f32,
                    s.albedo[1] as f32,
                    s.albedo[2] as f32,
                    s.roughness as f32,
                    s.specular as f32,
                ];
            }
        }
        block
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coplanar_triangles_share_a_plane_and_points_lift_back_onto_it() {
        let n = DVec3::new(0.3, -0.5, 0.8).normalize();
        let a = Plane::new(2, n, DVec3::new(1.0, 2.0, 3.0)).unwrap();
        // Another point of the same plane, the normal off by rounding.
        let along = n.cross(DVec3::X).normalize();
        let b = Plane::new(
            2,
            (n + DVec3::splat(1e-15)).normalize(),
            DVec3::new(1.0, 2.0, 3.0) + 0.7 * along,
        )
        .unwrap();
        assert_eq!(a, b);
        assert_eq!(a.axis, 2);
        assert_ne!(
            a,
            Plane::new(3, n, DVec3::new(1.0, 2.0, 3.0)).unwrap(),
            "pieces differ"
        );
        let p = a.lift(0.25, -1.5);
        assert!((a.normal.dot(p) - a.offset).abs() < 1e-12);
        assert_eq!(a.project(p), (0.25, -1.5));
        assert_eq!(Plane::new(0, DVec3::ZERO, DVec3::ZERO), None);
    }

    #[test]
    fn levels_bound_the_texels_by_the_footprint_and_blend_continuously() {
        let cache = FieldCache::new(1.0);
        let plane = Plane::new(0, DVec3::new(0.6, 0.0, 0.8), DVec3::ZERO).unwrap();
        let stretch = 1.0 / plane.cos_dominant();
        let mut last = None::<f64>;
        for k in 0..2000 {
            let f = 1e-4 * 1.003f64.powi(k);
            let l = cache.levels(&plane, f).unwrap();
            // The texels on the surface: the finer at most half the bound, the coarser at most it.
            assert!(spacing(l.finer) * stretch <= 0.5 * f * (1.0 + 1e-12));
            assert!(spacing(l.finer + 1) * stretch <= f * (1.0 + 1e-12));
            assert!((0.0..1.0).contains(&l.coarser_weight));
            // As an effective level, finer + weight rises continuously with the footprint.
            let effective = f64::from(l.finer) + l.coarser_weight;
            if let Some(e) = last {
                assert!(
                    effective >= e && effective - e < 0.01,
                    "{f}: {e} → {effective}"
                );
            }
            last = Some(effective);
            // At weight 0 the pixel's footprint is the level's own.
            let own = cache.footprint_of(&plane, l.finer);
            assert!(own <= f * (1.0 + 1e-12) && f < 2.0 * own, "{f} {own}");
        }
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e300] {
            assert_eq!(cache.levels(&plane, bad), None, "{bad}");
        }
    }

    #[test]
    fn rgb_error_is_the_largest_channel_difference_over_the_seen_pixels() {
        // 100 seen pixels: 98 equal, one off by 3 in green, one by 10 in blue and 2 in red;
        // an unseen pixel off by 200 does not count.
        let reference = vec![50u8; 101 * 3];
        let mut image = reference.clone();
        image[3 * 7 + 1] += 3;
        image[3 * 9] += 2;
        image[3 * 9 + 2] += 10;
        image[3 * 100] += 200;
        let mut seen = vec![true; 101];
        seen[100] = false;
        let e = RgbError::of(&image, &reference, &seen);
        assert_eq!(e.pixels, 100);
        assert!((e.rms - ((9.0 + 100.0) / 100.0f64).sqrt()).abs() < 1e-12);
        assert_eq!(e.p99, 3, "the 99th of 100 sorted differences");
        // One pixel: every percentile is its difference.
        let one = RgbError::of(&image[27..30], &reference[27..30], &[true]);
        assert_eq!((one.p99, one.rms), (10, 10.0));
        assert_eq!(RgbError::of(&reference, &reference, &seen).rms, 0.0);
    }

    #[test]
    fn spacing_is_a_power_of_two() {
        assert_eq!(spacing(0), 1.0);
        assert_eq!(spacing(-3), 0.125);
        assert_eq!(spacing(5), 32.0);
        assert_eq!(spacing(-40) * spacing(40), 1.0);
    }
}
