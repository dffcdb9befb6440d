//! Meshing an assembly: each shape's primitive is tessellated by the chord rule after its
//! placement's stretch, shell patterns displace tubes radially, a beam deformation bends a
//! shape as the mechanics says, and the placement puts it in the world. Each vertex keeps its
//! position from before any deformation (where textures are evaluated).

use super::beam::problem;
use super::shell_grid::{graded_tube, local_extent};
use super::tessellation::{chord_tolerance, segments_for_chord};
use crate::geometry::Mesh;
use crate::geometry::primitives::Primitive;
use crate::mechanics::{Deformation, Shell, ShellPattern, kinks, section_frames};
use crate::scene::{AssemblySpec, Bending, LabelledPattern, ShapeSpec};
use glam::DVec3;

/// Radius of a sphere about the origin containing every shape.
pub fn assembly_radius(assembly: &AssemblySpec) -> f64 {
    assembly
        .shapes
        .iter()
        .map(|s| s.affine().translation.length() + stretch(s) * s.primitive.bounding_radius())
        .fold(0.0, f64::max)
}

/// Largest stretch of a shape's placement (for tolerances and bounds).
fn stretch(shape: &ShapeSpec) -> f64 {
    let m = shape.affine().matrix3;
    m.x_axis
        .length()
        .max(m.y_axis.length())
        .max(m.z_axis.length())
}

/// The meshes of the shapes with their part labels. `pixel_footprint` is the size of a pixel
/// (metres) at the nearest distance a camera can be from this assembly.
pub fn mesh_assembly(
    assembly: &AssemblySpec,
    pixel_footprint: f64,
) -> Result<Vec<BuiltShape<'_>>, String> {
    if assembly.shapes.is_empty() {
        return Err(format!("assembly \"{}\" has no shapes", assembly.name));
    }
    let tolerance = chord_tolerance(assembly.tessellation, pixel_footprint);
    assembly
        .shapes
        .iter()
        .map(|s| mesh_shape(assembly, s, tolerance))
        .collect()
}

/// One shape, with chords within `tolerance` metres after placement (a scaled shape is
/// tessellated more finely).
fn mesh_shape<'a>(
    assembly: &AssemblySpec,
    s: &'a ShapeSpec,
    tolerance: f64,
) -> Result<BuiltShape<'a>, String> {
    s.primitive.validate()?;
    let m = s.affine();
    if !m.is_finite() || m.matrix3.determinant().abs() < 1e-300 {
        return Err(format!(
            "assembly \"{}\": a shape of part \"{}\" has a degenerate placement",
            assembly.name, s.part
        ));
    }
    let local = tolerance / stretch(s);
    let fixed = s
        .detail
        .and_then(|[n, rings]| s.primitive.fixed_mesh(n as usize, rings as usize));
    let shell = s.shell().filter(|_| !s.shell.is_empty());
    let mut mesh = match (&shell, fixed) {
        (Some(shell), _) => shell_mesh(&s.primitive, shell, &s.shell, local),
        (_, Some(mesh)) => mesh,
        _ => s.primitive.mesh(local),
    }
    .map_err(|e| format!("assembly \"{}\", part \"{}\": {e}", assembly.name, s.part))?;
    let rest: Vec<DVec3> = mesh
        .positions
        .iter()
        .map(|&p| m.transform_point3(p))
        .collect();
    if let Some(shell) = &shell {
        displace_shell(&mut mesh, shell, &s.shell);
    }
    if let Some(bending) = &s.bending {
        bend(&mut mesh, bending)
            .map_err(|e| format!("assembly \"{}\", part \"{}\": {e}", assembly.name, s.part))?;
    }
    mesh.transform(&m);
    Ok(BuiltShape {
        mesh,
        rest,
        part: &s.part,
    })
}

/// One shape of an assembly, meshed, deformed and placed.
#[derive(Debug)]
pub struct BuiltShape<'a> {
    /// The shape, deformed and placed, world coordinates in metres.
    pub mesh: Mesh,
    /// Where each vertex lies before the shape was deformed (textures are fixed there).
    pub rest: Vec<DVec3>,
    /// The part the shape belongs to.
    pub part: &'a str,
}

/// A tube meshed finely enough for its patterns: uniformly by the chord rule on the patterns'
/// summed curvature, or on a grid graded around each local pattern (dent, buckle patch) when
/// there is one (`shell_grid`).
fn shell_mesh(
    tube: &Primitive,
    shell: &Shell,
    patterns: &[LabelledPattern],
    tolerance: f64,
) -> Result<Mesh, String> {
    let plain: Vec<ShellPattern> = patterns.iter().map(|l| l.pattern.clone()).collect();
    if plain.iter().any(|p| local_extent(p).is_some()) {
        return graded_tube(tube, shell, &plain, tolerance);
    }
    let (kz, ks) = patterns
        .iter()
        .map(|p| p.pattern.curvatures(shell))
        .fold((0.0, 0.0), |(a, b), (z, s)| (a + z, b + s));
    let need = |length: f64, k: f64| segments_for_chord(length, k, tolerance).min(4096);
    // An even ring count puts a ring at mid-height, where wind lobes peak.
    let rings = need(shell.height, kz).next_multiple_of(2);
    let segments = need(2.0 * std::f64::consts::PI * shell.radius, ks);
    tube.tube_mesh(tolerance, rings, segments)
        .expect("shell patterns apply to tubes")
}

/// Moves every vertex of the tube radially by the sum of the patterns.
fn displace_shell(mesh: &mut Mesh, shell: &Shell, patterns: &[LabelledPattern]) {
    for p in &mut mesh.positions {
        let r = p.x.hypot(p.y);
        let theta = p.y.atan2(p.x);
        let w: f64 = patterns
            .iter()
            .map(|l| l.pattern.at(shell, theta, p.z))
            .sum();
        *p += DVec3::new(p.x / r, p.y / r, 0.0) * w;
    }
}

/// Smallest and largest coordinate of the mesh along `direction`.
fn range_along(mesh: &Mesh, direction: DVec3) -> (f64, f64) {
    mesh.positions
        .iter()
        .map(|p| p.dot(direction))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        })
}

/// Moves every vertex with the deformed beam: sections turn with the bending rotation and the
/// axis shortens, exactly as for a meshed beam (the vertices are the stations).
fn bend(mesh: &mut Mesh, b: &Bending) -> Result<(), String> {
    let (axis, towards) = (
        DVec3::from_array(b.axis).normalize(),
        DVec3::from_array(b.towards).normalize(),
    );
    let up = -towards;
    let across = up.cross(axis);
    let along = |p: DVec3| p.dot(axis);
    let (lo, hi) = range_along(mesh, axis);
    let extent = hi - lo;
    if (extent - b.beam.length).abs() > 1e-6 * extent {
        return Err(format!(
            "the beam's length {} m must equal the shape's extent along the axis, {extent} m",
            b.beam.length
        ));
    }
    let (bottom, top) = range_along(mesh, up);
    let neutral = 0.5 * (bottom + top);
    let deformation = Deformation::solve(&problem(&b.beam))?;
    let mut stations: Vec<f64> = mesh.positions.iter().map(|&p| along(p) - lo).collect();
    stations.extend(kinks(&b.beam.loads));
    stations.push(0.0);
    stations.sort_by(f64::total_cmp);
    stations.dedup();
    let frames = section_frames(&stations, b.beam.mapping, b.beam.axial(), |x| {
        deformation.at(x)
    });
    for p in &mut mesh.positions {
        let s = along(*p) - lo;
        let frame = frames[stations.partition_point(|&x| x < s)];
        let z = p.dot(up) - neutral;
        let (x, z) = frame.place(z);
        *p = (lo + x) * axis + (neutral + z) * up + p.dot(across) * across;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::mesh_beam;
    use crate::mechanics::Load;
    use crate::scene::BeamSpec;
    use glam::DAffine3;

    #[test]
    fn a_bent_box_matches_the_same_beam_meshed_directly() {
        // A 4 m box along x bent as a cantilever (axis x, deflecting towards −z) lands where the
        // beam mesher puts the same beam: compare the displaced corner at the tip.
        let mut beam = BeamSpec::rectangular(4.0, 0.3, 0.5);
        beam.support = crate::mechanics::Support::Cantilever;
        beam.loads = vec![Load::Point {
            at: 4.0,
            force: 1.0,
        }];
        beam.target = crate::mechanics::Target::Peak { deflection: 0.4 };
        let mut shape = ShapeSpec::new(Primitive::Box {
            size: [4.0, 0.3, 0.5],
        });
        shape.bending = Some(Bending {
            axis: [1.0, 0.0, 0.0],
            towards: [0.0, 0.0, -1.0],
            beam: beam.clone(),
        });
        let mut a = AssemblySpec::new("bent");
        a.shapes.push(shape);
        let bent = &mesh_assembly(&a, 1e-3).unwrap()[0].mesh;
        let direct = mesh_beam(&beam, 1e-3).unwrap().mesh;
        // Both are centred on x = 0 at rest: the beam mesher's tip section (its last four
        // vertices) must be corners of the bent box.
        for corner in &direct.positions[direct.positions.len() - 4..] {
            assert!(
                bent.positions
                    .iter()
                    .any(|p| (*p - *corner).length() < 1e-9),
                "tip corner {corner} missing"
            );
        }
        assert!(bent.is_closed_and_oriented());
        // Bent as a fixed–fixed beam (the axis restrained), the box keeps both ends in place.
        let mut held = a.clone();
        let held_beam = &mut held.shapes[0].bending.as_mut().unwrap().beam;
        held_beam.support = crate::mechanics::Support::FixedFixed;
        held_beam.loads[0] = Load::Point {
            at: 2.0,
            force: 1.0,
        };
        let ends = &mesh_assembly(&held, 1e-3).unwrap()[0].mesh;
        assert!(ends.positions.iter().all(|p| p.x.abs() == 2.0), "{ends:?}");
        // A deflection beyond small rotations is refused, naming the slope.
        let mut steep = a.clone();
        let steep_beam = &mut steep.shapes[0].bending.as_mut().unwrap().beam;
        steep_beam.target = crate::mechanics::Target::Peak { deflection: 3.0 };
        steep_beam.theory = crate::mechanics::Theory::EulerBernoulli;
        let e = mesh_assembly(&steep, 1e-3).unwrap_err();
        assert!(
            e.contains("part \"body\"") && e.contains("slope of the axis"),
            "{e}"
        );
        // A length that does not match the shape is refused, naming both.
        let mut wrong = a.clone();
        wrong.shapes[0].bending.as_mut().unwrap().beam.length = 3.0;
        assert!(
            mesh_assembly(&wrong, 1e-3)
                .unwrap_err()
                .contains("must equal the shape's extent")
        );
    }

    #[test]
    fn shell_patterns_reach_their_requested_amplitude_on_the_mesh() {
        // A thick wall keeps the deformed outer (2.94–3.1 m) and inner (2.44–2.6 m) surfaces apart.
        let tube = Primitive::Tube {
            radius: 3.0,
            height: 12.0,
            wall: 0.5,
        };
        let mut shape = ShapeSpec::new(tube);
        let shell = shape.shell().unwrap();
        for pattern in [
            ShellPattern::Ovalisation {
                amplitude: 0.08,
                n: 3,
                towards: 0.0,
            },
            ShellPattern::HoopExpansion { amplitude: 0.02 },
        ] {
            shape.shell.push(LabelledPattern::new(pattern, &shell));
        }
        let mut a = AssemblySpec::new("silo");
        a.shapes.push(shape);
        let mesh = &mesh_assembly(&a, 1e-3).unwrap()[0].mesh;
        assert!(mesh.is_closed_and_oriented());
        // Outer surface: largest radius = r + 0.08 + 0.02 at mid-height on the lobe; smallest
        // = r − 0.08 + 0.02 between lobes (θ = π/3); ends stay at r + 0.02.
        let outer: Vec<(f64, f64)> = mesh
            .positions
            .iter()
            .map(|p| (p.x.hypot(p.y), p.z))
            .filter(|(r, _)| *r > 2.8)
            .collect();
        let max = outer.iter().map(|o| o.0).fold(0.0, f64::max);
        let min = outer.iter().map(|o| o.0).fold(f64::INFINITY, f64::min);
        assert!((max - 3.1).abs() < 1e-12, "{max}");
        assert!((min - 2.94).abs() < 1e-4, "{min}");
        assert!(
            outer
                .iter()
                .filter(|o| o.1 == 0.0)
                .all(|o| (o.0 - 3.02).abs() < 1e-12)
        );
        assert!(
            (a.shapes[0].shell[0].plausible_amplitude).abs() < 0.01,
            "real wind gives millimetres"
        );
    }

    #[test]
    fn a_dent_on_a_tall_silo_follows_its_surface_within_the_budget() {
        // A 62 mm dent of 0.6 m radius on a 3 m × 16 m shell at a 12 µm chord tolerance: a
        // uniform grid for its curvature would need 1506 rings × 1773 segments (10.7 M
        // triangles, over the budget); the graded grid stays closed and follows the dent's
        // analytic surface r + w(θ, z) to the tolerance everywhere on and around it.
        let tolerance = 1.2e-5;
        let mut shape = ShapeSpec::new(Primitive::Tube {
            radius: 3.0,
            height: 16.0,
            wall: 0.008,
        });
        let shell = shape.shell().unwrap();
        let dent = ShellPattern::Dimple {
            amplitude: 0.062,
            angle: 1.0,
            height: 5.0,
            radius: 0.6,
        };
        shape.shell.push(LabelledPattern::new(dent.clone(), &shell));
        let mut a = AssemblySpec::new("silo");
        a.tessellation = crate::scene::Tolerance::Chord(tolerance);
        a.shapes.push(shape);
        let mesh = &mesh_assembly(&a, 1.0).unwrap()[0].mesh;
        assert!(mesh.is_closed_and_oriented());
        assert!(mesh.triangles.len() < 2_000_000, "{}", mesh.triangles.len());
        let (mut checked, mut worst) = (0, 0.0_f64);
        for t in &mesh.triangles {
            let [p, q, r] = t.map(|i| mesh.positions[i as usize]);
            // The outer surface's triangles face away from the axis (the inner's towards it).
            let outward = (q - p).cross(r - p).dot(DVec3::new(p.x, p.y, 0.0)) > 0.0;
            if !outward || p.z == q.z && q.z == r.z {
                continue;
            }
            let near = |v: &DVec3| {
                let arc = 3.0 * (v.y.atan2(v.x) - 1.0);
                arc.hypot(v.z - 5.0) < 0.7
            };
            if !near(&p) {
                continue;
            }
            for (wp, wq) in [(1.0 / 3.0, 1.0 / 3.0), (0.5, 0.5), (0.5, 0.0), (0.0, 0.5)] {
                let x = wp * p + wq * q + (1.0 - wp - wq) * r;
                let want = 3.0 + dent.at(&shell, x.y.atan2(x.x), x.z);
                worst = worst.max((x.x.hypot(x.y) - want).abs());
                checked += 1;
            }
        }
        assert!(checked > 100_000, "{checked}");
        assert!(worst <= tolerance, "{worst} m off the dent");
    }

    #[test]
    fn placements_compose_and_keep_volumes() {
        let mut s = ShapeSpec::new(Primitive::Box {
            size: [1.0, 2.0, 3.0],
        });
        s.then(DAffine3::from_rotation_z(0.7));
        s.then(DAffine3::from_scale(DVec3::splat(2.0)));
        s.then(DAffine3::from_translation(DVec3::new(10.0, 0.0, 0.0)));
        let mut a = AssemblySpec::new("a");
        a.shapes.push(s);
        let shape = &mesh_assembly(&a, 1e-3).unwrap()[0];
        let (mesh, part) = (&shape.mesh, shape.part);
        assert_eq!(part, "body");
        assert!(
            (mesh.signed_volume() - 6.0 * 8.0).abs() < 1e-9,
            "{}",
            mesh.signed_volume()
        );
        let (lo, hi) = mesh.bounds().unwrap();
        assert!(((lo + hi) / 2.0 - DVec3::new(10.0, 0.0, 0.0)).length() < 1e-12);
        assert!(
            mesh.positions
                .iter()
                .all(|p| p.length() <= assembly_radius(&a) + 1e-12),
            "every vertex within the bounding radius"
        );
        // A mirror keeps the mesh outward-facing.
        let mut m = ShapeSpec::new(Primitive::Box {
            size: [1.0, 1.0, 1.0],
        });
        m.then(DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0)));
        let mut mirrored = AssemblySpec::new("m");
        mirrored.shapes.push(m);
        assert!(
            mesh_assembly(&mirrored, 1e-3).unwrap()[0]
                .mesh
                .signed_volume()
                > 0.0
        );
    }
}
