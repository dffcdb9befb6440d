//! A view's camera as its record (`camera` in the view's JSON) states it: size, K, the
//! poses in both conventions and the Brown–Conrady coefficients of a distorted lens.

use crate::cameras::Distortion;
use anyhow::{Context, Result, bail};
use serde_json::Value;

/// One view's camera; pixel (i, j) has its centre at (j + 0.5, i + 0.5).
#[derive(Clone, Debug)]
pub struct Camera {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Intrinsics, pixels.
    pub k: [[f64; 3]; 3],
    /// World → camera, OpenCV axes (x right, y down, z forward), row-major.
    pub w2c_opencv: [[f64; 4]; 4],
    /// Camera → world, OpenCV axes.
    pub c2w_opencv: [[f64; 4]; 4],
    /// Camera → world, OpenGL axes (y up, looking along −z): nerfstudio's `transform_matrix`.
    pub c2w_opengl: [[f64; 4]; 4],
    /// The lens's distortion; None for a pinhole camera.
    pub distortion: Option<Distortion>,
}

fn matrix<const R: usize, const C: usize>(camera: &Value, name: &str) -> Result<[[f64; C]; R]> {
    let rows = camera
        .get(name)
        .and_then(Value::as_array)
        .filter(|r| r.len() == R)
        .with_context(|| format!("camera.{name} is not a {R}×{C} matrix"))?;
    let mut out = [[0.0; C]; R];
    for (i, row) in rows.iter().enumerate() {
        let row = row
            .as_array()
            .filter(|r| r.len() == C)
            .with_context(|| format!("camera.{name} is not a {R}×{C} matrix"))?;
        for (j, v) in row.iter().enumerate() {
            out[i][j] = v
                .as_f64()
                .filter(|v| v.is_finite())
                .with_context(|| format!("camera.{name}[{i}][{j}] is not a finite number"))?;
        }
    }
    Ok(out)
}

impl Camera {
    /// The camera of a view record.
    pub fn from_record(record: &Value) -> Result<Camera> {
        let camera = record.get("camera").context("no camera")?;
        let size = |name: &str| {
            camera
                .get(name)
                .and_then(Value::as_u64)
                .and_then(|v| u32::try_from(v).ok())
                .filter(|&v| v > 0)
                .with_context(|| format!("camera.{name} is not a positive whole number"))
        };
        let distortion = match camera.get("model").and_then(Value::as_str) {
            Some("pinhole") => None,
            Some("opencv") => {
                let d = camera
                    .get("distortion")
                    .context("camera.distortion missing")?;
                let c = |name: &str| {
                    d.get(name)
                        .and_then(Value::as_f64)
                        .filter(|v| v.is_finite())
                        .with_context(|| format!("camera.distortion.{name} is not a number"))
                };
                Some(Distortion {
                    k1: c("k1")?,
                    k2: c("k2")?,
                    p1: c("p1")?,
                    p2: c("p2")?,
                    k3: c("k3")?,
                })
            }
            other => bail!("camera.model {other:?} is neither \"pinhole\" nor \"opencv\""),
        };
        Ok(Camera {
            width: size("width")?,
            height: size("height")?,
            k: matrix(camera, "K")?,
            w2c_opencv: matrix(camera, "w2c_opencv")?,
            c2w_opencv: matrix(camera, "c2w_opencv")?,
            c2w_opengl: matrix(camera, "c2w_opengl")?,
            distortion,
        })
    }
}
