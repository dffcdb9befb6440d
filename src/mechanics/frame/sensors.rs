//! Virtual sensors on a frame's members: what a transducer, an accelerometer, an inclinometer
//! or a strain gauge fixed at a point of a member records while the time loads of a sequence
//! cross the frame's lane, each at its own rate, with optional noise.
//!
//! Owns: where a sensor sits on a frame (a member, a distance along it and, for translations,
//! the world direction it measures along) and reading each kind from the frame's state in time.
//! Must not touch: files, recipes or random streams (the noise arrives as standard normal
//! values). The integration and the grouping by rate are `FrameDynamics` and
//! `sensors::record_by_rate`, shared with beams; so is the convention that a record is the
//! response to the time loads alone (zero at rest under the frame's static loads).
//!
//! Reading (docs/sensors.md, "Sensors on frames"): a translation is the point's displacement,
//! velocity or acceleration along `direction`, each mode's field inside the member included,
//! so a point between nodes is as exact as a node; rotation, moment and strain are those of
//! the member's strong plane of bending (local x–z), signed as on a beam: for a horizontal
//! member, rotation is the slope of the downward deflection and a sagging moment stretches
//! the bottom face.

use super::{FrameModel, FrameSolution, FrameState};
use crate::mechanics::dynamics::{Motion, STEPS_PER_PERIOD, TimeLoad};
use crate::mechanics::sensors::{Sensor, Series, record_by_rate};
use glam::DVec3;

/// A sensor on a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct MemberSensor {
    /// What it measures, where along its member (`at`), at which rate, with which noise.
    pub sensor: Sensor,
    /// The member it is fixed to.
    pub member: usize,
    /// For displacement, velocity and acceleration: the world direction measured along, a
    /// unit vector (down, [0, 0, −1], matches a beam's sign).
    pub direction: DVec3,
}

/// The time loads on a frame's lane and its modal model.
#[derive(Clone, Copy, Debug)]
pub struct FrameExcitation<'a> {
    /// Members in order that the loads move along.
    pub lane: &'a [usize],
    /// The loads.
    pub loads: &'a [TimeLoad],
    /// Number of modes superposed.
    pub modes: usize,
    /// Modal damping ratio.
    pub damping: f64,
}

impl MemberSensor {
    /// Its member exists, its position lies on it, its direction is a unit vector and its
    /// rate, noise and fibre are in range; otherwise the parameter and its value.
    pub fn check(&self, model: &FrameModel, duration: f64) -> Result<(), String> {
        let name = &self.sensor.name;
        let Some(member) = model.members.get(self.member) else {
            return Err(format!(
                "sensor {name:?}: member {} does not exist (the frame has {} members)",
                self.member,
                model.members.len()
            ));
        };
        let [a, b] = [member.start, member.end].map(|n| DVec3::from_array(model.nodes[n]));
        self.sensor.check(a.distance(b), duration)?;
        if !(self.direction.is_finite() && (self.direction.length() - 1.0).abs() < 1e-9) {
            return Err(format!(
                "sensor {name:?}: direction {} must be a unit vector",
                self.direction
            ));
        }
        Ok(())
    }

    /// What it reads from `state`, minus what it reads at rest (`rest`).
    fn read(&self, frame: &Reading, state: &FrameState) -> f64 {
        let (m, x) = (self.member, self.sensor.at);
        let here = state.solution.strong_axis_at(m, x);
        let rest = frame.rest.strong_axis_at(m, x);
        let moved = state.solution.member_at(m, x).0 - frame.rest.member_at(m, x).0;
        let along = |v: DVec3| v.dot(self.direction);
        let motion = Motion {
            deflection: along(moved),
            velocity: along(frame.rate(state, 0, m, x)),
            acceleration: along(frame.rate(state, 1, m, x)),
            slope: here.rotation - rest.rotation,
            moment: here.moment - rest.moment,
        };
        self.sensor.kind.read(&motion, here.rigidity)
    }
}

/// What the readings of one frame share: its modal model and its state at rest.
struct Reading {
    dynamics: super::FrameDynamics,
    rest: FrameSolution,
}

impl Reading {
    fn rate(&self, state: &FrameState, rate: usize, m: usize, x: f64) -> DVec3 {
        self.dynamics.rate_at(state, rate, m, x)
    }
}

/// Each sensor's record of `model` from rest (under its static loads) at t = 0 to `duration`
/// under `excitation`, in the order of `sensors`; `normal` as `sensors::record` takes it.
/// Without time loads nothing moves: every record is zero (plus its noise), and the frame
/// needs no lane.
pub fn record_members(
    model: &FrameModel,
    excitation: FrameExcitation,
    duration: f64,
    sensors: &[MemberSensor],
    normal: &mut dyn FnMut() -> f64,
) -> Result<Vec<Series>, String> {
    for sensor in sensors {
        sensor.check(model, duration)?;
    }
    let plain: Vec<Sensor> = sensors.iter().map(|s| s.sensor.clone()).collect();
    let reading = match excitation.loads {
        [] => None,
        loads => {
            let dynamics = model.dynamics(excitation.lane, excitation.modes, excitation.damping)?;
            let rest = model.solve()?;
            Some((Reading { dynamics, rest }, loads))
        }
    };
    record_by_rate(&plain, duration, normal, |times, same_rate| {
        let Some((frame, loads)) = &reading else {
            return Ok(vec![vec![0.0; times.len()]; same_rate.len()]);
        };
        let states = frame
            .dynamics
            .respond(loads, 0.0, times, STEPS_PER_PERIOD)?;
        Ok(same_rate
            .iter()
            .map(|&j| states.iter().map(|s| sensors[j].read(frame, s)).collect())
            .collect())
    })
}

#[cfg(test)]
mod tests {
    use super::super::modes_tests::chain;
    use super::super::{STEEL_DENSITY, STEEL_E};
    use super::*;
    use crate::mechanics::Support;
    use crate::mechanics::dynamics::{Axle, ModalBeam};
    use crate::mechanics::sensors::{Fibre, SensorKind, record};

    /// The chain's 0.1 × 0.2 m rectangle: area, I and the extreme fibre.
    const AREA: f64 = 0.1 * 0.2;
    const INERTIA: f64 = 0.1 * 0.008 / 12.0;
    const FIBRE: f64 = 0.1;

    fn sensor(name: &str, kind: SensorKind, at: f64) -> Sensor {
        Sensor {
            name: name.into(),
            kind,
            at,
            rate: 200.0,
            noise: 0.0,
        }
    }

    /// The same kinds on a frame chain (member, x) and on the beam (x along the span).
    fn kinds() -> Vec<(Sensor, usize, f64)> {
        let bottom = SensorKind::Strain {
            fibre: Fibre::Bottom,
            distance: FIBRE,
        };
        vec![
            (sensor("mid", SensorKind::Displacement, 0.625), 7, 5.0),
            (sensor("inner", SensorKind::Displacement, 0.25), 2, 1.5),
            (sensor("speed", SensorKind::Velocity, 0.3), 9, 5.925),
            (sensor("acc", SensorKind::Acceleration, 0.625), 7, 5.0),
            (sensor("slope", SensorKind::Rotation, 0.0), 0, 0.0),
            (sensor("gauge", bottom, 0.625), 7, 5.0),
        ]
    }

    fn on_members(chosen: &[(Sensor, usize, f64)]) -> Vec<MemberSensor> {
        chosen
            .iter()
            .map(|(s, member, _)| MemberSensor {
                sensor: s.clone(),
                member: *member,
                direction: DVec3::NEG_Z,
            })
            .collect()
    }

    fn on_beam(chosen: &[(Sensor, usize, f64)]) -> Vec<Sensor> {
        chosen
            .iter()
            .map(|(s, _, x)| Sensor {
                at: *x,
                ..s.clone()
            })
            .collect()
    }

    #[test]
    fn sensors_on_a_chain_read_what_the_same_sensors_on_the_beam_read() {
        // A force crossing at 30 m/s (dynamic amplification clearly present); the chain of 16
        // Hermite members follows the beam's modes to a few 1e-4 in frequency, so the readings
        // agree to a stated fraction of each history's peak (measured: 6e-5, 6e-5, 2e-4,
        // 4e-3, 7e-5, 1.1e-3): displacements and the support's slope to 2e-4, velocity to
        // 1e-3, acceleration (weighted to the higher modes) to 1e-2, strain at mid-span (the
        // modes' moment is linear inside an element) to 5e-3.
        let (model, _) = chain(16, Support::SimplySupported);
        let loads = vec![TimeLoad::Vehicle {
            axles: vec![Axle {
                behind: 0.0,
                force: 1e4,
            }],
            speed: 30.0,
            enters: 0.0,
        }];
        let lane: Vec<usize> = (0..16).collect();
        let chosen = kinds();
        let excitation = FrameExcitation {
            lane: &lane,
            loads: &loads,
            modes: 4,
            damping: 0.02,
        };
        let frame =
            record_members(&model, excitation, 0.5, &on_members(&chosen), &mut || 0.0).unwrap();
        let beam = ModalBeam::new(
            Support::SimplySupported,
            10.0,
            STEEL_E * INERTIA,
            STEEL_DENSITY * AREA,
            0.02,
            4,
        )
        .unwrap();
        let truth = record(&beam, &loads, 0.5, &on_beam(&chosen), &mut || 0.0).unwrap();
        let tolerances = [2e-4, 2e-4, 1e-3, 1e-2, 2e-4, 5e-3];
        for ((f, b), ((s, _, _), tolerance)) in
            frame.iter().zip(&truth).zip(chosen.iter().zip(tolerances))
        {
            assert_eq!(f.times, b.times);
            let peak = b.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(peak > 0.0, "{}", s.name);
            let worst = f
                .values
                .iter()
                .zip(&b.values)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(
                worst < tolerance * peak,
                "{}: worst {worst:e} of peak {peak:e}",
                s.name
            );
        }
    }

    #[test]
    fn a_settled_step_gives_the_static_closed_forms_at_mid_span() {
        // P at mid-span of a simply supported span, settled: deflection PL³/48EI, end slope
        // PL²/16EI, bottom strain (PL/4)c/EI; the chain has a node there, so the element's
        // fields are exact.
        let (model, _) = chain(16, Support::SimplySupported);
        let force = 1e4;
        let loads = vec![TimeLoad::Ramp {
            at: 5.0,
            force,
            start: 0.0,
            rise: 0.0,
        }];
        let lane: Vec<usize> = (0..16).collect();
        let excitation = FrameExcitation {
            lane: &lane,
            loads: &loads,
            modes: 4,
            damping: 0.6,
        };
        let chosen = kinds();
        let sensors = on_members(&chosen);
        let settled = record_members(&model, excitation, 3.0, &sensors, &mut || 0.0).unwrap();
        let ei = STEEL_E * INERTIA;
        let l = 10.0f64;
        let last = |name: &str| {
            let i = chosen.iter().position(|(s, _, _)| s.name == name).unwrap();
            *settled[i].values.last().unwrap()
        };
        let close = |got: f64, exact: f64| (got / exact - 1.0).abs() < 1e-6;
        let deflection = force * l.powi(3) / (48.0 * ei);
        assert!(close(last("mid"), deflection), "{}", last("mid"));
        let slope = force * l * l / (16.0 * ei);
        assert!(close(last("slope"), slope), "{} vs {slope}", last("slope"));
        let strain = force * l / 4.0 * FIBRE / ei;
        assert!(
            close(last("gauge"), strain),
            "{} vs {strain}",
            last("gauge")
        );
        // Settled: the acceleration has decayed (ζ = 0.6 for 3 s) to nothing measurable.
        assert!(last("acc").abs() < 1e-9, "{}", last("acc"));
    }

    #[test]
    fn without_time_loads_nothing_moves_and_bad_sensors_are_refused() {
        let (model, _) = chain(4, Support::SimplySupported);
        let mut sensors = on_members(&kinds()[..1]);
        sensors[0].member = 1;
        let excitation = FrameExcitation {
            lane: &[],
            loads: &[],
            modes: 4,
            damping: 0.02,
        };
        let still = record_members(&model, excitation, 1.0, &sensors, &mut || 0.0).unwrap();
        assert_eq!(still[0].values, vec![0.0; 200]);
        sensors[0].member = 4;
        let why = record_members(&model, excitation, 1.0, &sensors, &mut || 0.0).unwrap_err();
        assert!(why.contains("member 4 does not exist"), "{why}");
        sensors[0].member = 1;
        sensors[0].direction = DVec3::new(0.0, 0.0, -2.0);
        let why = record_members(&model, excitation, 1.0, &sensors, &mut || 0.0).unwrap_err();
        assert!(why.contains("direction") && why.contains("-2"), "{why}");
        sensors[0].direction = DVec3::NEG_Z;
        sensors[0].sensor.at = 2.6;
        let why = record_members(&model, excitation, 1.0, &sensors, &mut || 0.0).unwrap_err();
        assert!(why.contains("at = 2.6"), "{why}");
    }
}
