//! Image-space geometric warps (the 3DGEN paper's zoom and rotation, used only when a
//! recipe asks for `mode: "image"`): a 2D similarity applied to RGB (bilinear) and to label
//! layers (nearest), with the intrinsics and camera rotation that make it exact.
//!
//! Coordinates are continuous pixels, x to the right and y down, pixel (i, j) centred at
//! (j + ½, i + ½). The similarity maps a point x of the input to
//!
//! ```text
//! x′ = s·R(θ)·(x − c) + c + t,   R(θ) = [[cos θ, −sin θ], [sin θ, cos θ]],
//! ```
//!
//! so with y pointing down a positive θ turns the picture **clockwise on screen**
//! (torchvision's `F.rotate(angle = α°)`, documented as counter-clockwise, is θ = −α·π/180).
//!
//! Exactness for a pinhole camera u = f·X/Z + p (fx = fy = f): substituting,
//! x′ = (s·f)·R(θ)·(X/Z, Y/Z) + [s·R(θ)(p − c) + c + t], and R(θ)·(X/Z, Y/Z) is the
//! normalised image of the same point in the camera turned about its optical axis,
//! X′_cam = R_z(θ)·X_cam with R_z(θ) = [[R(θ), 0], [0, 1]], which keeps every Z. Hence
//! f′ = s·f, p′ = s·R(θ)(p − c) + c + t, planar depth values unchanged, and the new pose
//! w2c′ = R_z(θ)·w2c (c2w′ = c2w·R_z(θ)ᵀ): the camera's own x axis turns towards its −y
//! axis by θ. A zoom or shift alone is exact with fx ≠ fy too; a rotation needs fx = fy. With
//! lens distortion the same K′ holds (the principal point is also the distortion centre, and
//! moves with the picture); the lens, seen from the turned camera, has its tangential
//! coefficients turned by θ, which the caller applies (the pipeline's moved camera).
//!
//! Sampling: each output pixel centre is mapped back into the input. A pixel whose source
//! point lies outside [0, W) × [0, H) is invalid: black in RGB, 0 in every label layer, 0 in
//! the validity mask. Inside, RGB is interpolated bilinearly between the four nearest pixel
//! centres (the edge pixel repeated within half a pixel of the border); labels take the
//! pixel that contains the source point, so no label value is ever invented.

use super::draw::{Range, check_probability, check_range, happens};
use super::rgb_pixels;
use crate::seeds::Stream;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A 2D similarity of pixel coordinates: x′ = zoom·R(angle)·(x − centre) + centre + shift.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Similarity {
    /// Magnification s, dimensionless, > 0 (> 1 zooms in).
    pub zoom: f64,
    /// In-plane rotation θ, radians; positive turns the picture clockwise on screen.
    pub angle: f64,
    /// Fixed point c of zoom and rotation, input pixels (continuous, centres at +½).
    pub centre: [f64; 2],
    /// Translation t after zoom and rotation, output pixels.
    pub shift: [f64; 2],
}

/// Pinhole intrinsics in pixels, pixel centres at +½.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Pinhole {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels from the left edge.
    pub cx: f64,
    /// Principal point y, pixels from the top edge.
    pub cy: f64,
}

impl Pinhole {
    /// Square pixels: fx = fy = `focal`, principal point (`cx`, `cy`).
    pub fn square(focal: f64, cx: f64, cy: f64) -> Self {
        Pinhole {
            fx: focal,
            fy: focal,
            cx,
            cy,
        }
    }

    /// The pixel a camera-frame point (OpenCV axes, Z > 0) projects to.
    pub fn project(&self, point: [f64; 3]) -> [f64; 2] {
        let [x, y, z] = point;
        [self.fx * x / z + self.cx, self.fy * y / z + self.cy]
    }
}

impl Similarity {
    /// The identity.
    pub const IDENTITY: Similarity = Similarity {
        zoom: 1.0,
        angle: 0.0,
        centre: [0.0, 0.0],
        shift: [0.0, 0.0],
    };

    /// Zoom and rotation about the centre of a `width` × `height` image, then `shift`.
    pub fn about_centre(
        width: usize,
        height: usize,
        zoom: f64,
        angle: f64,
        shift: [f64; 2],
    ) -> Self {
        Similarity {
            zoom,
            angle,
            centre: [0.5 * width as f64, 0.5 * height as f64],
            shift,
        }
    }

    /// Crop the window at (`left`, `top`) of `crop` = [width, height] pixels and resize it to
    /// `out` = [width, height]; the two scale factors must agree (a similarity has one).
    pub fn crop_resize(
        left: f64,
        top: f64,
        crop: [f64; 2],
        out: [usize; 2],
    ) -> Result<Self, String> {
        let (sx, sy) = (out[0] as f64 / crop[0], out[1] as f64 / crop[1]);
        if !(sx.is_finite() && sx > 0.0) || (sx - sy).abs() > 1e-9 * sx {
            return Err(format!(
                "crop {crop:?} resized to {out:?} scales x by {sx} and y by {sy}: not a similarity"
            ));
        }
        Ok(Similarity {
            zoom: sx,
            angle: 0.0,
            centre: [left, top],
            shift: [-left, -top],
        })
    }

    /// The linear part A = s·R(θ) and offset b of x′ = A·x + b.
    pub fn matrix(&self) -> ([[f64; 2]; 2], [f64; 2]) {
        let (sin, cos) = libm::sincos(self.angle);
        let a = [
            [self.zoom * cos, -self.zoom * sin],
            [self.zoom * sin, self.zoom * cos],
        ];
        let [c0, c1] = self.centre;
        let b = [
            c0 + self.shift[0] - (a[0][0] * c0 + a[0][1] * c1),
            c1 + self.shift[1] - (a[1][0] * c0 + a[1][1] * c1),
        ];
        (a, b)
    }

    /// Where input point `p` lands.
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let (a, b) = self.matrix();
        [
            a[0][0] * p[0] + a[0][1] * p[1] + b[0],
            a[1][0] * p[0] + a[1][1] * p[1] + b[1],
        ]
    }

    /// The input point that lands on output point `q`.
    pub fn invert(&self, q: [f64; 2]) -> [f64; 2] {
        Inverse::of(self).apply(q)
    }

    /// This similarity followed by `next`, about the origin.
    pub fn then(&self, next: &Similarity) -> Similarity {
        Similarity {
            zoom: self.zoom * next.zoom,
            angle: self.angle + next.angle,
            centre: [0.0, 0.0],
            shift: next.apply(self.apply([0.0, 0.0])),
        }
    }

    /// The intrinsics K′ under which the warped image is the exact pinhole image of the
    /// camera turned by [`Similarity::camera_rotation`]: f′ = s·f, p′ = s·R(θ)(p − c) + c + t.
    /// A rotation needs fx = fy (to 1 part in 10⁹).
    pub fn intrinsics(&self, k: &Pinhole) -> Result<Pinhole, String> {
        let (sin, _) = libm::sincos(self.angle);
        if sin.abs() > 1e-12 && (k.fx - k.fy).abs() > 1e-9 * k.fx.abs() {
            return Err(format!(
                "an in-plane rotation of {} rad needs square pixels, but fx = {} and fy = {}",
                self.angle, k.fx, k.fy
            ));
        }
        let [cx, cy] = self.apply([k.cx, k.cy]);
        Ok(Pinhole {
            fx: self.zoom * k.fx,
            fy: self.zoom * k.fy,
            cx,
            cy,
        })
    }

    /// R_z(θ), row-major: the new camera frame is X′_cam = R_z(θ)·X_cam, so
    /// w2c′ = R_z(θ)·w2c and c2w′ = c2w·R_z(θ)ᵀ (OpenCV axes: x right, y down, z forward).
    pub fn camera_rotation(&self) -> [[f64; 3]; 3] {
        let (sin, cos) = libm::sincos(self.angle);
        [[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]]
    }
}

/// The inverse map, output point → input point, and the input's extent.
struct Inverse {
    a: [[f64; 2]; 2],
    b: [f64; 2],
}

impl Inverse {
    fn of(sim: &Similarity) -> Self {
        // (s·R(θ))⁻¹ = R(−θ)/s.
        let (a, b) = sim.matrix();
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let inv = [
            [a[1][1] / det, -a[0][1] / det],
            [-a[1][0] / det, a[0][0] / det],
        ];
        Inverse {
            a: inv,
            b: [
                -(inv[0][0] * b[0] + inv[0][1] * b[1]),
                -(inv[1][0] * b[0] + inv[1][1] * b[1]),
            ],
        }
    }

    fn apply(&self, q: [f64; 2]) -> [f64; 2] {
        [
            self.a[0][0] * q[0] + self.a[0][1] * q[1] + self.b[0],
            self.a[1][0] * q[0] + self.a[1][1] * q[1] + self.b[1],
        ]
    }

    /// The source point of output pixel (i, j) if it lies inside a `width` × `height` input.
    fn source(&self, i: usize, j: usize, width: usize, height: usize) -> Option<[f64; 2]> {
        let [x, y] = self.apply([j as f64 + 0.5, i as f64 + 0.5]);
        let inside = (0.0..width as f64).contains(&x) && (0.0..height as f64).contains(&y);
        inside.then_some([x, y])
    }
}

/// Output size and source size of a warp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame {
    /// Input width, pixels.
    pub width: usize,
    /// Input height, pixels.
    pub height: usize,
    /// Output width, pixels.
    pub out_width: usize,
    /// Output height, pixels.
    pub out_height: usize,
}

impl Frame {
    /// Input and output of the same size.
    pub fn same(width: usize, height: usize) -> Self {
        Frame {
            width,
            height,
            out_width: width,
            out_height: height,
        }
    }
}

/// Fills `out` (`channels` values a pixel, `frame.out_width` pixels a row), row by row in
/// parallel, from each output pixel's source point (None = outside the input).
fn fill_rows<T: Send>(
    out: &mut [T],
    channels: usize,
    frame: Frame,
    sim: &Similarity,
    pixel: impl Fn(Option<[f64; 2]>, &mut [T]) + Sync,
) {
    let inverse = Inverse::of(sim);
    if frame.out_width == 0 {
        return;
    }
    out.par_chunks_mut(channels * frame.out_width)
        .enumerate()
        .for_each(|(i, row)| {
            for (j, values) in row.chunks_exact_mut(channels).enumerate() {
                pixel(inverse.source(i, j, frame.width, frame.height), values);
            }
        });
}

/// The warped sRGB8 image: bilinear inside, black where the source is outside.
pub fn warp_rgb(rgb: &[u8], frame: Frame, sim: &Similarity) -> Vec<u8> {
    rgb_pixels(rgb, frame.width, frame.height);
    let mut out = vec![0u8; 3 * frame.out_width * frame.out_height];
    fill_rows(&mut out, 3, frame, sim, |source, values| {
        if let Some(p) = source {
            bilinear(rgb, frame.width, frame.height, p, values);
        }
    });
    out
}

/// Bilinear interpolation at continuous point `p` between the four nearest pixel centres,
/// indices clamped to the image.
fn bilinear(rgb: &[u8], width: usize, height: usize, p: [f64; 2], out: &mut [u8]) {
    let (u, v) = (p[0] - 0.5, p[1] - 0.5);
    let (u0, v0) = (u.floor(), v.floor());
    let (fu, fv) = (u - u0, v - v0);
    let column = |k: f64| (k.max(0.0) as usize).min(width - 1);
    let row = |k: f64| (k.max(0.0) as usize).min(height - 1);
    let (j0, j1, i0, i1) = (column(u0), column(u0 + 1.0), row(v0), row(v0 + 1.0));
    for (c, o) in out.iter_mut().enumerate() {
        let at = |i: usize, j: usize| f64::from(rgb[3 * (i * width + j) + c]);
        let top = at(i0, j0) * (1.0 - fu) + at(i0, j1) * fu;
        let bottom = at(i1, j0) * (1.0 - fu) + at(i1, j1) * fu;
        *o = (top * (1.0 - fv) + bottom * fv).round().clamp(0.0, 255.0) as u8;
    }
}

/// A warped label layer (depth, mask, ids: one value a pixel): the value of the input pixel
/// containing each source point, `T::default()` (0) where the source is outside.
pub fn warp_labels<T: Copy + Default + Send + Sync>(
    labels: &[T],
    frame: Frame,
    sim: &Similarity,
) -> Vec<T> {
    assert_eq!(labels.len(), frame.width * frame.height, "label layer size");
    let mut out = vec![T::default(); frame.out_width * frame.out_height];
    fill_rows(&mut out, 1, frame, sim, |source, value| {
        if let Some([x, y]) = source {
            value[0] = labels[y as usize * frame.width + x as usize];
        }
    });
    out
}

/// The validity mask of a warp: 255 where the output pixel's source lies inside the input,
/// 0 where it does not.
pub fn warp_validity(frame: Frame, sim: &Similarity) -> Vec<u8> {
    let mut out = vec![0u8; frame.out_width * frame.out_height];
    fill_rows(&mut out, 1, frame, sim, |source, value| {
        value[0] = if source.is_some() { 255 } else { 0 };
    });
    out
}

/// Where image-space warps are drawn from: zoom and rotation about the image centre, then a
/// shift; the output has the input's size.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct WarpSpec {
    /// Range of the zoom, dimensionless, within [0.05, 20].
    pub zoom: Range,
    /// Range of the in-plane rotation, radians (positive: clockwise on screen).
    pub rotation: Range,
    /// Range of the horizontal shift, fraction of the image width, within [−1, 1].
    pub shift_x: Range,
    /// Range of the vertical shift, fraction of the image height, within [−1, 1].
    pub shift_y: Range,
    /// Probability of warping a view, in [0, 1].
    pub probability: f64,
}

impl WarpSpec {
    /// The 3DGEN paper's zoom × 0.8–1.2 and rotation 0–360°, on every view.
    pub fn paper() -> Self {
        WarpSpec {
            zoom: Range::Span([0.8, 1.2]),
            rotation: Range::Span([0.0, std::f64::consts::TAU]),
            shift_x: Range::Fixed(0.0),
            shift_y: Range::Fixed(0.0),
            probability: 1.0,
        }
    }

    /// Checks every range; the error names the parameter by its path under `at` and shows
    /// its value.
    pub fn validate(&self, at: &str) -> Result<(), String> {
        check_range(&format!("{at}.zoom"), &self.zoom, 0.05, 20.0)?;
        check_range(&format!("{at}.rotation"), &self.rotation, -1e3, 1e3)?;
        check_range(&format!("{at}.shift_x"), &self.shift_x, -1.0, 1.0)?;
        check_range(&format!("{at}.shift_y"), &self.shift_y, -1.0, 1.0)?;
        check_probability(at, self.probability)
    }

    /// Draws the warp of one `width` × `height` view, or `None` when the probability says skip.
    pub fn draw(&self, stream: &mut Stream, width: usize, height: usize) -> Option<Similarity> {
        happens(stream, self.probability).then(|| {
            let zoom = self.zoom.draw(stream);
            let angle = self.rotation.draw(stream);
            let shift = [
                self.shift_x.draw(stream) * width as f64,
                self.shift_y.draw(stream) * height as f64,
            ];
            Similarity::about_centre(width, height, zoom, angle, shift)
        })
    }
}

/// Crop-and-resize: a window of `size` times the image's sides (the aspect kept), at a place
/// drawn uniformly inside the image, resized to fill the frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CropSpec {
    /// Range of the window's side, fraction of the image's, within (0, 1].
    pub size: Range,
    /// Probability of cropping a view, in [0, 1].
    pub probability: f64,
}

impl CropSpec {
    /// Checks the range and probability; the error names the parameter by its path under
    /// `at` and shows its value.
    pub fn validate(&self, at: &str) -> Result<(), String> {
        check_range(&format!("{at}.size"), &self.size, 1e-3, 1.0)?;
        check_probability(at, self.probability)
    }

    /// Draws the crop of one `width` × `height` view as the similarity that resizes it, or
    /// `None` when the probability says skip.
    pub fn draw(&self, stream: &mut Stream, width: usize, height: usize) -> Option<Similarity> {
        if !happens(stream, self.probability) {
            return None;
        }
        let size = self.size.draw(stream);
        let (w, h) = (width as f64, height as f64);
        let crop = [size * w, size * h];
        let (left, top) = (
            stream.uniform(0.0, w - crop[0]),
            stream.uniform(0.0, h - crop[1]),
        );
        Some(Similarity {
            zoom: 1.0 / size,
            angle: 0.0,
            centre: [left, top],
            shift: [-left, -top],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::{assert_frequency, assert_uniform, on_threads, test_image, test_stream};
    use std::f64::consts::FRAC_PI_2;

    fn close(a: [f64; 2], b: [f64; 2], tol: f64) -> bool {
        (a[0] - b[0]).abs() < tol && (a[1] - b[1]).abs() < tol
    }

    fn rotate(r: [[f64; 3]; 3], p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2])
    }

    #[test]
    fn a_drawn_crop_fills_the_frame_from_a_window_inside_the_image() {
        let spec = CropSpec {
            size: Range::Span([0.5, 0.9]),
            probability: 1.0,
        };
        let mut s = test_stream("crop");
        for _ in 0..200 {
            let sim = spec.draw(&mut s, 640, 480).unwrap();
            // The output frame's corners come from inside the input image.
            for corner in [[0.0, 0.0], [640.0, 0.0], [0.0, 480.0], [640.0, 480.0]] {
                let [x, y] = sim.invert(corner);
                assert!((-1e-9..=640.0 + 1e-9).contains(&x), "{x}");
                assert!((-1e-9..=480.0 + 1e-9).contains(&y), "{y}");
            }
            assert!((1.0 / 0.9..=2.0).contains(&sim.zoom));
        }
    }

    #[test]
    fn a_warped_projection_is_the_projection_with_the_new_camera() {
        // The paper's camera: 960 × 960, vertical field of view π/3.
        let f = 480.0 / (std::f64::consts::FRAC_PI_6).tan();
        let k = Pinhole::square(f, 480.0, 480.0);
        let mut s = test_stream("warp points");
        for sim in [
            Similarity::about_centre(960, 960, 1.17, 2.1, [13.0, -40.5]),
            Similarity {
                zoom: 0.83,
                angle: -0.6,
                centre: [100.0, 700.0],
                shift: [0.0, 5.0],
            },
            Similarity::crop_resize(100.0, 50.0, [480.0, 480.0], [960, 960]).unwrap(),
        ] {
            let k2 = sim.intrinsics(&k).unwrap();
            let r = sim.camera_rotation();
            for _ in 0..50 {
                let p = [
                    s.uniform(-3.0, 3.0),
                    s.uniform(-3.0, 3.0),
                    s.uniform(2.0, 30.0),
                ];
                let warped = sim.apply(k.project(p));
                let direct = k2.project(rotate(r, p));
                assert!(close(warped, direct, 1e-9), "{warped:?} vs {direct:?}");
                // The turned camera sees the point at the same depth.
                assert!((rotate(r, p)[2] - p[2]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn positive_angles_turn_the_picture_clockwise_and_roll_the_camera_back() {
        let sim = Similarity::about_centre(100, 100, 1.0, FRAC_PI_2, [0.0, 0.0]);
        // A point right of the centre goes below it (y down): clockwise on screen.
        assert!(close(sim.apply([80.0, 50.0]), [50.0, 80.0], 1e-12));
        // The camera's x axis, seen from the new camera, lies along +y: the new x axis is
        // the old −y.
        let r = sim.camera_rotation();
        let x_seen = rotate(r, [1.0, 0.0, 0.0]);
        assert!((x_seen[1] - 1.0).abs() < 1e-12 && x_seen[0].abs() < 1e-12);
        // With the principal point at the centre, K does not change.
        let k = Pinhole::square(90.0, 50.0, 50.0);
        let k2 = sim.intrinsics(&k).unwrap();
        assert!((k2.fx - 90.0).abs() < 1e-12 && close([k2.cx, k2.cy], [50.0, 50.0], 1e-12));
        let skew = Pinhole { fy: 91.0, ..k };
        assert!(sim.intrinsics(&skew).unwrap_err().contains("fy = 91"));
        let zoom_only = Similarity::about_centre(100, 100, 2.0, 0.0, [0.0, 0.0]);
        assert_eq!(zoom_only.intrinsics(&skew).unwrap().fy, 182.0);
    }

    #[test]
    fn the_image_moves_as_the_similarity_says() {
        let (w, h) = (40, 30);
        let original = test_image(w, h, "warp rgb");
        // A quarter turn about the centre of a 40 × 30 image with a shift that keeps pixel
        // centres on pixel centres: every output pixel is one input pixel.
        let sim = Similarity::about_centre(w, h, 1.0, FRAC_PI_2, [3.0, -2.0]);
        let frame = Frame::same(w, h);
        let out = warp_rgb(&original, frame, &sim);
        let valid = warp_validity(frame, &sim);
        for i in 0..h {
            for j in 0..w {
                let centre = [j as f64 + 0.5, i as f64 + 0.5];
                let [x, y] = sim.apply(centre);
                let (oj, oi) = (x.floor() as usize, y.floor() as usize);
                if x < 0.0 || y < 0.0 || oj >= w || oi >= h {
                    continue;
                }
                assert_eq!(valid[oi * w + oj], 255);
                assert_eq!(
                    out[3 * (oi * w + oj)..][..3],
                    original[3 * (i * w + j)..][..3],
                    "({i}, {j})"
                );
            }
        }
    }

    #[test]
    fn nearest_sampling_never_invents_label_values() {
        let (w, h) = (37, 29);
        let mut s = test_stream("labels");
        let ids: Vec<u32> = (0..w * h).map(|_| s.integer(1, 1_000_000) as u32).collect();
        let depth: Vec<f32> = (0..w * h).map(|_| s.uniform(1.0, 50.0) as f32).collect();
        let sim = Similarity::about_centre(w, h, 1.37, 0.41, [2.3, -1.7]);
        let frame = Frame::same(w, h);
        let warped_ids = warp_labels(&ids, frame, &sim);
        let warped_depth = warp_labels(&depth, frame, &sim);
        let valid = warp_validity(frame, &sim);
        for k in 0..w * h {
            assert_eq!(warped_ids[k] == 0, valid[k] == 0);
            assert_eq!(warped_depth[k] == 0.0, valid[k] == 0);
            assert!(warped_ids[k] == 0 || ids.contains(&warped_ids[k]));
            assert!(warped_depth[k] == 0.0 || depth.contains(&warped_depth[k]));
        }
    }

    #[test]
    fn pixels_whose_source_is_outside_are_invalid() {
        let (w, h) = (64, 48);
        let original = vec![200u8; w * h * 3];
        // Shrinking to half leaves a frame of pixels with nothing behind them.
        let sim = Similarity::about_centre(w, h, 0.5, 0.0, [0.0, 0.0]);
        let frame = Frame::same(w, h);
        let out = warp_rgb(&original, frame, &sim);
        let depth = warp_labels(&vec![3.0f32; w * h], frame, &sim);
        let mask = warp_labels(&vec![255u8; w * h], frame, &sim);
        let valid = warp_validity(frame, &sim);
        let inside = |i: usize, j: usize| (16..48).contains(&j) && (12..36).contains(&i);
        for i in 0..h {
            for j in 0..w {
                let k = i * w + j;
                let expect = if inside(i, j) { 255 } else { 0 };
                assert_eq!(valid[k], expect, "({i}, {j})");
                assert_eq!(mask[k], expect);
                assert_eq!(depth[k], if inside(i, j) { 3.0 } else { 0.0 });
                assert_eq!(out[3 * k], if inside(i, j) { 200 } else { 0 });
            }
        }
    }

    #[test]
    fn crops_resize_and_compositions_compose() {
        let sim = Similarity::crop_resize(10.0, 20.0, [40.0, 30.0], [80, 60]).unwrap();
        assert!(close(sim.apply([10.0, 20.0]), [0.0, 0.0], 1e-12));
        assert!(close(sim.apply([50.0, 50.0]), [80.0, 60.0], 1e-12));
        assert!(Similarity::crop_resize(0.0, 0.0, [40.0, 30.0], [80, 80]).is_err());
        let k = Pinhole::square(100.0, 32.0, 24.0);
        // Crop then resize: f′ = s·f, c′ = s·(c − offset).
        let k2 = sim.intrinsics(&k).unwrap();
        assert_eq!((k2.fx, k2.cx, k2.cy), (200.0, 44.0, 8.0));
        let frame = Frame {
            width: 64,
            height: 48,
            out_width: 80,
            out_height: 60,
        };
        assert_eq!(warp_validity(frame, &sim).len(), 80 * 60);
        let a = Similarity::about_centre(64, 48, 1.2, 0.3, [1.0, 2.0]);
        let b = Similarity::about_centre(64, 48, 0.7, -1.1, [-4.0, 0.5]);
        let p = [13.0, 29.0];
        assert!(close(a.then(&b).apply(p), b.apply(a.apply(p)), 1e-9));
        assert!(close(a.invert(a.apply(p)), p, 1e-9));
    }

    #[test]
    fn warped_bytes_do_not_depend_on_the_thread_count() {
        let (w, h) = (50, 40);
        let original = test_image(w, h, "warp threads");
        let sim = Similarity::about_centre(w, h, 1.1, 0.9, [0.0, 0.0]);
        let run = |threads| on_threads(threads, || warp_rgb(&original, Frame::same(w, h), &sim));
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn draws_follow_the_spec() {
        let mut s = test_stream("warp spec");
        let spec = WarpSpec {
            shift_x: Range::Span([-0.1, 0.1]),
            ..WarpSpec::paper()
        };
        spec.validate("warp").unwrap();
        let drawn: Vec<Similarity> = (0..4000)
            .filter_map(|_| spec.draw(&mut s, 960, 480))
            .collect();
        assert_eq!(drawn.len(), 4000);
        assert!(drawn.iter().all(|d| (0.8..1.2).contains(&d.zoom)));
        assert!(
            drawn
                .iter()
                .all(|d| d.shift[0].abs() <= 96.0 && d.shift[1] == 0.0)
        );
        assert!(drawn.iter().all(|d| d.centre == [480.0, 240.0]));
        let of = |f: fn(&Similarity) -> f64| drawn.iter().map(f).collect::<Vec<f64>>();
        assert_uniform(&of(|d| d.zoom), (0.8, 1.2), "warp.zoom");
        let tau = std::f64::consts::TAU;
        assert_uniform(&of(|d| d.angle), (0.0, tau), "warp.rotation");
        assert_uniform(&of(|d| d.shift[0] / 960.0), (-0.1, 0.1), "warp.shift_x");
        let bad = WarpSpec {
            zoom: Range::Fixed(0.0),
            ..spec
        };
        assert!(bad.validate("warp").unwrap_err().contains("warp.zoom"));
    }

    #[test]
    fn crop_sizes_and_places_follow_the_declared_distribution() {
        let spec = CropSpec {
            size: Range::Span([0.5, 0.9]),
            probability: 0.6,
        };
        let (w, h) = (640.0, 480.0);
        let mut s = test_stream("crop draws");
        let n = 5000;
        let drawn: Vec<Similarity> = (0..n).filter_map(|_| spec.draw(&mut s, 640, 480)).collect();
        assert_frequency(drawn.len(), n, 0.6, "crop.probability");
        let sizes: Vec<f64> = drawn.iter().map(|d| 1.0 / d.zoom).collect();
        assert_uniform(&sizes, (0.5, 0.9), "crop.size");
        // The window's top-left corner is uniform over the places that keep it inside: as a
        // fraction of the room left, uniform in [0, 1].
        let place = |axis: usize, side: f64| -> Vec<f64> {
            (drawn.iter())
                .map(|d| d.centre[axis] / (side - side / d.zoom))
                .collect()
        };
        assert_uniform(&place(0, w), (0.0, 1.0), "crop left");
        assert_uniform(&place(1, h), (0.0, 1.0), "crop top");
    }
}
