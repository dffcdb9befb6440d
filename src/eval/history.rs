//! Histories: predicted sensor time series (a tracker's displacement history of a point, an
//! identified acceleration) against the virtual sensors a dataset recorded
//! (`{sample:06}.sensors_{rate}hz.csv`, `docs/sensors.md`).
//!
//! Owns: reading a history CSV (bounded, errors at file:line), matching predicted columns to
//! the truth's sensors by name, and the metrics of one column: RMSE, the largest error, the
//! error of the peak, the RMSE normalised by the truth's range, and the error of the first
//! natural frequency identified from each series by the same method ([`identify_frequency`]).
//!
//! A prediction mirrors the truth file's name (`0000/000003.sensors_200hz.csv`); its first
//! column is the time, the others are named as the truth's sensors (`mid`, or the truth's full
//! label `mid:displacement[m]@10m`), in any order, any subset. Its times must be the truth's.
//! An empty cell, `nan` or ±inf is "no prediction" at that instant and is left out.

use super::Counts;
use super::outcome::{Outcome, Tallied};
use super::predictions::mirrored;
use super::stats;
use crate::dataset::files::{Bound, open_regular, read_bounded};
use crate::dataset::{Dataset, Sample, kind_of};
use anyhow::{Result, bail};
use serde::Serialize;
use std::f64::consts::PI;
use std::path::Path;

/// The largest history file read: 1 GiB (10⁷ rows of a dozen sensors).
pub(super) const HISTORY_FILE: Bound = Bound {
    what: "a history CSV",
    bytes: 1 << 30,
};

/// A CSV of series: labels, then one row per instant.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Table {
    /// Each sensor column's name (its label up to the first `:`).
    pub(super) names: Vec<String>,
    /// The time column, s.
    pub(super) times: Vec<f64>,
    /// One vector per sensor column.
    pub(super) columns: Vec<Vec<f64>>,
}

/// Parses a history CSV called `name` in messages: a header whose first label is the time,
/// then rows of as many numbers. Missing values (empty, `nan`, ±inf) become NaN.
pub(super) fn parse(text: &str, name: &str) -> Result<Table> {
    let mut lines = text.lines().enumerate();
    let Some((_, header)) = lines.next() else {
        bail!("{name}:1: empty file (a header `time[s],<sensor>,…` is needed)");
    };
    let labels: Vec<&str> = header.split(',').map(str::trim).collect();
    if labels.len() < 2 {
        bail!("{name}:1: a header of the time and at least one sensor is needed, got {header:?}");
    }
    let names: Vec<String> = labels[1..]
        .iter()
        .map(|l| l.split(':').next().unwrap_or(l).to_string())
        .collect();
    if let Some((k, n)) = names
        .iter()
        .enumerate()
        .find(|(k, n)| n.is_empty() || names[..*k].contains(n))
    {
        bail!("{name}:1: column {} is named {n:?} (empty or twice)", k + 2);
    }
    let mut times = Vec::new();
    let mut columns = vec![Vec::new(); names.len()];
    for (k, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != labels.len() {
            bail!(
                "{name}:{}: {} values, the header has {}",
                k + 1,
                cells.len(),
                labels.len()
            );
        }
        let value = |cell: &str| -> Result<f64> {
            let cell = cell.trim();
            if cell.is_empty() {
                return Ok(f64::NAN);
            }
            let v: f64 = cell
                .parse()
                .map_err(|_| anyhow::anyhow!("{name}:{}: {cell:?} is not a number", k + 1))?;
            Ok(if v.is_finite() { v } else { f64::NAN })
        };
        let t = value(cells[0])?;
        if t.is_nan() {
            bail!(
                "{name}:{}: the time {:?} is not a finite number",
                k + 1,
                cells[0]
            );
        }
        times.push(t);
        for (column, cell) in columns.iter_mut().zip(&cells[1..]) {
            column.push(value(cell)?);
        }
    }
    Ok(Table {
        names,
        times,
        columns,
    })
}

/// Reads and parses the history CSV at `path` (a file the user named: a regular file, at most
/// [`HISTORY_FILE`]).
pub(super) fn read(path: &Path) -> Result<Table> {
    let name = path.display().to_string();
    let bytes = read_bounded(open_regular(path)?, &name, HISTORY_FILE)?;
    let text = String::from_utf8(bytes).map_err(|_| anyhow::anyhow!("{name}: not UTF-8 text"))?;
    parse(&text, &name)
}

/// The truth's history files of `sample` (kinds `sensors_{rate}hz.csv`), each with the
/// outcome of its prediction, named `{sample:06}.{kind}`.
pub(super) fn score_sample(
    dataset: &Dataset,
    samples: &Path,
    sample: &Sample,
) -> Result<Vec<(String, Outcome<Vec<ColumnScore>>)>> {
    let mut out = Vec::new();
    for relative in &sample.files {
        let Some(kind) = kind_of(relative).filter(|k| is_history(k)) else {
            continue;
        };
        let name = format!("{:06}.{kind}", sample.index);
        let path = mirrored(samples, relative);
        if !path.exists() {
            out.push((name, Outcome::Missing));
            continue;
        }
        let bytes = dataset.read(relative, HISTORY_FILE)?;
        let text =
            String::from_utf8(bytes).map_err(|_| anyhow::anyhow!("{relative}: not UTF-8 text"))?;
        let truth = parse(&text, relative)?;
        let scores = score(&truth, &read(&path)?, &path.display().to_string())?;
        out.push((name, Outcome::Scored(scores)));
    }
    Ok(out)
}

/// Whether a per-sample file kind is a sensor history (`sensors_200hz.csv`).
fn is_history(kind: &str) -> bool {
    kind.starts_with("sensors_") && kind.ends_with("hz.csv")
}

/// Histories in the report: counts, per-sensor means over the files scored, each file's scores.
#[derive(Clone, Debug, Serialize)]
pub struct HistoryReport {
    /// Files scored (`images`), missing, and instants (`pixels`) scored and left out.
    pub counts: Counts,
    /// Per sensor name, the means over the files that predict it.
    pub sensors: Vec<SensorSummary>,
    /// Each scored file's scores, in dataset order.
    pub files: Vec<HistoryResult>,
}

/// The means of one sensor's scores over the files predicting it (units: the sensor's).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SensorSummary {
    /// The sensor's name.
    pub sensor: String,
    /// Files it was scored in.
    pub files: usize,
    /// Mean RMSE.
    pub rmse: f64,
    /// Mean largest error.
    pub max_error: f64,
    /// Mean |peak error|.
    pub peak_error: f64,
    /// Mean normalised RMSE (over the files where the truth is not constant).
    pub nrmse: Option<f64>,
    /// Mean |error of the identified first frequency|, Hz (over the files where both were
    /// identified).
    pub frequency_error: Option<f64>,
}

/// One file's scores.
#[derive(Clone, Debug, Serialize)]
pub struct HistoryResult {
    /// `{sample:06}.sensors_{rate}hz.csv`.
    pub file: String,
    /// Each predicted column's scores.
    pub sensors: Vec<ColumnScore>,
}

/// The report of histories, None when none was predicted.
pub(super) fn report(
    outcomes: &[(String, Outcome<Vec<ColumnScore>>)],
    counts: Counts,
) -> Option<HistoryReport> {
    if !outcomes.iter().any(|(_, o)| o.predicted()) {
        return None;
    }
    let files: Vec<HistoryResult> = outcomes
        .iter()
        .filter_map(|(file, o)| {
            o.scored().map(|s| HistoryResult {
                file: file.clone(),
                sensors: s.clone(),
            })
        })
        .collect();
    let mut names: Vec<&str> = Vec::new();
    for c in files.iter().flat_map(|f| &f.sensors) {
        if !names.contains(&c.sensor.as_str()) {
            names.push(&c.sensor);
        }
    }
    let sensors = names
        .into_iter()
        .map(|name| {
            let scores: Vec<&ColumnScore> = (files.iter().flat_map(|f| &f.sensors))
                .filter(|c| c.sensor == name && c.scored > 0)
                .collect();
            summary(name, &scores)
        })
        .collect();
    Some(HistoryReport {
        counts,
        sensors,
        files,
    })
}

/// The means of `scores` (one sensor's, over files), summed in dataset order.
fn summary(sensor: &str, scores: &[&ColumnScore]) -> SensorSummary {
    let all = |f: fn(&ColumnScore) -> f64| stats::mean(scores.iter().map(|c| f(c)));
    let some = |f: fn(&ColumnScore) -> Option<f64>| stats::mean(scores.iter().filter_map(|c| f(c)));
    SensorSummary {
        sensor: sensor.to_string(),
        files: scores.len(),
        rmse: all(|c| c.rmse).unwrap_or(0.0),
        max_error: all(|c| c.max_error).unwrap_or(0.0),
        peak_error: all(|c| c.peak_error.abs()).unwrap_or(0.0),
        nrmse: some(|c| c.nrmse),
        frequency_error: some(|c| c.frequency_error.map(f64::abs)),
    }
}

impl HistoryReport {
    /// The block of the text report: one line per sensor.
    pub(super) fn text(&self) -> String {
        let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4e}"));
        let mut out = format!(
            "histories: {} files, {} instants (per sensor, mean over the files predicting it)\n  sensor           RMSE         max error    |peak error| NRMSE        |Δf₁| Hz\n",
            self.counts.images, self.counts.pixels
        );
        for s in &self.sensors {
            out += &format!(
                "  {:<16} {:<12} {:<12} {:<12} {:<12} {}\n",
                s.sensor,
                f(Some(s.rmse)),
                f(Some(s.max_error)),
                f(Some(s.peak_error)),
                f(s.nrmse),
                f(s.frequency_error)
            );
        }
        out
    }
}

/// The scores of one sensor's predicted history.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ColumnScore {
    /// The sensor's name.
    pub sensor: String,
    /// Instants scored (predicted and finite).
    pub scored: u64,
    /// Instants left out (no prediction).
    pub excluded: u64,
    /// √mean (p − t)², in the sensor's unit.
    pub rmse: f64,
    /// max |p − t|.
    pub max_error: f64,
    /// max |p| − max |t|: the error of the peak amplitude (signed).
    pub peak_error: f64,
    /// RMSE / (max t − min t); None when the truth is constant.
    pub nrmse: Option<f64>,
    /// The first natural frequency identified from the truth, Hz (None: no peak).
    pub frequency_truth: Option<f64>,
    /// The same identified from the prediction, Hz.
    pub frequency_predicted: Option<f64>,
    /// Their difference, predicted − truth, Hz.
    pub frequency_error: Option<f64>,
}

impl Tallied for Vec<ColumnScore> {
    fn has_metrics(&self) -> bool {
        self.iter().any(|c| c.scored > 0)
    }
    fn pixels(&self) -> (u64, u64) {
        let sum = |f: fn(&ColumnScore) -> u64| self.iter().map(f).sum();
        (sum(|c| c.scored), sum(|c| c.excluded))
    }
}

/// Scores each column of `predicted` against the truth's column of the same name. `name`
/// (the prediction's file) is for messages.
pub(super) fn score(truth: &Table, predicted: &Table, name: &str) -> Result<Vec<ColumnScore>> {
    check_times(truth, predicted, name)?;
    predicted
        .names
        .iter()
        .zip(&predicted.columns)
        .map(|(sensor, values)| {
            let Some(k) = truth.names.iter().position(|n| n == sensor) else {
                bail!(
                    "{name}: column {sensor:?} is not a sensor of the truth (its sensors: {})",
                    truth.names.join(", ")
                );
            };
            Ok(score_column(
                sensor,
                &truth.times,
                &truth.columns[k],
                values,
            ))
        })
        .collect()
}

/// The prediction's times are the truth's: as many, each within a millionth of a sample
/// interval (the CSV's decimals round-trip, so equal times are equal numbers).
fn check_times(truth: &Table, predicted: &Table, name: &str) -> Result<()> {
    if truth.times.len() != predicted.times.len() {
        bail!(
            "{name}: {} rows, the truth has {} (one per instant of the sensor's rate)",
            predicted.times.len(),
            truth.times.len()
        );
    }
    let interval = match truth.times.as_slice() {
        [a, b, ..] => b - a,
        _ => 1.0,
    };
    let off = truth
        .times
        .iter()
        .zip(&predicted.times)
        .enumerate()
        .find(|(_, (t, p))| (*t - *p).abs() > 1e-6 * interval);
    if let Some((k, (t, p))) = off {
        bail!("{name}:{}: time {p} s, the truth's instant is {t} s", k + 2);
    }
    Ok(())
}

/// The metrics of one predicted series against its truth.
fn score_column(sensor: &str, times: &[f64], truth: &[f64], predicted: &[f64]) -> ColumnScore {
    let pairs: Vec<(f64, f64)> = truth
        .iter()
        .zip(predicted)
        .filter(|(_, p)| p.is_finite())
        .map(|(&t, &p)| (t, p))
        .collect();
    let n = pairs.len();
    let amplitude = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0_f64, |m, x| m.max(x.abs()));
    let (lo, hi) = truth
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
            (lo.min(t), hi.max(t))
        });
    let rmse = if n == 0 {
        0.0
    } else {
        (pairs.iter().map(|(t, p)| (p - t).powi(2)).sum::<f64>() / n as f64).sqrt()
    };
    let rate = match times {
        [a, b, ..] => 1.0 / (b - a),
        _ => 0.0,
    };
    // A frequency needs the whole series: a prediction with gaps is not identified.
    let frequency_truth = identify_frequency(truth, rate);
    let frequency_predicted = (n == predicted.len())
        .then(|| identify_frequency(predicted, rate))
        .flatten();
    ColumnScore {
        sensor: sensor.to_string(),
        scored: n as u64,
        excluded: (predicted.len() - n) as u64,
        rmse,
        max_error: amplitude(&mut pairs.iter().map(|(t, p)| p - t)),
        peak_error: amplitude(&mut pairs.iter().map(|p| p.1))
            - amplitude(&mut pairs.iter().map(|p| p.0)),
        nrmse: (hi > lo).then(|| rmse / (hi - lo)),
        frequency_truth,
        frequency_predicted,
        frequency_error: frequency_truth.zip(frequency_predicted).map(|(t, p)| p - t),
    }
}

/// How much the spectrum is zero-padded: the DFT's bins are 1/8 of the record's resolution
/// 1/T, and the interpolation below refines within a bin.
const PADDING: usize = 8;

/// The first natural frequency of `values` sampled at `rate` Hz, identified as the frequency
/// of the largest peak of the amplitude spectrum above 2/T (T the record's length: below that
/// a record cannot show two cycles, and a crossing vehicle's quasi-static bump lives there).
///
/// Method: remove the least-squares line (offset and drift), apply a Hann window, zero-pad to
/// at least 8× the length (a power of two), FFT, take the largest bin above 2/T, and refine it
/// by a parabola through the logarithms of the three magnitudes around it (Gaussian
/// interpolation: exact for a Gaussian peak, and within a few thousandths of a bin for the
/// Hann window's main lobe). None when there are fewer than 8 values or no interior peak.
pub fn identify_frequency(values: &[f64], rate: f64) -> Option<f64> {
    let n = values.len();
    if n < 8 || !(rate > 0.0) || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let size = (PADDING * n).next_power_of_two();
    let mut re = detrended_windowed(values);
    re.resize(size, 0.0);
    let mut im = vec![0.0; size];
    fft(&mut re, &mut im);
    let magnitude: Vec<f64> = (0..=size / 2).map(|k| re[k].hypot(im[k])).collect();
    let bin = rate / size as f64;
    let first = ((2.0 * rate / n as f64) / bin).ceil() as usize;
    let last = magnitude.len() - 2;
    if first < 1 || first > last {
        return None;
    }
    let k = (first..=last).max_by(|&a, &b| magnitude[a].total_cmp(&magnitude[b]))?;
    let [a, b, c] = [k - 1, k, k + 1].map(|i| magnitude[i].max(f64::MIN_POSITIVE).ln());
    let curvature = a - 2.0 * b + c;
    if !(curvature < 0.0) {
        return None;
    }
    let offset = 0.5 * (a - c) / curvature;
    Some((k as f64 + offset.clamp(-0.5, 0.5)) * bin)
}

/// `values` minus their least-squares line, times a Hann window.
fn detrended_windowed(values: &[f64]) -> Vec<f64> {
    let n = values.len() as f64;
    let mean_k = (n - 1.0) / 2.0;
    let mean_v = values.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (k, v) in values.iter().enumerate() {
        let dk = k as f64 - mean_k;
        sxy += dk * (v - mean_v);
        sxx += dk * dk;
    }
    let slope = sxy / sxx;
    values
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let window = 0.5 - 0.5 * (2.0 * PI * k as f64 / (n - 1.0)).cos();
            (v - mean_v - slope * (k as f64 - mean_k)) * window
        })
        .collect()
}

/// In-place radix-2 decimation-in-time FFT of a power-of-two length.
fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let angle = -2.0 * PI / len as f64;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                // Each twiddle from its angle (not by repeated multiplication, which drifts).
                let (s, c) = (angle * k as f64).sin_cos();
                let (a, b) = (start + k, start + k + len / 2);
                let (tr, ti) = (re[b] * c - im[b] * s, re[b] * s + im[b] * c);
                (re[b], im[b]) = (re[a] - tr, im[a] - ti);
                (re[a], im[a]) = (re[a] + tr, im[a] + ti);
            }
        }
        len <<= 1;
    }
}

#[cfg(test)]
mod tests;
