//! The records of a dataset — `run.json` and the JSON of every view — as typed, versioned
//! structs: the one place their fields are defined. Their JSON Schemas (`docs/schema/`) are
//! generated from these types.

use super::finite::check_finite;
use super::view::RenderedView;
use crate::build::{BackdropDraw, BuiltSample, LightDraw};
use crate::cameras::{ViewDraw, rows4};
use crate::materials::MaterialDraw;
use crate::materials::procedural::CRACK_LABEL_COVER;
use crate::mechanics::{Labels, SectionProperties};
use crate::output::DEPTH_CHANNEL;
use crate::recipe::Recipe;
use crate::scene::{DatasetSpec, Structure};
use anyhow::Result;
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;

/// Tags `run.json`; bump when a field changes meaning.
#[derive(Clone, Copy, Debug, Serialize, schemars::JsonSchema)]
pub enum RunSchema {
    #[serde(rename = "shmgen.run/1")]
    V1,
}

/// Tags each view's JSON; bump when a field changes meaning.
#[derive(Clone, Copy, Debug, Serialize, schemars::JsonSchema)]
pub enum ViewSchema {
    #[serde(rename = "shmgen.view/1")]
    V1,
}

/// `run.json`: everything that identifies a dataset, and nothing about how it was run
/// (threads, shard, output path), so every shard and every resumed run agrees on it.
#[derive(Serialize, schemars::JsonSchema)]
pub struct RunRecord<'a> {
    pub schema: RunSchema,
    pub tool: Tool,
    pub recipe: RecipeRecord<'a>,
    /// The resolved value of every parameter the recipe declared.
    pub params: &'a BTreeMap<String, Value>,
    pub dataset: &'a DatasetSpec,
    pub view_schema: ViewSchema,
    /// Where a view's files are, by sample and view index.
    pub layout: &'static str,
    pub manifest: &'static str,
}

/// The program that wrote a dataset.
#[derive(Serialize, schemars::JsonSchema)]
pub struct Tool {
    pub name: &'static str,
    pub version: &'static str,
}

/// The recipe a dataset was built from: its file name and the blake3 hash of its sources
/// (the recipe and every module it imports).
#[derive(Serialize, schemars::JsonSchema)]
pub struct RecipeRecord<'a> {
    pub file: String,
    pub hash: &'a str,
}

/// The JSON of one view: everything needed to re-create and interpret its files.
#[derive(Serialize, schemars::JsonSchema)]
pub struct ViewRecord<'a> {
    pub schema: ViewSchema,
    /// The dataset's name.
    pub dataset: &'a str,
    pub sample: u64,
    pub view: u32,
    /// The view's files by output, relative to the dataset root.
    pub files: BTreeMap<&'static str, String>,
    pub seeds: Seeds,
    /// The resolved value of every parameter the recipe declared.
    pub params: &'a BTreeMap<String, Value>,
    pub camera: CameraRecord,
    pub depth: DepthConvention,
    pub mask: MaskConvention,
    pub cracks: CrackConvention,
    pub segmentation: &'a Segmentation,
    /// What the RGB image shows where no structure is.
    pub background: &'a BackdropDraw,
    /// The light of the sample, as drawn.
    pub light: &'a LightDraw,
    pub scene: SceneRecord<'a>,
    pub mesh: MeshRecord,
    /// Share of the pixels that see a structure.
    pub coverage: f64,
}

/// Where the random values of a view came from: streams derived from the run seed, a scope
/// (sample, or sample and view) and a name.
#[derive(Serialize, schemars::JsonSchema)]
pub struct Seeds {
    pub run_seed: u64,
    pub scene_stream: StreamRecord,
    pub camera_stream: StreamRecord,
}

#[derive(Serialize, schemars::JsonSchema)]
pub struct StreamRecord {
    pub scope: Vec<u64>,
    pub name: &'static str,
}

#[derive(Serialize, schemars::JsonSchema)]
pub enum CameraModel {
    #[serde(rename = "pinhole")]
    Pinhole,
}

/// The camera of a view. Matrices are row-major; OpenCV axes are x right, y down, z forward,
/// and `c2w_opengl = c2w_opencv · diag(1, −1, −1, 1)`.
#[derive(Serialize, schemars::JsonSchema)]
pub struct CameraRecord {
    pub model: CameraModel,
    pub width: u32,
    pub height: u32,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Pixel (i, j) has its centre at (j + pixel_center, i + pixel_center) in K's coordinates.
    pub pixel_center: f64,
    /// Intrinsics in pixels.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
    pub w2c_opencv: [[f64; 4]; 4],
    pub c2w_opencv: [[f64; 4]; 4],
    pub c2w_opengl: [[f64; 4]; 4],
    /// Centre of projection, world axes.
    pub position: [f64; 3],
    /// The point the camera was aimed at.
    pub target: [f64; 3],
    pub drawn: ViewDraw,
}

#[derive(Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DepthKind {
    /// Distance along the optical axis.
    PlanarZ,
}

#[derive(Serialize, schemars::JsonSchema)]
pub enum Unit {
    #[serde(rename = "m")]
    Metre,
}

/// How to read the depth file.
#[derive(Serialize, schemars::JsonSchema)]
pub struct DepthConvention {
    pub kind: DepthKind,
    pub unit: Unit,
    /// The value of pixels that see no surface.
    pub no_surface: f64,
    /// The EXR channel holding depth.
    pub channel: &'static str,
}

/// How to read the mask file.
#[derive(Serialize, schemars::JsonSchema)]
pub struct MaskConvention {
    pub structure: u8,
    pub background: u8,
}

/// How to read the crack file.
#[derive(Serialize, schemars::JsonSchema)]
pub struct CrackConvention {
    pub crack: u8,
    pub elsewhere: u8,
    pub rule: &'static str,
    pub min_cover: f64,
}

/// The id tables of the segmentation images, shared by every view of a sample.
#[derive(Serialize, schemars::JsonSchema)]
pub struct Segmentation {
    /// Part names by id; id 0 is "background".
    pub part_ids: Vec<String>,
    /// The structure each instance id is; id 0 (background) is null.
    pub instance_ids: Vec<Option<Instance>>,
    pub encoding: &'static str,
}

/// A structure of the scene, as an instance id names it.
#[derive(Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Instance {
    Beam { structure: usize },
    Assembly { structure: usize, name: String },
}

#[derive(Serialize, schemars::JsonSchema)]
pub struct SceneRecord<'a> {
    pub structures: &'a [StructureRecord<'a>],
}

/// A structure as described, with what its sample drew and, for beams, what the mechanics
/// found.
#[derive(Serialize, schemars::JsonSchema)]
pub struct StructureRecord<'a> {
    #[serde(flatten)]
    pub structure: &'a Structure,
    pub material_drawn: MaterialDraw,
    #[serde(flatten)]
    pub beam: Option<BeamRecord<'a>>,
}

/// What the mechanics of a beam found.
#[derive(Serialize, schemars::JsonSchema)]
pub struct BeamRecord<'a> {
    pub section_properties: SectionProperties,
    /// Intervals along the length of the mesh.
    pub segments: usize,
    pub labels: &'a Labels,
}

/// Size of the sample's deformed mesh.
#[derive(Serialize, schemars::JsonSchema)]
pub struct MeshRecord {
    pub vertices: usize,
    pub triangles: usize,
    pub bounding_radius: f64,
}

/// What every view of a sample shares in its record.
pub struct SampleRecord<'a> {
    pub structures: Vec<StructureRecord<'a>>,
    pub segmentation: Segmentation,
}

/// Pretty JSON with a final newline, as every record is written; a record holding a
/// non-finite number is refused (JSON would show it as `null`).
pub fn json_bytes(record: &impl Serialize) -> Result<Vec<u8>> {
    check_finite(record)?;
    let mut bytes = serde_json::to_vec_pretty(record)?;
    bytes.push(b'\n');
    Ok(bytes)
}

/// `run.json` of `recipe`.
pub fn run_json(recipe: &Recipe) -> Result<Vec<u8>> {
    let file = recipe
        .path
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_default();
    json_bytes(&RunRecord {
        schema: RunSchema::V1,
        tool: Tool {
            name: "shmgen",
            version: env!("CARGO_PKG_VERSION"),
        },
        recipe: RecipeRecord {
            file,
            hash: &recipe.hash,
        },
        params: &recipe.params,
        dataset: &recipe.dataset,
        view_schema: ViewSchema::V1,
        layout: "samples/{sample/1000:04}/{sample:06}_{view:02}.{rgb.png,depth.exr,mask.png,json}",
        manifest: "manifest.jsonl: one line per finished sample, in sample order once the dataset is complete",
    })
}

impl<'a> SampleRecord<'a> {
    /// The structures of `sample` with their labels, and its segmentation id tables.
    pub fn new(sample: &'a BuiltSample) -> Self {
        let structures = sample
            .scene
            .structures
            .iter()
            .zip(&sample.beams)
            .zip(&sample.shaders)
            .map(|((structure, outcome), shader)| StructureRecord {
                structure,
                material_drawn: shader.drawn(),
                beam: match (structure, outcome) {
                    (Structure::Beam(b), Some(outcome)) => Some(BeamRecord {
                        section_properties: b.section.properties(b.poisson),
                        segments: outcome.segments,
                        labels: &outcome.labels,
                    }),
                    _ => None,
                },
            })
            .collect();
        let mut part_ids = vec!["background".to_string()];
        part_ids.extend(sample.parts.iter().cloned());
        let mut instance_ids = vec![None];
        instance_ids.extend(sample.scene.structures.iter().enumerate().map(|(i, s)| {
            Some(match s {
                Structure::Beam(_) => Instance::Beam { structure: i },
                Structure::Assembly(a) => Instance::Assembly {
                    structure: i,
                    name: a.name.clone(),
                },
            })
        }));
        SampleRecord {
            structures,
            segmentation: Segmentation {
                part_ids,
                instance_ids,
                encoding: "PNG grey, 8-bit when every id fits, else 16-bit; 0 = background",
            },
        }
    }

    /// The record of one rendered view of the sample, whose files are `files`.
    pub fn view(
        &'a self,
        recipe: &'a Recipe,
        sample: &'a BuiltSample,
        rendered: &'a RenderedView,
        files: BTreeMap<&'static str, String>,
    ) -> ViewRecord<'a> {
        let camera = &rendered.camera;
        let view = rendered.view;
        ViewRecord {
            schema: ViewSchema::V1,
            dataset: &recipe.dataset.name,
            sample: sample.index,
            view,
            files,
            seeds: Seeds {
                run_seed: recipe.dataset.seed,
                scene_stream: StreamRecord {
                    scope: vec![sample.index],
                    name: "scene",
                },
                camera_stream: StreamRecord {
                    scope: vec![sample.index, u64::from(view)],
                    name: "camera",
                },
            },
            params: &recipe.params,
            camera: CameraRecord {
                model: CameraModel::Pinhole,
                width: camera.intrinsics.width,
                height: camera.intrinsics.height,
                fov_y: recipe.dataset.camera.fov_y,
                pixel_center: 0.5,
                k: camera.intrinsics.matrix(),
                w2c_opencv: rows4(camera.w2c_cv()),
                c2w_opencv: rows4(camera.c2w_cv()),
                c2w_opengl: rows4(camera.c2w_gl()),
                position: camera.position.to_array(),
                target: sample.centre.to_array(),
                drawn: rendered.draw,
            },
            depth: DepthConvention {
                kind: DepthKind::PlanarZ,
                unit: Unit::Metre,
                no_surface: 0.0,
                channel: DEPTH_CHANNEL,
            },
            mask: MaskConvention {
                structure: 255,
                background: 0,
            },
            cracks: CrackConvention {
                crack: 255,
                elsewhere: 0,
                rule: "at the centre ray's surface point, a crack covers at least this share of the pixel's footprint",
                min_cover: CRACK_LABEL_COVER,
            },
            segmentation: &self.segmentation,
            background: &rendered.backdrop_drawn,
            light: &sample.light_drawn,
            scene: SceneRecord {
                structures: &self.structures,
            },
            mesh: MeshRecord {
                vertices: sample.mesh.positions.len(),
                triangles: sample.mesh.triangles.len(),
                bounding_radius: sample.radius,
            },
            coverage: rendered.coverage(),
        }
    }
}

/// The JSON Schema (draft 2020-12) of each view's JSON, generated from [`ViewRecord`].
pub fn view_schema() -> Value {
    serde_json::to_value(schemars::schema_for!(ViewRecord<'static>))
        .expect("a schema is plain JSON")
}

/// The JSON Schema (draft 2020-12) of `run.json`, generated from [`RunRecord`].
pub fn run_schema() -> Value {
    serde_json::to_value(schemars::schema_for!(RunRecord<'static>)).expect("a schema is plain JSON")
}
