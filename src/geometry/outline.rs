//! Section outlines: the polygons a prism or a beam is swept from, with their end caps
//! triangulated. Coordinates are (u, v): across and up, origin at the centroid.

use glam::DVec2;

/// Vertices of a section for meshing. `loops[0]` is the outer boundary, counter-clockwise
/// seen along the sweep; further loops are holes, clockwise. `cap` triangulates the section
/// face over the loop vertices (concatenated in order) followed by `interior` points.
#[derive(Clone, Debug, Default)]
pub struct SectionOutline {
    /// The outer boundary first, then the holes.
    pub loops: Vec<Vec<DVec2>>,
    /// Cap vertices that are not on a loop (the inner grid points of the paper's faces).
    pub interior: Vec<DVec2>,
    /// Cap triangles, counter-clockwise, indexing loops then interior points.
    pub cap: Vec<[u32; 3]>,
}

impl SectionOutline {
    /// Area and second moment about the horizontal (u) axis of the region the loops bound,
    /// by Green's theorem: exact for polygons.
    pub fn area_and_second_moment(&self) -> (f64, f64) {
        let (mut area, mut second_moment) = (0.0, 0.0);
        for ring in &self.loops {
            for k in 0..ring.len() {
                let (p, q) = (ring[k], ring[(k + 1) % ring.len()]);
                let cross = p.x * q.y - q.x * p.y;
                area += cross / 2.0;
                second_moment += cross * (p.y * p.y + p.y * q.y + q.y * q.y) / 12.0;
            }
        }
        (area, second_moment)
    }
}

/// The paper's meshing of its cuboid: five 1→4 subdivisions of each face, 2⁵ divisions per
/// edge.
pub const PAPER_DIVISIONS: usize = 32;

/// Segments for a circle of radius r whose chords deviate from it by at most `tolerance`.
pub fn circle_segments(r: f64, tolerance: f64) -> usize {
    let ratio = (1.0 - tolerance / r).clamp(-1.0, 1.0);
    let n = (std::f64::consts::PI / ratio.acos()).ceil();
    if n.is_finite() {
        (n as usize).clamp(8, 4096)
    } else {
        4096
    }
}

/// A w × h rectangle whose edges are split into `n` parts, with the face triangulated on the
/// n × n grid.
pub fn rectangle(w: f64, h: f64, n: usize) -> SectionOutline {
    let point = |i: usize, j: usize| {
        DVec2::new(
            -w / 2.0 + w * i as f64 / n as f64,
            -h / 2.0 + h * j as f64 / n as f64,
        )
    };
    // Boundary walk, counter-clockwise from the bottom-left corner.
    let mut boundary: Vec<(usize, usize)> = Vec::with_capacity(4 * n);
    boundary.extend((0..n).map(|i| (i, 0)));
    boundary.extend((0..n).map(|j| (n, j)));
    boundary.extend((0..n).map(|i| (n - i, n)));
    boundary.extend((0..n).map(|j| (0, n - j)));
    let mut index = vec![vec![u32::MAX; n + 1]; n + 1];
    for (k, &(i, j)) in boundary.iter().enumerate() {
        index[i][j] = k as u32;
    }
    let mut interior = Vec::new();
    #[expect(
        clippy::needless_range_loop,
        reason = "i and j are grid coordinates: point(i, j) needs them as much as index does"
    )]
    for i in 1..n {
        for j in 1..n {
            index[i][j] = (boundary.len() + interior.len()) as u32;
            interior.push(point(i, j));
        }
    }
    let mut cap = Vec::with_capacity(2 * n * n);
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (
                index[i][j],
                index[i + 1][j],
                index[i + 1][j + 1],
                index[i][j + 1],
            );
            cap.push([a, b, c]);
            cap.push([a, c, d]);
        }
    }
    SectionOutline {
        loops: vec![boundary.iter().map(|&(i, j)| point(i, j)).collect()],
        interior,
        cap,
    }
}

/// A doubly symmetric I: flange width `b`, overall height `h`, flange and web thicknesses.
pub fn i_shape(b: f64, h: f64, tf: f64, tw: f64) -> SectionOutline {
    let (y, z, yw, zf) = (b / 2.0, h / 2.0, tw / 2.0, h / 2.0 - tf);
    let outline = [
        (-y, -z),
        (y, -z),
        (y, -zf),
        (yw, -zf),
        (yw, zf),
        (y, zf),
        (y, z),
        (-y, z),
        (-y, zf),
        (-yw, zf),
        (-yw, -zf),
        (-y, -zf),
    ];
    // Bottom flange, web and top flange, each fanned from a corner that sees all its vertices.
    let cap = vec![
        [0, 1, 2],
        [0, 2, 3],
        [0, 3, 10],
        [0, 10, 11],
        [10, 3, 4],
        [10, 4, 9],
        [6, 7, 8],
        [6, 8, 9],
        [6, 9, 4],
        [6, 4, 5],
    ];
    SectionOutline {
        loops: vec![outline.iter().map(|&(a, b)| DVec2::new(a, b)).collect()],
        interior: Vec::new(),
        cap,
    }
}

/// A w × h rectangle with a uniform wall `t`.
pub fn hollow_rectangle(w: f64, h: f64, t: f64) -> SectionOutline {
    let corners = |w: f64, h: f64| {
        vec![
            DVec2::new(-w / 2.0, -h / 2.0),
            DVec2::new(w / 2.0, -h / 2.0),
            DVec2::new(w / 2.0, h / 2.0),
            DVec2::new(-w / 2.0, h / 2.0),
        ]
    };
    annulus(corners(w, h), corners(w - 2.0 * t, h - 2.0 * t))
}

/// A circular ring of outer diameter `d` and wall `t`, its circles within `tolerance` of the
/// true ones.
pub fn hollow_circle(d: f64, t: f64, tolerance: f64) -> SectionOutline {
    let n = circle_segments(d / 2.0, tolerance);
    annulus(circle(d / 2.0, n), circle(d / 2.0 - t, n))
}

/// `n` points on a circle of radius `r`, counter-clockwise from +u.
pub fn circle(r: f64, n: usize) -> Vec<DVec2> {
    (0..n)
        .map(|k| DVec2::from_angle(std::f64::consts::TAU * k as f64 / n as f64) * r)
        .collect()
}

/// A ring between `outer` and `inner`, both listed counter-clockwise with matching vertices.
pub fn annulus(outer: Vec<DVec2>, inner: Vec<DVec2>) -> SectionOutline {
    let n = outer.len() as u32;
    let mut cap = Vec::with_capacity(2 * n as usize);
    // The hole is stored clockwise (reversed), so inner vertex k sits at index n + (n − 1 − k).
    let inner_index = |k: u32| n + (n - 1 - k % n);
    for k in 0..n {
        let (o0, o1, i0, i1) = (k, (k + 1) % n, inner_index(k), inner_index(k + 1));
        cap.push([o0, o1, i1]);
        cap.push([o0, i1, i0]);
    }
    let hole: Vec<DVec2> = inner.into_iter().rev().collect();
    SectionOutline {
        loops: vec![outer, hole],
        interior: Vec::new(),
        cap,
    }
}

/// The unit disc as an n-gon fanned from its centre.
pub fn disc(n: usize) -> SectionOutline {
    let n32 = n as u32;
    SectionOutline {
        loops: vec![circle(1.0, n)],
        interior: vec![DVec2::ZERO],
        cap: (0..n32).map(|k| [n32, k, (k + 1) % n32]).collect(),
    }
}

/// Whether `p` lies inside the closed polygon (even–odd rule).
pub fn polygon_contains(outline: &[DVec2], p: DVec2) -> bool {
    let mut inside = false;
    for (k, &a) in outline.iter().enumerate() {
        let b = outline[(k + 1) % outline.len()];
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

/// Distance from `p` to the closed polygon `outline`: 0 inside, else to its nearest edge.
pub fn distance_outside(outline: &[DVec2], p: DVec2) -> f64 {
    if polygon_contains(outline, p) {
        return 0.0;
    }
    (0..outline.len())
        .map(|k| {
            let (a, b) = (outline[k], outline[(k + 1) % outline.len()]);
            let t = ((p - a).dot(b - a) / (b - a).length_squared().max(f64::MIN_POSITIVE))
                .clamp(0.0, 1.0);
            p.distance(a + t * (b - a))
        })
        .fold(f64::INFINITY, f64::min)
}

/// A simple polygon, made counter-clockwise, with its face triangulated by ear clipping.
pub fn polygon(profile: &[[f64; 2]]) -> Result<SectionOutline, String> {
    let mut points: Vec<DVec2> = profile.iter().map(|&p| DVec2::from_array(p)).collect();
    if points.len() < 3 || points.iter().any(|p| !p.is_finite()) {
        return Err(format!(
            "a profile needs at least 3 finite points, got {profile:?}"
        ));
    }
    let area: f64 = (0..points.len())
        .map(|i| points[i].perp_dot(points[(i + 1) % points.len()]))
        .sum::<f64>()
        / 2.0;
    if area.abs() < 1e-12 {
        return Err(format!("the profile {profile:?} encloses no area"));
    }
    if area < 0.0 {
        points.reverse();
    }
    let cap = ear_clip(&points).ok_or_else(|| {
        format!("the profile {profile:?} is not a simple polygon (its edges cross)")
    })?;
    Ok(SectionOutline {
        loops: vec![points],
        interior: Vec::new(),
        cap,
    })
}

/// Triangulates a counter-clockwise simple polygon; None if it is not simple.
fn ear_clip(points: &[DVec2]) -> Option<Vec<[u32; 3]>> {
    let mut left: Vec<usize> = (0..points.len()).collect();
    let mut triangles = Vec::with_capacity(points.len() - 2);
    while left.len() > 3 {
        let n = left.len();
        let ear = (0..n).find(|&i| {
            let (a, b, c) = (
                points[left[(i + n - 1) % n]],
                points[left[i]],
                points[left[(i + 1) % n]],
            );
            (b - a).perp_dot(c - b) > 0.0
                && left.iter().all(|&j| {
                    let p = points[j];
                    p == a
                        || p == b
                        || p == c
                        || !((b - a).perp_dot(p - a) >= 0.0
                            && (c - b).perp_dot(p - b) >= 0.0
                            && (a - c).perp_dot(p - c) >= 0.0)
                })
        })?;
        triangles.push([
            left[(ear + n - 1) % n] as u32,
            left[ear] as u32,
            left[(ear + 1) % n] as u32,
        ]);
        left.remove(ear);
    }
    triangles.push([left[0] as u32, left[1] as u32, left[2] as u32]);
    Some(triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn caps_cover_the_section_once_with_counter_clockwise_triangles() {
        let outlines = [
            rectangle(0.3, 0.5, 1),
            rectangle(1.0, 2.0, PAPER_DIVISIONS),
            i_shape(0.150, 0.300, 0.0107, 0.0071),
            hollow_rectangle(0.2, 0.3, 0.01),
            hollow_circle(0.3239, 0.01, 1e-4),
        ];
        for (k, o) in outlines.iter().enumerate() {
            let points: Vec<DVec2> = o
                .loops
                .iter()
                .flatten()
                .chain(&o.interior)
                .copied()
                .collect();
            let covered: f64 = o
                .cap
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| points[i as usize]);
                    let twice = (b - a).perp_dot(c - a);
                    assert!(
                        twice > 0.0,
                        "outline {k}: cap triangle {t:?} is not counter-clockwise"
                    );
                    twice / 2.0
                })
                .sum();
            let (area, _) = o.area_and_second_moment();
            assert!((covered / area - 1.0).abs() < 1e-12, "outline {k}");
        }
    }

    #[test]
    fn green_integrals_match_the_rectangle_formulas() {
        // A = bh, I = bh³/12, and a hole subtracts its own.
        let (a, i) = rectangle(0.3, 0.5, 3).area_and_second_moment();
        assert!((a - 0.15).abs() < 1e-15 && (i - 0.3 * 0.125 / 12.0).abs() < 1e-15);
        let (a, i) = hollow_rectangle(0.2, 0.3, 0.01).area_and_second_moment();
        assert!((a - (0.06 - 0.18 * 0.28)).abs() < 1e-15);
        assert!((i - (0.2 * 0.027 - 0.18 * 0.28f64.powi(3)) / 12.0).abs() < 1e-15);
    }

    #[test]
    fn circles_get_the_segments_their_tolerance_needs() {
        for tol in [1e-2, 1e-3, 1e-5] {
            let n = circle_segments(0.5, tol);
            let sagitta = 0.5 * (1.0 - (std::f64::consts::PI / n as f64).cos());
            assert!(sagitta <= tol * (1.0 + 1e-9));
            let coarser = 0.5 * (1.0 - (std::f64::consts::PI / (n - 1) as f64).cos());
            assert!(n == 8 || coarser > tol, "n = {n} is more than needed");
        }
        assert_eq!(circle_segments(0.5, 10.0), 8);
    }
}
