//! One sample, end to end: draw its scene, build it, render each view, hand the view's layers
//! to the dataset's writers, and stage their files with the view's record.

use super::finite::check_finite;
use super::record::{SampleRecord, json_bytes};
use super::view::{SampleRenderer, view_camera};
use crate::build::{BuiltSample, build_sample};
use crate::output::{MAX_SEGMENTATION_ID, SampleStage, WRITERS, view_file};
use crate::recipe::Recipe;
use anyhow::{Result, bail};
use std::collections::BTreeMap;

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
    for view in 0..recipe.dataset.images_per_sample() {
        view_camera(&recipe.dataset, &sample, view)?;
    }
    check_segmentation(recipe, &sample)?;
    Ok(sample)
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

/// Renders every view of the sample and stages its files. Returns the number of views written.
pub fn write_sample(recipe: &Recipe, sample: &BuiltSample, stage: &mut SampleStage) -> Result<u32> {
    let dataset = &recipe.dataset;
    let renderer = SampleRenderer::new(dataset, sample);
    let record = SampleRecord::new(sample);
    for view in 0..dataset.images_per_sample() {
        let rendered = renderer.view(view)?;
        let mut files = BTreeMap::new();
        for writer in WRITERS.iter().filter(|w| dataset.outputs.wants(w.output)) {
            let encoded = (writer.write)(&rendered)?;
            for ((name, key), bytes) in writer.files.iter().zip(writer.keys()).zip(encoded) {
                let path = view_file(sample.index, view, name);
                stage.write(path.clone(), &bytes)?;
                files.insert(key, path);
            }
        }
        let json = json_bytes(&record.view(recipe, sample, &rendered, files))?;
        stage.write(view_file(sample.index, view, "json"), &json)?;
    }
    Ok(dataset.images_per_sample())
}
