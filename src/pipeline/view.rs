//! Rendering the views of a built sample into memory: the camera of each view, its trace, and
//! the layers writers and previews ask for, each computed once and only when asked for.

use crate::build::{BackdropDraw, BuiltSample, draw_backdrop};
use crate::cameras::{Camera, ViewDraw};
use crate::materials::Backdrop;
use crate::output::ViewLayers;
use crate::render::{GBuffer, NO_HIT, SampleSurfaces, TraceMesh, shade};
use crate::scene::DatasetSpec;
use crate::seeds::{self, Scope, Stream};
use anyhow::{Result, anyhow};
use std::sync::OnceLock;

/// The camera of view `view` of a built sample.
pub fn view_camera(
    dataset: &DatasetSpec,
    sample: &BuiltSample,
    view: u32,
) -> Result<(Camera, ViewDraw)> {
    let mut stream = Stream::new(dataset.seed, Scope::View(sample.index, view), seeds::CAMERA);
    dataset
        .camera
        .draw(&mut stream, sample.centre, sample.radius)
        .map_err(|e| anyhow!("sample {}, view {view}: {e}", sample.index))
}

/// Everything a sample's views share: the BVH, the surface look of every structure and the
/// lighting. Built once per sample; `view` renders one view.
pub struct SampleRenderer<'a> {
    dataset: &'a DatasetSpec,
    sample: &'a BuiltSample,
    trace_mesh: TraceMesh,
    surfaces: SampleSurfaces<'a>,
}

/// One view of a sample: its camera and centre-ray trace, with the other layers rendered on
/// first request.
pub struct RenderedView<'a> {
    renderer: &'a SampleRenderer<'a>,
    /// View index within the sample.
    pub view: u32,
    /// The camera of the view.
    pub camera: Camera,
    /// The yaw, pitch, roll and distance drawn for the camera.
    pub draw: ViewDraw,
    /// Depth and triangle id of every pixel, from its centre ray.
    pub gbuffer: GBuffer,
    backdrop: Backdrop,
    /// The background drawn for this view.
    pub backdrop_drawn: BackdropDraw,
    rgb: OnceLock<Vec<u8>>,
    cracks: OnceLock<Vec<u8>>,
}

impl<'a> SampleRenderer<'a> {
    /// Builds the BVH and surfaces of `sample`, a sample of `dataset`.
    pub fn new(dataset: &'a DatasetSpec, sample: &'a BuiltSample) -> Self {
        SampleRenderer {
            dataset,
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

    /// Traces view `view` and draws its backdrop.
    pub fn view(&self, view: u32) -> Result<RenderedView<'_>> {
        let dataset = self.dataset;
        let (camera, draw) = view_camera(dataset, self.sample, view)?;
        let gbuffer = self.trace_mesh.trace(&camera);
        let mut stream = Stream::new(
            dataset.seed,
            Scope::View(self.sample.index, view),
            seeds::BACKGROUND,
        );
        let frame = (dataset.camera.width, dataset.camera.height);
        let (backdrop, backdrop_drawn) = draw_backdrop(&dataset.background, &mut stream, frame);
        Ok(RenderedView {
            renderer: self,
            view,
            camera,
            draw,
            gbuffer,
            backdrop,
            backdrop_drawn,
            rgb: OnceLock::new(),
            cracks: OnceLock::new(),
        })
    }
}

impl RenderedView<'_> {
    /// Share of the pixels that see a structure.
    pub fn coverage(&self) -> f64 {
        let triangles = &self.gbuffer.triangle;
        let hits = triangles.iter().filter(|&&t| t != NO_HIT).count();
        hits as f64 / triangles.len() as f64
    }

    /// Per-pixel id + 1 of what each triangle belongs to (0 = background).
    fn ids(&self, of_triangle: &[u32]) -> Vec<u32> {
        self.gbuffer
            .triangle
            .iter()
            .map(|&t| {
                if t == NO_HIT {
                    0
                } else {
                    of_triangle[t as usize] + 1
                }
            })
            .collect()
    }
}

impl ViewLayers for RenderedView<'_> {
    fn size(&self) -> (u32, u32) {
        (self.gbuffer.width, self.gbuffer.height)
    }

    fn rgb(&self) -> &[u8] {
        self.rgb.get_or_init(|| {
            let r = self.renderer;
            shade(
                &self.gbuffer,
                &r.trace_mesh,
                &self.camera,
                &r.sample.lighting,
                &r.surfaces,
                &self.backdrop,
                r.dataset.antialias,
            )
        })
    }

    fn depth(&self) -> &[f32] {
        &self.gbuffer.depth
    }

    fn mask(&self) -> Vec<u8> {
        self.gbuffer
            .triangle
            .iter()
            .map(|&t| if t == NO_HIT { 0 } else { 255 })
            .collect()
    }

    fn part_ids(&self) -> Vec<u32> {
        self.ids(&self.renderer.sample.part)
    }

    fn instance_ids(&self) -> Vec<u32> {
        self.ids(&self.renderer.sample.owner)
    }

    fn cracks(&self) -> &[u8] {
        self.cracks.get_or_init(|| {
            let r = self.renderer;
            r.surfaces
                .crack_mask(&self.gbuffer, &self.camera, &r.trace_mesh)
        })
    }
}
