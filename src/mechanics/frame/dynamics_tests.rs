//! Frames in time against independent truth: a simply supported span modelled as a chain of
//! members follows the beam module's modal solution (itself checked against Frýba's series) as
//! a force crosses it; a slow vehicle on a continuous girder, driven along a lane listed end to
//! start, stays on the static solution of the load where the test puts it by hand; a step load
//! settles to the static solution at the damping ratio's rate; bad lanes and parameters are
//! refused with their values.

use super::modes_tests::chain;
use super::*;
use crate::mechanics::dynamics::{Axle, ModalBeam, TimeLoad};
use crate::mechanics::{Load, Support};

/// A single force `force` (N, downward) crossing from lane position 0 at `speed`.
fn crossing(force: f64, speed: f64) -> Vec<TimeLoad> {
    vec![TimeLoad::Vehicle {
        axles: vec![Axle { behind: 0.0, force }],
        speed,
        enters: 0.0,
    }]
}

fn lane_of(model: &FrameModel) -> Vec<usize> {
    (0..model.members.len()).collect()
}

/// Vertical displacement of `node`, positive downward.
fn sag(state: &FrameState, node: usize) -> f64 {
    -state.solution.nodes[node].displacement[2]
}

#[test]
fn a_force_crossing_a_chain_follows_the_beams_modal_solution() {
    // 16 Hermite members: the bending frequencies above the beam's by the leading error
    // (β_n h)⁴/1440 (2.6e-4 for the fourth), so the histories agree to a few 1e-4 of the
    // peak, carried mostly by the first mode (error 1e-6). The four
    // lowest modes of the plane chain are its bending modes (its first axial mode, 128 Hz,
    // is the sixth), and a vertical force does not excite axial modes anyway.
    let (model, _) = chain(16, Support::SimplySupported);
    let (area, inertia) = (0.1 * 0.2, 0.1 * 0.2f64.powi(3) / 12.0);
    let beam = ModalBeam::new(
        Support::SimplySupported,
        10.0,
        STEEL_E * inertia,
        STEEL_DENSITY * area,
        0.02,
        4,
    )
    .unwrap();
    let frame = model.dynamics(&lane_of(&model), 4, 0.02).unwrap();
    assert_eq!(frame.lane_length(), 10.0);
    for (n, (f_frame, f_beam)) in frame
        .frequencies()
        .iter()
        .zip(beam.frequencies())
        .enumerate()
    {
        let beta_h = (n + 1) as f64 * std::f64::consts::PI / 16.0;
        let leading = beta_h.powi(4) / 1440.0;
        let error = f_frame / f_beam - 1.0;
        assert!(
            error > 0.0 && error < 1.5 * leading,
            "mode {}: {f_frame} vs {f_beam}",
            n + 1
        );
    }
    // 30 m/s: a speed parameter α = v / (2 f₁ L) ≈ 0.32, dynamic amplification clearly seen.
    let loads = crossing(1e4, 30.0);
    let times: Vec<f64> = (1..=60).map(|k| k as f64 * 0.01).collect();
    let response = beam.respond(&loads, 0.0, &times, 32);
    let states = frame.respond(&loads, 0.0, &times, 32).unwrap();
    let truth: Vec<f64> = (0..times.len())
        .map(|k| response.at(&beam, &loads, k, 5.0).deflection)
        .collect();
    let peak = truth.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let static_peak = 1e4 * 1000.0 / (48.0 * STEEL_E * inertia);
    assert!(
        peak > 1.1 * static_peak,
        "the crossing should amplify: {peak} vs {static_peak}"
    );
    for (k, state) in states.iter().enumerate() {
        assert_eq!(state.time, times[k]);
        let error = (sag(state, 8) - truth[k]).abs();
        assert!(
            error < 5e-4 * peak,
            "t = {}: {} vs {}",
            times[k],
            sag(state, 8),
            truth[k]
        );
    }
}

/// A 20 m girder continuous over a middle support, 16 members a span.
fn continuous_girder() -> FrameModel {
    let (mut model, _) = chain(32, Support::SimplySupported);
    for (i, node) in model.nodes.iter_mut().enumerate() {
        node[0] = 20.0 * i as f64 / 32.0;
    }
    model.supports.push(NodeSupport::roller(16));
    model
}

#[test]
fn a_slow_vehicle_on_a_lane_listed_backwards_stays_on_the_static_solution() {
    // The lane runs from node 32 to node 0 over members listed last to first: lane position s
    // is x = 20 − s. Two axles 3 m apart at 0.05 m/s: α ≈ 3e-4, so the dynamic part is below
    // 1e-3 of the static response, which the test builds by hand with member loads.
    let model = continuous_girder();
    let lane: Vec<usize> = (0..32).rev().collect();
    let frame = model.dynamics(&lane, 6, 0.02).unwrap();
    let loads = vec![TimeLoad::Vehicle {
        axles: vec![
            Axle {
                behind: 0.0,
                force: 6e4,
            },
            Axle {
                behind: 3.0,
                force: 9e4,
            },
        ],
        speed: 0.05,
        enters: 0.0,
    }];
    let times = [70.0, 150.0, 230.0, 310.0];
    let states = frame.respond(&loads, 0.0, &times, 16).unwrap();
    for (state, &t) in states.iter().zip(&times) {
        let mut by_hand = model.clone();
        for (behind, force) in [(0.0, 6e4), (3.0, 9e4)] {
            let s: f64 = 0.05 * t - behind;
            if !(0.0..20.0).contains(&s) {
                continue;
            }
            let x = 20.0 - s;
            let member = ((x / 0.625).floor() as usize).min(31);
            by_hand.members[member].loads.push(MemberLoad {
                load: Load::Point {
                    at: x - 0.625 * member as f64,
                    force,
                },
                direction: [0.0, 0.0, -1.0],
                axes: Axes::Global,
            });
        }
        let static_solution = by_hand.solve().unwrap();
        let peak = static_solution
            .nodes
            .iter()
            .fold(0.0f64, |m, n| m.max(n.displacement[2].abs()));
        for (node, expected) in static_solution.nodes.iter().enumerate() {
            let got = state.solution.nodes[node].displacement[2];
            assert!(
                (got - expected.displacement[2]).abs() < 1e-3 * peak,
                "t = {t}, node {node}: {got} vs {}",
                expected.displacement[2]
            );
        }
    }
}

#[test]
fn a_step_settles_to_the_static_solution_at_the_damping_rate() {
    // A 20 kN step at 2.5 m on the simply supported chain. ζ = 0.1: after 5 s the first mode
    // (ω₁ ≈ 29.5 rad/s) has decayed by e^(−ζ ω₁ t) ≈ 4e-7; the mode-acceleration recovery makes
    // the static part exact, so the remainder is the decay alone.
    let (model, _) = chain(16, Support::SimplySupported);
    let frame = model.dynamics(&lane_of(&model), 4, 0.1).unwrap();
    let loads = [TimeLoad::Ramp {
        at: 2.5,
        force: 2e4,
        start: 0.0,
        rise: 0.0,
    }];
    let states = frame.respond(&loads, 0.0, &[0.05, 5.0], 16).unwrap();
    let mut by_hand = model.clone();
    by_hand.loads.push(NodalLoad {
        node: 4,
        force: [0.0, 0.0, -2e4],
        moment: [0.0; 3],
    });
    let settled = by_hand.solve().unwrap();
    let expected = settled.nodes[8].displacement[2];
    let early = states[0].solution.nodes[8].displacement[2];
    let late = states[1].solution.nodes[8].displacement[2];
    assert!(
        (early - expected).abs() > 0.1 * expected.abs(),
        "rings at first: {early}"
    );
    assert!(
        (late - expected).abs() < 1e-6 * expected.abs(),
        "{late} vs {expected}"
    );
    // At rest: the velocity and acceleration are gone too.
    assert!(states[1].velocity[8][2].abs() < 1e-5 * expected.abs() * 29.5);
    assert!(states[1].acceleration[8][2].abs() < 1e-5 * expected.abs() * 29.5 * 29.5);
}

#[test]
fn bad_lanes_and_parameters_are_refused_with_their_values() {
    let model = continuous_girder();
    let message = |lane: &[usize], modes: usize, damping: f64| {
        model.dynamics(lane, modes, damping).unwrap_err()
    };
    assert!(message(&[], 4, 0.02).contains("at least one member"));
    assert!(message(&[0, 40], 4, 0.02).contains("lane member 40 does not exist"));
    let gap = message(&[0, 1, 5], 4, 0.02);
    assert!(
        gap.contains("lane member 5") && gap.contains("position 2"),
        "{gap}"
    );
    assert!(message(&[0], 4, 1.5).contains("got 1.5"));
    assert!(message(&[0], 0, 0.02).contains("at least one mode"));
    let mut p_delta = model.clone();
    p_delta.second_order = true;
    assert!(
        p_delta
            .dynamics(&[0], 2, 0.02)
            .unwrap_err()
            .contains("second_order")
    );
    let frame = model.dynamics(&[0, 1], 2, 0.02).unwrap();
    let off_lane = [TimeLoad::Ramp {
        at: 3.0,
        force: 1.0,
        start: 0.0,
        rise: 0.0,
    }];
    let refused = frame.respond(&off_lane, 0.0, &[1.0], 16).unwrap_err();
    assert!(
        refused.contains("3 m lies off the span 0 to 1.25 m"),
        "{refused}"
    );
}
