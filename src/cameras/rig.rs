//! Camera distributions: positions on a sphere (or a band of it) around a target.

use super::{Camera, Intrinsics};
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

/// Where views are drawn from: yaw (azimuth from +x towards +y), pitch (elevation above the
/// horizontal plane through the target; +π/2 looks straight down) and roll about the view
/// axis, each uniform in its range; pitch is drawn uniform in area on the sphere.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct CameraRig {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Vertical field of view, radians, in (0, π); pixels are square and the principal point is the
    /// image centre.
    pub fov_y: f64,
    /// Range [min, max] of the yaw: azimuth of the camera about the target from +x towards +y,
    /// radians.
    pub yaw: [f64; 2],
    /// Range [min, max] of the pitch: elevation of the camera above the target's horizontal plane,
    /// radians within [−π/2, π/2]; sin(pitch) is drawn uniformly.
    pub pitch: [f64; 2],
    /// Range [min, max] of the roll about the view axis, radians (0 keeps the horizon level).
    pub roll: [f64; 2],
    /// How far the camera is from the target.
    pub distance: Distance,
}

impl Default for CameraRig {
    fn default() -> Self {
        CameraRig {
            width: 960,
            height: 960,
            fov_y: std::f64::consts::FRAC_PI_3,
            yaw: [0.0, std::f64::consts::TAU],
            pitch: [-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2],
            roll: [0.0, 0.0],
            distance: Distance::Frame { margin: 1.05 },
        }
    }
}

/// The values actually drawn for one view, recorded in its JSON.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ViewDraw {
    /// Azimuth of the camera about the target, from +x towards +y, radians.
    pub yaw: f64,
    /// Elevation of the camera above the target's horizontal plane, radians (+π/2: straight above,
    /// looking down).
    pub pitch: f64,
    /// Roll about the view axis, radians; positive turns the camera's x axis towards its y axis.
    pub roll: f64,
    /// Distance from the target (the centre of the sample's bounding sphere) to the camera centre,
    /// metres.
    pub distance: f64,
}

/// The narrowest vertical field of view (radians). A camera that frames a structure at field
/// of view φ stands about 2R/φ away; f64 places its rays to about that distance × 1.1e-16,
/// which must stay below a thousandth of a pixel (2R/φ × φ/H) for H up to 16,384 pixels:
/// φ ≥ 1.1e-16 × 16,384 × 1000 ≈ 1.8e-9.
pub const MIN_FOV: f64 = 1e-8;

impl CameraRig {
    /// Checks what the ranges alone cannot: a field of view inside (0, π), pitches on the
    /// sphere, a positive distance or framing margin. Messages name the recipe's option.
    pub fn validate(&self) -> Result<(), String> {
        let fov_y = self.fov_y;
        if !(fov_y >= MIN_FOV && fov_y < std::f64::consts::PI) {
            return Err(format!(
                "dataset.camera.fov_y = {fov_y} must lie in [{MIN_FOV}, π) radians (below \
                 {MIN_FOV} rad a camera framing the structure stands so far off that f64 \
                 cannot aim its rays to a thousandth of a pixel)"
            ));
        }
        let half_pi = std::f64::consts::FRAC_PI_2;
        if self.pitch[0] < -half_pi - 1e-12 || self.pitch[1] > half_pi + 1e-12 {
            return Err(format!(
                "dataset.camera.pitch = [{}, {}] must lie within [-π/2, π/2]",
                self.pitch[0], self.pitch[1]
            ));
        }
        match self.distance {
            Distance::Range { min, .. } if min <= 0.0 => Err(format!(
                "dataset.camera.distance = {min} must be positive (metres) or \"frame\""
            )),
            Distance::Frame { margin } if margin <= 0.0 => {
                Err(format!("dataset.camera.margin = {margin} must be positive"))
            }
            _ => Ok(()),
        }
    }

    /// The intrinsics every view of the rig shares.
    pub fn intrinsics(&self) -> Intrinsics {
        Intrinsics::from_fov_y(self.width, self.height, self.fov_y)
    }

    /// Size of a pixel (metres) at the nearest distance this rig can place a camera from the
    /// surface of a structure with bounding radius `radius`; tessellation aims below it.
    pub fn nearest_pixel_footprint(&self, radius: f64) -> f64 {
        let k = self.intrinsics();
        let centre_distance = match self.distance {
            Distance::Range { min, .. } => min,
            Distance::Frame { margin } => margin * radius / k.min_half_fov().sin(),
        };
        (centre_distance - radius).max(1e-3 * radius) / k.fx.max(k.fy)
    }

    /// Draws one view of a structure whose bounding sphere is (`centre`, `radius`); fails when
    /// the values drawn make no finite camera (a distance that overflows, say).
    pub fn draw(
        &self,
        stream: &mut Stream,
        centre: DVec3,
        radius: f64,
    ) -> Result<(Camera, ViewDraw), String> {
        let yaw = stream.uniform(self.yaw[0], self.yaw[1]);
        let (s0, s1) = (self.pitch[0].sin(), self.pitch[1].sin());
        let pitch = stream.uniform(s0, s1).clamp(-1.0, 1.0).asin();
        let roll = stream.uniform(self.roll[0], self.roll[1]);
        let intrinsics = self.intrinsics();
        let distance = match self.distance {
            Distance::Range { min, max } => stream.uniform(min, max),
            Distance::Frame { margin } => margin * radius / intrinsics.min_half_fov().sin(),
        };
        let draw = ViewDraw {
            yaw,
            pitch,
            roll,
            distance,
        };
        let camera = orbit_camera(intrinsics, centre, &draw);
        if !camera.is_finite() {
            return Err(format!(
                "dataset.camera: the camera drawn is not finite (yaw {yaw}, pitch {pitch}, roll {roll}, distance {distance} m from a structure of radius {radius} m); narrow the ranges or the margin"
            ));
        }
        Ok((camera, draw))
    }
}

/// Camera on the sphere around `target`, looking at it. The image x axis is the direction of
/// increasing yaw, which depends on yaw alone: well defined at the poles, where a look-at with
/// a fixed up vector has no answer.
pub fn orbit_camera(intrinsics: Intrinsics, target: DVec3, d: &ViewDraw) -> Camera {
    let (sy, cy) = d.yaw.sin_cos();
    let (sp, cp) = d.pitch.sin_cos();
    let outward = DVec3::new(cp * cy, cp * sy, sp);
    let forward = -outward;
    let right = DVec3::new(-sy, cy, 0.0);
    let down = forward.cross(right);
    let (sr, cr) = d.roll.sin_cos();
    // Roll turns the image clockwise as seen by the viewer (x towards y).
    let (right, down) = (cr * right + sr * down, cr * down - sr * right);
    Camera {
        intrinsics,
        rotation: DMat3::from_cols(right, down, forward),
        position: target + d.distance * outward,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::seeds::{Scope, Stream};
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn poles_give_finite_orthonormal_cameras_looking_at_the_target() {
        let k = CameraRig::default().intrinsics();
        let target = DVec3::new(1.0, 2.0, 3.0);
        for pitch in [FRAC_PI_2, -FRAC_PI_2, FRAC_PI_2 - 1e-12, 0.0] {
            for yaw in [0.0, 1.0, PI] {
                let d = ViewDraw {
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
        let cam = orbit_camera(
            k,
            DVec3::ZERO,
            &ViewDraw {
                yaw: 0.7,
                pitch: 0.2,
                roll: 0.0,
                distance: 3.0,
            },
        );
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
        let (cam, d) = rig.draw(&mut s, DVec3::ZERO, 2.0).unwrap();
        // The sphere's tangent cone half-angle equals the narrower half FOV / margin.
        let half = (2.0 / d.distance).asin();
        assert!(half < rig.intrinsics().min_half_fov());
        assert!((d.distance - 1.05 * 2.0 / rig.intrinsics().min_half_fov().sin()).abs() < 1e-12);
        assert!((cam.position.length() - d.distance).abs() < 1e-12);
    }

    #[test]
    fn band_draws_stay_in_their_ranges() {
        let rig = CameraRig {
            pitch: [0.2, 0.6],
            yaw: [1.0, 2.0],
            roll: [-0.1, 0.1],
            ..CameraRig::default()
        };
        for v in 0..500 {
            let mut s = Stream::new(1, Scope::View(7, v), "camera");
            let (_, d) = rig.draw(&mut s, DVec3::ZERO, 1.0).unwrap();
            assert!(
                (0.2..=0.6).contains(&d.pitch)
                    && (1.0..2.0).contains(&d.yaw)
                    && (-0.1..0.1).contains(&d.roll)
            );
        }
    }
}
