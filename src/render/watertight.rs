//! Watertight ray–triangle intersection (Woop, Benthin & Wald, JCGT 2013).
//!
//! The ray is sheared so that it runs along +z from the origin; the triangle's 2D edge
//! functions then decide coverage with no epsilon, so a ray through a shared edge or vertex
//! hits exactly one of the triangles that meet there (or both, never neither). Edge functions
//! that come out exactly zero are recomputed in f64, where the products are exact.

use glam::Vec3A;

#[derive(Clone, Copy, Debug)]
pub struct ShearedRay {
    origin: Vec3A,
    axes: [usize; 3],
    shear: Vec3A,
}

impl ShearedRay {
    pub fn new(origin: Vec3A, direction: Vec3A) -> Self {
        let a = direction.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        // Keep the winding of the projected triangle when the major axis points backwards.
        if direction[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = direction[kz];
        ShearedRay {
            origin,
            axes: [kx, ky, kz],
            shear: Vec3A::new(direction[kx] / dz, direction[ky] / dz, 1.0 / dz),
        }
    }

    /// Ray parameter of the hit with triangle (v0, v1, v2), or +∞. Both sides count as hits.
    #[inline(always)]
    pub fn intersect(&self, v0: Vec3A, v1: Vec3A, v2: Vec3A, t_max: f32) -> f32 {
        // The axes are fixed per ray, so this branch is predicted for all of its triangles,
        // and each arm reads components at constant indices instead of indexing at run time.
        match self.axes {
            [1, 2, 0] => self.intersect_along::<1, 2, 0>(v0, v1, v2, t_max),
            [2, 1, 0] => self.intersect_along::<2, 1, 0>(v0, v1, v2, t_max),
            [2, 0, 1] => self.intersect_along::<2, 0, 1>(v0, v1, v2, t_max),
            [0, 2, 1] => self.intersect_along::<0, 2, 1>(v0, v1, v2, t_max),
            [0, 1, 2] => self.intersect_along::<0, 1, 2>(v0, v1, v2, t_max),
            _ => self.intersect_along::<1, 0, 2>(v0, v1, v2, t_max),
        }
    }

    /// `intersect` with the axes (kx, ky, kz) = (X, Y, Z) known when compiling.
    #[inline(always)]
    fn intersect_along<const X: usize, const Y: usize, const Z: usize>(
        &self,
        v0: Vec3A,
        v1: Vec3A,
        v2: Vec3A,
        t_max: f32,
    ) -> f32 {
        let (a, b, c) = (
            (v0 - self.origin).to_array(),
            (v1 - self.origin).to_array(),
            (v2 - self.origin).to_array(),
        );
        let s = self.shear;
        let (ax, ay) = (a[X] - s.x * a[Z], a[Y] - s.y * a[Z]);
        let (bx, by) = (b[X] - s.x * b[Z], b[Y] - s.y * b[Z]);
        let (cx, cy) = (c[X] - s.x * c[Z], c[Y] - s.y * c[Z]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let wide = |p: f32, q: f32, r: f32, t: f32| {
                (f64::from(p) * f64::from(q) - f64::from(r) * f64::from(t)) as f32
            };
            u = wide(cx, by, cy, bx);
            v = wide(ax, cy, ay, cx);
            w = wide(bx, ay, by, ax);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return f32::INFINITY;
        }
        let det = u + v + w;
        if det == 0.0 {
            return f32::INFINITY;
        }
        let t_scaled = s.z * (u * a[Z] + v * b[Z] + w * c[Z]);
        let t = t_scaled / det;
        if t > 0.0 && t < t_max {
            t
        } else {
            f32::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32, z: f32) -> Vec3A {
        Vec3A::new(x, y, z)
    }

    #[test]
    fn hits_interior_from_both_sides_and_reports_distance() {
        let (a, b, c) = (v(0.0, 0.0, 5.0), v(1.0, 0.0, 5.0), v(0.0, 1.0, 5.0));
        let front = ShearedRay::new(v(0.2, 0.2, 0.0), v(0.0, 0.0, 1.0));
        assert!((front.intersect(a, b, c, f32::INFINITY) - 5.0).abs() < 1e-6);
        let back = ShearedRay::new(v(0.2, 0.2, 10.0), v(0.0, 0.0, -2.0));
        assert!((back.intersect(a, b, c, f32::INFINITY) - 2.5).abs() < 1e-6);
        assert_eq!(front.intersect(a, b, c, 4.0), f32::INFINITY, "beyond t_max");
        let miss = ShearedRay::new(v(0.8, 0.8, 0.0), v(0.0, 0.0, 1.0));
        assert_eq!(miss.intersect(a, b, c, f32::INFINITY), f32::INFINITY);
    }

    #[test]
    fn shared_edge_never_leaks() {
        // Two triangles sharing the diagonal of a quad; rays swept exactly across the diagonal
        // from awkward directions must hit at least one of them every time. (The end points are
        // outer corners of the open quad, where no hit is promised.)
        let q = [
            v(-1.3, -0.7, 4.1),
            v(2.9, -0.2, 3.3),
            v(2.1, 1.9, 5.7),
            v(-0.4, 1.1, 6.2),
        ];
        let mut leaks = 0;
        for i in 1..400 {
            let s = i as f32 / 400.0;
            let target = q[0] + (q[2] - q[0]) * s;
            for origin in [v(0.1, 0.3, -3.0), v(7.0, -5.0, 0.5), v(-9.0, 0.2, 20.0)] {
                let ray = ShearedRay::new(origin, target - origin);
                let h1 = ray.intersect(q[0], q[1], q[2], f32::INFINITY);
                let h2 = ray.intersect(q[0], q[2], q[3], f32::INFINITY);
                if h1.is_infinite() && h2.is_infinite() {
                    leaks += 1;
                }
            }
        }
        assert_eq!(leaks, 0);
    }

    #[test]
    fn ray_in_the_triangle_plane_misses_without_nan() {
        let (a, b, c) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let ray = ShearedRay::new(v(-1.0, 0.2, 0.0), v(1.0, 0.0, 0.0));
        let t = ray.intersect(a, b, c, f32::INFINITY);
        assert!(!t.is_nan());
    }
}
