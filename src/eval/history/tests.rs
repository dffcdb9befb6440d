//! Against independent truth: a prediction equal to the truth scores 0; an offset c has RMSE
//! |c|, a scale s has RMSE |s − 1|·rms(t) and peak error (s − 1)·max|t|; a decaying sine's
//! frequency is identified to 10⁻³ of itself (with drift and a weaker second mode); the FFT
//! equals the direct DFT; the writer's files read back (CSV here, `.npy` by our reader).

use super::*;
use crate::output::{RateGroup, SensorColumn};

const RATE: f64 = 100.0;

/// A decaying sine of `f` Hz at ζ = 0.02, 20 s at 100 Hz.
fn ringing(f: f64) -> Vec<f64> {
    let w = 2.0 * PI * f;
    (0..2000)
        .map(|k| {
            let t = k as f64 / RATE;
            (-0.02 * w * t).exp() * (w * t).sin()
        })
        .collect()
}

fn table(columns: Vec<(&str, Vec<f64>)>) -> Table {
    let n = columns[0].1.len();
    Table {
        names: columns.iter().map(|(n, _)| n.to_string()).collect(),
        times: (0..n).map(|k| k as f64 / RATE).collect(),
        columns: columns.into_iter().map(|(_, v)| v).collect(),
    }
}

#[test]
fn a_prediction_equal_to_the_truth_scores_zero() {
    let truth = table(vec![("mid", ringing(2.37)), ("quarter", ringing(3.1))]);
    let scores = score(&truth, &truth, "p.csv").unwrap();
    for s in &scores {
        assert_eq!(
            (s.rmse, s.max_error, s.peak_error, s.nrmse),
            (0.0, 0.0, 0.0, Some(0.0))
        );
        assert_eq!(s.frequency_error, Some(0.0));
        assert_eq!((s.scored, s.excluded), (2000, 0));
    }
}

#[test]
fn an_offset_and_a_scale_give_their_closed_form_errors() {
    let t = ringing(2.37);
    let rms = (t.iter().map(|v| v * v).sum::<f64>() / t.len() as f64).sqrt();
    let peak = t.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let (lo, hi) = t
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    let truth = table(vec![("mid", t.clone())]);
    let offset = table(vec![("mid", t.iter().map(|v| v + 0.003).collect())]);
    let s = &score(&truth, &offset, "p.csv").unwrap()[0];
    assert!((s.rmse - 0.003).abs() < 1e-12 && (s.max_error - 0.003).abs() < 1e-12);
    assert!((s.nrmse.unwrap() - 0.003 / (hi - lo)).abs() < 1e-12);
    // A constant offset does not move the identified frequency (the line is removed).
    assert!(
        s.frequency_error.unwrap().abs() < 1e-9,
        "{:?}",
        s.frequency_error
    );
    let scaled = table(vec![("mid", t.iter().map(|v| 1.1 * v).collect())]);
    let s = &score(&truth, &scaled, "p.csv").unwrap()[0];
    assert!((s.rmse / (0.1 * rms) - 1.0).abs() < 1e-12, "{}", s.rmse);
    assert!((s.peak_error / (0.1 * peak) - 1.0).abs() < 1e-12);
    assert!(s.frequency_error.unwrap().abs() < 1e-9);
}

#[test]
fn missing_instants_are_left_out_and_counted() {
    let t = ringing(2.37);
    let mut p = t.clone();
    p[10] = f64::NAN;
    p[20] += 1.0;
    let s = &score(&table(vec![("mid", t)]), &table(vec![("mid", p)]), "p").unwrap()[0];
    assert_eq!((s.scored, s.excluded), (1999, 1));
    assert!((s.rmse - (1.0 / 1999.0_f64).sqrt()).abs() < 1e-12);
    // A series with gaps has no identified frequency.
    assert_eq!(s.frequency_predicted, None);
}

#[test]
fn the_frequency_of_a_decaying_sine_is_identified_within_a_thousandth() {
    for f in [0.37, 1.0, 2.37, 7.9, 31.3] {
        let got = identify_frequency(&ringing(f), RATE).unwrap();
        assert!((got / f - 1.0).abs() < 1e-3, "{f} Hz: {got}");
    }
    // Drift, offset and a weaker second mode at 4f do not move the first.
    let f = 2.37;
    let second = ringing(4.0 * f);
    let mixed: Vec<f64> = (ringing(f).iter().zip(&second).enumerate())
        .map(|(k, (a, b))| a + 0.3 * b + 0.5 + 0.01 * k as f64)
        .collect();
    let got = identify_frequency(&mixed, RATE).unwrap();
    assert!((got / f - 1.0).abs() < 1e-3, "{got}");
    assert_eq!(identify_frequency(&[1.0; 5], RATE), None);
    assert_eq!(identify_frequency(&vec![0.0; 100], RATE), None);
}

#[test]
fn the_fft_is_the_direct_dft() {
    let n = 64;
    let signal: Vec<f64> = (0..n).map(|k| ((k * k) % 7) as f64 - 3.0).collect();
    let (mut re, mut im) = (signal.clone(), vec![0.0; n]);
    fft(&mut re, &mut im);
    for j in 0..n {
        let (mut dr, mut di) = (0.0, 0.0);
        for (k, x) in signal.iter().enumerate() {
            let a = -2.0 * PI * (j * k) as f64 / n as f64;
            dr += x * a.cos();
            di += x * a.sin();
        }
        assert!(
            (re[j] - dr).abs() < 1e-9 && (im[j] - di).abs() < 1e-9,
            "bin {j}"
        );
    }
}

fn written() -> RateGroup {
    RateGroup {
        rate: 4.0,
        times: vec![0.0, 0.25, 0.5],
        columns: vec![SensorColumn {
            member: None,
            name: "mid".into(),
            kind: "displacement".into(),
            unit: "m".into(),
            at: 10.0,
            values: vec![0.0, 1.0 / 3.0, -2.5e-7],
        }],
    }
}

#[test]
fn the_writers_files_read_back_as_they_were_written() {
    let group = written();
    let csv = String::from_utf8(group.csv().unwrap()).unwrap();
    let read = parse(&csv, "t.csv").unwrap();
    assert_eq!(read.names, ["mid"]);
    assert_eq!(read.times, group.times);
    assert_eq!(read.columns[0], group.columns[0].values);
    // Our .npy reader (the one eval uses for predictions) on the writer's bytes.
    let array = super::super::npy::parse(&group.npy().unwrap()).unwrap();
    assert_eq!(array.shape, [3, 2]);
    assert_eq!(array.values, [0.0, 0.0, 0.25, 1.0 / 3.0, 0.5, -2.5e-7]);
}

#[test]
fn bad_csvs_and_mismatched_predictions_are_refused_at_their_line() {
    let e = |text: &str| parse(text, "p.csv").unwrap_err().to_string();
    assert!(e("").contains("p.csv:1"));
    assert!(e("time[s]\n0\n").contains("p.csv:1"));
    assert!(e("time[s],a,a\n").contains("\"a\""));
    let bad = e("time[s],mid\n0,1\n0.25,x\n");
    assert!(bad.contains("p.csv:3") && bad.contains("\"x\""), "{bad}");
    assert!(e("time[s],mid\n0,1,2\n").contains("p.csv:2: 3 values"));
    let truth = parse(&String::from_utf8(written().csv().unwrap()).unwrap(), "t").unwrap();
    let other = parse("time[s],far\n0,0\n0.25,0\n0.5,0\n", "p.csv").unwrap();
    assert!(
        score(&truth, &other, "p.csv")
            .unwrap_err()
            .to_string()
            .contains("\"far\"")
    );
    let shifted = parse("time[s],mid\n0,0\n0.3,0\n0.5,0\n", "p.csv").unwrap();
    let e = score(&truth, &shifted, "p.csv").unwrap_err().to_string();
    assert!(e.contains("p.csv:3") && e.contains("0.25"), "{e}");
    // Missing cells are missing values, not errors.
    let gaps = parse("time[s],mid\n0,\n0.25,nan\n0.5,1\n", "p.csv").unwrap();
    assert!(gaps.columns[0][0].is_nan() && gaps.columns[0][1].is_nan());
}
