//! Screen-space culling of primary rays: which square tiles of a view can see the mesh.
//!
//! Owns: projecting BVH boxes through a camera into pixel rectangles and marking the tiles
//! they touch. Must not touch: rays or hits. Culling only skips pixels whose centre ray
//! provably misses every box, so the traced buffers are exactly those of tracing every pixel.
//!
//! Why boxes of the BVH and not only the mesh's bounds: a slender beam seen along a diagonal
//! fills a few per cent of its bounding rectangle, and every ray in that rectangle would
//! otherwise walk the BVH to find nothing. Boxes a few levels down follow the silhouette.

use crate::cameras::Camera;
use glam::DVec3;
use obvhs::bvh2::Bvh2;
use std::ops::Range;

/// Side of a tile, pixels. Rays are traced tile by tile, so neighbouring rays walk the same
/// BVH nodes while they are in cache.
pub const TILE: usize = 8;

/// A node whose projection is at most this many tiles is marked whole rather than split.
const SMALL: f64 = 4.0 * (TILE * TILE) as f64;

/// Deepest level whose boxes are projected: beyond it, marking costs more than it saves.
const MAX_DEPTH: u32 = 12;

/// Tiles of a view that may see the mesh, row-major (`columns` per tile row).
pub struct TileMask {
    columns: usize,
    marked: Vec<bool>,
}

/// Pixel rows and columns a box may cover through a camera.
pub type PixelRect = (Range<usize>, Range<usize>);

impl TileMask {
    /// No tile marked, for a `width` × `height` image.
    fn empty(width: usize, height: usize) -> Self {
        let columns = width.div_ceil(TILE);
        TileMask {
            columns,
            marked: vec![false; columns * height.div_ceil(TILE)],
        }
    }

    /// Marks every tile touching the pixel rectangle.
    fn mark(&mut self, (rows, cols): PixelRect) {
        if rows.is_empty() || cols.is_empty() {
            return;
        }
        for tile_row in rows.start / TILE..rows.end.div_ceil(TILE) {
            let line = &mut self.marked[tile_row * self.columns..][..self.columns];
            line[cols.start / TILE..cols.end.div_ceil(TILE)].fill(true);
        }
    }

    /// The marked tiles of tile row `tile_row`, by tile column.
    pub fn row(&self, tile_row: usize) -> impl Iterator<Item = usize> + '_ {
        self.marked[tile_row * self.columns..][..self.columns]
            .iter()
            .enumerate()
            .filter_map(|(column, &marked)| marked.then_some(column))
    }
}

/// The tiles of `camera`'s image that the BVH's boxes (vertices relative to `anchor`) may
/// cover. `bounds` projects a box to its pixel rectangle, None when part of it is at or
/// behind the camera. A lens that distorts bends box edges, so there only the root's
/// rectangle (`bounds` follows its edges) is used.
pub fn visible_tiles(
    bvh: &Bvh2,
    camera: &Camera,
    bounds: impl Fn(DVec3, DVec3) -> Option<PixelRect>,
) -> TileMask {
    let k = camera.intrinsics;
    let (width, height) = (k.width as usize, k.height as usize);
    let mut mask = TileMask::empty(width, height);
    let full = (0..height, 0..width);
    let node_box = |i: usize| {
        let aabb = bvh.nodes[i].aabb;
        (aabb.min.as_dvec3(), aabb.max.as_dvec3())
    };
    if bvh.nodes.is_empty() {
        return mask;
    }
    if !k.distortion.is_none() {
        let (lo, hi) = node_box(0);
        mask.mark(bounds(lo, hi).unwrap_or(full));
        return mask;
    }
    let mut stack = vec![(0usize, 0u32)];
    while let Some((i, depth)) = stack.pop() {
        let node = &bvh.nodes[i];
        let (lo, hi) = node_box(i);
        let rect = bounds(lo, hi);
        let small = rect
            .as_ref()
            .is_some_and(|(r, c)| (r.len() * c.len()) as f64 <= SMALL);
        if node.prim_count > 0 || depth >= MAX_DEPTH || small {
            mask.mark(rect.unwrap_or_else(|| full.clone()));
        } else if rect
            .as_ref()
            .is_none_or(|(r, c)| !r.is_empty() && !c.is_empty())
        {
            // Split what is on screen (or reaches behind the camera, where a child may not).
            let first = node.first_index as usize;
            stack.extend([(first, depth + 1), (first + 1, depth + 1)]);
        }
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marking_covers_every_tile_a_rectangle_touches() {
        let mut mask = TileMask::empty(20, 17);
        mask.mark((7..9, 15..17));
        let rows: Vec<Vec<usize>> = (0..3).map(|r| mask.row(r).collect()).collect();
        assert_eq!(rows, vec![vec![1, 2], vec![1, 2], vec![]]);
        mask.mark((16..17, 0..1));
        assert_eq!(mask.row(2).collect::<Vec<_>>(), vec![0]);
        mask.mark((3..3, 0..20));
        assert_eq!(
            mask.row(0).collect::<Vec<_>>(),
            vec![1, 2],
            "empty rectangle"
        );
    }
}
