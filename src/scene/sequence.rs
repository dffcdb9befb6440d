//! Time in a scene description: the sequence of frames a dataset films (duration, frame rate,
//! exposure, how the camera mounts shake) and the force histories a beam carries over it.
//!
//! Owns: plain, validated data about time — where a sample's sequence and its beams' time loads
//! live, for everything downstream (frames, virtual sensors). Must not touch: Rhai, integration
//! of the motion (`mechanics::dynamics`), random streams or files. Random excitation arrives
//! here already drawn (as `TimeLoad::Sampled` values) from the sample's seeded stream.
//!
//! Where to find it: `DatasetSpec::sequence` (every sample of a dataset films the same frames)
//! and `BeamSpec::motion` (the time loads, damping and modes of each beam that moves).

use crate::mechanics::dynamics::TimeLoad;
use serde::Serialize;

/// Default exposure time as a fraction of the frame interval when a recipe gives none: a
/// shutter open half the frame time (the "180° shutter" of film cameras).
pub const DEFAULT_EXPOSURE_FRACTION: f64 = 0.5;

/// Most frames one sample may film: a recipe asking for more is refused (4 s at 60 fps is 240).
pub const MAX_FRAMES: u32 = 100_000;

/// The frames every sample of a dataset films: frame k is the scene at t = k / fps, k from 0 to
/// `frames() − 1`.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SequenceSpec {
    /// Length of the sequence, seconds (positive).
    pub duration: f64,
    /// Frame rate, frames per second (positive).
    pub fps: f64,
    /// How long the shutter is open, seconds (0 < exposure ≤ 1 / fps). Without motion blur
    /// the images are rendered at the frame's instant; labels are always at that instant, the
    /// middle of the exposure.
    pub exposure: f64,
    /// Motion blur: the RGB image of a frame is the average, in linear light before the
    /// sensor's effects, of this many renders at the sub-instants `exposure_instants` across
    /// the exposure; 0 (the default) renders the frame's instant alone.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub motion_blur: u32,
    /// How the camera mounts shake, if they do (absent: perfectly still tripods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mount: Option<MountShake>,
    /// Views that fly along a path instead of standing where the rig drew them (drones).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub paths: Vec<CameraPath>,
    /// The `point_tracks` output's query grid: the structure pixels of the first frame whose
    /// rows and columns are stride/2 + n·stride (default 16).
    #[serde(
        default = "default_track_stride",
        skip_serializing_if = "is_default_track_stride"
    )]
    pub track_stride: u32,
}

/// A view's camera flying over the sequence: its centre of projection moves through the
/// waypoints, straight between them at constant speed (held before the first and after the
/// last), looking with world z up at the point its waypoints aim at, which moves between them
/// likewise (a drone sweeping its gaze along a girder); its lens is the rig's.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct CameraPath {
    /// The view (camera index in the rig) that flies.
    pub view: u32,
    /// Where the camera is and what it looks at when, in increasing time.
    pub waypoints: Vec<Waypoint>,
}

/// A point of a camera's path: where its centre of projection is at `time`, and the point it
/// looks at then.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Waypoint {
    /// Seconds from the start of the sequence.
    pub time: f64,
    /// World metres.
    pub position: [f64; 3],
    /// The point looked at, world metres.
    pub target: [f64; 3],
}

impl CameraPath {
    /// Where the camera is at `time`: linear between the waypoints around it, held outside.
    pub fn position_at(&self, time: f64) -> [f64; 3] {
        self.along(time, |w| w.position)
    }

    /// The point the camera looks at at `time`: linear between the waypoints around it, held
    /// outside.
    pub fn target_at(&self, time: f64) -> [f64; 3] {
        self.along(time, |w| w.target)
    }

    /// The point `of` each waypoint, at `time` between the waypoints around it.
    fn along(&self, time: f64, of: impl Fn(&Waypoint) -> [f64; 3]) -> [f64; 3] {
        let w = &self.waypoints;
        let after = w.partition_point(|p| p.time <= time);
        if after == 0 {
            return of(&w[0]);
        }
        if after == w.len() {
            return of(&w[w.len() - 1]);
        }
        let (a, b) = (of(&w[after - 1]), of(&w[after]));
        let s = (time - w[after - 1].time) / (w[after].time - w[after - 1].time);
        std::array::from_fn(|i| a[i] + s * (b[i] - a[i]))
    }

    /// The problem with the path of entry `i` of `sequence.paths`, naming the value; None when
    /// it is fine. `views` is the number of views of the rig.
    pub fn problem(&self, i: usize, views: u32) -> Option<String> {
        let at = format!("sequence.paths[{i}]");
        if self.view >= views {
            return Some(format!(
                "{at}.view = {} but the dataset has {views} views (0 to {})",
                self.view,
                views - 1
            ));
        }
        if self.waypoints.is_empty() {
            return Some(format!(
                "{at}.waypoints is empty: give at least one [time, [x, y, z]]"
            ));
        }
        let finite = |p: &[f64; 3]| p.iter().all(|c| c.is_finite());
        let mut last = f64::NEG_INFINITY;
        for (j, w) in self.waypoints.iter().enumerate() {
            if !(w.time.is_finite() && w.time > last) {
                return Some(format!(
                    "{at}.waypoints[{j}]: time {} s must be finite and after the waypoint before ({last} s)",
                    w.time
                ));
            }
            if !finite(&w.position) {
                return Some(format!(
                    "{at}.waypoints[{j}]: position {:?} must be a finite point",
                    w.position
                ));
            }
            if !finite(&w.target) {
                return Some(format!(
                    "{at}.waypoints[{j}]: target {:?} must be a finite point",
                    w.target
                ));
            }
            last = w.time;
        }
        self.passes_through_target(&at)
    }

    /// Refuses a path whose camera reaches the point it looks at: it would look nowhere there.
    /// Between two waypoints the gaze (target − position) moves linearly too, so it vanishes
    /// on a leg only where the segment between its two ends passes through zero.
    fn passes_through_target(&self, at: &str) -> Option<String> {
        let gaze =
            |w: &Waypoint| glam::DVec3::from_array(w.target) - glam::DVec3::from_array(w.position);
        let first = &self.waypoints[0];
        let legs = self.waypoints.windows(2).map(|w| (w[0], w[1]));
        std::iter::once((*first, *first)).chain(legs).find_map(|(a, b)| {
            let (ga, gb) = (gaze(&a), gaze(&b));
            let along = (gb - ga).length_squared();
            let s = if along > 0.0 {
                (-ga.dot(gb - ga) / along).clamp(0.0, 1.0)
            } else {
                0.0
            };
            ((ga + s * (gb - ga)).length() < 1e-6).then(|| {
                let time = a.time + s * (b.time - a.time);
                format!(
                    "{at}: the camera passes through its target {:?} (at {:?}, t = {time} s) and would look nowhere there",
                    self.target_at(time),
                    self.position_at(time)
                )
            })
        })
    }
}

impl SequenceSpec {
    /// Number of frames: every k with k / fps < duration (at least one).
    pub fn frames(&self) -> u32 {
        let n = (self.duration * self.fps - 1e-9).ceil().max(1.0);
        n.min(f64::from(MAX_FRAMES)) as u32
    }

    /// The instant of frame `k`, seconds.
    pub fn time(&self, k: u32) -> f64 {
        f64::from(k) / self.fps
    }

    /// The instants of every frame, in order.
    pub fn times(&self) -> Vec<f64> {
        (0..self.frames()).map(|k| self.time(k)).collect()
    }

    /// The sub-instants frame `k`'s motion blur averages: the midpoints of `motion_blur` equal
    /// parts of the exposure [t − exposure/2, t + exposure/2] (empty without motion blur).
    pub fn exposure_instants(&self, k: u32) -> Vec<f64> {
        let n = f64::from(self.motion_blur);
        let t = self.time(k);
        (0..self.motion_blur)
            .map(|j| t + self.exposure * ((f64::from(j) + 0.5) / n - 0.5))
            .collect()
    }

    /// The problem with the values, naming the parameter and its value; None when they are fine.
    pub fn problem(&self) -> Option<String> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.duration) {
            return Some(format!(
                "sequence.duration = {} s must be a positive number of seconds",
                self.duration
            ));
        }
        if !positive(self.fps) {
            return Some(format!(
                "sequence.fps = {} must be a positive frame rate",
                self.fps
            ));
        }
        let frames = self.duration * self.fps;
        if frames > f64::from(MAX_FRAMES) {
            return Some(format!(
                "sequence.duration × fps = {frames} frames, more than the {MAX_FRAMES} a sample may film"
            ));
        }
        if !(positive(self.exposure) && self.exposure <= 1.0 / self.fps) {
            return Some(format!(
                "sequence.exposure = {} s must be positive and at most the frame interval 1/fps = {} s",
                self.exposure,
                1.0 / self.fps
            ));
        }
        if self.motion_blur > MAX_MOTION_BLUR {
            return Some(format!(
                "sequence.motion_blur = {} sub-instants, more than the {MAX_MOTION_BLUR} a frame may average",
                self.motion_blur
            ));
        }
        self.mount.as_ref().and_then(MountShake::problem)
    }
}

fn is_zero(n: &u32) -> bool {
    *n == 0
}

/// The default stride of the point tracks' query grid, pixels: 3,600 queries on a 960² image.
pub const DEFAULT_TRACK_STRIDE: u32 = 16;

/// The largest stride of the point tracks' query grid, pixels.
pub const MAX_TRACK_STRIDE: u32 = 4096;

fn default_track_stride() -> u32 {
    DEFAULT_TRACK_STRIDE
}

fn is_default_track_stride(n: &u32) -> bool {
    *n == DEFAULT_TRACK_STRIDE
}

/// Most sub-instants a frame's motion blur may average.
pub const MAX_MOTION_BLUR: u32 = 64;

/// Small random motions of each camera's mount about its drawn pose, frame by frame: band-limited
/// white noise of the given RMS in each rotation and translation axis, drawn per sample and view
/// from their seeded stream and recorded in each frame's camera.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct MountShake {
    /// RMS rotation about each camera axis, radians.
    pub rotation: f64,
    /// RMS translation along each camera axis, metres.
    pub translation: f64,
    /// Highest frequency of the shake, Hz (the noise is white below it).
    pub band: f64,
}

impl MountShake {
    fn problem(&self) -> Option<String> {
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        if !non_negative(self.rotation) {
            return Some(format!(
                "sequence.mount.rotation = {} rad must be a finite RMS ≥ 0",
                self.rotation
            ));
        }
        if !non_negative(self.translation) {
            return Some(format!(
                "sequence.mount.translation = {} m must be a finite RMS ≥ 0",
                self.translation
            ));
        }
        if !(self.band.is_finite() && self.band > 0.0) {
            return Some(format!(
                "sequence.mount.band = {} Hz must be a positive frequency",
                self.band
            ));
        }
        None
    }
}

/// Default modal damping ratio of a beam in motion: 2 %, typical of steel and composite girders.
pub const DEFAULT_DAMPING: f64 = 0.02;

/// Default number of modes kept in a beam's response.
pub const DEFAULT_MODES: u32 = 10;

/// Default density of a beam's material, kg/m³ (structural steel).
pub const STEEL_DENSITY: f64 = 7850.0;

/// How a beam responds over a sequence: the forces acting on it in time (on top of its static
/// loads, which act throughout) and its modal model.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct BeamMotion {
    /// The force histories, in the order the recipe added them.
    pub loads: Vec<TimeLoad>,
    /// Modal damping ratio ζ of every mode, 0 ≤ ζ < 1.
    pub damping: f64,
    /// Number of modes kept, ≥ 1.
    pub modes: u32,
    /// Density of the material, kg/m³; the mass per length is density × section area.
    pub density: f64,
    /// The frames show the static response to the forces acting at their instant (no inertia)
    /// instead of the dynamic response.
    pub quasi_static: bool,
}

impl Default for BeamMotion {
    fn default() -> Self {
        BeamMotion {
            loads: Vec::new(),
            damping: DEFAULT_DAMPING,
            modes: DEFAULT_MODES,
            density: STEEL_DENSITY,
            quasi_static: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sequence(duration: f64, fps: f64) -> SequenceSpec {
        SequenceSpec {
            duration,
            fps,
            exposure: 0.5 / fps,
            motion_blur: 0,
            mount: None,
            paths: Vec::new(),
            track_stride: DEFAULT_TRACK_STRIDE,
        }
    }

    fn flight(waypoints: &[(f64, [f64; 3])]) -> CameraPath {
        CameraPath {
            view: 0,
            waypoints: waypoints
                .iter()
                .map(|&(time, position)| Waypoint {
                    time,
                    position,
                    target: [0.0, 0.0, 0.0],
                })
                .collect(),
        }
    }

    #[test]
    fn a_camera_flies_straight_between_waypoints_and_holds_outside_them() {
        let path = flight(&[(1.0, [0.0, -4.0, 1.0]), (3.0, [4.0, -4.0, 3.0])]);
        assert_eq!(path.position_at(0.0), [0.0, -4.0, 1.0]);
        assert_eq!(path.position_at(2.0), [2.0, -4.0, 2.0]);
        assert_eq!(path.position_at(2.5), [3.0, -4.0, 2.5]);
        assert_eq!(path.position_at(9.0), [4.0, -4.0, 3.0]);
        assert_eq!(path.problem(0, 1), None);
    }

    #[test]
    fn bad_paths_are_named_with_their_value() {
        let why = |p: CameraPath, views| p.problem(2, views).unwrap();
        let ok = flight(&[(0.0, [0.0, -4.0, 1.0]), (1.0, [1.0, -4.0, 1.0])]);
        assert!(why(ok.clone(), 0).contains("sequence.paths[2].view = 0 but the dataset has 0"));
        let back = flight(&[(1.0, [0.0, -4.0, 1.0]), (0.5, [1.0, -4.0, 1.0])]);
        assert!(why(back, 1).contains("waypoints[1]: time 0.5 s must be finite and after"));
        let through = flight(&[(0.0, [-1.0, 0.0, 0.0]), (1.0, [1.0, 0.0, 0.0])]);
        assert!(why(through, 1).contains("passes through its target [0.0, 0.0, 0.0]"));
        let nan = flight(&[(0.0, [f64::NAN, 0.0, 1.0])]);
        assert!(why(nan, 1).contains("position [NaN, 0.0, 1.0]"));
        let mut aimless = ok.clone();
        aimless.waypoints[1].target = [0.0, f64::INFINITY, 0.0];
        assert!(why(aimless, 1).contains("waypoints[1]: target [0.0, inf, 0.0]"));
        // A gaze sweeping along with the camera: the two meet halfway, at t = 0.5 s.
        let mut chased = ok;
        chased.waypoints[0].target = [2.0, -4.0, 1.0];
        chased.waypoints[1].target = [-1.0, -4.0, 1.0];
        assert!(why(chased, 1).contains(
            "passes through its target [0.5, -4.0, 1.0] (at [0.5, -4.0, 1.0], t = 0.5 s)"
        ));
    }

    #[test]
    fn a_camera_gaze_sweeps_between_the_targets_of_its_waypoints() {
        let mut path = flight(&[(1.0, [0.0, -4.0, 1.0]), (3.0, [4.0, -4.0, 3.0])]);
        path.waypoints[0].target = [0.0, 0.0, 0.0];
        path.waypoints[1].target = [8.0, 0.0, 2.0];
        assert_eq!(path.target_at(0.0), [0.0, 0.0, 0.0]);
        assert_eq!(path.target_at(2.0), [4.0, 0.0, 1.0]);
        assert_eq!(path.target_at(9.0), [8.0, 0.0, 2.0]);
        assert_eq!(path.problem(0, 1), None);
    }

    #[test]
    fn blur_sub_instants_are_the_midpoints_of_equal_parts_of_the_exposure() {
        let mut s = sequence(1.0, 50.0);
        assert!(s.exposure_instants(3).is_empty());
        s.motion_blur = 4;
        // t = 0.06 s, exposure 0.01 s: parts of 2.5 ms from 0.055 s, midpoints 1.25 ms in.
        let instants = s.exposure_instants(3);
        let expected = [0.05625, 0.05875, 0.06125, 0.06375];
        for (got, want) in instants.iter().zip(expected) {
            assert!((got - want).abs() < 1e-15, "{instants:?}");
        }
        s.motion_blur = 65;
        assert!(s.problem().unwrap().contains("motion_blur = 65"));
    }

    #[test]
    fn frames_are_the_instants_before_the_end() {
        // 4 s at 60 fps: t = 0, 1/60, …, 239/60 — 240 frames, none at t = 4 itself.
        let s = sequence(4.0, 60.0);
        assert_eq!(s.frames(), 240);
        assert_eq!(s.time(239), 239.0 / 60.0);
        // A duration that is not a whole number of frames keeps the last partial interval.
        assert_eq!(sequence(0.05, 60.0).frames(), 3);
        assert_eq!(sequence(1e-6, 60.0).frames(), 1);
    }

    #[test]
    fn bad_values_are_named_with_their_value() {
        let mut s = sequence(4.0, 60.0);
        assert_eq!(s.problem(), None);
        s.exposure = 0.1;
        let why = s.problem().unwrap();
        assert!(why.contains("exposure = 0.1"), "{why}");
        let why = sequence(-1.0, 60.0).problem().unwrap();
        assert!(why.contains("duration = -1"), "{why}");
        let why = sequence(1.0, f64::NAN).problem().unwrap();
        assert!(why.contains("fps = NaN"), "{why}");
        let why = sequence(1e4, 1e3).problem().unwrap();
        assert!(why.contains("10000000 frames"), "{why}");
    }
}
