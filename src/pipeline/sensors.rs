//! The hook that writes a sample's virtual sensors: every sensor of every beam recorded over
//! the dataset's sequence, grouped by rate into the files of `output::series`.
//!
//! Owns: the order of the columns (beams in scene order, then each beam's sensors in recipe
//! order), the noise stream (`seeds::SENSORS`, scope: the sample) and the check that names are
//! unique in the sample. Must not touch: the mechanics (`scene::record_sensors`) or the bytes
//! (`output::series_files`).

use crate::build::BuiltSample;
use crate::output::{RateGroup, SensorColumn, series_files};
use crate::scene::{BeamSpec, DatasetSpec, Structure};
use crate::seeds::{SENSORS, Scope, Stream};
use anyhow::{Result, anyhow, bail};

/// The sensor files of `sample` as (kind, bytes), none when no beam has a sensor.
pub(super) fn sensor_files(
    dataset: &DatasetSpec,
    sample: &BuiltSample,
) -> Result<Vec<(String, Vec<u8>)>> {
    let beams: Vec<&BeamSpec> = (sample.scene.structures.iter())
        .filter_map(|s| match s {
            Structure::Beam(b) if !b.sensors.is_empty() => Some(b),
            _ => None,
        })
        .collect();
    if beams.is_empty() {
        return Ok(Vec::new());
    }
    let Some(sequence) = &dataset.sequence else {
        bail!(
            "sensor {:?} needs a time to record over: set dataset.sequence (duration, fps)",
            beams[0].sensors[0].name
        );
    };
    let mut stream = Stream::new(dataset.seed, Scope::Sample(sample.index), SENSORS);
    let mut groups: Vec<RateGroup> = Vec::new();
    for beam in beams {
        let series = crate::scene::record_sensors(beam, sequence.duration, &mut || stream.normal())
            .map_err(|why| anyhow!("sample {}: {why}", sample.index))?;
        for (spec, recorded) in beam.sensors.iter().zip(series) {
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
                unit: spec.sensor(beam).kind.unit().to_string(),
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
