//! Surface materials. Here a material is a plain colour; text prompts and procedural
//! textures come later and will compile into this same description.
//!
//! Owns: what a surface looks like (albedo). Must not touch: geometry, lights or files.

use serde::Serialize;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Material {
    /// Base colour, sRGB components in [0, 1].
    pub colour: [f64; 3],
}

impl Default for Material {
    /// Light grey, like primed steel.
    fn default() -> Self {
        Material {
            colour: [0.62, 0.62, 0.6],
        }
    }
}

impl Material {
    /// Linear-light albedo for shading.
    pub fn albedo(&self) -> [f64; 3] {
        self.colour.map(crate::render::srgb_to_linear)
    }
}
