//! One sample, end to end: draw its scene, build it, render each view, hand the view's layers
//! to the dataset's writers, and stage their files with the view's record.

use super::record::{SampleRecord, json_bytes};
use super::view::SampleRenderer;
use crate::build::{BuiltSample, build_sample};
use crate::output::{SampleStage, WRITERS, view_file};
use crate::recipe::Recipe;
use anyhow::Result;
use std::collections::BTreeMap;

/// Draws the scene of sample `index` and builds its deformed meshes; fails on anything that
/// would make non-finite output.
pub fn prepare(recipe: &Recipe, index: u64) -> Result<BuiltSample> {
    let scene = recipe.scene(index)?;
    build_sample(&recipe.dataset, index, scene).map_err(|e| {
        let context = format!("while building sample {index}");
        recipe.locate(&e.message, e.site.as_ref(), &context).into()
    })
}

/// Renders every view of the sample and stages its files. Returns the number of views written.
pub fn write_sample(recipe: &Recipe, sample: &BuiltSample, stage: &mut SampleStage) -> Result<u32> {
    let dataset = &recipe.dataset;
    let renderer = SampleRenderer::new(dataset, sample);
    let record = SampleRecord::new(sample);
    for view in 0..dataset.views {
        let rendered = renderer.view(view);
        let mut files = BTreeMap::new();
        for writer in WRITERS.iter().filter(|w| dataset.outputs.wants(w.output)) {
            for file in (writer.write)(&rendered)? {
                let name = format!("{}.{}", file.key, file.extension);
                let path = view_file(sample.index, view, &name);
                stage.write(path.clone(), &file.bytes)?;
                files.insert(file.key, path);
            }
        }
        let json = json_bytes(&record.view(recipe, sample, &rendered, files))?;
        stage.write(view_file(sample.index, view, "json"), &json)?;
    }
    Ok(dataset.views)
}
