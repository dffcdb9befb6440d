//! Cross-sections: their properties for bending about the horizontal axis, and their outline
//! for meshing. Coordinates are (y, z): y across the beam, z up, origin at the centroid.

use glam::DVec2;
use serde::Serialize;

#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum Section {
    Rectangle {
        width: f64,
        height: f64,
    },
    /// Doubly symmetric I/H: flange width, overall height, flange and web thicknesses.
    ISection {
        width: f64,
        height: f64,
        flange: f64,
        web: f64,
    },
    /// Rectangular hollow section with uniform wall.
    HollowBox {
        width: f64,
        height: f64,
        wall: f64,
    },
    /// Circular hollow section (tube).
    CircularHollow {
        diameter: f64,
        wall: f64,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SectionProperties {
    pub area: f64,
    pub second_moment: f64,
    /// Timoshenko shear coefficient κ (shear area = κA).
    pub shear_coefficient: f64,
    /// Distance from the centroid to the extreme fibre.
    pub extreme_fibre: f64,
}

/// Vertices of a section for meshing. `loops[0]` is the outer boundary, counter-clockwise
/// seen from +x; further loops are holes, clockwise. `cap` triangulates the section face over
/// the loop vertices (concatenated in order) followed by `interior` points.
#[derive(Clone, Debug, Default)]
pub struct SectionOutline {
    pub loops: Vec<Vec<DVec2>>,
    pub interior: Vec<DVec2>,
    pub cap: Vec<[u32; 3]>,
}

impl Section {
    pub fn width(&self) -> f64 {
        match *self {
            Section::Rectangle { width, .. }
            | Section::ISection { width, .. }
            | Section::HollowBox { width, .. } => width,
            Section::CircularHollow { diameter, .. } => diameter,
        }
    }

    pub fn height(&self) -> f64 {
        match *self {
            Section::Rectangle { height, .. }
            | Section::ISection { height, .. }
            | Section::HollowBox { height, .. } => height,
            Section::CircularHollow { diameter, .. } => diameter,
        }
    }

    /// Checks the dimensions; the message names the offending one and its value.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, x: f64| {
            if x > 0.0 && x.is_finite() {
                Ok(())
            } else {
                Err(format!("section {name} = {x} must be positive (metres)"))
            }
        };
        let thinner = |name: &str, t: f64, limit: f64, what: &str| {
            if t < limit {
                Ok(())
            } else {
                Err(format!(
                    "section {name} = {t} m must be less than {what} ({limit} m)"
                ))
            }
        };
        match *self {
            Section::Rectangle { width, height } => {
                positive("width", width).and(positive("height", height))
            }
            Section::ISection {
                width,
                height,
                flange,
                web,
            } => {
                positive("width", width)?;
                positive("height", height)?;
                positive("flange", flange)?;
                positive("web", web)?;
                thinner("flange", flange, height / 2.0, "half the height")?;
                thinner("web", web, width, "the flange width")
            }
            Section::HollowBox {
                width,
                height,
                wall,
            } => {
                positive("width", width)?;
                positive("height", height)?;
                positive("wall", wall)?;
                thinner(
                    "wall",
                    wall,
                    width.min(height) / 2.0,
                    "half the smaller outer dimension",
                )
            }
            Section::CircularHollow { diameter, wall } => {
                positive("diameter", diameter)?;
                positive("wall", wall)?;
                thinner("wall", wall, diameter / 2.0, "the radius")
            }
        }
    }

    pub fn properties(&self, poisson: f64) -> SectionProperties {
        let nu = poisson;
        let (area, second_moment, shear_coefficient) = match *self {
            // Cowper (1966) for the rectangle.
            Section::Rectangle {
                width: b,
                height: h,
            } => (
                b * h,
                b * h.powi(3) / 12.0,
                10.0 * (1.0 + nu) / (12.0 + 11.0 * nu),
            ),
            // Shear carried by the web: κ = A_web/A.
            Section::ISection {
                width: b,
                height: h,
                flange: tf,
                web: tw,
            } => {
                let area = 2.0 * b * tf + (h - 2.0 * tf) * tw;
                (
                    area,
                    (b * h.powi(3) - (b - tw) * (h - 2.0 * tf).powi(3)) / 12.0,
                    (h - 2.0 * tf) * tw / area,
                )
            }
            // EN 1993-1-1 §6.2.6 shear area of a hollow rectangle loaded parallel to its height: A·h/(b + h).
            Section::HollowBox {
                width: b,
                height: h,
                wall: t,
            } => {
                let (bi, hi) = (b - 2.0 * t, h - 2.0 * t);
                (
                    b * h - bi * hi,
                    (b * h.powi(3) - bi * hi.powi(3)) / 12.0,
                    h / (b + h),
                )
            }
            // Cowper (1966) for a hollow circle, m = inner/outer diameter.
            Section::CircularHollow {
                diameter: d,
                wall: t,
            } => {
                let di = d - 2.0 * t;
                let m2 = (di / d).powi(2);
                let kappa = 6.0 * (1.0 + nu) * (1.0 + m2).powi(2)
                    / ((7.0 + 6.0 * nu) * (1.0 + m2).powi(2) + (20.0 + 12.0 * nu) * m2);
                let pi = std::f64::consts::PI;
                (
                    pi / 4.0 * (d * d - di * di),
                    pi / 64.0 * (d.powi(4) - di.powi(4)),
                    kappa,
                )
            }
        };
        SectionProperties {
            area,
            second_moment,
            shear_coefficient,
            extreme_fibre: self.height() / 2.0,
        }
    }

    /// The outline with no more vertices than the shape needs: polygons exactly, circles with
    /// sagitta ≤ `chord_tolerance`.
    pub fn outline(&self, chord_tolerance: f64) -> SectionOutline {
        match *self {
            Section::Rectangle { width, height } => rectangle_grid(width, height, 1),
            Section::ISection {
                width: b,
                height: h,
                flange: tf,
                web: tw,
            } => i_outline(b, h, tf, tw),
            Section::HollowBox {
                width: b,
                height: h,
                wall: t,
            } => {
                let rect = |w: f64, h: f64| {
                    vec![
                        DVec2::new(-w / 2.0, -h / 2.0),
                        DVec2::new(w / 2.0, -h / 2.0),
                        DVec2::new(w / 2.0, h / 2.0),
                        DVec2::new(-w / 2.0, h / 2.0),
                    ]
                };
                annulus(rect(b, h), rect(b - 2.0 * t, h - 2.0 * t))
            }
            Section::CircularHollow {
                diameter: d,
                wall: t,
            } => {
                let n = circle_segments(d / 2.0, chord_tolerance);
                let circle = |r: f64| {
                    (0..n)
                        .map(|k| DVec2::from_angle(std::f64::consts::TAU * k as f64 / n as f64) * r)
                        .collect()
                };
                annulus(circle(d / 2.0), circle(d / 2.0 - t))
            }
        }
    }

    /// The paper's meshing of its cuboid: every face divided into a 32 × 32 grid.
    pub fn paper_outline(&self) -> Option<SectionOutline> {
        match *self {
            Section::Rectangle { width, height } => {
                Some(rectangle_grid(width, height, PAPER_DIVISIONS))
            }
            _ => None,
        }
    }
}

/// One section of each kind, for tests across the crate (the I-section is an IPE 300:
/// 150 × 300, tf 10.7, tw 7.1, root fillets ignored).
#[cfg(test)]
pub fn examples() -> Vec<Section> {
    vec![
        Section::Rectangle {
            width: 0.3,
            height: 0.5,
        },
        Section::ISection {
            width: 0.150,
            height: 0.300,
            flange: 0.0107,
            web: 0.0071,
        },
        Section::HollowBox {
            width: 0.2,
            height: 0.3,
            wall: 0.01,
        },
        Section::CircularHollow {
            diameter: 0.3239,
            wall: 0.01,
        },
    ]
}

/// Five 1→4 subdivisions of a cube face: 2⁵ divisions per edge.
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
pub(crate) fn rectangle_grid(w: f64, h: f64, n: usize) -> SectionOutline {
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

fn i_outline(b: f64, h: f64, tf: f64, tw: f64) -> SectionOutline {
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

/// A ring between `outer` and `inner`, both listed counter-clockwise with matching vertices.
pub(crate) fn annulus(outer: Vec<DVec2>, inner: Vec<DVec2>) -> SectionOutline {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Area and second moment of the meshed face by the polygon (Green's theorem) formulas.
    fn outline_integrals(o: &SectionOutline) -> (f64, f64) {
        let (mut area, mut iy) = (0.0, 0.0);
        for ring in &o.loops {
            for k in 0..ring.len() {
                let (p, q) = (ring[k], ring[(k + 1) % ring.len()]);
                let cross = p.x * q.y - q.x * p.y;
                area += cross / 2.0;
                iy += cross * (p.y * p.y + p.y * q.y + q.y * q.y) / 12.0;
            }
        }
        (area, iy)
    }

    #[test]
    fn properties_match_the_meshed_outline_and_handbook_values() {
        for s in examples() {
            let p = s.properties(0.3);
            // Polygons are exact; the tube is an inscribed polygon at 1e-7 m sagitta.
            let (area, second_moment) = outline_integrals(&s.outline(1e-7));
            assert!(
                (area / p.area - 1.0).abs() < 1e-5,
                "{s:?}: area {area} vs {}",
                p.area
            );
            assert!(
                (second_moment / p.second_moment - 1.0).abs() < 1e-5,
                "{s:?}: I {second_moment} vs {}",
                p.second_moment
            );
            assert!(p.shear_coefficient > 0.0 && p.shear_coefficient <= 1.0);
        }
        // IPE 300 tables (with 15 mm root fillets): A = 53.8 cm², I = 8356 cm⁴. The four fillets
        // add 4(1 − π/4)r² = 1.93 cm² of area and about 4 % of I, which this section omits.
        let ipe = examples()[1].properties(0.3);
        assert!(
            (ipe.area * 1e4 - (53.8 - 1.93)).abs() < 0.05,
            "{}",
            ipe.area * 1e4
        );
        assert!(
            (ipe.second_moment * 1e8 / 8356.0 - 0.96).abs() < 0.01,
            "{}",
            ipe.second_moment * 1e8
        );
        // Cowper's values: rectangle 0.8497, thin tube → 2(1+ν)/(4+3ν) = 0.5306.
        assert!((examples()[0].properties(0.3).shear_coefficient - 0.8497).abs() < 1e-4);
        let thin = Section::CircularHollow {
            diameter: 1.0,
            wall: 1e-4,
        }
        .properties(0.3);
        assert!((thin.shear_coefficient - 2.6 / 4.9).abs() < 1e-3);
    }

    #[test]
    fn caps_cover_the_section_once_with_counter_clockwise_triangles() {
        for s in examples().into_iter().chain([Section::Rectangle {
            width: 1.0,
            height: 2.0,
        }]) {
            for o in [s.outline(1e-4), s.paper_outline().unwrap_or_default()] {
                if o.loops.is_empty() {
                    continue;
                }
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
                            "{s:?}: cap triangle {t:?} is not counter-clockwise"
                        );
                        twice / 2.0
                    })
                    .sum();
                assert!(
                    (covered / outline_integrals(&o).0 - 1.0).abs() < 1e-12,
                    "{s:?}"
                );
            }
        }
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

    #[test]
    fn bad_dimensions_are_named() {
        let e = Section::CircularHollow {
            diameter: 0.2,
            wall: 0.15,
        }
        .validate()
        .unwrap_err();
        assert!(e.contains("wall = 0.15"), "{e}");
        assert!(
            Section::ISection {
                width: 0.1,
                height: 0.2,
                flange: 0.01,
                web: f64::NAN
            }
            .validate()
            .is_err()
        );
    }
}
