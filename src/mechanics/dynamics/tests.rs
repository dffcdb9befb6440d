//! Against closed forms: natural frequencies, the step response of a damped oscillator, free
//! decay, the static limit, and Frýba's series for a constant force crossing a simply supported
//! beam (Frýba, *Vibration of Solids and Structures under Moving Loads*, 1972, §1.1).

use super::*;

pub(crate) const L: f64 = 20.0;
pub(crate) const EI: f64 = 2.0e9;
pub(crate) const MASS: f64 = 4000.0;

pub(crate) fn first_omega_simply_supported() -> f64 {
    (PI / L).powi(2) * (EI / MASS).sqrt()
}

/// Frýba's undamped solution while the force is on the span, summed to `terms`:
/// v(x, t) = v₀ Σ 1/(j²(j² − α²)) [sin jωt − (α/j) sin ω_j t] sin(jπx/L), v₀ = 2PL³/(π⁴EI),
/// ω = πc/L, α = ω/ω₁.
pub(crate) fn fryba(force: f64, speed: f64, x: f64, t: f64, terms: u32) -> f64 {
    let v0 = 2.0 * force * L.powi(3) / (PI.powi(4) * EI);
    let omega = PI * speed / L;
    let alpha = omega / first_omega_simply_supported();
    (1..=terms)
        .map(|j| {
            let j = j as f64;
            let wj = j * j * first_omega_simply_supported();
            ((j * omega * t).sin() - alpha / j * (wj * t).sin()) / (j * j * (j * j - alpha * alpha))
                * (j * PI * x / L).sin()
        })
        .sum::<f64>()
        * v0
}

pub(crate) fn crossing(force: f64, speed: f64) -> Vec<TimeLoad> {
    vec![TimeLoad::Vehicle {
        axles: vec![Axle { behind: 0.0, force }],
        speed,
        enters: 0.0,
    }]
}

/// A one-mode simply supported beam damped at `zeta`, a 10 ms blow at mid-span at t = 0, and
/// the first mode's damped period.
pub(crate) fn ringing_after_a_blow(zeta: f64) -> (ModalBeam, [TimeLoad; 1], f64) {
    let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, zeta, 1).unwrap();
    let blow = TimeLoad::Pulse {
        at: L / 2.0,
        force: 5.0e4,
        start: 0.0,
        duration: 0.01,
    };
    let w = first_omega_simply_supported();
    (beam, [blow], 2.0 * PI / (w * (1.0 - zeta * zeta).sqrt()))
}

#[test]
fn frequencies_and_modal_masses_match_closed_forms() {
    let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, 0.0, 5).unwrap();
    for (n, f) in beam.frequencies().iter().enumerate() {
        let k = (n + 1) as f64;
        let exact = k * k * PI / (2.0 * L * L) * (EI / MASS).sqrt();
        assert!(
            (f / exact - 1.0).abs() < 1e-12,
            "mode {k}: {f} Hz vs {exact}"
        );
        // ∫ sin² = L/2.
        assert!((beam.modes[n].mass / (MASS * L / 2.0) - 1.0).abs() < 1e-12);
    }
    let cantilever = ModalBeam::new(Support::Cantilever, L, EI, MASS, 0.0, 1).unwrap();
    // β₁L = 1.875104068711961 (Blevins, Formulas for Natural Frequency and Mode Shape, Table 8-1).
    let exact = 1.875_104_068_711_961_f64.powi(2) / (2.0 * PI * L * L) * (EI / MASS).sqrt();
    assert!((cantilever.frequencies()[0] / exact - 1.0).abs() < 1e-12);
}

#[test]
fn a_step_force_gives_the_damped_oscillator_step_response() {
    let zeta = 0.05;
    let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, zeta, 1).unwrap();
    let force = 1.0e4;
    let loads = [TimeLoad::Ramp {
        at: L / 2.0,
        force,
        start: 0.1,
        rise: 0.0,
    }];
    let times: Vec<f64> = (1..=40).map(|k| 0.1 + 0.037 * k as f64).collect();
    let response = beam.respond(&loads, 0.0, &times, 16);
    let w = first_omega_simply_supported();
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let q_static = force / (MASS * L / 2.0) / (w * w);
    for (k, &t) in times.iter().enumerate() {
        let s = t - 0.1;
        let exact = q_static
            * (1.0 - (-zeta * w * s).exp() * ((wd * s).cos() + zeta * w / wd * (wd * s).sin()));
        let q = response.modal(k)[0];
        assert!(
            (q - exact).abs() < 1e-10 * q_static,
            "t = {t}: {q} vs {exact}"
        );
    }
}

#[test]
fn free_vibration_decays_by_the_damping_ratio() {
    let zeta = 0.02;
    let (beam, loads, period) = ringing_after_a_blow(zeta);
    let w = first_omega_simply_supported();
    let times: Vec<f64> = (0..6).map(|k| 0.05 + k as f64 * period).collect();
    let response = beam.respond(&loads, 0.0, &times, 64);
    let ratio = (-zeta * w * period).exp();
    for k in 1..times.len() {
        let (a, b) = (response.modal(k - 1)[0], response.modal(k)[0]);
        assert!(
            (b / a - ratio).abs() < 1e-9,
            "cycle {k}: {} vs {ratio}",
            b / a
        );
    }
}

#[test]
fn a_force_crossing_a_simply_supported_beam_follows_frybas_series() {
    // α = 0.5 and α = 0.9: well below and near the critical speed c_cr = ω₁L/π.
    for alpha in [0.5, 0.9] {
        let speed = alpha * first_omega_simply_supported() * L / PI;
        let force = 1.0e5;
        let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, 0.0, 16).unwrap();
        let loads = crossing(force, speed);
        let crossing_time = L / speed;
        let times: Vec<f64> = (1..=60).map(|k| crossing_time * k as f64 / 60.0).collect();
        let response = beam.respond(&loads, 0.0, &times, 200);
        let static_peak = force * L.powi(3) / (48.0 * EI);
        let mut peak: f64 = 0.0;
        for (k, &t) in times.iter().enumerate() {
            for x in [0.25 * L, 0.5 * L, 0.8 * L] {
                let got = response.at(&beam, &loads, k, x).deflection;
                let exact = fryba(force, speed, x, t, 4000);
                assert!(
                    (got - exact).abs() < 2e-5 * static_peak,
                    "α {alpha}, t {t:.3}, x {x}: {got} vs {exact}"
                );
                if x == 0.5 * L {
                    peak = peak.max(got);
                }
            }
        }
        // The dynamic amplification grows towards the critical speed.
        let amplification = peak / static_peak;
        let exact_peak = times
            .iter()
            .map(|&t| fryba(force, speed, 0.5 * L, t, 4000))
            .fold(0.0, f64::max);
        assert!((amplification - exact_peak / static_peak).abs() < 1e-4);
        assert!(
            amplification > if alpha > 0.8 { 1.5 } else { 1.2 },
            "α {alpha}: {amplification}"
        );
    }
}

#[test]
fn an_output_at_the_start_is_the_rest_state() {
    // A step applied at the start: at t = 0 the beam has not moved yet (before, the output at
    // the start instant took the state after the first step).
    let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, 0.0, 2).unwrap();
    let loads = [TimeLoad::Ramp {
        at: L / 2.0,
        force: 1.0e5,
        start: 0.0,
        rise: 0.0,
    }];
    let response = beam.respond(&loads, 0.0, &[0.0, 0.05], 16);
    assert_eq!(response.modal(0), [0.0, 0.0]);
    assert_eq!(response.at(&beam, &loads, 0, L / 2.0).velocity, 0.0);
    assert!(response.modal(1)[0] > 0.0);
}

#[test]
fn a_slow_crossing_is_the_static_solution() {
    let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, 0.02, 3).unwrap();
    // Damping makes the response lag the load by about 2ζα of it: keep α at 10⁻⁶.
    let speed = 1e-6 * first_omega_simply_supported() * L / PI;
    let force = 2.0e5;
    let loads = crossing(force, speed);
    let t = 0.3 * L / speed;
    let response = beam.respond(&loads, 0.0, &[t], 16);
    // Point load P at a = 0.3L, b = 0.7L: v(x) = P b x (L² − b² − x²)/(6 L EI) for x ≤ a,
    // and M(a) = P a b / L.
    let (a, b) = (0.3 * L, 0.7 * L);
    let x = 0.2 * L;
    let exact = force * b * x * (L * L - b * b - x * x) / (6.0 * L * EI);
    let got = response.at(&beam, &loads, 0, x);
    assert!(
        (got.deflection / exact - 1.0).abs() < 1e-5,
        "{} vs {exact}",
        got.deflection
    );
    let moment = response.at(&beam, &loads, 0, a).moment;
    assert!(
        (moment / (force * a * b / L) - 1.0).abs() < 1e-5,
        "{moment}"
    );
}

#[test]
fn a_cantilever_settles_to_its_static_tip_deflection_at_high_mode_numbers() {
    // 60 modes: the clamped mode shapes stay finite and the steps stable.
    let beam = ModalBeam::new(Support::Cantilever, 5.0, 1.0e7, 50.0, 0.05, 60).unwrap();
    let force = 1.0e3;
    let loads = [TimeLoad::Ramp {
        at: 5.0,
        force,
        start: 0.0,
        rise: 0.0,
    }];
    let response = beam.respond(&loads, 0.0, &[60.0], 8);
    let tip = response.at(&beam, &loads, 0, 5.0);
    let exact = force * 125.0 / (3.0 * 1.0e7);
    assert!(
        (tip.deflection / exact - 1.0).abs() < 1e-6,
        "{} vs {exact}",
        tip.deflection
    );
    assert!(tip.acceleration.is_finite() && tip.acceleration.abs() < 1e-3);
}

#[test]
fn bad_parameters_are_refused_with_their_values() {
    let e = ModalBeam::new(Support::SimplySupported, L, EI, -1.0, 0.0, 2).unwrap_err();
    assert!(e.contains("mass per length") && e.contains("-1"), "{e}");
    let e = ModalBeam::new(Support::SimplySupported, L, EI, MASS, 1.5, 2).unwrap_err();
    assert!(e.contains("1.5"), "{e}");
    let e = crossing(1.0, 0.0)[0].check(L).unwrap_err();
    assert!(e.contains("speed") && e.contains('0'), "{e}");
    let pulse = TimeLoad::Pulse {
        at: 25.0,
        force: 1.0,
        start: 0.0,
        duration: 0.1,
    };
    assert!(pulse.check(L).unwrap_err().contains("25"));
    let single = TimeLoad::Sampled {
        at: 1.0,
        start: 0.0,
        step: 0.01,
        values: vec![5.0],
    };
    assert!(single.check(L).unwrap_err().contains("got 1"));
}
