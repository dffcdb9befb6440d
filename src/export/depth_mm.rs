//! Planar depth in metres (float32 EXR) → 16-bit grey PNG in whole millimetres, the encoding
//! nerfstudio (`depth_unit_scale_factor` 0.001), KITTI-style loaders and OpenCV's
//! `IMREAD_ANYDEPTH` read.
//!
//! Each value is rounded to the nearest millimetre (halves away from zero); 0 stays 0 (no
//! surface). A surface closer than 0.5 mm would round to 0 and read as "no surface", so it is
//! written as 1 and counted (`raised`); one beyond 65.535 m is written as 65535 and counted
//! (`saturated`). A value that is negative or not finite is not depth, and is an error.

use crate::dataset::{Dataset, View};
use crate::output::{SCALAR_CHANNELS, grey16_png};
use anyhow::{Result, bail};
use rayon::prelude::*;

/// Pixels that did not fit whole millimetres in 16 bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Clamped {
    /// Beyond 65.535 m: written 65535.
    pub(super) saturated: u64,
    /// Closer than 0.5 mm: written 1.
    pub(super) raised: u64,
}

/// Millimetres of each depth value in metres; `file` names the source in errors.
pub(super) fn to_mm(depth: &[f32], width: usize, file: &str) -> Result<(Vec<u16>, Clamped)> {
    let mut clamped = Clamped::default();
    let mut out = Vec::with_capacity(depth.len());
    for (i, &d) in depth.iter().enumerate() {
        if !d.is_finite() || d < 0.0 {
            bail!(
                "{file}: pixel (row {}, column {}) holds {d}, which is not a depth in metres",
                i / width,
                i % width
            );
        }
        let mm = (f64::from(d) * 1000.0).round();
        out.push(if d == 0.0 {
            0
        } else if mm > f64::from(u16::MAX) {
            clamped.saturated += 1;
            u16::MAX
        } else if mm < 1.0 {
            clamped.raised += 1;
            1
        } else {
            mm as u16
        });
    }
    Ok((out, clamped))
}

/// The view's depth EXR as a millimetre PNG.
pub(super) fn png_of(dataset: &Dataset, view: &View) -> Result<(Vec<u8>, Clamped)> {
    let layer = dataset.layer(view, "depth.exr", &SCALAR_CHANNELS.sets())?;
    let file = view.file("depth.exr").unwrap_or_default();
    let (mm, clamped) = to_mm(&layer.channels[0], layer.width, file)?;
    Ok((
        grey16_png(layer.width as u32, layer.height as u32, &mm),
        clamped,
    ))
}

/// `png_of` for each view, on every core, in the views' order.
pub(super) fn pngs_of(dataset: &Dataset, views: &[&View]) -> Result<Vec<(Vec<u8>, Clamped)>> {
    views.par_iter().map(|v| png_of(dataset, v)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn millimetres_round_to_nearest_and_clamp_at_both_ends() {
        let depth = [0.0, 1.2344, 1.2346, 0.0004, 0.0006, 65.5344, 65.5356, 100.0];
        let (mm, clamped) = to_mm(&depth, 4, "d.exr").unwrap();
        assert_eq!(mm, [0, 1234, 1235, 1, 1, 65534, 65535, 65535]);
        assert_eq!(
            clamped,
            Clamped {
                saturated: 2,
                raised: 1
            }
        );
        let err = to_mm(&[1.0, f32::NAN], 2, "d.exr").unwrap_err();
        assert!(format!("{err}").contains("d.exr: pixel (row 0, column 1) holds NaN"));
        assert!(to_mm(&[-1.0], 1, "d.exr").is_err());
    }
}
