//! A built sample's geometry as the per-sample writers read it: the loaded and unloaded meshes
//! (one vertex list order, one triangle list) with part ids, and points drawn on the loaded
//! surface from the sample's own stream, so they are the same on any thread or shard.

use crate::build::{BuiltSample, StructureMesh};
use crate::output::{MeshLayer, PointLayer, SampleLayers};
use crate::scene::DatasetSpec;
use crate::seeds::{self, Scope, Stream};
use glam::DVec3;

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
            positions: drawn.iter().map(|(p, _)| *p).collect(),
            normals: drawn.iter().map(|(_, n)| n.as_vec3().to_array()).collect(),
        }
    }
}
