//! From the mechanics' damage records of a built sample to the marks the renderer draws and
//! labels, and the warning for cracks no view of a sample can resolve.
//!
//! Owns: the translation (faces, surface coordinates, widths in metres, the strength rust is
//! drawn with, instance ids = index + 1 in a structure's `damage.items`), and the resolution
//! check. The drawing and the per-pixel labels are `render::damage`'s.

use crate::build::{BuiltSample, Relief, spall_bars};
use crate::cameras::Camera;
use crate::mechanics::Section;
use crate::mechanics::damage::{
    Damage, DamageShape, Face, ShellDamageKind, ShellDamageLabels, SurfacePoint, shell_damage,
};
use crate::render::{
    DamageClass, DamagedPiece, DamagedShell, FaceSegment, Mark, MarkShape, PieceFace, SampleDamage,
    ShellMark,
};
use crate::scene::{AssemblySpec, BeamSpec, Structure};
use glam::{DMat3, DVec2, DVec3};

/// The part name of a beam's own triangles (the one its damage records name).
const BEAM_PART: &str = "beam";

/// The dents and local buckles of an assembly's shells as damage records, shape by shape and
/// pattern by pattern; None when it has none.
pub fn assembly_damage(assembly: &AssemblySpec) -> Option<ShellDamageLabels> {
    let items: Vec<_> = assembly
        .shapes
        .iter()
        .filter_map(|s| Some((s.shell()?, s)))
        .flat_map(|(shell, s)| {
            s.shell
                .iter()
                .filter_map(move |l| shell_damage(&shell, &l.pattern, &s.part))
        })
        .collect();
    (!items.is_empty()).then_some(ShellDamageLabels { items })
}

/// The share of a pixel a crack must cover in some view for it to count as resolved.
pub const RESOLVED_COVERAGE: f64 = 0.05;

/// The damage of every damaged beam and frame member of `sample`, ready to draw; None for a
/// sound sample.
pub fn sample_damage(sample: &BuiltSample) -> Option<SampleDamage> {
    let mut pieces = match sample.parts.iter().position(|p| p == BEAM_PART) {
        Some(part) => damaged_pieces(sample, part as u32),
        None => Vec::new(),
    };
    pieces.extend(damaged_members(sample));
    SampleDamage::new(
        pieces,
        damaged_shells(sample),
        &sample.owner,
        &sample.part,
        &sample.piece,
    )
}

/// The damaged members of every frame of `sample`: each member a prism in its own frame (x
/// from its start node, z the section's height), drawn through the beam's path; instance ids
/// are index + 1 in the frame's `analysis.damage.items`.
fn damaged_members(sample: &BuiltSample) -> Vec<DamagedPiece> {
    let mut out = Vec::new();
    for (i, (structure, labels)) in sample
        .scene
        .structures
        .iter()
        .zip(&sample.frames)
        .enumerate()
    {
        let (Structure::Frame(frame), Some(damage)) =
            (structure, labels.as_ref().and_then(|l| l.damage.as_ref()))
        else {
            continue;
        };
        // A frame's mesh pieces are its members, in order.
        let first_piece = sample.pieces.iter().position(|(s, _)| *s == i as u32);
        for md in &damage.members {
            let model = &frame.model;
            let member = &model.members[md.member];
            let Some(part) = sample.parts.iter().position(|p| *p == member.part) else {
                continue;
            };
            let axes = model.member_axes(md.member);
            let start = DVec3::from_array(model.nodes[member.start]);
            let length = start.distance(DVec3::from_array(model.nodes[member.end]));
            let items = &damage.items[md.first_item..md.first_item + md.item_count];
            out.push(DamagedPiece {
                structure: i as u32,
                part: part as u32,
                mesh_piece: first_piece.map(|p| (p + md.member) as u32),
                rotation: axes.transpose(),
                centre: start + 0.5 * length * axes.row(0),
                length,
                half_height: 0.5 * member.section.height(),
                half_width: 0.5 * member.section.width(),
                marks: items
                    .iter()
                    .enumerate()
                    .map(|(k, item)| mark(None, &member.section, md.first_item + k, item))
                    .collect(),
            });
        }
    }
    out
}

/// The dented or buckled shells of `sample`'s assemblies, their marks numbered as
/// [`assembly_damage`] lists them.
fn damaged_shells(sample: &BuiltSample) -> Vec<DamagedShell> {
    let mut out = Vec::new();
    for (i, structure) in sample.scene.structures.iter().enumerate() {
        let Structure::Assembly(assembly) = structure else {
            continue;
        };
        let mut instance = 0u16;
        for shape in &assembly.shapes {
            let Some(shell) = shape.shell() else {
                continue;
            };
            let marks: Vec<ShellMark> = shape
                .shell
                .iter()
                .filter_map(|l| shell_damage(&shell, &l.pattern, &shape.part))
                .map(|d| {
                    instance = instance.saturating_add(1);
                    ShellMark {
                        class: match d.kind {
                            ShellDamageKind::Dent => DamageClass::Dent,
                            ShellDamageKind::Buckle => DamageClass::Buckle,
                        },
                        instance,
                        angle: d.position.angle,
                        height: d.position.height,
                        radius: d.radius,
                    }
                })
                .collect();
            let part = sample.parts.iter().position(|p| *p == shape.part);
            let (Some(part), false) = (part, marks.is_empty()) else {
                continue;
            };
            out.push(DamagedShell {
                structure: i as u32,
                part: part as u32,
                to_local: shape.affine().inverse(),
                radius: shell.radius,
                wall: shell.wall,
                marks,
            });
        }
    }
    out
}

fn damaged_pieces(sample: &BuiltSample, part: u32) -> Vec<DamagedPiece> {
    let structures = sample.scene.structures.iter().zip(&sample.beams);
    structures
        .enumerate()
        .filter_map(|(i, (structure, outcome))| {
            let (Structure::Beam(beam), Some(outcome)) = (structure, outcome) else {
                return None;
            };
            let damage = outcome.damage.as_ref()?;
            Some(DamagedPiece {
                structure: i as u32,
                part,
                mesh_piece: None,
                rotation: DMat3::from_rotation_z(beam.yaw),
                centre: DVec3::from_array(beam.centre),
                length: beam.length,
                half_height: 0.5 * beam.section.height(),
                half_width: 0.5 * beam.section.width(),
                marks: damage
                    .items
                    .iter()
                    .enumerate()
                    .map(|(index, item)| mark(Some(beam), &beam.section, index, item))
                    .collect(),
            })
        })
        .collect()
}

fn piece_face(face: Face) -> PieceFace {
    match face {
        Face::Bottom => PieceFace::Bottom,
        Face::Top => PieceFace::Top,
        Face::SideNegY => PieceFace::SideNegY,
        Face::SidePosY => PieceFace::SidePosY,
    }
}

fn on_face(p: &SurfacePoint) -> DVec2 {
    DVec2::new(p.along, p.height)
}

/// A crack's polyline as straight pieces on single faces (a step from one face to the next
/// is a corner, not a piece).
fn crack_segments(path: &[SurfacePoint]) -> Vec<FaceSegment> {
    path.windows(2)
        .filter(|w| w[0].face == w[1].face)
        .map(|w| FaceSegment {
            face: piece_face(w[0].face),
            from: on_face(&w[0]),
            to: on_face(&w[1]),
        })
        .collect()
}

/// How strongly rust is drawn for a section loss: visible staining even with no measurable
/// loss, dense dark rust from 15 % (the "severe" step) on.
fn rust_strength(section_loss: f64) -> f64 {
    (0.45 + 0.5 * (section_loss / 0.15)).min(0.95)
}

/// How far above the underside a corroded bottom reaches on every face: on an I-section the
/// bottom flange (its underside, edges and top, where water and debris lie) and the foot of
/// the web over one more flange thickness (the flange–web junction, where the FHWA manual
/// finds corrosion concentrated); 0 on other sections, whose underside is one face.
fn bottom_flange_reach(section: &Section) -> f64 {
    match section {
        Section::ISection { flange, .. } => 2.0 * flange,
        _ => 0.0,
    }
}

/// The mark of damage `index` of a beam or frame member of `section` (`beam`: the beam, whose
/// spalls may bare its bars).
fn mark(beam: Option<&BeamSpec>, section: &Section, index: usize, damage: &Damage) -> Mark {
    let reach = Relief::of(damage).map_or(0.0, |r| r.reach());
    let (class, shape) = match &damage.shape {
        DamageShape::FlexuralCrack { path, width_mm } => (
            DamageClass::FlexuralCrack,
            MarkShape::Crack {
                segments: crack_segments(path),
                width: width_mm * 1e-3,
            },
        ),
        DamageShape::ShearCrack { path, width_mm } => (
            DamageClass::ShearCrack,
            MarkShape::Crack {
                segments: crack_segments(path),
                width: width_mm * 1e-3,
            },
        ),
        DamageShape::MapCracking {
            from,
            to,
            face,
            cell,
            width_mm,
        } => (
            DamageClass::MapCracking,
            MarkShape::Network {
                face: piece_face(*face),
                from: *from,
                to: *to,
                cell: *cell,
                width: width_mm * 1e-3,
            },
        ),
        DamageShape::Corrosion {
            from,
            to,
            faces,
            section_loss,
            stain_length,
            ..
        } => (
            DamageClass::Corrosion,
            MarkShape::Corrosion {
                faces: faces.iter().copied().map(piece_face).collect(),
                rises: bottom_flange_reach(section),
                from: *from,
                to: *to,
                strength: rust_strength(*section_loss),
                stain_length: *stain_length,
            },
        ),
        DamageShape::Spall { outline, depth } => {
            let bars = beam.map_or_else(Vec::new, |b| spall_bars(b, damage));
            (
                DamageClass::Spall,
                MarkShape::Spall {
                    face: piece_face(damage.position.face),
                    outline: outline.iter().map(on_face).collect(),
                    depth: *depth,
                    reach,
                    bars: bars.iter().map(|b| b.centre).collect(),
                    bar_radius: bars.first().map_or(0.0, |b| b.radius),
                },
            )
        }
        DamageShape::Dent { radius, depth } => (
            DamageClass::Dent,
            MarkShape::Dent {
                face: piece_face(damage.position.face),
                centre: on_face(&damage.position),
                radius: *radius,
                depth: *depth,
            },
        ),
    };
    Mark {
        class,
        instance: u16::try_from(index + 1).unwrap_or(u16::MAX),
        shape,
    }
}

/// A crack no view resolves: which, how wide, and the smallest pixel footprint any view that
/// sees it has there (None when no view sees it).
#[derive(Debug, PartialEq)]
pub struct Unresolved {
    /// Structure index.
    pub structure: u32,
    /// Where its structure's damage items are: "damage" (a beam) or "analysis.damage" (a
    /// frame).
    pub items_at: &'static str,
    /// Instance id (index + 1 in the structure's damage items).
    pub instance: u16,
    /// Width, millimetres.
    pub width_mm: f64,
    /// Smallest pixel footprint at the crack over the views that see it, millimetres.
    pub footprint_mm: Option<f64>,
}

/// The cracks of `damage` whose best coverage over `cameras` stays below
/// `RESOLVED_COVERAGE`. A view sees a crack piece when its midpoint (undeformed) lies in front
/// of the camera, inside the frame, on a face turned to it; the best case is taken (the
/// piece face-on, at its nearest point, occlusion not tested), so the warning errs towards
/// silence.
pub fn unresolved_cracks(damage: &SampleDamage, cameras: &[Camera]) -> Vec<Unresolved> {
    let mut out = Vec::new();
    for piece in damage.pieces() {
        for mark in &piece.marks {
            let MarkShape::Crack { segments, width } = &mark.shape else {
                continue;
            };
            let footprint = segments
                .iter()
                .flat_map(|s| cameras.iter().filter_map(|c| seen_footprint(piece, s, c)))
                .reduce(f64::min);
            if footprint.is_none_or(|f| width / f < RESOLVED_COVERAGE) {
                out.push(Unresolved {
                    structure: piece.structure,
                    items_at: match piece.mesh_piece {
                        Some(_) => "analysis.damage",
                        None => "damage",
                    },
                    instance: mark.instance,
                    width_mm: width * 1e3,
                    footprint_mm: footprint.map(|f| f * 1e3),
                });
            }
        }
    }
    out
}

/// The pixel footprint (metres) at the middle of crack piece `s` through `camera`, if the
/// camera sees that point.
fn seen_footprint(piece: &DamagedPiece, s: &FaceSegment, camera: &Camera) -> Option<f64> {
    let mid = 0.5 * (s.from + s.to);
    // On a side the point is taken on the mid-plane (its depth differs by half the width).
    let local = match s.face.is_side() {
        true => DVec3::new(mid.x, 0.0, mid.y),
        false => DVec3::new(mid.x, mid.y, 0.0) + piece.half_height * s.face.normal(),
    };
    let world = piece.world(local);
    let normal = piece.rotation * s.face.normal();
    if normal.dot(world - camera.position) >= 0.0 {
        return None;
    }
    let seen = camera.world_to_camera(world);
    if !(seen.z > 0.0) {
        return None;
    }
    let k = camera.intrinsics;
    let (u, v) = k.project(seen);
    let inside = (0.0..f64::from(k.width)).contains(&u) && (0.0..f64::from(k.height)).contains(&v);
    inside.then(|| seen.z / k.fx.max(k.fy))
}

/// The warning for a sample's cracks that no view resolves (None when every crack is
/// resolved): the first three by name, width and the smallest pixel footprint, and how many
/// more.
pub fn unresolved_warning(sample: u64, cracks: &[Unresolved]) -> Option<String> {
    cracks.first()?;
    let named: Vec<String> = cracks
        .iter()
        .take(3)
        .map(|c| {
            let seen = match c.footprint_mm {
                Some(f) => format!(
                    "smallest pixel footprint {f:.1} mm, coverage at most {:.3}",
                    c.width_mm / f
                ),
                None => "seen by no view".to_string(),
            };
            format!(
                "structures[{}].{}.items[{}] ({:.2} mm wide; {seen})",
                c.structure,
                c.items_at,
                c.instance - 1,
                c.width_mm
            )
        })
        .collect();
    let more = match cracks.len() {
        n if n > 3 => format!(" and {} more", n - 3),
        _ => String::new(),
    };
    Some(format!(
        "sample {sample}: {} crack{} no view resolves (covering under {RESOLVED_COVERAGE} of a pixel, so drawn fainter than the image can show): {}{more}; bring the cameras closer (camera.distance) or raise the resolution (camera.width, camera.height) to see them",
        cracks.len(),
        if cracks.len() == 1 { "" } else { "s" },
        named.join(", "),
    ))
}
