//! The surfaces of a sample's mesh: from a hit on the deformed mesh back to the undeformed
//! surface, where the structure's material is evaluated. Textures therefore stay attached to
//! the material as the structure bends, and a shared edge reads the same point from either
//! side. With a sample's `FieldCache`, the material is read from the fields it cached on the
//! triangle's plane instead of evaluated at every pixel.

use super::fields::carried;
use super::shade::{Surfaces, hit_geometry};
use super::trace::{GBuffer, NO_HIT, TraceMesh};
use crate::cameras::Camera;
use crate::geometry::Mesh;
use crate::materials::cache::{FieldCache, Plane};
use crate::materials::noise::LANES;
use crate::materials::{Grain, Shader, Surface, SurfacePoint};
use glam::DVec3;
use rayon::prelude::*;

/// The materials of a sample, by triangle.
pub struct SampleSurfaces<'a> {
    /// The mesh as traced: the loaded one, or for the unloaded image the unloaded one.
    pub mesh: &'a Mesh,
    /// Undeformed position of every vertex of `mesh`.
    pub rest: &'a [DVec3],
    /// Piece (a beam or one shape of an assembly) of every triangle.
    pub piece: &'a [u32],
    /// Shader index and grain of every piece.
    pub pieces: &'a [(u32, Grain)],
    /// The material of every structure, with the sample's random choices.
    pub shaders: &'a [Shader],
    /// The sample's cached material fields; None evaluates the material at every point (the
    /// per-pixel reference).
    pub cache: Option<&'a FieldCache>,
}

impl SampleSurfaces<'_> {
    /// The undeformed surface point under world point `p` of triangle `tri`.
    fn rest_point(&self, tri: u32, p: DVec3, footprint: f64) -> SurfacePoint {
        SurfacePoint {
            rest: carried(self.mesh, tri, p, self.rest),
            rest_normal: self.rest_normal(tri),
            footprint,
        }
    }

    /// Unit normal of the triangle's undeformed surface.
    fn rest_normal(&self, tri: u32) -> DVec3 {
        let [ra, rb, rc] = self.mesh.triangles[tri as usize].map(|i| self.rest[i as usize]);
        (rb - ra).cross(rc - ra).normalize_or_zero()
    }

    fn shader_of(&self, tri: u32) -> (&Shader, &Grain) {
        let (shader, grain) = &self.pieces[self.piece[tri as usize] as usize];
        (&self.shaders[*shader as usize], grain)
    }

    /// 255 where the centre ray meets a crack, 0 elsewhere (see `Shader::crack`).
    pub fn crack_mask(&self, g: &GBuffer, camera: &Camera, mesh: &TraceMesh) -> Vec<u8> {
        let width = g.width as usize;
        let mut mask = vec![0u8; g.triangle.len()];
        mask.par_chunks_mut(width)
            .enumerate()
            .for_each(|(row, out)| {
                for (col, m) in out.iter_mut().enumerate() {
                    let i = row * width + col;
                    let tri = g.triangle[i];
                    if tri == NO_HIT {
                        continue;
                    }
                    let (shader, grain) = self.shader_of(tri);
                    if !shader.material().has_cracks() {
                        continue;
                    }
                    let view = camera.intrinsics.ray_through_pixel(row as u32, col as u32);
                    let (p, _, footprint) =
                        hit_geometry(camera, mesh, tri, view, f64::from(g.depth[i]));
                    if shader.crack(&self.rest_point(tri, p, footprint), grain) {
                        *m = 255;
                    }
                }
            });
        mask
    }
}

impl Surfaces for SampleSurfaces<'_> {
    fn at(&self, tri: u32, p: DVec3, footprint: f64) -> Surface {
        let (shader, grain) = self.shader_of(tri);
        if !shader.textured() {
            // A plain colour needs no point on the undeformed surface.
            return shader.untextured();
        }
        let point = self.rest_point(tri, p, footprint);
        let plane = self.cache.and_then(|cache| {
            let plane = cache.plane(tri, || {
                let corner = self.rest[self.mesh.triangles[tri as usize][0] as usize];
                Plane::new(self.piece[tri as usize], point.rest_normal, corner)
            })?;
            Some((cache, plane))
        });
        match plane {
            Some((cache, plane)) => cache.surface(shader, grain, &plane, point.rest, footprint),
            None => shader.surface(&point, grain),
        }
    }

    fn at_span(&self, hits: &[(u32, DVec3, f64)], out: &mut [Surface]) {
        // Runs of hits on one piece (one material and grain) read the material together;
        // with a field cache each hit reads it from the cache.
        let mut start = 0;
        while start < hits.len() {
            let piece = self.piece[hits[start].0 as usize];
            let end = start
                + hits[start..]
                    .iter()
                    .take_while(|h| self.piece[h.0 as usize] == piece)
                    .count();
            let (shader, grain) = self.shader_of(hits[start].0);
            if self.cache.is_some() || !shader.textured() || end - start < 2 {
                for (s, &(tri, p, footprint)) in out[start..end].iter_mut().zip(&hits[start..end]) {
                    *s = self.at(tri, p, footprint);
                }
            } else {
                let run = &hits[start..end];
                let mut points = [self.rest_point(run[0].0, run[0].1, run[0].2); LANES];
                for (point, &(tri, p, footprint)) in points.iter_mut().zip(run).skip(1) {
                    *point = self.rest_point(tri, p, footprint);
                }
                shader.surfaces(&points[..run.len()], grain, &mut out[start..end]);
            }
            start = end;
        }
    }

    fn flat(&self, tri: u32) -> [f64; 3] {
        self.shader_of(tri).0.albedo()
    }

    fn textured(&self, tri: u32) -> bool {
        self.shader_of(tri).0.textured()
    }

    fn matte(&self, tri: u32) -> bool {
        let shader = self.shader_of(tri).0;
        !shader.textured() && shader.material().specular == 0.0
    }

    fn continues(&self, a: u32, b: u32) -> bool {
        self.piece[a as usize] == self.piece[b as usize]
            && self.rest_normal(a).dot(self.rest_normal(b)) >= SHALLOW_CREASE_COS
    }
}

/// Cosine of the sharpest crease within one face of a piece, 20°: facets of a tessellated
/// curve meet at a few degrees, the faces of a box at 90°.
const SHALLOW_CREASE_COS: f64 = 0.939_692_620_785_908_4;

/// Barycentric weights of the point of triangle (a, b, c) nearest to `p`'s projection,
/// clamped onto the triangle (a hit can stray outside it by the f32 rounding of tracing).
pub(super) fn barycentric(a: DVec3, b: DVec3, c: DVec3, p: DVec3) -> [f64; 3] {
    let [_, v, w] = affine_weights(a, b, c, p);
    let (v, w) = (v.max(0.0), w.max(0.0));
    let total = (v + w).max(1.0);
    let (v, w) = (v / total, w / total);
    [1.0 - v - w, v, w]
}

/// Barycentric weights of `p`'s projection on the plane of triangle (a, b, c), not clamped:
/// the triangle's affine map carries points and vectors off the triangle too. A degenerate
/// triangle gives its first corner.
pub(super) fn affine_weights(a: DVec3, b: DVec3, c: DVec3, p: DVec3) -> [f64; 3] {
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let v = (d22 * d1 - d12 * d2) / det;
    let w = (d11 * d2 - d12 * d1) / det;
    [1.0 - v - w, v, w]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_weights_rebuild_the_point_and_clamp_outside() {
        let (a, b, c) = (
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(4.0, 2.5, 3.0),
            DVec3::new(1.5, 6.0, 2.0),
        );
        for (v, w) in [(0.2, 0.3), (0.0, 0.0), (0.5, 0.5), (0.9, 0.05)] {
            let p = a + v * (b - a) + w * (c - a);
            let [x, y, z] = barycentric(a, b, c, p);
            assert!((x * a + y * b + z * c - p).length() < 1e-12);
        }
        let outside = barycentric(a, b, c, a - (b - a));
        assert_eq!(outside, [1.0, 0.0, 0.0]);
    }
}
