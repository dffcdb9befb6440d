//! Blur: Gaussian (separable), motion (a line segment) and defocus (a disc).
//!
//! Like torchvision's `GaussianBlur` the blurs act on the stored, gamma-encoded values.
//! Pixels beyond the border are the nearest edge pixel (clamp to edge; torchvision pads by
//! reflection instead). Each output row is computed on its own from an edge-padded copy, in
//! a fixed order of summation, so rows run in parallel and the bytes do not depend on the
//! thread count. Rounding is to the nearest level.

use super::draw::{Range, check_probability, check_range, happens};
use super::rgb_pixels;
use crate::seeds::Stream;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A blur drawn for one view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Blur {
    /// Gaussian blur: kernel exp(−x²/2σ²) sampled at whole pixels out to ⌈3σ⌉, normalised.
    Gaussian {
        /// Standard deviation, pixels.
        sigma: f64,
    },
    /// Linear motion blur: the image averaged along a segment centred on each pixel
    /// (bilinear samples at most one pixel apart, trapezoidal weights).
    Motion {
        /// Length of the segment (the distance moved during the exposure), pixels.
        length: f64,
        /// Direction of the motion, radians from the image's +x axis towards its +y axis
        /// (clockwise on screen, y pointing down).
        angle: f64,
    },
    /// Defocus blur: the average over a disc. In each row dy the disc's area within the band
    /// [dy − ½, dy + ½] is laid out as a centred segment of that length, each pixel weighted
    /// by its overlap with the segment.
    Defocus {
        /// Radius of the disc (circle of confusion), pixels.
        radius: f64,
    },
}

/// Where blurs are drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum BlurSpec {
    /// Gaussian blur.
    Gaussian {
        /// Range of the standard deviation, pixels, within [0, 50].
        sigma: Range,
        /// Probability of applying it to a view, in [0, 1].
        probability: f64,
    },
    /// Linear motion blur.
    Motion {
        /// Range of the length, pixels, within [0, 200].
        length: Range,
        /// Range of the direction, radians (any finite values).
        angle: Range,
        /// Probability of applying it to a view, in [0, 1].
        probability: f64,
    },
    /// Defocus blur.
    Defocus {
        /// Range of the disc radius, pixels, within [0, 100].
        radius: Range,
        /// Probability of applying it to a view, in [0, 1].
        probability: f64,
    },
}

impl BlurSpec {
    /// Checks every range; the error names the parameter by its path under `at` and shows
    /// its value.
    pub fn validate(&self, at: &str) -> Result<(), String> {
        let field = |name: &str| format!("{at}.{name}");
        let probability = match self {
            BlurSpec::Gaussian { sigma, probability } => {
                check_range(&field("sigma"), sigma, 0.0, 50.0)?;
                probability
            }
            BlurSpec::Motion {
                length,
                angle,
                probability,
            } => {
                check_range(&field("length"), length, 0.0, 200.0)?;
                check_range(&field("angle"), angle, -f64::MAX, f64::MAX)?;
                probability
            }
            BlurSpec::Defocus {
                radius,
                probability,
            } => {
                check_range(&field("radius"), radius, 0.0, 100.0)?;
                probability
            }
        };
        check_probability(at, *probability)
    }

    /// Draws one view's blur, or `None` when the probability says skip.
    pub fn draw(&self, stream: &mut Stream) -> Option<Blur> {
        match *self {
            BlurSpec::Gaussian { sigma, probability } => {
                happens(stream, probability).then(|| Blur::Gaussian {
                    sigma: sigma.draw(stream),
                })
            }
            BlurSpec::Motion {
                length,
                angle,
                probability,
            } => happens(stream, probability).then(|| Blur::Motion {
                length: length.draw(stream),
                angle: angle.draw(stream),
            }),
            BlurSpec::Defocus {
                radius,
                probability,
            } => happens(stream, probability).then(|| Blur::Defocus {
                radius: radius.draw(stream),
            }),
        }
    }
}

/// Applies `blur` to an sRGB8 image in place.
pub fn blur(rgb: &mut [u8], width: usize, height: usize, blur: &Blur) {
    rgb_pixels(rgb, width, height);
    if width == 0 || height == 0 {
        return;
    }
    match *blur {
        Blur::Gaussian { sigma } => gaussian(rgb, width, height, sigma),
        Blur::Motion { length, angle } => {
            apply_kernel(rgb, width, height, &Kernel::motion(length, angle))
        }
        Blur::Defocus { radius } => apply_kernel(rgb, width, height, &Kernel::disc(radius)),
    }
}

/// The normalised Gaussian kernel sampled at −r…r, r = ⌈3σ⌉ (one tap of 1 for σ = 0).
pub fn gaussian_kernel(sigma: f64) -> Vec<f32> {
    if sigma <= 0.0 {
        return vec![1.0];
    }
    let r = (3.0 * sigma).ceil() as i64;
    let raw: Vec<f64> = (-r..=r)
        .map(|i| libm::exp(-0.5 * (i as f64 / sigma).powi(2)))
        .collect();
    let sum: f64 = raw.iter().sum();
    raw.iter().map(|w| (w / sum) as f32).collect()
}

/// An edge-padded copy of the image with `margin` extra pixels on every side.
struct Padded {
    bytes: Vec<u8>,
    /// Values (3 a pixel) per padded row.
    stride: usize,
    margin: usize,
}

impl Padded {
    fn new(rgb: &[u8], width: usize, height: usize, margin: usize) -> Self {
        let stride = 3 * (width + 2 * margin);
        let mut bytes = Vec::with_capacity(stride * (height + 2 * margin));
        for y in 0..height + 2 * margin {
            let row = &rgb[3 * width * (y.saturating_sub(margin)).min(height - 1)..][..3 * width];
            for x in 0..width + 2 * margin {
                let from = 3 * x.saturating_sub(margin).min(width - 1);
                bytes.extend_from_slice(&row[from..from + 3]);
            }
        }
        Padded {
            bytes,
            stride,
            margin,
        }
    }

    fn row(&self, y: usize) -> &[u8] {
        &self.bytes[y * self.stride..][..self.stride]
    }
}

fn gaussian(rgb: &mut [u8], width: usize, height: usize, sigma: f64) {
    if sigma <= 0.0 {
        return;
    }
    let taps = gaussian_kernel(sigma);
    let padded = Padded::new(rgb, width, height, taps.len() / 2);
    let line = 3 * width;
    // Horizontal pass over every padded row, then a vertical pass into the image.
    let mut across = vec![0f32; line * (height + taps.len() - 1)];
    across
        .par_chunks_mut(line)
        .enumerate()
        .for_each(|(y, out)| horizontal(out, padded.row(y), &taps));
    rgb.par_chunks_mut(line)
        .enumerate()
        .for_each(|(y, out)| vertical(out, &across[y * line..], line, &taps));
}

fn horizontal(out: &mut [f32], padded_row: &[u8], taps: &[f32]) {
    let n = out.len();
    for (k, &t) in taps.iter().enumerate() {
        for (o, &v) in out.iter_mut().zip(&padded_row[3 * k..][..n]) {
            *o += t * f32::from(v);
        }
    }
}

fn vertical(out: &mut [u8], rows: &[f32], line: usize, taps: &[f32]) {
    let mut acc = vec![0f32; line];
    for (k, &t) in taps.iter().enumerate() {
        for (a, &v) in acc.iter_mut().zip(&rows[k * line..][..line]) {
            *a += t * v;
        }
    }
    for (o, a) in out.iter_mut().zip(acc) {
        *o = a.round().clamp(0.0, 255.0) as u8;
    }
}

/// A 2D kernel as whole-pixel runs of weight 1 (summed with row prefix sums) plus weighted
/// single taps; offsets in pixels (dx right, dy down).
#[derive(Debug, Default)]
pub struct Kernel {
    /// (dy, half): pixels dx ∈ [−half, half] of row dy, weight 1 each.
    runs: Vec<(i64, i64)>,
    /// (dx, dy, weight).
    taps: Vec<(i64, i64, f32)>,
}

impl Kernel {
    /// The disc of `radius`: row dy gets the segment [−a, a] whose length 2a is the disc's
    /// area within the band [dy − ½, dy + ½], and pixel dx the length of its overlap with
    /// [dx − ½, dx + ½]; the weights add up to πr².
    pub fn disc(radius: f64) -> Self {
        if radius <= 0.0 {
            return Kernel::motion(0.0, 0.0);
        }
        let mut kernel = Kernel::default();
        let reach = (radius + 0.5).floor() as i64;
        for dy in -reach..=reach {
            let a = band_half_width(radius, dy as f64);
            if a < 0.5 {
                kernel.taps.push((0, dy, (2.0 * a) as f32));
                continue;
            }
            let half = (a - 0.5).floor() as i64;
            kernel.runs.push((dy, half));
            let edge = (a - 0.5 - half as f64) as f32;
            if edge > 0.0 {
                kernel.taps.push((-half - 1, dy, edge));
                kernel.taps.push((half + 1, dy, edge));
            }
        }
        kernel
    }

    /// A segment of `length` through the origin in direction `angle`: ⌈length⌉ + 1 points
    /// evenly spaced, trapezoidal weights, each splatted bilinearly onto whole pixels.
    pub fn motion(length: f64, angle: f64) -> Self {
        let n = length.ceil().max(0.0) as usize + 1;
        let (sin, cos) = libm::sincos(angle);
        let mut weights: BTreeMap<(i64, i64), f64> = BTreeMap::new();
        if n == 1 {
            weights.insert((0, 0), 1.0);
        }
        let intervals = (n - 1) as f64;
        for i in (0..n).filter(|_| n > 1) {
            let t = length * (i as f64 / intervals - 0.5);
            let end = i == 0 || i + 1 == n;
            let share = if end { 0.5 } else { 1.0 };
            splat(&mut weights, t * cos, t * sin, share / intervals);
        }
        Kernel {
            runs: Vec::new(),
            taps: weights
                .into_iter()
                .filter(|&(_, w)| w > 0.0)
                .map(|((dx, dy), w)| (dx, dy, w as f32))
                .collect(),
        }
    }

    /// How far the kernel reaches from its centre, pixels.
    fn reach(&self) -> usize {
        let runs = self.runs.iter().map(|&(dy, half)| dy.abs().max(half));
        let taps = self.taps.iter().map(|&(dx, dy, _)| dx.abs().max(dy.abs()));
        runs.chain(taps).max().unwrap_or(0) as usize
    }

    /// The sum of all weights.
    fn total(&self) -> f32 {
        let runs: i64 = self.runs.iter().map(|&(_, half)| 2 * half + 1).sum();
        runs as f32 + self.taps.iter().map(|t| t.2).sum::<f32>()
    }
}

/// Half the area of the disc of radius r within the band [y − ½, y + ½]: the integral of
/// √(r² − y²) over the band.
fn band_half_width(r: f64, y: f64) -> f64 {
    let primitive = |y: f64| {
        let y = y.clamp(-r, r);
        0.5 * (y * (r * r - y * y).sqrt() + r * r * libm::asin(y / r))
    };
    primitive(y + 0.5) - primitive(y - 0.5)
}

/// Adds weight `w` at (x, y) to the four pixels around it, bilinearly.
fn splat(weights: &mut BTreeMap<(i64, i64), f64>, x: f64, y: f64, w: f64) {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    for (dx, dy, share) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        *weights.entry((x0 + dx, y0 + dy)).or_default() += w * share;
    }
}

/// Row prefix sums of a padded image: `sums[y][3x + c]` = Σ of channel c over x' < x.
fn prefix_sums(padded: &Padded) -> Vec<u32> {
    let line = padded.stride + 3;
    let rows = padded.bytes.len() / padded.stride;
    let mut sums = vec![0u32; line * rows];
    sums.par_chunks_mut(line).enumerate().for_each(|(y, out)| {
        for (i, &v) in padded.row(y).iter().enumerate() {
            out[i + 3] = out[i] + u32::from(v);
        }
    });
    sums
}

fn apply_kernel(rgb: &mut [u8], width: usize, height: usize, kernel: &Kernel) {
    let padded = Padded::new(rgb, width, height, kernel.reach());
    let sums = if kernel.runs.is_empty() {
        Vec::new()
    } else {
        prefix_sums(&padded)
    };
    let scale = 1.0 / kernel.total();
    rgb.par_chunks_mut(3 * width)
        .enumerate()
        .for_each(|(y, out)| kernel_row(out, y, &padded, &sums, kernel, scale));
}

fn kernel_row(out: &mut [u8], y: usize, padded: &Padded, sums: &[u32], k: &Kernel, scale: f32) {
    let (m, n, line) = (padded.margin as i64, out.len(), padded.stride + 3);
    let row_at = |dy: i64| (y as i64 + m + dy) as usize;
    // Whole runs: differences of prefix sums, exact in integers.
    let mut whole = vec![0u32; n];
    for &(dy, half) in &k.runs {
        let sums = &sums[row_at(dy) * line..][..line];
        let upper = &sums[3 * (m + half + 1) as usize..][..n];
        let lower = &sums[3 * (m - half) as usize..][..n];
        for ((acc, &hi), &lo) in whole.iter_mut().zip(upper).zip(lower) {
            *acc += hi - lo;
        }
    }
    // Weighted taps, added in the kernel's order.
    let mut parts = vec![0f32; n];
    for &(dx, dy, w) in &k.taps {
        let source = &padded.row(row_at(dy))[3 * (m + dx) as usize..][..n];
        for (acc, &v) in parts.iter_mut().zip(source) {
            *acc += w * f32::from(v);
        }
    }
    for ((o, whole), part) in out.iter_mut().zip(whole).zip(parts) {
        *o = ((whole as f32 + part) * scale).round().clamp(0.0, 255.0) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::{assert_frequency, assert_uniform, on_threads, test_image, test_stream};

    fn impulse(w: usize, h: usize) -> Vec<u8> {
        let mut img = vec![0u8; w * h * 3];
        img[3 * (h / 2 * w + w / 2)] = 255;
        img
    }

    /// Mass, centroid and second moments of channel 0 about the image centre pixel.
    fn moments(img: &[u8], w: usize, h: usize) -> (f64, [f64; 2], [f64; 3]) {
        let (mut mass, mut first, mut second) = (0.0, [0.0; 2], [0.0; 3]);
        for i in 0..h {
            for j in 0..w {
                let v = f64::from(img[3 * (i * w + j)]);
                let (x, y) = (j as f64 - (w / 2) as f64, i as f64 - (h / 2) as f64);
                mass += v;
                first = [first[0] + v * x, first[1] + v * y];
                second = [
                    second[0] + v * x * x,
                    second[1] + v * y * y,
                    second[2] + v * x * y,
                ];
            }
        }
        (mass, first.map(|f| f / mass), second.map(|s| s / mass))
    }

    #[test]
    fn gaussian_blur_of_an_impulse_is_the_sampled_gaussian() {
        let (w, h, sigma) = (21, 21, 1.7);
        let mut img = impulse(w, h);
        blur(&mut img, w, h, &Blur::Gaussian { sigma });
        let g = |d: i64| (-0.5 * (d as f64 / sigma).powi(2)).exp();
        let norm: f64 = (-6..=6).map(g).sum();
        for i in 0..h as i64 {
            for j in 0..w as i64 {
                let (dy, dx) = (i - 10, j - 10);
                let inside = dx.abs() <= 6 && dy.abs() <= 6;
                let want = if inside {
                    255.0 * g(dx) * g(dy) / norm / norm
                } else {
                    0.0
                };
                let got = f64::from(img[3 * (i as usize * w + j as usize)]);
                assert!(
                    (got - want).abs() <= 0.5 + 1e-3,
                    "({dy}, {dx}): {got} vs {want}"
                );
            }
        }
        assert_eq!(gaussian_kernel(0.0), vec![1.0]);
        assert_eq!(gaussian_kernel(1.0).len(), 7);
    }

    #[test]
    fn every_blur_keeps_a_constant_image() {
        let (w, h) = (23, 19);
        for b in [
            Blur::Gaussian { sigma: 2.3 },
            Blur::Motion {
                length: 7.5,
                angle: 0.7,
            },
            Blur::Defocus { radius: 3.6 },
            Blur::Defocus { radius: 0.2 },
        ] {
            let mut img: Vec<u8> = [40u8, 130, 250].repeat(w * h);
            blur(&mut img, w, h, &b);
            assert_eq!(img, [40u8, 130, 250].repeat(w * h), "{b:?}");
        }
    }

    #[test]
    fn motion_blur_spreads_an_impulse_over_its_length_and_direction() {
        let (w, h, length) = (61, 61, 20.0);
        let mut img = impulse(w, h);
        blur(&mut img, w, h, &Blur::Motion { length, angle: 0.0 });
        // Horizontal: one row, 21 pixels, the ends half weight (255/20 = 12.75 → 13,
        // ends 6.375 → 6).
        let row = |i: usize| img[3 * i * w..3 * (i + 1) * w].iter().step_by(3).copied();
        let lit: Vec<u8> = row(h / 2).filter(|&v| v > 0).collect();
        assert_eq!(lit.len(), 21);
        assert_eq!((lit[0], lit[10], lit[20]), (6, 13, 6));
        assert!(row(h / 2 - 1).all(|v| v == 0));

        // Diagonal: the spread along the direction has the variance of a segment of
        // that length (L²/12), and almost none across it.
        let mut img = impulse(w, h);
        let angle = std::f64::consts::FRAC_PI_4;
        blur(&mut img, w, h, &Blur::Motion { length, angle });
        let (mass, mean, [xx, yy, xy]) = moments(&img, w, h);
        assert!((mass / 255.0 - 1.0).abs() < 0.05, "{mass}");
        assert!(mean[0].abs() < 0.1 && mean[1].abs() < 0.1, "{mean:?}");
        let along = 0.5 * (xx + yy) + xy;
        let across = 0.5 * (xx + yy) - xy;
        assert!(
            (along / (length * length / 12.0) - 1.0).abs() < 0.08,
            "{along}"
        );
        assert!(across < 0.5, "{across}");
    }

    #[test]
    fn defocus_blur_fills_a_disc_of_its_radius() {
        let (w, h, radius) = (41, 41, 8.0);
        let mut img = impulse(w, h);
        blur(&mut img, w, h, &Blur::Defocus { radius });
        // The kernel: area πr², and E[x²] = E[y²] = r²/4 as for a uniform disc.
        let kernel = Kernel::disc(radius);
        let total = f64::from(kernel.total());
        assert!(
            (total / (std::f64::consts::PI * 64.0) - 1.0).abs() < 1e-6,
            "{total}"
        );
        let (mut xx, mut yy) = (0.0, 0.0);
        for &(dy, half) in &kernel.runs {
            xx += (-half..=half).map(|dx| (dx * dx) as f64).sum::<f64>();
            yy += ((2 * half + 1) * dy * dy) as f64;
        }
        for &(dx, dy, w) in &kernel.taps {
            xx += f64::from(w) * (dx * dx) as f64;
            yy += f64::from(w) * (dy * dy) as f64;
        }
        let quarter = radius * radius / 4.0;
        assert!((xx / total / quarter - 1.0).abs() < 0.03, "{xx}");
        assert!((yy / total / quarter - 1.0).abs() < 0.03, "{yy}");
        // The image: 255 shared by about 201 pixels, nothing outside the disc.
        let (mass, _, _) = moments(&img, w, h);
        assert!((mass / 255.0 - 1.0).abs() < 0.25, "{mass}");
        for i in 0..h {
            for j in 0..w {
                let (dx, dy) = (j as f64 - 20.0, i as f64 - 20.0);
                if dx.hypot(dy) > radius + 0.75 {
                    assert_eq!(img[3 * (i * w + j)], 0, "({i}, {j})");
                }
            }
        }
    }

    #[test]
    fn blurred_bytes_do_not_depend_on_the_thread_count() {
        let (w, h) = (64, 48);
        let original = test_image(w, h, "threads");
        for b in [Blur::Gaussian { sigma: 1.5 }, Blur::Defocus { radius: 2.5 }] {
            let run = |threads| {
                let mut img = original.clone();
                on_threads(threads, || blur(&mut img, w, h, &b));
                img
            };
            assert_eq!(run(1), run(2));
        }
    }

    #[test]
    fn draws_pick_the_declared_kind() {
        let mut s = test_stream("blur");
        let spec = BlurSpec::Motion {
            length: Range::Span([5.0, 15.0]),
            angle: Range::Span([0.0, 3.0]),
            probability: 1.0,
        };
        spec.validate("blur").unwrap();
        let Some(Blur::Motion { length, angle }) = spec.draw(&mut s) else {
            panic!("not a motion blur");
        };
        assert!((5.0..15.0).contains(&length) && (0.0..3.0).contains(&angle));
        let bad = BlurSpec::Defocus {
            radius: Range::Fixed(-1.0),
            probability: 1.0,
        };
        assert!(bad.validate("blur").unwrap_err().contains("blur.radius"));
    }

    #[test]
    fn each_kind_draws_its_parameters_from_the_declared_ranges() {
        let mut s = test_stream("blur draws");
        let n = 4000;
        let gaussian = BlurSpec::Gaussian {
            sigma: Range::Span([0.5, 2.0]),
            probability: 0.4,
        };
        let sigmas: Vec<f64> = (0..n)
            .filter_map(|_| match gaussian.draw(&mut s)? {
                Blur::Gaussian { sigma } => Some(sigma),
                other => panic!("{other:?}"),
            })
            .collect();
        assert_frequency(sigmas.len(), n, 0.4, "blur.probability");
        assert_uniform(&sigmas, (0.5, 2.0), "blur.sigma");
        let motion = BlurSpec::Motion {
            length: Range::Span([3.0, 12.0]),
            angle: Range::Span([-1.0, 3.0]),
            probability: 1.0,
        };
        let (lengths, angles): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|_| match motion.draw(&mut s) {
                Some(Blur::Motion { length, angle }) => (length, angle),
                other => panic!("{other:?}"),
            })
            .unzip();
        assert_uniform(&lengths, (3.0, 12.0), "blur.length");
        assert_uniform(&angles, (-1.0, 3.0), "blur.angle");
        let defocus = BlurSpec::Defocus {
            radius: Range::Span([1.0, 3.0]),
            probability: 1.0,
        };
        let radii: Vec<f64> = (0..n)
            .map(|_| match defocus.draw(&mut s) {
                Some(Blur::Defocus { radius }) => radius,
                other => panic!("{other:?}"),
            })
            .collect();
        assert_uniform(&radii, (1.0, 3.0), "blur.radius");
    }
}
