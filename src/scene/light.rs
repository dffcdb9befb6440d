//! Light and backdrop of a dataset, as declared (with ranges), and their draw for one sample
//! or view.

use crate::materials::image::ImageFile;
use crate::materials::srgb_to_linear;
use crate::render::{Backdrop, Lighting, Sky, Sun};
use crate::seeds::Stream;
use glam::DVec3;
use serde::Serialize;
use serde_json::{Value, json};

/// The light of a dataset. Without sun and sky, the studio lights fixed to the camera light
/// every view alike (the paper's renders); with them, the light is fixed in the world and
/// drawn per sample, so all views of a sample share one sun.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LightSpec {
    pub studio: bool,
    pub sun: Option<SunSpec>,
    pub sky: Option<SkySpec>,
    /// Uniform light, as a range to draw from.
    pub ambient: [f64; 2],
    pub shadows: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SunSpec {
    /// Angle above the horizon (radians), range.
    pub elevation: [f64; 2],
    /// Compass angle from +x towards +y (radians), range.
    pub azimuth: [f64; 2],
    pub intensity: [f64; 2],
    /// sRGB colour of the light.
    pub colour: [f64; 3],
}

#[derive(Clone, Debug, PartialEq, Serialize)]
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

impl LightSpec {
    /// The light of one sample, and what was drawn (for the JSON).
    pub fn draw(&self, stream: &mut Stream) -> (Lighting, Value) {
        let mut pick = |[lo, hi]: [f64; 2]| if lo == hi { lo } else { stream.uniform(lo, hi) };
        let ambient = pick(self.ambient);
        let sun = self.sun.as_ref().map(|s| {
            let (elevation, azimuth, intensity) =
                (pick(s.elevation), pick(s.azimuth), pick(s.intensity));
            let direction = DVec3::new(
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            );
            let light = Sun {
                direction,
                colour: s.colour.map(|c| srgb_to_linear(c) * intensity),
            };
            (light, json!({ "elevation": elevation, "azimuth": azimuth, "intensity": intensity, "direction": direction.to_array() }))
        });
        let sky = self.sky.as_ref().map(|s| {
            let intensity = pick(s.intensity);
            let light = Sky {
                sky: s.colour.map(|c| srgb_to_linear(c) * intensity),
                ground: s.ground.map(|c| srgb_to_linear(c) * intensity),
            };
            (light, json!({ "intensity": intensity }))
        });
        let defaults = Lighting::default();
        let drawn = json!({
            "studio": self.studio,
            "ambient": ambient,
            "sun": sun.as_ref().map(|s| s.1.clone()),
            "sky": sky.as_ref().map(|s| s.1.clone()),
            "shadows": self.shadows,
        });
        let lighting = Lighting {
            ambient,
            studio: defaults.studio.filter(|_| self.studio),
            sun: sun.map(|s| s.0),
            sky: sky.map(|s| s.0),
            shadows: self.shadows,
        };
        (lighting, drawn)
    }
}

/// What the RGB images show where no structure is. Depth, masks and labels are unaffected.
#[derive(Clone, Debug, PartialEq, Serialize)]
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

#[derive(Clone, Debug, PartialEq, Serialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ImageRecord {
    pub file: String,
    pub hash: String,
}

impl Background {
    /// The backdrop of one view of `frame` (width, height) pixels, and what was drawn (for the
    /// JSON).
    pub fn draw(&self, stream: &mut Stream, frame: (u32, u32)) -> (Backdrop, Value) {
        match self {
            Background::Colour(c) => (
                Backdrop::Colour(c.map(|c| (c * 255.0).round() as u8)),
                json!({ "colour": c }),
            ),
            Background::Sky { sky } => (
                Backdrop::Sky {
                    zenith: sky.zenith.map(srgb_to_linear),
                    horizon: sky.horizon.map(srgb_to_linear),
                    ground: sky.ground.map(srgb_to_linear),
                },
                json!({ "sky": sky }),
            ),
            Background::Images { decoded, .. } => {
                let chosen = &decoded[stream.integer(0, decoded.len() as i64 - 1) as usize];
                let (w, h) = (f64::from(frame.0), f64::from(frame.1));
                let (iw, ih) = (chosen.image.width() as f64, chosen.image.height() as f64);
                // The widest window with the frame's aspect that fits the image, then 50–100 %
                // of it, anywhere inside the image.
                let widest = (ih * w / (iw * h)).min(1.0);
                let width = stream.uniform(0.5, 1.0) * widest;
                let size = (width, width * iw * h / (ih * w));
                let origin = (
                    stream.uniform(0.0, 1.0 - size.0),
                    stream.uniform(0.0, 1.0 - size.1),
                );
                (
                    Backdrop::Image {
                        image: chosen.image.clone(),
                        origin,
                        size,
                    },
                    json!({ "image": chosen.name, "hash": chosen.hash, "window_origin": [origin.0, origin.1], "window_size": [size.0, size.1] }),
                )
            }
        }
    }
}
