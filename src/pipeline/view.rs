//! Rendering the views of a built sample into memory: the camera of each view, its trace, and
//! the layers writers and previews ask for, each computed once and only when asked for. The
//! unloaded structure (for the rest image, its depth and the flow) is traced through a second
//! BVH, built once per sample when a view first needs it. In a sequence, a frame's renderer
//! also holds the frames before and after it (`FrameNeighbours`), for the flow between frames,
//! and the first frame, for the point tracks.

use super::augmented::{Applied, copy_camera, draw_sensor, photometric};
use super::damage::sample_damage;
use super::sequence::{flown, mount_offset, shaken};
use crate::augment::defocus_by_depth;
use crate::build::{BackdropDraw, BuiltSample, draw_backdrop};
use crate::cameras::{Camera, ViewDraw};
use crate::materials::Backdrop;
use crate::materials::cache::FieldCache;
use crate::output::{DamageLayers, Flow, FrameFlow, ViewLayers};
use crate::render::{
    CacheSettings, DamagedSurfaces, Deformed, GBuffer, ImageVisibility, LightCache, NO_HIT,
    OtherFrame, SampleDamage, SampleSurfaces, SecondaryRays, SeenMesh, Shaded, Surfaces, TraceMesh,
    Traced, TrackPoint, ViewVisibility, displacement, flow, frame_flow, normals, ray_distance,
    shade, track_points, track_queries,
};
use crate::scene::{DEFAULT_TRACK_STRIDE, DatasetSpec, NormalsFrame, Shading};
use crate::seeds::{self, Scope, Stream};
use anyhow::{Result, anyhow};
use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// Which eye of a stereo pair a view is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Eye {
    /// The drawn camera.
    Left,
    /// The left eye moved by the baseline along its x axis (and turned by the toe-in).
    Right,
}

/// The camera of one view, what was drawn for it and, for a stereo rig, its place in the pair.
#[derive(Clone, Copy, Debug)]
pub struct ViewCamera {
    /// The camera the view is rendered with.
    pub camera: Camera,
    /// The values drawn for its pose and lens.
    pub draw: ViewDraw,
    /// (pose, eye) of a stereo rig: views 2p and 2p + 1 are the left and right eyes of pose p.
    pub stereo: Option<(u32, Eye)>,
    /// The left eye's camera, for a right eye.
    pub left: Option<Camera>,
}

/// The camera of view `view` of a built sample. Each pose draws from its own stream, so both
/// eyes of a stereo pair share one draw.
pub fn view_camera(dataset: &DatasetSpec, sample: &BuiltSample, view: u32) -> Result<ViewCamera> {
    let rig = &dataset.camera;
    let (pose, eye) = match rig.stereo {
        Some(_) => (
            view / 2,
            Some(if view.is_multiple_of(2) {
                Eye::Left
            } else {
                Eye::Right
            }),
        ),
        None => (view, None),
    };
    let mut stream = Stream::new(dataset.seed, Scope::View(sample.index, pose), seeds::CAMERA);
    let (left, draw) = rig
        .draw(
            &mut stream,
            pose,
            dataset.views,
            sample.centre,
            sample.radius,
        )
        .map_err(|e| anyhow!("sample {}, view {view}: {e}", sample.index))?;
    let camera = match eye {
        Some(Eye::Right) => rig.right_eye(&left).expect("a stereo rig"),
        _ => left,
    };
    above_ground(sample, &camera, &draw)
        .map_err(|e| anyhow!("sample {}, view {view}: {e}", sample.index))?;
    Ok(ViewCamera {
        camera,
        draw,
        stereo: eye.map(|e| (pose, e)),
        left: (eye == Some(Eye::Right)).then_some(left),
    })
}

/// The camera of view `view` at instant `time` of a sequence (None for a still): the drawn
/// camera, where its flight path has it then (if it has one), its mount displaced as the
/// sequence's mount shake has it then.
pub fn frame_camera(
    dataset: &DatasetSpec,
    sample: &BuiltSample,
    view: u32,
    time: Option<f64>,
) -> Result<ViewCamera> {
    let standing = view_camera(dataset, sample, view)?;
    let Some(t) = time else {
        return Ok(standing);
    };
    let path = (dataset.sequence.iter())
        .flat_map(|s| &s.paths)
        .find(|p| p.view == view);
    let mut drawn = path.map_or(standing, |path| flown(standing, path, t));
    if let Some(offset) = mount_offset(dataset, sample.index, view, t) {
        drawn.camera = shaken(drawn.camera, &offset);
    }
    Ok(drawn)
}

/// One frame of a sequence as built, kept while its neighbours are rendered: its structures at
/// its instant, its mesh ready for tracing and, on first use, its unloaded twin (where the flow
/// between frames finds material points).
pub struct SequenceFrame {
    /// The sample as built at the frame's instant.
    pub sample: BuiltSample,
    /// The frame's instant, seconds.
    pub time: f64,
    /// The loaded mesh, ready for tracing.
    pub trace_mesh: Arc<TraceMesh>,
    rest: OnceLock<Traced>,
}

impl SequenceFrame {
    /// Frame `sample`, built at `time`, with its mesh prepared for tracing.
    pub fn new(sample: BuiltSample, time: f64, trace_mesh: Arc<TraceMesh>) -> Self {
        SequenceFrame {
            sample,
            time,
            trace_mesh,
            rest: OnceLock::new(),
        }
    }

    fn rest(&self) -> &Traced {
        self.rest.get_or_init(|| unloaded_twin(&self.sample))
    }

    fn deformed(&self) -> Deformed<'_> {
        deformed(&self.sample, &self.trace_mesh)
    }
}

/// A track point as its file row: x, y, state (1 seen, 0 hidden or outside, −1 no image).
fn track_row(point: &TrackPoint) -> [f64; 3] {
    match *point {
        TrackPoint::Visible([x, y]) => [x, y, 1.0],
        TrackPoint::Occluded([x, y]) => [x, y, 0.0],
        TrackPoint::Lost => [0.0, 0.0, -1.0],
    }
}

/// The unloaded structure of `sample` ready for tracing: its mesh's triangles over the
/// undeformed vertices.
fn unloaded_twin(sample: &BuiltSample) -> Traced {
    Traced::with_positions(&sample.mesh, &sample.rest, sample.structure_triangles())
}

/// The loaded structure of `sample` (traced as `traced`) with its vertices' unloaded positions.
fn deformed<'a>(sample: &'a BuiltSample, traced: &'a TraceMesh) -> Deformed<'a> {
    Deformed {
        mesh: &sample.mesh,
        traced,
        rest: &sample.rest,
    }
}

/// The frames before and after the one being rendered (None at the ends of a sequence, and
/// for a still), and the first frame, where the point tracks' queries are chosen.
#[derive(Clone, Copy, Default)]
pub struct FrameNeighbours<'a> {
    /// The previous frame.
    pub prev: Option<&'a SequenceFrame>,
    /// The next frame.
    pub next: Option<&'a SequenceFrame>,
    /// The first frame of the sequence (only when the point tracks are asked for).
    pub first: Option<&'a SequenceFrame>,
}

/// Refuses a camera at or below the ground: it would see the ground's underside, or nothing
/// of the structure. Cameras a few millimetres above it are fine.
pub fn above_ground(sample: &BuiltSample, camera: &Camera, draw: &ViewDraw) -> Result<(), String> {
    let Some(ground) = sample.ground else {
        return Ok(());
    };
    let clearance = camera.position.z - ground.height;
    if clearance > 1e-6 * sample.radius {
        return Ok(());
    }
    Err(format!(
        "the camera stands at z = {:.3} m, {:.3} m below the ground at z = {:.3} m (dataset.ground); it was drawn at pitch {:.1}° and distance {:.3} m from the structure's centre at z = {:.3} m: raise dataset.camera.pitch's lower end above the ground (at this distance, above {:.1}°), or place the camera higher",
        camera.position.z,
        -clearance,
        ground.height,
        draw.pitch.to_degrees(),
        draw.distance,
        sample.centre.z,
        (-((sample.centre.z - ground.height) / draw.distance).clamp(-1.0, 1.0))
            .asin()
            .to_degrees(),
    ))
}

/// Everything a sample's views share: the BVH, the surface look of every structure and the
/// lighting. Built once per sample; `view` renders one view.
pub struct SampleRenderer<'a> {
    dataset: &'a DatasetSpec,
    sample: &'a BuiltSample,
    trace_mesh: Arc<TraceMesh>,
    /// The material fields the views have asked for so far, when they are cached in surface
    /// space (`with_texel_fraction`); dropped with the renderer, so with its sample. Runs
    /// evaluate materials at every pixel under either `shading`: no texel bound made the
    /// cache pay at an error worth having (docs/materials.md, "Caching material fields").
    cache: Option<FieldCache>,
    rest: OnceLock<Traced>,
    /// The lighting caches of the loaded and the unloaded mesh, made on first use (none with
    /// `shading: "per_pixel"`), shared by every view and dropped with the sample.
    light_caches: [OnceLock<LightCache>; 2],
    /// The sample's damage, drawn and labelled; None for a sound sample (drawn as before).
    damage: Option<SampleDamage>,
    /// How finely those caches sample the light (the default, or `for_preview`'s).
    light_settings: CacheSettings,
    /// In a sequence, the frames around this one.
    neighbours: FrameNeighbours<'a>,
}

/// One view of a sample: its camera and centre-ray trace, with the other layers rendered on
/// first request.
pub struct RenderedView<'a> {
    renderer: &'a SampleRenderer<'a>,
    /// View index within the sample.
    pub view: u32,
    /// The camera of the view.
    pub camera: Camera,
    /// The camera as drawn, with its place in a stereo pair.
    pub drawn: ViewCamera,
    /// Depth and triangle id of every pixel, from its centre ray: the structures and the
    /// ground, as the RGB image shows them.
    pub gbuffer: GBuffer,
    /// The same without the ground (built when the sample has one and a layer asks).
    structure: OnceLock<GBuffer>,
    rest_structure: OnceLock<GBuffer>,
    backdrop: Backdrop,
    /// The background drawn for this view.
    pub backdrop_drawn: BackdropDraw,
    /// What the sensor does to the view's RGB images, as drawn.
    pub sensor: Vec<Applied>,
    rgb: OnceLock<Shaded>,
    cracks: OnceLock<Vec<u8>>,
    /// The unloaded structure through the same camera.
    rest_gbuffer: OnceLock<GBuffer>,
    rest_rgb: OnceLock<Shaded>,
    /// Whether the flow's occlusion rays were traced.
    flow_traced: AtomicBool,
    /// The augmented copy rendered through its own camera, None for the clean view: the flow
    /// between frames films the other frames through the copy's camera then.
    copy: Option<u32>,
}

/// A view's layers, and how the ones asked for so far were found: rasterised or traced, and
/// what else walked the BVH (for the view's record).
pub trait RenderedLayers: ViewLayers {
    fn visibility(&self) -> ViewVisibility;
}

impl RenderedLayers for RenderedView<'_> {
    fn visibility(&self) -> ViewVisibility {
        self.found()
    }
}

impl<'a> SampleRenderer<'a> {
    /// Prepares the mesh and surfaces of `sample`, a sample of `dataset`.
    pub fn new(dataset: &'a DatasetSpec, sample: &'a BuiltSample) -> Self {
        let trace_mesh = TraceMesh::build_with_core(&sample.mesh, sample.structure_triangles());
        Self::with_trace_mesh(dataset, sample, Arc::new(trace_mesh))
    }

    /// The renderer of `sample` with `trace_mesh`, its mesh ready for tracing (prepared by
    /// `TraceMesh::build_with_core` with its structure triangles as the core).
    pub fn with_trace_mesh(
        dataset: &'a DatasetSpec,
        sample: &'a BuiltSample,
        trace_mesh: Arc<TraceMesh>,
    ) -> Self {
        SampleRenderer {
            dataset,
            sample,
            trace_mesh,
            cache: None,
            rest: OnceLock::new(),
            light_caches: Default::default(),
            damage: sample_damage(sample),
            light_settings: CacheSettings::default(),
            neighbours: FrameNeighbours::default(),
        }
    }

    /// The same renderer for a preview, which is looked at, not measured: its lighting
    /// caches sample the light at `CacheSettings::PREVIEW` (runs keep the default).
    pub fn for_preview(self) -> Self {
        SampleRenderer {
            light_settings: CacheSettings::PREVIEW,
            ..self
        }
    }

    /// The same renderer with its materials cached in surface space at texel bound `fraction`
    /// (see `FieldCache::new`), or evaluated at every pixel (None, what runs do): for the
    /// benchmark and tests that measure the cache against the per-pixel reference.
    pub fn with_texel_fraction(self, fraction: Option<f64>) -> Self {
        SampleRenderer {
            cache: fraction.map(FieldCache::new),
            ..self
        }
    }

    /// The same renderer for a frame of a sequence between `neighbours`.
    pub fn between(self, neighbours: FrameNeighbours<'a>) -> Self {
        SampleRenderer { neighbours, ..self }
    }

    /// Lattice points of material fields the cache holds (0 per pixel).
    pub fn cached_points(&self) -> usize {
        self.cache.as_ref().map_or(0, FieldCache::points)
    }

    /// The surfaces of the loaded mesh, with the sample's cache.
    fn surfaces(&self) -> SampleSurfaces<'_> {
        let s = self.sample;
        SampleSurfaces {
            mesh: &s.mesh,
            rest: &s.rest,
            piece: &s.piece,
            pieces: &s.pieces,
            shaders: &s.shaders,
            cache: self.cache.as_ref(),
        }
    }

    /// The lighting cache of the loaded (`rest` false) or unloaded mesh, None when the
    /// dataset shades per pixel.
    fn light_cache(&self, rest: bool) -> Option<&LightCache> {
        let lighting = &self.sample.lighting;
        (self.dataset.shading == Shading::Cached).then(|| {
            self.light_caches[usize::from(rest)]
                .get_or_init(|| LightCache::new(lighting, self.light_settings))
        })
    }

    /// The unloaded structure ready for tracing, prepared on first use: the loaded mesh's
    /// triangles over the undeformed vertices.
    fn rest(&self) -> &Traced {
        self.rest.get_or_init(|| unloaded_twin(self.sample))
    }

    /// The loaded structure with the undeformed position of every vertex.
    fn deformed(&self) -> Deformed<'_> {
        deformed(self.sample, &self.trace_mesh)
    }

    /// The dataset the views belong to.
    pub fn dataset(&self) -> &'a DatasetSpec {
        self.dataset
    }

    /// The sample being viewed.
    pub fn sample(&self) -> &'a BuiltSample {
        self.sample
    }

    /// The sample's damage as drawn; None for a sound sample.
    pub fn damage(&self) -> Option<&SampleDamage> {
        self.damage.as_ref()
    }

    /// Traces view `view` and draws its backdrop.
    pub fn view(&self, view: u32) -> Result<RenderedView<'_>> {
        let drawn = view_camera(self.dataset, self.sample, view)?;
        Ok(self.view_with(view, drawn.camera, drawn))
    }

    /// Traces view `view` through `camera` (the drawn one, or one an augmentation changed)
    /// and draws its backdrop.
    pub fn view_with(&self, view: u32, camera: Camera, drawn: ViewCamera) -> RenderedView<'_> {
        let dataset = self.dataset;
        let gbuffer = self.trace_mesh.trace(&camera);
        // Both eyes of a stereo pair photograph one scene: they draw the left eye's backdrop.
        let backdrop_view = drawn.stereo.map_or(view, |(pose, _)| 2 * pose);
        let mut stream = Stream::new(
            dataset.seed,
            Scope::View(self.sample.index, backdrop_view),
            seeds::BACKGROUND,
        );
        let frame = (dataset.camera.width, dataset.camera.height);
        let (backdrop, backdrop_drawn) = draw_backdrop(&dataset.background, &mut stream, frame);
        let sensor = draw_sensor(dataset, self.sample.index, view);
        RenderedView {
            renderer: self,
            view,
            camera,
            drawn,
            gbuffer,
            backdrop,
            backdrop_drawn,
            structure: OnceLock::new(),
            rest_structure: OnceLock::new(),
            sensor,
            rgb: OnceLock::new(),
            cracks: OnceLock::new(),
            rest_gbuffer: OnceLock::new(),
            rest_rgb: OnceLock::new(),
            flow_traced: AtomicBool::new(false),
            copy: None,
        }
    }
}

/// `g` with every pixel that sees the ground (a triangle from `first_ground` on) turned into
/// one that sees nothing.
fn without_ground(g: &GBuffer, first_ground: usize) -> GBuffer {
    let (depth, triangle) = g
        .depth
        .iter()
        .zip(&g.triangle)
        .map(|(&d, &t)| {
            if t != NO_HIT && t as usize >= first_ground {
                (0.0, NO_HIT)
            } else {
                (d, t)
            }
        })
        .unzip();
    GBuffer {
        width: g.width,
        height: g.height,
        depth,
        triangle,
        visibility: g.visibility,
    }
}

impl RenderedView<'_> {
    /// The same view as augmented copy `copy`, rendered through the copy's camera.
    pub fn as_copy(self, copy: u32) -> Self {
        RenderedView {
            copy: Some(copy),
            ..self
        }
    }

    /// This view's camera at frame `other` of the sequence: the drawn camera shaken as then,
    /// moved as this copy's augmentation moves it. None if it cannot be drawn (the other
    /// frame, rendering the same camera, then reports why).
    fn camera_at(&self, other: &SequenceFrame) -> Option<Camera> {
        let r = self.renderer;
        let drawn = frame_camera(r.dataset, &other.sample, self.view, Some(other.time)).ok()?;
        match self.copy {
            None => Some(drawn.camera),
            Some(copy) => copy_camera(r.dataset, (r.sample.index, self.view, copy), &drawn)
                .ok()
                .map(|(_, camera)| camera),
        }
    }

    /// Flow from this frame's image to frame `other`'s (invalid everywhere without one).
    fn flow_to(&self, other: Option<&SequenceFrame>) -> Flow {
        let field = other.and_then(|other| {
            let camera = self.camera_at(other)?;
            self.flow_traced.store(true, Ordering::Relaxed);
            let other = OtherFrame {
                deformed: other.deformed(),
                rest: other.rest(),
                camera,
            };
            Some(frame_flow(
                self.geometric(),
                &self.camera,
                &self.renderer.deformed(),
                &other,
            ))
        });
        match field {
            Some(field) => Flow::from_field(&field),
            None => Flow::invalid(self.gbuffer.triangle.len()),
        }
    }

    /// Where the query points chosen on frame `first` are in this frame (none without one):
    /// the queries found again from that frame's structure and this view's camera then.
    fn tracks_from(&self, first: Option<&SequenceFrame>) -> Vec<TrackPoint> {
        let Some(first) = first else {
            return Vec::new();
        };
        let Some(first_camera) = self.camera_at(first) else {
            return Vec::new();
        };
        let r = self.renderer;
        let stride = (r.dataset.sequence.as_ref()).map_or(DEFAULT_TRACK_STRIDE, |s| s.track_stride);
        let structure = first.sample.structure_triangles();
        let queries = track_queries(&first.deformed(), &first_camera, structure, stride);
        let here = OtherFrame {
            deformed: r.deformed(),
            rest: r.rest(),
            camera: self.camera,
        };
        track_points(&queries, &here)
    }

    /// What the structures alone are seen as: the trace without the ground (the mask's).
    fn structure(&self) -> &GBuffer {
        let sample = self.renderer.sample;
        match sample.ground {
            None => &self.gbuffer,
            Some(g) => self
                .structure
                .get_or_init(|| without_ground(&self.gbuffer, g.first_triangle)),
        }
    }

    /// What the geometric outputs (depth, normals, ray distance, displacement) see: the
    /// ground too when the dataset asks for it in depth.
    fn geometric(&self) -> &GBuffer {
        if self.ground_in_depth() {
            &self.gbuffer
        } else {
            self.structure()
        }
    }

    /// The unloaded trace as the geometric outputs see it (`rest_depth`, `flow`).
    fn rest_geometric(&self) -> &GBuffer {
        let sample = self.renderer.sample;
        match sample.ground {
            Some(g) if !self.ground_in_depth() => self
                .rest_structure
                .get_or_init(|| without_ground(self.rest_gbuffer(), g.first_triangle)),
            _ => self.rest_gbuffer(),
        }
    }

    fn ground_in_depth(&self) -> bool {
        let dataset = self.renderer.dataset;
        dataset.ground.as_ref().is_some_and(|g| g.in_depth)
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

    /// RGB of what `g` saw through this view's camera in `mesh`, with the sample's
    /// light and this view's backdrop, through the lens and the sensor; the sample's damage
    /// drawn on `surfaces` when it has some.
    fn shaded(
        &self,
        g: &GBuffer,
        mesh: &TraceMesh,
        surfaces: &SampleSurfaces,
        cache: Option<&LightCache>,
    ) -> Shaded {
        let mut shaded = self.filmed(g, mesh, surfaces, cache);
        self.develop(&mut shaded.rgb, g);
        shaded
    }

    /// The light reaching the film: `shaded` before the lens's defocus and the sensor.
    fn filmed(
        &self,
        g: &GBuffer,
        mesh: &TraceMesh,
        surfaces: &SampleSurfaces,
        cache: Option<&LightCache>,
    ) -> Shaded {
        match &self.renderer.damage {
            Some(damage) => {
                let damaged = DamagedSurfaces {
                    inner: surfaces,
                    damage,
                    seen: SeenMesh {
                        mesh: surfaces.mesh,
                        rest: surfaces.rest,
                        camera: &self.camera,
                    },
                };
                self.filmed_surfaces(g, mesh, &damaged, cache)
            }
            None => self.filmed_surfaces(g, mesh, surfaces, cache),
        }
    }

    fn filmed_surfaces(
        &self,
        g: &GBuffer,
        mesh: &TraceMesh,
        surfaces: &impl Surfaces,
        cache: Option<&LightCache>,
    ) -> Shaded {
        let r = self.renderer;
        shade(
            g,
            mesh,
            &self.camera,
            (&r.sample.lighting, cache),
            surfaces,
            &self.backdrop,
            r.dataset.antialias,
        )
    }

    /// The lens's defocus (from `g`'s depth) and the sensor's effects on the filmed `rgb`.
    fn develop(&self, rgb: &mut [u8], g: &GBuffer) {
        let r = self.renderer;
        let size = (g.width as usize, g.height as usize);
        if let Some(lens) = &r.dataset.camera.depth_of_field {
            // Circles from the exact planar depth; the backdrop lies at infinity.
            let (radius, distance) = lens.circles(&self.camera.intrinsics, &g.depth);
            defocus_by_depth(rgb, size.0, size.1, &radius, &distance);
        }
        // The operations are validated; an encoder failing in memory is a bug.
        photometric(rgb, size, &self.sensor, None).expect("sensor effects on a valid image");
    }

    /// The loaded structure's light on the film, before the lens and the sensor: what motion
    /// blur averages over the exposure.
    pub(super) fn film(&self) -> Shaded {
        let r = self.renderer;
        let cache = r.light_cache(false);
        self.filmed(&self.gbuffer, &r.trace_mesh, &r.surfaces(), cache)
    }

    /// Sets this view's RGB to `filmed` (the light on the film over the exposure) through the
    /// lens and the sensor, as its own shading would have been.
    pub(super) fn expose(&self, mut filmed: Shaded) {
        self.develop(&mut filmed.rgb, &self.gbuffer);
        assert!(self.rgb.set(filmed).is_ok(), "a view is exposed once");
    }

    /// How the images asked for so far were found (call it once every layer is encoded).
    fn found(&self) -> ViewVisibility {
        let image = |g: &GBuffer, shaded: &OnceLock<Shaded>| ImageVisibility {
            primary: g.visibility,
            edge_rays: shaded.get().and_then(|s| s.edge_rays),
        };
        let mut secondary: Vec<SecondaryRays> = [&self.rgb, &self.rest_rgb]
            .into_iter()
            .filter_map(OnceLock::get)
            .flat_map(|s| s.secondary.iter().copied())
            .collect();
        if self.flow_traced.load(Ordering::Relaxed) {
            secondary.push(SecondaryRays::FlowOcclusion);
        }
        secondary.sort();
        secondary.dedup();
        ViewVisibility {
            loaded: image(&self.gbuffer, &self.rgb),
            unloaded: self.rest_gbuffer.get().map(|g| image(g, &self.rest_rgb)),
            secondary,
        }
    }

    fn rest_gbuffer(&self) -> &GBuffer {
        self.rest_gbuffer
            .get_or_init(|| self.renderer.rest().trace_mesh.trace(&self.camera))
    }
}

impl ViewLayers for RenderedView<'_> {
    fn size(&self) -> (u32, u32) {
        (self.gbuffer.width, self.gbuffer.height)
    }

    fn rgb(&self) -> &[u8] {
        &self
            .rgb
            .get_or_init(|| {
                let r = self.renderer;
                self.shaded(
                    &self.gbuffer,
                    &r.trace_mesh,
                    &r.surfaces(),
                    r.light_cache(false),
                )
            })
            .rgb
    }

    fn depth(&self) -> &[f32] {
        &self.geometric().depth
    }

    fn mask(&self) -> Vec<u8> {
        self.structure()
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
            r.surfaces()
                .crack_mask(self.structure(), &self.camera, &r.trace_mesh)
        })
    }

    fn erased(&self) -> Vec<u8> {
        vec![0; self.gbuffer.triangle.len()]
    }

    fn valid(&self) -> Vec<u8> {
        vec![255; self.gbuffer.triangle.len()]
    }

    fn normals(&self) -> Vec<[f32; 3]> {
        let axes = match self.renderer.dataset.normals {
            NormalsFrame::Camera => self.camera.rotation.transpose(),
            NormalsFrame::World => glam::DMat3::IDENTITY,
        };
        normals(
            self.geometric(),
            &self.renderer.trace_mesh,
            &self.camera,
            axes,
        )
    }

    fn ray_distance(&self) -> Vec<f32> {
        ray_distance(self.geometric(), &self.camera)
    }

    fn displacement(&self) -> Vec<[f32; 3]> {
        displacement(self.geometric(), &self.camera, &self.renderer.deformed())
    }

    fn flow(&self) -> Flow {
        self.flow_traced.store(true, Ordering::Relaxed);
        let field = flow(
            self.rest_geometric(),
            &self.camera,
            self.renderer.rest(),
            &self.renderer.deformed(),
        );
        Flow::from_field(&field)
    }

    fn frame_flow(&self) -> FrameFlow {
        let neighbours = self.renderer.neighbours;
        FrameFlow {
            next: self.flow_to(neighbours.next),
            prev: self.flow_to(neighbours.prev),
        }
    }

    fn point_tracks(&self) -> Vec<[f64; 3]> {
        self.tracks_from(self.renderer.neighbours.first)
            .iter()
            .map(track_row)
            .collect()
    }

    fn rest_rgb(&self) -> &[u8] {
        &self
            .rest_rgb
            .get_or_init(|| {
                let r = self.renderer;
                let rest = r.rest();
                // The same materials, read at the same undeformed points: only the shape differs.
                let surfaces = SampleSurfaces {
                    mesh: &rest.mesh,
                    ..r.surfaces()
                };
                let cache = r.light_cache(true);
                self.shaded(self.rest_gbuffer(), &rest.trace_mesh, &surfaces, cache)
            })
            .rgb
    }

    fn rest_depth(&self) -> &[f32] {
        &self.rest_geometric().depth
    }

    fn damage(&self) -> DamageLayers {
        let r = self.renderer;
        let pixels = self.gbuffer.triangle.len();
        let Some(damage) = &r.damage else {
            return DamageLayers {
                class: vec![0; pixels],
                instance: vec![0; pixels],
                crack_width_mm: vec![0.0; pixels],
                crack_coverage: vec![0.0; pixels],
            };
        };
        let seen = SeenMesh {
            mesh: &r.sample.mesh,
            rest: &r.sample.rest,
            camera: &self.camera,
        };
        let labels = damage.labels(self.structure(), &self.camera, &seen);
        DamageLayers {
            class: labels.iter().map(|d| d.class as u8).collect(),
            instance: labels.iter().map(|d| d.instance).collect(),
            crack_width_mm: labels.iter().map(|d| d.crack_width_mm as f32).collect(),
            crack_coverage: labels.iter().map(|d| d.crack_coverage as f32).collect(),
        }
    }

    fn coverage(&self) -> f64 {
        let triangles = &self.structure().triangle;
        let hits = triangles.iter().filter(|&&t| t != NO_HIT).count();
        hits as f64 / triangles.len() as f64
    }
}
