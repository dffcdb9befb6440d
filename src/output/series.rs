//! Time series files: what a sample's virtual sensors recorded, as CSV (for people, pandas and
//! spreadsheets) and as NumPy `.npy` float64 (for training code), one pair of files per
//! sampling rate.
//!
//! Owns: the file names, the column labels and the bytes. Must not touch: mechanics or
//! recipes; it receives finished series as plain numbers. Layout (`docs/sensors.md`):
//! `{sample:06}.sensors_{rate}hz.csv` and `.npy`, where `{rate}` is the rate in Hz as Rust
//! writes the shortest exact decimal with `p` for the point (`200`, `62p5`), so no dot comes
//! before the kind; the first column is the time in seconds, then one column per sensor at
//! that rate, in the recipe's order. A CSV's header labels each column
//! `{name}:{kind}[{unit}]@{x}m` (`@member{m}+{x}m` on a frame); the `.npy` has shape `[samples, sensors + 1]` in the same
//! column order (its labels are the CSV's).

use super::encode::npy;
use anyhow::{Result, bail};
use std::fmt::Write;

/// The label of the time column.
pub const TIME_LABEL: &str = "time[s]";

/// One sensor's column.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorColumn {
    /// The sensor's name (letters, digits, `_` and `-`).
    pub name: String,
    /// What it measures (`displacement`, `strain_bottom`, …).
    pub kind: String,
    /// The values' SI unit.
    pub unit: String,
    /// On a frame: the member it is fixed to.
    pub member: Option<usize>,
    /// Position along its beam's axis, or along its member, m.
    pub at: f64,
    /// One value per sample time.
    pub values: Vec<f64>,
}

impl SensorColumn {
    /// `{name}:{kind}[{unit}]@{x}m`, e.g. `mid:displacement[m]@10m`; on a frame's member
    /// `{name}:{kind}[{unit}]@member{m}+{x}m`, e.g. `deck:acceleration[m/s^2]@member7+0.5m`.
    pub fn label(&self) -> String {
        let (name, kind, unit, at) = (&self.name, &self.kind, &self.unit, self.at);
        match self.member {
            Some(m) => format!("{name}:{kind}[{unit}]@member{m}+{at}m"),
            None => format!("{name}:{kind}[{unit}]@{at}m"),
        }
    }
}

/// The sensors sampled at one rate.
#[derive(Clone, Debug, PartialEq)]
pub struct RateGroup {
    /// Sampling rate, Hz.
    pub rate: f64,
    /// Sample times, s.
    pub times: Vec<f64>,
    /// The sensors, each with one value per time.
    pub columns: Vec<SensorColumn>,
}

impl RateGroup {
    /// The file kind of this group with `extension`: `sensors_200hz.csv`, `sensors_62p5hz.npy`.
    pub fn kind(&self, extension: &str) -> String {
        let rate = self.rate.to_string().replace('.', "p");
        format!("sensors_{rate}hz.{extension}")
    }

    /// Every value is finite and every column as long as the times; otherwise the sensor and
    /// the time where it is not.
    fn check(&self) -> Result<()> {
        if let Some(t) = self.times.iter().find(|t| !t.is_finite()) {
            bail!("sensor time {t} s at {} Hz is not finite", self.rate);
        }
        for column in &self.columns {
            if column.values.len() != self.times.len() {
                bail!(
                    "sensor {:?} has {} values for {} times",
                    column.name,
                    column.values.len(),
                    self.times.len()
                );
            }
            if let Some(k) = column.values.iter().position(|v| !v.is_finite()) {
                bail!(
                    "sensor {:?} recorded {} at t = {} s",
                    column.name,
                    column.values[k],
                    self.times[k]
                );
            }
        }
        Ok(())
    }

    /// The CSV: a header of labels, then one line per time. Numbers are Rust's shortest
    /// decimal that reads back to the same f64, so the CSV and the `.npy` hold equal values.
    pub fn csv(&self) -> Result<Vec<u8>> {
        self.check()?;
        let mut text = String::from(TIME_LABEL);
        for column in &self.columns {
            text.push(',');
            text.push_str(&column.label());
        }
        text.push('\n');
        for (k, t) in self.times.iter().enumerate() {
            let _ = write!(text, "{t}");
            for column in &self.columns {
                let _ = write!(text, ",{}", column.values[k]);
            }
            text.push('\n');
        }
        Ok(text.into_bytes())
    }

    /// The `.npy`: float64 little-endian, shape `[times, sensors + 1]`, row-major, the time in
    /// column 0.
    pub fn npy(&self) -> Result<Vec<u8>> {
        self.check()?;
        let width = self.columns.len() + 1;
        let mut data = Vec::with_capacity(self.times.len() * width * 8);
        for (k, t) in self.times.iter().enumerate() {
            data.extend_from_slice(&t.to_le_bytes());
            for column in &self.columns {
                data.extend_from_slice(&column.values[k].to_le_bytes());
            }
        }
        Ok(npy("<f8", &[self.times.len(), width], &data))
    }
}

/// Every file of a sample's sensors, as (kind, bytes): a CSV and a `.npy` per rate group.
/// Two groups of the same rate are an error (their files would share a name).
pub fn series_files(groups: &[RateGroup]) -> Result<Vec<(String, Vec<u8>)>> {
    let mut files = Vec::with_capacity(2 * groups.len());
    for (i, group) in groups.iter().enumerate() {
        if groups[..i].iter().any(|g| g.rate == group.rate) {
            bail!("two groups of sensors at {} Hz", group.rate);
        }
        files.push((group.kind("csv"), group.csv()?));
        files.push((group.kind("npy"), group.npy()?));
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn group() -> RateGroup {
        RateGroup {
            rate: 62.5,
            times: vec![0.0, 0.016, 0.032],
            columns: vec![
                SensorColumn {
                    member: None,
                    name: "mid".into(),
                    kind: "displacement".into(),
                    unit: "m".into(),
                    at: 10.0,
                    values: vec![0.0, 1.25e-3, -0.1],
                },
                SensorColumn {
                    member: None,
                    name: "gauge-2".into(),
                    kind: "strain_bottom".into(),
                    unit: "m/m".into(),
                    at: 2.5,
                    values: vec![1e-6, 2.0, 0.3],
                },
            ],
        }
    }

    #[test]
    fn the_csv_names_each_column_and_holds_exact_values() {
        let text = String::from_utf8(group().csv().unwrap()).unwrap();
        assert_eq!(
            text,
            "time[s],mid:displacement[m]@10m,gauge-2:strain_bottom[m/m]@2.5m\n\
             0,0,0.000001\n0.016,0.00125,2\n0.032,-0.1,0.3\n"
        );
        // Shortest round-trip decimals: every value reads back to the same bits.
        let third = 1.0 / 3.0;
        let mut g = group();
        g.columns[0].values[1] = third;
        let text = String::from_utf8(g.csv().unwrap()).unwrap();
        let cell: f64 = text
            .lines()
            .nth(2)
            .unwrap()
            .split(',')
            .nth(1)
            .unwrap()
            .parse()
            .unwrap();
        assert_eq!(cell.to_bits(), third.to_bits());
    }

    #[test]
    fn names_carry_the_rate_without_a_dot() {
        let mut g = group();
        assert_eq!(g.kind("csv"), "sensors_62p5hz.csv");
        g.rate = 200.0;
        assert_eq!(g.kind("npy"), "sensors_200hz.npy");
        let files = series_files(&[group(), g.clone()]).unwrap();
        let kinds: Vec<&str> = files.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(
            kinds,
            [
                "sensors_62p5hz.csv",
                "sensors_62p5hz.npy",
                "sensors_200hz.csv",
                "sensors_200hz.npy"
            ]
        );
        let e = series_files(&[g.clone(), g]).unwrap_err().to_string();
        assert!(e.contains("200 Hz"), "{e}");
    }

    #[test]
    fn a_value_that_is_not_finite_is_refused_with_its_sensor_and_time() {
        let mut g = group();
        g.columns[1].values[2] = f64::NAN;
        for e in [g.csv().unwrap_err(), g.npy().unwrap_err()] {
            let e = e.to_string();
            assert!(
                e.contains("gauge-2") && e.contains("NaN") && e.contains("0.032"),
                "{e}"
            );
        }
        g.columns[1].values.pop();
        assert!(
            g.csv()
                .unwrap_err()
                .to_string()
                .contains("2 values for 3 times")
        );
    }
}
