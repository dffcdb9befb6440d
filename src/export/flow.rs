//! `--format flow`: every view's optical flow (`flow.exr` with `flow_valid.png`) in the two
//! formats flow training code reads, mirroring the dataset's `samples/` folder:
//!
//! ```text
//! DIR/samples/NNNN/{stem}.flow_kitti.png   KITTI: 16-bit RGB, R = U·64 + 2¹⁵, G = V·64 + 2¹⁵,
//!                                          B = 1 where the flow is valid, (0, 0, 0) elsewhere
//! DIR/samples/NNNN/{stem}.flo              Middlebury: "PIEH", int32 width, int32 height, then
//!                                          float32 (U, V) per pixel, row-major, little-endian;
//!                                          1e10 in both where the flow is unknown
//! DIR/samples/NNNN/{stem}.rest_rgb.png     the first image of the pair (hard link), when the
//! DIR/samples/NNNN/{stem}.rgb.png          dataset has it, and the second
//! ```
//!
//! The flow is the dataset's: on the unloaded image (`rest_rgb`), the pixel's surface point's
//! move to the loaded image (`rgb`), in pixels, U right, V down. KITTI's 16 bits hold
//! −512 ≤ U, V < 512 in steps of 1/64 px (values are rounded to the nearest step); a vector
//! beyond that is written invalid and counted, never clamped: a clamped vector would be a wrong
//! label that trains as a right one. The `.flo` file keeps every float32 exactly.

use super::{Job, needed};
use crate::dataset::{Dataset, View};
use crate::output::{FLOW_CHANNELS, rgb16_png};
use anyhow::{Result, bail};
use rayon::prelude::*;
use serde_json::{Value, json};

/// Views converted together: memory stays bounded, every core works.
const BATCH: usize = 64;

/// KITTI's steps per pixel and the code of zero flow.
const KITTI_SCALE: f64 = 64.0;
const KITTI_ZERO: f64 = 32768.0;

/// Middlebury's tag (the float 202021.25, "PIEH" in little-endian bytes) and its value for an
/// unknown component (its readers take anything above 1e9 as unknown).
const FLO_TAG: f32 = 202_021.25;
const FLO_UNKNOWN: f32 = 1e10;

/// One view's flow as read from the dataset: vectors and validity, row-major.
struct ViewFlow {
    width: usize,
    height: usize,
    u: Vec<f32>,
    v: Vec<f32>,
    valid: Vec<bool>,
}

/// One view's files in both formats, and its valid vectors KITTI cannot hold.
struct Encoded {
    kitti: Vec<u8>,
    flo: Vec<u8>,
    out_of_range: u64,
}

pub(super) fn write(job: &mut Job) -> Result<Value> {
    let dataset = job.dataset;
    let views: Vec<&View> = dataset.views().collect();
    let mut out_of_range = 0;
    for batch in views.chunks(BATCH) {
        for view in batch {
            needed(view, "flow.exr", "flow")?;
            needed(view, "flow_valid.png", "flow")?;
        }
        let encoded: Vec<Encoded> = batch
            .par_iter()
            .map(|view| encode(&read(dataset, view)?))
            .collect::<Result<_>>()?;
        for (view, files) in batch.iter().zip(encoded) {
            let folder = job.out.join(view.folder());
            let stem = &view.stem;
            job.placer
                .write(&folder.join(format!("{stem}.flow_kitti.png")), &files.kitti)?;
            job.placer
                .write(&folder.join(format!("{stem}.flo")), &files.flo)?;
            for kind in ["rest_rgb.png", "rgb.png"] {
                if let Some(image) = view.file(kind) {
                    job.placer
                        .place(dataset, image, &folder.join(format!("{stem}.{kind}")))?;
                }
            }
            out_of_range += files.out_of_range;
            job.summary.views += 1;
        }
    }
    job.summary.flow_out_of_range = out_of_range;
    Ok(json!({
        "layout": "samples/{sample/1000:04}/{sample:06}_{view:02}[a{copy}].{flow_kitti.png,flo,rest_rgb.png,rgb.png}",
        "flow": {
            "meaning": "on rest_rgb (the unloaded image), where the pixel's surface point lands in rgb (the loaded one), minus the pixel centre; pixels, U right, V down",
            "kitti": "16-bit RGB PNG: R = round(U*64) + 32768, G = round(V*64) + 32768, B = 1 valid / 0 invalid (then R = G = 0)",
            "flo": "Middlebury .flo: float 202021.25, int32 width, int32 height, float32 (U, V) row-major, little-endian; 1e10 = unknown",
            "kitti_out_of_range_pixels": out_of_range,
            "kitti_out_of_range_rule": "a valid vector with a component outside [-512, 511.984375] px is written invalid in the KITTI PNG (the .flo keeps it)",
        },
    }))
}

/// The view's flow and validity, refusing a value that is not a finite number of pixels.
fn read(dataset: &Dataset, view: &View) -> Result<ViewFlow> {
    let layer = dataset.layer(view, "flow.exr", &FLOW_CHANNELS.sets())?;
    let valid = dataset.grey(view, "flow_valid.png")?;
    let file = view.file("flow.exr").unwrap_or_default();
    let mut channels = layer.channels.into_iter();
    let (u, v) = (
        channels.next().unwrap_or_default(),
        channels.next().unwrap_or_default(),
    );
    if let Some(i) = (0..u.len()).find(|&i| !u[i].is_finite() || !v[i].is_finite()) {
        bail!(
            "{file}: pixel (row {}, column {}) holds ({}, {}), which is not a flow in pixels",
            i / layer.width,
            i % layer.width,
            u[i],
            v[i]
        );
    }
    Ok(ViewFlow {
        width: layer.width,
        height: layer.height,
        u,
        v,
        valid: valid.values.iter().map(|&m| m != 0).collect(),
    })
}

/// Both files of one view.
fn encode(flow: &ViewFlow) -> Result<Encoded> {
    let mut out_of_range = 0;
    let kitti: Vec<[u16; 3]> = (0..flow.u.len())
        .map(|i| {
            let pixel = kitti_pixel(flow.u[i], flow.v[i], flow.valid[i]);
            out_of_range += u64::from(flow.valid[i] && pixel[2] == 0);
            pixel
        })
        .collect();
    Ok(Encoded {
        kitti: rgb16_png(flow.width as u32, flow.height as u32, &kitti),
        flo: flo(flow)?,
        out_of_range,
    })
}

/// One KITTI pixel: the two components in 1/64 px around 2¹⁵ and 1, or (0, 0, 0) where the
/// flow is invalid or a component does not fit 16 bits.
fn kitti_pixel(u: f32, v: f32, valid: bool) -> [u16; 3] {
    let code = |x: f32| {
        let q = (f64::from(x) * KITTI_SCALE + KITTI_ZERO).round();
        (0.0..=f64::from(u16::MAX)).contains(&q).then_some(q as u16)
    };
    match (valid, code(u), code(v)) {
        (true, Some(r), Some(g)) => [r, g, 1],
        _ => [0, 0, 0],
    }
}

/// The Middlebury `.flo` bytes of a view.
fn flo(flow: &ViewFlow) -> Result<Vec<u8>> {
    let side =
        |n: usize| i32::try_from(n).map_err(|_| anyhow::anyhow!("{n} pixels: beyond .flo's int32"));
    let mut out = Vec::with_capacity(12 + 8 * flow.u.len());
    out.extend_from_slice(&FLO_TAG.to_le_bytes());
    out.extend_from_slice(&side(flow.width)?.to_le_bytes());
    out.extend_from_slice(&side(flow.height)?.to_le_bytes());
    for i in 0..flow.u.len() {
        let (u, v) = match flow.valid[i] {
            true => (flow.u[i], flow.v[i]),
            false => (FLO_UNKNOWN, FLO_UNKNOWN),
        };
        out.extend_from_slice(&u.to_le_bytes());
        out.extend_from_slice(&v.to_le_bytes());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kitti_codes_are_sixty_fourths_of_a_pixel_around_two_to_the_fifteenth() {
        // Hand-computed: −1.5·64 + 32768 = 32672, 0.25·64 + 32768 = 32784.
        assert_eq!(kitti_pixel(-1.5, 0.25, true), [32672, 32784, 1]);
        assert_eq!(kitti_pixel(0.0, 0.0, true), [32768, 32768, 1]);
        // Rounded to the nearest 1/64 px: 0.01·64 = 0.64 → 1.
        assert_eq!(kitti_pixel(0.01, -0.007, true), [32769, 32768, 1]);
        // The ends of the range: −512 → 0, 511.984375 → 65535; one step beyond is invalid.
        assert_eq!(kitti_pixel(-512.0, 32767.0 / 64.0, true), [0, 65535, 1]);
        assert_eq!(kitti_pixel(-512.02, 0.0, true), [0, 0, 0]);
        assert_eq!(kitti_pixel(3.0, 512.0, true), [0, 0, 0]);
        // Invalid flow is (0, 0, 0) whatever the vector, as KITTI's devkit writes it.
        assert_eq!(kitti_pixel(2.0, 1.0, false), [0, 0, 0]);
    }

    #[test]
    fn flo_files_carry_the_tag_size_and_interleaved_vectors() {
        let flow = ViewFlow {
            width: 3,
            height: 1,
            u: vec![1.5, -2.25, 7.0],
            v: vec![0.5, 3.0, 8.0],
            valid: vec![true, true, false],
        };
        let bytes = flo(&flow).unwrap();
        assert_eq!(&bytes[..4], b"PIEH");
        let word = |at: usize| <[u8; 4]>::try_from(&bytes[at..at + 4]).unwrap();
        assert_eq!(i32::from_le_bytes(word(4)), 3);
        assert_eq!(i32::from_le_bytes(word(8)), 1);
        let floats: Vec<f32> = (12..bytes.len())
            .step_by(4)
            .map(|at| f32::from_le_bytes(word(at)))
            .collect();
        assert_eq!(floats, [1.5, 0.5, -2.25, 3.0, 1e10, 1e10]);
    }

    #[test]
    fn out_of_range_vectors_are_counted_and_written_invalid() {
        let flow = ViewFlow {
            width: 2,
            height: 2,
            u: vec![600.0, 1.0, -700.0, 0.0],
            v: vec![0.0, 1.0, 0.0, 0.0],
            valid: vec![true, true, false, true],
        };
        let encoded = encode(&flow).unwrap();
        // Only the valid vector beyond 512 px counts; the invalid one was invalid anyway.
        assert_eq!(encoded.out_of_range, 1);
    }
}
