//! `--format png16`: every view's depth as `samples/NNNN/{stem}.depth_mm.png`, 16-bit grey in
//! whole millimetres (see `depth_mm`), mirroring the dataset's `samples/` folder, for loaders
//! that read no OpenEXR.

use super::depth_mm;
use super::{Job, Summary, needed};
use crate::dataset::View;
use anyhow::Result;
use serde_json::{Value, json};

/// Views converted together.
const BATCH: usize = 64;

pub(super) fn write(job: &mut Job) -> Result<Value> {
    let (dataset, out) = (job.dataset, job.out);
    let views: Vec<&View> = dataset.views().collect();
    // Converted a batch at a time on every core, written in order: memory stays bounded.
    for batch in views.chunks(BATCH) {
        for view in batch {
            needed(view, "depth.exr", "png16")?;
        }
        for (view, (png, clamped)) in batch.iter().zip(depth_mm::pngs_of(dataset, batch)?) {
            let target = format!("{}/{}.depth_mm.png", view.folder(), view.stem);
            job.placer.write(&out.join(target), &png)?;
            job.summary.views += 1;
            job.summary.saturated += clamped.saturated;
            job.summary.raised += clamped.raised;
        }
    }
    Ok(json!({
        "layout": "samples/{sample/1000:04}/{sample:06}_{view:02}[a{copy}].depth_mm.png",
        "depth_mm": depth_record(&job.summary),
    }))
}

/// How depth was encoded, and how many pixels did not fit: for `export.json`.
pub(super) fn depth_record(summary: &Summary) -> Value {
    json!({
        "encoding": "16-bit grey PNG, planar z in whole millimetres (rounded to nearest), 0 = no surface",
        "saturated_pixels": summary.saturated,
        "saturated_rule": "depth beyond 65.535 m written as 65535",
        "raised_pixels": summary.raised,
        "raised_rule": "depth closer than 0.5 mm written as 1, so no surface is lost",
    })
}
