//! Traced meshes shared between samples whose meshes are the same: an imported mesh that no
//! load moves and no draw changes has its triangles, planes and solids (and its BVH, once a
//! ray needs one) prepared once per run instead of once per sample (on a 10⁶-triangle mesh
//! they cost as much as a view, the BVH as several).
//!
//! Owns: recognising a mesh already prepared (by a BLAKE3 fingerprint of its vertex and index
//! bytes) and holding the latest one. Must not touch: how a mesh is prepared, its BVH built or
//! traced. A shared traced mesh is the one the sample would have prepared (preparing, and the
//! BVH's build, are pure functions of the mesh), so sharing changes no output byte.

use super::TraceMesh;
use crate::geometry::Mesh;
use std::sync::{Arc, Mutex, OnceLock};

/// A traced mesh being prepared or prepared, shared by the samples that ask for it.
type Slot = Arc<OnceLock<Arc<TraceMesh>>>;

/// The traced mesh most recently asked for. Samples under way at once (one per thread) that
/// ask for the same mesh wait for one preparation; a different mesh replaces it, so at most
/// one traced mesh outlives the samples that used it.
#[derive(Default)]
pub struct SharedTraceMeshes {
    latest: Mutex<Option<(blake3::Hash, Slot)>>,
}

impl SharedTraceMeshes {
    /// `mesh`, whose first `core` triangles are the structures, prepared for tracing (see
    /// `TraceMesh::build_with_core`) unless the latest mesh asked for is the same.
    pub fn get(&self, mesh: &Mesh, core: usize) -> Arc<TraceMesh> {
        let key = fingerprint(mesh, core);
        let slot = {
            let mut latest = self.latest.lock().unwrap_or_else(|e| e.into_inner());
            match &*latest {
                Some((known, slot)) if *known == key => slot.clone(),
                _ => {
                    let slot = Slot::default();
                    *latest = Some((key, slot.clone()));
                    slot
                }
            }
        };
        slot.get_or_init(|| Arc::new(TraceMesh::build_with_core(mesh, core)))
            .clone()
    }
}

/// BLAKE3 of the core count, the vertex positions' bits and the triangles' indices.
fn fingerprint(mesh: &Mesh, core: usize) -> blake3::Hash {
    let mut hasher = blake3::Hasher::new();
    hasher.update(&(core as u64).to_le_bytes());
    hasher.update(&(mesh.positions.len() as u64).to_le_bytes());
    // Bytes gathered in blocks: one hasher call per value would cost more than the hashing.
    let mut block = Vec::with_capacity(BLOCK);
    let mut feed = |bytes: &[u8]| {
        block.extend_from_slice(bytes);
        if block.len() >= BLOCK {
            hasher.update(&block);
            block.clear();
        }
    };
    for p in &mesh.positions {
        for c in p.to_array() {
            feed(&c.to_bits().to_le_bytes());
        }
    }
    for t in &mesh.triangles {
        for i in t {
            feed(&i.to_le_bytes());
        }
    }
    hasher.update(&block);
    hasher.finalize()
}

/// Bytes handed to the hasher at a time.
const BLOCK: usize = 1 << 16;

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn triangle(z: f64) -> Mesh {
        Mesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(0.0, 1.0, z)],
            triangles: vec![[0, 1, 2]],
        }
    }

    #[test]
    fn the_same_mesh_is_prepared_once_and_any_change_anew() {
        let shared = SharedTraceMeshes::default();
        let first = shared.get(&triangle(0.0), 1);
        assert!(Arc::ptr_eq(&first, &shared.get(&triangle(0.0), 1)));
        // The least change of a coordinate, the core count or the winding is another mesh.
        let moved = shared.get(&triangle(f64::from_bits(1)), 1);
        assert!(!Arc::ptr_eq(&first, &moved));
        assert!(!Arc::ptr_eq(
            &moved,
            &shared.get(&triangle(f64::from_bits(1)), 0)
        ));
        let mut turned = triangle(0.0);
        turned.triangles[0] = [0, 2, 1];
        assert_ne!(fingerprint(&turned, 1), fingerprint(&triangle(0.0), 1));
    }
}
