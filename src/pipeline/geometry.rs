//! A built sample's geometry as the per-sample writers read it: the loaded and unloaded meshes
//! (one vertex list order, one triangle list) with part ids, and points drawn on the loaded
//! surface from the sample's own stream, so they are the same on any thread or shard, coloured
//! by the material's albedo where they lie.

use crate::augment::srgb;
use crate::build::{BuiltSample, StructureMesh};
use crate::output::{MeshLayer, PointLayer, SampleLayers};
use crate::render::{SampleSurfaces, Surfaces};
use crate::scene::DatasetSpec;
use crate::seeds::{self, Scope, Stream};
use glam::DVec3;
use rayon::prelude::*;

/// The geometry of one sample of a dataset: its structures, without a ground.
pub struct SampleGeometry<'a> {
    dataset: &'a DatasetSpec,
    sample: &'a BuiltSample,
    /// The structures' loaded mesh.
    mesh: StructureMesh<'a>,
    /// The unloaded position of each of its vertices.
    rest: &'a [DVec3],
    /// Part id of every triangle, as the segmentation images number parts (from 1).
    parts: Vec<u32>,
}

impl<'a> SampleGeometry<'a> {
    /// The geometry of `sample`, a sample of `dataset`.
    pub fn new(dataset: &'a DatasetSpec, sample: &'a BuiltSample) -> Self {
        let (mesh, rest) = sample.structure_mesh();
        let parts = &sample.part[..mesh.triangles.len()];
        SampleGeometry {
            dataset,
            sample,
            parts: parts.iter().map(|p| p + 1).collect(),
            mesh,
            rest,
        }
    }
}

impl SampleLayers for SampleGeometry<'_> {
    fn mesh(&self) -> MeshLayer<'_> {
        MeshLayer {
            positions: &self.mesh.positions,
            triangles: &self.mesh.triangles,
            parts: &self.parts,
        }
    }

    fn rest_mesh(&self) -> MeshLayer<'_> {
        MeshLayer {
            positions: self.rest,
            ..self.mesh()
        }
    }

    fn points(&self) -> PointLayer {
        let (dataset, sample) = (self.dataset, self.sample);
        let mut stream = Stream::new(dataset.seed, Scope::Sample(sample.index), seeds::POINTS);
        // A surface without area (every triangle degenerate) has no point to draw.
        let drawn = self
            .mesh
            .sample_surface(dataset.points as usize, || stream.unit())
            .unwrap_or_default();
        PointLayer {
            positions: drawn.iter().map(|s| s.position).collect(),
            normals: drawn
                .iter()
                .map(|s| s.normal.as_vec3().to_array())
                .collect(),
            colours: self.colours(drawn.iter().map(|s| (s.triangle, s.position)).collect()),
        }
    }
}

impl SampleGeometry<'_> {
    /// The material's albedo at each drawn point as sRGB bytes: the surface's own colour,
    /// without light or shadow, evaluated where the renderer evaluates it (on the unloaded
    /// surface under the point). Texture detail finer than the points' mean spacing, √(area /
    /// points), is averaged out as a pixel of that size would average it: a point stands for
    /// the patch around it. `drawn` holds each point's triangle and position.
    fn colours(&self, drawn: Vec<(usize, DVec3)>) -> Vec<[u8; 3]> {
        let sample = self.sample;
        let surfaces = SampleSurfaces {
            mesh: &self.mesh,
            rest: self.rest,
            piece: &sample.piece,
            pieces: &sample.pieces,
            shaders: &sample.shaders,
            // Points take their colours from the material itself, as they always have.
            cache: None,
        };
        let spacing = (self.mesh.area() / drawn.len().max(1) as f64).sqrt();
        drawn
            .par_iter()
            .map(|&(triangle, position)| {
                let albedo = surfaces.at(triangle as u32, position, spacing).albedo;
                albedo.map(|c| srgb::encode(c as f32))
            })
            .collect()
    }
}
