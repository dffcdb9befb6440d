//! The frames of a sequence: what each beam or frame in motion does over the sequence, the
//! scene of each frame, how each fixed camera's mount shakes and where each flying camera is.
//!
//! Owns: turning a sample's scene and the dataset's `SequenceSpec` into one scene per frame and
//! per sub-instant of a frame's motion blur (each beam's static loads plus the forces acting
//! then, and the dynamic part of its deflection as mode amplitudes, which the build stage adds
//! to the static solution; each frame's model with the forces acting then on its lane, and its
//! nodes' displacements from its modal response); the average of a blurred frame's renders; the
//! offset of every camera's mount and the pose of every camera on a flight path at an instant.
//! Must not touch: meshing, rendering or files (the sample pipeline builds and writes each
//! frame as it builds a still).

use super::view::ViewCamera;
use crate::augment::srgb;
use crate::cameras::{Camera, ViewDraw};
use crate::mechanics::Target;
use crate::mechanics::dynamics::{ModalBeam, Response, STEPS_PER_PERIOD};
use crate::mechanics::frame::Lane;
use crate::render::{SecondaryRays, Shaded};
use crate::scene::{
    BeamSpec, CameraPath, DatasetSpec, FrameSpec, SceneSpec, SequenceSpec, SourceSite, Structure,
};
use crate::seeds::{Scope, Stream};
use glam::{DMat3, DVec3};
use serde::Serialize;

/// Name of the random stream each view's mount shake is drawn from.
const MOUNT_STREAM: &str = "mount";

/// A beam in motion over the sequence: its modal model and response at every frame.
struct MovingBeam {
    modal: ModalBeam,
    response: Response,
}

/// A frame in motion over the sequence: its lane and, unless quasi-static, every node's
/// displacement at every frame.
struct MovingFrame {
    lane: Lane,
    displaced: Option<Vec<Vec<[f64; 6]>>>,
}

/// What one structure does over the sequence.
enum Moving {
    Beam(MovingBeam),
    Frame(MovingFrame),
}

/// What the structures of one sample do over its sequence, ready to give each frame's scene
/// and, with motion blur, the scenes of the sub-instants its exposure averages.
pub struct SampleMotion {
    /// The instants the response is known at, ascending and distinct (the integration steps
    /// forward through them).
    times: Vec<f64>,
    /// Index in `times` of each instant asked for: frame k's at `k × stride`, then its
    /// exposure's sub-instants (held at t = 0 before the start: the structures are at rest
    /// until then).
    instants: Vec<usize>,
    /// Instants per frame: 1 + its motion blur's sub-instants.
    stride: usize,
    /// Per structure, in scene order: the response of a structure in motion, None for the
    /// others.
    structures: Vec<Option<Moving>>,
}

/// Why a sample's motion cannot be computed, and the recipe call to point at.
pub struct MotionError {
    /// What is wrong, with the parameter and its value.
    pub message: String,
    /// Where the beam was declared, when known.
    pub site: Option<SourceSite>,
}

impl SampleMotion {
    /// Integrates every beam in motion of `scene` over `sequence` (from rest at t = 0).
    pub fn new(scene: &SceneSpec, sequence: &SequenceSpec) -> Result<Self, MotionError> {
        let stride = 1 + sequence.motion_blur as usize;
        let asked: Vec<f64> = (0..sequence.frames())
            .flat_map(|k| {
                let during = sequence
                    .exposure_instants(k)
                    .into_iter()
                    .map(|t| t.max(0.0));
                std::iter::once(sequence.time(k)).chain(during)
            })
            .collect();
        let (times, instants) = ascending(&asked);
        let located = |i: usize, site: &Option<SourceSite>| {
            let site = site.clone();
            move |message| MotionError {
                message: format!("structure {i}: {message}"),
                site,
            }
        };
        let structures = scene
            .structures
            .iter()
            .enumerate()
            .map(|(i, structure)| match structure {
                Structure::Beam(b) if b.motion.is_some() => moving_beam(b, &times)
                    .map(|m| Some(Moving::Beam(m)))
                    .map_err(located(i, &b.declared_at)),
                Structure::Frame(f) if f.motion.is_some() => moving_frame(f, &times)
                    .map(|m| Some(Moving::Frame(m)))
                    .map_err(located(i, &f.declared_at)),
                _ => Ok(None),
            })
            .collect::<Result<_, _>>()?;
        Ok(SampleMotion {
            times,
            instants,
            stride,
            structures,
        })
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.instants.len() / self.stride
    }

    /// The scene of frame `k`: every beam in motion carries its static loads plus the forces
    /// acting at the frame's instant, and the dynamic part of its deflection (unless it is
    /// quasi-static); everything else as in `scene`.
    pub fn scene_at(&self, scene: &SceneSpec, k: usize) -> SceneSpec {
        self.scene_at_instant(scene, k * self.stride)
    }

    /// The scenes at the sub-instants frame `k`'s motion blur averages, in time order (none
    /// without motion blur).
    pub fn scenes_during(&self, scene: &SceneSpec, k: usize) -> Vec<SceneSpec> {
        let first = k * self.stride + 1;
        (first..first + self.stride - 1)
            .map(|i| self.scene_at_instant(scene, i))
            .collect()
    }

    /// The scene at instant `instant` (an index into `instants`).
    fn scene_at_instant(&self, scene: &SceneSpec, instant: usize) -> SceneSpec {
        let mut frame = scene.clone();
        let i = self.instants[instant];
        let t = self.times[i];
        for (structure, moving) in frame.structures.iter_mut().zip(&self.structures) {
            match (structure, moving) {
                (Structure::Beam(b), Some(Moving::Beam(m))) => {
                    b.frame_modes = frame_modes(b, m, i);
                    let loads = b.motion.as_ref().map(|motion| &motion.loads[..]);
                    b.loads
                        .extend(m.modal.static_loads(loads.unwrap_or(&[]), t));
                }
                (Structure::Frame(f), Some(Moving::Frame(m))) => {
                    let loads = f
                        .motion
                        .as_ref()
                        .map_or(&[][..], |motion| &motion.loads[..]);
                    f.model = m.lane.loaded(&f.model, loads, t);
                    f.displaced = m.displaced.as_ref().map(|d| d[i].clone());
                }
                _ => {}
            }
        }
        frame
    }
}

/// `asked` sorted ascending without repeats, and where each of its values went: the times an
/// integration from rest steps through (for frames alone, already ascending: unchanged).
fn ascending(asked: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let mut times = asked.to_vec();
    times.sort_by(f64::total_cmp);
    times.dedup();
    let index = asked
        .iter()
        .map(|t| times.partition_point(|u| u < t))
        .collect();
    (times, index)
}

/// The dynamic mode amplitudes of `beam` at instant `i` of its response.
fn frame_modes(beam: &BeamSpec, moving: &MovingBeam, i: usize) -> Vec<(u32, f64)> {
    match &beam.motion {
        Some(motion) if !motion.quasi_static => {
            moving.response.dynamic_amplitudes(&moving.modal, i)
        }
        _ => Vec::new(),
    }
}

/// The modal model of a beam in motion and its response at `times`. Its static loads act
/// throughout, already in equilibrium at t = 0, so only the time loads are integrated; they add
/// to the static loads linearly, which needs physical loads.
fn moving_beam(beam: &BeamSpec, times: &[f64]) -> Result<MovingBeam, String> {
    let motion = beam.motion.as_ref().expect("a beam in motion");
    if beam.target != Target::Physical {
        return Err(
            "a beam with time loads takes physical static loads (point_force, distributed_load), not a target deflection: the time loads add to them in newtons"
                .into(),
        );
    }
    if !beam.vibration.is_empty() || !beam.damage_asked.is_empty() {
        return Err(
            "a beam with time loads cannot also take a vibration snapshot or damage: its frames are the response to its loads"
                .into(),
        );
    }
    // The sensors' model of the beam, so their series and the frames agree.
    let modal = crate::scene::modal_beam(beam, motion)?;
    for load in &motion.loads {
        load.check(beam.length)?;
    }
    let response = modal.respond(&motion.loads, 0.0, times, STEPS_PER_PERIOD);
    Ok(MovingBeam { modal, response })
}

/// The lane of a frame in motion and, unless it is quasi-static, its response at `times`
/// (from rest under its static loads at t = 0, by its own modes; `FrameModel::dynamics`).
fn moving_frame(frame: &FrameSpec, times: &[f64]) -> Result<MovingFrame, String> {
    let motion = frame.motion.as_ref().expect("a frame in motion");
    let lane = Lane::new(&frame.model, &frame.lane)?;
    if motion.quasi_static {
        return Ok(MovingFrame {
            lane,
            displaced: None,
        });
    }
    let dynamics = frame
        .model
        .dynamics(&frame.lane, motion.modes as usize, motion.damping)?;
    let states = dynamics.respond(&motion.loads, 0.0, times, STEPS_PER_PERIOD)?;
    let displaced = states
        .iter()
        .map(|state| {
            let nodes = &state.solution.nodes;
            nodes
                .iter()
                .map(|n| {
                    let [ux, uy, uz] = n.displacement;
                    let [rx, ry, rz] = n.rotation;
                    [ux, uy, uz, rx, ry, rz]
                })
                .collect()
        })
        .collect();
    Ok(MovingFrame {
        lane,
        displaced: Some(displaced),
    })
}

/// The light on the film over an exposure: the average of `films` (the renders at its
/// sub-instants, in time order) in linear light, each 8-bit sRGB code decoded, the mean encoded
/// to the nearest code; renders that agree average to themselves exactly. The record's ray
/// counts are the middle render's, its secondary rays those of any.
pub fn averaged_in_linear_light(films: Vec<Shaded>) -> Shaded {
    let n = films.len();
    assert!(n > 0, "an exposure averages at least one render");
    let mut sum = vec![0f32; films[0].rgb.len()];
    for film in &films {
        for (s, &code) in sum.iter_mut().zip(&film.rgb) {
            *s += srgb::decode(code);
        }
    }
    let mut secondary: Vec<SecondaryRays> = films
        .iter()
        .flat_map(|f| f.secondary.iter().copied())
        .collect();
    secondary.sort();
    secondary.dedup();
    Shaded {
        rgb: sum.iter().map(|&s| srgb::encode(s / n as f32)).collect(),
        edge_rays: films[n / 2].edge_rays,
        secondary,
    }
}

/// How a view's camera mount is displaced at one frame, in the camera's own axes (OpenCV).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, schemars::JsonSchema)]
pub struct MountOffset {
    /// Small rotation about the camera's x, y and z axes, radians (applied x, then y, then z).
    pub rotation: [f64; 3],
    /// Translation along the camera's x, y and z axes, metres.
    pub translation: [f64; 3],
}

/// The mount offset of view `view` of sample `sample` at `time`: six independent band-limited
/// noises (`MountShake`), drawn from the view's own stream, read at `time`. None when the
/// sequence's mounts are still.
pub fn mount_offset(
    dataset: &DatasetSpec,
    sample: u64,
    view: u32,
    time: f64,
) -> Option<MountOffset> {
    let sequence = dataset.sequence.as_ref()?;
    let shake = sequence.mount.as_ref()?;
    let mut stream = Stream::new(dataset.seed, Scope::View(sample, view), MOUNT_STREAM);
    let mut axis = |rms: f64| {
        let (step, values) = stream.band_limited_noise(rms, shake.band, sequence.duration);
        linear_at(&values, time / step)
    };
    let rotation = [(); 3].map(|()| axis(shake.rotation));
    let translation = [(); 3].map(|()| axis(shake.translation));
    Some(MountOffset {
        rotation,
        translation,
    })
}

/// The piecewise-linear signal through `values` (one per unit of `s`) at `s`, held at the ends.
fn linear_at(values: &[f64], s: f64) -> f64 {
    let last = values.len() - 1;
    let k = (s.floor().max(0.0) as usize).min(last.saturating_sub(1));
    let w = (s - k as f64).clamp(0.0, 1.0);
    values[k] * (1.0 - w) + values[(k + 1).min(last)] * w
}

/// The view's camera `drawn` at `time` of its flight `path`: the rig's lens at the path's
/// position then, looking at its target then with world z up (recorded as the view's aim).
pub fn flown(drawn: ViewCamera, path: &CameraPath, time: f64) -> ViewCamera {
    let position = DVec3::from_array(path.position_at(time));
    let aim = path.target_at(time);
    ViewCamera {
        camera: Camera::look_at(
            drawn.camera.intrinsics,
            position,
            DVec3::from_array(aim),
            DVec3::Z,
        ),
        draw: ViewDraw { aim, ..drawn.draw },
        ..drawn
    }
}

/// `camera` moved by `offset`, in its own axes: the mount turns the camera about its centre of
/// projection and shifts it.
pub fn shaken(camera: Camera, offset: &MountOffset) -> Camera {
    let [rx, ry, rz] = offset.rotation;
    let turn = DMat3::from_rotation_z(rz) * DMat3::from_rotation_y(ry) * DMat3::from_rotation_x(rx);
    Camera {
        rotation: camera.rotation * turn,
        position: camera.position + camera.rotation * DVec3::from_array(offset.translation),
        ..camera
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_average_in_linear_light_and_agreeing_ones_to_themselves() {
        let film = |rgb: Vec<u8>| Shaded {
            rgb,
            edge_rays: None,
            secondary: Vec::new(),
        };
        // Every code averaged with itself, any number of times, is itself.
        let all: Vec<u8> = (0..=255).collect();
        for n in [1, 3, 7] {
            let same = (0..n).map(|_| film(all.clone())).collect();
            assert_eq!(averaged_in_linear_light(same).rgb, all);
        }
        // Black and white half the exposure each: half the light, code 188 (sRGB of 0.5), not
        // the code midway (128, which is 22 % of the light).
        let half = averaged_in_linear_light(vec![film(vec![0]), film(vec![255])]);
        assert_eq!(half.rgb, [188]);
        assert!((srgb::to_encoded(0.5) * 255.0 - 188.0).abs() < 0.5);
    }

    #[test]
    fn instants_are_integrated_in_order_and_found_again() {
        let asked = [0.0, 0.0, 0.004, 0.02, 0.016, 0.024];
        let (times, index) = ascending(&asked);
        assert_eq!(times, [0.0, 0.004, 0.016, 0.02, 0.024]);
        for (t, i) in asked.iter().zip(index) {
            assert_eq!(times[i], *t);
        }
    }

    #[test]
    fn linear_reading_interpolates_and_holds_the_ends() {
        let v = [0.0, 2.0, 4.0, 1.0];
        assert_eq!(linear_at(&v, 0.5), 1.0);
        assert_eq!(linear_at(&v, 2.25), 3.25);
        assert_eq!(linear_at(&v, 3.0), 1.0);
        assert_eq!(linear_at(&v, 7.0), 1.0);
        assert_eq!(linear_at(&v, -1.0), 0.0);
    }

    #[test]
    fn a_shaken_camera_turns_about_its_own_axes_and_moves_along_them() {
        let camera = Camera::look_at(
            crate::cameras::Intrinsics::from_fov_y(64, 64, 1.0),
            DVec3::new(0.0, -5.0, 0.0),
            DVec3::ZERO,
            DVec3::Z,
        );
        // Along its own z (forward, world +y here) by 0.1 m.
        let moved = shaken(
            camera,
            &MountOffset {
                translation: [0.0, 0.0, 0.1],
                ..MountOffset::default()
            },
        );
        assert!((moved.position - DVec3::new(0.0, -4.9, 0.0)).length() < 1e-12);
        // A turn about its y axis (down, world −z) swings the view direction sideways.
        let turned = shaken(
            camera,
            &MountOffset {
                rotation: [0.0, 0.01, 0.0],
                ..MountOffset::default()
            },
        );
        let forward = turned.rotation.col(2);
        assert!((forward.x.abs() - 0.01f64.sin()).abs() < 1e-12, "{forward}");
        assert!((turned.rotation.determinant() - 1.0).abs() < 1e-12);
    }
}
