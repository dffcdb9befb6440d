//! Assemblies: structures built in recipes from labelled, transformed primitives.

use super::BeamSpec;
use super::beam::segments_for_chord;
use crate::geometry::Mesh;
use crate::geometry::primitives::Primitive;
use crate::materials::Material;
use crate::mechanics::{Deformation, Shell, ShellPattern, kinks, section_frames};
use glam::{DAffine3, DMat3, DVec3};
use serde::Serialize;

/// A primitive placed in its assembly, with the part it belongs to (for segmentation).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShapeSpec {
    pub primitive: Primitive,
    /// Affine map from the primitive's frame to the assembly's: rows of a 3 × 4 matrix.
    pub transform: [[f64; 4]; 3],
    pub part: String,
    /// A beam deformation applied in the primitive's own frame, before placement.
    pub bending: Option<Bending>,
    /// Radial shell deformation patterns of a tube, about its own axis, before placement.
    pub shell: Vec<LabelledPattern>,
    /// Fixed (segments around, rings along) for round primitives instead of the tolerance rule,
    /// for parity with meshes made elsewhere.
    pub detail: Option<[u32; 2]>,
}

/// A shell pattern with what a physical load would plausibly give (written into the JSON).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LabelledPattern {
    #[serde(flatten)]
    pub pattern: ShellPattern,
    pub plausible_amplitude: f64,
    pub plausible_basis: &'static str,
}

impl LabelledPattern {
    pub fn new(pattern: ShellPattern, shell: &Shell) -> Self {
        let (plausible_amplitude, plausible_basis) = pattern.plausible(shell);
        LabelledPattern {
            pattern,
            plausible_amplitude,
            plausible_basis,
        }
    }
}

/// Bends a shape like a beam: `axis` runs along the beam (from the shape's lowest coordinate
/// on it, which is the beam's x = 0), and positive deflection moves material along `towards`.
/// The beam's length must equal the shape's extent along the axis; its section gives the
/// stiffness for the labels and Timoshenko, and the shape's bounds give the neutral axis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bending {
    pub axis: [f64; 3],
    pub towards: [f64; 3],
    pub beam: BeamSpec,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AssemblySpec {
    pub name: String,
    pub shapes: Vec<ShapeSpec>,
    pub material: Material,
}

impl ShapeSpec {
    pub fn new(primitive: Primitive) -> Self {
        ShapeSpec {
            primitive,
            transform: to_rows(DAffine3::IDENTITY),
            part: "body".into(),
            bending: None,
            shell: Vec::new(),
            detail: None,
        }
    }

    /// The shell a tube forms, for shell patterns.
    pub fn shell(&self) -> Option<Shell> {
        match self.primitive {
            Primitive::Tube {
                radius,
                height,
                wall,
            } => Some(Shell {
                radius,
                wall,
                height,
            }),
            _ => None,
        }
    }

    pub fn affine(&self) -> DAffine3 {
        let r = &self.transform;
        DAffine3 {
            matrix3: DMat3::from_cols(
                DVec3::new(r[0][0], r[1][0], r[2][0]),
                DVec3::new(r[0][1], r[1][1], r[2][1]),
                DVec3::new(r[0][2], r[1][2], r[2][2]),
            ),
            translation: DVec3::new(r[0][3], r[1][3], r[2][3]),
        }
    }

    /// Applies `m` after the current placement.
    pub fn then(&mut self, m: DAffine3) {
        self.transform = to_rows(m * self.affine());
    }

    /// Largest stretch of the placement (for tolerances and bounds).
    fn stretch(&self) -> f64 {
        let m = self.affine().matrix3;
        m.x_axis
            .length()
            .max(m.y_axis.length())
            .max(m.z_axis.length())
    }
}

fn to_rows(m: DAffine3) -> [[f64; 4]; 3] {
    let (c, t) = (m.matrix3, m.translation);
    [
        [c.x_axis.x, c.y_axis.x, c.z_axis.x, t.x],
        [c.x_axis.y, c.y_axis.y, c.z_axis.y, t.y],
        [c.x_axis.z, c.y_axis.z, c.z_axis.z, t.z],
    ]
}

impl AssemblySpec {
    /// Radius of a sphere about the origin containing every shape.
    pub fn radius(&self) -> f64 {
        self.shapes
            .iter()
            .map(|s| s.affine().translation.length() + s.stretch() * s.primitive.bounding_radius())
            .fold(0.0, f64::max)
    }

    /// The meshes of the shapes with their part labels. Chords stay within `tolerance` metres
    /// after placement (a scaled shape is tessellated more finely).
    pub fn build(&self, tolerance: f64) -> Result<Vec<BuiltShape<'_>>, String> {
        if self.shapes.is_empty() {
            return Err(format!("assembly \"{}\" has no shapes", self.name));
        }
        self.shapes
            .iter()
            .map(|s| self.build_shape(s, tolerance))
            .collect()
    }

    fn build_shape<'a>(&self, s: &'a ShapeSpec, tolerance: f64) -> Result<BuiltShape<'a>, String> {
        s.primitive.validate()?;
        let m = s.affine();
        if !m.is_finite() || m.matrix3.determinant().abs() < 1e-300 {
            return Err(format!(
                "assembly \"{}\": a shape of part \"{}\" has a degenerate placement",
                self.name, s.part
            ));
        }
        let local = tolerance / s.stretch();
        let fixed = s
            .detail
            .and_then(|[n, rings]| s.primitive.fixed_mesh(n as usize, rings as usize));
        let shell = s.shell().filter(|_| !s.shell.is_empty());
        let mut mesh = match (&shell, fixed) {
            (Some(shell), _) => shell_mesh(&s.primitive, shell, &s.shell, local),
            (_, Some(mesh)) => mesh,
            _ => s.primitive.mesh(local),
        };
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
                .map_err(|e| format!("assembly \"{}\", part \"{}\": {e}", self.name, s.part))?;
        }
        mesh.transform(&m);
        Ok(BuiltShape {
            mesh,
            rest,
            part: &s.part,
        })
    }
}

/// One shape of an assembly, meshed, deformed and placed.
#[derive(Debug)]
pub struct BuiltShape<'a> {
    pub mesh: Mesh,
    /// Where each vertex lies before the shape was deformed (textures are fixed there).
    pub rest: Vec<DVec3>,
    pub part: &'a str,
}

/// A tube meshed finely enough for its patterns (chord rule on each pattern's curvature).
fn shell_mesh(
    tube: &Primitive,
    shell: &Shell,
    patterns: &[LabelledPattern],
    tolerance: f64,
) -> Mesh {
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
    let deformation = Deformation::solve(&b.beam.problem())?;
    let mut stations: Vec<f64> = mesh.positions.iter().map(|&p| along(p) - lo).collect();
    stations.extend(kinks(&b.beam.loads));
    stations.push(0.0);
    stations.sort_by(f64::total_cmp);
    stations.dedup();
    let frames = section_frames(&stations, b.beam.mapping, |x| deformation.at(x));
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
    use crate::mechanics::Load;

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
        let a = AssemblySpec {
            name: "bent".into(),
            shapes: vec![shape],
            material: Material::default(),
        };
        let bent = &a.build(1e-3).unwrap()[0].mesh;
        let direct = beam.build(1e-3).unwrap().mesh;
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
        // A length that does not match the shape is refused, naming both.
        let mut wrong = a.clone();
        wrong.shapes[0].bending.as_mut().unwrap().beam.length = 3.0;
        assert!(
            wrong
                .build(1e-3)
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
        let a = AssemblySpec {
            name: "silo".into(),
            shapes: vec![shape],
            material: Material::default(),
        };
        let mesh = &a.build(1e-3).unwrap()[0].mesh;
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
    fn placements_compose_and_keep_volumes() {
        let mut s = ShapeSpec::new(Primitive::Box {
            size: [1.0, 2.0, 3.0],
        });
        s.then(DAffine3::from_rotation_z(0.7));
        s.then(DAffine3::from_scale(DVec3::splat(2.0)));
        s.then(DAffine3::from_translation(DVec3::new(10.0, 0.0, 0.0)));
        let a = AssemblySpec {
            name: "a".into(),
            shapes: vec![s],
            material: Material::default(),
        };
        let shape = &a.build(1e-3).unwrap()[0];
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
                .all(|p| p.length() <= a.radius() + 1e-12),
            "every vertex within the bounding radius"
        );
        // A mirror keeps the mesh outward-facing.
        let mut m = ShapeSpec::new(Primitive::Box {
            size: [1.0, 1.0, 1.0],
        });
        m.then(DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0)));
        let mirrored = AssemblySpec {
            name: "m".into(),
            shapes: vec![m],
            material: Material::default(),
        };
        assert!(mirrored.build(1e-3).unwrap()[0].mesh.signed_volume() > 0.0);
    }
}
