//! Light and backdrops as shading sees them: directions and linear radiance, fixed for one
//! sample (light) or one view (backdrop), and the film (exposure, tone curve) that turns
//! linear light into display values. Plain values, drawn by the build stage from what a
//! recipe declared and consumed by the renderer.

use super::environment::EnvironmentMap;
use super::image::TextureImage;
use glam::DVec3;
use std::sync::Arc;

/// The light of one sample. Directions point towards the light.
#[derive(Clone, Debug, PartialEq)]
pub struct Lighting {
    /// Uniform light from everywhere (linear, per channel).
    pub ambient: f64,
    /// Key and fill lights fixed to the camera (camera axes: x right, y down, z forward), so
    /// every view is lit alike; the default when a recipe sets no light.
    pub studio: Option<[(DVec3, f64); 2]>,
    /// A directional light fixed in the world.
    pub sun: Option<Sun>,
    /// Hemispherical light: `sky` from above, `ground` bounce from below.
    pub sky: Option<Sky>,
    /// Light from an environment map, if any (replaces `sky`).
    pub environment: Option<EnvironmentLight>,
    /// Whether the sun casts shadows.
    pub shadows: bool,
    /// Light bounced up once by a ground plane lit by the sun and sky, if the scene has one;
    /// without it, the sky's own `ground` colour lights faces from below.
    pub ground: Option<GroundBounce>,
    /// How linear light becomes a pixel: exposure and tone curve.
    pub film: Film,
}

/// An infinite horizontal Lambertian ground plane below the structure that bounces the sun's
/// and the sky's light once onto faces turned down to it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundBounce {
    /// Height of the plane (world z, metres).
    pub height: f64,
    /// Linear albedo of the plane, per channel.
    pub albedo: [f64; 3],
}

/// How linear radiance becomes a displayed value in [0, 1] before sRGB encoding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Film {
    /// Factor on linear radiance (2^EV).
    pub exposure: f64,
    /// The tone curve applied after exposure.
    pub tone: ToneCurve,
}

/// Tone curves from scene-linear to display-linear values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ToneCurve {
    /// Values above 1 clip to 1 (the paper's look; identity below 1).
    Clip,
    /// Narkowicz's (2015) fit of the ACES filmic curve: a toe, a shoulder rolling off towards 1.
    Filmic,
}

impl Default for Film {
    /// No exposure change, clipping: the renderer's look before exposure existed.
    fn default() -> Self {
        Film {
            exposure: 1.0,
            tone: ToneCurve::Clip,
        }
    }
}

impl Film {
    /// Display-linear value in [0, 1] of a non-negative linear radiance.
    pub fn display(&self, linear: f64) -> f64 {
        // An exposure of exactly 1 multiplies by nothing, so the default keeps every bit.
        let x = if self.exposure == 1.0 {
            linear
        } else {
            linear * self.exposure
        };
        match self.tone {
            ToneCurve::Clip => x.clamp(0.0, 1.0),
            ToneCurve::Filmic => filmic(x.max(0.0)),
        }
    }
}

/// Narkowicz's ACES fit, x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), clamped to [0, 1]
/// (it passes 1 at x ≈ 7.24 and tends to 2.51/2.43 beyond).
pub fn filmic(x: f64) -> f64 {
    if !x.is_finite() {
        return 1.0;
    }
    (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// A directional light fixed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit vector towards the sun, world axes.
    pub direction: DVec3,
    /// Linear radiance per channel.
    pub colour: [f64; 3],
    /// Angular diameter of the sun's disk, radians (0.53° for the real sun; 0 = a point).
    pub angular_diameter: f64,
    /// Shadow rays per shaded point, spread over the disk: the penumbra's steps (1 = a hard
    /// shadow along `direction`).
    pub shadow_rays: u32,
}

/// Hemispherical light: a face gets `sky` weighted by (1 + n_z)/2 and `ground` by (1 − n_z)/2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sky {
    /// Linear radiance of the sky, per channel.
    pub sky: [f64; 3],
    /// Linear radiance of the ground, per channel.
    pub ground: [f64; 3],
    /// Occlusion rays per shaded point over its hemisphere (0 = the sky reaches every face
    /// unobstructed).
    pub occlusion_rays: u32,
}

/// Diffuse light from an environment map, fixed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentLight {
    /// The map, with its SH coefficients computed once when it was read.
    pub map: Arc<EnvironmentMap>,
    /// Factor on the map's radiance.
    pub intensity: f64,
    /// Turn of the map about +z, radians: what the map shows at longitude φ lies at world
    /// longitude φ + rotation.
    pub rotation: f64,
    /// Occlusion rays per shaded point over its hemisphere (0 = the map reaches every face
    /// unobstructed).
    pub occlusion_rays: u32,
}

impl EnvironmentLight {
    /// Radiance a white Lambertian face with world normal `n` reflects under the map
    /// (irradiance / π), unoccluded.
    pub fn diffuse(&self, n: DVec3) -> [f64; 3] {
        let lit = self.map.diffuse(turn_about_z(n, -self.rotation));
        lit.map(|c| c * self.intensity)
    }
}

/// `d` turned by `angle` radians about +z (counter-clockwise seen from above).
pub fn turn_about_z(d: DVec3, angle: f64) -> DVec3 {
    if angle == 0.0 {
        return d;
    }
    let (s, c) = (libm::sin(angle), libm::cos(angle));
    DVec3::new(c * d.x - s * d.y, s * d.x + c * d.y, d.z)
}

impl Default for Lighting {
    fn default() -> Self {
        Lighting {
            ambient: 0.12,
            // Key above-left and behind the camera; fill from the right, weaker.
            studio: Some([
                (DVec3::new(-0.45, -0.6, -0.66).normalize(), 0.85),
                (DVec3::new(0.7, -0.1, -0.7).normalize(), 0.3),
            ]),
            sun: None,
            sky: None,
            environment: None,
            shadows: false,
            ground: None,
            film: Film::default(),
        }
    }
}

/// What a view shows where no structure is.
#[derive(Clone, Debug, PartialEq)]
pub enum Backdrop {
    /// sRGB 8-bit.
    Colour([u8; 3]),
    /// Linear colours: a gradient from the horizon up to the zenith, flat ground below.
    Sky {
        /// Linear colour straight up.
        zenith: [f64; 3],
        /// Linear colour at the horizon (eye level).
        horizon: [f64; 3],
        /// Linear colour of everything below the horizon.
        ground: [f64; 3],
    },
    /// A window of an image filling the frame: top-left `origin` and `size` (width, height), in
    /// image units (1 = the whole image), with square pixels.
    Image {
        /// The image, decoded.
        image: Arc<TextureImage>,
        /// Top-left corner of the window, (x, y) in image units, y down.
        origin: (f64, f64),
        /// Width and height of the window, in image units.
        size: (f64, f64),
    },
    /// An environment map fixed in the world, seen along each pixel's ray.
    Environment {
        /// The map.
        map: Arc<EnvironmentMap>,
        /// Factor on the map's radiance.
        intensity: f64,
        /// Turn of the map about +z, radians (see `EnvironmentLight::rotation`).
        rotation: f64,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `rotation` moves what the map shows at longitude φ to φ + rotation: a map bright only
    /// around +x, turned a quarter turn, lights a face looking along +y, not one along +x.
    #[test]
    fn a_turned_map_lights_the_turned_direction() {
        let (width, height) = (64, 32);
        let texels = (0..width * height)
            .map(|i| {
                let (r, c) = (i / width, i % width);
                let near_x = (c < 4 || c >= width - 4) && (12..20).contains(&r);
                [if near_x { 1.0 } else { 0.0 }; 3]
            })
            .collect();
        let light = EnvironmentLight {
            map: Arc::new(EnvironmentMap::from_texels(width, height, texels)),
            intensity: 2.0,
            rotation: std::f64::consts::FRAC_PI_2,
            occlusion_rays: 0,
        };
        let along_y = light.diffuse(DVec3::Y)[0];
        let along_x = light.diffuse(DVec3::X)[0];
        assert!(
            along_y > 0.05 && along_x < 0.25 * along_y,
            "+y {along_y}, +x {along_x}"
        );
        let turned = turn_about_z(DVec3::X, std::f64::consts::FRAC_PI_2);
        assert!((turned - DVec3::Y).length() < 1e-15, "{turned}");
    }

    #[test]
    fn the_default_film_is_clipping_and_keeps_every_bit() {
        let film = Film::default();
        for x in [-0.5, 0.0, 1e-300, 0.123_456_789, 0.999_999_999, 1.0, 7.0] {
            assert_eq!(film.display(x).to_bits(), x.clamp(0.0, 1.0).to_bits());
        }
        let brighter = Film {
            exposure: 2.0,
            ..film
        };
        assert_eq!(brighter.display(0.25), 0.5);
    }

    /// The ACES fit has a toe (darker than the identity below about 0.1), lifts mid-tones
    /// (0.18 grey → 0.27) and rolls highlights off: monotone, below white until x ≈ 7.24,
    /// white beyond.
    #[test]
    fn the_filmic_curve_rolls_highlights_off_towards_white() {
        assert_eq!(filmic(0.0), 0.0);
        assert!(filmic(0.02) < 0.02, "toe");
        assert!(
            (filmic(0.18) - 0.267).abs() < 0.005,
            "mid grey {}",
            filmic(0.18)
        );
        let mut last = 0.0;
        for i in 1..=2000 {
            let x = f64::from(i) * 0.01;
            let y = filmic(x);
            assert!(y >= last, "monotone at {x}");
            assert!(x >= 7.24 || y < 1.0, "below white at {x}: {y}");
            last = y;
        }
        assert_eq!(filmic(11.0), 1.0);
        assert_eq!(filmic(f64::INFINITY), 1.0);
    }
}
