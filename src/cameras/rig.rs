//! Camera rigs: where the cameras of a dataset stand and what lenses they have, as declared,
//! and the draw of one view. Poses come from a sphere (or a band of it) around the structure,
//! fixed inspection cameras, an orbit or a flight line; each may aim with jitter, draw its
//! field of view, principal point and lens distortion from ranges, and be the left eye of a
//! stereo pair.

use super::{Camera, Distortion, Intrinsics, LensFault};
use crate::seeds::Stream;
use glam::{DMat3, DVec3};
use serde::Serialize;

/// How far the camera is from the target.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Distance {
    /// A distance in metres drawn uniformly from [min, max] (fixed when min = max).
    Range {
        /// Nearest distance, metres (positive).
        min: f64,
        /// Farthest distance, metres.
        max: f64,
    },
    /// The distance at which the structure's bounding sphere just fits the narrower field of
    /// view, times `margin` (≥ 1 keeps the whole structure in frame from every direction).
    Frame {
        /// Factor on the distance at which the bounding sphere just fits (default 1.05).
        margin: f64,
    },
}

/// Where the cameras of a sample stand.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Poses {
    /// Drawn on a sphere (or a band of it) around the target: yaw (azimuth from +x towards
    /// +y), pitch (elevation above the target's horizontal plane; +π/2 looks straight down)
    /// and roll about the view axis, each uniform in its range; pitch uniform in area.
    Sphere {
        /// Range [min, max] of the yaw, radians.
        yaw: [f64; 2],
        /// Range [min, max] of the pitch, radians within [−π/2, π/2]; sin(pitch) is drawn
        /// uniformly.
        pitch: [f64; 2],
        /// Range [min, max] of the roll about the view axis, radians (0 keeps the horizon
        /// level).
        roll: [f64; 2],
        /// How far the camera is from the target.
        distance: Distance,
    },
    /// Inspection cameras at fixed places: view i is camera i (one view per camera).
    Fixed {
        /// The cameras, in view order.
        cameras: Vec<FixedCamera>,
    },
    /// A circle around the target at one elevation, the views in order along it.
    Orbit {
        /// How far the cameras are from the target.
        distance: Distance,
        /// Elevation of the circle above the target's horizontal plane, radians.
        pitch: f64,
        /// Azimuth of the first view, radians from +x towards +y.
        yaw_start: f64,
        /// Azimuth swept from the first view to the last, radians (2π: a full circle, the last
        /// view one step short of the first).
        sweep: f64,
        /// Roll about the view axis, radians.
        roll: f64,
    },
    /// A straight flight line past the structure, the views evenly spaced from `from` to
    /// `to`, each looking at the target.
    Line {
        /// First camera position, world metres.
        from: [f64; 3],
        /// Last camera position, world metres.
        to: [f64; 3],
        /// The point the cameras look at, world metres (null: the structure's centre).
        target: Option<[f64; 3]>,
        /// Roll about the view axis, radians.
        roll: f64,
    },
}

/// A camera at a fixed place.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FixedCamera {
    /// Centre of projection, world metres.
    pub position: [f64; 3],
    /// The point it looks at, world metres (null: the structure's centre).
    pub target: Option<[f64; 3]>,
    /// Roll about the view axis, radians (0 keeps the horizon level).
    pub roll: f64,
}

/// Ranges of the Brown–Conrady coefficients, drawn per view (fixed when min = max).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, schemars::JsonSchema)]
pub struct DistortionRanges {
    /// Range [min, max] of k1.
    pub k1: [f64; 2],
    /// Range [min, max] of k2.
    pub k2: [f64; 2],
    /// Range [min, max] of p1.
    pub p1: [f64; 2],
    /// Range [min, max] of p2.
    pub p2: [f64; 2],
    /// Range [min, max] of k3.
    pub k3: [f64; 2],
}

/// A stereo pair per pose: the drawn camera is the left eye, the right eye stands `baseline`
/// to its right (along its x axis), turned by `toe_in` about its own y axis towards the left
/// eye's axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Stereo {
    /// Distance between the two centres of projection, metres (positive).
    pub baseline: f64,
    /// Convergence of the right eye towards the left eye's axis, radians (0: parallel axes,
    /// a rectified pair).
    pub toe_in: f64,
}

/// The cameras of a dataset: image size, lens and poses.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct CameraRig {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Range [min, max] of the vertical field of view, radians within [1e-8, π); pixels are
    /// square.
    pub fov_y: [f64; 2],
    /// Ranges of the principal point's offset from the image centre, pixels: [x range,
    /// y range].
    pub principal_offset: [[f64; 2]; 2],
    /// Lens distortion, drawn per view (all zero: a pinhole).
    pub distortion: DistortionRanges,
    /// Where the cameras stand.
    pub poses: Poses,
    /// Radius of the ball around the target the camera actually aims at, metres (0: exactly
    /// at the target).
    pub aim_jitter: f64,
    /// A stereo pair per pose (null: one camera).
    pub stereo: Option<Stereo>,
    /// A thin lens's depth of field blurring RGB by each pixel's depth (none: a pinhole,
    /// everything sharp).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_of_field: Option<super::DepthOfField>,
}

impl Default for CameraRig {
    /// The paper's cameras: 960×960, π/3, on the whole sphere, framing the structure.
    fn default() -> Self {
        CameraRig {
            width: 960,
            height: 960,
            fov_y: [std::f64::consts::FRAC_PI_3; 2],
            principal_offset: [[0.0; 2]; 2],
            distortion: DistortionRanges::default(),
            poses: Poses::Sphere {
                yaw: [0.0, std::f64::consts::TAU],
                pitch: [-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2],
                roll: [0.0, 0.0],
                distance: Distance::Frame { margin: 1.05 },
            },
            aim_jitter: 0.0,
            stereo: None,
            depth_of_field: None,
        }
    }
}

/// The values actually drawn for one view, recorded in its JSON. Yaw, pitch, roll and
/// distance describe the camera about the point it aims at, whatever the rig.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ViewDraw {
    /// Azimuth of the camera about its target, radians from +x towards +y.
    pub yaw: f64,
    /// Elevation of the camera above its target's horizontal plane, radians.
    pub pitch: f64,
    /// Roll about the view axis, radians.
    pub roll: f64,
    /// Distance from the camera to its target, metres.
    pub distance: f64,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Offset of the principal point from the image centre, pixels (x, y).
    pub principal_offset: [f64; 2],
    /// The point the camera aims at, world metres (the target plus any aim jitter).
    pub aim: [f64; 3],
}

/// The narrowest vertical field of view (radians). A camera that frames a structure at field
/// of view φ stands about 2R/φ away; f64 places its rays to about that distance × 1.1e-16,
/// which must stay below a thousandth of a pixel (2R/φ × φ/H) for H up to 16,384 pixels:
/// φ ≥ 1.1e-16 × 16,384 × 1000 ≈ 1.8e-9.
pub const MIN_FOV: f64 = 1e-8;

/// A range's value: its only value when fixed (no draw), else uniform in it.
fn pick(stream: &mut Stream, [lo, hi]: [f64; 2]) -> f64 {
    if lo == hi { lo } else { stream.uniform(lo, hi) }
}

impl CameraRig {
    /// Images per sample when `views` poses are drawn: two per pose for a stereo rig.
    pub fn images(&self, views: u32) -> u64 {
        u64::from(views) * if self.stereo.is_some() { 2 } else { 1 }
    }

    /// Checks what the options alone cannot: fields of view inside [MIN_FOV, π), pitches on
    /// the sphere, positive distances and baselines, a lens that does not fold the image,
    /// poses that exist for every view (`views`) and never stand on their target. Messages
    /// name the recipe's option.
    pub fn validate(&self, views: u32) -> Result<(), String> {
        for fov_y in self.fov_y {
            if !(MIN_FOV..std::f64::consts::PI).contains(&fov_y) {
                return Err(format!(
                    "dataset.camera.fov_y = {} must lie in [{MIN_FOV}, π) radians (below \
                     {MIN_FOV} rad a camera framing the structure stands so far off that f64 \
                     cannot aim its rays to a thousandth of a pixel)",
                    crate::words::number(fov_y)
                ));
            }
        }
        self.validate_lens()?;
        self.validate_poses(views)?;
        if !(self.aim_jitter >= 0.0 && self.aim_jitter.is_finite()) {
            return Err(format!(
                "dataset.camera.aim_jitter = {} must be a distance ≥ 0 (metres)",
                crate::words::number(self.aim_jitter)
            ));
        }
        match self.stereo {
            Some(s) if !(s.baseline > 0.0 && s.baseline.is_finite()) => Err(format!(
                "dataset.camera.stereo.baseline = {} must be positive (metres): two eyes in one place are one camera",
                crate::words::number(s.baseline)
            )),
            Some(s) if !(s.toe_in.abs() < std::f64::consts::FRAC_PI_2) => Err(format!(
                "dataset.camera.stereo.toe_in = {} must lie within (−π/2, π/2) radians",
                crate::words::number(s.toe_in)
            )),
            _ => Ok(()),
        }
    }

    /// Every lens the ranges can draw must map the image one-to-one: the corners of the
    /// ranges (extreme coefficients) are checked at the widest field of view.
    fn validate_lens(&self) -> Result<(), String> {
        let d = &self.distortion;
        let ranges = [d.k1, d.k2, d.p1, d.p2, d.k3];
        if ranges.iter().flatten().any(|c| !c.is_finite()) {
            return Err(format!(
                "dataset.camera.distortion {ranges:?} must be finite"
            ));
        }
        let reach = self.frame_reach(1.0, 0.0);
        let Some((lens, fault)) = self.worst_fault(reach) else {
            return Ok(());
        };
        let what = match fault {
            LensFault::Folds { .. } => "folds the image before its corners",
            LensFault::NoInverse { .. } => "cannot be inverted out to the image's corners",
        };
        Err(format!(
            "dataset.camera.distortion {} {what}: they reach a distorted radius of {reach:.3} (normalised; with a 5 % margin, {:.3}), but the lens model {fault}; use smaller coefficients",
            lens.describe(),
            1.05 * reach
        ))
    }

    /// Checks that every lens the ranges can draw also maps one-to-one the wider frame an
    /// exact geometric augmentation renders (`what`, as the recipe names it): a zoom down to
    /// `zoom` and shifts of up to `shift` (fractions of the width and height) show the lens
    /// beyond the clean frame's corners, and a pixel past the lens's fold has no ray.
    pub fn validate_widened(&self, zoom: f64, shift: [f64; 2], what: &str) -> Result<(), String> {
        let shift = (shift[0] * f64::from(self.width)).hypot(shift[1] * f64::from(self.height));
        let reach = self.frame_reach(zoom, shift);
        match self.worst_fault(reach) {
            None => Ok(()),
            Some((lens, fault)) => Err(format!(
                "{what} widens the frame an exact copy renders to a distorted radius of {reach:.3} (normalised; with a 5 % margin, {:.3}), but the lens dataset.camera.distortion {} {fault}: the outer pixels would have no ray. Zoom out less, shift less, use a milder lens, or mode: \"image\" (which warps the rendered images instead)",
                1.05 * reach,
                lens.describe()
            )),
        }
    }

    /// The farthest a camera of this rig images from its principal point, in normalised
    /// distorted units, when an exact augmentation zooms by `zoom` and shifts by up to `shift`
    /// pixels. The new camera's pixel q sees what the clean camera sees at the warp's source
    /// point p, at the same normalised distance from the principal point c (the warp only
    /// turns it), and |p − c| ≤ (|q − centre| + |shift|)/zoom + |c − centre|: at the widest
    /// field of view (the shortest focal length) that is the half-diagonal plus the shift,
    /// over the zoomed focal length, plus the largest principal-point offset.
    fn frame_reach(&self, zoom: f64, shift: f64) -> f64 {
        let widest = self.lens(self.fov_y[1], [0.0; 2], Distortion::default());
        let half_diagonal = 0.5 * f64::from(self.width).hypot(f64::from(self.height));
        let [x, y] = self.principal_offset.map(|r| r[0].abs().max(r[1].abs()));
        (half_diagonal + shift) / (zoom * widest.fy) + x.hypot(y) / widest.fy
    }

    /// The first lens at a corner of the coefficient ranges that leaves a point within
    /// `reach` without a ray, with why.
    fn worst_fault(&self, reach: f64) -> Option<(Distortion, LensFault)> {
        let d = &self.distortion;
        (0..32u32).find_map(|corner| {
            let at = |range: [f64; 2], bit: u32| range[((corner >> bit) & 1) as usize];
            let lens = Distortion {
                k1: at(d.k1, 0),
                k2: at(d.k2, 1),
                p1: at(d.p1, 2),
                p2: at(d.p2, 3),
                k3: at(d.k3, 4),
            };
            lens.fault_within(reach).map(|fault| (lens, fault))
        })
    }

    fn validate_poses(&self, views: u32) -> Result<(), String> {
        let distance_ok = |d: &Distance| match *d {
            Distance::Range { min, .. } if min <= 0.0 => Err(format!(
                "dataset.camera.distance = {} must be positive (metres) or \"frame\"",
                crate::words::number(min)
            )),
            Distance::Frame { margin } if margin <= 0.0 => Err(format!(
                "dataset.camera.margin = {} must be positive",
                crate::words::number(margin)
            )),
            _ => Ok(()),
        };
        match &self.poses {
            Poses::Sphere {
                pitch, distance, ..
            } => {
                let half_pi = std::f64::consts::FRAC_PI_2;
                if pitch[0] < -half_pi - 1e-12 || pitch[1] > half_pi + 1e-12 {
                    return Err(format!(
                        "dataset.camera.pitch = [{}, {}] must lie within [-π/2, π/2]",
                        crate::words::number(pitch[0]),
                        crate::words::number(pitch[1])
                    ));
                }
                distance_ok(distance)
            }
            Poses::Orbit {
                distance, sweep, ..
            } => {
                distance_ok(distance)?;
                orbit_views_apart(*sweep, views)
            }
            Poses::Fixed { cameras } => {
                if cameras.len() != views as usize {
                    return Err(format!(
                        "dataset.camera.fixed lists {} cameras but dataset.views = {views}: each view is one fixed camera",
                        cameras.len()
                    ));
                }
                for (i, c) in cameras.iter().enumerate() {
                    if c.target.is_some_and(|t| t == c.position) {
                        return Err(format!(
                            "dataset.camera.fixed[{i}]: the target {:?} is the camera's own position",
                            c.position
                        ));
                    }
                }
                Ok(())
            }
            Poses::Line {
                from, to, target, ..
            } => {
                if from == to && views > 1 {
                    return Err(format!(
                        "dataset.camera.line runs from {from:?} to the same point: a path of length zero cannot hold {views} views"
                    ));
                }
                match target {
                    Some(t) if segment_distance(DVec3::from_array(*t), *from, *to) == 0.0 => {
                        Err(format!(
                            "dataset.camera.line passes through its target {t:?}: a view standing there would aim at its own position; move the target off the line"
                        ))
                    }
                    _ => Ok(()),
                }
            }
        }
    }

    /// The nominal intrinsics: the narrowest field of view, a centred principal point, no
    /// distortion (the drawn ones are in each view's record).
    pub fn intrinsics(&self) -> Intrinsics {
        self.lens(self.fov_y[0], [0.0; 2], Distortion::default())
    }

    /// Intrinsics for a drawn field of view, principal-point offset and lens.
    fn lens(&self, fov_y: f64, offset: [f64; 2], distortion: Distortion) -> Intrinsics {
        let mut k = Intrinsics::from_fov_y(self.width, self.height, fov_y);
        k.cx += offset[0];
        k.cy += offset[1];
        k.distortion = distortion;
        k
    }

    /// Size of a pixel (metres) at the nearest distance this rig can place a camera from the
    /// surface of a structure whose bounding sphere is (`centre`, `radius`); tessellation aims
    /// below it.
    pub fn nearest_pixel_footprint(&self, centre: DVec3, radius: f64) -> f64 {
        // The narrowest field of view has the finest pixels and, framing, stands farthest;
        // the widest stands nearest: take the finer of the two.
        self.fov_y
            .iter()
            .map(|&fov| {
                let k = self.lens(fov, [0.0; 2], Distortion::default());
                let nearest = self.nearest_centre_distance(&k, centre, radius);
                (nearest - radius).max(1e-3 * radius) / k.fx.max(k.fy)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The nearest a camera of this rig comes to `centre`.
    fn nearest_centre_distance(&self, k: &Intrinsics, centre: DVec3, radius: f64) -> f64 {
        let framing = |d: &Distance| match *d {
            Distance::Range { min, .. } => min,
            Distance::Frame { margin } => margin * radius / k.min_half_fov().sin(),
        };
        match &self.poses {
            Poses::Sphere { distance, .. } | Poses::Orbit { distance, .. } => framing(distance),
            Poses::Fixed { cameras } => cameras
                .iter()
                .map(|c| centre.distance(DVec3::from_array(c.position)))
                .fold(f64::INFINITY, f64::min),
            Poses::Line { from, to, .. } => segment_distance(centre, *from, *to),
        }
    }

    /// Draws pose `pose` of `poses` for a structure whose bounding sphere is (`centre`,
    /// `radius`); fails when the values drawn make no finite camera (a distance that
    /// overflows, say). The stream is the pose's own.
    pub fn draw(
        &self,
        stream: &mut Stream,
        pose: u32,
        poses: u32,
        centre: DVec3,
        radius: f64,
    ) -> Result<(Camera, ViewDraw), String> {
        let place = self.place(stream, pose, poses, centre, radius);
        let fov_y = pick(stream, self.fov_y);
        let offset = self.principal_offset.map(|range| pick(stream, range));
        let d = &self.distortion;
        let lens = Distortion {
            k1: pick(stream, d.k1),
            k2: pick(stream, d.k2),
            p1: pick(stream, d.p1),
            p2: pick(stream, d.p2),
            k3: pick(stream, d.k3),
        };
        let intrinsics = self.lens(fov_y, offset, lens);
        // The ranges' extremes were checked; this is the lens actually drawn.
        intrinsics
            .check_lens()
            .map_err(|e| format!("dataset.camera.distortion: {e}"))?;
        let (eye, target, roll, on_sphere) = place(&intrinsics);
        let jitter = self.jitter(stream);
        let aim = target + jitter;
        let outward = eye - aim;
        let distance = outward.length();
        if distance == 0.0 {
            return Err(self.on_its_aim(pose, eye));
        }
        // On the sphere the angles are the ones drawn; elsewhere they describe the pose.
        let (yaw, pitch) = on_sphere.map_or(
            (
                outward.y.atan2(outward.x),
                (outward.z / distance).clamp(-1.0, 1.0).asin(),
            ),
            |o| (o.yaw, o.pitch),
        );
        let draw = ViewDraw {
            yaw,
            pitch,
            roll,
            distance,
            fov_y,
            principal_offset: offset,
            aim: aim.to_array(),
        };
        let camera = match on_sphere {
            // Aimed at the centre: the sphere's own basis, defined at the poles too.
            Some(orbit) if jitter == DVec3::ZERO => orbit_camera(intrinsics, target, &orbit),
            _ => rolled(Camera::look_at(intrinsics, eye, aim, DVec3::Z), roll),
        };
        if !camera.is_finite() || !distance.is_finite() || distance <= 0.0 {
            return Err(format!(
                "dataset.camera: the camera drawn is not finite (yaw {}, pitch {}, roll {}, distance {} m from a structure of radius {} m); narrow the ranges or the margin",
                crate::words::number(draw.yaw),
                crate::words::number(draw.pitch),
                crate::words::number(roll),
                crate::words::number(distance),
                crate::words::number(radius),
            ));
        }
        Ok((camera, draw))
    }

    /// Why pose `pose`, standing at `eye`, is no camera: it stands on the point it aims at.
    /// Names the rig's camera and where that point came from (a default target is the
    /// centre of the structure's bounding sphere, known only once the sample is built).
    fn on_its_aim(&self, pose: u32, eye: DVec3) -> String {
        let (who, target) = match &self.poses {
            Poses::Fixed { cameras } => {
                let i = pose as usize % cameras.len();
                (format!("dataset.camera.fixed[{i}]"), cameras[i].target)
            }
            Poses::Line { target, .. } => (format!("dataset.camera.line, view {pose},"), *target),
            _ => (format!("dataset.camera, view {pose},"), None),
        };
        let why = match target {
            None => {
                "the centre of this sample's structures, the default target; give it a `target` away from where it stands"
            }
            Some(_) => "its target",
        };
        let [x, y, z] = eye.to_array().map(crate::words::number);
        format!(
            "{who} stands at ({x}, {y}, {z}), the very point it aims at ({why}): a camera there has no direction to look"
        )
    }

    /// Where pose `pose` stands: a function of the intrinsics (framing depends on the field of
    /// view drawn) giving (eye, target, roll). The sphere's draws come first in the stream, as
    /// they always have, so datasets made before the other rigs existed keep their cameras.
    fn place(
        &self,
        stream: &mut Stream,
        pose: u32,
        poses: u32,
        centre: DVec3,
        radius: f64,
    ) -> impl Fn(&Intrinsics) -> (DVec3, DVec3, f64, Option<Orbit>) + use<> {
        let framing = move |d: Distance, k: &Intrinsics, drawn: f64| match d {
            Distance::Range { .. } => drawn,
            Distance::Frame { margin } => margin * radius / k.min_half_fov().sin(),
        };
        let fraction = |closed: bool| {
            let steps = if closed {
                poses
            } else {
                poses.saturating_sub(1)
            };
            if steps == 0 {
                0.0
            } else {
                f64::from(pose) / f64::from(steps)
            }
        };
        enum Place {
            /// (yaw, pitch) on a sphere about the centre, its distance and roll.
            Around(f64, f64, Distance, f64, f64),
            At(DVec3, DVec3, f64),
        }
        let place = match &self.poses {
            Poses::Sphere {
                yaw,
                pitch,
                roll,
                distance,
            } => {
                let yaw = stream.uniform(yaw[0], yaw[1]);
                let (s0, s1) = (pitch[0].sin(), pitch[1].sin());
                let pitch = stream.uniform(s0, s1).clamp(-1.0, 1.0).asin();
                let roll = stream.uniform(roll[0], roll[1]);
                let drawn = drawn_distance(stream, distance);
                Place::Around(yaw, pitch, *distance, drawn, roll)
            }
            Poses::Orbit {
                distance,
                pitch,
                yaw_start,
                sweep,
                roll,
            } => {
                let yaw = yaw_start + sweep * fraction(closed_orbit(*sweep));
                let drawn = drawn_distance(stream, distance);
                Place::Around(yaw, *pitch, *distance, drawn, *roll)
            }
            Poses::Fixed { cameras } => {
                let c = &cameras[pose as usize % cameras.len()];
                let target = c.target.map_or(centre, DVec3::from_array);
                Place::At(DVec3::from_array(c.position), target, c.roll)
            }
            Poses::Line {
                from,
                to,
                target,
                roll,
            } => {
                let (a, b) = (DVec3::from_array(*from), DVec3::from_array(*to));
                let eye = a + (b - a) * fraction(false);
                Place::At(eye, target.map_or(centre, DVec3::from_array), *roll)
            }
        };
        move |k: &Intrinsics| match place {
            Place::Around(yaw, pitch, distance, drawn, roll) => {
                let orbit = Orbit {
                    yaw,
                    pitch,
                    roll,
                    distance: framing(distance, k, drawn),
                };
                let (sp, cp) = pitch.sin_cos();
                let outward = DVec3::new(cp * yaw.cos(), cp * yaw.sin(), sp);
                (centre + orbit.distance * outward, centre, roll, Some(orbit))
            }
            Place::At(eye, target, roll) => (eye, target, roll, None),
        }
    }

    /// An offset uniform in the ball of radius `aim_jitter` (none drawn when it is 0).
    fn jitter(&self, stream: &mut Stream) -> DVec3 {
        if self.aim_jitter == 0.0 {
            return DVec3::ZERO;
        }
        loop {
            let p = DVec3::new(
                stream.uniform(-1.0, 1.0),
                stream.uniform(-1.0, 1.0),
                stream.uniform(-1.0, 1.0),
            );
            if p.length_squared() <= 1.0 {
                return p * self.aim_jitter;
            }
        }
    }

    /// The right eye of the stereo pair whose left eye is `left`.
    pub fn right_eye(&self, left: &Camera) -> Option<Camera> {
        let stereo = self.stereo?;
        let turn = DMat3::from_axis_angle(left.rotation.y_axis, -stereo.toe_in);
        Some(Camera {
            intrinsics: left.intrinsics,
            rotation: turn * left.rotation,
            position: left.position + stereo.baseline * left.rotation.x_axis,
        })
    }
}

/// Whether a full turn is swept: then the last view stops one step short of the first.
fn closed_orbit(sweep: f64) -> bool {
    (sweep.abs() - std::f64::consts::TAU).abs() < 1e-12
}

/// Checks that no two of an orbit's `views` share an azimuth (to 1e-9 rad): they would be
/// the same camera, which is no orbit. Views i and j coincide when sweep·(j − i)/steps is a
/// whole number of turns, so it is enough to look at the gaps from view 0.
fn orbit_views_apart(sweep: f64, views: u32) -> Result<(), String> {
    if !sweep.is_finite() {
        return Err(format!(
            "dataset.camera.orbit.sweep = {} must be finite (radians)",
            crate::words::number(sweep)
        ));
    }
    let steps = if closed_orbit(sweep) {
        views
    } else {
        views.saturating_sub(1)
    };
    let tau = std::f64::consts::TAU;
    let same = (1..views).find(|&gap| {
        let turn = (sweep * f64::from(gap) / f64::from(steps)).rem_euclid(tau);
        turn.min(tau - turn) < 1e-9
    });
    match same {
        None => Ok(()),
        Some(_) if sweep == 0.0 => Err(format!(
            "dataset.camera.orbit.sweep = 0 puts all {views} views at one azimuth: they would be one camera {views} times; sweep an angle (deg(360) for a full circle) or use views: 1"
        )),
        Some(1) => Err(format!(
            "dataset.camera.orbit.sweep = {} puts all {views} views at one azimuth: the step between them is a whole number of turns, so they would be one camera {views} times",
            crate::words::number(sweep)
        )),
        Some(gap) => Err(format!(
            "dataset.camera.orbit.sweep = {} puts views 0 and {gap} of {views} at the same azimuth (a whole number of turns apart): they would be the same camera; sweep less than a full turn between them",
            crate::words::number(sweep)
        )),
    }
}

/// The distance drawn for a range (none is drawn for framing, which needs the field of view).
fn drawn_distance(stream: &mut Stream, distance: &Distance) -> f64 {
    match *distance {
        Distance::Range { min, max } => stream.uniform(min, max),
        Distance::Frame { .. } => 0.0,
    }
}

/// Distance from `p` to the segment from `a` to `b`.
fn segment_distance(p: DVec3, a: [f64; 3], b: [f64; 3]) -> f64 {
    let (a, b) = (DVec3::from_array(a), DVec3::from_array(b));
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + t * ab)
}

/// `camera` turned about its view axis by `roll`: the image turns clockwise as seen by the
/// viewer (x towards y).
fn rolled(camera: Camera, roll: f64) -> Camera {
    if roll == 0.0 {
        return camera;
    }
    let (s, c) = roll.sin_cos();
    let (right, down) = (camera.rotation.x_axis, camera.rotation.y_axis);
    Camera {
        rotation: DMat3::from_cols(
            c * right + s * down,
            c * down - s * right,
            camera.rotation.z_axis,
        ),
        ..camera
    }
}

/// A place on the sphere around a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// Azimuth, radians from +x towards +y.
    pub yaw: f64,
    /// Elevation above the target's horizontal plane, radians.
    pub pitch: f64,
    /// Roll about the view axis, radians.
    pub roll: f64,
    /// Distance from the target, metres.
    pub distance: f64,
}

/// Camera on the sphere around `target` at `d`, looking at it. The image x axis is the
/// direction of increasing yaw, which depends on yaw alone: well defined at the poles, where
/// a look-at with a fixed up vector has no answer.
pub fn orbit_camera(intrinsics: Intrinsics, target: DVec3, d: &Orbit) -> Camera {
    let (sy, cy) = d.yaw.sin_cos();
    let (sp, cp) = d.pitch.sin_cos();
    let outward = DVec3::new(cp * cy, cp * sy, sp);
    let forward = -outward;
    let right = DVec3::new(-sy, cy, 0.0);
    let down = forward.cross(right);
    rolled(
        Camera {
            intrinsics,
            rotation: DMat3::from_cols(right, down, forward),
            position: target + d.distance * outward,
        },
        d.roll,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::seeds::{Scope, Stream};
    use std::f64::consts::{FRAC_PI_2, PI};

    fn sphere(yaw: [f64; 2], pitch: [f64; 2], roll: [f64; 2]) -> Poses {
        Poses::Sphere {
            yaw,
            pitch,
            roll,
            distance: Distance::Frame { margin: 1.05 },
        }
    }

    #[test]
    fn poles_give_finite_orthonormal_cameras_looking_at_the_target() {
        let k = CameraRig::default().intrinsics();
        let target = DVec3::new(1.0, 2.0, 3.0);
        for pitch in [FRAC_PI_2, -FRAC_PI_2, FRAC_PI_2 - 1e-12, 0.0] {
            for yaw in [0.0, 1.0, PI] {
                let d = Orbit {
                    yaw,
                    pitch,
                    roll: 0.3,
                    distance: 5.0,
                };
                let cam = orbit_camera(k, target, &d);
                let r = cam.rotation;
                assert!(r.is_finite());
                assert!((r.transpose() * r - DMat3::IDENTITY).abs_diff_eq(DMat3::ZERO, 1e-12));
                assert!((r.determinant() - 1.0).abs() < 1e-12);
                let t = cam.world_to_camera(target);
                assert!(t.x.abs() < 1e-12 && t.y.abs() < 1e-12 && (t.z - 5.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn unrolled_side_view_has_world_up_as_image_up() {
        let k = CameraRig::default().intrinsics();
        let d = Orbit {
            yaw: 0.7,
            pitch: 0.2,
            roll: 0.0,
            distance: 3.0,
        };
        let cam = orbit_camera(k, DVec3::ZERO, &d);
        assert!(
            cam.rotation.y_axis.z < 0.0,
            "image down must point to world −z"
        );
        assert_eq!(cam.rotation.x_axis.z, 0.0, "no roll: horizon is level");
    }

    #[test]
    fn framing_distance_keeps_the_bounding_sphere_in_view() {
        let rig = CameraRig {
            width: 960,
            height: 540,
            ..CameraRig::default()
        };
        let mut s = Stream::new(3, Scope::View(0, 0), "camera");
        let (cam, d) = rig.draw(&mut s, 0, 1, DVec3::ZERO, 2.0).unwrap();
        // The sphere's tangent cone half-angle equals the narrower half FOV / margin.
        let half = (2.0 / d.distance).asin();
        assert!(half < rig.intrinsics().min_half_fov());
        assert!((d.distance - 1.05 * 2.0 / rig.intrinsics().min_half_fov().sin()).abs() < 1e-12);
        assert!((cam.position.length() - d.distance).abs() < 1e-12);
    }

    #[test]
    fn band_draws_stay_in_their_ranges() {
        let rig = CameraRig {
            poses: sphere([1.0, 2.0], [0.2, 0.6], [-0.1, 0.1]),
            fov_y: [0.5, 0.9],
            principal_offset: [[-3.0, 3.0], [-2.0, 0.0]],
            ..CameraRig::default()
        };
        for v in 0..500 {
            let mut s = Stream::new(1, Scope::View(7, v), "camera");
            let (cam, d) = rig.draw(&mut s, v, 500, DVec3::ZERO, 1.0).unwrap();
            assert!(
                (0.2..=0.6).contains(&d.pitch)
                    && (1.0..2.0).contains(&d.yaw)
                    && (-0.1..0.1).contains(&d.roll)
                    && (0.5..0.9).contains(&d.fov_y)
            );
            let k = cam.intrinsics;
            assert!((k.cx - 480.0 - d.principal_offset[0]).abs() < 1e-12);
            assert!((-3.0..3.0).contains(&d.principal_offset[0]));
            assert!((-2.0..0.0).contains(&d.principal_offset[1]));
            assert!((2.0 * (0.5 * f64::from(k.height) / k.fy).atan() - d.fov_y).abs() < 1e-12);
        }
    }

    #[test]
    fn paths_place_their_views_in_order() {
        let target = DVec3::new(0.0, 0.0, 1.0);
        let line = CameraRig {
            poses: Poses::Line {
                from: [-5.0, -10.0, 2.0],
                to: [5.0, -10.0, 2.0],
                target: Some(target.to_array()),
                roll: 0.0,
            },
            ..CameraRig::default()
        };
        let mut s = Stream::new(0, Scope::View(0, 0), "camera");
        for v in 0..5u32 {
            let (cam, _) = line.draw(&mut s, v, 5, DVec3::ZERO, 1.0).unwrap();
            let x = -5.0 + 2.5 * f64::from(v);
            assert!((cam.position - DVec3::new(x, -10.0, 2.0)).length() < 1e-12);
            let t = cam.world_to_camera(target);
            assert!(t.x.abs() < 1e-9 && t.y.abs() < 1e-9 && t.z > 0.0);
        }
        let orbit = CameraRig {
            poses: Poses::Orbit {
                distance: Distance::Range { min: 4.0, max: 4.0 },
                pitch: 0.3,
                yaw_start: 0.5,
                sweep: std::f64::consts::TAU,
                roll: 0.0,
            },
            ..CameraRig::default()
        };
        for v in 0..8u32 {
            let (cam, d) = orbit.draw(&mut s, v, 8, target, 1.0).unwrap();
            assert!((d.yaw - (0.5 + std::f64::consts::TAU * f64::from(v) / 8.0)).abs() < 1e-12);
            assert!((cam.position.distance(target) - 4.0).abs() < 1e-12);
            assert!((d.pitch - 0.3).abs() < 1e-12);
        }
    }

    #[test]
    fn degenerate_rigs_are_refused_by_name() {
        let with = |poses: Poses| CameraRig {
            poses,
            ..CameraRig::default()
        };
        let zero_path = with(Poses::Line {
            from: [1.0, 2.0, 3.0],
            to: [1.0, 2.0, 3.0],
            target: None,
            roll: 0.0,
        });
        assert!(zero_path.validate(3).unwrap_err().contains("length zero"));
        assert!(zero_path.validate(1).is_ok());
        let on_target = with(Poses::Fixed {
            cameras: vec![FixedCamera {
                position: [1.0, 1.0, 1.0],
                target: Some([1.0, 1.0, 1.0]),
                roll: 0.0,
            }],
        });
        assert!(on_target.validate(1).unwrap_err().contains("own position"));
        assert!(
            on_target
                .validate(2)
                .unwrap_err()
                .contains("each view is one fixed camera")
        );
        let flat = CameraRig {
            stereo: Some(Stereo {
                baseline: 0.0,
                toe_in: 0.0,
            }),
            ..CameraRig::default()
        };
        assert!(flat.validate(1).unwrap_err().contains("baseline"));
        let orbit = |sweep: f64| {
            with(Poses::Orbit {
                distance: Distance::Frame { margin: 1.05 },
                pitch: 0.2,
                yaw_start: 0.0,
                sweep,
                roll: 0.0,
            })
        };
        assert!(
            orbit(0.0)
                .validate(3)
                .unwrap_err()
                .contains("sweep = 0 puts all 3 views")
        );
        assert!(orbit(0.0).validate(1).is_ok());
        // Two turns over 3 views: each step a whole turn; over 5 views, views 0 and 2 meet.
        let two_turns = 2.0 * std::f64::consts::TAU;
        assert!(
            orbit(two_turns)
                .validate(3)
                .unwrap_err()
                .contains("all 3 views")
        );
        assert!(
            orbit(two_turns)
                .validate(5)
                .unwrap_err()
                .contains("views 0 and 2")
        );
        for fine in [std::f64::consts::TAU, -std::f64::consts::TAU, 1.0, 6.0] {
            assert!(orbit(fine).validate(8).is_ok(), "{fine}");
        }
    }

    #[test]
    fn a_camera_on_the_point_it_aims_at_is_named() {
        let centre = DVec3::new(0.5, -1.0, 2.0);
        let fixed = CameraRig {
            poses: Poses::Fixed {
                cameras: vec![
                    FixedCamera {
                        position: [4.0, 0.0, 2.0],
                        target: None,
                        roll: 0.0,
                    },
                    FixedCamera {
                        position: centre.to_array(),
                        target: None,
                        roll: 0.0,
                    },
                ],
            },
            ..CameraRig::default()
        };
        let mut s = Stream::new(0, Scope::View(0, 0), "camera");
        assert!(fixed.draw(&mut s, 0, 2, centre, 1.0).is_ok());
        let err = fixed.draw(&mut s, 1, 2, centre, 1.0).unwrap_err();
        assert!(
            err.starts_with("dataset.camera.fixed[1] stands at (0.5, -1, 2)")
                && err.contains("give it a `target`"),
            "{err}"
        );
        let line = CameraRig {
            poses: Poses::Line {
                from: [-2.0, -1.0, 2.0],
                to: [3.0, -1.0, 2.0],
                target: None,
                roll: 0.0,
            },
            ..CameraRig::default()
        };
        // Five views 1.25 m apart: view 2 lands on the centre.
        let err = line.draw(&mut s, 2, 5, centre, 1.0).unwrap_err();
        assert!(
            err.starts_with("dataset.camera.line, view 2, stands at"),
            "{err}"
        );
        assert!(line.draw(&mut s, 1, 5, centre, 1.0).is_ok());
    }

    #[test]
    fn an_exact_zoom_out_must_keep_the_lens_one_to_one() {
        // k1 = −0.195 at 60°: one-to-one out to r_d = (2/3)/√(3 · 0.195) = 0.872; the clean
        // corners reach √2·tan 30° = 0.816, within the 5 % margin only down to zoom 0.984.
        let rig = CameraRig {
            width: 64,
            height: 64,
            distortion: DistortionRanges {
                k1: [-0.195; 2],
                ..DistortionRanges::default()
            },
            ..CameraRig::default()
        };
        rig.validate(1).unwrap();
        let err = rig.validate_widened(0.8, [0.0; 2], "zoom 0.8").unwrap_err();
        assert!(
            err.starts_with("zoom 0.8 widens") && err.contains("0.872"),
            "{err}"
        );
        assert!(rig.validate_widened(0.99, [0.0; 2], "zoom 0.99").is_ok());
        // A shift shows the lens beyond the corners too.
        assert!(rig.validate_widened(1.0, [0.2, 0.0], "shift").is_err());
        let pinhole = CameraRig::default();
        assert!(pinhole.validate_widened(0.05, [1.0, 1.0], "any").is_ok());
    }

    #[test]
    fn principal_offsets_along_both_axes_move_the_corner_diagonally() {
        // Offsets of (20, 20) px put the farthest corner (52, 52) px from the principal point
        // of a 64 × 64 image at 60°, a normalised radius of 1.327: a barrel lens folding at
        // 1.31 has no ray for it, though each offset alone would stay inside.
        let k1 = -(2.0 / 3.0 / 1.31f64).powi(2) / 3.0;
        let corner = 52.0 * 2f64.sqrt() / (32.0 / (std::f64::consts::PI / 6.0).tan());
        assert!((corner - 1.327).abs() < 1e-3);
        let rig = |offset: f64| CameraRig {
            width: 64,
            height: 64,
            principal_offset: [[offset; 2], [offset; 2]],
            distortion: DistortionRanges {
                k1: [k1; 2],
                ..DistortionRanges::default()
            },
            ..CameraRig::default()
        };
        assert!(
            rig(20.0)
                .validate(1)
                .unwrap_err()
                .contains("folds the image")
        );
        assert!(rig(0.0).validate(1).is_ok());
    }

    #[test]
    fn the_right_eye_stands_one_baseline_to_the_right() {
        let rig = CameraRig {
            stereo: Some(Stereo {
                baseline: 0.25,
                toe_in: 0.0,
            }),
            ..CameraRig::default()
        };
        let mut s = Stream::new(4, Scope::View(0, 0), "camera");
        let (left, _) = rig.draw(&mut s, 0, 1, DVec3::ZERO, 2.0).unwrap();
        let right = rig.right_eye(&left).unwrap();
        // In the left eye's frame the right eye sits at (b, 0, 0), axes parallel.
        let at = left.world_to_camera(right.position);
        assert!((at - DVec3::new(0.25, 0.0, 0.0)).length() < 1e-12);
        assert!((left.rotation - right.rotation).abs_diff_eq(DMat3::ZERO, 1e-15));
    }
}
