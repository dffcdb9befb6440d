//! Depth of field of a thin lens: the circle of confusion a point makes on the sensor when the
//! lens is focused elsewhere (Hecht, Optics, 5th ed., §5.7; Potmesil & Chakravarty 1981).
//!
//! Owns: the lens's f-number, focus distance and sensor size, and the blur diameter in pixels
//! of a point at a given planar depth. Must not touch: images (the blur itself is an image
//! operation, `augment::defocus_by_depth`), tracing or files. Depth and every label stay the
//! pinhole's: only RGB is blurred.

use super::Intrinsics;
use serde::Serialize;

/// A thin lens of aperture diameter f/N focused at a distance. The focal length in metres
/// follows from the sensor's width and the view's field of view (f = sensor width · f_x /
/// image width), so a zoomed-in view has the longer lens and the shallower focus it would.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct DepthOfField {
    /// f-number N: the aperture's diameter is the focal length over N.
    pub f_number: f64,
    /// Planar distance in sharp focus, metres.
    pub focus_distance: f64,
    /// Width of the sensor, metres (default 0.036: full frame).
    pub sensor_width: f64,
}

impl DepthOfField {
    /// Focal length in metres of a lens giving intrinsics `k` on this sensor.
    pub fn focal_length(&self, k: &Intrinsics) -> f64 {
        self.sensor_width * k.fx / f64::from(k.width)
    }

    /// Diameter in pixels of the circle of confusion of a point at planar depth `depth`
    /// (metres; 0 or infinite: at infinity, the backdrop): A·f·|d − s| / (d·(s − f)) on the
    /// sensor, A = f/N the aperture, s the focus distance, divided by the pixel pitch f/f_x.
    pub fn blur_diameter(&self, k: &Intrinsics, depth: f64) -> f64 {
        let f = self.focal_length(k);
        let (a, s) = (f / self.f_number, self.focus_distance);
        if s <= f {
            // A lens zoomed in past its focus (an exact zoom copy can lengthen f beyond what
            // the recipe's check saw) focuses nothing: everything is as blurred as allowed.
            return f64::INFINITY;
        }
        // |d − s| / d, which tends to 1 at infinity.
        let defocus = if depth > 0.0 && depth.is_finite() {
            (depth - s).abs() / depth
        } else {
            1.0
        };
        let on_sensor = a * f * defocus / (s - f);
        on_sensor * k.fx / f
    }

    /// Radius (pixels) of every pixel's circle of confusion given a planar `depth` image (0 =
    /// no surface: the backdrop, at infinity), and its distance for the gather's ordering
    /// (infinite for the backdrop).
    pub fn circles(&self, k: &Intrinsics, depth: &[f32]) -> (Vec<f32>, Vec<f32>) {
        let radius = (depth.iter())
            .map(|&d| (0.5 * self.blur_diameter(k, f64::from(d))) as f32)
            .collect();
        let distance = (depth.iter())
            .map(|&d| if d > 0.0 { d } else { f32::INFINITY })
            .collect();
        (radius, distance)
    }

    /// Checks the lens against the narrowest field of view `min_fov_y` (radians) a `width` ×
    /// `height` view may draw, where the focal length is longest: a positive f-number and
    /// sensor, and a focus beyond the focal length (a thin lens cannot focus nearer).
    pub fn validate(&self, (width, height): (u32, u32), min_fov_y: f64) -> Result<(), String> {
        let at = "dataset.camera.depth_of_field";
        for (name, value) in [
            ("f_number", self.f_number),
            ("focus_distance", self.focus_distance),
            ("sensor_width", self.sensor_width),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(format!("{at}.{name} = {value} must be a positive number"));
            }
        }
        let fy = 0.5 * f64::from(height) / libm::tan(0.5 * min_fov_y);
        let longest = self.sensor_width * fy / f64::from(width);
        if self.focus_distance <= 1.001 * longest {
            return Err(format!(
                "{at}.focus_distance = {} m must exceed the focal length ({longest:.4} m for a {} m sensor at the narrowest field of view)",
                self.focus_distance, self.sensor_width
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cameras::Distortion;

    fn intrinsics(fx: f64) -> Intrinsics {
        Intrinsics {
            width: 960,
            height: 960,
            fx,
            fy: fx,
            cx: 480.0,
            cy: 480.0,
            distortion: Distortion::default(),
        }
    }

    /// The blur circle by similar triangles from the lens equation 1/f = 1/d + 1/v: a point
    /// at d focuses at v(d) = f d/(d − f); the sensor sits at v(s); the cone of light through
    /// the aperture A meets it in a circle of diameter A·|v(d) − v(s)|/v(d).
    #[test]
    fn the_blur_circle_is_the_thin_lens_cone_cut_by_the_sensor() {
        let k = intrinsics(831.4);
        for (n, s) in [(2.8, 6.0), (8.0, 2.5), (1.4, 30.0)] {
            let lens = DepthOfField {
                f_number: n,
                focus_distance: s,
                sensor_width: 0.036,
            };
            let f = lens.focal_length(&k);
            let a = f / n;
            let image = |d: f64| f * d / (d - f);
            let pitch = f / k.fx;
            for d in [0.5, 1.0, 3.0, s, 10.0, 100.0] {
                let cone = a * (image(d) - image(s)).abs() / image(d) / pitch;
                let got = lens.blur_diameter(&k, d);
                assert!(
                    (got - cone).abs() <= 1e-9 * cone.max(1.0),
                    "N {n}, s {s}, d {d}: {got} px, the cone gives {cone} px"
                );
            }
            assert_eq!(
                lens.blur_diameter(&k, s),
                0.0,
                "sharp at the focus distance"
            );
            // At infinity the image lies at f: A·(v(s) − f)/f.
            let far = a * (image(s) - f) / f / pitch;
            assert!((lens.blur_diameter(&k, 0.0) - far).abs() < 1e-9 * far);
        }
    }

    #[test]
    fn a_focus_nearer_than_the_focal_length_is_refused() {
        let lens = DepthOfField {
            f_number: 2.0,
            focus_distance: 0.05,
            sensor_width: 0.036,
        };
        // A 2° view on a full-frame sensor is a 1 m lens.
        let err = lens.validate((960, 960), 2f64.to_radians()).unwrap_err();
        assert!(err.contains("focus_distance"), "{err}");
        assert!(lens.validate((960, 960), 1.0).is_ok());
        // Zoomed in past it anyway (f = 0.036 · 4000 / 960 = 0.15 m > 0.05 m): the widest
        // blur, never a negative or NaN circle.
        let (radius, _) = lens.circles(&intrinsics(4000.0), &[0.0, 0.05, 1.0]);
        assert!(radius.iter().all(|&r| r == f32::INFINITY), "{radius:?}");
    }
}
