//! One sample, end to end: scene → deformed mesh → BVH → views → encoded files + JSON.

use crate::cameras::{Camera, ViewDraw, rows4};
use crate::geometry::Mesh;
use crate::materials::{Grain, Shader};
use crate::mechanics::Labels;
use crate::output::{SampleStage, depth_exr, id_png, mask_png, rgb_png, view_file};
use crate::recipe::Recipe;
use crate::render::{GBuffer, Lighting, NO_HIT, SampleSurfaces, TraceMesh, shade};
use crate::scene::{DatasetSpec, PIXEL_TOLERANCE, SceneSpec, Structure};
use crate::seeds::{Scope, Stream};
use anyhow::{Result, bail};
use glam::DVec3;
use serde_json::{Value, json};

/// Identifies the per-view JSON layout; bump when fields change meaning.
pub const VIEW_SCHEMA: &str = "shmgen.view/1";

/// The deformed scene of one sample, ready to be viewed.
pub struct PreparedSample {
    pub index: u64,
    pub scene: SceneSpec,
    /// Mechanics labels and segment count of each beam (None for assemblies).
    pub labels: Vec<Option<(Labels, usize)>>,
    pub mesh: Mesh,
    /// Undeformed position of every vertex (where textures are evaluated).
    pub rest: Vec<DVec3>,
    /// Piece (a beam, or one shape of an assembly) of every triangle.
    pub piece: Vec<u32>,
    /// Structure index and grain direction of every piece.
    pub pieces: Vec<(u32, Grain)>,
    /// The material of every structure, with this sample's random choices.
    pub shaders: Vec<Shader>,
    /// The light of this sample, and the values drawn for it.
    pub lighting: (Lighting, Value),
    /// Structure index of every triangle.
    pub owner: Vec<u32>,
    /// Part of every triangle, as an index into `parts`.
    pub part: Vec<u32>,
    /// Part names, in order of first appearance; part id = index + 1 (0 = background).
    pub parts: Vec<String>,
    pub centre: DVec3,
    pub radius: f64,
}

/// Draws the scene and builds its deformed mesh; fails on anything that would make
/// non-finite output.
pub fn prepare(recipe: &Recipe, index: u64) -> Result<PreparedSample> {
    let scene = recipe.scene(index)?;
    let mut assembled = Assembled::default();
    let mut labels = Vec::new();
    for (i, structure) in scene.structures.iter().enumerate() {
        let failed = |m: String| anyhow::anyhow!("sample {index}, structure {i}: {m}");
        match structure {
            Structure::Beam(beam) => {
                let footprint = recipe.dataset.camera.nearest_pixel_footprint(beam.radius());
                let built = beam.build(footprint).map_err(failed)?;
                let grain = Grain {
                    axis: glam::DMat3::from_rotation_z(beam.yaw) * DVec3::X,
                    centre: DVec3::from_array(beam.centre),
                };
                assembled.add(&built.mesh, &built.rest, i, "beam", grain);
                labels.push(Some((built.deformation.labels, built.segments)));
            }
            Structure::Assembly(a) => {
                let tolerance =
                    PIXEL_TOLERANCE * recipe.dataset.camera.nearest_pixel_footprint(a.radius());
                for shape in a.build(tolerance).map_err(failed)? {
                    let grain = grain_of(&shape.rest);
                    assembled.add(&shape.mesh, &shape.rest, i, shape.part, grain);
                }
                labels.push(None);
            }
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
    if !mesh.is_finite() {
        bail!(
            "sample {index}: the deformed mesh has non-finite vertices (check the structure's dimensions and loads)"
        );
    }
    let (centre, radius) = mesh
        .bounding_sphere()
        .expect("a scene has at least one structure");
    if !(radius > 0.0 && radius.is_finite()) {
        bail!("sample {index}: the scene has no extent (radius {radius})");
    }
    let mut materials = Stream::new(recipe.dataset.seed, Scope::Sample(index), "material");
    let shaders = scene
        .structures
        .iter()
        .map(|s| Shader::new(s.material(), &mut materials))
        .collect();
    let lighting = recipe.dataset.light.draw(&mut Stream::new(
        recipe.dataset.seed,
        Scope::Sample(index),
        "light",
    ));
    Ok(PreparedSample {
        index,
        scene,
        labels,
        mesh,
        rest,
        piece,
        pieces,
        shaders,
        lighting,
        owner,
        part,
        parts,
        centre,
        radius,
    })
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
    let (lo, hi) = crate::geometry::bounds(rest).unwrap_or_default();
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
    }
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

/// The camera of view `view` of a prepared sample.
pub fn view_camera(
    dataset: &DatasetSpec,
    sample: &PreparedSample,
    view: u32,
) -> (Camera, ViewDraw) {
    let mut stream = Stream::new(dataset.seed, Scope::View(sample.index, view), "camera");
    dataset
        .camera
        .draw(&mut stream, sample.centre, sample.radius)
}

/// Everything a sample's views share: the BVH, the surface look of every structure and the
/// lighting. Built once per sample; `view` renders one view into memory.
pub struct SampleRenderer<'a> {
    recipe: &'a Recipe,
    sample: &'a PreparedSample,
    trace_mesh: TraceMesh,
    surfaces: SampleSurfaces<'a>,
}

/// One view of a sample, rendered into memory.
pub struct RenderedView {
    pub view: u32,
    pub camera: Camera,
    pub draw: ViewDraw,
    pub gbuffer: GBuffer,
    /// sRGB 8-bit, row-major, when the dataset asks for RGB.
    pub rgb: Option<Vec<u8>>,
    /// 255 where a crack is seen, when the dataset asks for it.
    pub cracks: Option<Vec<u8>>,
    /// The background drawn for this view.
    pub backdrop: Value,
}

impl<'a> SampleRenderer<'a> {
    pub fn new(recipe: &'a Recipe, sample: &'a PreparedSample) -> Self {
        SampleRenderer {
            recipe,
            sample,
            trace_mesh: TraceMesh::build(&sample.mesh),
            surfaces: SampleSurfaces {
                mesh: &sample.mesh,
                rest: &sample.rest,
                piece: &sample.piece,
                pieces: &sample.pieces,
                shaders: &sample.shaders,
            },
        }
    }

    pub fn view(&self, view: u32) -> RenderedView {
        let dataset = &self.recipe.dataset;
        let (camera, draw) = view_camera(dataset, self.sample, view);
        let gbuffer = self.trace_mesh.trace(&camera);
        let mut stream = Stream::new(
            dataset.seed,
            Scope::View(self.sample.index, view),
            "background",
        );
        let frame = (dataset.camera.width, dataset.camera.height);
        let (backdrop, drawn_backdrop) = dataset.background.draw(&mut stream, frame);
        let rgb = dataset.outputs.rgb.then(|| {
            shade(
                &gbuffer,
                &self.trace_mesh,
                &camera,
                &self.sample.lighting.0,
                &self.surfaces,
                &backdrop,
                dataset.antialias,
            )
        });
        let cracks = dataset.outputs.cracks.then(|| {
            self.surfaces
                .crack_mask(&gbuffer, &camera, &self.trace_mesh)
        });
        RenderedView {
            view,
            camera,
            draw,
            gbuffer,
            rgb,
            cracks,
            backdrop: drawn_backdrop,
        }
    }
}

impl RenderedView {
    /// 255 where the centre ray hit a structure, 0 elsewhere.
    pub fn mask(&self) -> Vec<u8> {
        self.gbuffer
            .triangle
            .iter()
            .map(|&t| if t == NO_HIT { 0 } else { 255 })
            .collect()
    }

    /// Part id of every pixel (see `PreparedSample::parts`; 0 = background).
    pub fn part_ids(&self, sample: &PreparedSample) -> Vec<u16> {
        ids(&self.gbuffer, &sample.part)
    }

    /// Structure index + 1 of every pixel (0 = background).
    pub fn instance_ids(&self, sample: &PreparedSample) -> Vec<u16> {
        ids(&self.gbuffer, &sample.owner)
    }
}

/// Renders and stages every view of the sample. Returns the number of views written.
pub fn render(recipe: &Recipe, sample: &PreparedSample, stage: &mut SampleStage) -> Result<u32> {
    let dataset = &recipe.dataset;
    let renderer = SampleRenderer::new(recipe, sample);
    let scene = scene_json(sample);
    for view in 0..dataset.views {
        let rendered = renderer.view(view);
        let g = &rendered.gbuffer;
        let (w, h) = (g.width, g.height);
        let mut files = serde_json::Map::new();
        let mut put =
            |stage: &mut SampleStage, kind: &str, ext: &str, bytes: Vec<u8>| -> Result<()> {
                let path = view_file(sample.index, view, &format!("{kind}.{ext}"));
                files.insert(kind.to_string(), json!(path));
                stage.write(path, &bytes)
            };
        if let Some(rgb) = &rendered.rgb {
            put(stage, "rgb", "png", rgb_png(w, h, rgb))?;
        }
        if dataset.outputs.depth {
            put(stage, "depth", "exr", depth_exr(w, h, &g.depth))?;
        }
        if dataset.outputs.mask {
            put(stage, "mask", "png", mask_png(w, h, &rendered.mask()))?;
        }
        if let Some(cracks) = &rendered.cracks {
            put(stage, "cracks", "png", mask_png(w, h, cracks))?;
        }
        if dataset.outputs.parts {
            put(
                stage,
                "parts",
                "png",
                id_png(w, h, &rendered.part_ids(sample)),
            )?;
        }
        if dataset.outputs.instances {
            put(
                stage,
                "instances",
                "png",
                id_png(w, h, &rendered.instance_ids(sample)),
            )?;
        }
        let meta = view_json(recipe, sample, &rendered, files, &scene);
        let path = view_file(sample.index, view, "json");
        let mut bytes = serde_json::to_vec_pretty(&meta)?;
        bytes.push(b'\n');
        stage.write(path, &bytes)?;
    }
    Ok(dataset.views)
}

/// Per-pixel id + 1 of what each triangle belongs to (0 = background).
fn ids(g: &GBuffer, of_triangle: &[u32]) -> Vec<u16> {
    g.triangle
        .iter()
        .map(|&t| {
            if t == NO_HIT {
                0
            } else {
                of_triangle[t as usize] as u16 + 1
            }
        })
        .collect()
}

/// What every view of a sample shares: its structures with their labels, and the id tables
/// of the segmentation images.
fn scene_json(sample: &PreparedSample) -> Value {
    let structures: Vec<Value> = sample
        .scene
        .structures
        .iter()
        .zip(&sample.labels)
        .zip(&sample.shaders)
        .map(|((s, labels), shader)| {
            let mut v = json!(s);
            v["material_drawn"] = shader.drawn();
            if let (Structure::Beam(b), Some((labels, segments))) = (s, labels) {
                v["section_properties"] = json!(b.section.properties(b.poisson));
                v["segments"] = json!(segments);
                v["labels"] = json!(labels);
            }
            v
        })
        .collect();
    let mut part_ids = vec![json!("background")];
    part_ids.extend(sample.parts.iter().map(|p| json!(p)));
    let mut instance_ids = vec![json!(null)];
    instance_ids.extend(
        sample
            .scene
            .structures
            .iter()
            .enumerate()
            .map(|(i, s)| match s {
                Structure::Beam(_) => json!({ "structure": i, "kind": "beam" }),
                Structure::Assembly(a) => {
                    json!({ "structure": i, "kind": "assembly", "name": a.name })
                }
            }),
    );
    json!({
        "structures": structures,
        "segmentation": { "part_ids": part_ids, "instance_ids": instance_ids, "encoding": "PNG grey, 8-bit when every id fits, else 16-bit; 0 = background" },
    })
}

fn view_json(
    recipe: &Recipe,
    sample: &PreparedSample,
    rendered: &RenderedView,
    files: serde_json::Map<String, Value>,
    scene: &Value,
) -> Value {
    let RenderedView {
        view,
        camera,
        draw,
        gbuffer: g,
        ..
    } = rendered;
    let k = camera.intrinsics;
    let hits = g.triangle.iter().filter(|&&t| t != NO_HIT).count();
    json!({
        "schema": VIEW_SCHEMA,
        "dataset": recipe.dataset.name,
        "sample": sample.index,
        "view": view,
        "files": files,
        "seeds": {
            "run_seed": recipe.dataset.seed,
            "scene_stream": { "scope": [sample.index], "name": "scene" },
            "camera_stream": { "scope": [sample.index, view], "name": "camera" },
        },
        "params": recipe.params,
        "camera": {
            "model": "pinhole",
            "width": k.width,
            "height": k.height,
            "fov_y": recipe.dataset.camera.fov_y,
            "pixel_center": 0.5,
            "K": k.matrix(),
            "w2c_opencv": rows4(camera.w2c_cv()),
            "c2w_opencv": rows4(camera.c2w_cv()),
            "c2w_opengl": rows4(camera.c2w_gl()),
            "position": camera.position.to_array(),
            "target": sample.centre.to_array(),
            "drawn": draw,
        },
        "depth": { "kind": "planar_z", "unit": "m", "no_surface": 0.0, "channel": crate::output::DEPTH_CHANNEL },
        "mask": { "structure": 255, "background": 0 },
        "cracks": { "crack": 255, "elsewhere": 0, "rule": "at the centre ray's surface point, a crack covers at least this share of the pixel's footprint", "min_cover": crate::materials::procedural::CRACK_LABEL_COVER },
        "segmentation": scene["segmentation"],
        "background": rendered.backdrop,
        "light": sample.lighting.1,
        "scene": { "structures": scene["structures"] },
        "mesh": { "vertices": sample.mesh.positions.len(), "triangles": sample.mesh.triangles.len(), "bounding_radius": sample.radius },
        "coverage": hits as f64 / g.triangle.len() as f64,
    })
}
