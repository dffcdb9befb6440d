//! How a view's images were found: which of the two visibility paths answered each set of
//! rays, and what else walked the BVH. Written into every view's record, so a user (or a
//! benchmark) can tell a rasterised view from a traced one.
//!
//! Owns: the vocabulary of that record. Must not touch: the choice of path (`trace`, `raster`,
//! `shade` make it and report it here) or files.

use serde::Serialize;

/// How the first surface along a set of rays was found. Both give the same hits (the same
/// triangle and depth for every ray; docs/rendering.md), at different costs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Visibility {
    /// Each triangle projected onto the image and tested against the rays' sample points.
    Rasterised,
    /// Each ray walked through the BVH.
    Traced,
}

/// A kind of ray traced from a surface point through the BVH.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SecondaryRays {
    /// Towards the sun's disk (shadows).
    Shadow,
    /// Over the hemisphere, for the share of sky, ground or environment a point sees.
    Occlusion,
    /// From where a point of the unloaded image moved to, back to the camera: whether the
    /// loaded structure hides it (the flow's validity).
    FlowOcclusion,
}

/// How one image (the loaded structure's, or the unloaded one's) was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
pub struct ImageVisibility {
    /// The centre ray of every pixel: depth, every label, normals and the centre colour.
    pub primary: Visibility,
    /// Anti-aliasing's four sub-pixel rays per edge pixel of the RGB image; null when none
    /// were cast (no RGB image, anti-aliasing off, or no edge).
    pub edge_rays: Option<Visibility>,
}

/// How a view's images were found.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
pub struct ViewVisibility {
    /// The loaded structure, as the view's images show it.
    #[serde(flatten)]
    pub loaded: ImageVisibility,
    /// The unloaded structure through the same camera (`rest_depth`, `rest_rgb`, `flow`); null
    /// when no output needed it.
    pub unloaded: Option<ImageVisibility>,
    /// What else was traced through the BVH for this view, in a fixed order.
    pub secondary: Vec<SecondaryRays>,
}
