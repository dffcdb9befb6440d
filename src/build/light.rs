//! Drawing the light of a sample and the backdrop of a view from what the recipe declared,
//! with a record of every value drawn.

use crate::materials::{Backdrop, Lighting, Sky, Sun, srgb_to_linear};
use crate::scene::{Background, LightSpec, SkyGradient};
use crate::seeds::Stream;
use glam::DVec3;
use serde::Serialize;

/// The light values drawn for a sample.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct LightDraw {
    /// Whether the studio key and fill lights (fixed to the camera) are on.
    pub studio: bool,
    /// Uniform light, linear.
    pub ambient: f64,
    pub sun: Option<SunDraw>,
    pub sky: Option<SkyDraw>,
    /// Whether the sun casts shadows.
    pub shadows: bool,
}

/// The sun drawn for a sample.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SunDraw {
    /// Radians above the horizon.
    pub elevation: f64,
    /// Radians from +x towards +y.
    pub azimuth: f64,
    pub intensity: f64,
    /// Unit vector towards the sun, world axes.
    pub direction: [f64; 3],
}

/// The sky drawn for a sample.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SkyDraw {
    pub intensity: f64,
}

/// The backdrop drawn for a view.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum BackdropDraw {
    /// A plain colour, sRGB 0–1.
    Colour { colour: [f64; 3] },
    /// A sky gradient fixed in the world.
    Sky { sky: SkyGradient },
    /// A window of a background image: its name and blake3 hash, and the window's top-left
    /// corner and size as fractions of the image.
    Image {
        image: String,
        hash: String,
        window_origin: [f64; 2],
        window_size: [f64; 2],
    },
}

/// The light of one sample, drawn from `stream`; a fixed value (`[x, x]`) draws nothing.
pub fn draw_light(spec: &LightSpec, stream: &mut Stream) -> (Lighting, LightDraw) {
    let mut pick = |[lo, hi]: [f64; 2]| if lo == hi { lo } else { stream.uniform(lo, hi) };
    let ambient = pick(spec.ambient);
    let sun = spec.sun.as_ref().map(|s| {
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
        let drawn = SunDraw {
            elevation,
            azimuth,
            intensity,
            direction: direction.to_array(),
        };
        (light, drawn)
    });
    let sky = spec.sky.as_ref().map(|s| {
        let intensity = pick(s.intensity);
        let light = Sky {
            sky: s.colour.map(|c| srgb_to_linear(c) * intensity),
            ground: s.ground.map(|c| srgb_to_linear(c) * intensity),
        };
        (light, SkyDraw { intensity })
    });
    let drawn = LightDraw {
        studio: spec.studio,
        ambient,
        sun: sun.as_ref().map(|s| s.1.clone()),
        sky: sky.as_ref().map(|s| s.1.clone()),
        shadows: spec.shadows,
    };
    let lighting = Lighting {
        ambient,
        studio: Lighting::default().studio.filter(|_| spec.studio),
        sun: sun.map(|s| s.0),
        sky: sky.map(|s| s.0),
        shadows: spec.shadows,
    };
    (lighting, drawn)
}

/// The backdrop of one view of `frame` (width, height) pixels, drawn from `stream`.
pub fn draw_backdrop(
    background: &Background,
    stream: &mut Stream,
    frame: (u32, u32),
) -> (Backdrop, BackdropDraw) {
    match background {
        Background::Colour(c) => (
            Backdrop::Colour(c.map(|c| (c * 255.0).round() as u8)),
            BackdropDraw::Colour { colour: *c },
        ),
        Background::Sky { sky } => (
            Backdrop::Sky {
                zenith: sky.zenith.map(srgb_to_linear),
                horizon: sky.horizon.map(srgb_to_linear),
                ground: sky.ground.map(srgb_to_linear),
            },
            BackdropDraw::Sky { sky: sky.clone() },
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
                BackdropDraw::Image {
                    image: chosen.name.clone(),
                    hash: chosen.hash.clone(),
                    window_origin: [origin.0, origin.1],
                    window_size: [size.0, size.1],
                },
            )
        }
    }
}
