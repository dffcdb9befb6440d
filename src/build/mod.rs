//! The build stage: one described sample becomes what can be rendered.
//!
//! Owns: solving each structure's mechanics and meshing it deformed (beams along their
//! stations, assemblies shape by shape, shell patterns, bending) to the one tessellation rule,
//! the undeformed position of every vertex (where textures live), the labels of every
//! triangle (structure, part, piece), each structure's material drawn for the sample, and the
//! light of the sample and backdrop of a view drawn from the recipe's ranges. Must not touch:
//! Rhai, rays, pixels or files. Everything drawn here comes from streams derived from
//! (seed, sample[, view], name), so a sample builds the same on any thread, in any order.

mod assembly;
mod beam;
mod frame;
mod ground;
mod light;
mod relief;
mod shell_grid;
mod supports;
mod tessellation;

pub use assembly::{BuiltShape, assembly_radius, mesh_assembly};
pub use beam::{BuiltBeam, beam_radius, mesh_beam, problem, section_outline, stations};
pub use frame::{BuiltFrame, frame_radius, mesh_frame};
pub use ground::ground_square;
pub use light::{BackdropDraw, LightDraw, SkyDraw, SunDraw, draw_backdrop, draw_light};
pub use relief::{Relief, spall_bars};
pub use supports::{SupportMaterial, SupportPiece, drawn_supports};
pub use tessellation::{chord_tolerance, segments_for_chord};

use crate::geometry::{self, MAX_COORDINATE, MAX_TRIANGLES, Mesh};
use crate::materials::{Grain, GroundBounce, Lighting, Material, Shader, prompt, srgb_to_linear};
use crate::mechanics::Labels;
use crate::scene::{DatasetSpec, GROUND_PART, SceneSpec, SourceSite, Structure, ground_radius};
use crate::seeds::{self, Scope, Stream};
use glam::{DMat3, DVec3};

/// The deformed scene of one sample, ready to be viewed.
pub struct BuiltSample {
    /// Sample index, from 0.
    pub index: u64,
    /// The scene the recipe drew for the sample.
    pub scene: SceneSpec,
    /// What building each structure found out (beams only; None for assemblies).
    pub beams: Vec<Option<BeamOutcome>>,
    /// What the analysis of each frame found (None for other structures).
    pub frames: Vec<Option<crate::mechanics::frame::FrameLabels>>,
    /// The deformed mesh of every structure, merged, world coordinates in metres.
    pub mesh: Mesh,
    /// Undeformed position of every vertex (where textures are evaluated).
    pub rest: Vec<DVec3>,
    /// Piece (a beam, or one shape of an assembly) of every triangle.
    pub piece: Vec<u32>,
    /// Structure index and grain direction of every piece.
    pub pieces: Vec<(u32, Grain)>,
    /// The material of every structure, with this sample's random choices.
    pub shaders: Vec<Shader>,
    /// The light of this sample.
    pub lighting: Lighting,
    /// The values drawn for the light.
    pub light_drawn: LightDraw,
    /// Structure index of every triangle.
    pub owner: Vec<u32>,
    /// Part of every triangle, as an index into `parts`.
    pub part: Vec<u32>,
    /// Part names, in order of first appearance; part id = index + 1 (0 = background).
    pub parts: Vec<String>,
    /// Centre and radius of the deformed scene's bounding sphere; cameras aim at the centre.
    pub centre: DVec3,
    /// Radius of that sphere, metres.
    pub radius: f64,
    /// The ground, when the dataset has one: its triangles and vertices come last in `mesh`.
    pub ground: Option<BuiltGround>,
}

/// Where the ground lies and where its geometry starts in the sample's mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuiltGround {
    /// Height of the ground plane, world z, metres.
    pub height: f64,
    /// Half the side of the ground square about the scene's centre, metres.
    pub radius: f64,
    /// Index of the ground's first triangle: every triangle before it is a structure's.
    pub first_triangle: usize,
    /// Index of the ground's first vertex: every vertex before it is a structure's.
    pub first_vertex: usize,
}

/// The structures' loaded mesh without the ground: borrowed when there is no ground.
pub type StructureMesh<'a> = std::borrow::Cow<'a, Mesh>;

impl BuiltSample {
    /// The structures' mesh without the ground (loaded, and the unloaded positions): what the
    /// mesh and point outputs hold.
    pub fn structure_mesh(&self) -> (StructureMesh<'_>, &[DVec3]) {
        match self.ground {
            None => (std::borrow::Cow::Borrowed(&self.mesh), &self.rest),
            Some(g) => (
                std::borrow::Cow::Owned(Mesh {
                    positions: self.mesh.positions[..g.first_vertex].to_vec(),
                    triangles: self.mesh.triangles[..g.first_triangle].to_vec(),
                }),
                &self.rest[..g.first_vertex],
            ),
        }
    }

    /// Number of the structures' triangles: those before the ground's.
    pub fn structure_triangles(&self) -> usize {
        self.ground
            .map_or(self.mesh.triangles.len(), |g| g.first_triangle)
    }
}

/// What building a beam found out: its mechanics labels and its intervals along the length.
pub struct BeamOutcome {
    /// What the mechanics found.
    pub labels: Labels,
    /// Equal intervals along the length (load positions and the peak add stations).
    pub segments: usize,
    /// The beam's damage and what it did to the deflection; None for a sound beam.
    pub damage: Option<crate::mechanics::damage::DamageLabels>,
}

/// Why a sample could not be built, and where the recipe declared what failed.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildError {
    /// What is wrong, naming the structure and the value at fault.
    pub message: String,
    /// The recipe call behind the failing structure, when known.
    pub site: Option<SourceSite>,
}

impl BuildError {
    fn whole_scene(message: String) -> Self {
        BuildError {
            message,
            site: None,
        }
    }
}

/// Builds the deformed meshes of sample `index` of `dataset`, whose scene the recipe drew as
/// `scene`; fails on anything that would make non-finite output.
pub fn build_sample(
    dataset: &DatasetSpec,
    index: u64,
    scene: SceneSpec,
) -> Result<BuiltSample, BuildError> {
    build_framed(dataset, index, scene, None)
}

/// Where a sample's cameras aim and its ground lies: by default the deformed scene's bounding
/// sphere and lowest point. Every frame of a sequence takes its reference's (the structures
/// under their static loads alone), so fixed cameras, light and ground stay put while the
/// structures move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framing {
    /// Centre of the sphere the cameras aim at.
    pub centre: DVec3,
    /// Its radius, metres.
    pub radius: f64,
    /// Lowest point of the structures, world z (where a ground without a height lies).
    pub lowest: f64,
}

impl BuiltSample {
    /// This sample's framing, for the frames of its sequence.
    pub fn framing(&self) -> Framing {
        let structures = self.structure_mesh().0;
        let lowest = structures
            .positions
            .iter()
            .map(|p| p.z)
            .fold(f64::INFINITY, f64::min);
        Framing {
            centre: self.centre,
            radius: self.radius,
            lowest: self.ground.map_or(lowest, |g| g.height),
        }
    }
}

/// [`build_sample`], framed by `framing` when given (a frame of a sequence) rather than by its
/// own deformed geometry.
pub fn build_framed(
    dataset: &DatasetSpec,
    index: u64,
    scene: SceneSpec,
    framing: Option<Framing>,
) -> Result<BuiltSample, BuildError> {
    let mut assembled = Assembled {
        structures: scene.structures.len(),
        ..Assembled::default()
    };
    let mut beams = Vec::new();
    let mut frames = Vec::new();
    for (i, structure) in scene.structures.iter().enumerate() {
        let failed = |m: String| BuildError {
            message: format!("structure {i}: {m}"),
            site: structure.declared_at().cloned(),
        };
        let mut frame_labels = None;
        match structure {
            Structure::Beam(beam) => {
                let footprint = dataset
                    .camera
                    .nearest_pixel_footprint(DVec3::from_array(beam.centre), beam_radius(beam));
                let built = mesh_beam(beam, footprint).map_err(failed)?;
                within_range(&built.mesh).map_err(failed)?;
                let (bottom, top) = heights(&built.rest);
                let grain = Grain {
                    axis: DMat3::from_rotation_z(beam.yaw) * DVec3::X,
                    centre: DVec3::from_array(beam.centre),
                    bottom,
                    top,
                };
                assembled.add(&built.mesh, &built.rest, i, "beam", grain);
                if beam.supports_drawn {
                    let lowest = built.mesh.bounds().map_or(0.0, |(lo, _)| lo.z);
                    for piece in drawn_supports(beam, lowest, footprint).map_err(failed)? {
                        within_range(&piece.mesh).map_err(failed)?;
                        let material = assembled.extra(match piece.material {
                            SupportMaterial::Steel => "steel",
                            SupportMaterial::Concrete => "concrete",
                        });
                        let grain = grain_of(&piece.mesh.positions);
                        assembled.add_piece(&piece.mesh, i, piece.part, grain, material);
                    }
                }
                beams.push(Some(BeamOutcome {
                    labels: built.deformation.labels,
                    segments: built.segments,
                    damage: built.damage,
                }));
            }
            Structure::Assembly(a) => {
                // Shapes are placed in world coordinates: the assembly's sphere is about the origin.
                let footprint = dataset
                    .camera
                    .nearest_pixel_footprint(DVec3::ZERO, assembly_radius(a));
                for shape in mesh_assembly(a, footprint).map_err(failed)? {
                    within_range(&shape.mesh)
                        .map_err(|m| failed(format!("part \"{}\": {m}", shape.part)))?;
                    let grain = grain_of(&shape.rest);
                    assembled.add(&shape.mesh, &shape.rest, i, shape.part, grain);
                }
                beams.push(None);
            }
            Structure::Frame(f) => {
                let footprint = dataset
                    .camera
                    .nearest_pixel_footprint(DVec3::ZERO, frame_radius(f));
                let built = mesh_frame(f, footprint).map_err(failed)?;
                for shape in &built.members {
                    within_range(&shape.mesh)
                        .map_err(|m| failed(format!("part \"{}\": {m}", shape.part)))?;
                    assembled.add(
                        &shape.mesh,
                        &shape.rest,
                        i,
                        shape.part,
                        grain_of(&shape.rest),
                    );
                }
                beams.push(None);
                frame_labels = Some(built.labels);
            }
        }
        frames.push(frame_labels);
        if assembled.mesh.triangles.len() > MAX_TRIANGLES {
            return Err(failed(format!(
                "the scene reaches {} triangles with this structure, over the budget of {MAX_TRIANGLES} a sample; coarsen the tessellation or split the scene",
                assembled.mesh.triangles.len()
            )));
        }
    }
    let (centre, radius) = match framing {
        Some(f) => (f.centre, f.radius),
        None => assembled
            .mesh
            .bounding_sphere()
            .expect("a scene has at least one structure"),
    };
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(BuildError::whole_scene(format!(
            "the scene has no extent (radius {radius})"
        )));
    }
    let ground = dataset.ground.as_ref().map(|spec| {
        let lowest = match framing {
            Some(f) => f.lowest,
            None => assembled.mesh.bounds().map_or(0.0, |(lo, _)| lo.z),
        };
        let height = spec.height.unwrap_or(lowest);
        let built = BuiltGround {
            height,
            radius: ground_radius(radius, centre.z - height),
            first_triangle: assembled.mesh.triangles.len(),
            first_vertex: assembled.mesh.positions.len(),
        };
        let square = ground_square(centre, built.height, built.radius);
        let material = assembled.extra_material(spec.material.clone());
        let grain = Grain {
            axis: DVec3::X,
            centre: DVec3::new(centre.x, centre.y, built.height),
            bottom: built.height,
            top: built.height,
        };
        let structures = scene.structures.len();
        assembled.add_piece(&square, structures, GROUND_PART, grain, material);
        built
    });
    let Assembled {
        mesh,
        rest,
        owner,
        part,
        parts,
        piece,
        pieces,
        extras,
        structures: _,
    } = assembled;
    let mut materials = Stream::new(dataset.seed, Scope::Sample(index), seeds::MATERIAL);
    // The structures' materials draw first, so a ground or drawn supports change none of them.
    let shaders = scene
        .structures
        .iter()
        .map(|s| s.material())
        .chain(&extras)
        .map(|m| Shader::new(m, &mut materials))
        .collect();
    let (mut lighting, light_drawn) = draw_light(
        &dataset.light,
        &mut Stream::new(dataset.seed, Scope::Sample(index), seeds::LIGHT),
    );
    // A ground under the structures bounces the light that falls on it, unless the recipe
    // declared its own bounce plane: its mean colour, at its height.
    if let (Some(built), Some(spec), None) = (&ground, &dataset.ground, &lighting.ground) {
        lighting.ground = Some(GroundBounce {
            height: built.height,
            albedo: spec.material.colour.map(srgb_to_linear),
        });
    }
    Ok(BuiltSample {
        index,
        scene,
        beams,
        frames,
        mesh,
        rest,
        piece,
        pieces,
        shaders,
        lighting,
        light_drawn,
        owner,
        part,
        parts,
        centre,
        radius,
        ground,
    })
}

/// Refuses a built structure with a vertex that is not finite or lies beyond
/// [`MAX_COORDINATE`]: its dimensions, placement or deformation are out of any sensible range.
fn within_range(mesh: &Mesh) -> Result<(), String> {
    match mesh.vertex_out_of_range() {
        None => Ok(()),
        Some(p) => Err(format!(
            "a vertex of the built mesh lies at ({}, {}, {}) m, beyond the {MAX_COORDINATE:e} m any scene coordinate may reach (check the structure's dimensions, placement and loads)",
            p.x, p.y, p.z
        )),
    }
}

/// The scene mesh being put together, with each triangle's structure, part and piece.
#[derive(Default)]
struct Assembled {
    mesh: Mesh,
    rest: Vec<DVec3>,
    owner: Vec<u32>,
    part: Vec<u32>,
    parts: Vec<String>,
    piece: Vec<u32>,
    /// Shader index and grain of every piece: structure i's material is shader i, and the
    /// materials of drawn supports and the ground follow the structures' as `extras`.
    pieces: Vec<(u32, Grain)>,
    /// Materials beyond the structures' (supports, ground), in order of first use.
    extras: Vec<Material>,
    /// The number of structures, known once the first extra material is asked for.
    structures: usize,
}

/// Grain along the longest side of a piece's undeformed bounding box.
fn grain_of(rest: &[DVec3]) -> Grain {
    let (lo, hi) = geometry::bounds(rest).unwrap_or_default();
    let size = hi - lo;
    let axis = if size.x >= size.y && size.x >= size.z {
        DVec3::X
    } else if size.y >= size.z {
        DVec3::Y
    } else {
        DVec3::Z
    };
    Grain {
        axis,
        centre: 0.5 * (lo + hi),
        bottom: lo.z,
        top: hi.z,
    }
}

/// Lowest and highest z of a piece's undeformed surface (where runs and dirt start).
fn heights(rest: &[DVec3]) -> (f64, f64) {
    let (lo, hi) = geometry::bounds(rest).unwrap_or_default();
    (lo.z, hi.z)
}

impl Assembled {
    /// Shader index of the material a structure-independent piece is drawn in, from its
    /// prompt (the supports' "steel" and "concrete").
    fn extra(&mut self, prompt_text: &str) -> u32 {
        let material = prompt::compile(prompt_text, true)
            .expect("a word of the vocabulary")
            .material;
        self.extra_material(material)
    }

    /// Shader index of `material` among the extra materials, added on first use.
    fn extra_material(&mut self, material: Material) -> u32 {
        let at = match self.extras.iter().position(|m| *m == material) {
            Some(at) => at,
            None => {
                self.extras.push(material);
                self.extras.len() - 1
            }
        };
        (self.structures + at) as u32
    }

    /// A piece that does not deform (its rest positions are its positions) of structure
    /// `owner` (the ground: one past the last structure) drawn in shader `shader`.
    fn add_piece(&mut self, mesh: &Mesh, owner: usize, part: &str, grain: Grain, shader: u32) {
        self.add(mesh, &mesh.positions, owner, part, grain);
        self.pieces.last_mut().expect("just added").0 = shader;
    }

    fn add(&mut self, mesh: &Mesh, rest: &[DVec3], structure: usize, part: &str, grain: Grain) {
        let id = match self.parts.iter().position(|p| p == part) {
            Some(id) => id,
            None => {
                self.parts.push(part.to_string());
                self.parts.len() - 1
            }
        };
        self.owner
            .extend(std::iter::repeat_n(structure as u32, mesh.triangles.len()));
        self.part
            .extend(std::iter::repeat_n(id as u32, mesh.triangles.len()));
        self.piece.extend(std::iter::repeat_n(
            self.pieces.len() as u32,
            mesh.triangles.len(),
        ));
        self.pieces.push((structure as u32, grain));
        self.rest.extend_from_slice(rest);
        self.mesh.append(mesh);
    }
}
