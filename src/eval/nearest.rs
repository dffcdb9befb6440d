//! Exact nearest distances from a query point to a set of triangles or points, in f64, through
//! a bounding-volume hierarchy (median split along the widest axis of the centroids, at most
//! `LEAF` items a leaf, depth-first search visiting the nearer child first and pruning boxes
//! farther than the best distance found).
//!
//! Why not the crate's ray-tracing BVH (`obvhs`): it has no nearest-point query and keeps its
//! boxes in f32, so pruning would need slack; nor a k-d tree crate: it holds points, and a mesh
//! needs point-to-triangle distances. This one is small, in f64, and tested against brute force.

use glam::DVec3;

/// Most items in a leaf.
const LEAF: usize = 4;

#[derive(Clone, Copy)]
enum Item {
    Point(DVec3),
    Triangle([DVec3; 3]),
}

impl Item {
    fn bounds(&self) -> (DVec3, DVec3) {
        match *self {
            Item::Point(p) => (p, p),
            Item::Triangle([a, b, c]) => (a.min(b).min(c), a.max(b).max(c)),
        }
    }

    fn centroid(&self) -> DVec3 {
        let (lo, hi) = self.bounds();
        (lo + hi) * 0.5
    }

    fn distance_squared(&self, q: DVec3) -> f64 {
        match *self {
            Item::Point(p) => p.distance_squared(q),
            Item::Triangle(t) => closest_on_triangle(q, t).distance_squared(q),
        }
    }
}

struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first item and count. Inner: `first` is the right child (the left is next).
    first: u32,
    count: u32,
}

/// A hierarchy over points or triangles answering "how far is the nearest?".
pub(super) struct Nearest {
    nodes: Vec<Node>,
    items: Vec<Item>,
}

impl Nearest {
    /// Over the triangles `triangles` of `positions`.
    pub(super) fn triangles(positions: &[DVec3], triangles: &[[u32; 3]]) -> Nearest {
        let items = triangles
            .iter()
            .map(|t| Item::Triangle(t.map(|i| positions[i as usize])))
            .collect();
        Nearest::build(items)
    }

    /// Over points.
    pub(super) fn points(points: &[DVec3]) -> Nearest {
        Nearest::build(points.iter().map(|&p| Item::Point(p)).collect())
    }

    fn build(mut items: Vec<Item>) -> Nearest {
        let mut nodes = Vec::with_capacity(2 * items.len() / LEAF + 1);
        if !items.is_empty() {
            let len = items.len();
            split(&mut items, 0, len, &mut nodes);
        }
        Nearest { nodes, items }
    }

    /// The distance from `q` to the nearest item; infinite when there is none.
    pub(super) fn distance(&self, q: DVec3) -> f64 {
        let mut best = f64::INFINITY;
        if self.nodes.is_empty() {
            return best;
        }
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if box_distance_squared(q, node.lo, node.hi) >= best {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                for item in &self.items[first..first + node.count as usize] {
                    best = best.min(item.distance_squared(q));
                }
                continue;
            }
            let (left, right) = (n + 1, node.first as usize);
            let dl = box_distance_squared(q, self.nodes[left].lo, self.nodes[left].hi);
            let dr = box_distance_squared(q, self.nodes[right].lo, self.nodes[right].hi);
            // Pushed last, popped first: the nearer child, which shrinks `best` soonest.
            if dl <= dr {
                stack.extend([right, left]);
            } else {
                stack.extend([left, right]);
            }
        }
        best.sqrt()
    }
}

/// Builds the node of items[start..end] and its subtree; returns its index.
fn split(items: &mut [Item], start: usize, end: usize, nodes: &mut Vec<Node>) -> usize {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for item in &items[start..end] {
        let (a, b) = item.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
        let c = item.centroid();
        clo = clo.min(c);
        chi = chi.max(c);
    }
    let index = nodes.len();
    nodes.push(Node {
        lo,
        hi,
        first: start as u32,
        count: (end - start) as u32,
    });
    let extent = chi - clo;
    if end - start <= LEAF || extent.max_element() <= 0.0 {
        return index;
    }
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = start + (end - start) / 2;
    items[start..end].select_nth_unstable_by(mid - start, |a, b| {
        a.centroid()[axis].total_cmp(&b.centroid()[axis])
    });
    split(items, start, mid, nodes);
    let right = split(items, mid, end, nodes);
    nodes[index].first = right as u32;
    nodes[index].count = 0;
    index
}

fn box_distance_squared(q: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    let d = (lo - q).max(q - hi).max(DVec3::ZERO);
    d.length_squared()
}

/// The point of triangle `[a, b, c]` nearest to `p`, by the Voronoi regions of its corners,
/// edges and face (Ericson, Real-Time Collision Detection, 2005, §5.1.5). A degenerate
/// triangle still gives a point on it.
pub(super) fn closest_on_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom <= 0.0 {
        // Zero area (collinear corners): the nearest of its three edges.
        let edges = [(a, b), (b, c), (c, a)].map(|(s, e)| closest_on_segment(p, s, e));
        return edges
            .into_iter()
            .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))
            .unwrap_or(a);
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

fn closest_on_segment(p: DVec3, s: DVec3, e: DVec3) -> DVec3 {
    let d = e - s;
    let len = d.length_squared();
    if len == 0.0 {
        return s;
    }
    s + d * ((p - s).dot(d) / len).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift), for test inputs only.
    struct Xorshift(u64);
    impl Xorshift {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn point(&mut self, scale: f64) -> DVec3 {
            DVec3::new(self.next(), self.next(), self.next()) * scale
        }
    }

    #[test]
    fn triangle_distances_match_the_plane_and_the_edges() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        // Above the face: straight down.
        let p = DVec3::new(0.2, 0.3, 0.7);
        assert!((closest_on_triangle(p, t) - DVec3::new(0.2, 0.3, 0.0)).length() < 1e-15);
        // Beyond the hypotenuse: its nearest point (0.5, 0.5, 0).
        let p = DVec3::new(1.0, 1.0, 0.0);
        assert!((closest_on_triangle(p, t) - DVec3::new(0.5, 0.5, 0.0)).length() < 1e-15);
        // Beyond a corner.
        assert_eq!(
            closest_on_triangle(DVec3::new(-1.0, -2.0, 3.0), t),
            DVec3::ZERO
        );
        // Degenerate: a segment from 0 to 2x.
        let flat = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        let q = closest_on_triangle(DVec3::new(1.5, 1.0, 0.0), flat);
        assert!((q - DVec3::new(1.5, 0.0, 0.0)).length() < 1e-15);
    }

    /// Distance to a triangle by dense sampling of its surface: an upper bound within the
    /// grid step of the truth, computed without the Voronoi-region logic.
    fn sampled_distance(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
        let n = 200;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                best = best.min((a + (b - a) * u + (c - a) * v).distance(p));
            }
        }
        best
    }

    #[test]
    fn the_hierarchy_finds_what_brute_force_finds() {
        let mut rng = Xorshift(0x9e3779b97f4a7c15);
        let positions: Vec<DVec3> = (0..300).map(|_| rng.point(10.0)).collect();
        let triangles: Vec<[u32; 3]> = (0..100).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let tree = Nearest::triangles(&positions, &triangles);
        let cloud = Nearest::points(&positions);
        for _ in 0..200 {
            let q = rng.point(12.0) - DVec3::ONE;
            let brute = triangles
                .iter()
                .map(|t| closest_on_triangle(q, t.map(|i| positions[i as usize])).distance(q))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(tree.distance(q), brute);
            let nearest_point = positions
                .iter()
                .map(|p| p.distance(q))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(cloud.distance(q), nearest_point);
        }
        // The Voronoi-region distance agrees with dense sampling of one triangle.
        for t in triangles.iter().take(5) {
            let q = rng.point(10.0);
            let tri = t.map(|i| positions[i as usize]);
            let exact = closest_on_triangle(q, tri).distance(q);
            let sampled = sampled_distance(q, tri);
            // Any point of the triangle is within one grid step along each edge of a sample.
            let step = ((tri[1] - tri[0]).length() + (tri[2] - tri[0]).length()) / 200.0;
            assert!(
                exact <= sampled + 1e-12 && sampled - exact <= step,
                "{exact} {sampled}"
            );
        }
        assert_eq!(Nearest::points(&[]).distance(DVec3::ZERO), f64::INFINITY);
    }
}
