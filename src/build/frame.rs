//! Analysing a frame and meshing it deformed: each member's section outline swept along its
//! deformed axis, sections turned by the analysed section rotation, stations fine enough for the
//! chord rule on the member's peak curvature. Each member runs on past its nodes as far as the
//! other members there reach along it, moving rigidly with its end, so the members of a joint
//! overlap there as they do at rest and no corner opens under deformation.

use super::beam::{section_outline, stations};
use super::tessellation::{chord_tolerance, segments_for_chord};
use crate::geometry::{Frame3, sweep};
use crate::mechanics::frame::{FrameLabels, FrameSolution, SectionScale, SpaceSection};
use crate::scene::FrameSpec;
use glam::{DQuat, DVec3};

/// A frame's member meshes and its labels.
pub struct BuiltFrame<'a> {
    /// One per member, in the order of the model's members.
    pub members: Vec<super::BuiltShape<'a>>,
    /// What the analysis found.
    pub labels: FrameLabels,
}

/// Radius of a sphere about the origin holding the undeformed frame.
pub fn frame_radius(frame: &FrameSpec) -> f64 {
    let reach = frame
        .model
        .members
        .iter()
        .map(|m| 0.5 * m.section.width().hypot(m.section.height()))
        .fold(0.0, f64::max);
    frame
        .model
        .nodes
        .iter()
        .map(|p| DVec3::from_array(*p).length())
        .fold(0.0, f64::max)
        + 2.0 * reach
}

/// Analyses `frame` and meshes its members deformed (displacements times its display scale).
/// `pixel_footprint`: a pixel's size (metres) at the nearest a camera can come.
pub fn mesh_frame(frame: &FrameSpec, pixel_footprint: f64) -> Result<BuiltFrame<'_>, String> {
    if !(frame.display_scale >= 0.0 && frame.display_scale.is_finite()) {
        return Err(format!(
            "display_scale = {} must be finite and not negative",
            frame.display_scale
        ));
    }
    let model = &frame.model;
    // A frame of a sequence moves as its sound modal model says: damage is drawn on the
    // static analysis only.
    let (solution, damage) = match &frame.displaced {
        Some(displaced) => (model.displaced_by(displaced.clone())?, None),
        None => model.solve_damaged()?,
    };
    let scale_of = |i: usize| {
        damage
            .iter()
            .flat_map(|d| &d.members)
            .find(|d| d.member == i)
            .map_or(SectionScale::ONE, |d| d.section_scale)
    };
    let tolerance = chord_tolerance(frame.tessellation, pixel_footprint);
    let overhang = joint_overhangs(frame, &solution);
    let members = model
        .members
        .iter()
        .enumerate()
        .map(|(i, member)| {
            let props = SpaceSection::of(&member.section, member.poisson).scaled(scale_of(i));
            let e = member.elastic_modulus * member.stiffness_factor;
            let r = &solution.members[i];
            let curvature = frame.display_scale
                * (r.peak_moment_y / (e * props.i_y)).max(r.peak_moment_z / (e * props.i_z));
            let length = solution.member_length(i);
            let segments = segments_for_chord(length, curvature, tolerance);
            let at = stations(length, segments, solution.member_kinks(i));
            let ends = overhang[i];
            let outline = section_outline(&member.section, tolerance);
            let start = DVec3::from_array(model.nodes[member.start]);
            let place = |scale: f64| {
                let frames = member_frames(&solution, i, start, &at, ends, scale);
                sweep(&outline, &frames)
            };
            Ok(super::BuiltShape {
                mesh: place(frame.display_scale)?,
                rest: place(0.0)?.positions,
                part: member.part.as_str(),
            })
        })
        .collect::<Result<Vec<_>, String>>()?;
    let mut labels = FrameLabels::new(&solution);
    if frame.displaced.is_some() {
        labels.analysis = "modal_response";
    }
    labels.damage = damage;
    Ok(BuiltFrame { members, labels })
}

/// How far each member runs on past its (start, end) node: as far as the other members meeting
/// there reach along its axis (each one's section box projected on that axis), and at least
/// half its own smaller section dimension, so the members of a joint overlap at rest. Measured
/// along the axis rather than by the largest section at the node, so a wide flat member (a deck
/// slab strip of a grillage) does not push a thin member meeting it (a shear connector) out
/// through its far face.
fn joint_overhangs(frame: &FrameSpec, solution: &FrameSolution) -> Vec<(f64, f64)> {
    let members = &frame.model.members;
    let mut at_node: Vec<Vec<usize>> = vec![Vec::new(); frame.model.nodes.len()];
    for (i, m) in members.iter().enumerate() {
        at_node[m.start].push(i);
        at_node[m.end].push(i);
    }
    let reach_along = |k: usize, axis: DVec3| {
        let (w, h) = (members[k].section.width(), members[k].section.height());
        let axes = solution.member_axes(k);
        0.5 * (axis.dot(axes.row(1)).abs() * w + axis.dot(axes.row(2)).abs() * h)
    };
    let overhang = |i: usize, node: usize| {
        let axis = solution.member_axes(i).row(0);
        let own = 0.5 * members[i].section.width().min(members[i].section.height());
        at_node[node]
            .iter()
            .filter(|&&k| k != i)
            .map(|&k| reach_along(k, axis))
            .fold(own, f64::max)
    };
    members
        .iter()
        .enumerate()
        .map(|(i, m)| (overhang(i, m.start), overhang(i, m.end)))
        .collect()
}

/// The section frames of member `m` at `stations` (and at the overhangs past its ends, which
/// move rigidly with the end), displacements times `scale`.
fn member_frames(
    solution: &FrameSolution,
    m: usize,
    start: DVec3,
    stations: &[f64],
    (before, after): (f64, f64),
    scale: f64,
) -> Vec<Frame3> {
    let axes = solution.member_axes(m);
    let (x, y, z) = (axes.row(0), axes.row(1), axes.row(2));
    let length = solution.member_length(m);
    let frame_at = |s: f64| {
        let on = s.clamp(0.0, length);
        let (u, r) = solution.member_at(m, on);
        let turn = DQuat::from_scaled_axis(scale * r);
        let centre = start + on * x + scale * u + turn * ((s - on) * x);
        Frame3 {
            origin: centre,
            u: turn * y,
            v: turn * z,
        }
    };
    let mut out = Vec::with_capacity(stations.len() + 2);
    if before > 0.0 {
        out.push(frame_at(-before));
    }
    out.extend(stations.iter().map(|&s| frame_at(s)));
    if after > 0.0 {
        out.push(frame_at(length + after));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::Section;
    use crate::mechanics::frame::{Member, NodalLoad, NodeSupport, Plane};

    /// A fixed-base portal with a lateral load, drawn at scale 50.
    fn portal() -> FrameSpec {
        let mut f = FrameSpec::new("portal");
        let s = Section::Rectangle {
            width: 0.2,
            height: 0.3,
        };
        let m = &mut f.model;
        m.nodes = vec![[0.0; 3], [0.0, 0.0, 3.0], [5.0, 0.0, 3.0], [5.0, 0.0, 0.0]];
        m.members = vec![
            Member::new(0, 1, s.clone()),
            Member::new(1, 2, s.clone()),
            Member::new(3, 2, s),
        ];
        m.supports = vec![NodeSupport::fixed(0), NodeSupport::fixed(3)];
        m.plane = Some(Plane::Xz);
        m.loads = vec![NodalLoad {
            node: 1,
            force: [5e4, 0.0, -2e4],
            moment: [0.0; 3],
        }];
        f.display_scale = 50.0;
        f
    }

    /// A thin vertical connector under a 3 m wide, 0.2 m thick slab strip (a grillage deck on
    /// its shear connector) reaches the strip's top face and stops there: it does not poke
    /// through by half the strip's width.
    #[test]
    fn a_thin_member_under_a_wide_slab_ends_at_the_slabs_top_face() {
        let mut f = FrameSpec::new("slab on a connector");
        let m = &mut f.model;
        m.nodes = vec![[0.0; 3], [0.0, 0.0, 1.0], [4.0, 0.0, 1.0]];
        let connector = Section::Rectangle {
            width: 0.02,
            height: 0.2,
        };
        let slab = Section::Rectangle {
            width: 3.0,
            height: 0.2,
        };
        m.members = vec![Member::new(0, 1, connector), Member::new(1, 2, slab)];
        m.supports = vec![NodeSupport::fixed(0)];
        let built = mesh_frame(&f, 1e-3).unwrap();
        let top = |shape: &crate::build::BuiltShape| {
            shape.rest.iter().map(|p| p.z).fold(f64::MIN, f64::max)
        };
        assert!(
            (top(&built.members[0]) - 1.1).abs() < 1e-12,
            "{}",
            top(&built.members[0])
        );
        assert!((top(&built.members[1]) - 1.1).abs() < 1e-12);
        // The strip runs on past its free end by half its own thickness, not half its width.
        let reach = built.members[1]
            .rest
            .iter()
            .map(|p| p.x)
            .fold(f64::MIN, f64::max);
        assert!((reach - 4.1).abs() < 1e-12, "{reach}");
    }

    #[test]
    fn members_are_closed_and_their_ends_move_with_the_node() {
        let f = portal();
        let built = mesh_frame(&f, 1e-3).unwrap();
        let solution = f.model.solve().unwrap();
        for (i, shape) in built.members.iter().enumerate() {
            assert!(shape.mesh.is_closed_and_oriented(), "member {i}");
            let member = &f.model.members[i];
            // Every vertex at or past a node (the end section and the overhang) moved rigidly
            // with that node: its translation plus its rotation, both scaled.
            let axis = solution.member_axes(i).row(0);
            let length = solution.member_length(i);
            let start = DVec3::from_array(f.model.nodes[member.start]);
            for (node, past) in [(member.start, 0.0), (member.end, length)] {
                let at = DVec3::from_array(f.model.nodes[node]);
                let n = solution.nodes[node];
                let turn = DQuat::from_scaled_axis(50.0 * DVec3::from_array(n.rotation));
                let shift = 50.0 * DVec3::from_array(n.displacement);
                let mut seen = 0;
                for (rest, p) in shape.rest.iter().zip(&shape.mesh.positions) {
                    let s = (rest - start).dot(axis);
                    let beyond = if past == 0.0 {
                        s <= 1e-12
                    } else {
                        s >= length - 1e-12
                    };
                    if !beyond {
                        continue;
                    }
                    seen += 1;
                    let want = at + shift + turn * (rest - at);
                    assert!(
                        p.distance(want) < 1e-9,
                        "member {i} node {node}: {p} vs {want}"
                    );
                }
                assert!(seen > 0, "member {i} node {node}");
            }
        }
    }
}
