//! Light and backdrop of a dataset, as declared (any value may be a range to draw from).
//! The build stage draws them for each sample or view.

use crate::materials::Lighting;
use crate::materials::image::ImageFile;
use serde::Serialize;

/// The light of a dataset. Without sun and sky, the studio lights fixed to the camera light
/// every view alike (the paper's renders); with them, the light is fixed in the world and
/// drawn per sample, so all views of a sample share one sun.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct LightSpec {
    pub studio: bool,
    pub sun: Option<SunSpec>,
    pub sky: Option<SkySpec>,
    /// Uniform light, as a range to draw from.
    pub ambient: [f64; 2],
    pub shadows: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SunSpec {
    /// Angle above the horizon (radians), range.
    pub elevation: [f64; 2],
    /// Compass angle from +x towards +y (radians), range.
    pub azimuth: [f64; 2],
    pub intensity: [f64; 2],
    /// sRGB colour of the light.
    pub colour: [f64; 3],
}

#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SkySpec {
    pub intensity: [f64; 2],
    /// sRGB colours of the sky's light from above and the ground's from below.
    pub colour: [f64; 3],
    pub ground: [f64; 3],
}

/// Uniform light outdoors, where the sky already lights every face from some side.
pub const OUTDOOR_AMBIENT: f64 = 0.02;

impl Default for LightSpec {
    /// The paper's look: studio lights, no sun, no shadows.
    fn default() -> Self {
        LightSpec {
            studio: true,
            sun: None,
            sky: None,
            ambient: [Lighting::default().ambient; 2],
            shadows: false,
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
        for (name, [lo, _]) in [("ambient", self.ambient)]
            .into_iter()
            .chain(self.sun.iter().map(|s| ("sun.intensity", s.intensity)))
            .chain(self.sky.iter().map(|s| ("sky.intensity", s.intensity)))
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
        }
    }
}

/// What the RGB images show where no structure is. Depth, masks and labels are unaffected.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum Background {
    /// sRGB colour; black by default, as in the paper.
    Colour([f64; 3]),
    /// A sky gradient (sRGB colours), fixed in the world: zenith above, horizon at eye level,
    /// ground below.
    Sky { sky: SkyGradient },
    /// A random image from a folder for each view, a random window of it filling the frame.
    Images {
        images: String,
        files: Vec<ImageRecord>,
        #[serde(skip)]
        decoded: Vec<ImageFile>,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SkyGradient {
    pub zenith: [f64; 3],
    pub horizon: [f64; 3],
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
    pub file: String,
    pub hash: String,
}
