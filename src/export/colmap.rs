//! `--format colmap`: one COLMAP text model per sample, the known-pose input of COLMAP's
//! `point_triangulator` and of Gaussian-splatting loaders:
//!
//! ```text
//! DIR/{sample:06}/images/{stem}.png          the RGB (hard link)
//! DIR/{sample:06}/sparse/0/cameras.txt       one camera per image: PINHOLE fx fy cx cy, or
//!                                            OPENCV fx fy cx cy k1 k2 p1 p2 (FULL_OPENCV with
//!                                            k3 and k4 = k5 = k6 = 0 when k3 ≠ 0)
//! DIR/{sample:06}/sparse/0/images.txt        IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then
//!                                            its 2-D points: X Y POINT3D_ID …
//! DIR/{sample:06}/sparse/0/points3D.txt      POINT3D_ID X Y Z R G B ERROR TRACK[] as
//!                                            (IMAGE_ID, POINT2D_IDX), from the sample's
//!                                            `points.ply` (none without the `points` output)
//! ```
//!
//! Which points, which frames see them, where and in what colour: `tracks`. A 2-D point is the
//! exact projection of its 3-D point, so every ERROR (COLMAP's mean reprojection error) is 0.
//! POINT2D_IDX counts from 0 in the image's list, POINT3D_ID from 1.
//!
//! The pose is world → camera in OpenCV axes (COLMAP's), R as a Hamilton unit quaternion
//! with QW ≥ 0, t as written in `w2c_opencv`. COLMAP puts the centre of the top-left pixel at
//! (0.5, 0.5), as we do, so K's principal point is written unchanged. Numbers are written in
//! the shortest form that reads back to the same f64.

use super::tracks::{self, Point3d};
use super::{Job, frames, intrinsics, needed};
use crate::dataset::{Camera, View};
use anyhow::{Result, bail};
use serde_json::{Value, json};
use std::fmt::Write as _;

pub(super) fn write(job: &mut Job) -> Result<Value> {
    let (dataset, out, options) = (job.dataset, job.out, job.options);
    for (sample, views) in frames(dataset, options)? {
        let sample_points = sample.file("points.ply");
        let sample = sample.index;
        let scene = out.join(format!("{sample:06}"));
        let mut cameras = String::from(
            "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n",
        );
        let mut images = String::from(
            "# Image list with two lines of data per image:\n#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n#   POINTS2D[] as (X, Y, POINT3D_ID)\n",
        );
        let points = match sample_points {
            Some(ply) => tracks::observed(dataset, ply, &views)?,
            None => Vec::new(),
        };
        let (points2d, tracks) = index_observations(&points, views.len());
        writeln!(cameras, "# Number of cameras: {}", views.len())?;
        writeln!(
            images,
            "# Number of images: {}, mean observations per image: {}",
            views.len(),
            mean(points2d.iter().map(Vec::len), views.len())
        )?;
        for ((id, view), points2d) in (1..).zip(&views).zip(&points2d) {
            let camera = dataset.camera(view)?;
            let name = format!("{}.png", view.stem);
            let rgb = needed(view, "rgb.png", "colmap")?;
            job.placer
                .place(dataset, rgb, &scene.join("images").join(&name))?;
            writeln!(cameras, "{id} {}", camera_line(&camera, view)?)?;
            let [qw, qx, qy, qz] = quaternion(rotation(&camera, view)?);
            let t = camera.w2c_opencv;
            writeln!(
                images,
                "{id} {qw} {qx} {qy} {qz} {} {} {} {id} {name}",
                t[0][3], t[1][3], t[2][3]
            )?;
            writeln!(images, "{}", points2d.join(" "))?;
            job.summary.views += 1;
        }
        let sparse = scene.join("sparse/0");
        job.placer
            .write(&sparse.join("cameras.txt"), cameras.as_bytes())?;
        job.placer
            .write(&sparse.join("images.txt"), images.as_bytes())?;
        job.placer.write(
            &sparse.join("points3D.txt"),
            points_text(&points, &tracks)?.as_bytes(),
        )?;
    }
    Ok(json!({
        "layout": "{sample:06}/images/{stem}.png and {sample:06}/sparse/0/{cameras,images,points3D}.txt",
        "points3D": {
            "source": "the sample's points.ply (the `points` output), its first points up to the cap; none without it",
            "max_points": tracks::MAX_POINTS,
            "track": "the frames where the point projects inside the image and the depth of its pixel is the point's own",
            "colour": "mean RGB of the pixels the point falls in, over its track",
            "error": 0,
        },
    }))
}

/// Each image's POINTS2D (`X Y POINT3D_ID`, in point order) and each point's TRACK
/// (`IMAGE_ID POINT2D_IDX`), image ids counting from 1 in frame order.
fn index_observations(points: &[Point3d], frames: usize) -> (Vec<Vec<String>>, Vec<Vec<String>>) {
    let mut points2d: Vec<Vec<String>> = vec![Vec::new(); frames];
    let tracks = (1..)
        .zip(points)
        .map(|(id, point)| {
            let track = point.track.iter().map(|o| {
                let list = &mut points2d[o.frame];
                list.push(format!("{} {} {id}", o.xy[0], o.xy[1]));
                format!("{} {}", o.frame + 1, list.len() - 1)
            });
            track.collect()
        })
        .collect();
    (points2d, tracks)
}

/// points3D.txt of `points` with their `tracks`.
fn points_text(points: &[Point3d], tracks: &[Vec<String>]) -> Result<String> {
    let mut text = String::from(
        "# 3D point list with one line of data per point:\n#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n",
    );
    writeln!(
        text,
        "# Number of points: {}, mean track length: {}",
        points.len(),
        mean(points.iter().map(|p| p.track.len()), points.len())
    )?;
    for ((id, point), track) in (1..).zip(points).zip(tracks) {
        let ([x, y, z], [r, g, b]) = (point.xyz, point.rgb);
        writeln!(text, "{id} {x} {y} {z} {r} {g} {b} 0 {}", track.join(" "))?;
    }
    Ok(text)
}

/// The mean of `counts` over `n` (0 for none), as COLMAP's headers give it.
fn mean(counts: impl Iterator<Item = usize>, n: usize) -> f64 {
    counts.sum::<usize>() as f64 / n.max(1) as f64
}

/// `MODEL WIDTH HEIGHT PARAMS…` of a view's camera.
fn camera_line(camera: &Camera, view: &View) -> Result<String> {
    let [fx, fy, cx, cy] = intrinsics(&camera.k, view)?;
    let (w, h) = (camera.width, camera.height);
    Ok(match camera.distortion {
        None => format!("PINHOLE {w} {h} {fx} {fy} {cx} {cy}"),
        Some(d) if d.k3 == 0.0 => format!(
            "OPENCV {w} {h} {fx} {fy} {cx} {cy} {} {} {} {}",
            d.k1, d.k2, d.p1, d.p2
        ),
        // FULL_OPENCV's radial factor is (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ +
        // k6 r⁶): with k4 = k5 = k6 = 0 it is Brown–Conrady's with k3.
        Some(d) => format!(
            "FULL_OPENCV {w} {h} {fx} {fy} {cx} {cy} {} {} {} {} {} 0 0 0",
            d.k1, d.k2, d.p1, d.p2, d.k3
        ),
    })
}

/// The rotation block of w2c, checked to be a rotation (orthonormal, determinant +1).
fn rotation(camera: &Camera, view: &View) -> Result<[[f64; 3]; 3]> {
    let m = camera.w2c_opencv;
    let r = [
        [m[0][0], m[0][1], m[0][2]],
        [m[1][0], m[1][1], m[1][2]],
        [m[2][0], m[2][1], m[2][2]],
    ];
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    if (det - 1.0).abs() > 1e-6 {
        bail!(
            "view {}: w2c_opencv's rotation has determinant {det}, not 1",
            view.stem
        );
    }
    Ok(r)
}

/// The Hamilton unit quaternion [w, x, y, z] of rotation matrix `r`, with w ≥ 0 (q and −q are
/// the same rotation; one sign keeps the files deterministic). Shepperd's method: divide by
/// the largest of the four squared components, never by a small one.
fn quaternion(r: [[f64; 3]; 3]) -> [f64; 4] {
    let trace = r[0][0] + r[1][1] + r[2][2];
    let q = if trace > 0.0 {
        let s = (trace + 1.0).sqrt() * 2.0;
        [
            0.25 * s,
            (r[2][1] - r[1][2]) / s,
            (r[0][2] - r[2][0]) / s,
            (r[1][0] - r[0][1]) / s,
        ]
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt() * 2.0;
        [
            (r[2][1] - r[1][2]) / s,
            0.25 * s,
            (r[0][1] + r[1][0]) / s,
            (r[0][2] + r[2][0]) / s,
        ]
    } else if r[1][1] > r[2][2] {
        let s = (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt() * 2.0;
        [
            (r[0][2] - r[2][0]) / s,
            (r[0][1] + r[1][0]) / s,
            0.25 * s,
            (r[1][2] + r[2][1]) / s,
        ]
    } else {
        let s = (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt() * 2.0;
        [
            (r[1][0] - r[0][1]) / s,
            (r[0][2] + r[2][0]) / s,
            (r[1][2] + r[2][1]) / s,
            0.25 * s,
        ]
    };
    let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    let sign = if q[0] < 0.0 { -1.0 } else { 1.0 };
    q.map(|c| sign * c / norm)
}

#[cfg(test)]
mod tests {
    use super::quaternion;

    /// Rotation by `angle` about unit `axis` (Rodrigues), an independent construction.
    fn rodrigues(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
        let [x, y, z] = axis;
        let (s, c) = angle.sin_cos();
        let t = 1.0 - c;
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    }

    #[test]
    fn quaternions_are_half_angle_and_axis_in_every_branch() {
        let n = (1.0f64 / 3.0).sqrt();
        for (axis, angle) in [
            ([0.0, 0.0, 1.0], 0.3),
            ([1.0, 0.0, 0.0], 3.0),  // trace < 0, x largest
            ([0.0, 1.0, 0.0], 3.1),  // trace < 0, y largest
            ([0.0, 0.0, 1.0], 3.13), // trace < 0, z largest
            ([n, n, n], 2.5),
            ([n, -n, n], 3.0),
        ] {
            let q = quaternion(rodrigues(axis, angle));
            let half = angle / 2.0;
            let expected = [
                half.cos(),
                axis[0] * half.sin(),
                axis[1] * half.sin(),
                axis[2] * half.sin(),
            ];
            for (a, b) in q.iter().zip(expected) {
                assert!(
                    (a - b).abs() < 1e-12,
                    "{axis:?} {angle}: {q:?} vs {expected:?}"
                );
            }
        }
    }
}
