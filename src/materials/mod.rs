//! Surface materials: what a surface looks like, described as plain data and evaluated per
//! shading point.
//!
//! A material is a base (steel, concrete, a timber species, paint, …) with a colour, a finish
//! (roughness and specular) and conditions layered on top (rust, cracks, moss, …). Text prompts
//! compile into this description (`prompt`); `procedural` evaluates it at a point of the
//! *undeformed* surface, in metres, so textures move with the deformation and procedural
//! patterns are continuous across every edge (moss, which prefers upward faces, and image
//! textures, projected along the axis nearest each face, change at creases as real ones do);
//! `cache` keeps a sample's evaluated fields in surface space for all its views; `image`
//! samples textures made elsewhere; `light` holds the light and backdrops a surface is
//! seen under, `environment` the maps of light from every direction.
//!
//! Owns: how things look — the material vocabulary, the generators, texture images, and the
//! light and backdrop values shading uses. Must not touch: geometry, cameras, recipes or
//! writing files.

pub mod cache;
pub mod environment;
pub mod ground;
pub mod image;
pub mod light;
pub mod noise;
pub mod procedural;
pub mod prompt;

pub use light::{Backdrop, EnvironmentLight, Film, GroundBounce, Lighting, Sky, Sun, ToneCurve};
pub use procedural::{Grain, MaterialDraw, Shader, Surface, SurfacePoint};

use serde::Serialize;
use std::sync::Arc;

/// How a surface looks: everything here is written to each view's JSON.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Material {
    /// The text the material was compiled from, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prompt: Option<String>,
    /// The substance, which picks the procedural pattern.
    pub base: Base,
    /// Base colour, sRGB components in [0, 1]: the paint, the plastic, the wood or the metal.
    pub colour: [f64; 3],
    /// Microfacet roughness in (0, 1]: 1 is fully matte.
    pub roughness: f64,
    /// Specular reflectance at normal incidence (about 0.04 for dielectrics, more for metals).
    pub specular: f64,
    /// Conditions layered over the base, in order.
    pub conditions: Vec<Condition>,
    /// Multiplies the size of every texture feature (1 = the material's natural size).
    pub scale: f64,
    /// Where the albedo comes from: the procedural generators or an image.
    pub texture: Texture,
}

/// The substance under any condition.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Base {
    /// A flat colour, no texture (the default, and `.colour([r, g, b])`).
    Plain,
    /// Bare structural steel, mottled by mill scale.
    Steel,
    /// Hot-dip galvanised steel: zinc spangle crystals about a centimetre across.
    GalvanisedSteel,
    /// Weathering (Corten) steel under a dark rust patina.
    WeatheringSteel,
    /// Aluminium, brushed along the piece's grain.
    Aluminium,
    /// Concrete, mottled, with small pores.
    Concrete,
    /// Timber: growth rings around a pith, figure, and fibres along the piece's grain.
    Timber(
        /// The wood species.
        Species,
    ),
    /// Plastic board, almost uniform.
    Plastic,
    /// Running-bond brickwork: 215 × 65 mm bricks, 10 mm mortar joints.
    Brick,
    /// Rubble stone masonry: irregular blocks about 0.3 m across in mortar.
    Stone,
    /// Paint over steel; the colour is the paint's.
    Painted,
    /// Open ground or paving under a structure (grass, soil, asphalt, a slab): mottled at the
    /// scale of metres and centimetres, without the joints or weathering of a built surface.
    Ground,
}

/// Wood species, for colour and ring spacing. Spacings are at `scale` 1; every length of a
/// texture is multiplied by the material's `scale`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Species {
    /// Pine: growth rings about 4 mm apart, strong contrast.
    Pine,
    /// Spruce (and fir): rings about 3 mm apart, moderate contrast.
    Spruce,
    /// Oak: rings about 2.5 mm apart, moderate contrast.
    Oak,
    /// Ash: rings about 2.5 mm apart, moderate contrast.
    Ash,
    /// Birch: fine rings about 2 mm apart, faint contrast.
    Birch,
    /// Cedar: rings about 2.5 mm apart, moderate contrast.
    Cedar,
    /// Teak: rings about 3 mm apart, moderate contrast.
    Teak,
    /// Walnut: rings about 3 mm apart, moderate contrast.
    Walnut,
    /// Mahogany: rings about 4 mm apart, low contrast.
    Mahogany,
    /// Rosewood: fine rings about 1.5 mm apart, strong contrast.
    Rosewood,
}

/// A condition of the surface with its intensity in (0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Condition {
    /// Which condition.
    pub kind: ConditionKind,
    /// How strong, in (0, 1]: "slightly" 0.3, "moderately" 0.6 (the default), "heavily" 1.0.
    pub intensity: f64,
}

/// A condition laid over a material's base.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ConditionKind {
    /// Rust patches (steel) or iron staining (other bases).
    Rusty,
    /// Rust with pitting and loss of section: darker, rougher.
    Corroded,
    /// A crack network, also written as a crack mask.
    Cracked,
    /// Faded, uneven colour.
    Weathered,
    /// Dark streaks running down the surface.
    Stained,
    /// Moss patches, mostly on upward-facing surfaces.
    Mossy,
    /// Clean and even, slightly glossier.
    New,
    /// Darker and glossier.
    Wet,
    /// Paint worn away in patches, showing the substrate.
    Worn,
}

/// Where the albedo comes from.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "source", rename_all = "snake_case")]
pub enum Texture {
    /// The procedural generators of the base and its conditions.
    Procedural,
    /// An image file tiled over the undeformed surface, `size` metres per tile.
    Image {
        /// Path of the image relative to the recipe's folder.
        file: String,
        /// blake3 of the file's bytes.
        hash: String,
        /// Edge length of one tile on the undeformed surface, metres (independent of `scale`).
        size: f64,
        /// How the file was chosen: "explicit" (named in the recipe) or "prompt" (found in the
        /// recipe's textures folder under the prompt's name).
        chosen: String,
        /// The decoded image (not recorded).
        #[serde(skip)]
        pixels: Arc<image::TextureImage>,
    },
}

impl Default for Material {
    /// Light grey, like primed steel.
    fn default() -> Self {
        Material::plain([0.62, 0.62, 0.6])
    }
}

impl Material {
    /// A flat colour (sRGB), matte.
    pub fn plain(colour: [f64; 3]) -> Self {
        Material {
            prompt: None,
            base: Base::Plain,
            colour,
            roughness: 1.0,
            specular: 0.0,
            conditions: Vec::new(),
            scale: 1.0,
            texture: Texture::Procedural,
        }
    }

    /// Linear-light base colour.
    pub fn albedo(&self) -> [f64; 3] {
        self.colour.map(srgb_to_linear)
    }

    /// Whether a metal is what is seen (rust then replaces the surface rather than staining it).
    pub fn is_metal(&self) -> bool {
        matches!(
            self.base,
            Base::Steel
                | Base::GalvanisedSteel
                | Base::WeatheringSteel
                | Base::Aluminium
                | Base::Painted
        )
    }

    /// Whether the material draws a crack network (and so has a crack mask).
    pub fn has_cracks(&self) -> bool {
        self.conditions
            .iter()
            .any(|c| c.kind == ConditionKind::Cracked)
    }
}

/// sRGB (0–1) → linear. `libm`'s pow, not the platform's, so albedos are the same bits on
/// every machine.
pub fn srgb_to_linear(s: f64) -> f64 {
    if s <= 0.040_45 {
        s / 12.92
    } else {
        libm::pow((s + 0.055) / 1.055, 2.4)
    }
}
