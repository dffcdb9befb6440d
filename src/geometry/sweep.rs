//! Sweeping a section outline through a sequence of frames: the one mesher behind beams and
//! every primitive. Consecutive frames are joined by flat quads on each outline loop, and the
//! first and last frames are closed by the outline's cap triangulation, so the result is closed
//! and consistently oriented whenever the frames advance along u × v.

use super::outline::SectionOutline;
use super::{MAX_TRIANGLES, Mesh};
use glam::{DVec2, DVec3};

/// Where the outline's (u, v) coordinates land: `origin + p.x·u + p.y·v`. The axes carry any
/// scale (a frustum's frames shrink); a zero scale collapses a ring to a point (a cone's apex).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame3 {
    /// Where the outline's origin lands.
    pub origin: DVec3,
    /// Where the outline's unit x lands, relative to `origin`.
    pub u: DVec3,
    /// Where the outline's unit y lands, relative to `origin`.
    pub v: DVec3,
}

impl Frame3 {
    /// The 3D position of outline point `p`.
    pub fn place(&self, p: DVec2) -> DVec3 {
        self.origin + p.x * self.u + p.y * self.v
    }
}

/// The closed mesh of `outline` swept through `frames` (at least two): quads between consecutive
/// frames, caps on the first and last. Fails, before allocating anything, when the mesh would
/// exceed the triangle budget.
pub fn sweep(outline: &SectionOutline, frames: &[Frame3]) -> Result<Mesh, String> {
    let ring: Vec<DVec2> = outline.loops.iter().flatten().copied().collect();
    let sides = 2 * frames.len().saturating_sub(1) as u128 * ring.len() as u128;
    let count = sides + 2 * outline.cap.len() as u128;
    if count > MAX_TRIANGLES as u128 {
        return Err(format!(
            "{} sections of {} points make {count} triangles, over the budget of {MAX_TRIANGLES} a mesh; coarsen the tessellation (segments, detail, pixel_tolerance)",
            frames.len(),
            ring.len()
        ));
    }
    let per_frame = ring.len() as u32;
    let mut mesh = Mesh::default();
    for frame in frames {
        mesh.positions.extend(ring.iter().map(|&p| frame.place(p)));
    }
    let (first, last) = (&frames[0], &frames[frames.len() - 1]);
    mesh.positions
        .extend(outline.interior.iter().map(|&p| first.place(p)));
    mesh.positions
        .extend(outline.interior.iter().map(|&p| last.place(p)));

    let mut loop_start = 0u32;
    for lp in &outline.loops {
        let n = lp.len() as u32;
        for i in 0..frames.len() as u32 - 1 {
            for k in 0..n {
                let at = |frame: u32, k: u32| frame * per_frame + loop_start + k % n;
                let (a, b, c, d) = (at(i, k), at(i, k + 1), at(i + 1, k + 1), at(i + 1, k));
                mesh.triangles.push([a, b, c]);
                mesh.triangles.push([a, c, d]);
            }
        }
        loop_start += n;
    }
    let count = frames.len() as u32;
    let interior = outline.interior.len() as u32;
    let cap_vertex = |i: u32, end: bool| {
        if i < per_frame {
            if end { (count - 1) * per_frame + i } else { i }
        } else {
            count * per_frame + (i - per_frame) + if end { interior } else { 0 }
        }
    };
    for t in &outline.cap {
        // The cap is counter-clockwise in (u, v): it faces along u × v at the far end, and
        // must be reversed at the near end.
        mesh.triangles.push(t.map(|i| cap_vertex(i, true)));
        mesh.triangles.push([
            cap_vertex(t[0], false),
            cap_vertex(t[2], false),
            cap_vertex(t[1], false),
        ]);
    }
    Ok(mesh)
}
