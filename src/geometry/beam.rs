//! The rectangular (cuboid) beam of the 3DGEN paper, deformed by a point load.

use super::Mesh;
use crate::mechanics::{Mapping, PointLoadShape, SectionMapper};
use glam::{DMat3, DVec3};

/// Everything the beam tessellation needs, in the beam's own frame: the axis runs along +x
/// from the axially fixed end, width along y, height along z (up); `placement` maps that
/// frame, centred on the undeformed beam, into the world.
pub struct BeamGeometry<'a> {
    pub length: f64,
    pub width: f64,
    pub height: f64,
    pub segments: u32,
    pub shape: &'a PointLoadShape,
    pub mapping: Mapping,
    pub rotation: DMat3,
    pub centre: DVec3,
}

/// Stations along the axis: `segments` equal intervals, plus the load point and the
/// peak (the curvature kinks), so that every vertex lies on the exact curve and no kink is cut.
pub fn stations(length: f64, segments: u32, kinks: &[f64]) -> Vec<f64> {
    let n = segments.max(1);
    let mut s: Vec<f64> = (0..=n).map(|i| length * f64::from(i) / f64::from(n)).collect();
    s.extend(kinks.iter().copied().filter(|k| *k > 0.0 && *k < length));
    s.sort_by(f64::total_cmp);
    // Drop stations closer than a micro-fraction of the length: they only make slivers.
    let min_gap = length * 1e-9;
    let mut out: Vec<f64> = Vec::with_capacity(s.len());
    for x in s {
        match out.last() {
            Some(&prev) if x - prev <= min_gap => {}
            _ => out.push(x),
        }
    }
    *out.last_mut().unwrap() = length;
    out
}

/// Tessellates the deformed cuboid: four corners per station, two triangles per side quad,
/// two per end cap. Sections are affine under the beam kinematics, so they need no interior
/// vertices; 4(N+1) vertices and 8N+4 triangles for N intervals.
pub fn beam_mesh(g: &BeamGeometry) -> Mesh {
    let st = stations(g.length, g.segments, &[g.shape.load_at, g.shape.peak_at()]);
    let mapper = SectionMapper::new(g.shape, g.mapping, &st);
    let (hw, hh) = (0.5 * g.width, 0.5 * g.height);
    // Corner order around the section, counter-clockwise seen from +x.
    let corners = [(-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh)];
    let mut mesh = Mesh::default();
    for i in 0..st.len() {
        for &(y, z) in &corners {
            let (x, z) = mapper.map(i, z);
            let local = DVec3::new(x - 0.5 * g.length, y, z);
            mesh.positions.push(g.centre + g.rotation * local);
        }
    }
    let ring = |i: usize, k: usize| (4 * i + k % 4) as u32;
    for i in 0..st.len() - 1 {
        for k in 0..4 {
            let (a, b, c, d) = (ring(i, k), ring(i, k + 1), ring(i + 1, k + 1), ring(i + 1, k));
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    let last = st.len() - 1;
    mesh.triangles.push([ring(0, 0), ring(0, 2), ring(0, 1)]);
    mesh.triangles.push([ring(0, 0), ring(0, 3), ring(0, 2)]);
    mesh.triangles.push([ring(last, 0), ring(last, 1), ring(last, 2)]);
    mesh.triangles.push([ring(last, 0), ring(last, 2), ring(last, 3)]);
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::Support;
    use std::collections::HashMap;

    fn geometry(shape: &PointLoadShape, segments: u32) -> BeamGeometry<'_> {
        BeamGeometry {
            length: shape.length,
            width: 0.3,
            height: 0.5,
            segments,
            shape,
            mapping: Mapping::RotateSections,
            rotation: DMat3::IDENTITY,
            centre: DVec3::ZERO,
        }
    }

    #[test]
    fn undeformed_beam_is_a_closed_box_with_the_right_volume() {
        let shape = PointLoadShape::new(Support::SimplySupported, 4.0, 1.0, 0.0);
        let mesh = beam_mesh(&geometry(&shape, 10));
        assert!((mesh.signed_volume() - 4.0 * 0.3 * 0.5).abs() < 1e-12, "{}", mesh.signed_volume());
        // Closed and consistently oriented: every directed edge appears once, its reverse once.
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1);
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}->{b} has no twin");
        }
        // 10 intervals, plus stations at the load point (1.0) and at the peak
        // (L − √(b(L+a)/3) = 4 − √5).
        assert_eq!(mesh.triangles.len(), 8 * 12 + 4);
    }

    #[test]
    fn bending_keeps_volume_to_second_order() {
        // Plane sections that rotate preserve the section area; the small volume change comes
        // from the fibre strain z·κ integrated over the section, which vanishes by symmetry.
        let shape = PointLoadShape::new(Support::SimplySupported, 4.0, 2.0, 0.02);
        let mesh = beam_mesh(&geometry(&shape, 64));
        assert!((mesh.signed_volume() / 0.6 - 1.0).abs() < 1e-4, "{}", mesh.signed_volume());
    }

    #[test]
    fn deformed_axis_passes_through_the_target_deflection() {
        let shape = PointLoadShape::new(Support::Cantilever, 3.0, 3.0, 0.12);
        let mesh = beam_mesh(&geometry(&shape, 32));
        let (lo, _) = mesh.bounds().unwrap();
        // Tip section centre: mean of its four corners (last ring), z ≈ −δ.
        let n = mesh.positions.len();
        let tip: DVec3 = mesh.positions[n - 4..].iter().sum::<DVec3>() / 4.0;
        assert!((tip.z + 0.12).abs() < 1e-12, "{tip}");
        assert!(lo.z < -0.12);
    }

    #[test]
    fn stations_include_kinks_and_both_ends() {
        let s = stations(2.0, 4, &[0.3, 1.0, 2.0, 0.0]);
        assert_eq!(s, vec![0.0, 0.3, 0.5, 1.0, 1.5, 2.0]);
    }
}
