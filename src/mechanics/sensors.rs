//! Virtual sensors on a beam in time: what a displacement transducer, a velocity sensor, an
//! accelerometer, an inclinometer or a strain gauge fixed at a point of the span would record
//! while the loads of a sequence act, each at its own sampling rate, with optional noise.
//!
//! Owns: the sensor description in the beam's frame (kind, position, rate, noise), the sample
//! times of a record, and turning the modal response of `dynamics` into each sensor's series.
//! Must not touch: files, recipes, meshes or random streams; the noise arrives as standard
//! normal values the caller draws from a stream it derived (never global state). Signs follow `dynamics`: deflection positive downward, sagging
//! moment positive; conventions and units are listed in `docs/sensors.md`.

use super::dynamics::{ModalBeam, Motion, Response, TimeLoad};

/// The most samples one sensor may record (10⁷: 80 MB of f64), so a mistyped rate or duration
/// is refused instead of exhausting memory.
pub const MAX_SAMPLES: f64 = 1e7;

/// Which face of the section a strain gauge is glued to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fibre {
    /// The upper face (compressed by a sagging moment).
    Top,
    /// The lower face (stretched by a sagging moment).
    Bottom,
}

/// What a sensor measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SensorKind {
    /// Vertical deflection of the axis, m, positive downward.
    Displacement,
    /// Its rate, m/s, positive downward.
    Velocity,
    /// Its second rate, m/s², positive downward.
    Acceleration,
    /// Slope of the axis dv/dx, rad: positive where the deflection grows with x.
    Rotation,
    /// Axial strain of a fibre `distance` metres from the neutral axis (the section's extreme
    /// fibre for a gauge on its face), positive in tension: ε = ∓ M·distance / EI for the top
    /// and bottom faces.
    Strain {
        /// The face.
        fibre: Fibre,
        /// Distance from the neutral axis, m (positive).
        distance: f64,
    },
}

impl SensorKind {
    /// The name in recipes and file headers.
    pub fn name(&self) -> &'static str {
        match self {
            SensorKind::Displacement => "displacement",
            SensorKind::Velocity => "velocity",
            SensorKind::Acceleration => "acceleration",
            SensorKind::Rotation => "rotation",
            SensorKind::Strain {
                fibre: Fibre::Top, ..
            } => "strain_top",
            SensorKind::Strain {
                fibre: Fibre::Bottom,
                ..
            } => "strain_bottom",
        }
    }

    /// The SI unit of the values.
    pub fn unit(&self) -> &'static str {
        match self {
            SensorKind::Displacement => "m",
            SensorKind::Velocity => "m/s",
            SensorKind::Acceleration => "m/s^2",
            SensorKind::Rotation => "rad",
            SensorKind::Strain { .. } => "m/m",
        }
    }

    /// The quantity this kind reads from the beam's motion at a point (`ei` for strain).
    pub fn read(&self, motion: &Motion, ei: f64) -> f64 {
        match *self {
            SensorKind::Displacement => motion.deflection,
            SensorKind::Velocity => motion.velocity,
            SensorKind::Acceleration => motion.acceleration,
            SensorKind::Rotation => motion.slope,
            // Sagging (M > 0) stretches the bottom face: ε = M·y/EI with y downward.
            SensorKind::Strain { fibre, distance } => {
                let below = match fibre {
                    Fibre::Top => -distance,
                    Fibre::Bottom => distance,
                };
                motion.moment * below / ei
            }
        }
    }
}

/// One sensor on a beam.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensor {
    /// Its name in file headers: letters, digits, `_` and `-` (unique on the sample).
    pub name: String,
    /// What it measures.
    pub kind: SensorKind,
    /// Position along the axis from x = 0, m.
    pub at: f64,
    /// Sampling rate, Hz.
    pub rate: f64,
    /// RMS of the white Gaussian noise added to each value, in the kind's unit (0 for none).
    pub noise: f64,
}

impl Sensor {
    /// Every number is finite and in range for a beam of span `length` recording for
    /// `duration` seconds; otherwise the parameter and its value.
    pub fn check(&self, length: f64, duration: f64) -> Result<(), String> {
        let name = &self.name;
        // The name labels a column of a CSV file: no separators, quotes or spaces.
        let plain = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
        if name.is_empty() || !name.chars().all(plain) {
            return Err(format!(
                "sensor name {name:?} must be letters, digits, _ and - (at least one)"
            ));
        }
        if !(self.at.is_finite() && (0.0..=length).contains(&self.at)) {
            return Err(format!(
                "sensor {name:?}: position at = {} m lies off the span 0 to {length} m",
                self.at
            ));
        }
        if !(self.rate.is_finite() && self.rate > 0.0) {
            return Err(format!(
                "sensor {name:?}: rate must be positive, got {} Hz",
                self.rate
            ));
        }
        if !(self.noise.is_finite() && self.noise >= 0.0) {
            return Err(format!(
                "sensor {name:?}: noise must be ≥ 0, got {}",
                self.noise
            ));
        }
        if let SensorKind::Strain { distance, .. } = self.kind
            && !(distance.is_finite() && distance > 0.0)
        {
            return Err(format!(
                "sensor {name:?}: fibre distance must be positive, got {distance} m"
            ));
        }
        if self.rate * duration > MAX_SAMPLES {
            return Err(format!(
                "sensor {name:?}: rate {} Hz over {duration} s is more than {MAX_SAMPLES} samples",
                self.rate
            ));
        }
        Ok(())
    }

    /// The instants it samples: k / rate for every k with k / rate < duration (at least
    /// t = 0), as the frames of a sequence are.
    pub fn times(&self, duration: f64) -> Vec<f64> {
        // The relative slack drops a last sample at t = duration when duration·rate is an
        // integer up to rounding (4 s at 60 Hz is 240.00000000000003 or 239.99999999999997).
        let count = (duration * self.rate * (1.0 - 1e-12)).ceil().max(1.0) as usize;
        (0..count).map(|k| k as f64 / self.rate).collect()
    }
}

/// What one sensor recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Sample instants, s, from 0 at the sensor's rate.
    pub times: Vec<f64>,
    /// The values at those instants, in the kind's unit.
    pub values: Vec<f64>,
}

pub use super::dynamics::STEPS_PER_PERIOD;

/// Each sensor's record of the beam from rest at t = 0 to `duration` under `loads`, in the
/// order of `sensors`. Sensors sharing a rate share one integration. `normal` gives
/// independent standard normal values; they are taken sensor by sensor in their order, one
/// per sample, and a sensor without noise takes none.
pub fn record(
    beam: &ModalBeam,
    loads: &[TimeLoad],
    duration: f64,
    sensors: &[Sensor],
    normal: &mut dyn FnMut() -> f64,
) -> Result<Vec<Series>, String> {
    for sensor in sensors {
        sensor.check(beam.length(), duration)?;
    }
    for load in loads {
        load.check(beam.length())?;
    }
    record_by_rate(sensors, duration, normal, |times, same_rate| {
        let response = beam.respond(loads, 0.0, times, STEPS_PER_PERIOD);
        Ok(same_rate
            .iter()
            .map(|&j| sample(beam, loads, &response, &sensors[j]))
            .collect())
    })
}

/// Each sensor's series over `duration`, in the order of `sensors` (already checked), with
/// their noise: `respond(times, indices)` gives the values of the sensors at `indices` (all
/// those sampling at one rate) at those times, so the structure is integrated once per rate.
pub fn record_by_rate(
    sensors: &[Sensor],
    duration: f64,
    normal: &mut dyn FnMut() -> f64,
    mut respond: impl FnMut(&[f64], &[usize]) -> Result<Vec<Vec<f64>>, String>,
) -> Result<Vec<Series>, String> {
    if !(duration.is_finite() && duration >= 0.0) {
        return Err(format!("duration must be ≥ 0, got {duration} s"));
    }
    let mut series: Vec<Option<Series>> = vec![None; sensors.len()];
    for (i, sensor) in sensors.iter().enumerate() {
        if series[i].is_some() {
            continue;
        }
        let times = sensor.times(duration);
        let same_rate: Vec<usize> = (i..sensors.len())
            .filter(|&j| sensors[j].rate == sensor.rate)
            .collect();
        let values = respond(&times, &same_rate)?;
        for (j, values) in same_rate.into_iter().zip(values) {
            series[j] = Some(Series {
                times: times.clone(),
                values,
            });
        }
    }
    let mut series: Vec<Series> = series.into_iter().flatten().collect();
    for (sensor, recorded) in sensors.iter().zip(&mut series) {
        add_noise(&mut recorded.values, sensor.noise, normal);
    }
    Ok(series)
}

/// The sensor's quantity at each output of `response`.
fn sample(beam: &ModalBeam, loads: &[TimeLoad], response: &Response, sensor: &Sensor) -> Vec<f64> {
    (0..response.len())
        .map(|k| {
            let motion = response.at(beam, loads, k, sensor.at);
            sensor.kind.read(&motion, beam.ei())
        })
        .collect()
}

/// Adds white Gaussian noise of RMS `rms` (nothing is drawn when it is 0).
fn add_noise(values: &mut [f64], rms: f64, normal: &mut dyn FnMut() -> f64) {
    if rms == 0.0 {
        return;
    }
    for v in values {
        *v += rms * normal();
    }
}

#[cfg(test)]
mod tests;
