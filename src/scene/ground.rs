//! The ground a sample stands on, as declared: what it is made of, where it lies and whether
//! the geometric outputs see it. The build stage turns it into a flat square of real geometry
//! under the structures; nothing here meshes, draws or traces.

use crate::materials::Material;
use serde::Serialize;

/// Part name of the ground in `segmentation.part_ids` (and the `ground` instance).
pub const GROUND_PART: &str = "ground";

/// A flat ground under the structures. The RGB image always shows it; `in_depth` says whether
/// the per-pixel geometric outputs do too.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct GroundSpec {
    /// What the ground is, from its prompt ("grass", "gravel", "asphalt", "concrete slab",
    /// "soil", "water").
    pub material: Material,
    /// Height of the ground plane, metres (world z); absent: the lowest point of the sample's
    /// structures (their footings, columns' bases, drawn supports), so they stand on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
    /// Whether depth, normals, ray distance, displacement, flow and the unloaded depth see the
    /// ground (true) or hold 0 there, as for the background (false, the default: the
    /// structure's depth alone, as the paper's). The mask is the structure's either way; the
    /// part and instance images always label the ground.
    pub in_depth: bool,
}

/// Half the side of the ground square for a scene whose bounding sphere has `radius` and
/// whose centre lies `depth` metres above the ground: far enough that its edge lies within a
/// pixel of the horizon for a camera that frames the scene (from a height h above the
/// ground, a half side of 1000 h dips the edge 0.06° below the horizon: 0.9 px at 960 px over
/// 60°), and at least 1 km. The camera is taken a radius above the scene's centre, and at
/// least 2 radii above the ground (the size for a ground at the structures' feet, unchanged);
/// a ground far below is as far below the camera, so its square grows with that depth.
/// Depth stays exact that far out: it comes from each triangle's plane in f64.
pub fn ground_radius(radius: f64, depth: f64) -> f64 {
    let camera_height = (2.0 * radius).max(depth + radius);
    (1000.0 * camera_height).max(1000.0)
}
