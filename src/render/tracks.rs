//! True point tracks through a sequence: query points chosen on the first frame's image (the
//! structure pixels' centres on a regular grid) and, in any frame, where each one's material
//! point is in that frame's image and whether it is seen there.
//!
//! A frame is computed on its own: the query points are found again from the first frame's
//! structure and camera by tracing only the query pixels' rays, so a process rendering frame
//! 120 never needs frame 0's images. A query point is carried to a frame exactly as the flow
//! between frames carries a pixel (`fields::carried_into`): found on that frame's unloaded mesh
//! by its unloaded position, carried with that frame's loaded vertices, projected through that
//! frame's camera, occlusion-checked with the flow's tolerance.

use super::fields::{
    Deformed, MaterialPoint, OtherFrame, Sighting, carried_into, material_point, sighting,
};
use crate::cameras::Camera;

/// A query point: the pixel of the first frame's image (row, col) whose centre it is, and the
/// material point that pixel's centre ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackQuery {
    /// (row, col) of the pixel on the first frame's image.
    pub pixel: (u32, u32),
    point: MaterialPoint,
}

/// Where a query point is in one frame's image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrackPoint {
    /// Seen at (x, y), pixels, the pixel-centre convention of the camera record ((0.5, 0.5) is
    /// the centre of the top-left pixel).
    Visible([f64; 2]),
    /// Projects to (x, y) but is hidden there by a nearer surface, or lies outside the frame.
    Occluded([f64; 2]),
    /// Has no image in this frame: behind the camera, or no face of this frame holds it.
    Lost,
}

/// The pixels of a `width` × `height` image whose centres are candidate queries: rows and
/// columns `stride / 2`, `stride / 2 + stride`, ..., in row-major order.
pub fn query_grid(width: u32, height: u32, stride: u32) -> impl Iterator<Item = (u32, u32)> {
    let stride = stride.max(1);
    let first = stride / 2;
    let rows = (first..height).step_by(stride as usize);
    rows.flat_map(move |row| {
        (first..width)
            .step_by(stride as usize)
            .map(move |col| (row, col))
    })
}

/// The query points of the first frame: each pixel of `query_grid` whose centre ray through
/// `camera` first meets a structure (a triangle below `structure_triangles` of `first`; a
/// ground or nothing is no query), in grid order.
pub fn track_queries(
    first: &Deformed,
    camera: &Camera,
    structure_triangles: usize,
    stride: u32,
) -> Vec<TrackQuery> {
    let k = camera.intrinsics;
    query_grid(k.width, k.height, stride)
        .filter_map(|pixel| {
            let (row, col) = pixel;
            let (depth, tri) = first
                .traced
                .first_hit(camera, k.ray_through_pixel(row, col))?;
            if tri as usize >= structure_triangles {
                return None;
            }
            let point = material_point(first, camera, pixel, tri, f64::from(depth))?;
            Some(TrackQuery { pixel, point })
        })
        .collect()
}

/// Where each query is in frame `here` (its structures and its camera).
pub fn track_points(queries: &[TrackQuery], here: &OtherFrame) -> Vec<TrackPoint> {
    queries
        .iter()
        .map(|query| {
            let Some(moved) = carried_into(here, &query.point) else {
                return TrackPoint::Lost;
            };
            match sighting(&here.camera, here.deformed.traced, moved) {
                Sighting::Seen(xy) => TrackPoint::Visible(xy),
                Sighting::Hidden(xy) | Sighting::Outside(xy) => TrackPoint::Occluded(xy),
                Sighting::Behind => TrackPoint::Lost,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_starts_half_a_stride_in_and_steps_by_the_stride() {
        let pixels: Vec<_> = query_grid(10, 5, 4).collect();
        assert_eq!(pixels, [(2, 2), (2, 6)]);
        assert_eq!(query_grid(3, 2, 1).count(), 6);
    }
}
