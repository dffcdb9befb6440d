//! Solving and meshing a straight beam: the mechanics gives the deflected axis, sections are
//! placed along it at stations fine enough for the chord rule, and the section outline is swept
//! through them, once loaded and once at rest (where textures are evaluated).

use super::relief::{Bar, Relief, bar_meshes, carve, refine_outline, spall_bars};
use super::tessellation::{chord_tolerance, segments_for_chord};
use crate::geometry::outline::{self, PAPER_DIVISIONS, SectionOutline};
use crate::geometry::{Frame3, Mesh, sweep};
use crate::mechanics::damage::{DamageLabels, DamagedMember, SteppedBeam, solve_damage};
use crate::mechanics::{
    AxisPoint, BeamProblem, Deformation, Section, SectionFrame, Theory, kinks, section_frames,
};
use crate::scene::{BeamSpec, Tessellation};
use glam::{DMat3, DVec3};

/// A beam's mesh and the mechanics behind it.
pub struct BuiltBeam {
    /// The deformed beam, world coordinates in metres.
    pub mesh: Mesh,
    /// Where each vertex of `mesh` lies on the undeformed beam (textures are fixed there).
    pub rest: Vec<DVec3>,
    /// The solved deflection and its labels.
    pub deformation: Deformation,
    /// Equal intervals along the length (load positions and the peak add stations).
    pub segments: usize,
    /// What damage the beam has and what it did to the deflection; None for a sound beam.
    pub damage: Option<DamageLabels>,
}

/// The mechanics problem a beam description poses.
pub fn problem(beam: &BeamSpec) -> BeamProblem {
    BeamProblem {
        support: beam.support,
        length: beam.length,
        loads: beam.loads.clone(),
        target: beam.target,
        section: beam.section.properties(beam.poisson),
        elastic_modulus: beam.elastic_modulus,
        poisson: beam.poisson,
        yield_strength: beam.yield_strength,
        theory: beam.theory,
        tolerance: beam.model_tolerance,
        vibration: beam.vibration.clone(),
        axial: beam.axial(),
    }
}

/// Radius of the undeformed beam's bounding sphere.
pub fn beam_radius(beam: &BeamSpec) -> f64 {
    0.5 * (beam.length.powi(2) + beam.section.width().powi(2) + beam.section.height().powi(2))
        .sqrt()
}

/// Solves the mechanics and meshes the deformed beam. `pixel_footprint` is the size of a
/// pixel (metres) at the nearest distance a camera can be from this beam.
pub fn mesh_beam(beam: &BeamSpec, pixel_footprint: f64) -> Result<BuiltBeam, String> {
    let deformation = Deformation::solve(&problem(beam))?.plus_modes(
        beam.support,
        beam.length,
        &beam.frame_modes,
    );
    let (damaged, damage) = match beam.damage_asked.is_empty() {
        true => (None, None),
        false => {
            let (axis, labels) = damage(beam, &deformation)?;
            (axis, Some(labels))
        }
    };
    let axis_at = |x: f64| -> AxisPoint {
        match &damaged {
            Some(d) => d.at(x),
            None => deformation.at(x),
        }
    };
    let tolerance = chord_tolerance(beam.tessellation.tolerance(), pixel_footprint);
    let max_curvature = match &damaged {
        Some(d) => d.max_curvature(),
        None => deformation.max_curvature(beam.length),
    };
    let segments = match beam.tessellation {
        Tessellation::Segments(n) => n as usize,
        Tessellation::Paper => PAPER_DIVISIONS,
        Tessellation::Chord(_) | Tessellation::Pixels(_) => {
            segments_for_chord(beam.length, max_curvature, tolerance)
        }
    };
    let outline = match beam.tessellation {
        Tessellation::Paper => paper_outline(&beam.section)
            .ok_or("the paper's mesh exists only for the rectangular section")?,
        _ => section_outline(&beam.section, tolerance),
    };
    let reliefs: Vec<Relief> = damage
        .iter()
        .flat_map(|d| d.items.iter().filter_map(Relief::of))
        .collect();
    let outline = match reliefs.is_empty() {
        true => outline,
        false => refine_outline(&outline, &reliefs)?,
    };
    let mut at = kinks(&beam.loads);
    at.extend(reliefs.iter().flat_map(Relief::stations));
    match &damage {
        Some(d) => {
            at.push(d.max_deflection_at);
            at.extend(d.stiffness_breaks());
        }
        None => at.push(deformation.labels.max_deflection_at),
    }
    let stations = stations(beam.length, segments, &at);
    let frames = section_frames(&stations, beam.mapping, beam.axial(), axis_at);
    let unloaded: Vec<SectionFrame> = stations
        .iter()
        .map(|&x| SectionFrame {
            x,
            v: 0.0,
            cos: 1.0,
            sin: 0.0,
        })
        .collect();
    let bars: Vec<Bar> = damage
        .iter()
        .flat_map(|d| d.items.iter().flat_map(|item| spall_bars(beam, item)))
        .collect();
    let place = |frames: &[SectionFrame]| -> Result<Mesh, String> {
        let frames = world_frames(
            beam.length,
            frames,
            DMat3::from_rotation_z(beam.yaw),
            DVec3::from_array(beam.centre),
        );
        let mut mesh = sweep(&outline, &frames)?;
        if !reliefs.is_empty() {
            carve(&mut mesh, &outline, &frames, &stations, &reliefs);
            mesh.append(&bar_meshes(&bars, &frames, &stations)?);
        }
        Ok(mesh)
    };
    let mesh = place(&frames)?;
    Ok(BuiltBeam {
        rest: place(&unloaded)?.positions,
        mesh,
        deformation,
        segments,
        damage,
    })
}

/// Places the damage the beam asks for under the physical loads of its sound solution, and
/// the damaged axis where its stiffness changed. A changed stiffness needs a static linear
/// solution to start from (the damaged beam is integrated as Euler–Bernoulli).
fn damage(
    beam: &BeamSpec,
    deformation: &Deformation,
) -> Result<(Option<SteppedBeam>, DamageLabels), String> {
    let labels = &deformation.labels;
    let member = DamagedMember {
        support: beam.support,
        length: beam.length,
        section: &beam.section,
        elastic_modulus: beam.elastic_modulus,
        second_moment: beam.section.properties(beam.poisson).second_moment,
        loads: &labels.loads,
        sound_peak: (labels.max_deflection, labels.max_deflection_at),
    };
    let (axis, damage) = solve_damage(&member, &beam.damage_asked)?;
    let linear = matches!(labels.theory, Theory::EulerBernoulli | Theory::Timoshenko);
    if axis.is_some() && (!linear || !beam.vibration.is_empty()) {
        return Err(format!(
            "damage that lowers the stiffness (cracks, section loss) needs a static linear solution to start from, but this beam ran {}{}; pin theory(\"euler_bernoulli\") or lower the deflection",
            labels.theory.name(),
            if beam.vibration.is_empty() {
                ""
            } else {
                " (a vibration snapshot)"
            }
        ));
    }
    Ok((axis, damage))
}

/// The outline with no more vertices than the shape needs: polygons exactly, circles with
/// sagitta ≤ `chord_tolerance`.
pub fn section_outline(section: &Section, chord_tolerance: f64) -> SectionOutline {
    match *section {
        Section::Rectangle { width, height } => outline::rectangle(width, height, 1),
        Section::ISection {
            width,
            height,
            flange,
            web,
        } => outline::i_shape(width, height, flange, web),
        Section::HollowBox {
            width,
            height,
            wall,
        } => outline::hollow_rectangle(width, height, wall),
        Section::CircularHollow { diameter, wall } => {
            outline::hollow_circle(diameter, wall, chord_tolerance)
        }
    }
}

/// The paper's meshing of its cuboid: every face divided into a 32 × 32 grid.
fn paper_outline(section: &Section) -> Option<SectionOutline> {
    match *section {
        Section::Rectangle { width, height } => {
            Some(outline::rectangle(width, height, PAPER_DIVISIONS))
        }
        _ => None,
    }
}

/// The world frames the section outline is swept through (one per station; the sweep closes
/// both ends). The beam's own frame (axis along x from 0 to `length`, y across, z up) is
/// centred on the undeformed beam and placed in the world by `rotation` and `centre`. Side
/// faces between stations are flat quads: the beam kinematics is affine across a section, so
/// sections need no interior vertices and only the length is subdivided.
fn world_frames(
    length: f64,
    frames: &[SectionFrame],
    rotation: DMat3,
    centre: DVec3,
) -> Vec<Frame3> {
    frames
        .iter()
        .map(|f| Frame3 {
            origin: centre + rotation * DVec3::new(f.x - 0.5 * length, 0.0, -f.v),
            // Section y stays across the beam; section z turns with the section.
            u: rotation * DVec3::Y,
            v: rotation * DVec3::new(f.sin, 0.0, f.cos),
        })
        .collect()
}

/// `segments` equal intervals plus the kinks, without slivers closer than 1e-9 L.
pub fn stations(length: f64, segments: usize, kinks: &[f64]) -> Vec<f64> {
    let n = segments.max(1);
    let mut s: Vec<f64> = (0..=n).map(|i| length * i as f64 / n as f64).collect();
    s.extend(kinks.iter().copied().filter(|k| *k > 0.0 && *k < length));
    s.sort_by(f64::total_cmp);
    let min_gap = length * 1e-9;
    let mut out: Vec<f64> = Vec::with_capacity(s.len());
    for x in s {
        match out.last() {
            Some(&prev) if x - prev <= min_gap => {}
            _ => out.push(x),
        }
    }
    *out.last_mut().expect("at least two stations") = length;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::{Load, Mapping, Support, Target, section_examples};

    #[test]
    fn section_outlines_have_the_section_properties() {
        for s in section_examples() {
            let p = s.properties(0.3);
            // Polygons are exact; the tube is an inscribed polygon at 1e-7 m sagitta.
            let (area, second_moment) = section_outline(&s, 1e-7).area_and_second_moment();
            assert!(
                (area / p.area - 1.0).abs() < 1e-5,
                "{s:?}: area {area} vs {}",
                p.area
            );
            assert!(
                (second_moment / p.second_moment - 1.0).abs() < 1e-5,
                "{s:?}: I {second_moment} vs {}",
                p.second_moment
            );
        }
    }

    #[test]
    fn every_section_gives_a_closed_mesh_with_the_section_volume() {
        for section in section_examples() {
            let mut b = BeamSpec::new(4.0, section.clone());
            b.tessellation = Tessellation::Chord(1e-5);
            let mesh = mesh_beam(&b, 1e-3).unwrap().mesh;
            assert!(mesh.is_closed_and_oriented());
            let area = section.properties(0.3).area;
            // Circles are inscribed polygons: their area is short by O(tolerance/r).
            let tol = if matches!(section, Section::CircularHollow { .. }) {
                1e-3
            } else {
                1e-12
            };
            assert!(
                (mesh.signed_volume() / (4.0 * area) - 1.0).abs() < tol,
                "{section:?}: {}",
                mesh.signed_volume() / (4.0 * area)
            );
        }
    }

    #[test]
    fn paper_mesh_has_the_papers_face_count() {
        let mut b = BeamSpec::rectangular(2.0, 0.2, 0.1);
        b.tessellation = Tessellation::Paper;
        let mesh = mesh_beam(&b, 1e-3).unwrap().mesh;
        assert_eq!(mesh.triangles.len(), 12_288);
        assert!(mesh.is_closed_and_oriented());
        assert!((mesh.signed_volume() - 2.0 * 0.2 * 0.1).abs() < 1e-12);
        let mut tube = BeamSpec::new(2.0, section_examples()[3].clone());
        tube.tessellation = Tessellation::Paper;
        assert!(mesh_beam(&tube, 1e-3).is_err());
    }

    #[test]
    fn deformed_axis_passes_through_the_target_deflection() {
        let mut b = BeamSpec::rectangular(3.0, 0.3, 0.5);
        b.support = Support::Cantilever;
        b.loads = vec![Load::Point {
            at: 3.0,
            force: 1.0,
        }];
        b.target = Target::Peak { deflection: 0.12 };
        let built = mesh_beam(&b, 1e-3).unwrap();
        let n = built.mesh.positions.len();
        let tip: DVec3 = built.mesh.positions[n - 4..].iter().sum::<DVec3>() / 4.0;
        assert!((tip.z + 0.12).abs() < 1e-12, "{tip}");
        assert!(built.mesh.is_closed_and_oriented());
        // Bending keeps the volume to second order in the rotation.
        assert!((built.mesh.signed_volume() / (3.0 * 0.15) - 1.0).abs() < 1e-4);
    }

    #[test]
    fn restrained_ends_stay_where_they_are() {
        // A fixed–fixed beam under a UDL, δ = 0.05 L: both clamps hold the axis (the default),
        // so the end sections stay exactly at x = ±L/2. With axial "free" the far clamp slides in
        // by ½∫v′² = (512/210) δ²/L, today's geometry for a pin-roller mapping
        // (docs/mechanics.md §5.2).
        let (l, delta) = (2.0, 0.1);
        let mut b = BeamSpec::rectangular(l, 0.1, 0.05);
        b.support = Support::FixedFixed;
        b.theory = crate::mechanics::Theory::EulerBernoulli;
        b.loads = vec![Load::Distributed {
            from: 0.0,
            to: l,
            intensity: 1.0,
        }];
        b.target = Target::Peak { deflection: delta };
        let ends = |built: &BuiltBeam, end: f64| -> Vec<f64> {
            built
                .rest
                .iter()
                .zip(&built.mesh.positions)
                .filter(|(r, _)| r.x == end)
                .map(|(_, p)| p.x)
                .collect()
        };
        let held = mesh_beam(&b, 1e-3).unwrap();
        assert_eq!(
            held.deformation.labels.axial,
            crate::mechanics::Axial::Restrained
        );
        for end in [-0.5 * l, 0.5 * l] {
            let xs = ends(&held, end);
            assert!(
                !xs.is_empty() && xs.iter().all(|&x| x == end),
                "{end}: {xs:?}"
            );
        }
        b.axial = Some(crate::mechanics::Axial::Free);
        let free = mesh_beam(&b, 1e-3).unwrap();
        let shortening = 512.0 / 210.0 * delta * delta / l;
        assert!(ends(&free, -0.5 * l).iter().all(|&x| x == -0.5 * l));
        for x in ends(&free, 0.5 * l) {
            assert!(
                (x - (0.5 * l - shortening)).abs() < 1e-6 * shortening,
                "{x}"
            );
        }
    }

    #[test]
    fn out_of_range_beams_are_refused_with_either_mapping() {
        for mapping in [Mapping::RotateSections, Mapping::AddDeflection] {
            let mut b = BeamSpec::rectangular(2.0, 0.2, 0.3);
            b.loads = vec![Load::EndMoments {
                start: 1e28,
                end: 0.0,
            }];
            b.mapping = mapping;
            let e = mesh_beam(&b, 1e-3).err().unwrap();
            assert!(
                e.contains("slope of the axis") && e.contains("exceeds 0.5"),
                "{e}"
            );
        }
    }

    #[test]
    fn stations_include_kinks_and_both_ends() {
        assert_eq!(
            stations(2.0, 4, &[0.3, 1.0, 2.0, 0.0]),
            vec![0.0, 0.3, 0.5, 1.0, 1.5, 2.0]
        );
    }
}
