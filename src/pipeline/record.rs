//! The records of a dataset — `run.json` and the JSON of every view — as typed, versioned
//! structs: the one place their fields are defined. Their JSON Schemas (`docs/schema/`) are
//! generated from these types.

use super::augmented::{Applied, turned_camera};
use super::finite::check_finite;
use super::view::{Eye, ViewCamera};
use crate::augment::Similarity;
use crate::build::{BackdropDraw, BuiltSample, LightDraw};
use crate::cameras::{Camera, CameraRig, Distortion, ViewDraw, rows4};
use crate::materials::procedural::CRACK_LABEL_COVER;
use crate::materials::{Material, MaterialDraw};
use crate::mechanics::{Labels, SectionProperties};
use crate::output::{FLOW_CHANNELS, SAMPLE_WRITERS, SCALAR_CHANNELS, VECTOR_CHANNELS, WRITERS};
use crate::recipe::Recipe;
use crate::render::ViewVisibility;
use crate::scene::{DatasetSpec, GeometryMode, NormalsFrame, Structure};
use crate::seeds;
use anyhow::Result;
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;

/// Tags `run.json`; bump when a field changes meaning.
#[derive(Clone, Copy, Debug, Serialize, schemars::JsonSchema)]
pub enum RunSchema {
    /// `shmgen.run/1`: the first version of `run.json`.
    #[serde(rename = "shmgen.run/1")]
    V1,
}

/// Tags each view's JSON; bump when a field changes meaning or the view's files change form.
#[derive(Clone, Copy, Debug, Serialize, schemars::JsonSchema)]
pub enum ViewSchema {
    /// `shmgen.view/2`: the EXR files' channels are the ones OpenCV reads (depth `Y`, normals
    /// and displacement `R G B`, flow `R G`); `shmgen.view/1` wrote depth `Z`, vectors `X Y Z`,
    /// flow `U V`, with the same fields.
    #[serde(rename = "shmgen.view/2")]
    V2,
}

/// `run.json`: everything that identifies a dataset, and nothing about how it was run
/// (threads, shard, output path), so every shard and every resumed run agrees on it.
#[derive(Serialize, schemars::JsonSchema)]
pub struct RunRecord<'a> {
    /// Version tag of this record: "shmgen.run/1".
    pub schema: RunSchema,
    /// The program that wrote the dataset.
    pub tool: Tool,
    /// The recipe file and the hash of everything it read.
    pub recipe: RecipeRecord<'a>,
    /// The resolved value of every parameter the recipe declared.
    pub params: &'a BTreeMap<String, Value>,
    /// The dataset's settings as the recipe resolved them: name, seed, counts, camera distribution,
    /// outputs, light and background.
    pub dataset: &'a DatasetSpec,
    /// Version tag of every view's JSON in this dataset.
    pub view_schema: ViewSchema,
    /// Where a view's files are, by sample and view index: the dataset's outputs and the
    /// view's JSON; then, if the dataset writes any, where a sample's own files are.
    pub layout: String,
    /// What `manifest.jsonl` holds.
    pub manifest: &'static str,
}

/// The program that wrote a dataset.
#[derive(Serialize, schemars::JsonSchema)]
pub struct Tool {
    /// Program name: "shmgen".
    pub name: &'static str,
    /// Program version (semantic versioning).
    pub version: &'static str,
}

/// The recipe a dataset was built from: its file name and the blake3 hash of its sources (the
/// recipe, every module it imports and every file it reads: meshes, textures, images).
#[derive(Serialize, schemars::JsonSchema)]
pub struct RecipeRecord<'a> {
    /// File name of the recipe, without its folder, when the dataset was created (a resumed
    /// run keeps it: a renamed copy of a recipe is the same dataset).
    pub file: String,
    /// blake3 hash (hex) over the content of the recipe, the modules it imports and the files
    /// it reads (each by its own blake3, under the name the recipe uses for it); the same
    /// recipe and files give the same hash, however their paths were spelled.
    pub hash: &'a str,
}

/// The JSON of one view: everything needed to re-create and interpret its files.
#[derive(Serialize, schemars::JsonSchema)]
pub struct ViewRecord<'a> {
    /// Version tag of this record: "shmgen.view/2".
    pub schema: ViewSchema,
    /// The dataset's name.
    pub dataset: &'a str,
    /// Sample index, from 0.
    pub sample: u64,
    /// View index within the sample, from 0.
    pub view: u32,
    /// The view's files by output, relative to the dataset root.
    pub files: BTreeMap<&'static str, String>,
    /// The files of the whole sample, shared by its views (meshes, point cloud), by kind
    /// (`mesh.ply`, `rest.ply`, `mesh.glb`, `points.ply`), relative to the dataset root.
    pub sample_files: &'a BTreeMap<&'static str, String>,
    /// The random streams every value of this view was drawn from.
    pub seeds: Seeds,
    /// The resolved value of every parameter the recipe declared.
    pub params: &'a BTreeMap<String, Value>,
    /// The camera of this view: intrinsics, poses and the values drawn.
    pub camera: CameraRecord,
    /// How to read the depth files: `depth` and `rest_depth` (the unloaded structure).
    pub depth: DepthConvention,
    /// How to read the ray distance file.
    pub ray_distance: DepthConvention,
    /// How to read the normals file.
    pub normals: VectorConvention,
    /// How to read the displacement file.
    pub displacement: VectorConvention,
    /// How to read the flow files (`flow` and `flow_valid`).
    pub flow: VectorConvention,
    /// How to read the flow between frames of a sequence (`flow_next`, `flow_next_valid`,
    /// `flow_prev`, `flow_prev_valid`); only when the dataset writes them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_flow: Option<VectorConvention>,
    /// How to read the true point tracks of a sequence (`tracks`); only when the dataset
    /// writes them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point_tracks: Option<TracksConvention>,
    /// How to read the mask file.
    pub mask: MaskConvention,
    /// How to read the crack file.
    pub cracks: CrackConvention,
    /// How to read the damage files (`damage_class`, `damage_instance`, `crack_width`,
    /// `crack_coverage`); only when the dataset writes them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damage: Option<DamageConvention>,
    /// The id tables of the part and instance images.
    pub segmentation: &'a Segmentation,
    /// What the RGB image shows where no structure is.
    pub background: &'a BackdropDraw,
    /// The light of the sample, as drawn.
    pub light: &'a LightDraw,
    /// The ground the structures stand on (absent without `dataset.ground`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground: Option<GroundRecord<'a>>,
    /// The sample's structures as described, with what the sample drew for their materials and, for
    /// beams, what the mechanics found.
    pub scene: SceneRecord<'a>,
    /// Size of the sample's deformed mesh.
    pub mesh: MeshRecord,
    /// Share of the pixels that see a structure, 0–1.
    pub coverage: f64,
    /// How the images were found: each pixel's first surface rasterised (projecting the
    /// triangles; the default for pinhole views) or traced through the BVH (lenses, meshes
    /// finer than the pixels), the same hits either way; and what else was traced.
    pub visibility: ViewVisibility,
    /// For an augmented copy, what was done to it (null for a clean view).
    pub augmentation: Option<AugmentationRecord<'a>>,
    /// What the sensor did to the RGB images (`dataset.sensor`), in order, with every value
    /// drawn; left out when the dataset declares no sensor effects.
    #[serde(default, skip_serializing_if = "<[Applied]>::is_empty")]
    pub sensor: &'a [Applied],
    /// For a frame of a sequence (`dataset.sequence`): which frame and when; absent for a still.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame: Option<FrameRecord>,
}

/// Which frame of a sequence a view shows and when. Every geometric layer and label is the
/// structure at `time`; `displacement` is still measured from the unloaded structure.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FrameRecord {
    /// Frame index k, from 0.
    pub index: u32,
    /// Its instant t = k / fps, seconds from the start of the sequence.
    pub time: f64,
    /// How long the shutter was open, seconds: the RGB image is rendered at `time`, or with
    /// `motion_blur` averaged over the exposure.
    pub exposure: f64,
    /// Frames in the sequence.
    pub frames: u32,
    /// Frame rate, frames per second.
    pub fps: f64,
    /// How this view's camera mount was displaced at this frame, in the camera's own axes
    /// (already in `camera`'s poses); absent when the mounts are still.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mount: Option<super::sequence::MountOffset>,
    /// Motion blur (`dataset.sequence.motion_blur`): the RGB image is the average, in linear
    /// light before the sensor's effects, of this many renders at the midpoints of equal parts
    /// of [time − exposure/2, time + exposure/2] (the structures, their loads and the mount at
    /// each); every other layer and label is at `time`, mid-exposure. Absent: no blur.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion_blur: Option<u32>,
}

/// How an augmented copy was made. Its camera (K and pose) is the one its files agree with.
#[derive(Serialize, schemars::JsonSchema)]
pub struct AugmentationRecord<'a> {
    /// Copy index of the view, from 0 (its files end in `a{copy}`).
    pub copy: u32,
    /// How its geometric operation acted.
    pub mode: GeometryMode,
    /// The operations applied, in order, with every value drawn.
    pub operations: &'a [Applied],
}

/// What a view's record says about the view itself: which one, through which camera, and
/// what it shows.
pub struct ViewFacts<'a> {
    /// View index within the sample.
    pub view: u32,
    /// The camera its files agree with.
    pub camera: Camera,
    /// The camera as drawn, with its place in a stereo pair.
    pub drawn: &'a ViewCamera,
    /// The background drawn for the view.
    pub backdrop: &'a BackdropDraw,
    /// Share of the pixels that see a structure.
    pub coverage: f64,
    /// How an augmented copy was made.
    pub augmentation: Option<AugmentationRecord<'a>>,
    /// What the sensor did to the view's RGB images.
    pub sensor: &'a [Applied],
}

impl ViewFacts<'_> {
    /// The similarity of the copy's geometric operation, if it has one.
    fn geometry(&self) -> Option<Similarity> {
        let operations = self.augmentation.as_ref()?.operations;
        operations.iter().find_map(Applied::geometry)
    }
}

/// Where the random values of a view came from: streams derived from the run seed, a scope
/// (sample, or sample and view) and a name.
#[derive(Serialize, schemars::JsonSchema)]
pub struct Seeds {
    /// The dataset's seed.
    pub run_seed: u64,
    /// The stream the recipe's `scene` function drew this sample from.
    pub scene_stream: StreamRecord,
    /// The stream this view's camera was drawn from.
    pub camera_stream: StreamRecord,
    /// The stream the sample's material variations were drawn from.
    pub material_stream: StreamRecord,
    /// The stream the sample's light was drawn from.
    pub light_stream: StreamRecord,
    /// The stream this view's background was drawn from.
    pub background_stream: StreamRecord,
    /// The stream the sample's point cloud was drawn from.
    pub points_stream: StreamRecord,
}

impl Seeds {
    /// The streams of view `view`, whose camera pose is `pose` (the view itself, or the pair
    /// of a stereo view).
    fn of_view(run_seed: u64, sample: u64, view: u32, pose: u32) -> Self {
        let of_sample = |name| StreamRecord {
            scope: vec![sample],
            name,
        };
        let of_view = |name| StreamRecord {
            scope: vec![sample, u64::from(view)],
            name,
        };
        Seeds {
            run_seed,
            scene_stream: of_sample(seeds::SCENE),
            camera_stream: StreamRecord {
                scope: vec![sample, u64::from(pose)],
                name: seeds::CAMERA,
            },
            material_stream: of_sample(seeds::MATERIAL),
            light_stream: of_sample(seeds::LIGHT),
            background_stream: of_view(seeds::BACKGROUND),
            points_stream: of_sample(seeds::POINTS),
        }
    }
}

/// One random stream: ChaCha8 seeded from the blake3 hash of the run seed, its scope and its name.
#[derive(Serialize, schemars::JsonSchema)]
pub struct StreamRecord {
    /// The indices the stream is derived from besides the run seed: [sample] or [sample, view].
    pub scope: Vec<u64>,
    /// The stream's name.
    pub name: &'static str,
}

/// The projection model of a camera.
#[derive(Serialize, schemars::JsonSchema)]
pub enum CameraModel {
    /// OpenCV's pinhole with Brown–Conrady distortion (`camera.distortion`), as COLMAP's and
    /// nerfstudio's "OPENCV".
    #[serde(rename = "opencv")]
    Opencv,
    /// An ideal pinhole camera: no lens distortion; a world point projects through `K` and
    /// `w2c_opencv` alone.
    #[serde(rename = "pinhole")]
    Pinhole,
}

/// The camera of a view. Matrices are row-major; OpenCV axes are x right, y down, z forward,
/// and `c2w_opengl = c2w_opencv · diag(1, −1, −1, 1)`.
#[derive(Serialize, schemars::JsonSchema)]
pub struct CameraRecord {
    /// The projection model.
    pub model: CameraModel,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Pixel (i, j) has its centre at (j + pixel_center, i + pixel_center) in K's coordinates.
    pub pixel_center: f64,
    /// Intrinsic matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], pixels; row-major.
    #[serde(rename = "K")]
    pub k: [[f64; 3]; 3],
    /// World-to-camera transform in OpenCV axes, row-major 4 × 4, metres:
    /// [x_cam, 1] = w2c_opencv · [x_world, 1]; the inverse of `c2w_opencv`.
    pub w2c_opencv: [[f64; 4]; 4],
    /// Camera-to-world transform in OpenCV axes (x right, y down, z forward), row-major 4 × 4,
    /// metres; its last column is the camera centre.
    pub c2w_opencv: [[f64; 4]; 4],
    /// Camera-to-world transform in OpenGL/nerfstudio axes (x right, y up, z backward), row-major
    /// 4 × 4, metres: nerfstudio's `transform_matrix`.
    pub c2w_opengl: [[f64; 4]; 4],
    /// Centre of projection, world axes, metres.
    pub position: [f64; 3],
    /// The point the camera was aimed at, world axes, metres: the centre of the sample's
    /// bounding sphere (or the rig's target), plus any aim jitter.
    pub target: [f64; 3],
    /// Lens distortion in OpenCV's convention (all zero for a pinhole): a pixel's normalised
    /// coordinates are the distortion of (X/Z, Y/Z).
    pub distortion: Distortion,
    /// The values drawn for this view's pose and lens.
    pub drawn: ViewDraw,
    /// For a view of a stereo rig, its pair (null otherwise).
    pub stereo: Option<StereoRecord>,
}

/// A view's place in a stereo pair.
#[derive(Serialize, schemars::JsonSchema)]
pub struct StereoRecord {
    /// The pose both eyes share (views 2·pair and 2·pair + 1).
    pub pair: u32,
    /// Which eye this view is.
    pub eye: Eye,
    /// The view index of the other eye.
    pub partner_view: u32,
    /// Distance between the eyes' centres, metres.
    pub baseline: f64,
    /// Turn of the right eye towards the left eye's axis, radians (0: rectified pair).
    pub toe_in: f64,
    /// Row-major 4 × 4 taking a point from the left eye's OpenCV camera frame to the right
    /// eye's, as the two views (or the two copies with this copy index) are written:
    /// [x_right, 1] = right_from_left · [x_left, 1] = w2c_right · c2w_left. A copy's geometric
    /// operation is drawn once per pair and turns both eyes alike, so a turned pair is still
    /// rigid, with this relative pose.
    pub right_from_left: [[f64; 4]; 4],
}

/// What a depth value measures.
#[derive(Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DepthKind {
    /// Distance along the optical axis.
    PlanarZ,
    /// Euclidean distance from the camera centre to the surface point, along the pixel's ray.
    RayDistance,
}

/// The unit of the values of a file.
#[derive(Serialize, schemars::JsonSchema)]
pub enum Unit {
    /// Metres.
    #[serde(rename = "m")]
    Metre,
    /// Pixels.
    #[serde(rename = "px")]
    Pixel,
    /// Dimensionless.
    #[serde(rename = "1")]
    Unitless,
}

/// The axes the vectors of a file are expressed in.
#[derive(Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Axes {
    /// The view's camera axes, OpenCV's: x right, y down, z forward.
    CameraOpencv,
    /// World axes: right-handed, +z up.
    World,
    /// Image axes: u along a row (right), v down the columns, as pixel coordinates.
    Image,
}

/// How to read a file of one vector per pixel (float32 OpenEXR, one channel per component,
/// named so OpenCV reads them: `cv2.imread(path, cv2.IMREAD_UNCHANGED)` returns the channels
/// B, G, R, that is the components in reverse order, B = 0 for a 2-vector).
#[derive(Serialize, schemars::JsonSchema)]
pub struct VectorConvention {
    /// What each pixel's vector is.
    pub meaning: &'static str,
    /// The axes of the vectors.
    pub axes: Axes,
    /// Unit of the components.
    pub unit: Unit,
    /// EXR channels holding the components, in axis order: ["R", "G", "B"] = (x, y, z), or
    /// ["R", "G"] = (u, v) for flow.
    pub channels: Vec<&'static str>,
    /// The value of every component where the pixel has no vector (no surface seen, or for flow
    /// an invalid pixel): 0.
    pub no_value: f64,
}

/// How to read a frame's point tracks: NumPy float64 `[queries, 3]`, a row per query point of
/// the sequence's first frame, in the same order in every frame.
#[derive(Serialize, schemars::JsonSchema)]
pub struct TracksConvention {
    /// What a row is.
    pub meaning: &'static str,
    /// The columns, in order.
    pub columns: [&'static str; 3],
    /// What the values of the `state` column mean.
    pub states: BTreeMap<&'static str, &'static str>,
    /// The query grid's stride, pixels: the queries are the first frame's structure pixels
    /// at rows and columns stride/2 + n·stride, in row-major order.
    pub stride: u32,
}

/// How to read a file of one distance per pixel (float32 OpenEXR, one channel, `Y`, which
/// OpenCV reads as a grey image).
#[derive(Serialize, schemars::JsonSchema)]
pub struct DepthConvention {
    /// What a value measures: "planar_z", the camera-frame z of the surface point (not the
    /// distance along the ray), or "ray_distance", its distance from the camera centre.
    pub kind: DepthKind,
    /// Unit of the values: "m".
    pub unit: Unit,
    /// The value of pixels that see no surface (0).
    pub no_surface: f64,
    /// The EXR channel holding the values: "Y".
    pub channel: &'static str,
}

/// How to read the mask file.
#[derive(Serialize, schemars::JsonSchema)]
pub struct MaskConvention {
    /// Value of pixels that see a structure (255).
    pub structure: u8,
    /// Value of pixels that see no structure (0).
    pub background: u8,
}

/// How to read the crack file.
#[derive(Serialize, schemars::JsonSchema)]
pub struct CrackConvention {
    /// Value of pixels labelled a crack (255).
    pub crack: u8,
    /// Value of every other pixel, structure or background (0).
    pub elsewhere: u8,
    /// When a pixel is labelled a crack, in words.
    pub rule: &'static str,
    /// Share of the pixel's footprint, 0–1, a crack must cover for the pixel to be labelled a
    /// crack.
    pub min_cover: f64,
}

/// How to read the damage files (docs/damage.md).
#[derive(Serialize, schemars::JsonSchema)]
pub struct DamageConvention {
    /// The damage type of each value of `damage_class` (8-bit): index = value, 0 "none".
    pub classes: [&'static str; 8],
    /// What `damage_instance` (16-bit) holds.
    pub instance: &'static str,
    /// What `crack_width` (float32 channel Y) holds.
    pub crack_width: &'static str,
    /// What `crack_coverage` (float32 channel Y) holds.
    pub crack_coverage: &'static str,
    /// The EXR channel of `crack_width` and `crack_coverage` ("Y").
    pub channel: &'static str,
    /// Share of a pixel below which a crack counts as unresolved by a view (the run warns
    /// when no view of a sample resolves a crack).
    pub resolved_coverage: f64,
}

/// The id tables of the segmentation images, shared by every view of a sample.
#[derive(Serialize, schemars::JsonSchema)]
pub struct Segmentation {
    /// Part names by id; id 0 is "background".
    pub part_ids: Vec<String>,
    /// The structure each instance id is; id 0 (background) is null.
    pub instance_ids: Vec<Option<Instance>>,
    /// How the part and instance images store ids.
    pub encoding: &'static str,
}

/// A structure of the scene, as an instance id names it.
#[derive(Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Instance {
    /// A beam.
    Beam {
        /// Index of the structure in `scene.structures`, from 0 (its instance id minus 1).
        structure: usize,
    },
    /// An assembly of primitives.
    Assembly {
        /// Index of the structure in `scene.structures`, from 0 (its instance id minus 1).
        structure: usize,
        /// The assembly's name, as the recipe gave it.
        name: String,
    },
    /// The ground (`dataset.ground`): the id after the last structure's.
    Ground,
}

/// The structures of a sample.
#[derive(Serialize, schemars::JsonSchema)]
pub struct SceneRecord<'a> {
    /// Every structure of the sample, in the order the recipe returned them; instance
    /// id = index + 1.
    pub structures: &'a [StructureRecord<'a>],
}

/// A structure as described, with what its sample drew and, for beams, what the mechanics
/// found.
#[derive(Serialize, schemars::JsonSchema)]
pub struct StructureRecord<'a> {
    /// The structure as the recipe described it; its fields appear at this level.
    #[serde(flatten)]
    pub structure: &'a Structure,
    /// What this sample drew for the structure's material.
    pub material_drawn: MaterialDraw,
    /// For a beam, what the mechanics found (its fields appear at this level); absent for
    /// assemblies.
    #[serde(flatten)]
    pub beam: Option<BeamRecord<'a>>,
    /// For a frame, what its analysis found: node displacements and rotations, reactions,
    /// member end forces, peak stress and utilisation; absent for other structures.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub analysis: Option<&'a crate::mechanics::frame::FrameLabels>,
    /// For an assembly whose shells carry dents or local buckles, those as damage records
    /// (type, position, size, depth, severity, cause, dimple tolerance); absent otherwise.
    #[serde(rename = "damage", skip_serializing_if = "Option::is_none")]
    #[schemars(with = "Option<AnyDamage>")]
    pub shell_damage: Option<crate::mechanics::damage::ShellDamageLabels>,
}

/// A structure's `damage`: a beam's (cracks, corrosion, spalls, dents, and what they did to
/// its stiffness) or an assembly's shells' (dents and local buckles). Only describes the
/// schema: the two records share the one key, so its schema must admit both.
#[derive(schemars::JsonSchema)]
#[serde(untagged)]
#[allow(dead_code)]
enum AnyDamage {
    /// A beam's damage.
    Beam(crate::mechanics::damage::DamageLabels),
    /// The dents and local buckles of an assembly's shells.
    Shells(crate::mechanics::damage::ShellDamageLabels),
}

/// What the mechanics of a beam found.
#[derive(Serialize, schemars::JsonSchema)]
pub struct BeamRecord<'a> {
    /// Properties of the beam's cross-section the mechanics used.
    pub section_properties: SectionProperties,
    /// Equal intervals the beam was meshed with along its length; stations at load positions
    /// and at the peak deflection come on top.
    pub segments: usize,
    /// What the mechanics found: the theory used and its estimated error, the physical loads, the
    /// peak deflection, moment and stress, and whether the beam could carry the loads.
    pub labels: &'a Labels,
    /// The beam's damage (cracks, corrosion, spalls, dents: type, position on the undeformed
    /// surface, size, orientation, width in mm, severity, cause), the crack model's section,
    /// and the damaged beam's stiffness and deflection; absent for a sound beam.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damage: Option<&'a crate::mechanics::damage::DamageLabels>,
}

/// The ground of a sample: a flat square under the structures, drawn in the RGB image.
#[derive(Serialize, schemars::JsonSchema)]
pub struct GroundRecord<'a> {
    /// What the ground is made of, compiled from its name.
    pub material: &'a Material,
    /// What the sample drew for the ground's material variations.
    pub material_drawn: MaterialDraw,
    /// Height of the ground plane, world z, metres: the structures' lowest point unless the
    /// recipe set it.
    pub height: f64,
    /// Half the side of the ground square about the scene's centre, metres (its edge lies
    /// near the horizon).
    pub half_side: f64,
    /// Whether depth, normals, ray distance, displacement, flow and rest depth see the ground
    /// (else they hold 0 there, as for the background). The mask never includes it.
    pub in_depth: bool,
    /// The ground's id in the part images (`segmentation.part_ids`).
    pub part_id: usize,
    /// The ground's id in the instance images (`segmentation.instance_ids`).
    pub instance_id: usize,
}

/// Size of the sample's deformed mesh.
#[derive(Serialize, schemars::JsonSchema)]
pub struct MeshRecord {
    /// Vertices of the sample's deformed mesh, all structures together.
    pub vertices: usize,
    /// Triangles of the sample's deformed mesh, all structures together.
    pub triangles: usize,
    /// Radius of the deformed scene's bounding sphere about `camera.target`, metres.
    pub bounding_radius: f64,
}

/// What every view of a sample shares in its record.
pub struct SampleRecord<'a> {
    /// The record of every structure of the sample.
    pub structures: Vec<StructureRecord<'a>>,
    /// The id tables of the part and instance images.
    pub segmentation: Segmentation,
    /// The sample's own files (meshes, point cloud) by kind, once written.
    pub files: BTreeMap<&'static str, String>,
    /// The frame of a sequence this record describes, if it is one.
    pub frame: Option<FrameRecord>,
}

/// Pretty JSON with a final newline, as every record is written; a record holding a
/// non-finite number is refused (JSON would show it as `null`).
pub fn json_bytes(record: &impl Serialize) -> Result<Vec<u8>> {
    check_finite(record)?;
    let mut bytes = serde_json::to_vec_pretty(record)?;
    bytes.push(b'\n');
    Ok(bytes)
}

/// `run.json` of `recipe`. `recorded` is the run.json already in the dataset folder, if
/// any: the recipe's file name does not identify a dataset (no output byte depends on it, and
/// the hash covers the recipe's content), so a dataset resumed from a renamed copy of its
/// recipe keeps the name it was created with.
pub fn run_json(recipe: &Recipe, recorded: Option<&Value>) -> Result<Vec<u8>> {
    let file = match recorded.and_then(|r| r.pointer("/recipe/file")?.as_str()) {
        Some(file) => file.to_string(),
        None => recipe
            .path
            .file_name()
            .map(|f| f.to_string_lossy().to_string())
            .unwrap_or_default(),
    };
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
        view_schema: ViewSchema::V2,
        layout: layout(&recipe.dataset),
        manifest: "manifest.jsonl: one line per finished sample, in sample order once the dataset is complete: {sample, views, files, hashes: {file: {bytes, blake3}}}",
    })
}

/// The path pattern of a view's files, listing the files of every output the dataset writes,
/// then that of the sample's own files, if it writes any.
fn layout(dataset: &DatasetSpec) -> String {
    let files: Vec<&str> = WRITERS
        .iter()
        .filter(|w| dataset.outputs.wants(w.output))
        .flat_map(|w| w.files.iter().copied())
        .chain(["json"])
        .collect();
    let copy = if dataset.augment.copies > 0 {
        "[a{copy}]"
    } else {
        ""
    };
    let views = format!(
        "samples/{{sample/1000:04}}/{{sample:06}}_{{view:02}}{copy}.{{{}}}",
        files.join(",")
    );
    let own: Vec<&str> = SAMPLE_WRITERS
        .iter()
        .filter(|w| dataset.outputs.wants(w.output))
        .flat_map(|w| w.files.iter().copied())
        .collect();
    if own.is_empty() {
        return views;
    }
    format!(
        "{views}; samples/{{sample/1000:04}}/{{sample:06}}.{{{}}}",
        own.join(",")
    )
}

/// The record of a sample's ground, when the dataset has one.
fn ground_record<'a>(dataset: &'a DatasetSpec, sample: &BuiltSample) -> Option<GroundRecord<'a>> {
    let (spec, built) = (dataset.ground.as_ref()?, sample.ground?);
    let part = sample.part[built.first_triangle];
    let shader = sample.pieces[sample.piece[built.first_triangle] as usize].0;
    Some(GroundRecord {
        material: &spec.material,
        material_drawn: sample.shaders[shader as usize].drawn(),
        height: built.height,
        half_side: built.radius,
        in_depth: spec.in_depth,
        part_id: part as usize + 1,
        instance_id: sample.scene.structures.len() + 1,
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
            .zip(&sample.frames)
            .map(
                |(((structure, outcome), shader), analysis)| StructureRecord {
                    structure,
                    material_drawn: shader.drawn(),
                    beam: match (structure, outcome) {
                        (Structure::Beam(b), Some(outcome)) => Some(BeamRecord {
                            section_properties: b.section.properties(b.poisson),
                            segments: outcome.segments,
                            labels: &outcome.labels,
                            damage: outcome.damage.as_ref(),
                        }),
                        _ => None,
                    },
                    analysis: analysis.as_ref(),
                    shell_damage: match structure {
                        Structure::Assembly(a) => super::damage::assembly_damage(a),
                        _ => None,
                    },
                },
            )
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
                Structure::Frame(f) => Instance::Assembly {
                    structure: i,
                    name: f.name.clone(),
                },
            })
        }));
        if sample.ground.is_some() {
            instance_ids.push(Some(Instance::Ground));
        }
        SampleRecord {
            structures,
            segmentation: Segmentation {
                part_ids,
                instance_ids,
                encoding: "PNG grey, 8-bit when every id fits, else 16-bit; 0 = background",
            },
            files: BTreeMap::new(),
            frame: None,
        }
    }

    /// The record of one view of the sample, whose files are `files`.
    pub fn view(
        &'a self,
        recipe: &'a Recipe,
        sample: &'a BuiltSample,
        facts: ViewFacts<'a>,
        visibility: ViewVisibility,
        files: BTreeMap<&'static str, String>,
    ) -> ViewRecord<'a> {
        let camera = &facts.camera;
        let view = facts.view;
        let rig = &recipe.dataset.camera;
        let k = &camera.intrinsics;
        ViewRecord {
            schema: ViewSchema::V2,
            dataset: &recipe.dataset.name,
            sample: sample.index,
            view,
            files,
            sample_files: &self.files,
            seeds: Seeds::of_view(
                recipe.dataset.seed,
                sample.index,
                view,
                facts.drawn.stereo.map_or(view, |(pair, _)| pair),
            ),
            params: &recipe.params,
            camera: CameraRecord {
                model: if k.distortion.is_none() {
                    CameraModel::Pinhole
                } else {
                    CameraModel::Opencv
                },
                width: k.width,
                height: k.height,
                fov_y: 2.0 * (0.5 * f64::from(k.height) / k.fy).atan(),
                pixel_center: 0.5,
                k: camera.intrinsics.matrix(),
                w2c_opencv: rows4(camera.w2c_cv()),
                c2w_opencv: rows4(camera.c2w_cv()),
                c2w_opengl: rows4(camera.c2w_gl()),
                position: camera.position.to_array(),
                target: facts.drawn.draw.aim,
                distortion: k.distortion,
                drawn: facts.drawn.draw,
                stereo: stereo_record(rig, facts.drawn, view, facts.geometry()),
            },
            depth: DepthConvention {
                kind: DepthKind::PlanarZ,
                unit: Unit::Metre,
                no_surface: 0.0,
                channel: SCALAR_CHANNELS.names[0],
            },
            ray_distance: DepthConvention {
                kind: DepthKind::RayDistance,
                unit: Unit::Metre,
                no_surface: 0.0,
                channel: SCALAR_CHANNELS.names[0],
            },
            normals: normals_convention(recipe.dataset.normals),
            displacement: VectorConvention {
                meaning: "displacement of the surface point seen, from the unloaded (undamaged) structure to the loaded one",
                axes: Axes::World,
                unit: Unit::Metre,
                channels: VECTOR_CHANNELS.names.to_vec(),
                no_value: 0.0,
            },
            flow: VectorConvention {
                meaning: "on the unloaded image (rest_rgb), where the pixel's surface point lands in the loaded image (rgb), minus the pixel centre; valid where flow_valid is 255 (the point lands inside the frame, unhidden)",
                axes: Axes::Image,
                unit: Unit::Pixel,
                channels: FLOW_CHANNELS.names.to_vec(),
                no_value: 0.0,
            },
            frame_flow: recipe
                .dataset
                .outputs
                .wants("frame_flow")
                .then_some(VectorConvention {
                    meaning: "on this frame's image (rgb), where the pixel's material point lands in the next frame's image (flow_next) or the previous frame's (flow_prev), through that frame's camera (its mount shaken as then), minus the pixel centre; valid where flow_next_valid / flow_prev_valid is 255 (the point lands inside that frame, unhidden; none at the last / first frame)",
                    axes: Axes::Image,
                    unit: Unit::Pixel,
                    channels: FLOW_CHANNELS.names.to_vec(),
                    no_value: 0.0,
                }),
            point_tracks: (recipe.dataset.sequence.as_ref())
                .filter(|_| recipe.dataset.outputs.wants("point_tracks"))
                .map(|sequence| tracks_convention(sequence.track_stride)),
            mask: MaskConvention {
                structure: 255,
                background: 0,
            },
            damage: recipe.dataset.outputs.wants("damage").then_some(DamageConvention {
                classes: crate::render::DamageClass::NAMES,
                instance: "index + 1 of the damage in scene.structures[s].damage.items (a frame's: scene.structures[s].analysis.damage.items), where s + 1 is the pixel's value in instances; 0 = none",
                crack_width: "width of the crack the pixel's footprint touches, millimetres; 0 elsewhere",
                crack_coverage: "share of the pixel's footprint the crack covers, 0-1, from the crack's band over the footprint's parallelogram on the surface",
                channel: SCALAR_CHANNELS.names[0],
                resolved_coverage: super::damage::RESOLVED_COVERAGE,
            }),
            cracks: CrackConvention {
                crack: 255,
                elsewhere: 0,
                rule: "at the centre ray's surface point, a crack covers at least this share of the pixel's footprint",
                min_cover: CRACK_LABEL_COVER,
            },
            segmentation: &self.segmentation,
            background: facts.backdrop,
            light: &sample.light_drawn,
            ground: ground_record(&recipe.dataset, sample),
            scene: SceneRecord {
                structures: &self.structures,
            },
            mesh: MeshRecord {
                vertices: sample
                    .ground
                    .map_or(sample.mesh.positions.len(), |g| g.first_vertex),
                triangles: sample.structure_triangles(),
                bounding_radius: sample.radius,
            },
            coverage: facts.coverage,
            visibility,
            augmentation: facts.augmentation,
            sensor: facts.sensor,
            frame: self.frame.map(|f| FrameRecord {
                mount: super::sequence::mount_offset(&recipe.dataset, sample.index, view, f.time),
                ..f
            }),
        }
    }
}

/// How to read the normals file, in the axes the dataset chose.
fn normals_convention(frame: NormalsFrame) -> VectorConvention {
    VectorConvention {
        meaning: "unit normal of the triangle seen, turned towards the camera",
        axes: match frame {
            NormalsFrame::Camera => Axes::CameraOpencv,
            NormalsFrame::World => Axes::World,
        },
        unit: Unit::Unitless,
        channels: VECTOR_CHANNELS.names.to_vec(),
        no_value: 0.0,
    }
}

/// The pair of a stereo view: the right eye's pose relative to the left's, as written. The
/// geometric operation of a copy (`moved_by`) is drawn once per pose, so it turns both eyes'
/// copies alike: the pair stays rigid and its relative pose is that of the turned cameras.
fn stereo_record(
    rig: &CameraRig,
    drawn: &ViewCamera,
    view: u32,
    moved_by: Option<Similarity>,
) -> Option<StereoRecord> {
    let (stereo, (pair, eye)) = (rig.stereo?, drawn.stereo?);
    let left = drawn.left.unwrap_or(drawn.camera);
    let right = rig.right_eye(&left)?;
    let (left, right) = match moved_by {
        Some(sim) => (turned_camera(&left, &sim), turned_camera(&right, &sim)),
        None => (left, right),
    };
    Some(StereoRecord {
        pair,
        eye,
        partner_view: match eye {
            Eye::Left => view + 1,
            Eye::Right => view - 1,
        },
        baseline: stereo.baseline,
        toe_in: stereo.toe_in,
        right_from_left: rows4(right.w2c_cv() * left.c2w_cv()),
    })
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

/// The point tracks' convention, for a query grid of stride `stride`.
fn tracks_convention(stride: u32) -> TracksConvention {
    TracksConvention {
        meaning: "where each query point (a structure pixel's centre on the first frame's image, on the stride grid) is in this frame's image: its material point carried with the structure and projected through this frame's camera (its mount shaken, its path flown as then); pixels, (0.5, 0.5) the centre of the top-left pixel",
        columns: ["x", "y", "state"],
        states: BTreeMap::from([
            ("1", "seen at (x, y)"),
            (
                "0",
                "hidden by a nearer surface, or outside the frame: (x, y) is its projection",
            ),
            (
                "-1",
                "no image: behind the camera, or not on this frame's structure; x = y = 0",
            ),
        ]),
        stride,
    }
}
