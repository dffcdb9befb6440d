//! Light and backdrop of a dataset, as declared (any value may be a range to draw from).
//! The build stage draws them for each sample or view.

use crate::geometry::coordinate_in_range;
use crate::materials::Lighting;
use crate::materials::environment::EnvironmentMap;
use crate::materials::image::ImageFile;
use serde::Serialize;
use std::sync::Arc;

/// The light of a dataset. Without sun and sky, the studio lights fixed to the camera light
/// every view alike (the paper's renders); with them, the light is fixed in the world and
/// drawn per sample, so all views of a sample share one sun.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct LightSpec {
    /// Whether the studio key and fill lights, fixed to the camera, are on (default: on unless a
    /// sun or sky is given).
    pub studio: bool,
    /// A directional sun fixed in the world, if any.
    pub sun: Option<SunSpec>,
    /// Hemispherical light from the sky above and the ground below, if any.
    pub sky: Option<SkySpec>,
    /// Diffuse light from an equirectangular environment map, if any (instead of `sky`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub environment: Option<EnvironmentLightSpec>,
    /// Uniform light from every direction, linear, as a range [min, max] to draw from (default
    /// 0.12, or 0.02 with a sun or sky).
    pub ambient: [f64; 2],
    /// Whether the sun casts shadows (default: on with a sun or sky).
    pub shadows: bool,
    /// A ground plane that bounces the sun's and sky's light once onto faces turned down to
    /// it, if declared (replaces the sky's `ground` colour); without it, a dataset's `ground`
    /// bounces light from its own height and colour.
    pub ground: Option<GroundBounceSpec>,
    /// Exposure in stops (EV): linear light × 2^exposure (default 0).
    pub exposure: f64,
    /// The tone curve from linear light to the display (default clip).
    pub tone: Tone,
}

/// A ground plane bouncing light, as declared.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct GroundBounceSpec {
    /// Height of the plane (world z, metres).
    pub height: f64,
    /// sRGB colour (0–1) of the ground's albedo.
    pub albedo: [f64; 3],
}

/// Tone curves from linear light to the display.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Tone {
    /// Light above white clips to white (the paper's look).
    Clip,
    /// The ACES filmic curve as fitted by Narkowicz (2015): highlights roll off.
    Filmic,
}

/// A directional sun as declared: each number a range [min, max] drawn once per sample.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SunSpec {
    /// Angle above the horizon (radians), range.
    pub elevation: [f64; 2],
    /// Compass angle from +x towards +y (radians), range.
    pub azimuth: [f64; 2],
    /// Range of the sun's intensity, a factor on its linear colour: 1 makes a white matte face
    /// turned to a white sun fully white.
    pub intensity: [f64; 2],
    /// sRGB colour of the light, components 0–1.
    pub colour: [f64; 3],
    /// Angular diameter of the sun's disk, radians (default 0.53°, the real sun's): the
    /// width of a shadow's soft edge is the distance to its caster times this angle.
    pub diameter: f64,
    /// Shadow rays per shaded point over the disk (default 8; 1 = a hard shadow).
    pub shadow_rays: u32,
}

/// Hemispherical sky and ground light as declared: a face gets the sky colour weighted by
/// (1 + n_z)/2 and the ground colour by (1 − n_z)/2, n_z the vertical component of its normal.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SkySpec {
    /// Range of the sky's intensity, a factor on its linear sky and ground colours.
    pub intensity: [f64; 2],
    /// sRGB colour (0–1) of the sky's light from above.
    pub colour: [f64; 3],
    /// sRGB colour (0–1) of the light the ground bounces up from below.
    pub ground: [f64; 3],
    /// Occlusion rays per shaded point (default 16; 0 = no ambient occlusion): the sky and
    /// ground light reach a face only along directions the structure leaves open.
    pub occlusion_rays: u32,
}

/// An equirectangular environment map as declared: a Radiance .hdr file next to the recipe,
/// +z up, longitude from +x towards +y.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct EnvironmentSpec {
    /// Path of the map relative to the recipe's folder.
    pub file: String,
    /// blake3 hash (hex) of the file's bytes.
    pub hash: String,
    /// Factor on the map's linear radiance (default 1).
    pub intensity: f64,
    /// Turn of the map about +z, radians (default 0): what the map shows at longitude φ lies
    /// at world longitude φ + rotation.
    pub rotation: f64,
    /// The map, decoded, with its SH coefficients (not recorded).
    #[serde(skip)]
    pub map: Arc<EnvironmentMap>,
}

/// Light from an environment map as declared.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct EnvironmentLightSpec {
    /// The map and how it is placed.
    #[serde(flatten)]
    pub map: EnvironmentSpec,
    /// Occlusion rays per shaded point (default 16; 0 = no ambient occlusion): the map's light
    /// reaches a face only along directions the structure leaves open.
    pub occlusion_rays: u32,
}

/// Uniform light outdoors, where the sky already lights every face from some side.
pub const OUTDOOR_AMBIENT: f64 = 0.02;

/// The real sun's mean angular diameter, 0.53° (32 arc minutes), in radians.
pub const SUN_DIAMETER: f64 = 0.53 * std::f64::consts::PI / 180.0;

impl Default for LightSpec {
    /// The paper's look: studio lights, no sun, no shadows.
    fn default() -> Self {
        LightSpec {
            studio: true,
            sun: None,
            sky: None,
            environment: None,
            ambient: [Lighting::default().ambient; 2],
            shadows: false,
            ground: None,
            exposure: 0.0,
            tone: Tone::Clip,
        }
    }
}

impl LightSpec {
    /// Checks what the ranges alone cannot: a sun above or on the horizon's sphere and no
    /// negative light. Messages name the recipe's option.
    pub fn validate(&self) -> Result<(), String> {
        if let Some(sun) = &self.sun {
            let half_pi = std::f64::consts::FRAC_PI_2;
            if sun.elevation[0] < -half_pi || sun.elevation[1] > half_pi {
                return Err(format!(
                    "dataset.light.sun.elevation = [{}, {}] must lie within [-π/2, π/2]",
                    sun.elevation[0], sun.elevation[1]
                ));
            }
        }
        if let Some(sun) = &self.sun
            && !(0.0..=0.5).contains(&sun.diameter)
        {
            return Err(format!(
                "dataset.light.sun.diameter = {} must lie within [0, 0.5] radians (the real sun: 0.00925)",
                sun.diameter
            ));
        }
        if self.environment.is_some() && self.sky.is_some() {
            return Err(
                "dataset.light: give `sky` or `environment`, not both (the map's light replaces the sky's)"
                    .to_string(),
            );
        }
        if !(-20.0..=20.0).contains(&self.exposure) {
            return Err(format!(
                "dataset.light.exposure = {} stops must lie within [-20, 20]",
                self.exposure
            ));
        }
        if let Some(g) = &self.ground {
            coordinate_in_range(g.height, "dataset.light.ground.height")?;
        }
        for (name, [lo, _]) in [("ambient", self.ambient)]
            .into_iter()
            .chain(self.sun.iter().map(|s| ("sun.intensity", s.intensity)))
            .chain(self.sky.iter().map(|s| ("sky.intensity", s.intensity)))
            .chain(
                self.environment
                    .iter()
                    .map(|e| ("environment.intensity", [e.map.intensity; 2])),
            )
        {
            if lo < 0.0 {
                return Err(format!(
                    "dataset.light.{name} must not be negative (got {lo})"
                ));
            }
        }
        Ok(())
    }
}

impl Default for SunSpec {
    /// A sun 40° up from any direction, slightly warm.
    fn default() -> Self {
        SunSpec {
            elevation: [0.7; 2],
            azimuth: [0.0, std::f64::consts::TAU],
            intensity: [1.2; 2],
            colour: [1.0, 0.96, 0.9],
            diameter: SUN_DIAMETER,
            shadow_rays: 8,
        }
    }
}

impl Default for SkySpec {
    /// A pale blue sky over brownish ground.
    fn default() -> Self {
        SkySpec {
            intensity: [0.3; 2],
            colour: [0.75, 0.83, 0.95],
            ground: [0.4, 0.36, 0.3],
            occlusion_rays: 16,
        }
    }
}

/// What the RGB images show where no structure is. Depth, masks and labels are unaffected.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum Background {
    /// sRGB colour, components 0–1; black by default, as in the paper.
    Colour([f64; 3]),
    /// A sky gradient (sRGB colours), fixed in the world: zenith above, horizon at eye level,
    /// ground below.
    Sky {
        /// The gradient's colours.
        sky: SkyGradient,
    },
    /// A random image from a folder for each view, a random window of it filling the frame.
    Images {
        /// The folder the images come from, relative to the recipe's folder.
        images: String,
        /// Every PNG or JPEG image in the folder, in name order, with its hash.
        files: Vec<ImageRecord>,
        /// The images, decoded (not recorded).
        #[serde(skip)]
        decoded: Vec<ImageFile>,
    },
    /// An equirectangular environment map fixed in the world, looked up along each pixel's ray.
    Environment {
        /// The map and how it is placed.
        environment: EnvironmentSpec,
    },
}

/// A sky backdrop fixed in the world, sRGB colours (0–1): from the horizon at eye level up to the
/// zenith, flat ground below.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SkyGradient {
    /// sRGB colour straight up.
    pub zenith: [f64; 3],
    /// sRGB colour at the horizon (eye level).
    pub horizon: [f64; 3],
    /// sRGB colour of everything below the horizon.
    pub ground: [f64; 3],
}

impl Default for SkyGradient {
    fn default() -> Self {
        SkyGradient {
            zenith: [0.32, 0.5, 0.78],
            horizon: [0.78, 0.84, 0.9],
            ground: [0.36, 0.34, 0.3],
        }
    }
}

/// A background image as recorded in run.json.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ImageRecord {
    /// Path of the image relative to the recipe's folder, with `/` separators.
    pub file: String,
    /// blake3 hash (hex) of the file's bytes.
    pub hash: String,
}
