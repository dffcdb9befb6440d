//! shmgen turns a Rhai recipe into a synthetic dataset of deformed civil structures:
//! ray-traced RGB, metric planar depth, masks and exact cameras, reproducible from a seed.
//!
//! Data flows one way, one module per step:
//! `recipe` (Rhai → plain descriptions) → `scene` (plain data) → `geometry` (meshes, deformed
//! through `mechanics`) → `render` (BVH, rays, buffers; cameras from `cameras`, surfaces from
//! `materials`) → `output` (encoders and the dataset folder). `pipeline` orders the work;
//! `seeds` derives every random stream from (seed, sample, view, name); `preview` serves the
//! person writing a recipe (`watch`, `check`); `words` suggests corrections for typos.

pub mod cameras;
pub mod geometry;
pub mod materials;
pub mod mechanics;
pub mod output;
pub mod pipeline;
pub mod preview;
pub mod recipe;
pub mod render;
pub mod scene;
pub mod seeds;
pub mod words;
