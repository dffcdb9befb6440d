//! One sample, end to end: draw its scene, build it, hand its geometry to the per-sample
//! writers, render each view, hand the view's layers to the per-view writers, and stage their
//! files with the view's record.

use super::augmented::{Applied, AugmentedView, copy_camera};
use super::damage::{unresolved_cracks, unresolved_warning};
use super::finite::check_finite;
use super::geometry::SampleGeometry;
use super::record::{AugmentationRecord, FrameRecord, SampleRecord, ViewFacts, json_bytes};
use super::sequence::{SampleMotion, averaged_in_linear_light};
use super::view::{
    FrameNeighbours, RenderedLayers, RenderedView, SampleRenderer, SequenceFrame, ViewCamera,
    frame_camera, view_camera,
};
use crate::build::{BuiltSample, build_framed, build_sample};
use crate::cameras::Camera;
use crate::output::{
    MAX_SEGMENTATION_ID, SAMPLE_WRITERS, SampleStage, ViewLayers, WRITERS, in_frame, sample_file,
    view_file,
};
use crate::recipe::Recipe;
use crate::render::{SharedTraceMeshes, TraceMesh};
use crate::scene::{DatasetSpec, GeometryMode, SequenceSpec};
use anyhow::{Result, bail};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::ops::Range;
use std::sync::Arc;

/// Draws the scene of sample `index` and builds its deformed meshes; fails on anything that
/// would make non-finite output: the meshes, the structures' labels and every view's camera
/// are checked here, before any file is written.
pub fn prepare(recipe: &Recipe, index: u64) -> Result<BuiltSample> {
    let scene = recipe.scene(index)?;
    let context = format!("while building sample {index}");
    let sample = build_sample(&recipe.dataset, index, scene)
        .map_err(|e| recipe.locate(&e.message, e.site.as_ref(), &context))?;
    let record = SampleRecord::new(&sample);
    for (structure, labels) in sample.scene.structures.iter().zip(&record.structures) {
        check_finite(labels)
            .map_err(|e| recipe.locate(&e.to_string(), structure.declared_at(), &context))?;
    }
    let cameras = format!("while drawing the cameras of sample {index}");
    let at_dataset = |e: anyhow::Error| recipe.locate_dataset(&e.to_string(), &cameras);
    for view in 0..recipe.dataset.cameras_per_sample() {
        let drawn = view_camera(&recipe.dataset, &sample, view).map_err(at_dataset)?;
        for copy in 0..recipe.dataset.augment.copies {
            copy_camera(&recipe.dataset, (index, view, copy), &drawn).map_err(at_dataset)?;
        }
    }
    check_segmentation(recipe, &sample)?;
    if let Some(sequence) = &recipe.dataset.sequence {
        sample_motion(recipe, &sample, sequence)?;
    }
    Ok(sample)
}

/// What the structures of `sample` do over `sequence`; an error points at the beam's call.
fn sample_motion(
    recipe: &Recipe,
    sample: &BuiltSample,
    sequence: &SequenceSpec,
) -> Result<SampleMotion> {
    let context = format!("while integrating the motion of sample {}", sample.index);
    SampleMotion::new(&sample.scene, sequence)
        .map_err(|e| recipe.locate(&e.message, e.site.as_ref(), &context).into())
}

/// Segmentation images hold ids up to 16 bits: a scene with more parts or structures than
/// that is refused before anything is written, rather than wrapping ids.
fn check_segmentation(recipe: &Recipe, sample: &BuiltSample) -> Result<()> {
    let outputs = &recipe.dataset.outputs;
    for (output, count, what) in [
        ("parts", sample.parts.len(), "distinct part names"),
        ("instances", sample.scene.structures.len(), "structures"),
    ] {
        if outputs.wants(output) && count as u64 > u64::from(MAX_SEGMENTATION_ID) {
            bail!(
                "sample {}: {count} {what}, but the \"{output}\" images hold ids up to {MAX_SEGMENTATION_ID}; write fewer, or leave \"{output}\" out of dataset.outputs",
                sample.index
            );
        }
    }
    Ok(())
}

/// Renders every view of the sample, clean and augmented, and stages its files, the sample's
/// own files first; its mesh, ready for tracing, comes from `shared` (prepared once for
/// samples of the same mesh). Returns the number of images written.
///
/// Views are rendered and encoded in parallel, as many at a time as there are threads (so a
/// run's last sample, or a run of fewer samples than threads, still keeps every core busy),
/// and their files are staged in view order after each group: the staging, and the first
/// error reported, are the same on any thread count, and memory holds one group's files.
///
/// A sample of a sequence writes every frame so, in order: the structures as they are at the
/// frame's instant, filmed by the same cameras (framed by the sample as built, its static
/// loads alone), each file named with the frame (`output::in_frame`).
pub fn write_sample(
    recipe: &Recipe,
    sample: &BuiltSample,
    shared: &SharedTraceMeshes,
    stage: &mut SampleStage,
) -> Result<u32> {
    write_sample_frames(recipe, sample, shared, stage, None)
}

/// [`write_sample`] of the frames `frames` of a sequence alone (all of them for None, and
/// always for a still): the files of those frames with the bytes the whole sequence gives
/// them. The frames just outside the range are built too when the flow between frames needs
/// them; the sensor series (one per sample) go with the range that holds frame 0.
pub fn write_sample_frames(
    recipe: &Recipe,
    sample: &BuiltSample,
    shared: &SharedTraceMeshes,
    stage: &mut SampleStage,
    frames: Option<Range<u32>>,
) -> Result<u32> {
    let dataset = &recipe.dataset;
    // The sensors record the whole sequence: one series a sample, not one a frame.
    if frames.as_ref().is_none_or(|range| range.start == 0) {
        write_sensor_files(dataset, sample, stage)?;
    }
    let Some(sequence) = &dataset.sequence else {
        let still = Still {
            trace_mesh: shared.get(&sample.mesh, sample.structure_triangles()),
            frame: None,
            neighbours: FrameNeighbours::default(),
            exposure: &[],
        };
        write_still(recipe, sample, still, shared, stage)?;
        return Ok(dataset.images_per_sample());
    };
    let motion = sample_motion(recipe, sample, sequence)?;
    let framing = sample.framing();
    let context = format!("while building the frames of sample {}", sample.index);
    let build_scene = |scene| {
        build_framed(dataset, sample.index, scene, Some(framing))
            .map_err(|e| recipe.locate(&e.message, e.site.as_ref(), &context))
    };
    let build = |k: usize| -> Result<SequenceFrame> {
        let frame = build_scene(motion.scene_at(&sample.scene, k))?;
        let trace_mesh = shared.get(&frame.mesh, frame.structure_triangles());
        Ok(SequenceFrame::new(
            frame,
            sequence.time(k as u32),
            trace_mesh,
        ))
    };
    let total = motion.frames();
    let range = frames.map_or(0..total, |r| r.start as usize..(r.end as usize).min(total));
    if range.is_empty() {
        return Ok(dataset.images_per_sample());
    }
    let keep_prev = dataset.outputs.wants("frame_flow");
    // The point tracks' queries are chosen on frame 0: built again here (not kept from the
    // window), so that any frame, in any range, can find them on its own.
    let first = (dataset.outputs.wants("point_tracks"))
        .then(|| build(0))
        .transpose()?;
    // The frame before the range, for the flow back to it from the range's first frame.
    let before = match range.start.checked_sub(1) {
        Some(k) if keep_prev => Some(build(k)?),
        _ => None,
    };
    let mut window = FrameWindow::new(before, build(range.start)?, keep_prev);
    for k in range.clone() {
        // The frame after the range is built too (for the flow to it), never written.
        let next = if k + 1 < total && (keep_prev || k + 1 < range.end) {
            Some(build(k + 1)?)
        } else {
            None
        };
        let index = k as u32;
        // With motion blur, the structures at each sub-instant of the exposure.
        let during = (motion.scenes_during(&sample.scene, k).into_iter())
            .map(build_scene)
            .collect::<Result<Vec<_>, _>>()?;
        let exposure: Vec<(&BuiltSample, f64)> = during
            .iter()
            .zip(sequence.exposure_instants(index))
            .collect();
        let record = FrameRecord {
            index,
            time: sequence.time(index),
            exposure: sequence.exposure,
            frames: sequence.frames(),
            fps: sequence.fps,
            mount: None,
            motion_blur: (sequence.motion_blur > 0).then_some(sequence.motion_blur),
        };
        let still = Still {
            trace_mesh: window.current.trace_mesh.clone(),
            frame: Some(record),
            neighbours: FrameNeighbours {
                first: first.as_ref(),
                ..window.neighbours(next.as_ref())
            },
            exposure: &exposure,
        };
        write_still(recipe, &window.current.sample, still, shared, stage)?;
        if let Some(next) = next {
            window.advance(next);
        }
    }
    Ok(dataset.images_per_sample())
}

/// The frames of a sequence kept while one is written: it, and the one before when the flow
/// between frames is asked for (else the previous frame is dropped at once).
struct FrameWindow {
    prev: Option<SequenceFrame>,
    current: SequenceFrame,
    keep_prev: bool,
}

impl FrameWindow {
    /// The window on `first`, `before` it (kept only when the flow between frames is asked
    /// for).
    fn new(before: Option<SequenceFrame>, first: SequenceFrame, keep_prev: bool) -> Self {
        FrameWindow {
            prev: before.filter(|_| keep_prev),
            current: first,
            keep_prev,
        }
    }

    /// The frames around the current one, `next` built ahead (none unless the flow between
    /// frames is asked for).
    fn neighbours<'a>(&'a self, next: Option<&'a SequenceFrame>) -> FrameNeighbours<'a> {
        if !self.keep_prev {
            return FrameNeighbours::default();
        }
        FrameNeighbours {
            prev: self.prev.as_ref(),
            next,
            first: None,
        }
    }

    /// Moves on to `next`.
    fn advance(&mut self, next: SequenceFrame) {
        let current = std::mem::replace(&mut self.current, next);
        self.prev = self.keep_prev.then_some(current);
    }
}

/// What a still is rendered with besides its sample: its mesh ready for tracing and, in a
/// sequence, its frame and the frames around it.
struct Still<'a> {
    trace_mesh: Arc<TraceMesh>,
    frame: Option<FrameRecord>,
    neighbours: FrameNeighbours<'a>,
    /// With motion blur, the structures at each sub-instant of the exposure, and when (empty:
    /// the frame's instant alone).
    exposure: &'a [(&'a BuiltSample, f64)],
}

/// Writes one still of the sample: its own files and every view, clean and augmented; in a
/// sequence, frame `still.frame` of it, its RGB images averaged over `still.exposure`; the
/// meshes of its sub-instants come from `shared`.
fn write_still(
    recipe: &Recipe,
    sample: &BuiltSample,
    still: Still,
    shared: &SharedTraceMeshes,
    stage: &mut SampleStage,
) -> Result<()> {
    let dataset = &recipe.dataset;
    let frame = still.frame;
    let renderer = SampleRenderer::with_trace_mesh(dataset, sample, still.trace_mesh)
        .between(still.neighbours);
    let during: Vec<SubInstant> = (still.exposure.iter())
        .map(|&(s, time)| SubInstant {
            renderer: renderer_of(dataset, shared, s),
            time,
        })
        .collect();
    let mut record = SampleRecord::new(sample);
    record.frame = frame;
    record.files = write_sample_files(dataset, sample, stage, frame.map(|f| f.index))?;
    let views: Vec<u32> = (0..dataset.cameras_per_sample()).collect();
    for group in views.chunks(rayon::current_num_threads().max(1)) {
        let encoded: Vec<Result<Vec<StagedFile>>> = group
            .par_iter()
            .map(|&view| {
                let mut files = Vec::new();
                let time = frame.map(|f| f.time);
                let at = (&renderer, time, &during[..]);
                for_each_image_at(at, view, |layers, copy, facts| {
                    files.extend(encode_view(
                        recipe,
                        (sample, &record),
                        (layers, copy),
                        facts,
                    )?);
                    Ok(())
                })?;
                Ok(files)
            })
            .collect();
        for files in encoded {
            for (path, bytes) in files? {
                stage.write(path, &bytes)?;
            }
        }
    }
    warn_unresolved_cracks(&renderer)?;
    Ok(())
}

/// The renderer of `sample`, its mesh prepared for tracing or shared from `shared`.
fn renderer_of<'a>(
    dataset: &'a DatasetSpec,
    shared: &SharedTraceMeshes,
    sample: &'a BuiltSample,
) -> SampleRenderer<'a> {
    let trace_mesh = shared.get(&sample.mesh, sample.structure_triangles());
    SampleRenderer::with_trace_mesh(dataset, sample, trace_mesh)
}

/// Warns (on stderr) about the sample's cracks no view of it resolves.
fn warn_unresolved_cracks(renderer: &SampleRenderer) -> Result<()> {
    let Some(damage) = renderer.damage() else {
        return Ok(());
    };
    let (dataset, sample) = (renderer.dataset(), renderer.sample());
    let cameras = (0..dataset.cameras_per_sample())
        .map(|view| Ok(view_camera(dataset, sample, view)?.camera))
        .collect::<Result<Vec<_>>>()?;
    let cracks = unresolved_cracks(damage, &cameras);
    if let Some(warning) = unresolved_warning(sample.index, &cracks) {
        eprintln!("warning: {warning}");
    }
    Ok(())
}

/// A file of a view: its path in the dataset and its bytes.
type StagedFile = (String, Vec<u8>);

/// Calls `each` with every image of camera view `view`: the clean one when the dataset keeps
/// it (copy None), then each augmented copy, with what its record says.
pub fn for_each_image(
    renderer: &SampleRenderer,
    view: u32,
    each: impl FnMut(&dyn RenderedLayers, Option<u32>, ViewFacts) -> Result<()>,
) -> Result<()> {
    for_each_image_at((renderer, None, &[]), view, each)
}

/// One sub-instant of a frame's exposure: the structures then, ready to render, and when.
struct SubInstant<'a> {
    renderer: SampleRenderer<'a>,
    time: f64,
}

/// [`for_each_image`] at instant `time` of a sequence (None for a still): the camera's mount
/// is displaced as the sequence's mount shake has it then; with motion blur (`during`, the
/// exposure's sub-instants), every RGB image rendered is the average over them.
fn for_each_image_at(
    (renderer, time, during): (&SampleRenderer, Option<f64>, &[SubInstant]),
    view: u32,
    mut each: impl FnMut(&dyn RenderedLayers, Option<u32>, ViewFacts) -> Result<()>,
) -> Result<()> {
    let (dataset, sample) = (renderer.dataset(), renderer.sample());
    let augment = &dataset.augment;
    // The view's camera at an instant: where its path has it, shaken on its mount.
    let at = |t: Option<f64>| frame_camera(dataset, sample, view, t);
    let drawn = at(time)?;
    // Each image's camera from the view's camera as drawn (and shaken) at one instant.
    let expose = |rendered: &RenderedView, camera_of: &dyn Fn(&ViewCamera) -> Result<Camera>| {
        if during.is_empty() {
            return Ok(());
        }
        let films = (during.iter())
            .map(|sub| {
                let drawn = at(Some(sub.time))?;
                let camera = camera_of(&drawn)?;
                Ok(sub.renderer.view_with(view, camera, drawn).film())
            })
            .collect::<Result<Vec<_>>>()?;
        rendered.expose(averaged_in_linear_light(films));
        anyhow::Ok(())
    };
    let clean = renderer.view_with(view, drawn.camera, drawn);
    expose(&clean, &|d| Ok(d.camera))?;
    if augment.keep_clean {
        let facts = ViewFacts {
            view,
            camera: clean.camera,
            drawn: &clean.drawn,
            backdrop: &clean.backdrop_drawn,
            coverage: clean.coverage(),
            augmentation: None,
            sensor: &clean.sensor,
        };
        each(&clean, None, facts)?;
    }
    for copy in 0..augment.copies {
        let (operations, camera) = copy_camera(dataset, (sample.index, view, copy), &drawn)?;
        let geometry = operations.iter().find_map(Applied::geometry);
        // Exact geometry renders the moved camera; image mode warps the clean render.
        let rendered;
        let (base, warp) = match (augment.mode, geometry) {
            (GeometryMode::Exact, Some(_)) => {
                rendered = renderer.view_with(view, camera, drawn).as_copy(copy);
                let of = (sample.index, view, copy);
                expose(&rendered, &|d| Ok(copy_camera(dataset, of, d)?.1))?;
                (&rendered, None)
            }
            (GeometryMode::Image, Some(sim)) => (&clean, Some(sim)),
            (_, None) => (&clean, None),
        };
        let copied = AugmentedView::new(base, warp, &operations, dataset.normals);
        let facts = ViewFacts {
            view,
            camera,
            drawn: &drawn,
            backdrop: &base.backdrop_drawn,
            coverage: copied.coverage(),
            augmentation: Some(AugmentationRecord {
                copy,
                mode: augment.mode,
                operations: &operations,
            }),
            sensor: &base.sensor,
        };
        each(&copied, Some(copy), facts)?;
    }
    Ok(())
}

/// Runs the dataset's per-sample writers and stages their files; returns them by kind.
fn write_sample_files(
    dataset: &DatasetSpec,
    sample: &BuiltSample,
    stage: &mut SampleStage,
    frame: Option<u32>,
) -> Result<BTreeMap<&'static str, String>> {
    let geometry = SampleGeometry::new(dataset, sample);
    let mut files = BTreeMap::new();
    for writer in SAMPLE_WRITERS
        .iter()
        .filter(|w| dataset.outputs.wants(w.output))
    {
        for (kind, bytes) in writer.files.iter().zip((writer.write)(&geometry)?) {
            let path = framed(sample_file(sample.index, kind), frame);
            stage.write(path.clone(), &bytes)?;
            files.insert(*kind, path);
        }
    }
    Ok(files)
}

/// Stages the sample's virtual sensor series (none when no beam has a sensor); not yet listed
/// in its records by kind.
fn write_sensor_files(
    dataset: &DatasetSpec,
    sample: &BuiltSample,
    stage: &mut SampleStage,
) -> Result<()> {
    for (kind, bytes) in super::sensors::sensor_files(dataset, sample)? {
        stage.write(sample_file(sample.index, &kind), &bytes)?;
    }
    Ok(())
}

/// Runs the dataset's writers on one view (or copy): its files and its record, in order.
fn encode_view(
    recipe: &Recipe,
    (sample, record): (&BuiltSample, &SampleRecord),
    (layers, copy): (&dyn RenderedLayers, Option<u32>),
    facts: ViewFacts,
) -> Result<Vec<StagedFile>> {
    let view = facts.view;
    let frame = record.frame.map(|f| f.index);
    let mut files = BTreeMap::new();
    let mut staged = Vec::new();
    for writer in WRITERS
        .iter()
        .filter(|w| recipe.dataset.outputs.wants(w.output))
    {
        let encoded = (writer.write)(layers as &dyn ViewLayers)?;
        for ((name, key), bytes) in writer.files.iter().zip(writer.keys()).zip(encoded) {
            let path = framed(view_file(sample.index, view, copy, name), frame);
            files.insert(key, path.clone());
            staged.push((path, bytes));
        }
    }
    let found = layers.visibility();
    let json = json_bytes(&record.view(recipe, sample, facts, found, files))?;
    let json_path = framed(view_file(sample.index, view, copy, "json"), frame);
    staged.push((json_path, json));
    Ok(staged)
}

/// `path` as named in frame `frame` of a sequence; unchanged for a still.
fn framed(path: String, frame: Option<u32>) -> String {
    match frame {
        Some(k) => in_frame(&path, k),
        None => path,
    }
}
