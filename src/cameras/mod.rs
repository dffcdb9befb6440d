//! Cameras: intrinsics with Brown–Conrady lens distortion, poses, and the rigs views are
//! drawn from.
//!
//! Owns: K and the lens (OpenCV's model, inverted exactly so that each pixel's ray is the one
//! that distorts onto it, and checked one-to-one over every frame that is rendered), the
//! camera-to-world pose in OpenCV axes (x right, y down, z forward), the conversions users
//! need (world-to-camera, OpenGL/nerfstudio axes), ray directions through pixel centres (pixel
//! (i, j) has its centre at (j + 0.5, i + 0.5)), and the rigs ([`CameraRig`]): poses on a
//! sphere or band, fixed inspection cameras, orbits and flight lines, drawn fields of view,
//! principal points and lenses, stereo pairs, the checks that refuse degenerate ones, and a
//! thin lens's depth of field (`focus`).
//! Must not touch: meshes, tracing or files.

mod distortion;
mod focus;
mod rig;

pub use distortion::{Distortion, LensFault};
pub use focus::DepthOfField;
pub use rig::{
    CameraRig, Distance, DistortionRanges, FixedCamera, MIN_FOV, Orbit, Poses, Stereo, ViewDraw,
    orbit_camera,
};

use glam::{DMat3, DMat4, DVec3, DVec4};

/// Intrinsics in pixels: a pinhole K, with optional lens distortion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels from the left edge of the image.
    pub cx: f64,
    /// Principal point y, pixels from the top edge of the image.
    pub cy: f64,
    /// Lens distortion (none for a pinhole).
    pub distortion: Distortion,
}

impl Intrinsics {
    /// Square pixels, centred principal point, vertical field of view `fov_y` (radians).
    pub fn from_fov_y(width: u32, height: u32, fov_y: f64) -> Self {
        let f = 0.5 * f64::from(height) / (0.5 * fov_y).tan();
        Intrinsics {
            width,
            height,
            fx: f,
            fy: f,
            cx: 0.5 * f64::from(width),
            cy: 0.5 * f64::from(height),
            distortion: Distortion::default(),
        }
    }

    /// K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], row-major.
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        [
            [self.fx, 0.0, self.cx],
            [0.0, self.fy, self.cy],
            [0.0, 0.0, 1.0],
        ]
    }

    /// The smaller of the horizontal and vertical half fields of view.
    pub fn min_half_fov(&self) -> f64 {
        let half_x = (0.5 * f64::from(self.width) / self.fx).atan();
        let half_y = (0.5 * f64::from(self.height) / self.fy).atan();
        half_x.min(half_y)
    }

    /// Direction in camera axes through the centre of pixel (row, col), scaled to unit z so
    /// that the ray parameter at a hit is the planar depth.
    pub fn ray_through_pixel(&self, row: u32, col: u32) -> DVec3 {
        self.ray_through(f64::from(col) + 0.5, f64::from(row) + 0.5)
    }

    /// Direction in camera axes through image point (u, v) (pixel units), unit z: through
    /// the undistorted point whose image is (u, v) when the lens distorts.
    ///
    /// Panics where the lens has no inverse: every camera that is rendered has passed
    /// [`Intrinsics::check_lens`] (a lens one-to-one past its corners), so there is none
    /// inside its frame, and a made-up ray would write a wrong label without a word.
    pub fn ray_through(&self, u: f64, v: f64) -> DVec3 {
        let (xd, yd) = ((u - self.cx) / self.fx, (v - self.cy) / self.fy);
        let Some((x, y)) = self.distortion.undistort(xd, yd) else {
            panic!(
                "no ray through ({u}, {v}): the lens {} has no inverse there, yet the camera was checked one-to-one out to its corners",
                self.distortion.describe()
            )
        };
        DVec3::new(x, y, 1.0)
    }

    /// Checks that the lens maps this camera's whole frame one-to-one, so that every pixel
    /// has a ray ([`Distortion::fault_within`] out to the farthest corner).
    pub fn check_lens(&self) -> Result<(), String> {
        let reach = self.corner_reach();
        match self.distortion.fault_within(reach) {
            None => Ok(()),
            Some(fault) => Err(format!(
                "the lens {} {fault}, but this camera's corners reach a distorted radius of {reach:.3} (normalised; with a 5 % margin, {:.3}): its outer pixels would have no ray",
                self.distortion.describe(),
                1.05 * reach
            )),
        }
    }

    /// Pixel coordinates (u, v) of a point in camera axes (z > 0), distorted by the lens.
    pub fn project(&self, p: DVec3) -> (f64, f64) {
        let (x, y) = self.distortion.distort(p.x / p.z, p.y / p.z);
        self.pixels_of(x, y)
    }

    /// Pixel coordinates (u, v) of a point in camera axes (z > 0) through an ideal pinhole:
    /// what `project` gives when the lens has no distortion (the distortion polynomial is then
    /// exactly the identity), without evaluating it.
    pub fn project_pinhole(&self, p: DVec3) -> (f64, f64) {
        self.pixels_of(p.x / p.z, p.y / p.z)
    }

    /// Pixel coordinates of normalised (distorted) image coordinates (x, y).
    fn pixels_of(&self, x: f64, y: f64) -> (f64, f64) {
        (self.fx * x + self.cx, self.fy * y + self.cy)
    }

    /// The farthest image corner from the principal point, in normalised distorted units.
    pub fn corner_reach(&self) -> f64 {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
            .iter()
            .map(|&(u, v)| ((u - self.cx) / self.fx).hypot((v - self.cy) / self.fy))
            .fold(0.0, f64::max)
    }
}

/// A posed pinhole camera. `rotation` holds the camera axes (OpenCV) as columns in world
/// coordinates; `position` is the centre of projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Image size and K.
    pub intrinsics: Intrinsics,
    /// Camera axes (OpenCV: x right, y down, z forward) as columns, in world coordinates.
    pub rotation: DMat3,
    /// Centre of projection, world coordinates, metres.
    pub position: DVec3,
}

impl Camera {
    /// Camera at `eye` looking at `target`, with `up` as the preferred image-up direction.
    /// When the view direction is (nearly) parallel to `up` the basis falls back to another
    /// axis instead of producing NaN.
    pub fn look_at(intrinsics: Intrinsics, eye: DVec3, target: DVec3, up: DVec3) -> Self {
        let forward = (target - eye).normalize();
        let helper = if forward.cross(up).length_squared() > 1e-12 {
            up
        } else {
            forward.any_orthonormal_vector()
        };
        let right = forward.cross(helper).normalize();
        let down = forward.cross(right);
        Camera {
            intrinsics,
            rotation: DMat3::from_cols(right, down, forward),
            position: eye,
        }
    }

    /// Camera-to-world, OpenCV axes.
    pub fn c2w_cv(&self) -> DMat4 {
        DMat4::from_cols(
            self.rotation.x_axis.extend(0.0),
            self.rotation.y_axis.extend(0.0),
            self.rotation.z_axis.extend(0.0),
            self.position.extend(1.0),
        )
    }

    /// World-to-camera, OpenCV axes: x_cam = Rᵀ(x_w − C).
    pub fn w2c_cv(&self) -> DMat4 {
        let rt = self.rotation.transpose();
        let t = -(rt * self.position);
        DMat4::from_cols(
            rt.x_axis.extend(0.0),
            rt.y_axis.extend(0.0),
            rt.z_axis.extend(0.0),
            t.extend(1.0),
        )
    }

    /// Camera-to-world in OpenGL/nerfstudio axes: c2w_gl = c2w_cv · diag(1, −1, −1, 1).
    pub fn c2w_gl(&self) -> DMat4 {
        self.c2w_cv() * DMat4::from_diagonal(DVec4::new(1.0, -1.0, -1.0, 1.0))
    }

    /// Whether every number of the pose and intrinsics is finite.
    pub fn is_finite(&self) -> bool {
        let k = &self.intrinsics;
        self.rotation.is_finite()
            && self.position.is_finite()
            && [k.fx, k.fy, k.cx, k.cy].iter().all(|x| x.is_finite())
    }

    /// World point `p` in camera axes (OpenCV), metres.
    pub fn world_to_camera(&self, p: DVec3) -> DVec3 {
        self.rotation.transpose() * (p - self.position)
    }

    /// Unit viewing direction (the optical axis), world axes.
    pub fn forward(&self) -> DVec3 {
        self.rotation.z_axis
    }
}

/// Row-major nested arrays, the layout every reader of the JSON expects.
pub fn rows4(m: DMat4) -> [[f64; 4]; 4] {
    m.transpose().to_cols_array_2d()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn k() -> Intrinsics {
        Intrinsics::from_fov_y(960, 960, std::f64::consts::FRAC_PI_3)
    }

    #[test]
    fn paper_intrinsics() {
        let k = k();
        assert_eq!((k.cx, k.cy), (480.0, 480.0));
        // f = (H/2)/tan(π/6) = 480·√3.
        assert!((k.fx - 480.0 * 3f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn projection_inverts_the_pixel_ray() {
        let k = Intrinsics::from_fov_y(640, 480, 0.9);
        for (row, col) in [(0, 0), (479, 639), (240, 320), (13, 601)] {
            let (u, v) = k.project(k.ray_through_pixel(row, col) * 7.5);
            assert!(
                (u - (f64::from(col) + 0.5)).abs() < 1e-9
                    && (v - (f64::from(row) + 0.5)).abs() < 1e-9
            );
        }
    }

    #[test]
    fn a_pinhole_projects_to_the_same_bits_either_way() {
        let k = Intrinsics::from_fov_y(640, 480, 0.9);
        let coordinates = [
            0.0,
            -0.0,
            1e-300,
            -3.7e-9,
            0.25,
            -1.0 / 3.0,
            7.5,
            -1234.5,
            1e12,
        ];
        for &x in &coordinates {
            for &y in &coordinates {
                for z in [1e-9, 0.3, 2.0, 1e7] {
                    let p = DVec3::new(x, y, z);
                    let (u, v) = k.project(p);
                    let (pu, pv) = k.project_pinhole(p);
                    assert_eq!(
                        (u.to_bits(), v.to_bits()),
                        (pu.to_bits(), pv.to_bits()),
                        "{p}"
                    );
                }
            }
        }
    }

    #[test]
    fn matrices_are_consistent() {
        let cam = Camera::look_at(
            k(),
            DVec3::new(3.0, -4.0, 2.0),
            DVec3::new(0.5, 0.2, 0.1),
            DVec3::Z,
        );
        let p = DVec3::new(0.3, 0.7, -0.4);
        let via_w2c = cam.w2c_cv().transform_point3(p);
        assert!((via_w2c - cam.world_to_camera(p)).length() < 1e-12);
        assert!((cam.c2w_cv() * cam.w2c_cv() - DMat4::IDENTITY).abs_diff_eq(DMat4::ZERO, 1e-12));
        // Target is straight ahead; image "down" has a negative world-z component.
        let t = cam.world_to_camera(DVec3::new(0.5, 0.2, 0.1));
        assert!(t.x.abs() < 1e-12 && t.y.abs() < 1e-12 && t.z > 0.0);
        assert!(cam.rotation.y_axis.z < 0.0);
        // OpenGL axes: looks along −z, y up.
        let gl = cam.c2w_gl();
        assert!((gl.z_axis.truncate() + cam.forward()).length() < 1e-12);
        assert!(gl.y_axis.z > 0.0);
        assert!((cam.rotation.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn look_at_along_up_is_finite() {
        for eye in [
            DVec3::new(0.0, 0.0, 10.0),
            DVec3::new(0.0, 0.0, -10.0),
            DVec3::new(1e-9, 0.0, 5.0),
        ] {
            let cam = Camera::look_at(k(), eye, DVec3::ZERO, DVec3::Z);
            assert!(cam.c2w_cv().is_finite(), "{eye}");
            assert!((cam.rotation.determinant() - 1.0).abs() < 1e-9);
            assert!((cam.forward() - (-eye).normalize()).length() < 1e-9);
        }
    }
}
