//! Meshing a straight beam: its section swept along the deformed axis.

use super::Mesh;
use crate::mechanics::{SectionFrame, SectionOutline};
use glam::{DMat3, DVec2, DVec3};

/// Sweeps `outline` through the section frames (one per station) and closes both ends.
/// The beam's own frame (axis along x from 0 to `length`, y across, z up) is centred on the
/// undeformed beam and placed in the world by `rotation` and `centre`. Side faces between
/// stations are flat quads: the beam kinematics is affine across a section, so sections need
/// no interior vertices and only the length is subdivided.
pub fn beam_mesh(length: f64, frames: &[SectionFrame], outline: &SectionOutline, rotation: DMat3, centre: DVec3) -> Mesh {
    let ring: Vec<DVec2> = outline.loops.iter().flatten().copied().collect();
    let per_station = ring.len() as u32;
    let place = |frame: &SectionFrame, p: DVec2| {
        let (x, z) = frame.place(p.y);
        centre + rotation * DVec3::new(x - 0.5 * length, p.x, z)
    };
    let mut mesh = Mesh::default();
    for frame in frames {
        mesh.positions.extend(ring.iter().map(|&p| place(frame, p)));
    }
    let (first, last) = (&frames[0], &frames[frames.len() - 1]);
    mesh.positions.extend(outline.interior.iter().map(|&p| place(first, p)));
    mesh.positions.extend(outline.interior.iter().map(|&p| place(last, p)));

    let mut loop_start = 0u32;
    for lp in &outline.loops {
        let n = lp.len() as u32;
        for i in 0..frames.len() as u32 - 1 {
            for k in 0..n {
                let at = |station: u32, k: u32| station * per_station + loop_start + k % n;
                let (a, b, c, d) = (at(i, k), at(i, k + 1), at(i + 1, k + 1), at(i + 1, k));
                mesh.triangles.push([a, b, c]);
                mesh.triangles.push([a, c, d]);
            }
        }
        loop_start += n;
    }
    let stations = frames.len() as u32;
    let interior = outline.interior.len() as u32;
    let cap_vertex = |i: u32, end: bool| {
        if i < per_station {
            if end { (stations - 1) * per_station + i } else { i }
        } else {
            stations * per_station + (i - per_station) + if end { interior } else { 0 }
        }
    };
    for t in &outline.cap {
        // The cap is counter-clockwise seen from +x: right for the far end, reversed for x = 0.
        mesh.triangles.push(t.map(|i| cap_vertex(i, true)));
        mesh.triangles.push([cap_vertex(t[0], false), cap_vertex(t[2], false), cap_vertex(t[1], false)]);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use crate::mechanics::{Load, Section, Support, Target};
    use crate::scene::{BeamSpec, Tessellation};
    use std::collections::HashMap;

    fn closed_and_oriented(mesh: &crate::geometry::Mesh) {
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}->{b} used twice in one direction");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}->{b} has no twin");
        }
    }

    fn sections() -> [Section; 4] {
        [
            Section::Rectangle { width: 0.3, height: 0.5 },
            Section::ISection { width: 0.15, height: 0.3, flange: 0.0107, web: 0.0071 },
            Section::HollowBox { width: 0.2, height: 0.3, wall: 0.01 },
            Section::CircularHollow { diameter: 0.32, wall: 0.01 },
        ]
    }

    #[test]
    fn every_section_gives_a_closed_mesh_with_the_section_volume() {
        for section in sections() {
            let mut b = BeamSpec::new(4.0, section.clone());
            b.tessellation = Tessellation::Chord(1e-5);
            let mesh = b.build(1e-3).unwrap().mesh;
            closed_and_oriented(&mesh);
            let area = section.properties(0.3).area;
            // Circles are inscribed polygons: their area is short by O(tolerance/r).
            let tol = if matches!(section, Section::CircularHollow { .. }) { 1e-3 } else { 1e-12 };
            assert!((mesh.signed_volume() / (4.0 * area) - 1.0).abs() < tol, "{section:?}: {}", mesh.signed_volume() / (4.0 * area));
        }
    }

    #[test]
    fn paper_mesh_has_the_papers_face_count() {
        let mut b = BeamSpec::rectangular(2.0, 0.2, 0.1);
        b.tessellation = Tessellation::Paper;
        let mesh = b.build(1e-3).unwrap().mesh;
        assert_eq!(mesh.triangles.len(), 12_288);
        closed_and_oriented(&mesh);
        assert!((mesh.signed_volume() - 2.0 * 0.2 * 0.1).abs() < 1e-12);
    }

    #[test]
    fn deformed_axis_passes_through_the_target_deflection() {
        let mut b = BeamSpec::rectangular(3.0, 0.3, 0.5);
        b.support = Support::Cantilever;
        b.loads = vec![Load::Point { at: 3.0, force: 1.0 }];
        b.target = Target::Peak { deflection: 0.12 };
        let built = b.build(1e-3).unwrap();
        let n = built.mesh.positions.len();
        let tip: glam::DVec3 = built.mesh.positions[n - 4..].iter().sum::<glam::DVec3>() / 4.0;
        assert!((tip.z + 0.12).abs() < 1e-12, "{tip}");
        closed_and_oriented(&built.mesh);
        // Bending keeps the volume to second order in the rotation.
        assert!((built.mesh.signed_volume() / (3.0 * 0.15) - 1.0).abs() < 1e-4);
    }
}
