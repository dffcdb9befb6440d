//! The hook that writes a sample's virtual sensors: every sensor of every beam and frame
//! recorded over the dataset's sequence, grouped by rate into the files of `output::series`.
//!
//! Owns: the order of the columns (structures in scene order, then each structure's sensors
//! in recipe order), the noise stream (`seeds::SENSORS`, scope: the sample) and the check that names are
//! unique in the sample. Must not touch: the mechanics (`scene::record_sensors`) or the bytes
//! (`output::series_files`).

use crate::build::BuiltSample;
use crate::output::{RateGroup, SensorColumn, series_files};
use crate::scene::{DatasetSpec, SensorSpec, Structure};
use crate::seeds::{SENSORS, Scope, Stream};
use anyhow::{Result, anyhow, bail};

/// The sensor files of `sample` as (kind, bytes), none when no structure has a sensor.
pub(super) fn sensor_files(
    dataset: &DatasetSpec,
    sample: &BuiltSample,
) -> Result<Vec<(String, Vec<u8>)>> {
    let instrumented: Vec<&Structure> = (sample.scene.structures.iter())
        .filter(|s| !sensors_of(s).is_empty())
        .collect();
    let Some(first) = instrumented.first() else {
        return Ok(Vec::new());
    };
    let Some(sequence) = &dataset.sequence else {
        bail!(
            "sensor {:?} needs a time to record over: set dataset.sequence (duration, fps)",
            sensors_of(first)[0].name
        );
    };
    let mut stream = Stream::new(dataset.seed, Scope::Sample(sample.index), SENSORS);
    let mut groups: Vec<RateGroup> = Vec::new();
    for structure in instrumented {
        let mut normal = || stream.normal();
        let series = match structure {
            Structure::Beam(b) => crate::scene::record_sensors(b, sequence.duration, &mut normal),
            Structure::Frame(f) => {
                crate::scene::record_frame_sensors(f, sequence.duration, &mut normal)
            }
            _ => unreachable!("only beams and frames carry sensors"),
        }
        .map_err(|why| anyhow!("sample {}: {why}", sample.index))?;
        for (spec, recorded) in sensors_of(structure).iter().zip(series) {
            let taken = groups.iter().flat_map(|g| &g.columns);
            if taken.into_iter().any(|c| c.name == spec.name) {
                bail!(
                    "sensor name {:?} is used twice in sample {}: names label columns and must be unique",
                    spec.name,
                    sample.index
                );
            }
            let column = SensorColumn {
                name: spec.name.clone(),
                kind: spec.kind.name().to_string(),
                unit: spec.kind.unit().to_string(),
                member: spec.member,
                at: spec.at,
                values: recorded.values,
            };
            match groups.iter_mut().find(|g| g.rate == spec.rate) {
                Some(group) => group.columns.push(column),
                None => groups.push(RateGroup {
                    rate: spec.rate,
                    times: recorded.times,
                    columns: vec![column],
                }),
            }
        }
    }
    series_files(&groups)
}

/// The sensors a structure carries (only beams and frames carry any).
fn sensors_of(structure: &Structure) -> &[SensorSpec] {
    match structure {
        Structure::Beam(b) => &b.sensors,
        Structure::Frame(f) => &f.sensors,
        _ => &[],
    }
}
