//! Ray tracing of one deformed mesh (and, for the unloaded image, its undeformed twin) into
//! per-pixel buffers.
//!
//! Owns: the BVH over a scene mesh (built once, reused for all its views, and shared by
//! samples whose mesh is the same), the watertight ray–triangle test, screen-space culling,
//! rasterising the centre rays of a pinhole view (the same first hits, far cheaper; see
//! docs/rendering.md), the per-pixel geometric buffers (planar depth, hit triangle) and the
//! fields that follow the same centre ray (normals, distance along the ray, displacement
//! from the unloaded structure, optical flow from its image, and between the frames of a
//! sequence, with the true point tracks through one), texture lookup on
//! the undeformed surface (through `materials`), shading into RGB with sun, sky, studio lights
//! and shadows (soft over the sun's disk), sky occlusion and a ground's bounce (`daylight`),
//! traced per pixel or read from a per-sample lighting cache (`light_cache`),
//! exposure and tone curve, anti-aliased with fixed sub-pixel rays only where the image
//! changes, and backdrops. Must not touch: recipes, scenes, mechanics or files;
//! it sees meshes, cameras and materials only. One centre ray per pixel for every geometric
//! label; nothing here draws random numbers.

mod damage;
mod daylight;
mod fields;
mod gloss;
mod light_cache;
mod raster;
mod shade;
mod shared_meshes;
mod surfaces;
mod tiles;
mod trace;
mod tracks;
mod visibility;
mod watertight;

pub use damage::{
    DamageAt, DamageClass, DamagedPiece, DamagedShell, DamagedSurfaces, FaceSegment, Mark,
    MarkShape, PieceFace, SampleDamage, SeenMesh, ShellMark,
};
pub use fields::{Deformed, OtherFrame, displacement, flow, frame_flow, normals, ray_distance};
pub use light_cache::{CacheSettings, LightCache};
pub use shade::{Shaded, Surfaces, shade};
pub use shared_meshes::SharedTraceMeshes;
pub use surfaces::SampleSurfaces;
pub use trace::{GBuffer, NO_HIT, PixelSet, TraceMesh, Traced};
pub use tracks::{TrackPoint, TrackQuery, query_grid, track_points, track_queries};
pub use visibility::{ImageVisibility, SecondaryRays, ViewVisibility, Visibility};
