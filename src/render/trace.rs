//! BVH construction and primary-ray tracing into a geometric buffer (handing pinhole views
//! of a mesh in front of the camera to `raster`, which finds the same first hits).

use super::raster::{Plane, SceneTriangle, rasterise, rasterise_samples};
use super::tiles::{PixelRect, TILE, visible_tiles};
use super::visibility::Visibility;
use super::watertight::ShearedRay;
use crate::cameras::Camera;
use crate::geometry::Mesh;
use glam::{DVec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::bvh2::{Bvh2, builder::build_bvh2_from_tris};
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use rayon::prelude::*;
use std::sync::OnceLock;
use std::time::Duration;

/// Triangle id of a pixel that saw no surface.
pub const NO_HIT: u32 = u32::MAX;

/// What the rays through a pixel's N sample points first meet: planar depth and triangle,
/// None for a ray that meets nothing.
pub type SampleHits<const N: usize> = [Option<(f32, u32)>; N];

/// A mesh ready for tracing. Vertices are stored in f32 relative to `anchor` (the centre of
/// the structures' bounds, a ground left out), so geometry far from the world origin keeps its
/// precision, and a ground however far below changes neither the anchor nor the structures'
/// f32 corners; rays start in f32 only where they enter the mesh's bounding sphere, so a
/// camera far away (a narrow field of view) loses nothing either. Depths come from each
/// triangle's plane in f64.
///
/// The BVH is built when a ray is first traced: views the rasteriser sees in full (every
/// pinhole view in front of a mesh, with rasterised sub-pixel rays and no shadows) never walk
/// it, and a 10⁶-triangle mesh's build costs as much as several of its views.
pub struct TraceMesh {
    /// Corners of each triangle, relative to `anchor`, in the mesh's order.
    corners: Vec<Triangle>,
    /// The plane of each triangle.
    planes: Vec<PlaneEquation>,
    /// The closed solid (`Mesh::solids`) each triangle belongs to.
    solids: Vec<u32>,
    /// Bounds of each solid, relative to `anchor`: a camera outside them is outside it.
    solid_bounds: Vec<(DVec3, DVec3)>,
    /// The BVH over `corners`, built on first use.
    tree: OnceLock<Tree>,
    /// Centre of the structures' bounds: the origin of `corners`, `planes` and the rays.
    anchor: DVec3,
    /// Radius about `anchor` of a sphere holding every vertex.
    reach: f64,
    /// Diagonal of the bounds of the structures' triangles (all but a ground's), metres: the
    /// scale shadow rays leave surfaces by.
    core_diagonal: f64,
    /// Those bounds, relative to `anchor` and grown by a millionth of the diagonal: a shadow
    /// or occlusion ray that misses them can meet nothing but the ground, which never blocks
    /// one (see `occluded_within`).
    core_bounds: (DVec3, DVec3),
}

/// A BVH and its triangles in leaf order, where traversal reads them.
struct Tree {
    bvh: Bvh2,
    /// Corners of each leaf's triangle.
    triangles: Vec<[Vec3A; 3]>,
    /// The mesh's index of each leaf's triangle.
    original: Vec<u32>,
}

impl Tree {
    /// Builds the BVH of `corners` (one thread: the build may run inside a pool's task).
    fn build(corners: &[Triangle]) -> Tree {
        let bvh = build_bvh2_from_tris(
            corners,
            build_params(corners.len()),
            &mut Duration::default(),
        );
        Tree {
            triangles: bvh
                .primitive_indices
                .iter()
                .map(|&i| {
                    let t = &corners[i as usize];
                    [t.v0, t.v1, t.v2]
                })
                .collect(),
            original: bvh.primitive_indices.clone(),
            bvh,
        }
    }
}

/// A triangle's plane: outward unit normal n (zero for a degenerate triangle) and n · a for
/// its first corner a, relative to the mesh's anchor.
#[derive(Clone, Copy)]
struct PlaneEquation {
    normal: DVec3,
    offset: f64,
}

impl PlaneEquation {
    /// The plane seen from `origin` (relative to the anchor).
    fn seen_from(&self, origin: DVec3) -> Plane {
        Plane {
            normal: self.normal,
            ahead: self.offset - self.normal.dot(origin),
        }
    }
}

/// Triangles per pixel above which a view is traced rather than rasterised: most triangles of
/// a mesh this fine cover no pixel centre, and projecting them all costs more than walking the
/// BVH once per pixel. Measured on the benchmark's 10⁶-triangle torus, one thread, ms per view
/// rasterised against traced: 960² (1.1 triangles per pixel) about 60 faster; 640² (2.4) 10
/// faster; 480² (4.3) 10 slower.
const RASTER_LIMIT: usize = 3;

/// Triangles per sub-pixel ray up to which the rays' hits are rasterised rather than traced:
/// rasterising costs about the projection of every triangle, tracing a BVH walk per ray. On
/// the benchmark's 10⁶-triangle torus (one thread, 960², 37,000–68,000 anti-aliased pixels
/// of four rays each) the two break even at about seven triangles per ray: rasterised 90–156
/// ms per view, traced 106–279 ms.
const TRIANGLES_PER_RAY: usize = 8;

/// Triangles above which a BVH is built for speed rather than quality.
const LARGE_MESH: usize = 200_000;

/// How hard to work on a BVH of `triangles` triangles. Past `LARGE_MESH` the build outweighs
/// what a better tree saves over a sample's views: on a 10⁶-triangle torus at 960×960, obvhs'
/// fast build takes 425 ms against the medium build's 566 ms, and its views trace no slower
/// (154 against 166 ms). Both are deterministic (obvhs without its `parallel` feature).
fn build_params(triangles: usize) -> BvhBuildParams {
    if triangles > LARGE_MESH {
        BvhBuildParams::fast_build()
    } else {
        BvhBuildParams::medium_build()
    }
}

/// obvhs' slab test replaces direction components below f32::EPSILON by ±1/EPSILON, i.e. it
/// traverses a slightly tilted ray and can cull the box whose triangle the exact test would
/// accept (seen for a camera exactly below a beam). Zeroing those components makes traversal
/// and the watertight test follow the same ray; the tilt dropped is below 1.2e-7 rad.
fn traversal_direction(d: Vec3A) -> Vec3A {
    Vec3A::select(d.abs().cmplt(Vec3A::splat(f32::EPSILON)), Vec3A::ZERO, d)
}

/// Per-pixel geometric labels of one view: planar depth (0 = no surface) and the original
/// index of the triangle hit (`NO_HIT` = none). Row-major, `width` × `height`.
pub struct GBuffer {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Planar depth of every pixel, metres (0 = no surface).
    pub depth: Vec<f32>,
    /// Index of the triangle each pixel sees, in the scene mesh (`NO_HIT` = none).
    pub triangle: Vec<u32>,
    /// How the first surfaces were found.
    pub visibility: Visibility,
}

/// Some pixels of an image, row by row, each row's columns ascending.
pub struct PixelSet {
    /// Where each row's pixels start in `rows` and `cols`, and (last) where they end.
    starts: Vec<usize>,
    rows: Vec<u32>,
    cols: Vec<u32>,
}

impl PixelSet {
    /// The pixels of `columns[row]` in each row (columns ascending).
    pub fn from_rows(columns: &[Vec<u32>]) -> PixelSet {
        let mut starts = Vec::with_capacity(columns.len() + 1);
        let (mut rows, mut cols) = (Vec::new(), Vec::new());
        for (row, line) in columns.iter().enumerate() {
            debug_assert!(line.windows(2).all(|w| w[0] < w[1]));
            starts.push(cols.len());
            rows.extend(std::iter::repeat_n(row as u32, line.len()));
            cols.extend(line);
        }
        starts.push(cols.len());
        PixelSet { starts, rows, cols }
    }

    /// How many pixels.
    pub fn len(&self) -> usize {
        self.cols.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.cols.is_empty()
    }

    /// Row and column of pixel `i`, as image coordinates of the pixel's corner.
    pub fn at(&self, i: usize) -> (f64, f64) {
        (f64::from(self.rows[i]), f64::from(self.cols[i]))
    }

    /// The indices of the pixels in `rows`.
    pub fn in_rows(&self, rows: std::ops::Range<usize>) -> std::ops::Range<usize> {
        let clamp = |r: usize| self.starts[r.min(self.starts.len() - 1)];
        clamp(rows.start)..clamp(rows.end)
    }

    /// The indices of the pixels of `row` whose columns lie in `cols`.
    pub fn in_row_between(
        &self,
        row: usize,
        cols: std::ops::Range<usize>,
    ) -> std::ops::Range<usize> {
        let all = self.in_rows(row..row + 1);
        let line = &self.cols[all.clone()];
        let from = |col: usize| all.start + line.partition_point(|&c| (c as usize) < col);
        from(cols.start)..from(cols.end)
    }
}

/// A mesh ready for tracing: the unloaded twin of a sample's mesh, traced for the unloaded
/// image.
pub struct Traced {
    /// The mesh.
    pub mesh: Mesh,
    /// The mesh prepared for tracing (its BVH built when a ray first needs one).
    pub trace_mesh: TraceMesh,
}

impl Traced {
    /// `mesh`'s triangles over other positions of its vertices (the unloaded ones, in the
    /// same order), ready for tracing; the first `core` triangles are the structures (see
    /// [`TraceMesh::build_with_core`]).
    pub fn with_positions(mesh: &Mesh, positions: &[DVec3], core: usize) -> Self {
        let mesh = Mesh {
            positions: positions.to_vec(),
            triangles: mesh.triangles.clone(),
        };
        let trace_mesh = TraceMesh::build_with_core(&mesh, core);
        Traced { mesh, trace_mesh }
    }
}

impl TraceMesh {
    /// Prepares `mesh` for tracing (its BVH is built on first use). The mesh must be
    /// non-empty with finite vertices (checked upstream).
    pub fn build(mesh: &Mesh) -> Self {
        Self::build_with_core(mesh, mesh.triangles.len())
    }

    /// Prepares a mesh whose first `core` triangles are the structures and the rest a
    /// ground far larger than them: the anchor is the structures' centre, so their f32
    /// corners (and every hit on them) are those of the structures traced alone wherever the
    /// ground lies; shadow rays leave a surface by a step scaled to the structures near the
    /// anchor, and to the distance from it far out on the ground, where f32 coordinates are
    /// coarser.
    pub fn build_with_core(mesh: &Mesh, core: usize) -> Self {
        let (lo, hi) = mesh.bounds().expect("scene mesh is non-empty");
        let (core_lo, core_hi) = if core == mesh.triangles.len() {
            (lo, hi)
        } else {
            mesh.triangles[..core]
                .iter()
                .flat_map(|t| t.map(|i| mesh.positions[i as usize]))
                .fold((hi, lo), |(l, h), p| (l.min(p), h.max(p)))
        };
        // The centre of the whole bounds would follow a ground 10⁷ m below half way down,
        // where f32 steps are half a metre: the structures would be quantised to that.
        let anchor = 0.5 * (core_lo + core_hi);
        let local = |i: u32| (mesh.positions[i as usize] - anchor).as_vec3a();
        let corners: Vec<Triangle> = mesh
            .triangles
            .iter()
            .map(|t| Triangle {
                v0: local(t[0]),
                v1: local(t[1]),
                v2: local(t[2]),
            })
            .collect();
        let planes: Vec<PlaneEquation> = (0..mesh.triangles.len())
            .map(|t| {
                let [a, b, c] = mesh.triangle(t);
                let normal = (b - a).cross(c - a).normalize_or_zero();
                PlaneEquation {
                    normal,
                    offset: normal.dot(a - anchor),
                }
            })
            .collect();
        let solids = mesh.solids();
        let mut solid_bounds = vec![(DVec3::INFINITY, DVec3::NEG_INFINITY); solids.count];
        for (t, &solid) in solids.of_triangle.iter().enumerate() {
            if let Some((lo, hi)) = solid_bounds.get_mut(solid as usize) {
                for p in mesh.triangle(t) {
                    (*lo, *hi) = (lo.min(p - anchor), hi.max(p - anchor));
                }
            }
        }
        TraceMesh {
            corners,
            planes,
            solids: solids.of_triangle,
            solid_bounds,
            tree: OnceLock::new(),
            anchor,
            reach: reach_about(anchor, (lo, hi)),
            core_diagonal: (core_hi - core_lo).length(),
            core_bounds: {
                let margin = DVec3::splat(1e-6 * (core_hi - core_lo).length());
                (core_lo - anchor - margin, core_hi - anchor + margin)
            },
        }
    }

    /// Builds the BVH now rather than when the first ray is traced, so that its cost can be
    /// timed apart (the benchmarks do).
    pub fn build_bvh(&self) {
        self.tree();
    }

    /// The BVH, built on first use.
    fn tree(&self) -> &Tree {
        self.tree.get_or_init(|| Tree::build(&self.corners))
    }

    /// Ray parameter where the ray from world point `origin` along `dir` meets the plane of
    /// `original_triangle`, in f64: infinite when the ray runs along the plane.
    pub fn plane_hit(&self, original_triangle: u32, origin: DVec3, dir: DVec3) -> f64 {
        self.plane_from(original_triangle, origin).hit(dir)
    }

    /// The plane of `original_triangle` seen from world point `origin`.
    fn plane_from(&self, original_triangle: u32, origin: DVec3) -> Plane {
        self.planes[original_triangle as usize].seen_from(origin - self.anchor)
    }

    /// Unit normal of a triangle of the scene mesh (by its original index), following its
    /// winding; zero for a degenerate triangle.
    pub fn normal(&self, original_triangle: u32) -> DVec3 {
        self.planes[original_triangle as usize].normal
    }

    /// The first surface along the centre ray of every pixel: rasterised where that is exact
    /// (see `raster`), else traced.
    pub fn trace(&self, camera: &Camera) -> GBuffer {
        let rays = PrimaryRays::new(camera);
        let k = camera.intrinsics;
        let pixels = k.width as usize * k.height as usize;
        if self.corners.len() > RASTER_LIMIT * pixels {
            return self.trace_rays_along(camera, &rays);
        }
        rasterise(camera, &rays, self.seen_by(camera), self.near())
            .unwrap_or_else(|| self.trace_rays_along(camera, &rays))
    }

    /// Planar depth and triangle first met by the ray through each point at `offsets` within
    /// each of `pixels` (image coordinates from the pixel's corner), in the order of
    /// `pixels`: rasterised where that is exact and costs less than the rays (see `raster`),
    /// else traced, giving the hits `first_hit` gives; and which of the two ran.
    pub fn sample_hits<const N: usize>(
        &self,
        camera: &Camera,
        pixels: &PixelSet,
        offsets: &[(f64, f64); N],
    ) -> (Vec<SampleHits<N>>, Visibility) {
        if self.corners.len() <= TRIANGLES_PER_RAY * N * pixels.len() {
            let seen = self.seen_by(camera);
            if let Some(hits) = rasterise_samples(camera, seen, self.near(), pixels, offsets) {
                return (hits, Visibility::Rasterised);
            }
        }
        let k = camera.intrinsics;
        let hits = (0..pixels.len())
            .into_par_iter()
            .map(|i| {
                let (row, col) = pixels.at(i);
                offsets.map(|(du, dv)| self.first_hit(camera, k.ray_through(col + du, row + dv)))
            })
            .collect();
        (hits, Visibility::Traced)
    }

    /// The triangles as the rasteriser takes them from `camera`, in the mesh's order, but
    /// those of a closed solid that the camera, outside it, sees from behind: a ray meeting
    /// one has met one of the solid's triangles facing it first, nearer (see `Mesh::solids`).
    /// Only triangles clearly turned away are left out (by more than a billionth of the
    /// scene's scale, far above the plane's rounding), so one seen edge-on always stays.
    fn seen_by<'a>(&'a self, camera: &Camera) -> impl Iterator<Item = SceneTriangle> + 'a {
        let from = camera.position - self.anchor;
        let margin = 1e-9 * (from.length() + self.reach);
        let outside: Vec<bool> = self
            .solid_bounds
            .iter()
            .map(|&(lo, hi)| {
                let grown = DVec3::splat(margin);
                from.cmplt(lo - grown).any() || from.cmpgt(hi + grown).any()
            })
            .collect();
        (0u32..)
            .zip(&self.corners)
            .zip(&self.planes)
            .zip(&self.solids)
            .filter_map(move |(((original, corners), plane), &solid)| {
                let plane = plane.seen_from(from);
                let behind = plane.ahead > margin && outside.get(solid as usize) == Some(&true);
                (!behind).then(|| SceneTriangle {
                    original,
                    corners: [corners.v0, corners.v1, corners.v2]
                        .map(|c| c.as_dvec3() + self.anchor),
                    plane,
                })
            })
    }

    /// Closer than this to the camera's plane, a corner's projection loses its precision.
    fn near(&self) -> f64 {
        1e-3 * self.reach
    }

    /// Traces one centre ray per pixel (never rasterised), in the tiles where the BVH's boxes
    /// may be seen only.
    pub fn trace_rays(&self, camera: &Camera) -> GBuffer {
        self.trace_rays_along(camera, &PrimaryRays::new(camera))
    }

    fn trace_rays_along(&self, camera: &Camera, rays: &PrimaryRays) -> GBuffer {
        let k = camera.intrinsics;
        let (w, h) = (k.width as usize, k.height as usize);
        let mut depth = vec![0.0f32; w * h];
        let mut triangle = vec![NO_HIT; w * h];
        let tiles = visible_tiles(&self.tree().bvh, camera, |lo, hi| {
            self.box_bounds(camera, lo, hi)
        });
        let origin = camera.position - self.anchor;
        depth
            .par_chunks_mut(w * TILE)
            .zip(triangle.par_chunks_mut(w * TILE))
            .enumerate()
            .for_each(|(band, (depth_band, tri_band))| {
                for tile in tiles.row(band) {
                    let cols = tile * TILE..((tile + 1) * TILE).min(w);
                    for (r, row) in (band * TILE..h).take(depth_band.len() / w).enumerate() {
                        for col in cols.clone() {
                            if let Some((t, tri)) = self.closest_hit(origin, rays.through(row, col))
                            {
                                depth_band[r * w + col] = t;
                                tri_band[r * w + col] = tri;
                            }
                        }
                    }
                }
            });
        GBuffer {
            width: k.width,
            height: k.height,
            depth,
            triangle,
            visibility: Visibility::Traced,
        }
    }

    /// Planar depth and triangle first hit along `view` (camera axes, unit z), if any.
    pub fn first_hit(&self, camera: &Camera, view: DVec3) -> Option<(f32, u32)> {
        self.closest_hit(camera.position - self.anchor, camera.rotation * view)
    }

    /// The triangle first met by the ray from world point `origin` along `dir`, and where the
    /// ray meets that triangle's plane (f64, world): the BVH picks the triangle in f32, its
    /// plane places the point.
    pub fn first_along(&self, origin: DVec3, dir: DVec3) -> Option<(u32, DVec3)> {
        let (_, tri) = self.closest_hit(origin - self.anchor, dir)?;
        let t = self.plane_hit(tri, origin, dir);
        t.is_finite().then(|| (tri, origin + t * dir))
    }

    /// Whether anything blocks the way from surface point `p` (world) with outward `normal`
    /// towards `direction`. The ray starts a little off the surface so that it cannot hit the
    /// triangle it leaves.
    pub fn occluded(&self, p: DVec3, normal: DVec3, direction: DVec3) -> bool {
        self.occluded_within(p, normal, direction, f64::INFINITY)
    }

    /// Whether anything blocks the way from `p` towards unit `direction` closer than `reach`
    /// (metres; infinite for any distance), the ray leaving the surface as in `occluded`.
    pub fn occluded_within(&self, p: DVec3, normal: DVec3, direction: DVec3, reach: f64) -> bool {
        // Without a ground the core is the whole mesh, and no point is farther from the anchor
        // than half its diagonal.
        let lift = 1e-5 * self.core_diagonal.max((p - self.anchor).length());
        let start = p - self.anchor + lift * normal;
        // Rays towards the sun and the sky rise, and rays down to a ground stop at it
        // (`reach`), so a ground never blocks: a ray that misses the structures' bounds is
        // free. Most of a ground's pixels are decided here, without entering the BVH.
        if !ray_meets_box(start, direction, reach, self.core_bounds) {
            return false;
        }
        let origin = start.as_vec3a();
        let dir = traversal_direction(direction.as_vec3a());
        let sheared = ShearedRay::new(origin, dir);
        let ray = Ray::new(origin, dir, 0.0, reach as f32);
        // Stops at the first blocker found.
        let tree = self.tree();
        !tree.bvh.ray_traverse_miss(ray, |r, id| {
            let [a, b, c] = tree.triangles[id];
            sheared.intersect(a, b, c, r.tmax)
        })
    }

    /// Whether every ray from world point `p` whose unit direction rises by at least `rise`
    /// (its z, above 0) surely misses the structures' bounds, so that `occluded_within` finds
    /// it free (a ground never blocks): seen from `p`, the bounds' top lies lower than that
    /// rise climbs over the horizontal distance to them. The bounds are grown by a millionth
    /// of the scene's scale beyond the slab test's, for its rounding; lifting the ray off the
    /// surface only raises it.
    pub fn rises_clear_of_structures(&self, p: DVec3, rise: f64) -> bool {
        let q = p - self.anchor;
        let slack = 1e-6 * (self.core_diagonal + q.length());
        let (lo, hi) = self.core_bounds;
        let outside = |x: f64, lo: f64, hi: f64| (lo - slack - x).max(x - hi - slack).max(0.0);
        let (dx, dy) = (outside(q.x, lo.x, hi.x), outside(q.y, lo.y, hi.y));
        let climb = hi.z + slack - q.z;
        let slope = rise / (1.0 - rise * rise).max(0.0).sqrt();
        rise > 0.0 && climb < (dx * dx + dy * dy).sqrt() * slope
    }

    /// Planar depth and original triangle of the first surface along `dir` (unit camera z)
    /// from `origin` (relative to the anchor). The f32 ray starts where the ray enters the
    /// mesh's bounding sphere, so its origin is as precise as the vertices however far the
    /// camera is; the depth is then taken from the hit triangle's plane in f64.
    fn closest_hit(&self, origin: DVec3, dir: DVec3) -> Option<(f32, u32)> {
        let skip = self.entry(origin, dir)?;
        let start = (origin + skip * dir).as_vec3a();
        let dir32 = traversal_direction(dir.as_vec3a());
        let sheared = ShearedRay::new(start, dir32);
        let ray = Ray::new(start, dir32, 0.0, f32::INFINITY);
        let mut hit = RayHit::none();
        let tree = self.tree();
        let found = tree.bvh.ray_traverse(ray, &mut hit, |r, id| {
            let [a, b, c] = tree.triangles[id];
            sheared.intersect(a, b, c, r.tmax)
        });
        if !found {
            return None;
        }
        let tri = tree.original[hit.primitive_id as usize];
        let refined = self.plane_hit(tri, origin + self.anchor, dir);
        let t = if refined.is_finite() && refined > 0.0 {
            refined
        } else {
            skip + f64::from(hit.t)
        } as f32;
        (t > 0.0 && t.is_finite()).then_some((t, tri))
    }

    /// How far along `dir` (in its own units) the ray from `origin` (relative to the anchor)
    /// can skip before it could meet the mesh: up to just short of the bounding sphere, or
    /// nothing when it starts inside. None when it misses the sphere.
    fn entry(&self, origin: DVec3, dir: DVec3) -> Option<f64> {
        let length = dir.length();
        let unit = dir / length;
        let along = -origin.dot(unit);
        // The closest approach by its offset vector: no difference of squared distances, so a
        // camera far away keeps the precision of the offset.
        let miss = (origin + along * unit).length_squared();
        let reach = self.reach * (1.0 + 1e-6) + 1e-9;
        if miss > reach * reach {
            return None;
        }
        let half_chord = (reach * reach - miss).sqrt();
        let near = along - half_chord - 1e-3 * reach;
        Some(near.max(0.0) / length)
    }

    /// Pixel rows and columns where the box from `lo` to `hi` (relative to the anchor) may
    /// be seen: its projection, widened by a pixel; None when a corner is at or behind the
    /// camera.
    fn box_bounds(&self, camera: &Camera, lo: DVec3, hi: DVec3) -> Option<PixelRect> {
        let k = camera.intrinsics;
        // A distorting lens bends the box's edges in the image: follow them point by point
        // and widen by the sagitta left between the points.
        let (steps, margin) = if k.distortion.is_none() {
            (1, 1.0)
        } else {
            (64, 4.0)
        };
        let (mut u0, mut v0, mut u1, mut v1) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for point in box_outline(lo, hi, steps) {
            let p = camera.world_to_camera(point + self.anchor);
            if p.z <= 1e-9 {
                return None;
            }
            let (u, v) = k.project(p);
            (u0, v0, u1, v1) = (u0.min(u), v0.min(v), u1.max(u), v1.max(v));
        }
        if !(u0.is_finite() && v0.is_finite() && u1.is_finite() && v1.is_finite()) {
            return None;
        }
        let clamp = |x: f64, n: u32| x.clamp(0.0, f64::from(n)) as usize;
        Some((
            clamp(v0.floor() - margin, k.height)..clamp(v1.ceil() + margin, k.height),
            clamp(u0.floor() - margin, k.width)..clamp(u1.ceil() + margin, k.width),
        ))
    }
}

/// Radius of a sphere about `anchor` holding the box `(lo, hi)`: its half diagonal plus the
/// anchor's distance from its centre (exactly the half diagonal for an anchor at the centre).
fn reach_about(anchor: DVec3, (lo, hi): (DVec3, DVec3)) -> f64 {
    0.5 * (hi - lo).length() + (anchor - 0.5 * (lo + hi)).length()
}

/// Points along the twelve edges of the box from `lo` to `hi`, each edge cut into `steps`
/// (its corners alone when `steps` is 1).
fn box_outline(lo: DVec3, hi: DVec3, steps: u32) -> impl Iterator<Item = DVec3> {
    let corner = move |i: u32| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let corners = (steps == 1)
        .then(|| (0..8).map(corner))
        .into_iter()
        .flatten();
    let edges = (0..8u32)
        .flat_map(|i| [1, 2, 4].map(|bit| (i, bit)))
        .filter(move |&(i, bit)| steps > 1 && i & bit == 0)
        .flat_map(move |(i, bit)| {
            let (a, b) = (corner(i), corner(i | bit));
            (0..=steps).map(move |step| a + (b - a) * (f64::from(step) / f64::from(steps)))
        });
    corners.chain(edges)
}

/// The centre-ray directions of a camera's pixels (world axes, unit camera z). For a pinhole
/// the camera-axes direction is (x(col), y(row), 1), so the rotation's products with x and y
/// are taken once per column and row, and summed as `DMat3 * DVec3` sums them: the same bits.
pub(super) struct PrimaryRays<'a> {
    camera: &'a Camera,
    /// Per column, rotation column x times x; per row, rotation column y times y (pinhole).
    pinhole: Option<(Vec<DVec3>, Vec<DVec3>)>,
}

impl<'a> PrimaryRays<'a> {
    pub(super) fn new(camera: &'a Camera) -> Self {
        let k = camera.intrinsics;
        let r = camera.rotation;
        let pinhole = k.distortion.is_none().then(|| {
            let x = (0..k.width).map(|c| r.x_axis * k.ray_through_pixel(0, c).x);
            let y = (0..k.height).map(|row| r.y_axis * k.ray_through_pixel(row, 0).y);
            (x.collect(), y.collect())
        });
        PrimaryRays { camera, pinhole }
    }

    /// The direction through the centre of pixel (`row`, `col`).
    pub(super) fn through(&self, row: usize, col: usize) -> DVec3 {
        match &self.pinhole {
            Some((x, y)) => x[col] + y[row] + self.camera.rotation.z_axis,
            None => {
                let k = self.camera.intrinsics;
                self.camera.rotation * k.ray_through_pixel(row as u32, col as u32)
            }
        }
    }
}

/// Whether the ray from `origin` along `direction` meets the box `(lo, hi)` within `reach`
/// (the slab test, Kay & Kajiya 1986): the largest entry along the axes before the smallest
/// exit. An axis the ray runs parallel to is met only from inside its slab.
fn ray_meets_box(origin: DVec3, direction: DVec3, reach: f64, (lo, hi): (DVec3, DVec3)) -> bool {
    let (mut enter, mut exit) = (0.0f64, reach);
    for axis in 0..3 {
        let (o, d) = (origin[axis], direction[axis]);
        if d == 0.0 {
            if o < lo[axis] || o > hi[axis] {
                return false;
            }
            continue;
        }
        let (a, b) = ((lo[axis] - o) / d, (hi[axis] - o) / d);
        enter = enter.max(a.min(b));
        exit = exit.min(a.max(b));
    }
    enter <= exit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_meet_a_box_as_the_slab_test_says() {
        let unit = (DVec3::splat(-1.0), DVec3::splat(1.0));
        let meets = |o: [f64; 3], d: [f64; 3], reach: f64| {
            ray_meets_box(DVec3::from(o), DVec3::from(d), reach, unit)
        };
        // Straight at it, from inside, and short of it.
        assert!(meets([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0], f64::INFINITY));
        assert!(meets([0.5, 0.5, 0.5], [0.0, 0.0, -1.0], 0.1));
        assert!(!meets([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0], 3.9));
        assert!(meets([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0], 4.0));
        // Pointing away, parallel outside a slab, and passing beside the box.
        assert!(!meets([-5.0, 0.0, 0.0], [-1.0, 0.0, 0.0], f64::INFINITY));
        assert!(!meets([-5.0, 1.5, 0.0], [1.0, 0.0, 0.0], f64::INFINITY));
        let diagonal = DVec3::new(1.0, 1.0, 0.0).normalize();
        assert!(meets([-3.0, -3.0, 0.0], diagonal.into(), f64::INFINITY));
        assert!(!meets(
            [-3.0, -3.0 + 2.0 + 1e-9, 0.0],
            [1.0, -1.0, 0.0],
            f64::INFINITY
        ));
        // A grazing ray along a face is inside its slab: it meets the box.
        assert!(meets([-5.0, 1.0, 0.0], [1.0, 0.0, 0.0], f64::INFINITY));
    }

    /// A view the rasteriser sees in full walks no BVH, so none is built: a cube's centre
    /// rays and sub-pixel rays rasterised leave it unbuilt. Traced ray by ray afterwards (the
    /// BVH built then), every pixel meets the triangle the rasteriser found, at its depth.
    #[test]
    fn rasterised_views_build_no_bvh_and_traced_rays_agree() {
        let trace = TraceMesh::build(&crate::geometry::import::tests::cube());
        let k = crate::cameras::Intrinsics::from_fov_y(64, 48, 1.0);
        let eye = DVec3::new(1.6, -0.9, 1.3);
        let camera = Camera::look_at(k, eye, DVec3::splat(0.5), DVec3::Z);
        let g = trace.trace(&camera);
        let rows: Vec<Vec<u32>> = (0..48).map(|_| (0..64).collect()).collect();
        let pixels = PixelSet::from_rows(&rows);
        let (centres, found) = trace.sample_hits(&camera, &pixels, &[(0.5, 0.5)]);
        assert!(trace.tree.get().is_none(), "a BVH was built");
        assert_eq!(
            (g.visibility, found),
            (Visibility::Rasterised, Visibility::Rasterised)
        );
        let mut seen = 0;
        for (i, [hit]) in centres.into_iter().enumerate() {
            let (row, col) = pixels.at(i);
            let traced = trace.first_hit(&camera, k.ray_through(col + 0.5, row + 0.5));
            let rasterised = (g.triangle[i] != NO_HIT).then_some((g.depth[i], g.triangle[i]));
            for found in [rasterised, hit] {
                assert_eq!(found.map(|h| h.1), traced.map(|h| h.1), "pixel {i}");
                if let (Some((d, _)), Some((t, _))) = (found, traced) {
                    assert!((d - t).abs() <= 1e-6 * t, "pixel {i}: {d} against {t}");
                }
            }
            seen += usize::from(traced.is_some());
        }
        assert!(
            trace.tree.get().is_some() && seen > 500,
            "{seen} pixels meet the cube"
        );
    }

    /// A lens's curved rays cannot be rasterised: the same cube seen through barrel
    /// distortion is traced, centres and sub-pixel rays alike, and says so.
    #[test]
    fn views_through_a_distorting_lens_say_they_were_traced() {
        let trace = TraceMesh::build(&crate::geometry::import::tests::cube());
        let mut k = crate::cameras::Intrinsics::from_fov_y(64, 48, 1.0);
        k.distortion = crate::cameras::Distortion {
            k1: -0.2,
            ..Default::default()
        };
        let camera = Camera::look_at(k, DVec3::new(1.6, -0.9, 1.3), DVec3::splat(0.5), DVec3::Z);
        let g = trace.trace(&camera);
        let pixels = PixelSet::from_rows(&[vec![10, 11], vec![20]]);
        let (hits, found) = trace.sample_hits(&camera, &pixels, &[(0.25, 0.25), (0.75, 0.75)]);
        assert_eq!(
            (g.visibility, found),
            (Visibility::Traced, Visibility::Traced)
        );
        assert_eq!(hits.len(), 3);
        assert!(g.triangle.iter().any(|&t| t != NO_HIT));
    }
}
