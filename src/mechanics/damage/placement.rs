//! Where the mechanics and the exposure rules put damage, and the damaged member's solution.
//!
//! Reinforced concrete: flexural cracks where |M| > M_cr, normal to the axis on the tension
//! face, s_r,max apart, each as wide as Eq. 7.8 gives at its moment; web-shear cracks where the
//! section is uncracked in bending but |V| exceeds the web-shear cracking force (principal
//! tension f_ctm at the centroid, at 45°). Steel: corrosion at the supported ends and along the
//! underside, stains running down. The member is then solved with the stiffness its cracks and
//! section loss leave (`stiffness`). Clauses and reasoning: docs/damage.md.

use super::concrete::{ConcreteSection, Reinforcement};
use super::stiffness::SteppedBeam;
use super::{Cause, Damage, DamageShape, Face, Severity, SurfacePoint};
use crate::mechanics::{Load, Section, Support};
use serde::Serialize;
use std::f64::consts::FRAC_PI_4;

/// Samples per span used to find where a rule holds (boundaries then refined by bisection).
const SCAN: usize = 4096;
/// The part name damage on a beam carries.
const MEMBER: &str = "beam";

/// The exposure rules that place corrosion on a steel member, and how much section each takes.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ExposureRules {
    /// Length of each supported end that corrodes (water from joints and bearings), metres;
    /// absent: the larger of the section height and a tenth of the span.
    pub end_length: Option<f64>,
    /// Section loss at the supported ends, a fraction (default 0.10).
    pub end_loss: f64,
    /// Section loss along the underside, a fraction (default 0.02; 0 stains without loss).
    pub bottom_loss: f64,
}

impl Default for ExposureRules {
    fn default() -> Self {
        ExposureRules {
            end_length: None,
            end_loss: 0.10,
            bottom_loss: 0.02,
        }
    }
}

/// A member's internal forces along its axis, as the crack rules read them: the bending moment
/// about the strong axis (sagging-positive, stretching the −z face) and the shear V = dM/dx.
pub trait InternalForces {
    /// Bending moment at x, N·m, sagging-positive.
    fn moment(&self, x: f64) -> f64;
    /// Shear force V = dM/dx at x, N.
    fn shear(&self, x: f64) -> f64;
}

impl InternalForces for SteppedBeam {
    fn moment(&self, x: f64) -> f64 {
        SteppedBeam::moment(self, x)
    }
    fn shear(&self, x: f64) -> f64 {
        SteppedBeam::shear(self, x)
    }
}

/// What damage a beam has or should get, as the recipe declared it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, schemars::JsonSchema)]
pub struct DamageRequest {
    /// Damage placed by the recipe, exactly where it says.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub placed: Vec<Damage>,
    /// The beam is reinforced concrete: the mechanics cracks it where the moment and the shear
    /// exceed the concrete's resistance, and solves it with the cracked stiffness.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reinforcement: Option<Reinforcement>,
    /// Corrosion placed by the exposure rules (steel members).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub corrosion_by_exposure: Option<ExposureRules>,
}

impl DamageRequest {
    /// Whether nothing is asked (the beam is sound and built as before).
    pub fn is_empty(&self) -> bool {
        self.placed.is_empty()
            && self.reinforcement.is_none()
            && self.corrosion_by_exposure.is_none()
    }
}

/// What the damage of a beam is and what it did to the deflection.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct DamageLabels {
    /// Every damage of the beam: placed, then by stress, then by exposure.
    pub items: Vec<Damage>,
    /// For reinforced concrete, the section the crack model solved (f_ctm, E_cm, M_cr, I_I,
    /// I_II, s_r,max, ...).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub concrete: Option<ConcreteSection>,
    /// Whether the damage changed the stiffness, so the shape below (not the sound one) was
    /// meshed.
    pub stiffness_changed: bool,
    /// Smallest ratio of the damaged to the sound bending stiffness along the span (1 when
    /// unchanged).
    pub min_stiffness_ratio: f64,
    /// The sound beam's peak deflection under the same loads, metres, positive downward.
    pub sound_max_deflection: f64,
    /// The damaged beam's peak deflection, metres, positive downward (equal to the sound one
    /// when the stiffness is unchanged).
    pub max_deflection: f64,
    /// Where it occurs, metres from x = 0.
    pub max_deflection_at: f64,
    /// Widest crack, millimetres (0 without cracks).
    pub max_crack_width_mm: f64,
}

impl DamageLabels {
    /// Where the stiffness jumps (ends of corrosion regions with section loss): stations there
    /// keep mesh vertices on the exact curve.
    pub fn stiffness_breaks(&self) -> Vec<f64> {
        section_loss_regions(&self.items)
            .into_iter()
            .flat_map(|(from, to, _)| [from, to])
            .collect()
    }
}

/// A beam as the damage model sees it.
pub struct DamagedMember<'a> {
    /// Supports.
    pub support: Support,
    /// Span, metres.
    pub length: f64,
    /// Cross-section.
    pub section: &'a Section,
    /// Young's modulus, Pa.
    pub elastic_modulus: f64,
    /// Sound second moment of area, m⁴.
    pub second_moment: f64,
    /// The physical loads.
    pub loads: &'a [Load],
    /// The sound beam's peak deflection and where.
    pub sound_peak: (f64, f64),
}

/// Places the damage `request` asks for on `member` and solves the damaged beam: the axis to
/// mesh when the stiffness changed, and the labels.
pub fn solve_damage(
    member: &DamagedMember,
    request: &DamageRequest,
) -> Result<(Option<SteppedBeam>, DamageLabels), String> {
    let (b, h) = (member.section.width(), member.section.height());
    let concrete = match (&request.reinforcement, member.section) {
        (None, _) => None,
        (Some(r), Section::Rectangle { .. }) => {
            r.validate(h)?;
            Some(ConcreteSection::new(b, h, r))
        }
        (Some(_), other) => {
            return Err(format!(
                "reinforced concrete needs a rectangular section (got {other:?})"
            ));
        }
    };
    let mut items = request.placed.clone();
    if let Some(rules) = &request.corrosion_by_exposure {
        items.extend(exposure_corrosion(member, rules));
    }
    let regions = section_loss_regions(&items);
    let remaining = |x: f64| -> f64 {
        regions
            .iter()
            .filter(|(from, to, _)| (*from..*to).contains(&x))
            .map(|r| r.2)
            .product()
    };
    let (e, i) = (member.elastic_modulus, member.second_moment);
    let curvature = |x: f64, m: f64| -> f64 {
        let sound = match &concrete {
            Some(c) => c.curvature(m, e),
            None => m / (e * i),
        };
        sound / remaining(x)
    };
    let breaks: Vec<f64> = regions.iter().flat_map(|r| [r.0, r.1]).collect();
    let stiffness_may_change = concrete.is_some() || !regions.is_empty();
    let axis = if stiffness_may_change {
        Some(SteppedBeam::solve(
            member.support,
            member.length,
            member.loads,
            &breaks,
            &curvature,
        )?)
    } else {
        None
    };
    let mut cracked = false;
    if let (Some(c), Some(axis)) = (&concrete, &axis) {
        let cracks = stress_cracks(MEMBER, member.length, c, axis);
        cracked = cracks
            .iter()
            .any(|d| matches!(d.shape, DamageShape::FlexuralCrack { .. }));
        items.extend(cracks);
    }
    let stiffness_changed = cracked || !regions.is_empty();
    let axis = axis.filter(|_| stiffness_changed);
    let min_stiffness_ratio = match &axis {
        Some(a) => stiffness_ratio(member, a, &curvature),
        None => 1.0,
    };
    let (max_deflection, max_deflection_at) = match &axis {
        Some(a) => a.peak(),
        None => member.sound_peak,
    };
    let max_crack_width_mm = items.iter().map(crack_width_mm).fold(0.0, f64::max);
    let labels = DamageLabels {
        items,
        concrete,
        stiffness_changed,
        min_stiffness_ratio,
        sound_max_deflection: member.sound_peak.0,
        max_deflection,
        max_deflection_at,
        max_crack_width_mm,
    };
    Ok((axis, labels))
}

/// The cracks the stresses of a reinforced-concrete member of `length` put on it: flexural
/// where |M| > M_cr, then web-shear where the section is uncracked in bending but |V| exceeds
/// the web-shear cracking force; each record names `member`.
pub fn stress_cracks(
    member: &str,
    length: f64,
    c: &ConcreteSection,
    forces: &dyn InternalForces,
) -> Vec<Damage> {
    let mut cracks = flexural_cracks(length, c, forces);
    cracks.extend(shear_cracks(length, c, forces));
    for d in &mut cracks {
        d.member = member.into();
    }
    cracks
}

/// The corrosion regions that lose section: (from, to, fraction of the section remaining).
pub fn section_loss_regions(items: &[Damage]) -> Vec<(f64, f64, f64)> {
    items
        .iter()
        .filter_map(|d| match d.shape {
            DamageShape::Corrosion {
                from,
                to,
                section_loss,
                ..
            } if section_loss > 0.0 => Some((from, to, 1.0 - section_loss)),
            _ => None,
        })
        .collect()
}

/// A crack's width, millimetres (0 for damage that is not a crack).
pub fn crack_width_mm(d: &Damage) -> f64 {
    match d.shape {
        DamageShape::FlexuralCrack { width_mm, .. }
        | DamageShape::ShearCrack { width_mm, .. }
        | DamageShape::MapCracking { width_mm, .. } => width_mm,
        _ => 0.0,
    }
}

/// Smallest EI_damaged / EI_sound over the scan, from the curvatures under the solved moment.
fn stiffness_ratio(
    member: &DamagedMember,
    axis: &SteppedBeam,
    curvature: &dyn Fn(f64, f64) -> f64,
) -> f64 {
    let ei = member.elastic_modulus * member.second_moment;
    (0..SCAN)
        .map(|k| member.length * (k as f64 + 0.5) / SCAN as f64)
        .filter_map(|x| {
            let m = axis.moment(x);
            let k = curvature(x, m);
            (m != 0.0 && k != 0.0).then(|| (m / ei) / k)
        })
        .fold(1.0, f64::min)
}

/// Crack severity by width: below 0.2 mm light, up to 0.4 mm moderate, wider severe.
fn crack_severity(width_mm: f64) -> Severity {
    Severity::grade(width_mm, 0.2, 0.4)
}

/// Flexural cracks in every stretch where |M| > M_cr: s_r,max apart, centred on the stretch,
/// rising from the tension face to the cracked section's neutral axis.
fn flexural_cracks(length: f64, c: &ConcreteSection, axis: &dyn InternalForces) -> Vec<Damage> {
    let over = |x: f64| axis.moment(x).abs() > c.cracking_moment;
    let mut cracks = Vec::new();
    for (from, to) in stretches(length, &over) {
        for x in spaced(from, to, c.crack_spacing) {
            let moment = axis.moment(x);
            let width_mm = c.crack_width(moment) * 1e3;
            let path = flexural_path(x, moment > 0.0, c);
            let (face, depth) = (path[2].face, c.height - c.neutral_axis);
            cracks.push(Damage {
                shape: DamageShape::FlexuralCrack { path, width_mm },
                member: MEMBER.into(),
                position: SurfacePoint {
                    along: x,
                    face,
                    height: 0.0,
                },
                size: [width_mm * 1e-3, c.width + 2.0 * depth],
                orientation: std::f64::consts::FRAC_PI_2,
                severity: crack_severity(width_mm),
                cause: Cause::Stress {
                    quantity: "bending_moment".into(),
                    value: moment,
                    limit: c.cracking_moment,
                },
            });
        }
    }
    cracks
}

/// A flexural crack at x: up one side from the tension face to the neutral axis, across the
/// tension face, and up the other side (sagging: the bottom; hogging: the top).
fn flexural_path(x: f64, sagging: bool, c: &ConcreteSection) -> Vec<SurfacePoint> {
    let (half_h, half_b) = (0.5 * c.height, 0.5 * c.width);
    let (face, edge, tip) = if sagging {
        (Face::Bottom, -half_h, half_h - c.neutral_axis)
    } else {
        (Face::Top, half_h, -half_h + c.neutral_axis)
    };
    let p = |face, height| SurfacePoint {
        along: x,
        face,
        height,
    };
    vec![
        p(Face::SideNegY, tip),
        p(Face::SideNegY, edge),
        p(face, -half_b),
        p(face, half_b),
        p(Face::SidePosY, edge),
        p(Face::SidePosY, tip),
    ]
}

/// Web-shear cracks where the section is uncracked in bending (|M| ≤ M_cr) and |V| exceeds
/// the web-shear cracking force: at 45°, normal to the principal tension at the centroid,
/// rising towards mid-span, one on each side face, s_r,max apart.
fn shear_cracks(length: f64, c: &ConcreteSection, axis: &dyn InternalForces) -> Vec<Damage> {
    let limit = c.shear_cracking_force();
    // Half the crack's reach along the axis (and up the web): to the bars' level.
    let reach = 0.5 * c.height - (c.height - c.effective_depth);
    let over = |x: f64| axis.shear(x).abs() > limit && axis.moment(x).abs() <= c.cracking_moment;
    let mut cracks = Vec::new();
    for (from, to) in stretches(length, &over) {
        for x in spaced(from, to, c.crack_spacing) {
            let (shear, moment) = (axis.shear(x), axis.moment(x));
            // Rises towards where |M| grows: the sign of V·M (of V where M vanishes).
            let rise = if (shear * if moment == 0.0 { 1.0 } else { moment }) >= 0.0 {
                1.0
            } else {
                -1.0
            };
            let width_mm = c.crack_width(moment.abs().max(c.cracking_moment)) * 1e3;
            // Near an end the crack is shortened to stay on the span.
            let reach = reach.min(x).min(length - x);
            for face in [Face::SideNegY, Face::SidePosY] {
                let p = |along, height| SurfacePoint {
                    along,
                    face,
                    height,
                };
                cracks.push(Damage {
                    shape: DamageShape::ShearCrack {
                        path: vec![p(x - reach, -rise * reach), p(x + reach, rise * reach)],
                        width_mm,
                    },
                    member: MEMBER.into(),
                    position: p(x, 0.0),
                    size: [2.0 * reach, 2.0 * reach],
                    orientation: rise * FRAC_PI_4,
                    severity: crack_severity(width_mm),
                    cause: Cause::Stress {
                        quantity: "shear_force".into(),
                        value: shear,
                        limit,
                    },
                });
            }
        }
    }
    cracks
}

/// Corrosion by the exposure rules: each supported end over `end_length` (bottom and sides),
/// and the underside along the span; stains run down by the section height.
fn exposure_corrosion(member: &DamagedMember, rules: &ExposureRules) -> Vec<Damage> {
    let supported_ends: &[f64] = match member.support {
        Support::Cantilever => &[0.0],
        _ => &[0.0, member.length],
    };
    exposed_corrosion(member.length, member.section, supported_ends, rules)
}

/// Corrosion by the exposure rules on a member of `length` and `section` whose ends at
/// `ends` (0 or `length`) are where water collects (bearings, joints, base plates): each over
/// `end_length` (bottom and sides), and the underside along the whole member; stains run down
/// by the section height.
pub fn exposed_corrosion(
    length: f64,
    section: &Section,
    ends: &[f64],
    rules: &ExposureRules,
) -> Vec<Damage> {
    let (l, h, b) = (length, section.height(), section.width());
    let end = rules.end_length.unwrap_or(h.max(0.1 * l)).min(l);
    let supported_ends = ends;
    let ends = [Face::Bottom, Face::SideNegY, Face::SidePosY];
    let mut items: Vec<Damage> = supported_ends
        .iter()
        .map(|&x| {
            let (from, to) = if x == 0.0 { (0.0, end) } else { (l - end, l) };
            corrosion(from, to, ends.to_vec(), rules.end_loss, h, b, "support_end")
        })
        .collect();
    items.push(corrosion(
        0.0,
        l,
        vec![Face::Bottom],
        rules.bottom_loss,
        h,
        b,
        "bottom_flange",
    ));
    items
}

fn corrosion(
    from: f64,
    to: f64,
    faces: Vec<Face>,
    section_loss: f64,
    height: f64,
    width: f64,
    rule: &str,
) -> Damage {
    Damage {
        shape: DamageShape::Corrosion {
            from,
            to,
            faces,
            section_loss,
            stain_direction: [0.0, 0.0, -1.0],
            stain_length: height,
        },
        member: MEMBER.into(),
        position: SurfacePoint {
            along: 0.5 * (from + to),
            face: Face::Bottom,
            height: 0.0,
        },
        size: [to - from, width],
        orientation: 0.0,
        severity: Severity::grade(section_loss, 0.05, 0.15),
        cause: Cause::Exposure { rule: rule.into() },
    }
}

/// The stretches of [0, length] where `holds`, their ends refined by bisection.
fn stretches(length: f64, holds: &dyn Fn(f64) -> bool) -> Vec<(f64, f64)> {
    let at = |k: usize| length * k as f64 / SCAN as f64;
    let edge = |inside: f64, outside: f64| {
        let (mut a, mut b) = (inside, outside);
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if holds(m) { a = m } else { b = m }
        }
        a
    };
    let mut out = Vec::new();
    let mut start: Option<f64> = None;
    for k in 0..=SCAN {
        let x = at(k);
        match (holds(x), start) {
            (true, None) => start = Some(if k == 0 { x } else { edge(x, at(k - 1)) }),
            (false, Some(s)) => {
                out.push((s, edge(at(k - 1), x)));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, length));
    }
    out
}

/// Positions `spacing` apart centred on [from, to], as many as fit (at least one).
fn spaced(from: f64, to: f64, spacing: f64) -> Vec<f64> {
    let n = ((to - from) / spacing).floor() as usize + 1;
    let first = 0.5 * (from + to) - 0.5 * (n - 1) as f64 * spacing;
    (0..n).map(|k| first + k as f64 * spacing).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::damage::concrete_modulus;

    /// A 6 m simply supported 300 × 500 mm C30/37 beam (3 φ16) under a central load `p`.
    fn rc_beam(p: f64, support: Support, at: f64) -> (Option<SteppedBeam>, DamageLabels) {
        let section = Section::Rectangle {
            width: 0.3,
            height: 0.5,
        };
        let loads = [Load::Point { at, force: p }];
        let member = DamagedMember {
            support,
            length: 6.0,
            section: &section,
            elastic_modulus: concrete_modulus(30e6),
            second_moment: 0.3 * 0.5f64.powi(3) / 12.0,
            loads: &loads,
            sound_peak: (0.0, 0.0),
        };
        let request = DamageRequest {
            reinforcement: Some(Reinforcement::default()),
            ..DamageRequest::default()
        };
        solve_damage(&member, &request).unwrap()
    }

    #[test]
    fn flexural_cracks_lie_where_the_moment_exceeds_the_cracking_moment() {
        let p = 60e3;
        let (axis, labels) = rc_beam(p, Support::SimplySupported, 3.0);
        let c = labels.concrete.clone().unwrap();
        // M(x) = P x/2 on the left half: cracked beyond x₀ = 2 M_cr / P.
        let x0 = 2.0 * c.cracking_moment / p;
        let cracks: Vec<&Damage> = labels
            .items
            .iter()
            .filter(|d| matches!(d.shape, DamageShape::FlexuralCrack { .. }))
            .collect();
        // The cracked stretch [x₀, L − x₀] holds ⌊(L − 2x₀)/s_r,max⌋ + 1 cracks s_r,max apart.
        let expected = ((6.0 - 2.0 * x0) / c.crack_spacing).floor() as usize + 1;
        assert_eq!(cracks.len(), expected);
        for pair in cracks.windows(2) {
            let gap = pair[1].position.along - pair[0].position.along;
            assert!((gap - c.crack_spacing).abs() < 1e-9);
        }
        for d in &cracks {
            let x = d.position.along;
            assert!(
                x > x0 && x < 6.0 - x0,
                "crack at {x} outside [{x0}, {}]",
                6.0 - x0
            );
            let m = p * x.min(6.0 - x) / 2.0;
            let Cause::Stress { value, limit, .. } = d.cause else {
                panic!("{:?}", d.cause)
            };
            assert!((value / m - 1.0).abs() < 1e-9, "{value} vs {m}");
            assert_eq!(limit, c.cracking_moment);
            // Normal to the axis, on the tension (bottom) face, up to the neutral axis.
            assert_eq!(d.orientation, std::f64::consts::FRAC_PI_2);
            assert_eq!(d.position.face, Face::Bottom);
            let DamageShape::FlexuralCrack { path, width_mm } = &d.shape else {
                unreachable!()
            };
            assert!(path.iter().all(|q| q.along == x));
            assert_eq!(path[0].height, 0.25 - c.neutral_axis);
            assert!((width_mm - c.crack_width(m) * 1e3).abs() < 1e-9);
        }
        // No web-shear cracks: V = 30 kN is far below (2/3) b h f_ctm ≈ 290 kN.
        assert!(
            labels
                .items
                .iter()
                .all(|d| !matches!(d.shape, DamageShape::ShearCrack { .. }))
        );
        // The cracked beam is softer than the sound one.
        let axis = axis.unwrap();
        let sound = p * 216.0 / (48.0 * c.concrete_modulus * c.uncracked_inertia);
        assert!(
            axis.at(3.0).v > 1.2 * sound,
            "{} vs {sound}",
            axis.at(3.0).v
        );
        assert!(labels.stiffness_changed && labels.min_stiffness_ratio < 0.5);
    }

    #[test]
    fn hogging_cracks_a_cantilever_from_the_top() {
        let (_, labels) = rc_beam(20e3, Support::Cantilever, 6.0);
        let c = labels.concrete.unwrap();
        // M = −P (L − x): cracked for x < L − M_cr/P.
        let edge = 6.0 - c.cracking_moment / 20e3;
        let flexural = labels
            .items
            .iter()
            .filter(|d| matches!(d.shape, DamageShape::FlexuralCrack { .. }));
        for d in flexural {
            assert!(d.position.along < edge);
            assert_eq!(d.position.face, Face::Top);
        }
    }

    #[test]
    fn shear_cracks_sit_near_the_supports_inclined_towards_the_load() {
        // 700 kN: V = 350 kN > 290 kN, and |M| ≤ M_cr only within 2 M_cr/P ≈ 0.10 m of a support.
        let p = 700e3;
        let (_, labels) = rc_beam(p, Support::SimplySupported, 3.0);
        let c = labels.concrete.unwrap();
        let near = 2.0 * c.cracking_moment / p;
        let shear: Vec<&Damage> = labels
            .items
            .iter()
            .filter(|d| matches!(d.shape, DamageShape::ShearCrack { .. }))
            .collect();
        assert!(!shear.is_empty());
        for d in shear {
            let x = d.position.along;
            assert!(x < near || x > 6.0 - near, "{x}");
            // Rising towards mid-span: +45° on the left half, −45° on the right.
            let rise = if x < 3.0 { 1.0 } else { -1.0 };
            assert_eq!(d.orientation, rise * FRAC_PI_4);
            assert!(d.position.face.is_side());
        }
    }

    #[test]
    fn an_uncracked_beam_gets_no_cracks_and_keeps_its_shape() {
        // M_max = P L/4 = 30 kN·m < M_cr ≈ 36.2 kN·m.
        let (axis, labels) = rc_beam(20e3, Support::SimplySupported, 3.0);
        assert!(labels.items.is_empty());
        assert!(axis.is_none() && !labels.stiffness_changed);
        assert_eq!(labels.min_stiffness_ratio, 1.0);
    }

    #[test]
    fn exposure_corrodes_the_supported_ends_and_the_underside() {
        let section = Section::ISection {
            width: 0.2,
            height: 0.4,
            flange: 0.015,
            web: 0.01,
        };
        let loads = [Load::Point {
            at: 2.5,
            force: 1e4,
        }];
        let member = DamagedMember {
            support: Support::Cantilever,
            length: 5.0,
            section: &section,
            elastic_modulus: 210e9,
            second_moment: section.properties(0.3).second_moment,
            loads: &loads,
            sound_peak: (0.0, 0.0),
        };
        let request = DamageRequest {
            corrosion_by_exposure: Some(ExposureRules::default()),
            ..DamageRequest::default()
        };
        let (axis, labels) = solve_damage(&member, &request).unwrap();
        // A cantilever has one supported end: the clamp, corroded over max(h, L/10) = 0.5 m.
        let rules: Vec<(f64, f64)> = labels
            .items
            .iter()
            .map(|d| match d.shape {
                DamageShape::Corrosion { from, to, .. } => (from, to),
                _ => panic!("{d:?}"),
            })
            .collect();
        assert_eq!(rules, vec![(0.0, 0.5), (0.0, 5.0)]);
        // Section loss 10 % then 2 % on the root: EI × 0.9 × 0.98 there. Tip deflection by the
        // unit-load method: P ∫₀^a (a − x)²/EI(x) dx with a = 2.5 m, beyond the load rigid.
        let ei = 210e9 * member.second_moment;
        let (r1, r2) = (0.9 * 0.98, 0.98);
        let under_load = 1e4
            * ((2.5f64.powi(3) - 2.0f64.powi(3)) / (3.0 * ei * r1)
                + 2.0f64.powi(3) / (3.0 * ei * r2));
        let axis = axis.unwrap();
        assert!((axis.at(2.5).v / under_load - 1.0).abs() < 1e-12);
        assert!((labels.min_stiffness_ratio - r1).abs() < 1e-12);
    }
}
