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
mod light;
mod tessellation;

pub use assembly::{BuiltShape, assembly_radius, mesh_assembly};
pub use beam::{BuiltBeam, beam_radius, mesh_beam, problem, section_outline, stations};
pub use light::{BackdropDraw, LightDraw, SkyDraw, SunDraw, draw_backdrop, draw_light};
pub use tessellation::{chord_tolerance, segments_for_chord};

use crate::geometry::{self, MAX_COORDINATE, MAX_TRIANGLES, Mesh};
use crate::materials::{Grain, Lighting, Shader};
use crate::mechanics::Labels;
use crate::scene::{DatasetSpec, SceneSpec, SourceSite, Structure};
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
}

/// What building a beam found out: its mechanics labels and its intervals along the length.
pub struct BeamOutcome {
    /// What the mechanics found.
    pub labels: Labels,
    /// Equal intervals along the length (load positions and the peak add stations).
    pub segments: usize,
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
    let mut assembled = Assembled::default();
    let mut beams = Vec::new();
    for (i, structure) in scene.structures.iter().enumerate() {
        let failed = |m: String| BuildError {
            message: format!("structure {i}: {m}"),
            site: structure.declared_at().cloned(),
        };
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
                beams.push(Some(BeamOutcome {
                    labels: built.deformation.labels,
                    segments: built.segments,
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
        }
        if assembled.mesh.triangles.len() > MAX_TRIANGLES {
            return Err(failed(format!(
                "the scene reaches {} triangles with this structure, over the budget of {MAX_TRIANGLES} a sample; coarsen the tessellation or split the scene",
                assembled.mesh.triangles.len()
            )));
        }
    }
    let Assembled {
        mesh,
        rest,
        owner,
        part,
        parts,
        piece,
        pieces,
    } = assembled;
    let (centre, radius) = mesh
        .bounding_sphere()
        .expect("a scene has at least one structure");
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(BuildError::whole_scene(format!(
            "the scene has no extent (radius {radius})"
        )));
    }
    let mut materials = Stream::new(dataset.seed, Scope::Sample(index), seeds::MATERIAL);
    let shaders = scene
        .structures
        .iter()
        .map(|s| Shader::new(s.material(), &mut materials))
        .collect();
    let (lighting, light_drawn) = draw_light(
        &dataset.light,
        &mut Stream::new(dataset.seed, Scope::Sample(index), seeds::LIGHT),
    );
    Ok(BuiltSample {
        index,
        scene,
        beams,
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
    pieces: Vec<(u32, Grain)>,
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
