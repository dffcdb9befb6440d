//! Damage on a structure's surface, per pixel: which damage a pixel's surface point lies on
//! (the per-pixel class, instance, crack-width and crack-coverage labels) and how it changes the
//! surface's look (cracks darken by their coverage of the pixel, corrosion browns and pits the
//! albedo with stains running down, a spall's fracture surfaces are dulled and its exposed
//! bars drawn as rusty steel). Spalls and dents are cut into the mesh by `build::relief`; here
//! a point under a face's plane within a spall's or dent's reach takes its label.
//!
//! Owns: the damage marks of a piece in its own material frame (plain numbers: the pipeline
//! turns the mechanics' records into them), the coverage model of a crack of width w over a
//! pixel's footprint (the exact area of the crack's band over the pixel's parallelogram on the
//! surface, docs/damage.md), and the `Surfaces` wrapper that draws them. Points are found on
//! the undeformed surface (the hit carried through its triangle to the rest mesh), so damage
//! moves with the structure. Nothing here draws random numbers: pitting and map cracking come
//! from a hash of integer cell coordinates.

use super::shade::Surfaces;
use super::surfaces::affine_weights;
use super::trace::{GBuffer, NO_HIT};
use crate::cameras::Camera;
use crate::geometry::Mesh;
use crate::geometry::outline::polygon_contains;
use crate::materials::Surface;
use glam::{DMat3, DVec2, DVec3};
use rayon::prelude::*;

/// The per-pixel damage class (the value `damage_class.png` holds).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default)]
#[repr(u8)]
pub enum DamageClass {
    /// No damage (or no surface).
    #[default]
    None = 0,
    /// A flexural crack.
    FlexuralCrack = 1,
    /// An inclined shear crack.
    ShearCrack = 2,
    /// Map cracking.
    MapCracking = 3,
    /// Corrosion and the stains running from it.
    Corrosion = 4,
    /// A spall.
    Spall = 5,
    /// A dent.
    Dent = 6,
    /// A local buckle of a shell.
    Buckle = 7,
}

impl DamageClass {
    /// The name of each class by value, as the view record and the damage records call them.
    pub const NAMES: [&'static str; 8] = [
        "none",
        "flexural_crack",
        "shear_crack",
        "map_cracking",
        "corrosion",
        "spall",
        "dent",
        "buckle",
    ];
}

/// A face of a prismatic piece, in its own frame (x along the axis, y across, z up).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PieceFace {
    /// The underside, normal −z.
    Bottom,
    /// The top, normal +z.
    Top,
    /// The side facing −y.
    SideNegY,
    /// The side facing +y.
    SidePosY,
}

impl PieceFace {
    /// The face whose outward normal `n` (piece frame) points along; None for the end caps.
    fn facing(n: DVec3) -> Option<PieceFace> {
        let a = n.abs();
        if a.x >= a.y && a.x >= a.z {
            None
        } else if a.z >= a.y {
            Some(if n.z < 0.0 {
                PieceFace::Bottom
            } else {
                PieceFace::Top
            })
        } else {
            Some(if n.y < 0.0 {
                PieceFace::SideNegY
            } else {
                PieceFace::SidePosY
            })
        }
    }

    /// Whether the face is a side (its across coordinate is z).
    pub fn is_side(self) -> bool {
        matches!(self, PieceFace::SideNegY | PieceFace::SidePosY)
    }

    /// Coordinates on the face of a piece-frame point or vector: (along the axis, across it:
    /// z on the sides, y on top and bottom).
    fn coordinates(self, v: DVec3) -> DVec2 {
        if self.is_side() {
            DVec2::new(v.x, v.z)
        } else {
            DVec2::new(v.x, v.y)
        }
    }

    /// Outward unit normal, piece frame.
    pub fn normal(self) -> DVec3 {
        match self {
            PieceFace::Bottom => -DVec3::Z,
            PieceFace::Top => DVec3::Z,
            PieceFace::SideNegY => -DVec3::Y,
            PieceFace::SidePosY => DVec3::Y,
        }
    }
}

/// A straight piece of a crack on one face: its ends in face coordinates (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceSegment {
    /// The face it lies on.
    pub face: PieceFace,
    /// Start, (along, across).
    pub from: DVec2,
    /// End.
    pub to: DVec2,
}

/// What a damage is on the surface.
#[derive(Clone, Debug, PartialEq)]
pub enum MarkShape {
    /// A crack: straight pieces on the faces, `width` metres wide.
    Crack {
        /// Its pieces.
        segments: Vec<FaceSegment>,
        /// Width, metres.
        width: f64,
    },
    /// A net of cracks bounding cells about `cell` metres wide over [from, to] of one face.
    Network {
        /// The face.
        face: PieceFace,
        /// Start along the axis, metres.
        from: f64,
        /// End along the axis, metres.
        to: f64,
        /// Cell size, metres.
        cell: f64,
        /// Crack width, metres.
        width: f64,
    },
    /// Corrosion over [from, to] of `faces`, `strength` 0–1, stains running down the sides
    /// below a corroded top by `stain_length` metres.
    Corrosion {
        /// The faces.
        faces: Vec<PieceFace>,
        /// With the bottom among `faces`: how far above the underside every face is corroded
        /// too, metres (an I-section's bottom flange, on which water and debris lie, and its
        /// junction with the web; 0 for sections whose underside is one face).
        rises: f64,
        /// Start along the axis, metres.
        from: f64,
        /// End, metres.
        to: f64,
        /// How dark and dense the rust is, 0–1.
        strength: f64,
        /// How far stains run down, metres.
        stain_length: f64,
    },
    /// A spall: a cavity under a polygon on a face (face coordinates), and the bars it lays
    /// bare.
    Spall {
        /// The face.
        face: PieceFace,
        /// Its outline, closed.
        outline: Vec<DVec2>,
        /// Depth of its floor under the face, metres.
        depth: f64,
        /// How far beyond the outline its walls may reach on the face, metres.
        reach: f64,
        /// Centres of the exposed bars in the section, piece frame (y, z).
        bars: Vec<DVec2>,
        /// The bars' radius, metres.
        bar_radius: f64,
    },
    /// A dent: a bowl under a disc on a face.
    Dent {
        /// The face.
        face: PieceFace,
        /// Its centre, face coordinates.
        centre: DVec2,
        /// Radius, metres.
        radius: f64,
        /// Depth at its centre, metres.
        depth: f64,
    },
}

/// One damage of a piece, with its label.
#[derive(Clone, Debug, PartialEq)]
pub struct Mark {
    /// Its class.
    pub class: DamageClass,
    /// Its id in the instance layer: index + 1 in its structure's damage list.
    pub instance: u16,
    /// Where it is.
    pub shape: MarkShape,
}

/// A damaged prismatic piece: which triangles are its, its frame, its marks.
#[derive(Clone, Debug, PartialEq)]
pub struct DamagedPiece {
    /// The structure index its triangles have (`owner`).
    pub structure: u32,
    /// The part index its triangles have.
    pub part: u32,
    /// When several pieces of a structure share a part (a frame's members), the mesh piece
    /// (`BuiltSample::piece`) its triangles have; None: every triangle of the part.
    pub mesh_piece: Option<u32>,
    /// Rotation from the piece frame to the world.
    pub rotation: DMat3,
    /// World position of the piece frame's point (length/2, 0, 0): the undeformed centre.
    pub centre: DVec3,
    /// Length, metres (the frame's x runs from 0 to it).
    pub length: f64,
    /// Half the section's height, metres: top and bottom faces lie at z = ±this.
    pub half_height: f64,
    /// Half the section's width, metres: the sides lie at y = ±this.
    pub half_width: f64,
    /// Its damage.
    pub marks: Vec<Mark>,
}

impl DamagedPiece {
    /// A world point of the undeformed piece in the piece frame.
    fn local(&self, rest: DVec3) -> DVec3 {
        self.rotation.transpose() * (rest - self.centre) + DVec3::new(0.5 * self.length, 0.0, 0.0)
    }

    /// A piece-frame point in the world (undeformed).
    pub fn world(&self, local: DVec3) -> DVec3 {
        self.centre + self.rotation * (local - DVec3::new(0.5 * self.length, 0.0, 0.0))
    }
}

/// What damage a surface point shows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DamageAt {
    /// The label's class.
    pub class: DamageClass,
    /// The label's instance (0: none).
    pub instance: u16,
    /// Width of the crack the pixel touches, millimetres (0: none).
    pub crack_width_mm: f64,
    /// Share of the pixel's footprint the crack covers, 0–1.
    pub crack_coverage: f64,
    /// Rust's strength at the point, 0–1 (pitting included).
    pub rust: f64,
    /// Whether the point lies in a spall.
    pub spalled: bool,
    /// Whether the point lies on a bar a spall exposes.
    pub rebar: bool,
}

/// A pixel's footprint on the undeformed surface: the point under its centre and the
/// piece-frame vectors one pixel right and one pixel down move it by.
#[derive(Clone, Copy, Debug)]
pub struct Footprint {
    /// The point, piece frame.
    pub point: DVec3,
    /// One pixel along the image's u axis, piece frame.
    pub du: DVec3,
    /// One pixel along v.
    pub dv: DVec3,
}

/// Share of a pixel covered by a straight band `width` wide whose centre line passes `offset`
/// from the pixel centre, when the pixel's footprint projects onto the band's normal as two
/// edges of lengths `a` and `b` (a parallelogram): the footprint's extent along the normal is
/// then distributed as the sum of two uniforms, and the covered share is that distribution's
/// mass inside the band. A square pixel with the band along one of its axes has a = f, b = 0:
/// min(1, width/f) where the band lies inside the pixel.
pub fn band_coverage(offset: f64, width: f64, a: f64, b: f64) -> f64 {
    let (a, b) = (a.abs().max(b.abs()), a.abs().min(b.abs()));
    if a == 0.0 {
        return 0.0;
    }
    // The CDF of U(0, a) + U(0, b) at s, by pieces (no cancellation when b ≪ a): a quadratic
    // ramp over [0, b], linear over [b, a], a quadratic ramp over [a, a + b].
    let cdf = |t: f64| {
        let s = t + 0.5 * (a + b);
        if s <= 0.0 {
            0.0
        } else if s >= a + b {
            1.0
        } else if s < b {
            s * s / (2.0 * a * b)
        } else if s <= a {
            (s - 0.5 * b) / a
        } else {
            1.0 - (a + b - s).powi(2) / (2.0 * a * b)
        }
    };
    let centre = offset.abs();
    (cdf(centre + 0.5 * width) - cdf(centre - 0.5 * width)).clamp(0.0, 1.0)
}

/// How much of the footprint a crack piece at 2-D `offset` (from the point, face coordinates)
/// with unit `normal` covers.
fn crack_piece_coverage(offset: f64, normal: DVec2, width: f64, du: DVec2, dv: DVec2) -> f64 {
    band_coverage(offset, width, du.dot(normal), dv.dot(normal))
}

/// Distance from `p` to segment [a, b] and the segment's unit normal.
fn to_segment(p: DVec2, a: DVec2, b: DVec2) -> (f64, DVec2) {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 == 0.0 {
        return ((p - a).length(), DVec2::X);
    }
    let t = ((p - a).dot(ab) / len2).clamp(0.0, 1.0);
    let normal = DVec2::new(-ab.y, ab.x) / len2.sqrt();
    ((p - (a + t * ab)).length(), normal)
}

/// A hash of integer cell coordinates to [0, 1): the same cell gives the same number on any
/// thread.
fn cell_hash(i: i64, j: i64, salt: u64) -> f64 {
    let mut z = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ salt.wrapping_mul(0x1656_67B1_9E37_79F9);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// The site of cell (i, j) of a jittered grid of `cell` metres.
fn site(i: i64, j: i64, cell: f64, salt: u64) -> DVec2 {
    let jitter = DVec2::new(cell_hash(i, j, salt), cell_hash(i, j, salt ^ 0x5bd1));
    (DVec2::new(i as f64, j as f64) + 0.15 + 0.7 * jitter) * cell
}

/// Distance from `p` to the nearest edge of the Voronoi cells of a jittered grid, and that
/// edge's unit normal: the cracks of map cracking run along the cell edges.
fn to_cell_edge(p: DVec2, cell: f64, salt: u64) -> (f64, DVec2) {
    let (ci, cj) = ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
    let near = |di: i64, dj: i64| site(ci + di, cj + dj, cell, salt);
    let neighbours: Vec<DVec2> = (-2..=2)
        .flat_map(|di| (-2..=2).map(move |dj| (di, dj)))
        .map(|(di, dj)| near(di, dj))
        .collect();
    let own = *neighbours
        .iter()
        .min_by(|a, b| a.distance_squared(p).total_cmp(&b.distance_squared(p)))
        .expect("25 sites");
    neighbours
        .iter()
        .filter(|&&s| s != own)
        .map(|&s| {
            let normal = (s - own).normalize();
            (normal.dot(0.5 * (own + s) - p).abs(), normal)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap_or((f64::INFINITY, DVec2::X))
}

/// The region label a point keeps when it lies in several: a spall over a dent over corrosion
/// (the class further down the table), the first of equal classes.
fn prevailing(kept: Option<(DamageClass, u16)>, new: (DamageClass, u16)) -> (DamageClass, u16) {
    match kept {
        Some(k) if k.0 >= new.0 => k,
        _ => new,
    }
}

/// Pits of rust: a value 0.6–1 per 6 mm cell.
fn pitting(p: DVec2, salt: u64) -> f64 {
    const PIT: f64 = 0.006;
    0.6 + 0.4 * cell_hash((p.x / PIT).floor() as i64, (p.y / PIT).floor() as i64, salt)
}

impl DamagedPiece {
    /// The damage a pixel's footprint shows: the crack covering most of it, else a spall, a
    /// dent or corrosion (first of the piece's marks of that kind); rust is reported wherever
    /// corrosion lies, under any crack. On an inner face (an I's flange seen from the web's
    /// side) only a corroded bottom's rise reaches.
    pub fn at(&self, footprint: &Footprint, face: PieceFace, outer: bool) -> DamageAt {
        let p = face.coordinates(footprint.point);
        let (du, dv) = (
            face.coordinates(footprint.du),
            face.coordinates(footprint.dv),
        );
        let mut found = DamageAt::default();
        let mut region: Option<(DamageClass, u16)> = None;
        for mark in &self.marks {
            if !outer && !matches!(mark.shape, MarkShape::Corrosion { .. }) {
                continue;
            }
            let covered = |(offset, normal): (f64, DVec2), width: f64| {
                crack_piece_coverage(offset, normal, width, du, dv)
            };
            let crack = match &mark.shape {
                MarkShape::Crack { segments, width } => segments
                    .iter()
                    .filter(|s| s.face == face)
                    .map(|s| covered(to_segment(p, s.from, s.to), *width))
                    .fold(0.0, f64::max),
                MarkShape::Network {
                    face: on,
                    from,
                    to,
                    cell,
                    width,
                } if *on == face && (*from..=*to).contains(&p.x) => {
                    covered(to_cell_edge(p, *cell, u64::from(mark.instance)), *width)
                }
                MarkShape::Corrosion {
                    faces,
                    rises,
                    from,
                    to,
                    strength,
                    stain_length,
                } if (*from..=*to).contains(&p.x) => {
                    let low = faces.contains(&PieceFace::Bottom)
                        && footprint.point.z <= *rises - self.half_height;
                    let rust = if low {
                        *strength
                    } else if outer {
                        self.rust(p, face, faces, *strength, *stain_length)
                    } else {
                        0.0
                    };
                    if rust > 0.0 {
                        found.rust = found.rust.max(rust * pitting(p, u64::from(mark.instance)));
                        region = Some(prevailing(region, (mark.class, mark.instance)));
                    }
                    0.0
                }
                MarkShape::Spall {
                    face: on, outline, ..
                } if *on == face => {
                    if polygon_contains(outline, p) {
                        found.spalled = true;
                        region = Some(prevailing(region, (mark.class, mark.instance)));
                    }
                    0.0
                }
                MarkShape::Dent {
                    face: on,
                    centre,
                    radius,
                    ..
                } if *on == face && p.distance(*centre) <= *radius => {
                    region = Some(prevailing(region, (mark.class, mark.instance)));
                    0.0
                }
                _ => 0.0,
            };
            if crack > found.crack_coverage {
                found.crack_coverage = crack;
                found.class = mark.class;
                found.instance = mark.instance;
                found.crack_width_mm = match &mark.shape {
                    MarkShape::Crack { width, .. } | MarkShape::Network { width, .. } => {
                        width * 1e3
                    }
                    _ => 0.0,
                };
            }
        }
        if found.crack_coverage == 0.0
            && let Some((class, instance)) = region
        {
            found.class = class;
            found.instance = instance;
        }
        found
    }

    /// How far the piece-frame point `local` lies under the plane of `face` (inside the
    /// piece: positive).
    fn under(&self, face: PieceFace, local: DVec3) -> f64 {
        let plane = match face.is_side() {
            true => self.half_width,
            false => self.half_height,
        };
        plane - local.dot(face.normal())
    }

    /// The spall or dent whose pushed-in surface, or exposed bar, the undeformed piece-frame
    /// point `local` lies on: a point under a face's plane (by more than rounding, and no
    /// deeper than the relief) within the relief's reach on that face. None elsewhere.
    fn relief_at(&self, local: DVec3) -> Option<DamageAt> {
        let tiny = 1e-9 * (1.0 + self.length);
        self.marks.iter().find_map(|mark| {
            let (face, depth, within, rebar) = match &mark.shape {
                MarkShape::Spall {
                    face,
                    outline,
                    depth,
                    reach,
                    bars,
                    bar_radius,
                } => {
                    let p = face.coordinates(local);
                    let lo = outline.iter().copied().reduce(DVec2::min)? - *reach;
                    let hi = outline.iter().copied().reduce(DVec2::max)? + *reach;
                    let near = p.cmpge(lo).all() && p.cmple(hi).all();
                    let section = DVec2::new(local.y, local.z);
                    let on_bar = bars
                        .iter()
                        .any(|c| c.distance(section) <= bar_radius * (1.0 + 1e-6));
                    (*face, *depth, near, on_bar)
                }
                MarkShape::Dent {
                    face,
                    centre,
                    radius,
                    depth,
                } => {
                    let near = face.coordinates(local).distance(*centre) <= *radius;
                    (*face, *depth, near, false)
                }
                _ => return None,
            };
            let under = self.under(face, local);
            (within && under > tiny && under <= depth + tiny).then_some(DamageAt {
                class: mark.class,
                instance: mark.instance,
                spalled: mark.class == DamageClass::Spall,
                rebar,
                ..DamageAt::default()
            })
        })
    }

    /// Rust at face point `p` of a corrosion over `faces`: `strength` on them, and on the
    /// sides below a corroded top, fading over `stain_length` in streaks.
    fn rust(
        &self,
        p: DVec2,
        face: PieceFace,
        faces: &[PieceFace],
        strength: f64,
        stain: f64,
    ) -> f64 {
        if faces.contains(&face) {
            return strength;
        }
        if !(face.is_side() && faces.contains(&PieceFace::Top) && stain > 0.0) {
            return 0.0;
        }
        let below = self.half_height - p.y;
        if !(0.0..stain).contains(&below) {
            return 0.0;
        }
        // Streaks 2 cm wide, each running its own share of the stain length.
        let streak = cell_hash((p.x / 0.02).floor() as i64, 0, 0x57a1);
        let reach = stain * (0.3 + 0.7 * streak);
        if below < reach {
            0.6 * strength * (1.0 - below / reach)
        } else {
            0.0
        }
    }
}

/// A dent or local buckle on a shell: a disc of `radius` metres (measured on the surface)
/// about a point of the shell's undeformed outer surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShellMark {
    /// Its class (`Dent` or `Buckle`).
    pub class: DamageClass,
    /// Its id in the instance layer: index + 1 in its structure's damage list.
    pub instance: u16,
    /// Angle of its centre about the shell's axis, radians.
    pub angle: f64,
    /// Height of its centre above the shell's base, metres.
    pub height: f64,
    /// Radius on the surface, metres.
    pub radius: f64,
}

/// A damaged cylindrical shell: which triangles are its, its own frame (axis along z from
/// its base), its outer radius and wall, and its marks. Dents and buckles are geometry (the
/// shell's patterns displace its mesh); here a point of its undeformed outer surface within
/// a mark's radius takes its label.
#[derive(Clone, Debug, PartialEq)]
pub struct DamagedShell {
    /// The structure index its triangles have (`owner`).
    pub structure: u32,
    /// The part index its triangles have.
    pub part: u32,
    /// From world coordinates of the undeformed structure to the shell's own frame.
    pub to_local: glam::DAffine3,
    /// Outer radius, metres.
    pub radius: f64,
    /// Wall thickness, metres (the inner surface, `radius − wall` from the axis, is not
    /// labelled: an inspector sees the outside).
    pub wall: f64,
    /// Its dents and buckles.
    pub marks: Vec<ShellMark>,
}

impl DamagedShell {
    /// The label of the undeformed world point `rest`, if it lies on the outer surface within a
    /// mark (surface distance: arc about the axis and height); the first mark wins.
    pub fn at(&self, rest: DVec3) -> Option<DamageAt> {
        let p = self.to_local.transform_point3(rest);
        if p.x.hypot(p.y) < self.radius - 0.5 * self.wall {
            return None;
        }
        let theta = p.y.atan2(p.x);
        let mark = self.marks.iter().find(|m| {
            let turn = (theta - m.angle + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            (self.radius * turn).hypot(p.z - m.height) < m.radius
        })?;
        Some(DamageAt {
            class: mark.class,
            instance: mark.instance,
            ..DamageAt::default()
        })
    }
}

/// The damaged pieces of a sample and, per triangle of its mesh, which piece it belongs to.
pub struct SampleDamage {
    pieces: Vec<DamagedPiece>,
    /// Index into `pieces` of every triangle, `u32::MAX` for undamaged ones.
    piece_of: Vec<u32>,
    /// The sample's dented or buckled shells.
    shells: Vec<DamagedShell>,
    /// Index into `shells` of every triangle, `u32::MAX` for others.
    shell_of: Vec<u32>,
}

impl SampleDamage {
    /// The damage of `pieces` and `shells` on a mesh whose triangles have `owner`
    /// (structure), `part` and `mesh_piece` indices; None when nothing has damage (then
    /// nothing changes).
    pub fn new(
        pieces: Vec<DamagedPiece>,
        shells: Vec<DamagedShell>,
        owner: &[u32],
        part: &[u32],
        mesh_piece: &[u32],
    ) -> Option<SampleDamage> {
        if pieces.iter().all(|p| p.marks.is_empty()) && shells.iter().all(|s| s.marks.is_empty()) {
            return None;
        }
        let index_of = |found: Option<usize>| found.map_or(u32::MAX, |k| k as u32);
        let triangles = owner.iter().zip(part);
        let piece_of = triangles
            .clone()
            .zip(mesh_piece)
            .map(|((&o, &p), &m)| {
                index_of(pieces.iter().position(|d| {
                    d.structure == o && d.part == p && d.mesh_piece.is_none_or(|k| k == m)
                }))
            })
            .collect();
        let shell_of = triangles
            .map(|(&o, &p)| index_of(shells.iter().position(|d| d.structure == o && d.part == p)))
            .collect();
        Some(SampleDamage {
            pieces,
            piece_of,
            shells,
            shell_of,
        })
    }

    /// The shells of the same structure and part as triangle `tri` (a part may hold several
    /// tubes): each tells whether a point is its own.
    fn shells_of(&self, tri: u32) -> impl Iterator<Item = &DamagedShell> {
        let first = self.shell_of.get(tri as usize).copied().unwrap_or(u32::MAX);
        let key = self
            .shells
            .get(first as usize)
            .map(|s| (s.structure, s.part));
        self.shells
            .iter()
            .filter(move |s| key == Some((s.structure, s.part)))
    }

    /// The damaged pieces.
    pub fn pieces(&self) -> &[DamagedPiece] {
        &self.pieces
    }

    fn piece(&self, tri: u32) -> Option<&DamagedPiece> {
        match self.piece_of.get(tri as usize) {
            Some(&k) if k != u32::MAX => Some(&self.pieces[k as usize]),
            _ => None,
        }
    }

    /// What the point `p` of triangle `tri` of `mesh` (whose vertices lie at `rest` undeformed)
    /// shows, seen through `camera` at image point (u, v).
    fn at_point(&self, seen: &SeenMesh, tri: u32, p: DVec3, uv: (f64, f64)) -> Option<DamageAt> {
        let piece = self.piece(tri)?;
        let local = piece.local(rest_point(seen, tri, p));
        if let Some(relief) = piece.relief_at(local) {
            return Some(relief);
        }
        let [a, b, c] = seen.mesh.triangles[tri as usize].map(|i| seen.rest[i as usize]);
        let rest_normal = piece.rotation.transpose() * (b - a).cross(c - a).normalize_or_zero();
        let face = PieceFace::facing(rest_normal)?;
        // Top and bottom are the outer faces (not the inner faces of an I's flanges).
        let outer =
            face.is_side() || (local.z.abs() - piece.half_height).abs() <= 0.01 * piece.half_height;
        let footprint = footprint(seen, tri, p, uv, piece)?;
        Some(piece.at(&footprint, face, outer))
    }

    /// The per-pixel damage labels of what `g` saw through `camera` on `seen`.
    pub fn labels(&self, g: &GBuffer, camera: &Camera, seen: &SeenMesh) -> Vec<DamageAt> {
        let width = g.width as usize;
        let mut out = vec![DamageAt::default(); g.triangle.len()];
        out.par_chunks_mut(width)
            .enumerate()
            .for_each(|(row, line)| {
                for (col, value) in line.iter_mut().enumerate() {
                    let tri = g.triangle[row * width + col];
                    if tri == NO_HIT {
                        continue;
                    }
                    let on_shell = self.shells_of(tri).next().is_some();
                    if self.piece(tri).is_none() && !on_shell {
                        continue;
                    }
                    let uv = (col as f64 + 0.5, row as f64 + 0.5);
                    let p = seen.centre_hit(camera, tri, uv, f64::from(g.depth[row * width + col]));
                    let found = if on_shell {
                        let rest = rest_point(seen, tri, p);
                        self.shells_of(tri).find_map(|s| s.at(rest))
                    } else {
                        self.at_point(seen, tri, p, uv)
                    };
                    if let Some(d) = found {
                        *value = d;
                    }
                }
            });
        out
    }
}

/// A mesh as traced, with the undeformed position of each vertex, and the camera.
pub struct SeenMesh<'a> {
    /// The mesh as traced (loaded, or the unloaded one).
    pub mesh: &'a Mesh,
    /// Undeformed position of each of its vertices.
    pub rest: &'a [DVec3],
    /// The camera it is seen through.
    pub camera: &'a Camera,
}

impl SeenMesh<'_> {
    /// The surface point a pixel's centre ray (through `uv`) met on triangle `tri` at planar
    /// `depth`: on the triangle's plane (f64) where that agrees with the traced depth to 0.1 %,
    /// else at the traced depth (a plane seen edge-on meets the ray far from the hit).
    fn centre_hit(&self, camera: &Camera, tri: u32, uv: (f64, f64), depth: f64) -> DVec3 {
        let traced =
            camera.position + camera.rotation * camera.intrinsics.ray_through(uv.0, uv.1) * depth;
        match self.hit(camera, tri, uv) {
            Some(p) if (camera.world_to_camera(p).z - depth).abs() <= 1e-3 * depth => p,
            _ => traced,
        }
    }

    /// Where the ray through image point `uv` meets the plane of triangle `tri`.
    fn hit(&self, camera: &Camera, tri: u32, uv: (f64, f64)) -> Option<DVec3> {
        let [a, b, c] = self.mesh.triangles[tri as usize].map(|i| self.mesh.positions[i as usize]);
        let n = (b - a).cross(c - a);
        let dir = camera.rotation * camera.intrinsics.ray_through(uv.0, uv.1);
        let t = n.dot(a - camera.position) / n.dot(dir);
        (t.is_finite() && t > 0.0).then(|| camera.position + t * dir)
    }
}

/// The undeformed point of world point `p` of triangle `tri`.
fn rest_point(seen: &SeenMesh, tri: u32, p: DVec3) -> DVec3 {
    let ids = seen.mesh.triangles[tri as usize];
    let [a, b, c] = ids.map(|i| seen.mesh.positions[i as usize]);
    ids.iter()
        .zip(affine_weights(a, b, c, p))
        .map(|(&i, w)| w * seen.rest[i as usize])
        .sum()
}

/// The footprint of the pixel at image point `uv` whose centre ray meets `p` on triangle
/// `tri`: the points half a pixel either side along u and v, on the triangle's plane, carried
/// to the undeformed piece. At grazing rays the footprint is capped at ten times its size
/// face-on, as the shading's is.
fn footprint(
    seen: &SeenMesh,
    tri: u32,
    p: DVec3,
    uv: (f64, f64),
    piece: &DamagedPiece,
) -> Option<Footprint> {
    let camera = seen.camera;
    let k = camera.intrinsics;
    let (w, h) = (f64::from(k.width), f64::from(k.height));
    let (u, v) = (uv.0.clamp(0.5, w - 0.5), uv.1.clamp(0.5, h - 0.5));
    let at = |u: f64, v: f64| {
        seen.hit(camera, tri, (u, v))
            .map(|q| rest_point(seen, tri, q))
    };
    let (u0, u1, v0, v1) = (
        at(u - 0.5, v)?,
        at(u + 0.5, v)?,
        at(u, v - 0.5)?,
        at(u, v + 0.5)?,
    );
    let depth = camera.world_to_camera(p).z;
    let cap = 10.0 * depth / k.fx.min(k.fy);
    let capped = |d: DVec3| d.clamp_length_max(cap);
    let to_piece = piece.rotation.transpose();
    Some(Footprint {
        point: piece.local(rest_point(seen, tri, p)),
        du: to_piece * capped(u1 - u0),
        dv: to_piece * capped(v1 - v0),
    })
}

/// Linear albedo of an open crack: a dark gap.
const CRACK_ALBEDO: [f64; 3] = [0.02, 0.018, 0.016];
/// Linear albedo of dense rust: dark brown (FHWA: corrosion "dark brown to black" where
/// active, with orange-brown stains).
const RUST_ALBEDO: [f64; 3] = [0.09, 0.035, 0.012];
/// Linear albedo of light surface rust and stains: orange-brown.
const SURFACE_RUST_ALBEDO: [f64; 3] = [0.25, 0.09, 0.03];
/// What a spall's cavity keeps of the light beyond the shadows its walls now cast: fresh
/// fracture surfaces of concrete are rougher and dustier than the formed face.
const SPALL_SHADE: f64 = 0.8;
/// Linear albedo of an exposed bar: steel under a skin of rust (FHWA: exposed reinforcement
/// "corroded", brown).
const REBAR_ALBEDO: [f64; 3] = [0.12, 0.06, 0.03];

/// The look of `surface` with the damage `d` drawn on it.
pub fn drawn(mut surface: Surface, d: &DamageAt) -> Surface {
    let mix = |base: [f64; 3], to: [f64; 3], t: f64| -> [f64; 3] {
        std::array::from_fn(|k| base[k] * (1.0 - t) + to[k] * t)
    };
    if d.rust > 0.0 {
        // Rust hides the coat over more of the surface than its density alone says (paint
        // lifts around each pit), and darkens from orange-brown to dark brown as it thickens.
        let rust = d.rust.clamp(0.0, 1.0);
        let colour = mix(SURFACE_RUST_ALBEDO, RUST_ALBEDO, rust);
        surface.albedo = mix(surface.albedo, colour, rust.sqrt());
        surface.roughness = surface.roughness.max(0.9);
        surface.specular *= 1.0 - rust;
    }
    if d.rebar {
        surface.albedo = REBAR_ALBEDO;
        surface.roughness = 0.6;
        surface.specular = 0.04;
    } else if d.spalled {
        surface.albedo = surface.albedo.map(|a| a * SPALL_SHADE);
    }
    if d.crack_coverage > 0.0 {
        surface.albedo = mix(surface.albedo, CRACK_ALBEDO, d.crack_coverage);
    }
    surface
}

/// Surfaces with a sample's damage drawn on them.
pub struct DamagedSurfaces<'a, S: Surfaces> {
    /// The surfaces as they are without damage.
    pub inner: &'a S,
    /// The sample's damage.
    pub damage: &'a SampleDamage,
    /// The mesh as traced and its undeformed vertices, with the camera.
    pub seen: SeenMesh<'a>,
}

impl<S: Surfaces> Surfaces for DamagedSurfaces<'_, S> {
    fn at(&self, tri: u32, p: DVec3, footprint: f64) -> Surface {
        let surface = self.inner.at(tri, p, footprint);
        if self.damage.piece(tri).is_none() {
            return surface;
        }
        let camera = self.seen.camera;
        let seen = camera.world_to_camera(p);
        if !(seen.z > 0.0) {
            return surface;
        }
        let uv = camera.intrinsics.project(seen);
        match self.damage.at_point(&self.seen, tri, p, uv) {
            Some(d) => drawn(surface, &d),
            None => surface,
        }
    }

    fn flat(&self, tri: u32) -> [f64; 3] {
        self.inner.flat(tri)
    }

    fn textured(&self, tri: u32) -> bool {
        self.damage.piece(tri).is_some() || self.inner.textured(tri)
    }

    fn matte(&self, tri: u32) -> bool {
        self.damage.piece(tri).is_none() && self.inner.matte(tri)
    }

    fn continues(&self, a: u32, b: u32) -> bool {
        self.inner.continues(a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_band_along_a_pixel_axis_covers_its_width_over_the_footprint() {
        // Square pixel f = 20 mm, crack 0.3 mm along v: w/f wherever the band lies inside.
        let (f, w) = (0.02, 0.0003);
        for offset in [0.0, 0.004, 0.0098] {
            let c = band_coverage(offset, w, f, 0.0);
            assert!((c - w / f).abs() < 1e-12, "{offset}: {c}");
        }
        // Straddling the pixel's edge at 10 mm: half of it inside.
        assert!((band_coverage(0.01, w, f, 0.0) - 0.5 * w / f).abs() < 1e-12);
        assert_eq!(band_coverage(0.0102, w, f, 0.0), 0.0);
        // A 2 mm crack at 1 mm/px fills the pixel.
        assert_eq!(band_coverage(0.0, 0.002, 0.001, 0.0), 1.0);
    }

    #[test]
    fn a_diagonal_band_covers_its_chord_through_the_pixel() {
        // A thin band through the centre of a square pixel at 45°: its chord is f√2, so it
        // covers w·f√2/f² (the footprint's edges project as f/√2 each).
        let (f, w) = (0.01, 1e-5);
        let edge = f / 2f64.sqrt();
        let c = band_coverage(0.0, w, edge, edge);
        // (to the triangle-shaped density's curvature over the band: w/(f/√2) = 1.4e-3).
        assert!((c / (w * 2f64.sqrt() / f) - 1.0).abs() < 1e-3, "{c}");
        // Integrated over every offset the band covers w / f of a pixel's width: the
        // footprint's mass is 1.
        let n = 4000;
        let step = 2.0 * f / n as f64;
        let total: f64 = (0..n)
            .map(|k| band_coverage(-f + (k as f64 + 0.5) * step, w, edge, 0.3 * edge) * step)
            .sum();
        assert!((total / w - 1.0).abs() < 1e-3, "{total}");
    }

    #[test]
    fn map_cracking_edges_lie_halfway_between_cell_sites() {
        let cell = 0.15;
        for k in 0..50 {
            let p = DVec2::new(0.037 * k as f64, 0.011 * k as f64 - 0.2);
            let (d, n) = to_cell_edge(p, cell, 7);
            assert!(d >= 0.0 && d < cell, "{d}");
            assert!((n.length() - 1.0).abs() < 1e-12);
            // Stepping the distance along the normal (either way) reaches a point as far from
            // two sites.
            let ties = [p + d * n, p - d * n].into_iter().any(|q| {
                let (ci, cj) = ((q.x / cell).floor() as i64, (q.y / cell).floor() as i64);
                let mut dist: Vec<f64> = (-2..=2)
                    .flat_map(|i| (-2..=2).map(move |j| (i, j)))
                    .map(|(i, j)| site(ci + i, cj + j, cell, 7).distance(q))
                    .collect();
                dist.sort_by(f64::total_cmp);
                (dist[1] - dist[0]).abs() < 1e-9
            });
            assert!(ties, "{p}");
        }
    }

    #[test]
    fn points_inside_and_outside_a_polygon() {
        let square = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        assert!(polygon_contains(&square, DVec2::new(0.5, 0.5)));
        assert!(!polygon_contains(&square, DVec2::new(1.5, 0.5)));
        assert!(!polygon_contains(&square, DVec2::new(0.5, -0.1)));
    }

    #[test]
    fn a_crack_darkens_by_its_coverage_and_nothing_else_changes_a_sound_point() {
        let surface = Surface {
            albedo: [0.5, 0.5, 0.5],
            roughness: 0.8,
            specular: 0.04,
            crack: false,
        };
        assert_eq!(drawn(surface, &DamageAt::default()), surface);
        let half = DamageAt {
            crack_coverage: 0.5,
            ..DamageAt::default()
        };
        let a = drawn(surface, &half).albedo;
        assert!(
            (a[0] - 0.5 * (0.5 + CRACK_ALBEDO[0])).abs() < 1e-12,
            "{a:?}"
        );
    }
}
