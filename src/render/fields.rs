//! Per-pixel geometric fields of a view beyond depth: surface normals, distance along the ray,
//! displacement from the unloaded structure, optical flow from the unloaded image to the
//! loaded one, and optical flow between frames of a sequence. Every field follows the one
//! centre ray per pixel the depth label uses (never anti-aliased); pixels that see no surface
//! hold the default (zero, or None).
//!
//! The unloaded and loaded meshes share their triangles and vertex order, so a surface point
//! is carried between them by its barycentric weights on its triangle. Two frames of a
//! sequence may not (a beam's stations follow its moving loads): a point is found on the other
//! frame's unloaded mesh by its unloaded position, then carried there the same way.

use super::shade::{facing_normal, hit_geometry};
use super::surfaces::barycentric;
use super::trace::{GBuffer, NO_HIT, TraceMesh, Traced};
use crate::cameras::Camera;
use crate::geometry::Mesh;
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// Runs `at(row, col, triangle, planar depth)` for every pixel that sees a surface, in
/// parallel by row; the other pixels hold `T::default()`.
fn per_hit<T: Copy + Default + Send>(
    g: &GBuffer,
    at: impl Fn(u32, u32, u32, f64) -> T + Sync,
) -> Vec<T> {
    let width = g.width as usize;
    let mut out = vec![T::default(); g.triangle.len()];
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(row, line)| {
            for (col, value) in line.iter_mut().enumerate() {
                let i = row * width + col;
                if g.triangle[i] != NO_HIT {
                    *value = at(row as u32, col as u32, g.triangle[i], f64::from(g.depth[i]));
                }
            }
        });
    out
}

/// Where a point of `mesh`'s triangle `tri` lies on the same triangle of `positions` (the
/// same mesh with its vertices moved): the sum of the vertices weighted by the point's
/// barycentric coordinates.
pub(super) fn carried(mesh: &Mesh, tri: u32, point: DVec3, positions: &[DVec3]) -> DVec3 {
    let ids = mesh.triangles[tri as usize];
    let [a, b, c] = ids.map(|i| mesh.positions[i as usize]);
    let weights = barycentric(a, b, c, point);
    ids.iter()
        .zip(weights)
        .map(|(&i, w)| w * positions[i as usize])
        .sum()
}

/// The unit normal of the triangle each pixel sees, turned towards the camera, expressed in
/// `axes` (rows: the output axes in world coordinates; the identity for world axes).
pub fn normals(g: &GBuffer, mesh: &TraceMesh, camera: &Camera, axes: DMat3) -> Vec<[f32; 3]> {
    let k = camera.intrinsics;
    per_hit(g, |row, col, tri, _| {
        let n = facing_normal(camera, mesh, tri, k.ray_through_pixel(row, col));
        (axes * n).as_vec3().to_array()
    })
}

/// Euclidean distance from the camera centre to each pixel's surface point: the planar depth
/// times the length of the pixel's ray at unit z.
pub fn ray_distance(g: &GBuffer, camera: &Camera) -> Vec<f32> {
    let k = camera.intrinsics;
    per_hit(g, |row, col, _, depth| {
        (depth * k.ray_through_pixel(row, col).length()) as f32
    })
}

/// The loaded structure, as traced, with the unloaded position of every vertex.
pub struct Deformed<'a> {
    /// The loaded mesh.
    pub mesh: &'a Mesh,
    /// Its BVH.
    pub traced: &'a TraceMesh,
    /// The unloaded position of every vertex of `mesh`.
    pub rest: &'a [DVec3],
}

/// World displacement (metres) from the unloaded to the loaded structure of the point each
/// pixel sees: Σ wᵢ (loadedᵢ − restᵢ) with the point's barycentric weights wᵢ on the loaded
/// triangle, i.e. the hit point minus the same point of the unloaded triangle, without the
/// cancellation of subtracting two positions far from the origin.
pub fn displacement(g: &GBuffer, camera: &Camera, deformed: &Deformed) -> Vec<[f32; 3]> {
    let k = camera.intrinsics;
    let moved: Vec<DVec3> = deformed
        .mesh
        .positions
        .iter()
        .zip(deformed.rest)
        .map(|(p, r)| *p - *r)
        .collect();
    per_hit(g, |row, col, tri, depth| {
        let view = k.ray_through_pixel(row, col);
        let (p, _, _) = hit_geometry(camera, deformed.traced, tri, view, depth);
        carried(deformed.mesh, tri, p, &moved).as_vec3().to_array()
    })
}

/// How much nearer than a surface point another surface may be before it counts as hiding
/// it, as a share of the point's planar depth: eight f32 roundings plus a hundredth of a
/// pixel's footprint (depth / f). When the ray meets the point's own triangle, the hit's depth
/// is that triangle's f64 plane rounded to f32, one rounding from the point's own depth (with
/// no tolerance, half the points of a bent beam would count as hidden; one rounding suffices
/// on the test views, eight leave a margin). When the f32 BVH answers with a neighbour across
/// an edge the point lies within rounding of, the neighbour's plane can pass in front of the
/// point by that rounding magnified by the slant: a hundredth of a pixel's footprint covers
/// it, and a surface so close in front is no occluder the image could show.
fn occlusion_tolerance(camera: &Camera) -> f64 {
    let k = camera.intrinsics;
    8.0 / f64::from(1u32 << 24) + 0.01 / k.fx.max(k.fy)
}

/// How a world point appears in a camera's image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Sighting {
    /// Behind the camera (or on its plane): it has no image.
    Behind,
    /// Its image (u, v), in pixels through the lens, lies outside the frame.
    Outside([f64; 2]),
    /// Its image lies inside the frame, but a nearer surface of the scene hides it.
    Hidden([f64; 2]),
    /// Seen at (u, v).
    Seen([f64; 2]),
}

/// How world point `moved` appears in the image of `camera` (through the lens, when it
/// distorts), `scene` (traced from the camera towards it) deciding whether it is hidden.
pub(super) fn sighting(camera: &Camera, scene: &TraceMesh, moved: DVec3) -> Sighting {
    let k = camera.intrinsics;
    let (width, height) = (f64::from(k.width), f64::from(k.height));
    let moved = camera.world_to_camera(moved);
    if !(moved.z > 0.0) {
        return Sighting::Behind;
    }
    let (u, v) = k.project(moved);
    if !((0.0..width).contains(&u) && (0.0..height).contains(&v)) {
        return Sighting::Outside([u, v]);
    }
    let tolerance = occlusion_tolerance(camera);
    let hidden = scene
        .first_hit(camera, moved / moved.z)
        .is_some_and(|(z, _)| f64::from(z) < moved.z * (1.0 - tolerance));
    if hidden {
        Sighting::Hidden([u, v])
    } else {
        Sighting::Seen([u, v])
    }
}

/// Where world point `moved` lands in the image of `camera`, minus pixel (row, col)'s centre,
/// in pixels (through the lens, when it distorts): None when it lies behind the camera or
/// outside the frame, or when `scene` (traced from the camera towards it) hides it.
fn landing(
    camera: &Camera,
    scene: &TraceMesh,
    moved: DVec3,
    (row, col): (u32, u32),
) -> Option<[f32; 2]> {
    let Sighting::Seen([u, v]) = sighting(camera, scene, moved) else {
        return None;
    };
    let (u0, v0) = (f64::from(col) + 0.5, f64::from(row) + 0.5);
    Some([(u - u0) as f32, (v - v0) as f32])
}

/// Optical flow on the unloaded image: for each pixel of `rest_g` (the unloaded structure
/// `rest` traced through `camera`), where its surface point lands in the loaded image, minus the
/// pixel centre, in pixels (through the lens, when it distorts). None where no surface is
/// seen, where the point lands behind the camera or outside the frame, or where the loaded
/// structure hides it (traced from the camera towards it).
pub fn flow(
    rest_g: &GBuffer,
    camera: &Camera,
    rest: &Traced,
    deformed: &Deformed,
) -> Vec<Option<[f32; 2]>> {
    let k = camera.intrinsics;
    per_hit(rest_g, |row, col, tri, depth| {
        let view = k.ray_through_pixel(row, col);
        let (p, _, _) = hit_geometry(camera, &rest.trace_mesh, tri, view, depth);
        let moved = carried(&rest.mesh, tri, p, &deformed.mesh.positions);
        landing(camera, deformed.traced, moved, (row, col))
    })
}

/// Another frame of a sequence, as the flow between frames reads it: its structure as built at
/// its instant, its unloaded twin (the same material points, its own tessellation) and the
/// camera of the view then (its mount shaken as at that instant).
pub struct OtherFrame<'a> {
    /// The frame's loaded structure with its unloaded vertex positions.
    pub deformed: Deformed<'a>,
    /// The frame's unloaded structure, traced to find material points on it.
    pub rest: &'a Traced,
    /// The view's camera at that frame.
    pub camera: Camera,
}

/// The triangle of `other`'s unloaded mesh holding the material point at unloaded position
/// `at`, on a face of unit normal `normal` whose triangle's longest edge is `size`, and the point
/// as it lies on that triangle's plane: a ray along the normal from just off the surface meets
/// the same face of the other tessellation there (the unloaded surfaces of two frames are the
/// same prisms and planes, tessellated differently). None where no face of the other frame
/// passes through the point (within rounding: a millionth of the face, and of the distance
/// from the origin for the f64 planes).
fn located(other: &Traced, at: DVec3, normal: DVec3, size: f64) -> Option<(u32, DVec3)> {
    let rounding = 1e-9 * at.length();
    let lift = 1e-4 * size + 1e3 * rounding;
    let (tri, found) = other.trace_mesh.first_along(at + lift * normal, -normal)?;
    ((found - at).length() <= 1e-6 * size + rounding).then_some((tri, found))
}

/// Unit normal and longest edge of triangle `tri` of `mesh` at the vertex positions
/// `positions`; None for a degenerate triangle.
fn triangle_shape(mesh: &Mesh, tri: u32, positions: &[DVec3]) -> Option<(DVec3, f64)> {
    let [a, b, c] = mesh.triangles[tri as usize].map(|i| positions[i as usize]);
    let normal = (b - a).cross(c - a).try_normalize()?;
    let size = (b - a).length().max((c - b).length()).max((a - c).length());
    Some((normal, size))
}

/// A material point of a structure, as another frame finds it: its unloaded position, the
/// unit normal of its unloaded face and that face's triangle's longest edge (the scale of the
/// search's tolerances).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct MaterialPoint {
    pub(super) at: DVec3,
    pub(super) normal: DVec3,
    pub(super) size: f64,
}

/// The material point pixel (row, col) of `camera` sees on the loaded structure `this`, where
/// the pixel's centre ray meets triangle `tri` at planar depth `depth`; None on a degenerate
/// triangle.
pub(super) fn material_point(
    this: &Deformed,
    camera: &Camera,
    (row, col): (u32, u32),
    tri: u32,
    depth: f64,
) -> Option<MaterialPoint> {
    let view = camera.intrinsics.ray_through_pixel(row, col);
    let (p, _, _) = hit_geometry(camera, this.traced, tri, view, depth);
    let at = carried(this.mesh, tri, p, this.rest);
    let (normal, size) = triangle_shape(this.mesh, tri, this.rest)?;
    Some(MaterialPoint { at, normal, size })
}

/// Where `point` is in frame `other` (world, its loaded structure): found on that frame's
/// unloaded mesh by its unloaded position, carried by its weights to the loaded one. None where
/// no face of that frame holds it.
pub(super) fn carried_into(other: &OtherFrame, point: &MaterialPoint) -> Option<DVec3> {
    let (found, on_plane) = located(other.rest, point.at, point.normal, point.size)?;
    Some(carried(
        &other.rest.mesh,
        found,
        on_plane,
        &other.deformed.mesh.positions,
    ))
}

/// Optical flow from this frame of a sequence to `other` (the next or the previous): for each
/// pixel of `g` (this frame's loaded structure `this` traced through `camera`), the material
/// point it sees is found on the other frame's unloaded structure by its unloaded position,
/// carried to where the other frame's loaded structure has it, and projected through the other
/// frame's camera; minus the pixel centre, in pixels. Exact when the frames tessellate the same
/// unloaded surface differently (a beam's stations follow its moving loads). None where no
/// surface is seen, where the point has no match on the other frame, lands behind its camera or
/// outside its frame, or is hidden there (traced from that camera towards it).
pub fn frame_flow(
    g: &GBuffer,
    camera: &Camera,
    this: &Deformed,
    other: &OtherFrame,
) -> Vec<Option<[f32; 2]>> {
    per_hit(g, |row, col, tri, depth| {
        let point = material_point(this, camera, (row, col), tri, depth)?;
        let moved = carried_into(other, &point)?;
        landing(&other.camera, other.deformed.traced, moved, (row, col))
    })
}
