//! Against closed forms: a step load's static deflection, end rotation and fibre strains
//! (PL³/48EI, PL²/16EI, ±(PL/4)c/EI), the free decay of an accelerometer's signal at the
//! damping ratio, Frýba's series for a constant force crossing the span (the helper of the
//! dynamics tests), the accelerometer against the second difference of the displacement
//! series, and the noise added as stated.

use super::*;
use crate::mechanics::Support;
use crate::mechanics::dynamics::tests::{
    EI, L, MASS, crossing, first_omega_simply_supported, fryba, ringing_after_a_blow,
};
use std::f64::consts::PI;

/// A source of "normal" values that counts its draws: 1, 2, 3, …
fn counting() -> impl FnMut() -> f64 {
    let mut drawn = 0.0;
    move || {
        drawn += 1.0;
        drawn
    }
}

fn sensor(name: &str, kind: SensorKind, at: f64, rate: f64) -> Sensor {
    Sensor {
        name: name.into(),
        kind,
        at,
        rate,
        noise: 0.0,
    }
}

#[test]
fn a_step_load_settles_to_the_static_deflection_rotation_and_strains() {
    // ζ = 0.5 damps the ringing to e^(−0.5·ω₁·6 s) ≈ 10⁻²³ of the step by the last sample.
    let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, 0.5, 8).unwrap();
    let force = 2.0e5;
    let loads = [TimeLoad::Ramp {
        at: L / 2.0,
        force,
        start: 0.5,
        rise: 0.0,
    }];
    let c = 0.4;
    let strain = |fibre| SensorKind::Strain { fibre, distance: c };
    let sensors = [
        sensor("mid", SensorKind::Displacement, L / 2.0, 50.0),
        sensor("end", SensorKind::Rotation, 0.0, 20.0),
        sensor("top", strain(Fibre::Top), L / 2.0, 50.0),
        sensor("bottom", strain(Fibre::Bottom), L / 2.0, 100.0),
    ];
    let series = record(&beam, &loads, 6.0, &sensors, &mut counting()).unwrap();
    let last = |k: usize| *series[k].values.last().unwrap();
    let deflection = force * L.powi(3) / (48.0 * EI);
    let rotation = force * L * L / (16.0 * EI);
    let surface = force * L / 4.0 * c / EI;
    for (got, exact) in [
        (last(0), deflection),
        (last(1), rotation),
        (last(2), -surface),
        (last(3), surface),
    ] {
        assert!((got / exact - 1.0).abs() < 1e-9, "{got} vs {exact}");
    }
    // Before the step nothing moves; each series has its own rate and ends before 6 s, as
    // the frames of a 6 s sequence do.
    assert_eq!(series[0].values[..25], [0.0; 25]);
    assert_eq!([0, 1, 3].map(|k| series[k].times.len()), [300, 120, 600]);
    assert_eq!(*series[1].times.last().unwrap(), 119.0 / 20.0);
}

#[test]
fn an_accelerometer_decays_at_the_damping_ratio_after_a_hammer_blow() {
    let zeta = 0.03;
    let (beam, loads, period) = ringing_after_a_blow(zeta);
    let w = first_omega_simply_supported();
    // 40 samples a damped period: sample k and k + 40 are one period apart.
    let accelerometer = sensor("a", SensorKind::Acceleration, L / 2.0, 40.0 / period);
    let series = record(
        &beam,
        &loads,
        6.0 * period,
        &[accelerometer],
        &mut counting(),
    )
    .unwrap();
    let a = &series[0].values;
    let ratio = (-zeta * w * period).exp();
    let peak = a.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let times = &series[0].times;
    for k in 0..a.len() - 40 {
        // After the blow, and away from the zeros, where a ratio means nothing.
        if times[k] > 0.01 && a[k].abs() > 0.3 * peak {
            let got = a[k + 40] / a[k];
            assert!((got - ratio).abs() < 1e-6, "sample {k}: {got} vs {ratio}");
        }
    }
}

#[test]
fn a_displacement_sensor_under_a_crossing_force_follows_frybas_series() {
    let alpha = 0.7;
    let speed = alpha * first_omega_simply_supported() * L / PI;
    let force = 1.0e5;
    let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, 0.0, 16).unwrap();
    let crossing_time = L / speed;
    let sensors = [
        sensor("mid", SensorKind::Displacement, L / 2.0, 1000.0),
        sensor("quarter", SensorKind::Displacement, L / 4.0, 1000.0),
    ];
    let series = record(
        &beam,
        &crossing(force, speed),
        crossing_time,
        &sensors,
        &mut counting(),
    )
    .unwrap();
    let static_peak = force * L.powi(3) / (48.0 * EI);
    for (sensor, recorded) in sensors.iter().zip(&series) {
        assert!(recorded.times.len() > 100);
        for (&t, &got) in recorded.times.iter().zip(&recorded.values) {
            let exact = fryba(force, speed, sensor.at, t, 4000);
            // The force's interpolation at 64 steps a period: (π/64)²/2 ≈ 1.2·10⁻³ of the
            // modal forces' variation, of which the deflection feels a small part.
            assert!(
                (got - exact).abs() < 2e-4 * static_peak,
                "{} t {t}: {got} vs {exact}",
                sensor.name
            );
        }
    }
}

#[test]
fn an_accelerometer_reads_the_second_difference_of_the_displacement() {
    // Three modes (the highest at 25 Hz) sampled at 1 kHz: the central difference's error is
    // (ω₃h)²/12 ≈ 2·10⁻³ of the third mode's share. After the blow the loads are zero, so the
    // displacement is Σ q φ and the acceleration Σ q̈ φ exactly.
    let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, 0.02, 3).unwrap();
    let loads = [TimeLoad::Pulse {
        at: 0.3 * L,
        force: 8.0e4,
        start: 0.0,
        duration: 0.02,
    }];
    let rate = 1000.0;
    let at = 0.4 * L;
    let sensors = [
        sensor("v", SensorKind::Displacement, at, rate),
        sensor("a", SensorKind::Acceleration, at, rate),
    ];
    let series = record(&beam, &loads, 2.0, &sensors, &mut counting()).unwrap();
    let (v, a) = (&series[0].values, &series[1].values);
    let peak = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let h = 1.0 / rate;
    for k in 30..v.len() - 1 {
        let difference = (v[k + 1] - 2.0 * v[k] + v[k - 1]) / (h * h);
        assert!(
            (difference - a[k]).abs() < 5e-3 * peak,
            "sample {k}: {difference} vs {}",
            a[k]
        );
    }
}

#[test]
fn noise_is_its_rms_times_the_normal_values_drawn_in_sensor_order() {
    let beam = ModalBeam::new(Support::Cantilever, 5.0, 1.0e7, 50.0, 0.05, 2).unwrap();
    let quiet = sensor("q", SensorKind::Acceleration, 5.0, 10.0);
    let mut noisy = sensor("n", SensorKind::Displacement, 2.0, 4.0);
    noisy.noise = 0.5;
    let mut louder = sensor("l", SensorKind::Acceleration, 5.0, 10.0);
    louder.noise = 2.0;
    // No load: each value is its noise alone. 1 s: 10 samples at 10 Hz, 4 at 4 Hz.
    let sensors = [quiet, noisy, louder];
    let series = record(&beam, &[], 1.0, &sensors, &mut counting()).unwrap();
    assert!(series[0].values.iter().all(|&v| v == 0.0));
    let expected = |first: usize, n: usize, rms: f64| -> Vec<f64> {
        (first..first + n).map(|k| rms * k as f64).collect()
    };
    assert_eq!(series[1].values, expected(1, 4, 0.5));
    assert_eq!(series[2].values, expected(5, 10, 2.0));
}

#[test]
fn bad_sensors_are_refused_with_their_values() {
    let beam = ModalBeam::new(Support::SimplySupported, L, EI, MASS, 0.0, 2).unwrap();
    let refused =
        |s: Sensor, duration: f64| record(&beam, &[], duration, &[s], &mut counting()).unwrap_err();
    let e = refused(sensor("s", SensorKind::Velocity, 25.0, 10.0), 1.0);
    assert!(e.contains("\"s\"") && e.contains("25"), "{e}");
    let e = refused(sensor("s", SensorKind::Velocity, 5.0, 0.0), 1.0);
    assert!(e.contains("rate") && e.contains("0 Hz"), "{e}");
    let e = refused(sensor("s", SensorKind::Velocity, 5.0, 1e6), 100.0);
    assert!(e.contains("samples"), "{e}");
    let gauge = SensorKind::Strain {
        fibre: Fibre::Top,
        distance: f64::NAN,
    };
    assert!(refused(sensor("g", gauge, 5.0, 10.0), 1.0).contains("NaN"));
    let e = refused(sensor("a,b", SensorKind::Velocity, 5.0, 10.0), 1.0);
    assert!(e.contains("\"a,b\""), "{e}");
    let e = refused(sensor("s", SensorKind::Velocity, 5.0, 10.0), -1.0);
    assert!(e.contains("duration") && e.contains("-1"), "{e}");
}
