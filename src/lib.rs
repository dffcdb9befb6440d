#![warn(missing_docs)]
//! shmgen turns a Rhai recipe into a synthetic dataset of deformed civil structures:
//! RGB, metric planar depth, masks and exact cameras, reproducible from a seed. What each
//! pixel of a pinhole view sees is rasterised (exactly a ray through its centre); shadows,
//! distorting lenses and meshes too fine to rasterise are ray-traced through a BVH (`render`).
//!
//! Data flows one way, one module per step:
//!
//! ```text
//! recipe ─→ scene ─→ build ─→ render ─→ output
//! (Rhai)   (plain    (deform,  (BVH,     (writers, folder)
//!           data)     mesh,     rays,
//!                     label)    buffers)
//! ```
//!
//! `pipeline` drives the steps for every sample and writes the typed records; `preview` serves
//! the person writing a recipe (`watch`, `check`); `export` and `eval` serve the person using a
//! finished dataset (other tools' layouts, metrics of predictions), reading it through
//! `dataset`. Between render and output the pipeline applies the augmentations the recipe
//! declares (`augment`: image-space operations on a rendered view; geometric ones can instead
//! move the camera and render again). Below them sit the domain modules the steps use:
//! `mechanics` (beam theories, shells), `geometry` (meshes, outlines, mesh files), `materials`
//! (how surfaces, light and backdrops look) and `cameras`. `seeds` derives every random stream
//! from (seed, sample, view, name); `words` suggests corrections for typos and keeps numbers
//! in messages short.
//!
//! Imports only point down this order: main → preview → pipeline → {recipe, build, render,
//! augment, output}; main → {export, eval} → dataset (both write through output; eval reads
//! meshes with geometry); recipe → scene; build → {scene, mechanics, geometry, materials,
//! cameras}; render → {geometry, cameras, materials}; scene names the augmentation specs
//! `augment` defines. `output`, `geometry` and `augment` (but for `seeds`) import nothing else
//! of the crate; the recipe asks `output` only which outputs exist. `tests/architecture.rs`
//! checks this from the source.

pub mod augment;
pub mod build;
pub mod cameras;
pub mod dataset;
pub mod eval;
pub mod export;
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
