//! Tests of the damaged frame analysis against closed forms: a corroded cantilever column, a
//! portal whose columns are linked by a pinned beam (sway stiffnesses 3EI/h³ in series with
//! the link), cracks of a reinforced-concrete portal on the faces its moment diagram stretches,
//! and exposure corrosion at joints and base plates.

use super::*;
use crate::mechanics::damage::{
    Cause, ConcreteSection, Damage, DamageRequest, DamageShape, ExposureRules, Face, Reinforcement,
    Severity, SurfacePoint, concrete_modulus,
};

const E: f64 = 210e9;

fn square(side: f64) -> Section {
    Section::Rectangle {
        width: side,
        height: side,
    }
}

/// Placed corrosion with section loss `loss` from `from` to `to` along a member.
fn corrosion(from: f64, to: f64, loss: f64) -> Damage {
    Damage {
        shape: DamageShape::Corrosion {
            from,
            to,
            faces: vec![Face::Bottom],
            section_loss: loss,
            stain_direction: [0.0, 0.0, -1.0],
            stain_length: 0.1,
        },
        member: "beam".into(),
        position: SurfacePoint {
            along: 0.5 * (from + to),
            face: Face::Bottom,
            height: 0.0,
        },
        size: [to - from, 0.1],
        orientation: 0.0,
        severity: Severity::Light,
        cause: Cause::Placed,
    }
}

fn placed(items: Vec<Damage>) -> DamageRequest {
    DamageRequest {
        placed: items,
        ..DamageRequest::default()
    }
}

/// A vertical cantilever column of height `h`, clamped at its base, with a horizontal force
/// `p` (world +X) at its top.
fn column(h: f64, p: f64) -> FrameModel {
    let mut m = FrameModel::new();
    m.nodes = vec![[0.0; 3], [0.0, 0.0, h]];
    m.members = vec![Member::new(0, 1, square(0.2))];
    m.supports = vec![NodeSupport::fixed(0)];
    pushed_at_node_1(m, p)
}

/// `m` in the x–z plane with a horizontal force `p` (world +X) at node 1.
fn pushed_at_node_1(mut m: FrameModel, p: f64) -> FrameModel {
    m.plane = Some(Plane::Xz);
    m.loads = vec![NodalLoad {
        node: 1,
        force: [p, 0.0, 0.0],
        moment: [0.0; 3],
    }];
    m
}

#[test]
fn a_column_corroded_at_its_base_sways_as_the_unit_load_method_says() {
    // Tip load P on a cantilever of height L with EI (1 − α) over [0, a] from the clamp:
    // δ = P [(L³ − (L − a)³)/(3 (1 − α) EI) + (L − a)³/(3 EI)].
    let (l, a, alpha, p) = (3.0, 0.8, 0.25, 2e4);
    let mut model = column(l, p);
    model
        .damage
        .insert(0, placed(vec![corrosion(0.0, a, alpha)]));
    let (solution, damage) = model.solve_damaged().unwrap();
    let ei = E * 0.2f64.powi(4) / 12.0;
    let want = p
        * ((l.powi(3) - (l - a).powi(3)) / (3.0 * (1.0 - alpha) * ei)
            + (l - a).powi(3) / (3.0 * ei));
    let got = solution.nodes[1].displacement[0];
    assert!((got / want - 1.0).abs() < 1e-9, "{got} vs {want}");
    let sound = p * l.powi(3) / (3.0 * ei);
    assert!((model.solve().unwrap().nodes[1].displacement[0] / sound - 1.0).abs() < 1e-9);
    let damage = damage.unwrap();
    assert!(damage.stiffness_changed);
    assert_eq!(damage.items[0].member, "members[0]");
    // A and I_z: the harmonic mean of the section remaining, L / (a/(1 − α) + L − a).
    let harmonic = l / (a / (1.0 - alpha) + l - a);
    let scale = damage.members[0].section_scale;
    assert!((scale.area / harmonic - 1.0).abs() < 1e-12);
    assert!((scale.weak / harmonic - 1.0).abs() < 1e-12);
}

/// Two clamped columns of height `h`, `span` apart, joined at their tops by a beam pinned at
/// both ends (a link), with a horizontal force `p` at the top of the first.
fn linked_columns(h: f64, span: f64, p: f64) -> FrameModel {
    let mut m = FrameModel::new();
    m.nodes = vec![[0.0; 3], [0.0, 0.0, h], [span, 0.0, h], [span, 0.0, 0.0]];
    let link = Member {
        releases: [Release::PIN, Release::PIN],
        ..Member::new(1, 2, square(0.1))
    };
    m.members = vec![
        Member::new(0, 1, square(0.2)),
        link,
        Member::new(3, 2, square(0.2)),
    ];
    m.supports = vec![NodeSupport::fixed(0), NodeSupport::fixed(3)];
    pushed_at_node_1(m, p)
}

#[test]
fn a_portal_with_a_corroded_column_sways_as_its_columns_and_link_in_closed_form() {
    // Each clamped column is a cantilever of flexibility 1/k = h³/(3EI) (the corroded one:
    // [(h³ − (h − a)³)/(1 − α) + (h − a)³]/(3EI)); the link carries N with N/k_L = δ₁ − δ₂,
    // k_L = EA/L: N = H (1/k₁) / (1/k₁ + 1/k₂ + 1/k_L), δ₁ = (H − N)/k₁, δ₂ = N/k₂.
    let (h, span, a, alpha, p) = (3.0, 5.0, 1.2, 0.3, 3e4);
    let mut model = linked_columns(h, span, p);
    model
        .damage
        .insert(0, placed(vec![corrosion(0.0, a, alpha)]));
    let (solution, _) = model.solve_damaged().unwrap();
    let ei = E * 0.2f64.powi(4) / 12.0;
    let f1 = ((h.powi(3) - (h - a).powi(3)) / (1.0 - alpha) + (h - a).powi(3)) / (3.0 * ei);
    let f2 = h.powi(3) / (3.0 * ei);
    let fl = span / (E * 0.01);
    let n = p * f1 / (f1 + f2 + fl);
    let (d1, d2) = ((p - n) * f1, n * f2);
    let got = (
        solution.nodes[1].displacement[0],
        solution.nodes[2].displacement[0],
    );
    assert!((got.0 / d1 - 1.0).abs() < 1e-9, "{} vs {d1}", got.0);
    assert!((got.1 / d2 - 1.0).abs() < 1e-9, "{} vs {d2}", got.1);
}

#[test]
fn a_sound_frame_and_one_with_labels_only_damage_solve_to_the_same_bits() {
    let model = linked_columns(3.0, 5.0, 3e4);
    let sound = model.solve().unwrap();
    let (same, none) = model.solve_damaged().unwrap();
    assert!(none.is_none());
    let mut labelled = model.clone();
    // Corrosion without section loss only stains.
    labelled
        .damage
        .insert(1, placed(vec![corrosion(0.5, 1.5, 0.0)]));
    let (stained, damage) = labelled.solve_damaged().unwrap();
    let damage = damage.unwrap();
    assert!(!damage.stiffness_changed);
    assert_eq!(damage.passes, 0);
    for s in [&same, &stained] {
        for (a, b) in sound.nodes.iter().zip(&s.nodes) {
            assert_eq!(a, b);
        }
    }
}

/// A reinforced-concrete portal (C30/37, columns 0.3 × 0.3 m, beam 0.3 × 0.5 m), clamped at
/// its bases, under a lateral force `h` at its top left and a load `w` down at mid-span.
fn rc_portal(h: f64, w: f64) -> FrameModel {
    let bars = Reinforcement::default();
    let concrete = |s: Section| Member {
        elastic_modulus: concrete_modulus(bars.fck),
        poisson: 0.2,
        yield_strength: bars.fck,
        ..Member::new(0, 0, s)
    };
    let column = concrete(square(0.3));
    let beam = concrete(Section::Rectangle {
        width: 0.3,
        height: 0.5,
    });
    let mut m = FrameModel::new();
    m.nodes = vec![[0.0; 3], [0.0, 0.0, 3.0], [6.0, 0.0, 3.0], [6.0, 0.0, 0.0]];
    m.members = vec![
        Member {
            start: 0,
            end: 1,
            ..column.clone()
        },
        Member {
            start: 1,
            end: 2,
            loads: vec![MemberLoad {
                load: crate::mechanics::Load::Point { at: 3.0, force: w },
                direction: [0.0, 0.0, -1.0],
                axes: Axes::Global,
            }],
            ..beam
        },
        Member {
            start: 3,
            end: 2,
            ..column
        },
    ];
    m.supports = vec![NodeSupport::fixed(0), NodeSupport::fixed(3)];
    let mut m = pushed_at_node_1(m, h);
    for k in 0..3 {
        m.damage.insert(
            k,
            DamageRequest {
                reinforcement: Some(bars.clone()),
                ..DamageRequest::default()
            },
        );
    }
    m
}

#[test]
fn an_rc_portal_cracks_on_the_faces_its_solved_moment_stretches() {
    let model = rc_portal(8e4, 6e4);
    let (solution, damage) = model.solve_damaged().unwrap();
    let damage = damage.unwrap();
    let mut faces_seen = vec![Vec::new(); 3];
    for md in &damage.members {
        let c = md.concrete.as_ref().unwrap();
        let items = &damage.items[md.first_item..md.first_item + md.item_count];
        assert!(!items.is_empty(), "member {} has no cracks", md.member);
        for d in items {
            assert_eq!(d.member, format!("members[{}]", md.member));
            let DamageShape::FlexuralCrack { width_mm, path } = &d.shape else {
                continue;
            };
            let x = d.position.along;
            let moment = solution.strong_axis_at(md.member, x).moment;
            assert!(
                moment.abs() > c.cracking_moment,
                "member {} at {x}",
                md.member
            );
            // The tension face: the bottom (−z) where the moment sags, the top where it hogs.
            let tension = if moment > 0.0 {
                Face::Bottom
            } else {
                Face::Top
            };
            assert_eq!(
                d.position.face, tension,
                "member {} at {x}: M = {moment}",
                md.member
            );
            assert!(path.iter().all(|p| p.along == x));
            assert!((width_mm / (c.crack_width(moment) * 1e3) - 1.0).abs() < 1e-12);
            faces_seen[md.member].push(tension);
        }
    }
    // Under sway the moment changes sign along each column and along the beam: both faces
    // crack on every member.
    for (k, faces) in faces_seen.iter().enumerate() {
        assert!(
            faces.contains(&Face::Bottom) && faces.contains(&Face::Top),
            "member {k}: {faces:?}"
        );
    }
    // The cracked frame sways more than the sound one, and its stiffness shares are the ones
    // its own moments give (the iteration settled).
    let sound = model.solve().unwrap();
    assert!(solution.nodes[1].displacement[0] > 1.2 * sound.nodes[1].displacement[0]);
    for md in &damage.members {
        let s = md.section_scale;
        assert!(s.strong < 1.0 && s.area == 1.0 && s.weak == 1.0, "{s:?}");
    }
    assert!(damage.passes > 1);
}

#[test]
fn a_cracked_cantilever_column_deflects_by_its_cracked_curvature_integrated() {
    // Determinate, so the moment is P (L − x) whatever the stiffness, and the tip deflection
    // is ∫ κ(M(x)) (L − x) dx with EN 1992-1-1's κ (Eq. 7.18) — integrated here on a fine
    // midpoint grid, independently of the analysis's Gauss rule.
    let (l, p) = (3.0, 4e4);
    let bars = Reinforcement::default();
    let mut model = column(l, p);
    let e = concrete_modulus(bars.fck);
    model.members[0].section = square(0.3);
    model.members[0].elastic_modulus = e;
    model.members[0].poisson = 0.2;
    model.damage.insert(
        0,
        DamageRequest {
            reinforcement: Some(bars.clone()),
            ..DamageRequest::default()
        },
    );
    let (solution, _) = model.solve_damaged().unwrap();
    let c = ConcreteSection::new(0.3, 0.3, &bars);
    let n = 200_000;
    let dx = l / n as f64;
    let want: f64 = (0..n)
        .map(|k| {
            let x = (k as f64 + 0.5) * dx;
            let m = p * (l - x);
            c.curvature(m, e) * (l - x) * dx
        })
        .sum();
    let got = solution.nodes[1].displacement[0];
    assert!((got / want - 1.0).abs() < 1e-6, "{got} vs {want}");
}

/// An exposure corrosion record: rule, from, to, faces, stain direction.
type ExposedRegion = (String, f64, f64, Vec<Face>, [f64; 3]);

#[test]
fn exposure_corrodes_joints_base_plates_and_the_beams_underside_with_stains_down() {
    let mut model = linked_columns(3.0, 5.0, 3e4);
    for k in 0..3 {
        model.damage.insert(
            k,
            DamageRequest {
                corrosion_by_exposure: Some(ExposureRules::default()),
                ..DamageRequest::default()
            },
        );
    }
    let (_, damage) = model.solve_damaged().unwrap();
    let damage = damage.unwrap();
    let rules = |k: usize| -> Vec<ExposedRegion> {
        let md = &damage.members[k];
        damage.items[md.first_item..md.first_item + md.item_count]
            .iter()
            .map(|d| match (&d.shape, &d.cause) {
                (
                    DamageShape::Corrosion {
                        from,
                        to,
                        faces,
                        stain_direction,
                        ..
                    },
                    Cause::Exposure { rule },
                ) => (rule.clone(), *from, *to, faces.clone(), *stain_direction),
                other => panic!("{other:?}"),
            })
            .collect()
    };
    // The beam (link): both ends at joints, and its underside; stains down its local −z.
    let beam = rules(1);
    assert_eq!(beam.len(), 3);
    assert_eq!(beam[0].0, "support_end");
    assert_eq!((beam[0].1, beam[0].2), (0.0, 0.5));
    assert_eq!((beam[1].1, beam[1].2), (4.5, 5.0));
    assert_eq!(beam[2].0, "bottom_flange");
    assert!(beam.iter().all(|r| r.4 == [0.0, 0.0, -1.0]));
    // A column: its base plate and its top joint, all four faces, no "underside"; down is its
    // local −x (the axis runs up).
    let col = rules(0);
    assert_eq!(col.len(), 2);
    assert!(col.iter().all(|r| r.0 == "support_end" && r.3.len() == 4));
    let down = col[0].4;
    assert!((down[0] + 1.0).abs() < 1e-12 && down[1].abs() < 1e-12 && down[2].abs() < 1e-12);
    // Section loss softened the members.
    assert!(damage.stiffness_changed);
}
