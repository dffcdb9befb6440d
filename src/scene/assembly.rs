//! Assemblies: structures built in recipes from labelled, transformed primitives, as plain
//! data. Meshing, bending and shell displacement are the build stage's work.

use super::{BeamSpec, PIXEL_TOLERANCE, SourceSite, Tolerance};
use crate::geometry::primitives::Primitive;
use crate::materials::Material;
use crate::mechanics::{Shell, ShellPattern};
use glam::{DAffine3, DMat3, DVec3};
use serde::Serialize;

/// A primitive placed in its assembly, with the part it belongs to (for segmentation).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ShapeSpec {
    /// The solid, in its own frame.
    pub primitive: Primitive,
    /// Affine map from the primitive's own frame to world coordinates (every placement of the
    /// shape and of its assembly applied): rows of a 3 × 4 matrix [R | t], t in metres.
    pub transform: [[f64; 4]; 3],
    /// Name of the part the shape belongs to, for the part-id image (default "body").
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
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct LabelledPattern {
    /// The pattern and its parameters; its fields appear at this level.
    #[serde(flatten)]
    pub pattern: ShellPattern,
    /// The amplitude a real load or a construction tolerance would plausibly give this shell,
    /// metres; compare with the pattern's `amplitude` to see how far it is exaggerated.
    pub plausible_amplitude: f64,
    /// What `plausible_amplitude` rests on: the load case or code clause, in words.
    pub plausible_basis: &'static str,
}

impl LabelledPattern {
    /// `pattern` on `shell`, with the amplitude a physical load would plausibly give it.
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
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Bending {
    /// Unit vector along the beam axis, in the primitive's frame (a coordinate axis such as
    /// [1, 0, 0]).
    pub axis: [f64; 3],
    /// Unit vector perpendicular to `axis`, in the primitive's frame: the direction positive
    /// deflection moves material (the beam's "down").
    pub towards: [f64; 3],
    /// The beam whose deflected shape is applied: supports, loads, theory and section as for any
    /// beam; its placement, tessellation and material are not used.
    pub beam: BeamSpec,
}

/// A structure made of placed primitives in one material, each shape labelled with a part: a silo,
/// a frame, an imported mesh.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct AssemblySpec {
    /// The assembly's name (in the instance table and in messages).
    pub name: String,
    /// Its shapes, each a primitive with its placement, part and deformations.
    pub shapes: Vec<ShapeSpec>,
    /// The material of every shape.
    pub material: Material,
    /// How closely curved surfaces are followed, after placement (a scaled shape is
    /// tessellated more finely).
    pub tessellation: Tolerance,
    /// The recipe call that made the assembly, where errors found when building it point.
    #[serde(skip)]
    pub declared_at: Option<SourceSite>,
}

impl AssemblySpec {
    /// An assembly with no shapes yet, in the default material and tessellation.
    pub fn new(name: &str) -> Self {
        AssemblySpec {
            name: name.to_string(),
            shapes: Vec::new(),
            material: Material::default(),
            tessellation: Tolerance::Pixels(PIXEL_TOLERANCE),
            declared_at: None,
        }
    }
}

impl ShapeSpec {
    /// `primitive` with the identity placement, undeformed, in part "body".
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

    /// The placement (`transform`) as an affine map.
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
}

fn to_rows(m: DAffine3) -> [[f64; 4]; 3] {
    let (c, t) = (m.matrix3, m.translation);
    [
        [c.x_axis.x, c.y_axis.x, c.z_axis.x, t.x],
        [c.x_axis.y, c.y_axis.y, c.z_axis.y, t.y],
        [c.x_axis.z, c.y_axis.z, c.z_axis.z, t.z],
    ]
}
