//! Ray tracing of one deformed mesh into per-pixel buffers.
//!
//! Owns: the BVH over a scene mesh (built once, reused for all its views), the watertight
//! ray–triangle test, screen-space culling, the per-pixel geometric buffers (planar depth,
//! hit triangle) and Lambert shading into RGB, anti-aliased with fixed sub-pixel rays only where
//! the image changes. Must not touch: recipes, mechanics or files. One centre ray per pixel for
//! every geometric label; nothing here is random.

mod shade;
mod trace;
mod watertight;

pub use shade::{Lighting, shade, srgb_to_linear};
pub use trace::{GBuffer, NO_HIT, TraceMesh};
