//! Virtual sensors as a recipe declares them on a beam or a frame's member (`.sensor(#{…})`):
//! what each measures, where, at which rate and with how much noise; and recording them over a
//! sample's sequence.
//!
//! Owns: the plain, serialisable description (`BeamSpec::sensors`, `FrameSpec::sensors`), its
//! translation into the mechanics' sensors, and the beam's modal model built from its declared
//! section, material and motion. Must not touch: Rhai, random streams or files: noise arrives as standard normal
//! values the caller draws from the sample's stream, and the series leave as numbers.

use super::{BeamMotion, BeamSpec, FrameSpec};
use crate::mechanics::dynamics::ModalBeam;
use crate::mechanics::frame::{FrameExcitation, MemberSensor, SpaceSection, record_members};
use crate::mechanics::sensors::{Fibre, Sensor, SensorKind, Series, record};
use serde::Serialize;

/// What a declared sensor measures (the recipe's `kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SensorQuantity {
    /// Vertical deflection, m, positive downward.
    Displacement,
    /// Its rate, m/s.
    Velocity,
    /// Its second rate, m/s².
    Acceleration,
    /// Slope of the axis, rad.
    Rotation,
    /// Strain of the upper face, positive in tension.
    StrainTop,
    /// Strain of the lower face, positive in tension.
    StrainBottom,
}

impl SensorQuantity {
    /// Every quantity, in the order recipes list them.
    pub const ALL: [SensorQuantity; 6] = [
        SensorQuantity::Displacement,
        SensorQuantity::Velocity,
        SensorQuantity::Acceleration,
        SensorQuantity::Rotation,
        SensorQuantity::StrainTop,
        SensorQuantity::StrainBottom,
    ];

    /// The mechanics' kind, with the fibre distance for strains.
    fn kind(self, fibre: f64) -> SensorKind {
        match self {
            SensorQuantity::Displacement => SensorKind::Displacement,
            SensorQuantity::Velocity => SensorKind::Velocity,
            SensorQuantity::Acceleration => SensorKind::Acceleration,
            SensorQuantity::Rotation => SensorKind::Rotation,
            SensorQuantity::StrainTop => SensorKind::Strain {
                fibre: Fibre::Top,
                distance: fibre,
            },
            SensorQuantity::StrainBottom => SensorKind::Strain {
                fibre: Fibre::Bottom,
                distance: fibre,
            },
        }
    }

    /// The name in recipes and files (`strain_top`, …).
    pub fn name(self) -> &'static str {
        self.kind(1.0).name()
    }

    /// The SI unit of its values.
    pub fn unit(self) -> &'static str {
        self.kind(1.0).unit()
    }
}

/// A sensor on a beam, as declared.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SensorSpec {
    /// Its name, the label of its column (letters, digits, `_`, `-`; unique in the sample).
    pub name: String,
    /// What it measures.
    pub kind: SensorQuantity,
    /// Position along the beam's axis from x = 0, or along its member from the member's start
    /// node, m.
    pub at: f64,
    /// On a frame: the member it is fixed to.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub member: Option<usize>,
    /// On a frame, for displacement, velocity and acceleration: the world direction measured
    /// along (a unit vector; absent: down, [0, 0, −1], a beam's sign).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 3]>,
    /// Sampling rate, Hz.
    pub rate: f64,
    /// RMS of the white Gaussian noise added, in the kind's unit (0: none).
    pub noise: f64,
    /// For strains: the gauge's distance from the neutral axis, m; absent: the section's
    /// extreme fibre (half its height).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fibre: Option<f64>,
}

impl SensorSpec {
    /// The mechanics' sensor on `beam`.
    pub fn sensor(&self, beam: &BeamSpec) -> Sensor {
        self.with_face(beam.section.properties(beam.poisson).extreme_fibre)
    }

    /// The mechanics' sensor on a member of `frame` (the member must exist: the recipe checks
    /// it); a strain gauge sits on the member's face in its strong plane unless told otherwise.
    pub fn member_sensor(&self, frame: &FrameSpec) -> MemberSensor {
        let member = self.member.unwrap_or(0);
        let face = frame
            .model
            .members
            .get(member)
            .map_or(0.0, |m| SpaceSection::of(&m.section, m.poisson).fibre_z);
        MemberSensor {
            sensor: self.with_face(face),
            member,
            direction: self
                .direction
                .map_or(glam::DVec3::NEG_Z, glam::DVec3::from_array),
        }
    }

    /// The mechanics' sensor with `face` as the default fibre distance.
    fn with_face(&self, face: f64) -> Sensor {
        Sensor {
            name: self.name.clone(),
            kind: self.kind.kind(self.fibre.unwrap_or(face)),
            at: self.at,
            rate: self.rate,
            noise: self.noise,
        }
    }
}

/// The modal model of `beam` moving as `motion` says: EI and the mass per length (density ×
/// area) from its declared section and material.
pub fn modal_beam(beam: &BeamSpec, motion: &BeamMotion) -> Result<ModalBeam, String> {
    let section = beam.section.properties(beam.poisson);
    ModalBeam::new(
        beam.support,
        beam.length,
        beam.elastic_modulus * section.second_moment,
        motion.density * section.area,
        motion.damping,
        motion.modes,
    )
}

/// What the beam's sensors record over `duration` seconds from rest, under the time loads of
/// its motion (none: the beam stays at rest and only noise is recorded), in the order they
/// were declared. Values are the response to the time loads: the static loads, which act
/// throughout, add their constant deflection and strain on top (`docs/sensors.md`).
pub fn record_sensors(
    beam: &BeamSpec,
    duration: f64,
    normal: &mut dyn FnMut() -> f64,
) -> Result<Vec<Series>, String> {
    let motion = beam.motion.clone().unwrap_or_default();
    let sensors: Vec<Sensor> = beam.sensors.iter().map(|s| s.sensor(beam)).collect();
    record(
        &modal_beam(beam, &motion)?,
        &motion.loads,
        duration,
        &sensors,
        normal,
    )
}

/// What the frame's sensors record over `duration` seconds from rest under its static loads,
/// under the time loads of its motion on its lane, in the order they were declared (the
/// response to the time loads, as for a beam).
pub fn record_frame_sensors(
    frame: &FrameSpec,
    duration: f64,
    normal: &mut dyn FnMut() -> f64,
) -> Result<Vec<Series>, String> {
    let motion = frame.motion.clone().unwrap_or_default();
    let sensors: Vec<MemberSensor> = frame
        .sensors
        .iter()
        .map(|s| s.member_sensor(frame))
        .collect();
    let excitation = FrameExcitation {
        lane: &frame.lane,
        loads: &motion.loads,
        modes: motion.modes as usize,
        damping: motion.damping,
    };
    record_members(&frame.model, excitation, duration, &sensors, normal)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::dynamics::TimeLoad;

    fn gauge(kind: SensorQuantity, fibre: Option<f64>) -> SensorSpec {
        SensorSpec {
            name: "g".into(),
            kind,
            at: 5.0,
            rate: 100.0,
            noise: 0.0,
            fibre,
            member: None,
            direction: None,
        }
    }

    #[test]
    fn a_strain_gauge_sits_on_the_sections_face_unless_told_otherwise() {
        let beam = BeamSpec::rectangular(10.0, 0.2, 0.5);
        let top = gauge(SensorQuantity::StrainTop, None).sensor(&beam);
        assert_eq!(
            top.kind,
            SensorKind::Strain {
                fibre: Fibre::Top,
                distance: 0.25
            }
        );
        let inner = gauge(SensorQuantity::StrainBottom, Some(0.1)).sensor(&beam);
        assert_eq!(
            inner.kind,
            SensorKind::Strain {
                fibre: Fibre::Bottom,
                distance: 0.1
            }
        );
        let names = SensorQuantity::ALL.map(SensorQuantity::name);
        assert_eq!(
            names,
            [
                "displacement",
                "velocity",
                "acceleration",
                "rotation",
                "strain_top",
                "strain_bottom"
            ]
        );
    }

    #[test]
    fn a_declared_beam_settles_to_its_static_deflection_under_a_step() {
        // A 10 m steel box 0.2 × 0.5 m: EI = 210e9 · 0.2 · 0.5³/12.
        let mut beam = BeamSpec::rectangular(10.0, 0.2, 0.5);
        let force = 1.0e4;
        beam.motion = Some(BeamMotion {
            loads: vec![TimeLoad::Ramp {
                at: 5.0,
                force,
                start: 0.0,
                rise: 0.0,
            }],
            damping: 0.6,
            ..BeamMotion::default()
        });
        beam.sensors = vec![gauge(SensorQuantity::Displacement, None)];
        let series = record_sensors(&beam, 3.0, &mut || 0.0).unwrap();
        let ei = 210e9 * 0.2 * 0.5f64.powi(3) / 12.0;
        let exact = force * 1000.0 / (48.0 * ei);
        let last = *series[0].values.last().unwrap();
        assert!((last / exact - 1.0).abs() < 1e-9, "{last} vs {exact}");
    }
}
