//! Occlusion by random erasing (cut-out), after torchvision's `RandomErasing`
//! (`torchvision/transforms/transforms.py`, `RandomErasing.get_params`): for each rectangle
//! the erased area is a fraction of the image drawn uniformly from `area`, the aspect ratio
//! h/w is log-uniform in `aspect`, h = round(√(area·aspect)), w = round(√(area/aspect)) with
//! Python's round-half-to-even, and up to 10 attempts are made until h < H and w < W; the
//! top-left corner is then uniform over the positions that keep the rectangle inside. A
//! rectangle that fits in none of its 10 attempts is left out (torchvision returns the image
//! unchanged). Unlike torchvision, an attempt that rounds to an empty rectangle also fails,
//! several rectangles may be drawn (`count`), and the erased pixels are returned as a mask.
//!
//! Note: torchvision's ratio is height over width; the 3DGEN paper calls its 0.08–0.3 range
//! "width/height", but `aspect` here is always h/w as in torchvision.

use super::draw::{Range, check_integers, check_probability, check_range, happens};
use super::{picture, rgb_pixels};
use crate::seeds::{Scope, Stream};
use serde::{Deserialize, Serialize};

/// Name of the streams a noise fill is drawn from (one per rectangle).
const FILL_STREAM: &str = "augment.erase";

/// What erased pixels are filled with, as declared.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Fill {
    /// Black (0, 0, 0), as the 3DGEN paper.
    #[default]
    Black,
    /// The image's mean colour before erasing, per channel, rounded.
    Mean,
    /// Independent uniform bytes in [0, 255] per channel (torchvision's "random" draws
    /// N(0, 1) in normalised units; uniform bytes are the 8-bit counterpart).
    Noise,
}

/// What erased pixels were filled with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Filled {
    /// Black.
    Black,
    /// The image's mean colour before erasing.
    Mean,
    /// Uniform noise; rectangle k's bytes come from the stream keyed by (`seed`, k,
    /// "augment.erase"), 8 bytes per 64-bit draw, little-endian, row by row.
    Noise {
        /// Seed of the noise.
        seed: u64,
    },
}

/// One erased rectangle, in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Rect {
    /// First row, pixels from the top.
    pub top: u32,
    /// First column, pixels from the left.
    pub left: u32,
    /// Height, pixels.
    pub height: u32,
    /// Width, pixels.
    pub width: u32,
}

/// The erasing drawn for one view.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Erasing {
    /// The rectangles erased (they may overlap); empty when none fitted.
    pub rects: Vec<Rect>,
    /// What they were filled with.
    pub fill: Filled,
}

/// Where erasing is drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ErasingSpec {
    /// Range of the number of rectangles, integers ≥ 0 (each equally likely).
    pub count: Range,
    /// Range of each rectangle's area, fraction of the image within (0, 1].
    pub area: Range,
    /// Range of each rectangle's aspect ratio height/width, > 0, drawn log-uniformly.
    pub aspect: Range,
    /// What erased pixels are filled with.
    #[serde(default)]
    pub fill: Fill,
    /// Probability of erasing anything in a view, in [0, 1].
    pub probability: f64,
}

impl ErasingSpec {
    /// The 3DGEN paper's cut-out: one black rectangle of 2–5 % of the area, aspect 0.08–0.3,
    /// applied with probability 0.5 (the paper says only "a certain probability"; 0.5 is
    /// torchvision's default).
    pub fn paper() -> Self {
        ErasingSpec {
            count: Range::Fixed(1.0),
            area: Range::Span([0.02, 0.05]),
            aspect: Range::Span([0.08, 0.3]),
            fill: Fill::Black,
            probability: 0.5,
        }
    }

    /// Checks every range (the count must hold a whole number); the error names the
    /// parameter by its path under `at` and shows its value.
    pub fn validate(&self, at: &str) -> Result<(), String> {
        check_range(&format!("{at}.count"), &self.count, 0.0, 1000.0)?;
        check_integers(&format!("{at}.count"), &self.count)?;
        check_range(&format!("{at}.area"), &self.area, f64::MIN_POSITIVE, 1.0)?;
        check_range(&format!("{at}.aspect"), &self.aspect, 1e-3, 1e3)?;
        check_probability(at, self.probability)
    }

    /// Draws the erasing of one `width` × `height` view, or `None` when the probability says
    /// skip.
    pub fn draw(&self, stream: &mut Stream, width: usize, height: usize) -> Option<Erasing> {
        if !happens(stream, self.probability) {
            return None;
        }
        let count = self.count.draw_integer(stream).max(0);
        let rects = (0..count)
            .filter_map(|_| self.draw_rect(stream, width, height))
            .collect();
        let fill = match self.fill {
            Fill::Black => Filled::Black,
            Fill::Mean => Filled::Mean,
            Fill::Noise => Filled::Noise {
                seed: stream.next_u64(),
            },
        };
        Some(Erasing { rects, fill })
    }

    /// torchvision's 10 attempts at one rectangle.
    fn draw_rect(&self, stream: &mut Stream, width: usize, height: usize) -> Option<Rect> {
        let image_area = (width * height) as f64;
        for _ in 0..10 {
            let area = image_area * self.area.draw(stream);
            let aspect = self.aspect.draw_log(stream);
            let h = (area * aspect).sqrt().round_ties_even() as usize;
            let w = (area / aspect).sqrt().round_ties_even() as usize;
            if h == 0 || w == 0 || h >= height || w >= width {
                continue;
            }
            let top = stream.integer(0, (height - h) as i64) as u32;
            let left = stream.integer(0, (width - w) as i64) as u32;
            return Some(Rect {
                top,
                left,
                height: h as u32,
                width: w as u32,
            });
        }
        None
    }
}

impl Erasing {
    /// The erased mask of a `width` × `height` image: 255 inside a rectangle, 0 elsewhere.
    pub fn mask(&self, width: usize, height: usize) -> Vec<u8> {
        let mut mask = vec![0u8; width * height];
        for rect in &self.rects {
            for i in rect.top as usize..(rect.top + rect.height) as usize {
                mask[i * width + rect.left as usize..][..rect.width as usize].fill(255);
            }
        }
        mask
    }
}

/// Erases the rectangles of `erasing` in an sRGB8 image in place and returns the erased
/// mask (one byte a pixel, 255 = erased, 0 = kept). A mean fill is the mean of the `valid`
/// pixels (0 = no picture there, as a warp's border; None: every pixel).
pub fn erase(
    rgb: &mut [u8],
    width: usize,
    height: usize,
    erasing: &Erasing,
    valid: Option<&[u8]>,
) -> Vec<u8> {
    rgb_pixels(rgb, width, height);
    let mut mask = vec![0u8; width * height];
    let mean = mean_colour(rgb, valid);
    for (k, rect) in erasing.rects.iter().enumerate() {
        let mut noise = match erasing.fill {
            Filled::Noise { seed } => Some(NoiseBytes::new(seed, k)),
            _ => None,
        };
        for i in rect.top as usize..(rect.top + rect.height) as usize {
            for j in rect.left as usize..(rect.left + rect.width) as usize {
                let colour = noise.as_mut().map_or(
                    if erasing.fill == Filled::Mean {
                        mean
                    } else {
                        [0; 3]
                    },
                    NoiseBytes::pixel,
                );
                rgb[3 * (i * width + j)..][..3].copy_from_slice(&colour);
                mask[i * width + j] = 255;
            }
        }
    }
    mask
}

/// The mean of each channel over the `valid` pixels (every pixel when None), rounded to the
/// nearest level; black when there are none.
pub fn mean_colour(rgb: &[u8], valid: Option<&[u8]>) -> [u8; 3] {
    let mut sums = [0u64; 3];
    let mut pixels = 0u64;
    for p in picture(rgb, valid) {
        pixels += 1;
        for (s, &v) in sums.iter_mut().zip(p) {
            *s += u64::from(v);
        }
    }
    let pixels = pixels.max(1);
    sums.map(|s| ((2 * s + pixels) / (2 * pixels)) as u8)
}

/// Uniform bytes from a seeded stream, eight per draw.
struct NoiseBytes {
    stream: Stream,
    bytes: [u8; 8],
    used: usize,
}

impl NoiseBytes {
    fn new(seed: u64, rect: usize) -> Self {
        NoiseBytes {
            stream: Stream::new(seed, Scope::Sample(rect as u64), FILL_STREAM),
            bytes: [0; 8],
            used: 8,
        }
    }

    fn byte(&mut self) -> u8 {
        if self.used == 8 {
            self.bytes = self.stream.next_u64().to_le_bytes();
            self.used = 0;
        }
        self.used += 1;
        self.bytes[self.used - 1]
    }

    fn pixel(&mut self) -> [u8; 3] {
        [self.byte(), self.byte(), self.byte()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::{test_image, test_stream};

    #[test]
    fn rectangles_follow_the_declared_area_and_aspect_distributions() {
        let (w, h) = (960, 960);
        let spec = ErasingSpec {
            count: Range::Fixed(1.0),
            area: Range::Span([0.02, 0.05]),
            aspect: Range::Span([0.3, 3.3]),
            fill: Fill::Black,
            probability: 1.0,
        };
        let mut s = test_stream("erase");
        let rects: Vec<Rect> = (0..4000)
            .flat_map(|_| spec.draw(&mut s, w, h).unwrap().rects)
            .collect();
        assert_eq!(rects.len(), 4000, "every draw fits on a large image");
        let n = rects.len() as f64;
        let areas: Vec<f64> = rects
            .iter()
            .map(|r| f64::from(r.width * r.height) / (w * h) as f64)
            .collect();
        let log_aspects: Vec<f64> = rects
            .iter()
            .map(|r| (f64::from(r.height) / f64::from(r.width)).ln())
            .collect();
        let mean_area = areas.iter().sum::<f64>() / n;
        let mean_log = log_aspects.iter().sum::<f64>() / n;
        // Uniform area: mean 0.035; log-uniform aspect: mean log (ln 0.3 + ln 3.3)/2.
        assert!((mean_area - 0.035).abs() < 0.0007, "{mean_area}");
        assert!(
            (mean_log - 0.5 * (0.3f64.ln() + 3.3f64.ln())).abs() < 0.03,
            "{mean_log}"
        );
        // Rounding h and w moves the area and aspect only slightly off their ranges.
        assert!(areas.iter().all(|a| (0.0195..0.0505).contains(a)));
        assert!(
            log_aspects
                .iter()
                .all(|a| (0.28f64.ln()..3.5f64.ln()).contains(a))
        );
        // Positions are uniform: the mean left edge is half the free width on average.
        let left = rects
            .iter()
            .map(|r| f64::from(r.left) / f64::from(960 - r.width));
        assert!((left.sum::<f64>() / n - 0.5).abs() < 0.02);
    }

    #[test]
    fn rectangles_that_never_fit_are_left_out() {
        let spec = ErasingSpec {
            count: Range::Fixed(3.0),
            area: Range::Fixed(0.9),
            aspect: Range::Fixed(4.0),
            fill: Fill::Black,
            probability: 1.0,
        };
        let drawn = spec.draw(&mut test_stream("too big"), 100, 100).unwrap();
        assert!(drawn.rects.is_empty());
    }

    #[test]
    fn the_mask_marks_exactly_the_filled_pixels() {
        let (w, h) = (40, 30);
        let original = test_image(w, h, "erase fill");
        for fill in [Fill::Black, Fill::Mean, Fill::Noise] {
            let spec = ErasingSpec {
                count: Range::Fixed(3.0),
                area: Range::Span([0.05, 0.1]),
                aspect: Range::Span([0.5, 2.0]),
                fill,
                probability: 1.0,
            };
            let erasing = spec.draw(&mut test_stream("erase mask"), w, h).unwrap();
            assert_eq!(erasing.rects.len(), 3);
            let mut img = original.clone();
            let mask = erase(&mut img, w, h, &erasing, None);
            let inside = |i: u32, j: u32| {
                erasing.rects.iter().any(|r| {
                    (r.top..r.top + r.height).contains(&i)
                        && (r.left..r.left + r.width).contains(&j)
                })
            };
            let mean = mean_colour(&original, None);
            for (k, (&m, (out, inp))) in mask
                .iter()
                .zip(img.chunks_exact(3).zip(original.chunks_exact(3)))
                .enumerate()
            {
                let (i, j) = ((k / w) as u32, (k % w) as u32);
                assert_eq!(m == 255, inside(i, j));
                match (m, fill) {
                    (0, _) => assert_eq!(out, inp),
                    (_, Fill::Black) => assert_eq!(out, [0, 0, 0]),
                    (_, Fill::Mean) => assert_eq!(out, mean),
                    (_, Fill::Noise) => {}
                }
            }
        }
    }

    #[test]
    fn noise_fill_is_uniform_and_reproducible() {
        let (w, h) = (200, 200);
        let erasing = Erasing {
            rects: vec![Rect {
                top: 0,
                left: 0,
                height: 199,
                width: 199,
            }],
            fill: Filled::Noise { seed: 5 },
        };
        let mut a = vec![0u8; w * h * 3];
        erase(&mut a, w, h, &erasing, None);
        let mut b = vec![9u8; w * h * 3];
        erase(&mut b, w, h, &erasing, None);
        assert_eq!(a[..3 * 199], b[..3 * 199]);
        let n = 199 * 199 * 3;
        let mean = a
            .chunks_exact(3 * w)
            .flat_map(|r| &r[..3 * 199])
            .map(|&v| f64::from(v));
        assert!((mean.sum::<f64>() / f64::from(n) - 127.5).abs() < 0.6);
    }

    #[test]
    fn the_paper_spec_validates_and_bad_values_are_named() {
        ErasingSpec::paper().validate("erase").unwrap();
        let bad = ErasingSpec {
            aspect: Range::Span([0.0, 0.3]),
            ..ErasingSpec::paper()
        };
        assert!(bad.validate("erase").unwrap_err().contains("erase.aspect"));
        assert_eq!(mean_colour(&[0, 10, 255, 1, 11, 254], None), [1, 11, 255]);
        // Pixels without picture are left out of the mean.
        let valid = [255, 0];
        assert_eq!(
            mean_colour(&[0, 10, 255, 1, 11, 254], Some(&valid)),
            [0, 10, 255]
        );
    }
}
