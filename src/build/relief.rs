//! Damage that changes a beam's surface: spall cavities and dents pushed into its flat faces,
//! and the reinforcing bars a spall lays bare.
//!
//! Owns: the relief of a spall (a flat floor `depth` under the face inside its outline, walls
//! one grid cell wide at its rim) and of a dent (a smooth bowl, depth·(1 − r²/R²)², flat at its
//! rim), the grid the face is divided on under them (extra outline points across the face and
//! extra stations along it, so the mesh keeps its topology and stays closed), and the bars.
//! The surface is cut in rest space, in the section's own (u, v) coordinates, and every moved
//! vertex is placed by its station's section frame like any other: the cavity deflects with
//! the member and the displacement labels stay exact. Geometry and sources: docs/damage.md.

use crate::geometry::outline::{SectionOutline, disc, distance_outside};
use crate::geometry::{Frame3, Mesh, sweep};
use crate::mechanics::damage::{Damage, DamageShape, Face, Reinforcement};
use crate::scene::BeamSpec;
use glam::DVec2;

/// Grid cells across a relief's extent, along and across the axis: a spall's wall is one cell
/// wide, a dent's bowl is sampled by this many chords over its diameter.
const RELIEF_CELLS: f64 = 24.0;
/// Width of a spall's sloped wall outside its outline, in grid cells (of the finer step);
/// the grid reaches `GRID_MARGIN` cells beyond the outline, so the wall ends on it.
const WALL_CELLS: f64 = 1.5;
const GRID_MARGIN: f64 = 2.0;
/// Sides of a bar's polygonal section (a sagitta of 1.7 % of its radius).
const BAR_SIDES: usize = 12;

/// What pushes a face in.
#[derive(Clone, Debug, PartialEq)]
enum Profile {
    /// A spall: `depth` everywhere inside `outline` (face coordinates: along, across).
    Cavity { outline: Vec<DVec2>, depth: f64 },
    /// A dent of `depth` at `centre`, reaching `radius`.
    Bowl {
        centre: DVec2,
        radius: f64,
        depth: f64,
    },
}

/// A spall or dent on one flat face of a beam.
#[derive(Clone, Debug, PartialEq)]
pub struct Relief {
    face: Face,
    /// Bounds of the pushed region on the face, (along, across), lower and upper.
    lo: DVec2,
    hi: DVec2,
    profile: Profile,
}

impl Relief {
    /// The relief of a spall or dent; None for other damage.
    pub fn of(damage: &Damage) -> Option<Relief> {
        let face = damage.position.face;
        let centre = DVec2::new(damage.position.along, damage.position.height);
        let (profile, lo, hi) = match &damage.shape {
            DamageShape::Spall { outline, depth } => {
                let outline: Vec<DVec2> = outline
                    .iter()
                    .map(|p| DVec2::new(p.along, p.height))
                    .collect();
                let lo = outline.iter().copied().reduce(DVec2::min)?;
                let hi = outline.iter().copied().reduce(DVec2::max)?;
                let depth = *depth;
                (Profile::Cavity { outline, depth }, lo, hi)
            }
            DamageShape::Dent { depth, radius } => {
                let (depth, radius) = (*depth, *radius);
                let bowl = Profile::Bowl {
                    centre,
                    radius,
                    depth,
                };
                (bowl, centre - radius, centre + radius)
            }
            _ => return None,
        };
        Some(Relief {
            face,
            lo,
            hi,
            profile,
        })
    }

    /// How far the face is pushed in at face point `p` (along, across), metres.
    fn push(&self, p: DVec2) -> f64 {
        match &self.profile {
            Profile::Cavity { outline, depth } => {
                // The floor inside the outline, a straight slope up to the face over the wall.
                let wall = WALL_CELLS * self.cell().min_element();
                depth * (1.0 - distance_outside(outline, p) / wall).max(0.0)
            }
            Profile::Bowl {
                centre,
                radius,
                depth,
            } => {
                let s = p.distance_squared(*centre) / (radius * radius);
                if s < 1.0 {
                    depth * (1.0 - s).powi(2)
                } else {
                    0.0
                }
            }
        }
    }

    fn cell(&self) -> DVec2 {
        (self.hi - self.lo).max(DVec2::splat(1e-6)) / RELIEF_CELLS
    }

    /// Grid lines over the region and `GRID_MARGIN` cells beyond it, along (x) or across (y).
    fn grid(&self, across: bool) -> Vec<f64> {
        let pick = |v: DVec2| if across { v.y } else { v.x };
        let step = pick(self.cell());
        let lo = pick(self.lo) - GRID_MARGIN * step;
        (0..=(RELIEF_CELLS + 2.0 * GRID_MARGIN) as usize)
            .map(|k| lo + step * k as f64)
            .collect()
    }

    /// How far around the pushed region (metres) the surface may be moved: as far as its
    /// grid reaches.
    pub fn reach(&self) -> f64 {
        GRID_MARGIN * self.cell().max_element()
    }

    /// The stations the relief needs along the axis (the caller keeps those inside the span).
    pub fn stations(&self) -> Vec<f64> {
        self.grid(false)
    }
}

/// Every face a relief can be on.
const FACES: [Face; 4] = [Face::Bottom, Face::Top, Face::SideNegY, Face::SidePosY];

/// The outward normal of `face` in section coordinates (u across, v up).
fn outward(face: Face) -> DVec2 {
    match face {
        Face::Bottom => DVec2::NEG_Y,
        Face::Top => DVec2::Y,
        Face::SideNegY => DVec2::NEG_X,
        Face::SidePosY => DVec2::X,
    }
}

/// The face coordinate across the axis of section point `p`: v on the sides, u on top and
/// bottom (as `SurfacePoint::height`).
fn across(face: Face, p: DVec2) -> f64 {
    if face.is_side() { p.y } else { p.x }
}

/// The offset of `face`'s plane along its outward normal: the outer loop's extreme there.
fn plane(outline: &SectionOutline, face: Face) -> f64 {
    let n = outward(face);
    outline.loops[0]
        .iter()
        .map(|p| p.dot(n))
        .fold(f64::NEG_INFINITY, f64::max)
}

fn on_plane(p: DVec2, face: Face, plane: f64) -> bool {
    (p.dot(outward(face)) - plane).abs() <= 1e-9 * (1.0 + plane.abs())
}

/// `outline` with the outer loop's edges on the faces of `reliefs` split at their grid lines,
/// and the cap triangles on those edges fanned to the new points; an error when a relief's
/// face has no flat edge to push in.
pub fn refine_outline(
    outline: &SectionOutline,
    reliefs: &[Relief],
) -> Result<SectionOutline, String> {
    let mut out = outline.clone();
    for relief in reliefs {
        let face = relief.face;
        let level = plane(&out, face);
        let cuts = relief.grid(true);
        out = split_face_edges(&out, |a, b| {
            if !(on_plane(a, face, level) && on_plane(b, face, level)) {
                return None;
            }
            let (ta, tb) = (across(face, a), across(face, b));
            let mut inner: Vec<f64> = cuts
                .iter()
                .map(|&c| (c - ta) / (tb - ta))
                .filter(|t| *t > 1e-6 && *t < 1.0 - 1e-6)
                .collect();
            inner.sort_by(f64::total_cmp);
            Some(inner.into_iter().map(|t| a.lerp(b, t)).collect())
        });
        if !out.loops[0]
            .windows(2)
            .any(|w| on_plane(w[0], face, level) && on_plane(w[1], face, level))
        {
            return Err(format!(
                "a spall or dent on face {face:?} needs a flat face to push in, and this section has none there"
            ));
        }
    }
    Ok(out)
}

/// Splits each edge a→b of the outer loop at the points `split(a, b)` gives (in order from a),
/// renumbering the cap and fanning each triangle on a split edge from its third corner.
fn split_face_edges(
    outline: &SectionOutline,
    split: impl Fn(DVec2, DVec2) -> Option<Vec<DVec2>>,
) -> SectionOutline {
    let ring = &outline.loops[0];
    let n = ring.len();
    let mut new_ring = Vec::with_capacity(n);
    let mut renumber = Vec::with_capacity(n);
    // For each old edge k → k+1: the new indices of the points inserted on it.
    let mut inserted: Vec<Vec<u32>> = vec![Vec::new(); n];
    for k in 0..n {
        renumber.push(new_ring.len() as u32);
        new_ring.push(ring[k]);
        for p in split(ring[k], ring[(k + 1) % n]).unwrap_or_default() {
            inserted[k].push(new_ring.len() as u32);
            new_ring.push(p);
        }
    }
    let added = (new_ring.len() - n) as u32;
    let index = |i: u32| match (i as usize) < n {
        true => renumber[i as usize],
        false => i + added,
    };
    let mut cap = Vec::with_capacity(outline.cap.len());
    for t in &outline.cap {
        let edge = (0..3).find(|&e| {
            let (a, b) = (t[e] as usize, t[(e + 1) % 3] as usize);
            a < n && b == (a + 1) % n && !inserted[a].is_empty()
        });
        match edge {
            None => cap.push(t.map(index)),
            Some(e) => {
                let (a, b, c) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
                let chain: Vec<u32> = std::iter::once(index(a))
                    .chain(inserted[a as usize].iter().copied())
                    .chain(std::iter::once(index(b)))
                    .collect();
                cap.extend(chain.windows(2).map(|w| [w[0], w[1], index(c)]));
            }
        }
    }
    let mut loops = outline.loops.clone();
    loops[0] = new_ring;
    SectionOutline {
        loops,
        interior: outline.interior.clone(),
        cap,
    }
}

/// Pushes the vertices of a swept `mesh` (as `sweep` lays it out: one ring of `outline`'s
/// loop points per frame) in by the reliefs on their faces, each placed by its own station's
/// frame. `stations[i]` is the axis coordinate of `frames[i]`.
pub fn carve(
    mesh: &mut Mesh,
    outline: &SectionOutline,
    frames: &[Frame3],
    stations: &[f64],
    reliefs: &[Relief],
) {
    let per_frame: usize = outline.loops.iter().map(Vec::len).sum();
    let levels: Vec<f64> = reliefs.iter().map(|r| plane(outline, r.face)).collect();
    for (i, (frame, &x)) in frames.iter().zip(stations).enumerate() {
        for (k, &p) in outline.loops[0].iter().enumerate() {
            // Reliefs on one face overlap by the deepest; a corner on two faces takes both.
            let shift: DVec2 = FACES
                .iter()
                .map(|&face| {
                    let deepest = reliefs
                        .iter()
                        .zip(&levels)
                        .filter(|(r, level)| r.face == face && on_plane(p, face, **level))
                        .map(|(r, _)| r.push(DVec2::new(x, across(face, p))))
                        .fold(0.0, f64::max);
                    -deepest * outward(face)
                })
                .sum();
            if shift != DVec2::ZERO {
                mesh.positions[i * per_frame + k] = frame.place(p + shift);
            }
        }
    }
}

/// A bar a spall exposes: its centre in the section (u, v), radius, and where it runs along
/// the axis (from, to).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bar {
    /// Centre, section coordinates.
    pub centre: DVec2,
    /// Radius, metres.
    pub radius: f64,
    /// Where it starts and ends along the axis, metres (inside the concrete beyond the walls).
    pub from: f64,
    /// End.
    pub to: f64,
}

/// The longitudinal bars of a `width` × `height` reinforced-concrete section: `bars` bars in a
/// layer `cover` + φ/2 above the bottom, spread evenly between the same distance from the
/// sides (one bar: on the axis), and the same layer mirrored at the top (hanger or compression
/// bars, which any cage has at least at its corners).
fn bar_centres(width: f64, height: f64, r: &Reinforcement) -> Vec<DVec2> {
    let inset = r.cover + 0.5 * r.bar_diameter;
    let span = width - 2.0 * inset;
    let ys: Vec<f64> = match r.bars {
        1 => vec![0.0],
        n => (0..n)
            .map(|k| -0.5 * span + span * k as f64 / (n - 1) as f64)
            .collect(),
    };
    let z = 0.5 * height - inset;
    [-z, z]
        .iter()
        .flat_map(|&z| ys.iter().map(move |&y| DVec2::new(y, z)))
        .collect()
}

/// The bars spall `damage` lays bare on `beam` (none unless the beam is reinforced concrete,
/// or the damage is not a spall): those whose top lies above its floor and whose centre lies
/// across its outline, running two cells beyond it either way (clipped to the span), where
/// they are buried again.
pub fn spall_bars(beam: &BeamSpec, damage: &Damage) -> Vec<Bar> {
    let (Some(bars), Some(relief)) = (&beam.damage_asked.reinforcement, Relief::of(damage)) else {
        return Vec::new();
    };
    let Profile::Cavity { depth, .. } = relief.profile else {
        return Vec::new();
    };
    let (width, height) = (beam.section.width(), beam.section.height());
    let face = relief.face;
    let level = 0.5 * if face.is_side() { width } else { height };
    let radius = 0.5 * bars.bar_diameter;
    let reach = relief.reach();
    bar_centres(width, height, bars)
        .into_iter()
        .filter(|c| level - c.dot(outward(face)) - radius < depth)
        .filter(|c| (relief.lo.y..=relief.hi.y).contains(&across(face, *c)))
        .map(|centre| Bar {
            centre,
            radius,
            from: (relief.lo.x - reach).max(0.0),
            to: (relief.hi.x + reach).min(beam.length),
        })
        .collect()
}

/// The closed meshes of `bars`, each swept through the section frames of the stations it
/// spans (`stations[i]` is the axis coordinate of `frames[i]`), so they deflect with the beam.
pub fn bar_meshes(bars: &[Bar], frames: &[Frame3], stations: &[f64]) -> Result<Mesh, String> {
    let section = disc(BAR_SIDES);
    let mut out = Mesh::default();
    for bar in bars {
        let along: Vec<Frame3> = frames
            .iter()
            .zip(stations)
            .filter(|(_, x)| (bar.from - 1e-12..=bar.to + 1e-12).contains(*x))
            .map(|(f, _)| Frame3 {
                origin: f.place(bar.centre),
                u: f.u * bar.radius,
                v: f.v * bar.radius,
            })
            .collect();
        if along.len() >= 2 {
            out.append(&sweep(&section, &along)?);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::mesh_beam;
    use crate::mechanics::damage::{Cause, Severity, SurfacePoint};
    use glam::DVec3;

    fn placed(shape: DamageShape, face: Face, along: f64, height: f64) -> Damage {
        Damage {
            shape,
            member: "beam".into(),
            position: SurfacePoint {
                along,
                face,
                height,
            },
            size: [0.2, 0.2],
            orientation: 0.0,
            severity: Severity::Light,
            cause: Cause::Placed,
        }
    }

    fn square(face: Face, at: DVec2, half: f64) -> Vec<SurfacePoint> {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(a, b)| SurfacePoint {
                along: at.x + a * half,
                face,
                height: at.y + b * half,
            })
            .to_vec()
    }

    fn beam_with(damage: Vec<Damage>) -> BeamSpec {
        let mut b = BeamSpec::rectangular(4.0, 0.3, 0.5);
        b.damage_asked.placed = damage;
        b
    }

    #[test]
    fn a_refined_outline_keeps_its_area_and_a_cap_over_every_point() {
        let spall = placed(
            DamageShape::Spall {
                outline: square(Face::Bottom, DVec2::new(2.0, 0.0), 0.1),
                depth: 0.03,
            },
            Face::Bottom,
            2.0,
            0.0,
        );
        let relief = Relief::of(&spall).unwrap();
        let rect = crate::geometry::outline::rectangle(0.3, 0.5, 1);
        let fine = refine_outline(&rect, &[relief]).unwrap();
        // 29 grid lines across 0.2 + 4 cells, all within the 0.3 m bottom edge.
        assert_eq!(fine.loops[0].len(), 4 + 29);
        let cap_area: f64 = fine
            .cap
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| fine.loops[0][i as usize]);
                0.5 * (b - a).perp_dot(c - a)
            })
            .sum();
        assert!((cap_area - 0.15).abs() < 1e-15, "{cap_area}");
        assert!(fine.cap.iter().all(|t| {
            let [a, b, c] = t.map(|i| fine.loops[0][i as usize]);
            (b - a).perp_dot(c - a) > 0.0
        }));
    }

    #[test]
    fn a_spalled_beam_is_closed_with_its_floor_at_the_spall_depth_and_bars_below_it() {
        let (depth, half) = (0.05, 0.1);
        let spall = placed(
            DamageShape::Spall {
                outline: square(Face::Bottom, DVec2::new(2.0, 0.0), half),
                depth,
            },
            Face::Bottom,
            2.0,
            0.0,
        );
        let mut b = beam_with(vec![spall]);
        b.damage_asked.reinforcement = Some(Reinforcement::default());
        let built = mesh_beam(&b, 1e-3).unwrap();
        assert!(built.mesh.is_closed_and_oriented());
        // Rest vertices strictly inside the square lie on the floor, z = −h/2 + depth; none
        // is pushed deeper, and the face outside the wall is untouched.
        let floor = -0.25 + depth;
        let inside = |p: DVec3| (p.x - 0.0).abs() < half - 1e-9 && p.y.abs() < half - 1e-9;
        let on_floor = built
            .rest
            .iter()
            .filter(|p| inside(**p) && (p.z - floor).abs() < 1e-12)
            .count();
        assert!(on_floor > 300, "{on_floor}");
        // Off the bars, the bottom lies between the face and the floor: on the face beyond
        // the wall (1.5 cells of 0.2/24 m outside the square), never deeper than the floor.
        let on_bar = |p: &DVec3| {
            [-0.107, 0.0, 0.107]
                .iter()
                .any(|y| (p.y - y).hypot(p.z + 0.207) < 0.008 + 1e-12)
        };
        let wall = 1.5 * 0.2 / 24.0;
        for p in built.rest.iter().filter(|p| p.z < -0.15 && !on_bar(p)) {
            assert!(p.z >= -0.25 - 1e-12 && p.z <= floor + 1e-12, "{p}");
            let outside = (p.x.abs() - half).max(p.y.abs() - half);
            if outside > wall + 1e-9 {
                assert_eq!(p.z, -0.25, "{p}");
            }
        }
        // Bars: three φ16 at 35 mm cover, their axes 43 mm above the bottom, at y = 0 and
        // ±0.107 m: only the middle one crosses the 0.2 m wide cavity, so only it is meshed.
        let bar_points = |y: f64| {
            let near = |p: &&DVec3| (p.y - y).hypot(p.z + 0.207) < 0.008 + 1e-12;
            built.rest.iter().filter(near).count()
        };
        assert!(bar_points(0.0) >= 12 * 20, "{}", bar_points(0.0));
        assert_eq!(bar_points(0.107) + bar_points(-0.107), 0);
    }

    #[test]
    fn damage_that_is_not_geometry_leaves_the_mesh_as_the_sound_beams() {
        let crack = placed(
            DamageShape::FlexuralCrack {
                path: square(Face::SideNegY, DVec2::new(2.0, 0.0), 0.1),
                width_mm: 0.3,
            },
            Face::SideNegY,
            2.0,
            0.0,
        );
        let sound = mesh_beam(&beam_with(Vec::new()), 1e-3).unwrap();
        let cracked = mesh_beam(&beam_with(vec![crack]), 1e-3).unwrap();
        assert_eq!(sound.mesh, cracked.mesh);
        assert_eq!(sound.rest, cracked.rest);
    }

    #[test]
    fn a_dent_is_a_smooth_bowl_of_its_depth_flat_at_its_rim() {
        let (depth, radius) = (0.02, 0.12);
        let dent = placed(
            DamageShape::Dent { depth, radius },
            Face::SideNegY,
            2.0,
            0.05,
        );
        let built = mesh_beam(&beam_with(vec![dent]), 1e-3).unwrap();
        assert!(built.mesh.is_closed_and_oriented());
        for p in built.rest.iter().filter(|p| p.y < -0.15 + 0.03) {
            let s = ((p.x - 0.0).powi(2) + (p.z - 0.05).powi(2)) / (radius * radius);
            let want = if s < 1.0 {
                depth * (1.0 - s).powi(2)
            } else {
                0.0
            };
            assert!((p.y + 0.15 - want).abs() < 1e-12, "{p}: {want}");
        }
        // A vertex sits at the centre, pushed by the full depth.
        assert!(built.rest.iter().any(|p| p.x.abs() < 1e-9
            && (p.z - 0.05).abs() < 1e-9
            && (p.y + 0.15 - depth).abs() < 1e-12));
    }
}
