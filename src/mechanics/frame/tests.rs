//! The analysis against closed forms and hand methods (textbook frames, the three-moment
//! equation, the method of joints), the beam module's own solution, invariance under moving
//! the model, equilibrium and compatibility, and the refusal of mechanisms.

use super::*;
use crate::mechanics::{LinearBeam, Support};
use glam::{DMat3, DVec3};

const E: f64 = STEEL_E;

fn rect(width: f64, height: f64) -> Section {
    Section::Rectangle { width, height }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

fn down(load: Load) -> MemberLoad {
    MemberLoad {
        load,
        direction: [0.0, 0.0, -1.0],
        axes: Axes::Global,
    }
}

fn udl(length: f64, w: f64) -> MemberLoad {
    down(Load::Distributed {
        from: 0.0,
        to: length,
        intensity: w,
    })
}

/// A portal frame in the x–z plane: bases 0 and 3, top corners 1 and 2, lateral load `h` at
/// node 1. Columns and beam are slender (A h²/I ≈ 2·10⁶, so axial shortening, which the closed
/// forms neglect, changes the sway by ~4e-6).
fn portal(base: fn(usize) -> NodeSupport, i_beam_factor: f64) -> (FrameModel, f64, f64, f64) {
    let (height, span) = (40.0, 60.0);
    let column = rect(0.2, 0.1);
    let beam = rect(0.2, 0.1 * i_beam_factor.cbrt());
    let mut m = FrameModel::new();
    m.nodes = vec![
        [0.0, 0.0, 0.0],
        [0.0, 0.0, height],
        [span, 0.0, height],
        [span, 0.0, 0.0],
    ];
    m.members = vec![
        Member::new(0, 1, column.clone()),
        Member::new(1, 2, beam),
        Member::new(3, 2, column),
    ];
    m.supports = vec![base(0), base(3)];
    m.plane = Some(Plane::Xz);
    m.loads = vec![NodalLoad {
        node: 1,
        force: [1e3, 0.0, 0.0],
        moment: [0.0; 3],
    }];
    (m, height, span, 0.2 * 0.1f64.powi(3) / 12.0)
}

#[test]
fn portal_frame_sway_matches_the_slope_deflection_formulas() {
    for factor in [0.5, 1.0, 3.0] {
        // k = (I_b / L) / (I_c / h).
        let (m, h, l, ic) = portal(NodeSupport::fixed, factor);
        let k = factor * h / l;
        let sway = m.solve().unwrap().nodes[1].displacement[0];
        let fixed = 1e3 * h.powi(3) * (3.0 * k + 2.0) / (12.0 * E * ic * (6.0 * k + 1.0));
        assert!(close(sway, fixed, 1e-5), "fixed k={k}: {sway} vs {fixed}");
        let (m, ..) = portal(NodeSupport::pinned, factor);
        let sway = m.solve().unwrap().nodes[1].displacement[0];
        let pinned = 1e3 * h.powi(3) * (2.0 * k + 1.0) / (12.0 * E * ic * k);
        assert!(
            close(sway, pinned, 1e-5),
            "pinned k={k}: {sway} vs {pinned}"
        );
    }
}

#[test]
fn propped_cantilever_under_udl() {
    let (l, w) = (5.0, 2e4);
    let mut m = FrameModel::new();
    m.nodes = vec![[0.0; 3], [l, 0.0, 0.0]];
    let mut beam = Member::new(0, 1, rect(0.2, 0.4));
    beam.loads.push(udl(l, w));
    m.members = vec![beam];
    m.supports = vec![NodeSupport::fixed(0), NodeSupport::roller(1)];
    m.plane = Some(Plane::Xz);
    let s = m.solve().unwrap();
    let r = |n: usize| s.reactions.iter().find(|r| r.node == n).unwrap();
    assert!(close(r(1).force[2], 3.0 * w * l / 8.0, 1e-12));
    assert!(close(r(0).force[2], 5.0 * w * l / 8.0, 1e-12));
    // The clamp's moment w L²/8, hogging: about +y it turns the beam's tip up (x toward −z).
    assert!(close(r(0).moment[1], -w * l * l / 8.0, 1e-12), "{:?}", r(0));
    assert!(close(s.members[0].peak_moment_y, w * l * l / 8.0, 1e-12));
    // Mid-span deflection w L⁴ / (192 EI).
    let ei = E * 0.2 * 0.4f64.powi(3) / 12.0;
    let mid = s.member_at(0, l / 2.0).0.z;
    assert!(close(-mid, w * l.powi(4) / (192.0 * ei), 1e-12), "{mid}");
}

#[test]
fn two_span_continuous_beam_reactions_follow_the_three_moment_equation() {
    let (l, w) = (6.0, 1.5e4);
    let mut m = FrameModel::new();
    m.nodes = vec![[0.0; 3], [l, 0.0, 0.0], [2.0 * l, 0.0, 0.0]];
    for (a, b) in [(0, 1), (1, 2)] {
        let mut span = Member::new(a, b, rect(0.3, 0.5));
        span.loads.push(udl(l, w));
        m.members.push(span);
    }
    m.supports = vec![
        NodeSupport::pinned(0),
        NodeSupport::roller(1),
        NodeSupport::roller(2),
    ];
    m.plane = Some(Plane::Xz);
    for solver in [Solver::Dense, Solver::Sparse] {
        let s = m.solve_with(solver).unwrap();
        let rz: Vec<f64> = s.reactions.iter().map(|r| r.force[2] / (w * l)).collect();
        for (got, want) in rz.iter().zip([3.0 / 8.0, 10.0 / 8.0, 3.0 / 8.0]) {
            assert!(close(*got, want, 1e-12), "{rz:?}");
        }
        // Hogging moment over the middle support: w L² / 8.
        for member in &s.members {
            assert!(close(member.peak_moment_y, w * l * l / 8.0, 1e-12));
        }
        // Every node sits on a support, so the largest deflection is inside a span. By symmetry
        // each span is a propped cantilever: y(x) = w x (L³ − 3 L x² + 2 x³) / (48 EI) from the
        // end support, largest at x = L (1 + √33) / 16.
        let ei = E * 0.3 * 0.5f64.powi(3) / 12.0;
        let x = l * (1.0 + 33f64.sqrt()) / 16.0;
        let peak = w * x * (l.powi(3) - 3.0 * l * x * x + 2.0 * x.powi(3)) / (48.0 * ei);
        let labels = FrameLabels::new(&s);
        assert!(
            close(labels.max_displacement, peak, 1e-9),
            "{labels:?} vs {peak}"
        );
        let (member, along) = (
            labels.max_displacement_member,
            labels.max_displacement_position,
        );
        let from_end = if member == 0 { along } else { l - along };
        assert!((from_end - x).abs() < 1e-3 * l, "{member} {along}");
    }
}

/// A Pratt truss of four panels (a × h): bottom nodes 0–4, top nodes 5–7 over nodes 1–3,
/// loads `p` down at nodes 1, 2, 3.
fn pratt(a: f64, h: f64, p: f64) -> FrameModel {
    let mut m = FrameModel::new();
    m.nodes = (0..5).map(|i| [a * i as f64, 0.0, 0.0]).collect();
    m.nodes.extend((1..4).map(|i| [a * i as f64, 0.0, h]));
    let bar = |s, e| Member::bar(s, e, rect(0.1, 0.1));
    m.members = vec![
        bar(0, 1),
        bar(1, 2),
        bar(2, 3),
        bar(3, 4),
        bar(5, 6),
        bar(6, 7),
        bar(0, 5),
        bar(4, 7),
        bar(1, 5),
        bar(2, 6),
        bar(3, 7),
        bar(5, 2),
        bar(7, 2),
    ];
    m.supports = vec![NodeSupport::pinned(0), NodeSupport::roller(4)];
    m.plane = Some(Plane::Xz);
    m.loads = [1, 2, 3]
        .map(|node| NodalLoad {
            node,
            force: [0.0, 0.0, -p],
            moment: [0.0; 3],
        })
        .to_vec();
    m
}

#[test]
fn pratt_truss_member_forces_match_the_method_of_joints() {
    let (a, h, p): (f64, f64, f64) = (3.0, 4.0, 1e5);
    let sin = h / f64::hypot(a, h);
    let want = [
        1.5 * p * a / h,
        1.5 * p * a / h,
        1.5 * p * a / h,
        1.5 * p * a / h,
        -2.0 * p * a / h,
        -2.0 * p * a / h,
        -1.5 * p / sin,
        -1.5 * p / sin,
        p,
        0.0,
        p,
        0.5 * p / sin,
        0.5 * p / sin,
    ];
    let s = pratt(a, h, p).solve().unwrap();
    for (i, (member, want)) in s.members.iter().zip(want).enumerate() {
        assert!(
            (member.axial_force - want).abs() <= 1e-9 * p,
            "member {i}: {} vs {want}",
            member.axial_force
        );
        // Pinned bars carry no moment.
        assert!(member.peak_moment_y <= 1e-9 * p * a, "member {i}");
    }
}

#[test]
fn one_member_cantilever_equals_the_beam_module() {
    let l = 3.0;
    let section = rect(0.3, 0.6);
    for theory in [MemberTheory::EulerBernoulli, MemberTheory::Timoshenko] {
        let loads = vec![
            Load::Point {
                at: 1.1,
                force: 4e4,
            },
            Load::Distributed {
                from: 0.5,
                to: 2.5,
                intensity: 3e4,
            },
        ];
        let mut m = FrameModel::new();
        m.nodes = vec![[0.0; 3], [l, 0.0, 0.0]];
        let mut member = Member::new(0, 1, section.clone());
        member.theory = theory;
        member.loads = loads.iter().copied().map(down).collect();
        m.members = vec![member];
        m.supports = vec![NodeSupport::fixed(0)];
        let s = m.solve().unwrap();
        let props = section.properties(STEEL_NU);
        let ei = E * props.second_moment;
        let g = E / (2.0 * (1.0 + STEEL_NU));
        let flex = match theory {
            MemberTheory::EulerBernoulli => 0.0,
            MemberTheory::Timoshenko => ei / (props.shear_coefficient * g * props.area),
        };
        let beam = LinearBeam::solve(Support::Cantilever, l, &loads, flex);
        let scale = beam.at(l).v / ei;
        for i in 0..=30 {
            let x = l * f64::from(i) / 30.0;
            let (u, r) = s.member_at(0, x);
            let b = beam.at(x);
            assert!((-u.z - b.v / ei).abs() <= 1e-12 * scale, "{theory:?} x={x}");
            // The section turns by the bending rotation ψ (x toward −z is about +y).
            assert!(
                (r.y - b.rotation / ei).abs() <= 1e-12 * scale / l,
                "{theory:?} x={x}"
            );
        }
    }
}

/// A space frame with members in three directions, releases, springs and loads of every kind.
pub(super) fn space_frame() -> FrameModel {
    let mut m = FrameModel::new();
    m.nodes = vec![
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 3.0],
        [4.0, 0.0, 3.0],
        [4.0, 0.0, 0.0],
        [4.0, 3.0, 3.0],
        [4.0, 3.0, 0.0],
    ];
    let ipe = Section::ISection {
        width: 0.15,
        height: 0.3,
        flange: 0.0107,
        web: 0.0071,
    };
    let tube = Section::CircularHollow {
        diameter: 0.2,
        wall: 0.01,
    };
    m.members = vec![
        Member::new(0, 1, tube.clone()),
        Member::new(1, 2, ipe.clone()),
        Member::new(3, 2, tube.clone()),
        Member::new(2, 4, ipe),
        Member::new(5, 4, tube.clone()),
        Member::bar(1, 4, tube),
    ];
    m.members[1].loads.push(udl(4.0, 8e3));
    m.members[1].loads.push(MemberLoad {
        load: Load::Point {
            at: 1.0,
            force: 5e3,
        },
        direction: [0.0, 1.0, 0.0],
        axes: Axes::Global,
    });
    m.members[3].loads.push(MemberLoad {
        load: Load::EndMoments {
            start: 0.0,
            end: 2e3,
        },
        direction: [1.0, 0.0, 0.0],
        axes: Axes::Local,
    });
    m.members[3].theory = MemberTheory::Timoshenko;
    m.members[3].releases[1] = Release::PIN;
    m.members[4].roll = 0.3;
    m.self_weight = true;
    let mut spring = NodeSupport::pinned(5);
    // Equal about x and y: the model is turned about z below.
    spring.springs = [0.0, 0.0, 0.0, 2e6, 2e6, 3e6];
    m.supports = vec![NodeSupport::fixed(0), NodeSupport::fixed(3), spring];
    m.loads = vec![NodalLoad {
        node: 4,
        force: [2e3, -1e3, -3e3],
        moment: [0.0, 0.0, 1e3],
    }];
    m
}

/// Σ applied + Σ reactions, forces and moments about the origin, with the largest term.
fn imbalance(m: &FrameModel, s: &FrameSolution) -> (f64, f64) {
    let mut force = DVec3::ZERO;
    let mut moment = DVec3::ZERO;
    let mut largest = 0.0f64;
    let mut add = |at: DVec3, f: DVec3, c: DVec3| {
        force += f;
        moment += c + at.cross(f);
        largest = largest.max(f.length()).max(c.length());
    };
    for l in &m.loads {
        let at = DVec3::from_array(m.nodes[l.node]);
        add(at, DVec3::from_array(l.force), DVec3::from_array(l.moment));
    }
    for r in &s.reactions {
        let at = DVec3::from_array(m.nodes[r.node]);
        add(at, DVec3::from_array(r.force), DVec3::from_array(r.moment));
    }
    // Member loads: integrate each member's loads as the applied forces they are.
    for (i, member) in m.members.iter().enumerate() {
        let start = DVec3::from_array(m.nodes[member.start]);
        let axes = s.member_axes(i);
        let x = axes.row(0);
        let length = s.member_length(i);
        let mut loads = member.loads.clone();
        if m.self_weight {
            let a = SpaceSection::of(&member.section, member.poisson).area;
            loads.push(udl(length, member.density * GRAVITY * a));
        }
        for l in loads {
            let dir = DVec3::from_array(l.direction);
            let dir = match l.axes {
                Axes::Global => dir,
                Axes::Local => axes.transpose() * dir,
            };
            match l.load {
                Load::Point { at, force } => add(start + at * x, force * dir, DVec3::ZERO),
                Load::Distributed {
                    from,
                    to,
                    intensity,
                } => add(
                    start + 0.5 * (from + to) * x,
                    intensity * (to - from) * dir,
                    DVec3::ZERO,
                ),
                Load::EndMoments { start: a, end: b } => add(start, DVec3::ZERO, (a + b) * dir),
            }
        }
    }
    let arm = m
        .nodes
        .iter()
        .map(|p| DVec3::from_array(*p).length())
        .fold(1.0, f64::max);
    (force.length() / largest, moment.length() / (largest * arm))
}

#[test]
fn equilibrium_and_compatibility_of_a_space_frame() {
    let m = space_frame();
    for solver in [Solver::Dense, Solver::Sparse] {
        let s = m.solve_with(solver).unwrap();
        let (f, c) = imbalance(&m, &s);
        assert!(f < 1e-9 && c < 1e-9, "{solver:?}: {f} {c}");
        // Each member's axis meets its nodes where they moved; rigid ends turn with them.
        for (i, member) in m.members.iter().enumerate() {
            let l = s.member_length(i);
            for (node, x, release) in [
                (member.start, 0.0, member.releases[0]),
                (member.end, l, member.releases[1]),
            ] {
                let (u, r) = s.member_at(i, x);
                let node = s.nodes[node];
                assert!(
                    u.distance(DVec3::from_array(node.displacement)) < 1e-9,
                    "member {i}"
                );
                if release == Release::default() {
                    assert!(
                        r.distance(DVec3::from_array(node.rotation)) < 1e-9,
                        "member {i}"
                    );
                }
            }
        }
    }
}

#[test]
fn moving_and_turning_the_model_moves_and_turns_the_results() {
    let m = space_frame();
    let s = m.solve().unwrap();
    // About world z (verticals stay vertical, so member axes and sections turn along) and far
    // from the origin.
    let turn = DMat3::from_rotation_z(0.7);
    let shift = DVec3::new(1e4, -2e4, 300.0);
    let mut moved = m.clone();
    for p in &mut moved.nodes {
        *p = (turn * DVec3::from_array(*p) + shift).to_array();
    }
    for l in &mut moved.loads {
        l.force = (turn * DVec3::from_array(l.force)).to_array();
        l.moment = (turn * DVec3::from_array(l.moment)).to_array();
    }
    for member in &mut moved.members {
        for l in &mut member.loads {
            if l.axes == Axes::Global {
                l.direction = (turn * DVec3::from_array(l.direction)).to_array();
            }
        }
    }
    let t = moved.solve().unwrap();
    let scale = s
        .nodes
        .iter()
        .map(|n| DVec3::from_array(n.displacement).length())
        .fold(0.0, f64::max);
    for (a, b) in s.nodes.iter().zip(&t.nodes) {
        let want = turn * DVec3::from_array(a.displacement);
        assert!(want.distance(DVec3::from_array(b.displacement)) < 1e-9 * scale);
    }
    // Member end forces in world axes (a vertical member's local axes take world X as their
    // reference and do not turn with the model); utilisation where the local axes turn along.
    for (i, (a, b)) in s.members.iter().zip(&t.members).enumerate() {
        let world = |r: &MemberResult, axes: DMat3, end: usize| {
            let f = |k: usize| DVec3::from_slice(&r.end_forces[6 * end + k..]);
            (axes.transpose() * f(0), axes.transpose() * f(3))
        };
        let top = a.end_forces.iter().fold(0.0f64, |m, f| m.max(f.abs()));
        for end in 0..2 {
            let (fa, ma) = world(a, s.member_axes(i), end);
            let (fb, mb) = world(b, t.member_axes(i), end);
            assert!((turn * fa).distance(fb) < 1e-9 * top, "member {i}");
            assert!((turn * ma).distance(mb) < 1e-9 * top, "member {i}");
        }
        if s.member_axes(i).row(0).z.abs() < 0.9 {
            assert!(close(b.utilisation, a.utilisation, 1e-9), "member {i}");
        }
    }
}

#[test]
fn a_mechanism_is_refused_with_its_dofs_named() {
    // A portal on pins with a pinned beam sways freely.
    let (mut m, ..) = portal(NodeSupport::pinned, 1.0);
    m.members[1].releases = [Release::PIN; 2];
    for solver in [Solver::Dense, Solver::Sparse] {
        let e = m.solve_with(solver).unwrap_err();
        assert!(
            e.contains("mechanism") && e.contains("node 1 ux") && e.contains("node 2 ux"),
            "{e}"
        );
    }
    // A bar hanging from nothing at its free end.
    let mut m = FrameModel::new();
    m.nodes = vec![[0.0; 3], [1.0, 0.0, 0.0]];
    m.members = vec![Member::bar(0, 1, rect(0.1, 0.1))];
    m.supports = vec![NodeSupport::pinned(0)];
    let e = m.solve().unwrap_err();
    assert!(
        e.contains("node 1 uy") && e.contains("node 1 uz") && !e.contains("node 1 ux"),
        "{e}"
    );
}

#[test]
fn dense_and_sparse_solvers_agree_on_a_large_truss() {
    let m = space_truss(60);
    let (d, s) = (
        m.solve_with(Solver::Dense).unwrap(),
        m.solve_with(Solver::Sparse).unwrap(),
    );
    let scale = d
        .nodes
        .iter()
        .map(|n| n.displacement[2].abs())
        .fold(0.0, f64::max);
    for (a, b) in d.nodes.iter().zip(&s.nodes) {
        for i in 0..3 {
            assert!((a.displacement[i] - b.displacement[i]).abs() < 1e-10 * scale);
        }
    }
}

/// The P-Δ cantilever column of the tests: length, tip force, axial load, bending stiffness.
struct Column {
    l: f64,
    h: f64,
    p: f64,
    ei: f64,
}

/// A vertical 6 m cantilever of `n` members (0.2 m square steel), a tip force H = 1 kN and
/// half its Euler load P = π² E I / (8 L²) at the top, analysed to second order.
fn p_delta_column(n: usize) -> (FrameModel, Column) {
    let (l, h) = (6.0, 1e3);
    let section = rect(0.2, 0.2);
    let ei = E * 0.2f64.powi(4) / 12.0;
    let p = 0.5 * std::f64::consts::PI.powi(2) * ei / (4.0 * l * l);
    let mut m = FrameModel::new();
    m.nodes = (0..=n)
        .map(|i| [0.0, 0.0, l * i as f64 / n as f64])
        .collect();
    m.members = (0..n)
        .map(|i| Member::new(i, i + 1, section.clone()))
        .collect();
    m.supports = vec![NodeSupport::fixed(0)];
    m.plane = Some(Plane::Xz);
    m.loads = vec![NodalLoad {
        node: n,
        force: [h, 0.0, -p],
        moment: [0.0; 3],
    }];
    m.second_order = true;
    (m, Column { l, h, p, ei })
}

#[test]
fn p_delta_cantilever_column_matches_the_beam_column_closed_form() {
    // A vertical cantilever under axial compression P and a tip force H: the exact tip
    // deflection is H (tan kL − kL) / (P k), k = √(P / EI) (Timoshenko & Gere §1.11), against
    // H L³ / (3 EI) at first order. Ten members (the cubic element's error falls as h⁴).
    let n = 10;
    let (mut m, Column { l, h, p, ei }) = p_delta_column(n);
    let critical = 2.0 * p;
    let s = m.solve().unwrap();
    let k = (p / ei).sqrt();
    let exact = h * ((k * l).tan() - k * l) / (p * k);
    let tip = s.nodes[n].displacement[0];
    // Axial shortening (P L / EA) changes nothing sideways; the discretisation ~1e-6.
    assert!(close(tip, exact, 1e-5), "{tip} vs {exact}");
    assert!(
        tip > 1.9 * h * l.powi(3) / (3.0 * ei),
        "amplified about 1/(1 − P/Pcr) = 2"
    );
    // At 1.1 times the critical load the column is refused.
    m.loads[0].force[2] = -1.1 * critical;
    let e = m.solve().unwrap_err();
    assert!(e.contains("critical"), "{e}");
}

/// Largest distance, over 9 stations inside each member, between the drawn axis of the
/// ten-member (or `n`-member) P-Δ cantilever column and the closed-form beam-column
/// v(z) = H/(P k) (tan kL (1 − cos kz) − kz + sin kz), as a fraction of the tip deflection;
/// and the same at the nodes.
fn p_delta_column_shape_errors(n: usize) -> (f64, f64) {
    let (m, Column { l, h, p, ei }) = p_delta_column(n);
    let s = m.solve().unwrap();
    let k = (p / ei).sqrt();
    let exact =
        |z: f64| h / (p * k) * ((k * l).tan() * (1.0 - (k * z).cos()) - k * z + (k * z).sin());
    let tip = exact(l);
    let (mut inside, mut nodes) = (0.0f64, 0.0f64);
    for i in 0..n {
        let length = s.member_length(i);
        for j in 0..=10 {
            let z = l * i as f64 / n as f64 + length * j as f64 / 10.0;
            let error = (s.member_at(i, length * j as f64 / 10.0).0.x - exact(z)).abs() / tip;
            if j == 0 || j == 10 {
                nodes = nodes.max(error);
            } else {
                inside = inside.max(error);
            }
        }
    }
    (inside, nodes)
}

#[test]
fn under_p_delta_the_shape_inside_a_member_is_the_beam_column_field() {
    // Given exact end values, the member's field is the closed form of E I v⁗ = N v″; in a
    // model of few members the drawn shape inside is then as good as its nodes (measured:
    // 2.3e-4 of the tip inside against 2.5e-4 at the nodes for two members, 4.8e-5 against
    // 5.1e-5 for three), where a cubic between the same nodes misses the amplification
    // (4.3e-4 and 9.5e-5: 1.7 to 1.9 times the nodes' error).
    for n in [2, 3] {
        let (inside, nodes) = p_delta_column_shape_errors(n);
        assert!(
            inside < 1.1 * nodes,
            "{n} members: inside {inside}, nodes {nodes}"
        );
    }
    // Cantilever under compression (kL = π/(2√2): half the Euler load) and under tension.
    let (l, h, p) = (6.0, 1e3, 2e5);
    let k = std::f64::consts::PI / (2.0 * 2f64.sqrt()) / l;
    let compressed = |x: f64| {
        let (t, y) = ((k * l).tan(), k * x);
        (
            h / (p * k) * (t * (1.0 - y.cos()) - y + y.sin()),
            h / p * (t * y.sin() - 1.0 + y.cos()),
        )
    };
    let stretched = |x: f64| {
        let (t, y) = ((k * l).tanh(), k * x);
        (
            h / (p * k) * (y - y.sinh() + t * (y.cosh() - 1.0)),
            h / p * (1.0 - y.cosh() + t * y.sinh()),
        )
    };
    for (s, field) in [
        (-k * k, &compressed as &dyn Fn(f64) -> (f64, f64)),
        (k * k, &stretched),
    ] {
        let ends = [0.0, 0.0, field(l).0, field(l).1];
        for i in 1..10 {
            let x = l * i as f64 / 10.0;
            let (v, theta) = results::beam_column(x / l, l, s, ends);
            let (want_v, want_theta) = field(x);
            assert!(
                (v - want_v).abs() < 1e-12 * ends[2],
                "s {s} x {x}: {v} vs {want_v}"
            );
            assert!(
                (theta - want_theta).abs() < 1e-12 * ends[3].abs(),
                "s {s} x {x}"
            );
        }
    }
    // A vanishing axial force gives the cubic (the series branch): v = v_L (3ξ² − 2ξ³) here.
    for xi in [0.25, 0.5, 0.75] {
        let (v, _) = results::beam_column(xi, l, -1e-12, [0.0, 0.0, 1.0, 0.0]);
        assert!(
            (v - (3.0 * xi * xi - 2.0 * xi.powi(3))).abs() < 1e-12,
            "{xi}: {v}"
        );
    }
}
