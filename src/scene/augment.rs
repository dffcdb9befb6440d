//! The augmented copies a dataset writes of every view, as declared: how many, whether the
//! clean view is kept, how geometric operations act, and the operations with their ranges.

// The specs are re-exported: recipes build them, and read nothing else from `augment`.
pub use crate::augment::{
    BlurSpec, ColourJitterSpec, CropSpec, ErasingSpec, ExposureSpec, Fill, GammaSpec, JpegSpec,
    NoiseSpec, Range, SigmaUnit, VignetteSpec, WarpSpec,
};
use crate::cameras::CameraRig;
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

    /// Its `op` name in a recipe.
    pub fn name(&self) -> &'static str {
        match self {
            Operation::Warp(_) => "warp",
            Operation::Crop(_) => "crop",
            Operation::ColourJitter(_) => "colour_jitter",
            Operation::Exposure(_) => "exposure",
            Operation::Gamma(_) => "gamma",
            Operation::Vignette(_) => "vignette",
            Operation::Noise(_) => "noise",
            Operation::Blur(_) => "blur",
            Operation::Jpeg(_) => "jpeg",
            Operation::Erase(_) => "erase",
        }
    }

    /// Checks the ranges; the error names the parameter by its path under `at` (the
    /// operation's place in the recipe) and shows its value.
    pub fn validate(&self, at: &str) -> Result<(), String> {
        match self {
            Operation::Warp(s) => s.validate(at),
            Operation::Crop(s) => s.validate(at),
            Operation::ColourJitter(s) => s.validate(at),
            Operation::Exposure(s) => s.validate(at),
            Operation::Gamma(s) => s.validate(at),
            Operation::Vignette(s) => s.validate(at),
            Operation::Noise(s) => s.validate(at),
            Operation::Blur(s) => s.validate(at),
            Operation::Jpeg(s) => s.validate(at),
            Operation::Erase(s) => s.validate(at),
        }
    }
}

/// Every operation's `op` name, for suggestions when a recipe misspells one.
pub const OPERATION_NAMES: [&str; 10] = [
    "warp",
    "crop",
    "colour_jitter",
    "exposure",
    "gamma",
    "vignette",
    "noise",
    "blur",
    "jpeg",
    "erase",
];

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
        for (i, op) in self.operations.iter().enumerate() {
            op.validate(&operation_path(i, op.name()))?;
        }
        let geometric: Vec<String> = (self.operations.iter().enumerate())
            .filter(|(_, op)| op.is_geometric())
            .map(|(i, op)| operation_path(i, op.name()))
            .collect();
        if let [first, second, ..] = geometric.as_slice() {
            return Err(format!(
                "{first} and {second}: at most one geometric operation (warp or crop) per copy"
            ));
        }
        if self.copies == 0 && !self.keep_clean {
            return Err(
                "dataset.augment: with no copies and keep_clean = false nothing would be written"
                    .into(),
            );
        }
        Ok(())
    }

    /// Checks the operations against the cameras they act on: an exact warp that zooms out
    /// or shifts renders the lens beyond the clean frame's corners, where it must still be
    /// one-to-one (see [`CameraRig::validate_widened`]).
    pub fn validate_with(&self, rig: &CameraRig) -> Result<(), String> {
        if self.copies == 0 || self.mode != GeometryMode::Exact {
            return Ok(());
        }
        for (i, op) in self.operations.iter().enumerate() {
            let Operation::Warp(warp) = op else { continue };
            if warp.probability == 0.0 {
                continue;
            }
            let farthest = |r: &Range| r.bounds().0.abs().max(r.bounds().1.abs());
            let (zoom, shift) = (
                warp.zoom.bounds().0,
                [farthest(&warp.shift_x), farthest(&warp.shift_y)],
            );
            let what = format!(
                "{}.zoom = {} with shifts up to ({}, {})",
                operation_path(i, op.name()),
                warp.zoom,
                shift[0],
                shift[1]
            );
            rig.validate_widened(zoom, shift, &what)?;
        }
        Ok(())
    }

    /// Views written per camera view: the clean one if kept, and the copies.
    pub fn per_view(&self) -> u32 {
        self.copies + u32::from(self.keep_clean)
    }
}

/// Where operation `i` (named `op`) sits in a recipe, as messages name it.
pub fn operation_path(i: usize, op: &str) -> String {
    format!("dataset.augment.operations[{i}] ({op})")
}
