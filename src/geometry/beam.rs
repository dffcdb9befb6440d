//! Meshing a straight beam: its section swept along the deformed axis.

use super::Mesh;
use super::sweep::{Frame3, sweep};
use crate::mechanics::{SectionFrame, SectionOutline};
use glam::{DMat3, DVec3};

/// Sweeps `outline` through the section frames (one per station) and closes both ends.
/// The beam's own frame (axis along x from 0 to `length`, y across, z up) is centred on the
/// undeformed beam and placed in the world by `rotation` and `centre`. Side faces between
/// stations are flat quads: the beam kinematics is affine across a section, so sections need
/// no interior vertices and only the length is subdivided.
pub fn beam_mesh(
    length: f64,
    frames: &[SectionFrame],
    outline: &SectionOutline,
    rotation: DMat3,
    centre: DVec3,
) -> Mesh {
    let frames: Vec<Frame3> = frames
        .iter()
        .map(|f| Frame3 {
            origin: centre + rotation * DVec3::new(f.x - 0.5 * length, 0.0, -f.v),
            // Section y stays across the beam; section z turns with the section.
            u: rotation * DVec3::Y,
            v: rotation * DVec3::new(f.sin, 0.0, f.cos),
        })
        .collect();
    sweep(outline, &frames)
}
