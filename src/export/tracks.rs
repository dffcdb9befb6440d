//! The 3-D points of a COLMAP model: the sample's `points.ply` (points on the true loaded
//! surface, with the normals of their triangles) read back, each projected into every frame,
//! and observed where the frame's depth says it is seen.
//!
//! A point is observed in a frame when it lies in front of the camera, its normal turns
//! towards the camera (shmgen's shapes are wound outward), it projects (through the camera's
//! lens, as COLMAP's OPENCV models do) inside the image, and the depth of the pixel it falls in
//! is where the pixel's centre ray meets the point's tangent plane, within `DEPTH_AGREEMENT`
//! of it: a nearer surface hiding the point, or another face at the pixel's centre, is off that
//! plane. Comparing with the plane rather than with the point's own depth keeps the test tight
//! on a surface seen at a slant, whose depth changes much across one pixel. Its 2-D point is
//! the projection, to full precision; its colour the mean of the RGB of those pixels over its
//! track, rounded (as COLMAP colours a point from the images that see it). Points no frame
//! sees are left out: a COLMAP point is an observed one. At most `MAX_POINTS` points are used,
//! the file's first ones: the file's points are independent uniform draws, so a prefix is as
//! uniform as the whole.

use crate::dataset::{Camera, Dataset, View, files::SAMPLE_FILE};
use crate::output::SCALAR_CHANNELS;
use anyhow::{Context, Result, bail};
use rayon::prelude::*;

/// The most points a model gets (the default `points` count of a dataset): 100 000 points
/// seen by 40 frames are 4 million observations, 100 MB of text.
pub(super) const MAX_POINTS: usize = 100_000;

/// One observation: the frame (index into the frames given), where the point projects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Observation {
    pub(super) frame: usize,
    pub(super) xy: [f64; 2],
    pub(super) rgb: [u8; 3],
}

/// A point seen by at least one frame.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Point3d {
    pub(super) xyz: [f64; 3],
    pub(super) rgb: [u8; 3],
    /// In frame order.
    pub(super) track: Vec<Observation>,
}

/// The most the depth of a pixel may differ, as a share of it, from where the pixel's centre
/// ray meets the tangent plane of a point seen there: float32 depth is good to 10⁻⁷, and a
/// curved surface leaves its tangent plane by (footprint)²·curvature / 2 within a pixel,
/// micrometres for a bent member; a hiding surface or another face is off by far more.
const DEPTH_AGREEMENT: f64 = 1e-3;

/// A point of `points.ply`: where it lies and the unit normal of its triangle, world axes.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PlyPoint {
    xyz: [f64; 3],
    normal: [f64; 3],
}

/// The observed points of `points_ply` (a file of the dataset) in `frames`.
pub(super) fn observed(
    dataset: &Dataset,
    points_ply: &str,
    frames: &[&View],
) -> Result<Vec<Point3d>> {
    let bytes = dataset.read(points_ply, SAMPLE_FILE)?;
    let mut points = ply_points(&bytes).with_context(|| points_ply.to_string())?;
    points.truncate(MAX_POINTS);
    // Per frame, the observation of each point it sees; memory is one frame's images at a
    // time per core, plus the observations.
    let seen: Vec<Vec<Option<Observation>>> = frames
        .par_iter()
        .enumerate()
        .map(|(frame, view)| observe(dataset, view, frame, &points))
        .collect::<Result<_>>()?;
    let mut observed = Vec::new();
    for (i, point) in points.iter().enumerate() {
        let track: Vec<Observation> = seen.iter().filter_map(|f| f[i]).collect();
        if !track.is_empty() {
            observed.push(Point3d {
                xyz: point.xyz,
                rgb: mean_colour(&track),
                track,
            });
        }
    }
    Ok(observed)
}

/// What frame `frame` (`view`) sees of `points`.
fn observe(
    dataset: &Dataset,
    view: &View,
    frame: usize,
    points: &[PlyPoint],
) -> Result<Vec<Option<Observation>>> {
    let camera = dataset.camera(view)?;
    let depth = dataset
        .layer(view, "depth.exr", &SCALAR_CHANNELS.sets())?
        .channels[0]
        .clone();
    let rgb = dataset.rgb(view, "rgb.png")?;
    let width = camera.width as usize;
    Ok(points
        .iter()
        .map(|point| {
            let (xy, in_camera) = project(&camera, point.xyz)?;
            let (col, row) = (xy[0].floor(), xy[1].floor());
            let pixel = row as usize * width + col as usize;
            let d = f64::from(depth[pixel]);
            let on_plane = plane_depth(&camera, point, in_camera, [col + 0.5, row + 0.5])?;
            (d > 0.0 && (d - on_plane).abs() <= DEPTH_AGREEMENT * on_plane).then(|| Observation {
                frame,
                xy,
                rgb: rgb[pixel],
            })
        })
        .collect())
}

/// The depth at which the centre ray of the pixel centred at `centre` meets the tangent plane
/// of `point` (at `in_camera`, camera axes); None when the point's normal turns away from the
/// camera, the ray runs along the plane, or the lens folds there.
fn plane_depth(
    camera: &Camera,
    point: &PlyPoint,
    in_camera: [f64; 3],
    centre: [f64; 2],
) -> Option<f64> {
    let m = camera.w2c_opencv;
    let n: [f64; 3] = std::array::from_fn(|r| (0..3).map(|c| m[r][c] * point.normal[c]).sum());
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    // The camera is at the origin of its axes: facing means n · (0 − p) > 0.
    if !(dot(n, in_camera) < 0.0) {
        return None;
    }
    let k = camera.k;
    let (xd, yd) = (
        (centre[0] - k[0][2]) / k[0][0],
        (centre[1] - k[1][2]) / k[1][1],
    );
    let (x, y) = match camera.distortion {
        Some(d) => d.undistort(xd, yd)?,
        None => (xd, yd),
    };
    let along = dot(n, [x, y, 1.0]);
    // The ray (x, y, 1)·t meets the plane n · (q − p) = 0 at t = n · p / n · (x, y, 1): its depth.
    (along.abs() > 1e-9).then(|| dot(n, in_camera) / along)
}

/// Where world point `p` appears in the image (pixel coordinates, the top-left pixel's centre
/// at (0.5, 0.5), through the lens) and where it lies in camera axes; None when it is behind
/// the camera or outside the image.
pub(super) fn project(camera: &Camera, p: [f64; 3]) -> Option<([f64; 2], [f64; 3])> {
    let m = camera.w2c_opencv;
    let c: [f64; 3] =
        std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3]);
    if !(c[2] > 0.0) {
        return None;
    }
    let (x, y) = (c[0] / c[2], c[1] / c[2]);
    let (x, y) = camera.distortion.map_or((x, y), |d| d.distort(x, y));
    let k = camera.k;
    let xy = [k[0][0] * x + k[0][2], k[1][1] * y + k[1][2]];
    let inside = (0.0..f64::from(camera.width)).contains(&xy[0])
        && (0.0..f64::from(camera.height)).contains(&xy[1]);
    inside.then_some((xy, c))
}

/// The mean colour of a track's pixels, rounded to the nearest level.
fn mean_colour(track: &[Observation]) -> [u8; 3] {
    std::array::from_fn(|c| {
        let sum: u64 = track.iter().map(|o| u64::from(o.rgb[c])).sum();
        ((sum as f64 / track.len() as f64).round()) as u8
    })
}

/// The points of a binary little-endian PLY whose one element is `vertex` with `double` or
/// `float` x, y, z and nx, ny, nz among scalar properties (shmgen's `points.ply`, or one
/// written by other software in that form).
fn ply_points(bytes: &[u8]) -> Result<Vec<PlyPoint>> {
    const END: &[u8] = b"end_header\n";
    const NAMES: [&str; 6] = ["x", "y", "z", "nx", "ny", "nz"];
    let end = bytes
        .windows(END.len())
        .take(64 << 10)
        .position(|w| w == END)
        .context("no PLY header (no end_header in the first 64 KiB)")?
        + END.len();
    let header = std::str::from_utf8(&bytes[..end]).context("the PLY header is not text")?;
    let mut lines = header.lines();
    if lines.next() != Some("ply") || lines.next() != Some("format binary_little_endian 1.0") {
        bail!("not a binary little-endian PLY");
    }
    let (mut count, mut stride, mut offsets) = (None, 0, [None; 6]);
    for line in lines {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words[..] {
            ["element", "vertex", n] if count.is_none() => {
                count = Some(n.parse::<usize>().context("element vertex: not a count")?);
            }
            ["element", other, ..] => bail!("element {other}: only one of vertices is read"),
            ["property", kind, name] => {
                let size = scalar_size(kind).with_context(|| format!("property {kind} {name}"))?;
                if let Some(at) = NAMES.iter().position(|&a| a == name) {
                    offsets[at] = Some((stride, kind));
                }
                stride += size;
            }
            ["property", ..] => bail!("{line}: only scalar properties are read"),
            _ => {}
        }
    }
    let count = count.context("no element vertex")?;
    let Some(offsets) = offsets.into_iter().collect::<Option<Vec<_>>>() else {
        bail!("the vertices lack one of x, y, z, nx, ny, nz");
    };
    let body = &bytes[end..];
    if body.len() / stride < count {
        bail!(
            "{count} vertices of {stride} bytes announced, {} bytes follow",
            body.len()
        );
    }
    let read = |record: &[u8], (at, kind): (usize, &str)| match kind {
        "double" | "float64" => {
            f64::from_le_bytes(record[at..at + 8].try_into().unwrap_or_default())
        }
        _ => f64::from(f32::from_le_bytes(
            record[at..at + 4].try_into().unwrap_or_default(),
        )),
    };
    let mut points = Vec::with_capacity(count);
    for record in body.chunks_exact(stride).take(count) {
        let v: [f64; 6] = std::array::from_fn(|i| read(record, offsets[i]));
        if !v.iter().all(|c| c.is_finite()) {
            bail!("a vertex {v:?} (x, y, z, nx, ny, nz): not finite");
        }
        points.push(PlyPoint {
            xyz: [v[0], v[1], v[2]],
            normal: [v[3], v[4], v[5]],
        });
    }
    Ok(points)
}

/// Bytes of a PLY scalar type.
fn scalar_size(kind: &str) -> Result<usize> {
    Ok(match kind {
        "char" | "uchar" | "int8" | "uint8" => 1,
        "short" | "ushort" | "int16" | "uint16" => 2,
        "int" | "uint" | "int32" | "uint32" | "float" | "float32" => 4,
        "double" | "float64" => 8,
        other => bail!("unknown PLY type {other}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ply(header_properties: &str, records: &[u8]) -> Vec<u8> {
        let mut bytes = format!(
            "ply\nformat binary_little_endian 1.0\ncomment c\nelement vertex 2\n{header_properties}end_header\n"
        )
        .into_bytes();
        bytes.extend_from_slice(records);
        bytes
    }

    #[test]
    fn points_are_read_by_name_whatever_the_other_properties() {
        let mut records = Vec::new();
        for (x, y, z) in [(1.5f32, -2.0f32, 3.25f64), (0.0, 7.0, -1e6)] {
            records.push(200u8);
            records.extend_from_slice(&y.to_le_bytes());
            records.extend_from_slice(&x.to_le_bytes());
            records.extend_from_slice(&z.to_le_bytes());
            for n in [0.0f32, 0.6, 0.8] {
                records.extend_from_slice(&n.to_le_bytes());
            }
        }
        let bytes = ply(
            "property uchar red\nproperty float y\nproperty float x\nproperty double z\n\
             property float nx\nproperty float ny\nproperty float nz\n",
            &records,
        );
        let points = ply_points(&bytes).unwrap();
        let xyz: Vec<[f64; 3]> = points.iter().map(|p| p.xyz).collect();
        assert_eq!(xyz, [[1.5, -2.0, 3.25], [0.0, 7.0, -1e6]]);
        assert_eq!(
            points[1].normal,
            [0.0, f64::from(0.6f32), f64::from(0.8f32)]
        );
        let short = &bytes[..bytes.len() - 1];
        let err = format!("{:#}", ply_points(short).unwrap_err());
        assert!(err.contains("2 vertices of 29 bytes announced"), "{err}");
        let faces = ply("property float x\nelement face 1\n", &[]);
        assert!(format!("{:#}", ply_points(&faces).unwrap_err()).contains("element face"));
        let bare = ply(
            "property float x\nproperty float y\nproperty float z\n",
            &[0; 24],
        );
        assert!(format!("{:#}", ply_points(&bare).unwrap_err()).contains("lack one of"));
    }

    #[test]
    fn a_pixel_centre_ray_meets_the_tangent_plane_at_its_depth() {
        // Camera at the origin looking down +z (w2c = identity), f = 100, 100 × 100 pixels.
        let camera = Camera {
            width: 100,
            height: 100,
            k: [[100.0, 0.0, 50.0], [0.0, 100.0, 50.0], [0.0, 0.0, 1.0]],
            w2c_opencv: IDENTITY,
            c2w_opencv: IDENTITY,
            c2w_opengl: IDENTITY,
            distortion: None,
        };
        // The plane z = 2 + x (normal (1, 0, −1)/√2 faces the camera) through (0.01, 0, 2.01).
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let point = PlyPoint {
            xyz: [0.01, 0.0, 2.01],
            normal: [s, 0.0, -s],
        };
        let (xy, in_camera) = project(&camera, point.xyz).unwrap();
        assert!((xy[0] - (50.0 + 100.0 * 0.01 / 2.01)).abs() < 1e-12);
        // The ray through pixel centre (60.5, 50.5) is (0.105, 0.005, 1)·t, meeting
        // z = 2 + x at t = 2 / (1 − 0.105).
        let depth = plane_depth(&camera, &point, in_camera, [60.5, 50.5]).unwrap();
        assert!((depth - 2.0 / 0.895).abs() < 1e-12, "{depth}");
        // Turned away from the camera: never seen.
        let away = PlyPoint {
            normal: [-s, 0.0, s],
            ..point
        };
        assert_eq!(plane_depth(&camera, &away, in_camera, [60.5, 50.5]), None);
        // Behind the camera or outside the image: no projection.
        assert!(project(&camera, [0.0, 0.0, -1.0]).is_none());
        assert!(project(&camera, [2.0, 0.0, 1.0]).is_none());
    }

    const IDENTITY: [[f64; 4]; 4] = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];

    #[test]
    fn colours_are_the_rounded_mean_of_the_track() {
        let at = |rgb| Observation {
            frame: 0,
            xy: [0.0; 2],
            rgb,
        };
        assert_eq!(
            mean_colour(&[at([10, 0, 255]), at([11, 1, 254]), at([11, 1, 254])]),
            [11, 1, 254]
        );
    }
}
