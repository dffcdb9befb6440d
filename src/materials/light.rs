//! Light and backdrops as shading sees them: directions and linear radiance, fixed for one
//! sample (light) or one view (backdrop). Plain values, drawn by the build stage from what a
//! recipe declared and consumed by the renderer.

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
    /// Whether the sun casts shadows.
    pub shadows: bool,
}

/// A directional light fixed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit vector towards the sun, world axes.
    pub direction: DVec3,
    /// Linear radiance per channel.
    pub colour: [f64; 3],
}

/// Hemispherical light: a face gets `sky` weighted by (1 + n_z)/2 and `ground` by (1 − n_z)/2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sky {
    /// Linear radiance of the sky, per channel.
    pub sky: [f64; 3],
    /// Linear radiance of the ground, per channel.
    pub ground: [f64; 3],
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
            shadows: false,
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
}
