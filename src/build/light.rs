//! Drawing the light of a sample and the backdrop of a view from what the recipe declared,
//! with a record of every value drawn.

use crate::materials::{
    Backdrop, EnvironmentLight, Film, GroundBounce, Lighting, Sky, Sun, ToneCurve, srgb_to_linear,
};
use crate::scene::{Background, EnvironmentSpec, LightSpec, SkyGradient, Tone};
use crate::seeds::Stream;
use glam::DVec3;
use serde::Serialize;

/// The light values drawn for a sample.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct LightDraw {
    /// Whether the studio key and fill lights (fixed to the camera) are on.
    pub studio: bool,
    /// Uniform light from every direction, linear (added to every face's irradiance).
    pub ambient: f64,
    /// The sun drawn, if the dataset has one.
    pub sun: Option<SunDraw>,
    /// The sky drawn, if the dataset has one.
    pub sky: Option<SkyDraw>,
    /// The environment map lighting the sample, if the dataset has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub environment: Option<EnvironmentDraw>,
    /// Whether the sun casts shadows.
    pub shadows: bool,
}

/// An environment map as recorded: which file, and how it was placed.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct EnvironmentDraw {
    /// Path of the map relative to the recipe's folder.
    pub environment: String,
    /// blake3 hash (hex) of the file's bytes.
    pub hash: String,
    /// Factor on the map's linear radiance.
    pub intensity: f64,
    /// Turn of the map about +z, radians.
    pub rotation: f64,
}

impl EnvironmentDraw {
    fn of(spec: &EnvironmentSpec) -> Self {
        EnvironmentDraw {
            environment: spec.file.clone(),
            hash: spec.hash.clone(),
            intensity: spec.intensity,
            rotation: spec.rotation,
        }
    }
}

/// The sun drawn for a sample.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SunDraw {
    /// Angle of the sun above the horizon, radians.
    pub elevation: f64,
    /// Compass angle of the sun from +x towards +y, radians.
    pub azimuth: f64,
    /// Intensity drawn: a factor on the sun's linear colour.
    pub intensity: f64,
    /// Unit vector towards the sun, world axes.
    pub direction: [f64; 3],
}

/// The sky drawn for a sample.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct SkyDraw {
    /// Intensity drawn: a factor on the sky's and the ground's linear colours.
    pub intensity: f64,
}

/// The backdrop drawn for a view.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum BackdropDraw {
    /// A plain colour, sRGB 0–1.
    Colour {
        /// sRGB colour, components 0–1.
        colour: [f64; 3],
    },
    /// A sky gradient fixed in the world.
    Sky {
        /// The gradient's colours.
        sky: SkyGradient,
    },
    /// A window of a background image: its name and blake3 hash, and the window's top-left
    /// corner and size as fractions of the image.
    Image {
        /// Path of the image relative to the recipe's folder.
        image: String,
        /// blake3 hash (hex) of the file's bytes.
        hash: String,
        /// Top-left corner of the window, (x, y) as fractions of the image's width and height, y
        /// down.
        window_origin: [f64; 2],
        /// Width and height of the window, as fractions of the image's width and height.
        window_size: [f64; 2],
    },
    /// An environment map fixed in the world.
    Environment(EnvironmentDraw),
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
            angular_diameter: s.diameter,
            shadow_rays: s.shadow_rays,
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
            occlusion_rays: s.occlusion_rays,
        };
        (light, SkyDraw { intensity })
    });
    let drawn = LightDraw {
        studio: spec.studio,
        ambient,
        sun: sun.as_ref().map(|s| s.1.clone()),
        sky: sky.as_ref().map(|s| s.1.clone()),
        environment: spec
            .environment
            .as_ref()
            .map(|e| EnvironmentDraw::of(&e.map)),
        shadows: spec.shadows,
    };
    let lighting = Lighting {
        ambient,
        studio: Lighting::default().studio.filter(|_| spec.studio),
        sun: sun.map(|s| s.0),
        sky: sky.map(|s| s.0),
        environment: spec.environment.as_ref().map(|e| EnvironmentLight {
            map: e.map.map.clone(),
            intensity: e.map.intensity,
            rotation: e.map.rotation,
            occlusion_rays: e.occlusion_rays,
        }),
        shadows: spec.shadows,
        ground: spec.ground.as_ref().map(|g| GroundBounce {
            height: g.height,
            albedo: g.albedo.map(srgb_to_linear),
        }),
        film: Film {
            exposure: libm::exp2(spec.exposure),
            tone: match spec.tone {
                Tone::Clip => ToneCurve::Clip,
                Tone::Filmic => ToneCurve::Filmic,
            },
        },
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
        Background::Environment { environment } => (
            Backdrop::Environment {
                map: environment.map.clone(),
                intensity: environment.intensity,
                rotation: environment.rotation,
            },
            BackdropDraw::Environment(EnvironmentDraw::of(environment)),
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
