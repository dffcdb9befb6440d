//! The augmented copies a dataset writes of every view, as declared: how many, whether the
//! clean view is kept, how geometric operations act, and the operations with their ranges.

use crate::augment::{
    BlurSpec, ColourJitterSpec, CropSpec, ErasingSpec, ExposureSpec, GammaSpec, JpegSpec,
    NoiseSpec, VignetteSpec, WarpSpec,
};
use serde::{Deserialize, Serialize};

/// The augmented copies of every view.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct AugmentSpec {
    /// Augmented copies written of each view (0: none).
    pub copies: u32,
    /// Whether the clean view is written beside its copies.
    pub keep_clean: bool,
    /// How geometric operations act.
    pub mode: GeometryMode,
    /// The operations: a geometric one acts first (on the camera, or on the rendered
    /// images); the others apply to the RGB image in the order listed.
    pub operations: Vec<Operation>,
}

/// How zoom, rotation, shift and crop act.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum GeometryMode {
    /// The camera changes (K and pose) and the view is rendered again: depth, masks and labels
    /// stay exact.
    #[default]
    Exact,
    /// The rendered images are warped, as the 3DGEN paper did: RGB bilinearly, depth and
    /// labels by nearest neighbour, pixels without a source invalid (depth 0, mask 0); the
    /// written K and pose are updated to match.
    Image,
}

/// One augmentation, with the ranges its parameters are drawn from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum Operation {
    /// Zoom, in-plane rotation and shift about the image centre.
    Warp(WarpSpec),
    /// Crop a window and resize it to the frame.
    Crop(CropSpec),
    /// Brightness, contrast, saturation and hue, as torchvision's ColorJitter.
    ColourJitter(ColourJitterSpec),
    /// Exposure in stops.
    Exposure(ExposureSpec),
    /// Gamma.
    Gamma(GammaSpec),
    /// Darker corners.
    Vignette(VignetteSpec),
    /// Sensor noise.
    Noise(NoiseSpec),
    /// Gaussian, motion or defocus blur.
    Blur(BlurSpec),
    /// JPEG re-compression.
    Jpeg(JpegSpec),
    /// Cut-out (random erasing), also written as the `erased` mask.
    Erase(ErasingSpec),
}

impl Operation {
    /// Whether it changes where pixels are (and so the camera).
    pub fn is_geometric(&self) -> bool {
        matches!(self, Operation::Warp(_) | Operation::Crop(_))
    }

    /// Checks the ranges; the error names the parameter and its value.
    pub fn validate(&self) -> Result<(), String> {
        match self {
            Operation::Warp(s) => s.validate(),
            Operation::Crop(s) => s.validate(),
            Operation::ColourJitter(s) => s.validate(),
            Operation::Exposure(s) => s.validate(),
            Operation::Gamma(s) => s.validate(),
            Operation::Vignette(s) => s.validate(),
            Operation::Noise(s) => s.validate(),
            Operation::Blur(s) => s.validate(),
            Operation::Jpeg(s) => s.validate(),
            Operation::Erase(s) => s.validate(),
        }
    }
}

impl Default for AugmentSpec {
    /// No augmentation: the clean views only.
    fn default() -> Self {
        AugmentSpec {
            copies: 0,
            keep_clean: true,
            mode: GeometryMode::Exact,
            operations: Vec::new(),
        }
    }
}

impl AugmentSpec {
    /// The 3DGEN paper's set: cut-out (2–5 % of the area, aspect 0.08–0.3, black), colour
    /// jitter (brightness, contrast, saturation × 0.8–1.2, hue ± 0.1), zoom × 0.8–1.2 and
    /// rotation 0–360°; one copy of each view beside the clean one, geometry exact.
    pub fn paper() -> Self {
        AugmentSpec {
            copies: 1,
            keep_clean: true,
            mode: GeometryMode::Exact,
            operations: vec![
                Operation::Warp(WarpSpec::paper()),
                Operation::ColourJitter(ColourJitterSpec::paper()),
                Operation::Erase(ErasingSpec::paper()),
            ],
        }
    }

    /// Checks the operations and their combination: at most one geometric operation.
    pub fn validate(&self) -> Result<(), String> {
        for op in &self.operations {
            op.validate()?;
        }
        if self.operations.iter().filter(|o| o.is_geometric()).count() > 1 {
            return Err(
                "dataset.augment: at most one geometric operation (warp or crop) per copy".into(),
            );
        }
        if self.copies == 0 && !self.keep_clean {
            return Err(
                "dataset.augment: with no copies and keep_clean = false nothing would be written"
                    .into(),
            );
        }
        Ok(())
    }

    /// Views written per camera view: the clean one if kept, and the copies.
    pub fn per_view(&self) -> u32 {
        self.copies + u32::from(self.keep_clean)
    }
}
