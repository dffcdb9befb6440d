//! Primary visibility by rasterisation: which triangle the centre ray of each pixel meets
//! first, found by projecting the triangles into the image instead of walking the BVH once
//! per pixel. For a pinhole camera the centre rays of a view all leave one point, so "the ray
//! through pixel p meets triangle T" is "p lies in T's projection", and the cost follows the
//! pixels the mesh covers, not the pixels of its screen rectangle.
//!
//! Coverage is decided by 2D edge functions in f64 (Pineda, "A parallel algorithm for polygon
//! rasterization", SIGGRAPH 1988) evaluated at pixel centres. An edge shared by two triangles
//! is always evaluated from its two endpoints in one fixed order, so both triangles see the
//! same value and a pixel centre on it belongs to exactly one of them; exact zeros are
//! resolved as for a centre nudged by an infinitesimal step along +u (then +v), a symbolic
//! perturbation (Edelsbrunner & Mücke, ACM TOG 9(1), 1990) under which no centre lies on any
//! edge, so a surface seamed from triangles has neither holes nor double cover, vertices
//! included. Depth is then taken from the hit triangle's plane along the pixel's ray in f64,
//! exactly as the ray tracer does, and of two surfaces the nearer wins (ties: the lower
//! triangle index), so the order triangles are drawn in changes nothing.
//!
//! Used only where it is exact: a lens without distortion, and every vertex in front of the
//! camera (else a triangle's projection is not the set of rays that meet it); otherwise the
//! caller traces rays.
//!
//! Owns: projecting triangles, per-band coverage and the depth test. Must not touch: shading,
//! the BVH or anything after the geometric buffer.

use super::trace::{GBuffer, NO_HIT, PixelSet, PrimaryRays, SampleHits};
use super::visibility::Visibility;
use crate::cameras::Camera;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Rows of pixels per band: a band is rasterised by one thread from the triangles binned to it.
const BAND: usize = 8;

thread_local! {
    /// Exact (f64) depth of the nearest surface so far at each pixel of the band a thread is
    /// rasterising: kept between bands and views rather than allocated and filled for each.
    static NEAREST: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
    /// The triangles binned to each band of the view a thread is rasterising: kept between
    /// views with their capacity, so a large mesh's bins are not allocated (and their pages
    /// faulted in) again for every view.
    static BINS: std::cell::RefCell<Vec<Vec<Projected>>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// A scene triangle as the rasteriser takes it.
pub(super) struct SceneTriangle {
    /// Its index in the scene mesh.
    pub original: u32,
    /// World corners.
    pub corners: [DVec3; 3],
    /// Its plane, seen from the camera.
    pub plane: Plane,
}

/// A triangle's plane as seen from a camera centre o: unit normal n and n · (a − o) for a
/// point a of the plane. The ray from o along d meets it at parameter (n · (a − o)) / (n · d)
/// (infinite when the ray runs along the plane); for d of unit camera z, that is the planar
/// depth.
#[derive(Clone, Copy)]
pub(super) struct Plane {
    /// Unit normal n.
    pub normal: DVec3,
    /// n · (a − o).
    pub ahead: f64,
}

impl Plane {
    /// Ray parameter where the ray from the camera centre along `dir` meets the plane.
    pub fn hit(&self, dir: DVec3) -> f64 {
        self.ahead / self.normal.dot(dir)
    }
}

/// Where in its pixel each sample point lies: offsets from the pixel's corner along u and v,
/// the least and the greatest (a pixel's centre alone: 0.5 and 0.5).
pub(super) struct Samples {
    u: (f64, f64),
    v: (f64, f64),
}

impl Samples {
    /// The pixel centres.
    const CENTRE: Samples = Samples {
        u: (0.5, 0.5),
        v: (0.5, 0.5),
    };

    /// The points at `offsets` within each pixel.
    pub(super) fn at(offsets: &[(f64, f64)]) -> Samples {
        let extent = |pick: fn(&(f64, f64)) -> f64| {
            let along = offsets.iter().map(pick);
            (
                along.clone().fold(f64::INFINITY, f64::min),
                along.fold(f64::NEG_INFINITY, f64::max),
            )
        };
        Samples {
            u: extent(|o| o.0),
            v: extent(|o| o.1),
        }
    }
}

/// A triangle projected into the image: pixel coordinates of its corners, its index in the
/// scene mesh, its plane and the rows and columns of pixel centres within its bounds. The
/// plane travels with it so that depth tests read nothing from the mesh: in a band, triangles
/// come from all over a large mesh, and a look-up by index would miss the cache each time.
#[derive(Clone, Copy)]
struct Projected {
    corners: [DVec2; 3],
    plane: Plane,
    original: u32,
    rows: [u32; 2],
    cols: [u32; 2],
}

impl Projected {
    /// The triangle with corners at image points `corners`, or None when its bounds hold no
    /// sample point of a `width` × `height` image (then it covers none).
    fn new(
        corners: [DVec2; 3],
        plane: Plane,
        original: u32,
        (width, height): (usize, usize),
        samples: &Samples,
    ) -> Option<Self> {
        let rows = sample_range(span(corners.map(|c| c.y)), height, samples.v)?;
        let cols = sample_range(span(corners.map(|c| c.x)), width, samples.u)?;
        let ends = |r: std::ops::Range<usize>| [r.start as u32, r.end as u32];
        Some(Projected {
            corners,
            plane,
            original,
            rows: ends(rows),
            cols: ends(cols),
        })
    }

    /// The rows of pixels with a sample point within the triangle's bounds.
    fn rows(&self) -> std::ops::Range<usize> {
        self.rows[0] as usize..self.rows[1] as usize
    }

    /// The columns of pixels with a sample point within the triangle's bounds.
    fn cols(&self) -> std::ops::Range<usize> {
        self.cols[0] as usize..self.cols[1] as usize
    }
}

/// The geometric buffer of `camera`'s view of `triangles`, or None when rasterising would not
/// be exact (a distorting lens, or a corner closer to the camera's plane than `near` metres,
/// or behind it).
pub(super) fn rasterise(
    camera: &Camera,
    rays: &PrimaryRays,
    triangles: impl Iterator<Item = SceneTriangle>,
    near: f64,
) -> Option<GBuffer> {
    let k = camera.intrinsics;
    if !k.distortion.is_none() {
        return None;
    }
    let (width, height) = (k.width as usize, k.height as usize);
    let mut binned = BINS.with_borrow_mut(std::mem::take);
    binned.iter_mut().for_each(Vec::clear);
    binned.resize_with(height.div_ceil(BAND), Vec::new);
    bin(
        camera,
        triangles,
        near,
        &Samples::CENTRE,
        &mut binned,
        |_| true,
    )?;
    let mut depth = vec![0.0f32; width * height];
    let mut triangle = vec![NO_HIT; width * height];
    depth
        .par_chunks_mut(width * BAND)
        .zip(triangle.par_chunks_mut(width * BAND))
        .zip(binned.par_iter())
        .enumerate()
        .for_each(|(band, ((depth, triangle), binned))| {
            let rows = band * BAND..(band * BAND + BAND).min(height);
            NEAREST.with_borrow_mut(|nearest| {
                // Read only where a triangle is recorded: what it held before does not matter.
                nearest.resize(depth.len(), 0.0);
                // The band's pixels from the first covered to the last: the others stay empty.
                let (mut first, mut end) = (usize::MAX, 0);
                for t in binned {
                    cover(t, rows.clone(), width, |row, col| {
                        let i = (row - rows.start) * width + col;
                        (first, end) = (first.min(i), end.max(i + 1));
                        let d = t.plane.hit(rays.through(row, col));
                        if replaces(d, t.original, (nearest[i], triangle[i])) {
                            nearest[i] = d;
                            triangle[i] = t.original;
                        }
                    });
                }
                let covered = first.min(end)..end;
                let depth = &mut depth[covered.clone()];
                let nearest = &nearest[covered.clone()];
                for ((out, &d), tri) in depth.iter_mut().zip(nearest).zip(&mut triangle[covered]) {
                    match label(d, *tri) {
                        Some((d, _)) => *out = d,
                        None => *tri = NO_HIT,
                    }
                }
            });
        });
    BINS.with_borrow_mut(|bins| *bins = binned);
    Some(GBuffer {
        width: k.width,
        height: k.height,
        depth,
        triangle,
        visibility: Visibility::Rasterised,
    })
}

/// Where the rays through the sample points at `offsets` within each pixel of `pixels` first
/// meet `triangles` (in the order of `pixels`), or None when rasterising would not be exact
/// (see `rasterise`). As for centre rays, "the ray meets T" is "the point lies in T's
/// projection", decided by the same edge functions, and the depth is the plane's along the
/// ray; only bands holding one of `pixels` are rasterised, and in them only those pixels.
pub(super) fn rasterise_samples<const N: usize>(
    camera: &Camera,
    triangles: impl Iterator<Item = SceneTriangle>,
    near: f64,
    pixels: &PixelSet,
    offsets: &[(f64, f64); N],
) -> Option<Vec<SampleHits<N>>> {
    let k = camera.intrinsics;
    if !k.distortion.is_none() {
        return None;
    }
    let height = k.height as usize;
    let band_rows = |band: usize| band * BAND..(band * BAND + BAND).min(height);
    let mut binned = BINS.with_borrow_mut(std::mem::take);
    binned.iter_mut().for_each(Vec::clear);
    binned.resize_with(height.div_ceil(BAND), Vec::new);
    let marked = Marks::of(pixels, k.width as usize, height);
    let samples = Samples::at(offsets);
    // The lines of sample points within a row, from its top.
    let mut lines: Vec<f64> = offsets.iter().map(|o| o.1).collect();
    lines.sort_by(f64::total_cmp);
    lines.dedup();
    bin(camera, triangles, near, &samples, &mut binned, |t| {
        marked.any_in(t.rows(), t.cols())
    })?;
    let mut nearest = vec![[(f64::INFINITY, NO_HIT); N]; pixels.len()];
    let mut rest = nearest.as_mut_slice();
    let mut bands = Vec::with_capacity(binned.len());
    for band in 0..binned.len() {
        let (head, tail) = rest.split_at_mut(pixels.in_rows(band_rows(band)).len());
        bands.push(head);
        rest = tail;
    }
    bands
        .into_par_iter()
        .zip(binned.par_iter())
        .enumerate()
        .for_each(|(band, (nearest, binned))| {
            let rows = band_rows(band);
            let first = pixels.in_rows(rows.clone()).start;
            // The rays as `TraceMesh::first_hit` takes them, for the same depths.
            let rays: Vec<[DVec3; N]> = (first..first + nearest.len())
                .map(|i| {
                    let (row, col) = pixels.at(i);
                    offsets.map(|(du, dv)| camera.rotation * k.ray_through(col + du, row + dv))
                })
                .collect();
            for t in binned {
                let Some(coverage) = Coverage::of(t) else {
                    continue;
                };
                for row in rows.start.max(t.rows().start)..rows.end.min(t.rows().end) {
                    // The row's pixels within the triangle's bounds; of more than a few, only
                    // those about where its sample lines cross the triangle.
                    let mut candidates = pixels.in_row_between(row, t.cols());
                    if candidates.len() > FEW_PIXELS {
                        let Some(cols) = sample_cols(t, row, &lines, k.width as usize) else {
                            continue;
                        };
                        candidates = pixels.in_row_between(row, cols);
                    }
                    for i in candidates {
                        let (v, u) = pixels.at(i);
                        for (s, (du, dv)) in offsets.iter().enumerate() {
                            if coverage.contains(DVec2::new(u + du, v + dv)) {
                                let d = t.plane.hit(rays[i - first][s]);
                                let held = &mut nearest[i - first][s];
                                if replaces(d, t.original, *held) {
                                    *held = (d, t.original);
                                }
                            }
                        }
                    }
                }
            }
        });
    BINS.with_borrow_mut(|bins| *bins = binned);
    Some(
        nearest
            .into_iter()
            .map(|samples| samples.map(|(d, tri)| label(d, tri)))
            .collect(),
    )
}

/// Which pixels of an image are in a `PixelSet`, a bit each, row by row: whether a triangle's
/// bounds hold one is a few word tests.
struct Marks {
    words_per_row: usize,
    bits: Vec<u64>,
}

impl Marks {
    fn of(pixels: &PixelSet, width: usize, height: usize) -> Marks {
        let words_per_row = width.div_ceil(64);
        let mut bits = vec![0u64; words_per_row * height];
        for i in 0..pixels.len() {
            let (row, col) = pixels.at(i);
            let (row, col) = (row as usize, col as usize);
            bits[row * words_per_row + col / 64] |= 1 << (col % 64);
        }
        Marks {
            words_per_row,
            bits,
        }
    }

    /// Whether a pixel of `rows` × `cols` (within the image) is marked.
    fn any_in(&self, rows: std::ops::Range<usize>, cols: std::ops::Range<usize>) -> bool {
        if cols.is_empty() {
            return false;
        }
        let (first, last) = (cols.start / 64, (cols.end - 1) / 64);
        let mask = |word: usize| {
            let low = if word == first {
                !0u64 << (cols.start % 64)
            } else {
                !0
            };
            let high = if word == last {
                !0u64 >> (63 - (cols.end - 1) % 64)
            } else {
                !0
            };
            low & high
        };
        rows.into_iter().any(|row| {
            let line = &self.bits[row * self.words_per_row..][..self.words_per_row];
            (first..=last).any(|w| line[w] & mask(w) != 0)
        })
    }
}

/// Projects `triangles` through `camera` into `bins` (one per band of rows, empty), each
/// triangle that holds a sample point within its bounds and that `keep` keeps into every band
/// its bounds reach; None when a corner is closer to the camera's plane than `near` (see
/// `rasterise`).
fn bin(
    camera: &Camera,
    triangles: impl Iterator<Item = SceneTriangle>,
    near: f64,
    samples: &Samples,
    bins: &mut [Vec<Projected>],
    keep: impl Fn(&Projected) -> bool,
) -> Option<()> {
    let k = camera.intrinsics;
    let size = (k.width as usize, k.height as usize);
    for SceneTriangle {
        original,
        corners,
        plane,
    } in triangles
    {
        let mut projected = [DVec2::ZERO; 3];
        for (out, corner) in projected.iter_mut().zip(corners) {
            let p = camera.world_to_camera(corner);
            if !(p.z >= near) {
                return None;
            }
            let (u, v) = k.project_pinhole(p);
            *out = DVec2::new(u, v);
        }
        let Some(triangle) = Projected::new(projected, plane, original, size, samples) else {
            continue;
        };
        if !keep(&triangle) {
            continue;
        }
        let rows = triangle.rows();
        for bin in &mut bins[rows.start / BAND..rows.end.div_ceil(BAND)] {
            bin.push(triangle);
        }
    }
    Some(())
}

/// The least and greatest of three coordinates.
fn span(coordinates: [f64; 3]) -> (f64, f64) {
    let [a, b, c] = coordinates;
    (a.min(b).min(c), a.max(b).max(c))
}

/// Pixels with a sample point (index + an offset from `offsets.0` to `offsets.1`) within
/// `lo..=hi` along one image axis of `size` pixels, or None when there is none.
fn sample_range(
    (lo, hi): (f64, f64),
    size: usize,
    offsets: (f64, f64),
) -> Option<std::ops::Range<usize>> {
    // Clamped to the image give or take a pixel first (NaN: to the far end, as `max` and
    // `min` take it), where rounding by conversion to an integer is exact.
    let edge = size as f64;
    let first = ceil_small((lo - offsets.1).max(-1.0).min(edge)).max(0);
    let last = floor_small((hi - offsets.0).min(edge).max(-1.0)).min(size as i64 - 1);
    (first <= last).then(|| first as usize..last as usize + 1)
}

/// ⌈x⌉ of an x well inside i64's range: exact, without a call into libm (baseline x86-64
/// has no rounding instruction).
fn ceil_small(x: f64) -> i64 {
    let truncated = x as i64;
    truncated + i64::from((truncated as f64) < x)
}

/// ⌊x⌋ of an x well inside i64's range (see `ceil_small`).
fn floor_small(x: f64) -> i64 {
    let truncated = x as i64;
    truncated - i64::from((truncated as f64) > x)
}

/// Columns of pixel centres up to which a triangle's bounds are tested whole.
const NARROW: usize = 4;

/// Calls `visit(row, col)` for every pixel of `rows` whose centre the triangle covers (only
/// the triangle's own rows are looked at).
fn cover(
    t: &Projected,
    rows: std::ops::Range<usize>,
    width: usize,
    mut visit: impl FnMut(usize, usize),
) {
    let Some(coverage) = Coverage::of(t) else {
        return;
    };
    let (own_rows, own_cols) = (t.rows(), t.cols());
    for row in rows.start.max(own_rows.start)..rows.end.min(own_rows.end) {
        let v = row as f64 + 0.5;
        // Narrow triangles are tested over their bounds; wide ones only about each row's span.
        let cols = if own_cols.len() <= NARROW {
            own_cols.clone()
        } else {
            match row_span(&t.corners, v, width) {
                Some(span) => span.start.max(own_cols.start)..span.end.min(own_cols.end),
                None => continue,
            }
        };
        for col in cols {
            if coverage.contains(DVec2::new(col as f64 + 0.5, v)) {
                visit(row, col);
            }
        }
    }
}

/// Pixels of a row within a triangle's bounds up to which each is tested for sub-pixel
/// samples, rather than first narrowing the columns to where the triangle crosses the row
/// (`sample_cols`, a division per edge and sample line: about the cost of testing two).
const FEW_PIXELS: usize = 4;

/// The columns where triangle `t` may hold a sample point of pixel row `row`, whose sample
/// points lie on `lines` (offsets from the row's top): within its bounds, about where each of
/// those lines crosses it.
fn sample_cols(
    t: &Projected,
    row: usize,
    lines: &[f64],
    width: usize,
) -> Option<std::ops::Range<usize>> {
    let own = t.cols();
    let spans = lines
        .iter()
        .filter_map(|dv| row_span(&t.corners, row as f64 + dv, width));
    let (start, end) = spans.fold((usize::MAX, 0), |(s, e), span| {
        (s.min(span.start), e.max(span.end))
    });
    (start < end).then(|| start.max(own.start)..end.min(own.end))
}

/// The columns a triangle may cover on the line of pixel centres at `v`: between where the
/// line crosses its edges, widened by a pixel each way (the exact test decides within).
fn row_span(corners: &[DVec2; 3], v: f64, width: usize) -> Option<std::ops::Range<usize>> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..3 {
        let (p, q) = (corners[i], corners[(i + 1) % 3]);
        if !(p.y.min(q.y) <= v && v <= p.y.max(q.y)) {
            continue;
        }
        let crossings = if p.y == q.y {
            [p.x, q.x] // the edge lies along the line
        } else {
            [p.x + (v - p.y) * (q.x - p.x) / (q.y - p.y); 2]
        };
        for u in crossings {
            (lo, hi) = (lo.min(u), hi.max(u));
        }
    }
    if lo > hi {
        return None; // the line passes above or below the triangle
    }
    sample_range((lo - 1.0, hi + 1.0), width, Samples::CENTRE.u)
}

/// The three edges of a projected triangle, each turned towards the triangle.
struct Coverage {
    edges: [Inward; 3],
}

impl Coverage {
    /// The triangle's edges, or None when it is seen edge-on (it covers nothing then).
    fn of(t: &Projected) -> Option<Coverage> {
        let [a, b, c] = t.corners;
        let edges = [Edge::new(a, b), Edge::new(b, c), Edge::new(c, a)];
        // Which side of each edge the triangle lies on: that of its opposite corner. A corner
        // on the line through the other two: the triangle is seen edge-on.
        let inside = [
            sign(edges[0].function(c)),
            sign(edges[1].function(a)),
            sign(edges[2].function(b)),
        ];
        if inside.contains(&0) {
            return None;
        }
        let [ab, bc, ca] = edges;
        Some(Coverage {
            edges: [
                Inward::new(ab, inside[0]),
                Inward::new(bc, inside[1]),
                Inward::new(ca, inside[2]),
            ],
        })
    }

    /// Whether the triangle covers image point `p` (on an edge: as nudged by
    /// `Edge::tie_side`).
    fn contains(&self, p: DVec2) -> bool {
        self.edges.iter().all(|e| e.holds(p))
    }
}

/// An edge with the triangle on the positive side of its function: the shared `Edge`'s
/// function, negated where the triangle lies on its negative side. Negating the direction
/// negates the function exactly (round to nearest is symmetric), so the triangles on either
/// side of a shared edge still decide from one value.
struct Inward {
    edge: Edge,
    /// Whether a point exactly on the line counts as inside (see `Edge::tie_side`).
    ties_inside: bool,
}

impl Inward {
    /// `edge` of a triangle lying on its `inside` side (+1 or −1).
    fn new(edge: Edge, inside: i8) -> Inward {
        let ties_inside = edge.tie_side() == inside;
        let along = if inside < 0 { -edge.along } else { edge.along };
        Inward {
            edge: Edge {
                from: edge.from,
                along,
            },
            ties_inside,
        }
    }

    /// Whether `p` is on the triangle's side of the line, or on the line and counted so (a
    /// NaN, as no sign, counts as on it).
    fn holds(&self, p: DVec2) -> bool {
        let f = self.edge.function(p);
        f > 0.0 || (self.ties_inside && !(f < 0.0))
    }
}

/// Whether a hit at ray parameter `d` on triangle `tri` replaces the nearest found so far
/// (`held`; none when its triangle is `NO_HIT`): in front of the camera and finite, and
/// nearer, or as near on a lower triangle index, so the order triangles come in changes
/// nothing.
fn replaces(d: f64, tri: u32, (held_d, held_tri): (f64, u32)) -> bool {
    d > 0.0
        && d.is_finite()
        && (held_tri == NO_HIT || d < held_d || (d == held_d && tri < held_tri))
}

/// The label of the nearest hit found (ray parameter `d` on triangle `tri`, or `NO_HIT`):
/// planar depth and triangle, or None for no surface. A depth that leaves f32's range is no
/// surface, as for traced rays.
fn label(d: f64, tri: u32) -> Option<(f32, u32)> {
    let d = d as f32;
    (tri != NO_HIT && d > 0.0 && d.is_finite()).then_some((d, tri))
}

/// An edge as a line through two image points, always taken from the lesser endpoint (by
/// u, then v) to the greater, so that the two triangles sharing it compute the same values.
struct Edge {
    from: DVec2,
    along: DVec2,
}

impl Edge {
    fn new(p: DVec2, q: DVec2) -> Edge {
        let (from, to) = if (p.x, p.y) <= (q.x, q.y) {
            (p, q)
        } else {
            (q, p)
        };
        Edge {
            from,
            along: to - from,
        }
    }

    /// The edge function at `p`: twice the signed area of the triangle (from, to, p).
    fn function(&self, p: DVec2) -> f64 {
        let d = p - self.from;
        self.along.x * d.y - self.along.y * d.x
    }

    /// The side, +1 or −1, of a point exactly on the line: the sign the edge function takes
    /// there nudged by an infinitesimal step along +u, then +v (∂/∂u = −along.y,
    /// ∂/∂v = along.x).
    fn tie_side(&self) -> i8 {
        if self.along.y != 0.0 {
            sign(-self.along.y)
        } else {
            sign(self.along.x)
        }
    }
}

/// −1, 0 or +1.
fn sign(x: f64) -> i8 {
    i8::from(x > 0.0) - i8::from(x < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cameras::{Camera, Intrinsics};

    /// Visits per pixel of a `size` × `size` image when every triangle is covered.
    fn visits(triangles: &[[DVec2; 3]], size: usize) -> Vec<u32> {
        let mut count = vec![0; size * size];
        for (i, corners) in triangles.iter().enumerate() {
            let plane = plane_at(1.0, 0.0);
            if let Some(t) =
                Projected::new(*corners, plane, i as u32, (size, size), &Samples::CENTRE)
            {
                cover(&t, 0..size, size, |row, col| count[row * size + col] += 1);
            }
        }
        count
    }

    /// A fan of triangles about `centre` through `rim` (closed), all corners on pixel centres.
    fn fan(centre: DVec2, rim: &[DVec2]) -> Vec<[DVec2; 3]> {
        (0..rim.len())
            .map(|i| [centre, rim[i], rim[(i + 1) % rim.len()]])
            .collect()
    }

    fn at(col: f64, row: f64) -> DVec2 {
        DVec2::new(col + 0.5, row + 0.5)
    }

    #[test]
    fn a_seamed_surface_covers_every_centre_inside_exactly_once() {
        // A grid of squares split along alternating diagonals: corners, edges and diagonals all
        // pass through pixel centres.
        let mut grid = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let (x, y) = (2.0 + 3.0 * f64::from(i), 2.0 + 3.0 * f64::from(j));
                let [a, b, c, d] = [
                    at(x, y),
                    at(x + 3.0, y),
                    at(x + 3.0, y + 3.0),
                    at(x, y + 3.0),
                ];
                if (i + j) % 2 == 0 {
                    grid.extend([[a, b, c], [a, c, d]]);
                } else {
                    grid.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        let count = visits(&grid, 20);
        for row in 0..20 {
            for col in 0..20 {
                let inside = (3..14).contains(&row) && (3..14).contains(&col);
                let on_border = (2..15).contains(&row) && (2..15).contains(&col) && !inside;
                let n = count[row * 20 + col];
                match (inside, on_border) {
                    (true, _) => assert_eq!(n, 1, "({row}, {col}) inside"),
                    (_, true) => assert!(n <= 1, "({row}, {col}) on the border"),
                    _ => assert_eq!(n, 0, "({row}, {col}) outside"),
                }
            }
        }
    }

    #[test]
    fn a_vertex_on_a_centre_is_covered_once_by_its_fan_whatever_the_slopes() {
        let c = at(10.0, 10.0);
        // Spokes of slope 0, 1, 2, 1/3, vertical and their mirrors, in both windings.
        let rim = [
            at(16.0, 10.0),
            at(16.0, 16.0),
            at(13.0, 16.0),
            at(10.0, 17.0),
            at(4.0, 12.0),
            at(4.0, 10.0),
            at(7.0, 4.0),
            at(10.0, 3.0),
            at(16.0, 4.0),
        ];
        let reversed: Vec<DVec2> = rim.iter().rev().copied().collect();
        for spokes in [rim.to_vec(), reversed] {
            let count = visits(&fan(c, &spokes), 20);
            assert_eq!(count[10 * 20 + 10], 1, "the shared vertex");
            // Every centre on a spoke (strictly between its ends) once.
            assert_eq!(count[10 * 20 + 13], 1);
            assert_eq!(count[13 * 20 + 13], 1);
            assert_eq!(count[14 * 20 + 10], 1);
            assert_eq!(count[7 * 20 + 10], 1);
            assert!(count.iter().all(|&n| n <= 1), "no centre twice");
            // Every centre strictly inside a triangle of the fan, once.
            for (i, &n) in count.iter().enumerate() {
                let p = at((i % 20) as f64, (i / 20) as f64);
                let strictly_inside = fan(c, &spokes).iter().any(|&[a, b, d]| {
                    let s = [(a, b), (b, d), (d, a)].map(|(x, y)| (y - x).perp_dot(p - x));
                    s.iter().all(|&e| e > 0.0) || s.iter().all(|&e| e < 0.0)
                });
                assert!(!strictly_inside || n == 1, "centre {i}");
            }
        }
    }

    #[test]
    fn an_inexact_shared_edge_through_centres_leaves_no_seam() {
        // Two triangles wound alike share the edge a–b, so each walks it the other way. Its
        // ends lie a fraction of a step beyond the centres c + m·step (fractions binary cannot
        // hold), so the line passes within rounding of those centres; evaluated from each
        // triangle's own end, the edge function rounds differently there and may put a centre
        // inside both triangles or neither (docs/rendering.md §2, "One order per edge").
        let (size, c) = (32, at(16.0, 16.0));
        let mut on_edge = 0;
        for step in [
            (1, 1),
            (1, 2),
            (2, 1),
            (1, 3),
            (3, 1),
            (2, 3),
            (3, -1),
            (1, -2),
            (-2, 3),
        ] {
            let step = DVec2::new(f64::from(step.0), f64::from(step.1));
            for back in [0.1, 0.3, 0.7, 1.0 / 3.0, 0.9] {
                let (a, b) = (c - back * step, c + (3.0 + 0.6 * back) * step);
                let across = 0.5 * step.perp();
                let mid = 0.5 * (a + b);
                let (left, right) = (mid + across, mid - across);
                let quad = [a, right, b, left]; // counter-clockwise: the two triangles' union
                let count = visits(&[[a, b, left], [b, a, right]], size);
                for (i, &n) in count.iter().enumerate() {
                    let p = at((i % size) as f64, (i / size) as f64);
                    // Clearly inside the union: more than 1e-9 inside each outer edge.
                    let margin =
                        |(x, y): (DVec2, DVec2)| (y - x).perp_dot(p - x) / (y - x).length();
                    let inside = (0..4).all(|k| margin((quad[k], quad[(k + 1) % 4])) > 1e-9);
                    on_edge += usize::from(inside && (b - a).perp_dot(p - a).abs() < 1e-9);
                    if inside {
                        assert_eq!(n, 1, "centre {p} inside, shared edge {a}–{b}");
                    } else {
                        assert!(n <= 1, "centre {p} twice, shared edge {a}–{b}");
                    }
                }
            }
        }
        assert!(on_edge >= 100, "only {on_edge} centres on a shared edge");
    }

    #[test]
    fn sample_ranges_round_as_libm_does() {
        // The range as written with libm's ceil and floor: pixels i with i + o in lo..=hi for
        // some offset o between the two.
        let libm = |(lo, hi): (f64, f64), size: usize, (o0, o1): (f64, f64)| {
            let first = (lo - o1).ceil().max(0.0);
            let last = (hi - o0).floor().min(size as f64 - 1.0);
            (first <= last).then(|| first as usize..last as usize + 1)
        };
        let mut ends = vec![f64::NAN, -1e300, -7.0, 1e300, f64::INFINITY, -f64::INFINITY];
        for i in -40..=120 {
            let x = f64::from(i) / 8.0;
            ends.extend([x, x.next_up(), x.next_down(), -0.0]);
        }
        for offsets in [(0.5, 0.5), (0.25, 0.75), (0.125, 0.875)] {
            for &lo in &ends {
                for &hi in &ends {
                    for size in [1, 9, 12] {
                        assert_eq!(
                            sample_range((lo, hi), size, offsets),
                            libm((lo, hi), size, offsets),
                            "{lo}..{hi} in {size}, offsets {offsets:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn edge_on_and_empty_triangles_cover_nothing() {
        let line = [at(1.0, 1.0), at(5.0, 5.0), at(9.0, 9.0)];
        let point = [at(3.0, 3.0); 3];
        assert!(visits(&[line, point], 12).iter().all(|&n| n == 0));
    }

    /// Two triangles making the square from (−1, −1) to (1, 1) at z = 0, seen from a camera
    /// at z = `camera_z` looking down the z axis.
    fn square_facing(camera_z: f64) -> (Camera, Vec<(u32, [DVec3; 3])>) {
        let k = Intrinsics::from_fov_y(32, 32, 1.0);
        let camera = Camera::look_at(k, DVec3::new(0.0, 0.0, camera_z), DVec3::ZERO, DVec3::Y);
        let [a, b, c, d] = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, y)| DVec3::new(x, y, 0.0));
        (camera, vec![(0, [a, b, c]), (1, [a, c, d])])
    }

    /// The plane z = `height` seen from a camera at z = `from`.
    fn plane_at(from: f64, height: f64) -> Plane {
        Plane {
            normal: DVec3::Z,
            ahead: height - from,
        }
    }

    /// Scene triangles (index, corners) all in `plane`.
    fn in_plane(
        triangles: impl IntoIterator<Item = (u32, [DVec3; 3])>,
        plane: Plane,
    ) -> impl Iterator<Item = SceneTriangle> {
        triangles
            .into_iter()
            .map(move |(original, corners)| SceneTriangle {
                original,
                corners,
                plane,
            })
    }

    #[test]
    fn nearer_surfaces_win_and_ties_go_to_the_lower_index() {
        let (camera, square) = square_facing(5.0);
        let rays = PrimaryRays::new(&camera);
        let g = rasterise(
            &camera,
            &rays,
            in_plane(square.clone(), plane_at(5.0, 0.0)),
            1e-3,
        )
        .unwrap();
        let centre = 16 * 32 + 16;
        assert!((g.depth[centre] - 5.0).abs() < 1e-6);
        // The same square twice, under other indices and in either order: the lower wins.
        for order in [[2u32, 7], [7, 2]] {
            let twice = square.iter().flat_map(|&(i, t)| order.map(|o| (o + i, t)));
            let g = rasterise(&camera, &rays, in_plane(twice, plane_at(5.0, 0.0)), 1e-3).unwrap();
            assert_ne!(g.triangle[centre], NO_HIT);
            assert!(g.triangle.iter().all(|&t| t == NO_HIT || t == 2 || t == 3));
        }
        // A nearer plane (the copies numbered 2 and 3) hides a farther one whatever the order.
        let nearer = || {
            let copies = square.iter().map(|&(i, t)| (i + 2, t));
            in_plane(copies, plane_at(5.0, 1.0))
        };
        let farther = || in_plane(square.clone(), plane_at(5.0, 0.0));
        for nearer_first in [false, true] {
            let both: Vec<_> = if nearer_first {
                nearer().chain(farther()).collect()
            } else {
                farther().chain(nearer()).collect()
            };
            let g = rasterise(&camera, &rays, both.into_iter(), 1e-3).unwrap();
            assert!((g.depth[centre] - 4.0).abs() < 1e-6);
            assert!(g.triangle.iter().all(|&t| t == NO_HIT || t >= 2));
        }
    }

    #[test]
    fn lenses_and_corners_behind_the_camera_are_left_to_ray_tracing() {
        let (camera, square) = square_facing(5.0);
        let rays = PrimaryRays::new(&camera);
        let plane = plane_at(5.0, 0.0);
        let behind = square
            .iter()
            .map(|&(i, [a, b, c])| (i, [a, b, c + 9.0 * DVec3::Z]));
        assert!(rasterise(&camera, &rays, in_plane(behind, plane), 1e-3).is_none());
        let mut lens = camera;
        lens.intrinsics.distortion.k1 = -0.01;
        let rays = PrimaryRays::new(&lens);
        assert!(rasterise(&lens, &rays, in_plane(square, plane), 1e-3).is_none());
    }
}
