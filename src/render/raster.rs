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

use super::trace::{GBuffer, NO_HIT, PrimaryRays};
use crate::cameras::Camera;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Rows of pixels per band: a band is rasterised by one thread from the triangles binned to it.
const BAND: usize = 8;

thread_local! {
    /// Exact (f64) depth of the nearest surface so far at each pixel of the band a thread is
    /// rasterising: kept between bands and views rather than allocated and filled for each.
    static NEAREST: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// A triangle projected into the image: pixel coordinates of its corners and its index in
/// the scene mesh.
#[derive(Clone, Copy)]
struct Projected {
    corners: [DVec2; 3],
    original: u32,
}

/// The geometric buffer of `camera`'s view of `triangles` (world corners with their scene
/// indices), or None when rasterising would not be exact (a distorting lens, or a corner
/// closer to the camera's plane than `near` metres, or behind it). `depth_along(tri, dir)`
/// is the planar depth at which the ray along world `dir` (unit camera z) meets the plane of
/// scene triangle `tri`.
pub(super) fn rasterise(
    camera: &Camera,
    rays: &PrimaryRays,
    triangles: impl Iterator<Item = (u32, [DVec3; 3])>,
    near: f64,
    depth_along: impl Fn(u32, DVec3) -> f64 + Sync,
) -> Option<GBuffer> {
    let k = camera.intrinsics;
    if !k.distortion.is_none() {
        return None;
    }
    let (width, height) = (k.width as usize, k.height as usize);
    let bands = height.div_ceil(BAND);
    let mut binned: Vec<Vec<Projected>> = vec![Vec::new(); bands];
    for (original, corners) in triangles {
        let mut projected = [DVec2::ZERO; 3];
        for (out, corner) in projected.iter_mut().zip(corners) {
            let p = camera.world_to_camera(corner);
            if !(p.z >= near) {
                return None;
            }
            let (u, v) = k.project(p);
            *out = DVec2::new(u, v);
        }
        let Some(rows) = centre_range(span(projected.map(|c| c.y)), height) else {
            continue;
        };
        if centre_range(span(projected.map(|c| c.x)), width).is_none() {
            continue;
        }
        let triangle = Projected {
            corners: projected,
            original,
        };
        for bin in &mut binned[rows.start / BAND..rows.end.div_ceil(BAND)] {
            bin.push(triangle);
        }
    }
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
                let mut covered = usize::MAX..0;
                for t in binned {
                    cover(t, rows.clone(), width, |row, col| {
                        let i = (row - rows.start) * width + col;
                        covered = covered.start.min(i)..covered.end.max(i + 1);
                        let d = depth_along(t.original, rays.through(row, col));
                        let nearer = triangle[i] == NO_HIT
                            || d < nearest[i]
                            || (d == nearest[i] && t.original < triangle[i]);
                        if d > 0.0 && d.is_finite() && nearer {
                            nearest[i] = d;
                            triangle[i] = t.original;
                        }
                    });
                }
                let covered = covered.start.min(covered.end)..covered.end;
                let depth = &mut depth[covered.clone()];
                let nearest = &nearest[covered.clone()];
                for ((out, &d), tri) in depth.iter_mut().zip(nearest).zip(&mut triangle[covered]) {
                    // A depth that leaves f32's range is no surface, as for traced rays.
                    let d = d as f32;
                    if *tri != NO_HIT && d > 0.0 && d.is_finite() {
                        *out = d;
                    } else {
                        *tri = NO_HIT;
                    }
                }
            });
        });
    Some(GBuffer {
        width: k.width,
        height: k.height,
        depth,
        triangle,
    })
}

/// The least and greatest of three coordinates.
fn span(coordinates: [f64; 3]) -> (f64, f64) {
    let [a, b, c] = coordinates;
    (a.min(b).min(c), a.max(b).max(c))
}

/// Pixels whose centre (index + 0.5) lies within `lo..=hi` along one image axis of `size`
/// pixels, or None when there is none.
fn centre_range((lo, hi): (f64, f64), size: usize) -> Option<std::ops::Range<usize>> {
    let first = (lo - 0.5).ceil().max(0.0);
    let last = (hi - 0.5).floor().min(size as f64 - 1.0);
    (first <= last).then(|| first as usize..last as usize + 1)
}

/// Calls `visit(row, col)` for every pixel of `rows` whose centre the triangle covers.
fn cover(
    t: &Projected,
    rows: std::ops::Range<usize>,
    width: usize,
    mut visit: impl FnMut(usize, usize),
) {
    let [a, b, c] = t.corners;
    let edges = [Edge::new(a, b), Edge::new(b, c), Edge::new(c, a)];
    // Which side of each edge the triangle lies on: that of its opposite corner. A corner on
    // the line through the other two: the triangle is seen edge-on, it covers nothing.
    let inside = [
        sign(edges[0].function(c)),
        sign(edges[1].function(a)),
        sign(edges[2].function(b)),
    ];
    if inside.contains(&0) {
        return;
    }
    for row in rows {
        let v = row as f64 + 0.5;
        let Some(cols) = row_span(&t.corners, v, width) else {
            continue;
        };
        for col in cols {
            let p = DVec2::new(col as f64 + 0.5, v);
            if edges.iter().zip(inside).all(|(e, s)| e.side(p) == s) {
                visit(row, col);
            }
        }
    }
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
    centre_range((lo - 1.0, hi + 1.0), width)
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

    /// The side of the line pixel centre `p` is on, +1 or −1: the sign of the edge function,
    /// and where that is exactly zero the sign it takes at `p` nudged by an infinitesimal
    /// step along +u, then +v (∂/∂u = −along.y, ∂/∂v = along.x).
    fn side(&self, p: DVec2) -> i8 {
        match sign(self.function(p)) {
            0 if self.along.y != 0.0 => sign(-self.along.y),
            0 => sign(self.along.x),
            s => s,
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
            let t = Projected {
                corners: *corners,
                original: i as u32,
            };
            cover(&t, 0..size, size, |row, col| count[row * size + col] += 1);
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
    fn edge_on_and_empty_triangles_cover_nothing() {
        let line = [at(1.0, 1.0), at(5.0, 5.0), at(9.0, 9.0)];
        let point = [at(3.0, 3.0); 3];
        assert!(visits(&[line, point], 12).iter().all(|&n| n == 0));
    }

    fn square_facing(camera_z: f64) -> (Camera, Vec<(u32, [DVec3; 3])>) {
        let k = Intrinsics::from_fov_y(32, 32, 1.0);
        let camera = Camera::look_at(k, DVec3::new(0.0, 0.0, camera_z), DVec3::ZERO, DVec3::Y);
        let [a, b, c, d] = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, y)| DVec3::new(x, y, 0.0));
        (camera, vec![(0, [a, b, c]), (1, [a, c, d])])
    }

    /// Planar depth of the plane z = `height` along `dir` from a camera at z = `from`.
    fn plane_at(from: f64, height: f64) -> impl Fn(u32, DVec3) -> f64 + Sync {
        move |_, dir| (height - from) / dir.z
    }

    #[test]
    fn nearer_surfaces_win_and_ties_go_to_the_lower_index() {
        let (camera, square) = square_facing(5.0);
        let rays = PrimaryRays::new(&camera);
        let g = rasterise(
            &camera,
            &rays,
            square.clone().into_iter(),
            1e-3,
            plane_at(5.0, 0.0),
        )
        .unwrap();
        let centre = 16 * 32 + 16;
        assert!((g.depth[centre] - 5.0).abs() < 1e-6);
        // The same square twice, under other indices and in either order: the lower wins.
        for order in [[2u32, 7], [7, 2]] {
            let twice = square.iter().flat_map(|&(i, t)| order.map(|o| (o + i, t)));
            let g = rasterise(&camera, &rays, twice, 1e-3, plane_at(5.0, 0.0)).unwrap();
            assert_ne!(g.triangle[centre], NO_HIT);
            assert!(g.triangle.iter().all(|&t| t == NO_HIT || t == 2 || t == 3));
        }
        // A nearer plane (the copies numbered 2 and 3) hides a farther one whatever the order.
        let (near_plane, far_plane) = (plane_at(5.0, 1.0), plane_at(5.0, 0.0));
        let near = |tri: u32, dir: DVec3| {
            if tri >= 2 {
                near_plane(tri, dir)
            } else {
                far_plane(tri, dir)
            }
        };
        let copies = || square.iter().map(|&(i, t)| (i + 2, t));
        for nearer_first in [false, true] {
            let both: Vec<_> = if nearer_first {
                copies().chain(square.iter().copied()).collect()
            } else {
                square.iter().copied().chain(copies()).collect()
            };
            let g = rasterise(&camera, &rays, both.into_iter(), 1e-3, near).unwrap();
            assert!((g.depth[centre] - 4.0).abs() < 1e-6);
            assert!(g.triangle.iter().all(|&t| t == NO_HIT || t >= 2));
        }
    }

    #[test]
    fn lenses_and_corners_behind_the_camera_are_left_to_ray_tracing() {
        let (camera, square) = square_facing(5.0);
        let rays = PrimaryRays::new(&camera);
        let behind = square
            .iter()
            .map(|&(i, [a, b, c])| (i, [a, b, c + 9.0 * DVec3::Z]));
        assert!(rasterise(&camera, &rays, behind, 1e-3, plane_at(5.0, 0.0)).is_none());
        let mut lens = camera;
        lens.intrinsics.distortion.k1 = -0.01;
        let rays = PrimaryRays::new(&lens);
        assert!(rasterise(&lens, &rays, square.into_iter(), 1e-3, plane_at(5.0, 0.0)).is_none());
    }
}
