//! Colour jitter with the semantics of torchvision's `ColorJitter` on 8-bit tensors
//! (`torchvision/transforms/transforms.py` and `_functional_tensor.py`).
//!
//! Like torchvision it works on the stored, gamma-encoded sRGB values scaled to [0, 255]
//! (no conversion to linear light), each operation in single precision with the factor
//! rounded to `f32`, and converts back to 8 bits after every operation by clamping to
//! [0, 255] and truncating towards zero (`Tensor.to(torch.uint8)`), so the order matters:
//!
//! * `_blend(a, b, r) = clamp(r·a + (1 − r)·b, 0, 255)`, then truncated;
//! * brightness: blend with black;
//! * contrast: blend with the mean over the image of the grayscale image
//!   `gray = trunc(0.2989·R + 0.587·G + 0.114·B)` (torchvision accumulates the mean in
//!   float32; we take the exact mean, a difference below 10⁻⁵ levels);
//! * saturation: blend with each pixel's own `gray`;
//! * hue: values / 255 → HSV (`_rgb2hsv`), `h ← (h + shift) mod 1`, → RGB (`_hsv2rgb`), then
//!   `trunc(x · 255.999)` (`convert_image_dtype`'s `max + 1 − 10⁻³`).
//!
//! An operation whose factor is its identity (1, or a hue shift of 0) is skipped, as
//! torchvision skips a range that is the single identity value.

use super::draw::{Range, check_probability, check_range, happens};
use super::{apply_table, picture, rgb_pixels};
use crate::seeds::Stream;
use serde::{Deserialize, Serialize};

/// One of the four colour operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ColourOp {
    /// Multiply by the brightness factor (blend with black).
    Brightness,
    /// Blend with the image's mean gray level.
    Contrast,
    /// Blend with each pixel's gray level.
    Saturation,
    /// Rotate the HSV hue.
    Hue,
}

/// The colour jitter drawn for one view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ColourJitter {
    /// Brightness factor, dimensionless, ≥ 0 (1 = unchanged).
    pub brightness: f64,
    /// Contrast factor, dimensionless, ≥ 0 (1 = unchanged).
    pub contrast: f64,
    /// Saturation factor, dimensionless, ≥ 0 (1 = unchanged, 0 = gray).
    pub saturation: f64,
    /// Hue shift, turns in [−0.5, 0.5] (0 = unchanged, 0.5 = 180°).
    pub hue: f64,
    /// The order the four operations were applied in (drawn, as torchvision's `randperm(4)`).
    pub order: [ColourOp; 4],
}

impl ColourJitter {
    /// Parameters that change nothing.
    pub const IDENTITY: ColourJitter = ColourJitter {
        brightness: 1.0,
        contrast: 1.0,
        saturation: 1.0,
        hue: 0.0,
        order: [
            ColourOp::Brightness,
            ColourOp::Contrast,
            ColourOp::Saturation,
            ColourOp::Hue,
        ],
    };
}

/// Where colour jitter is drawn from: each factor uniform in its range, the order a uniform
/// permutation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ColourJitterSpec {
    /// Range of the brightness factor, dimensionless, within [0, ∞).
    pub brightness: Range,
    /// Range of the contrast factor, dimensionless, within [0, ∞).
    pub contrast: Range,
    /// Range of the saturation factor, dimensionless, within [0, ∞).
    pub saturation: Range,
    /// Range of the hue shift, turns within [−0.5, 0.5].
    pub hue: Range,
    /// Probability of applying the jitter to a view, in [0, 1].
    pub probability: f64,
}

impl ColourJitterSpec {
    /// The 3DGEN paper's jitter: brightness, contrast and saturation × 0.8–1.2, hue ±0.1,
    /// applied to every view.
    pub fn paper() -> Self {
        ColourJitterSpec {
            brightness: Range::Span([0.8, 1.2]),
            contrast: Range::Span([0.8, 1.2]),
            saturation: Range::Span([0.8, 1.2]),
            hue: Range::Span([-0.1, 0.1]),
            probability: 1.0,
        }
    }

    /// Checks every range; the error names the parameter by its path under `at` and shows
    /// its value.
    pub fn validate(&self, at: &str) -> Result<(), String> {
        for (field, range) in [
            ("brightness", &self.brightness),
            ("contrast", &self.contrast),
            ("saturation", &self.saturation),
        ] {
            check_range(&format!("{at}.{field}"), range, 0.0, f64::MAX)?;
        }
        check_range(&format!("{at}.hue"), &self.hue, -0.5, 0.5)?;
        check_probability(at, self.probability)
    }

    /// Draws the jitter of one view, or `None` when the probability says skip.
    pub fn draw(&self, stream: &mut Stream) -> Option<ColourJitter> {
        if !happens(stream, self.probability) {
            return None;
        }
        let mut order = ColourJitter::IDENTITY.order;
        // Fisher–Yates: every permutation equally likely.
        for i in (1..order.len()).rev() {
            order.swap(i, stream.integer(0, i as i64) as usize);
        }
        Some(ColourJitter {
            brightness: self.brightness.draw(stream),
            contrast: self.contrast.draw(stream),
            saturation: self.saturation.draw(stream),
            hue: self.hue.draw(stream),
            order,
        })
    }
}

/// Applies `jitter` in place to an sRGB8 image (3 bytes a pixel, row-major).
/// `valid` (one byte a pixel, 0 = no picture there, as a warp's border) keeps pixels without
/// picture out of the mean that contrast blends towards; None: every pixel is picture.
pub fn colour_jitter(
    rgb: &mut [u8],
    width: usize,
    height: usize,
    jitter: &ColourJitter,
    valid: Option<&[u8]>,
) {
    rgb_pixels(rgb, width, height);
    for op in jitter.order {
        match op {
            ColourOp::Brightness if jitter.brightness != 1.0 => brightness(rgb, jitter.brightness),
            ColourOp::Contrast if jitter.contrast != 1.0 => contrast(rgb, jitter.contrast, valid),
            ColourOp::Saturation if jitter.saturation != 1.0 => saturation(rgb, jitter.saturation),
            ColourOp::Hue if jitter.hue != 0.0 => hue(rgb, jitter.hue),
            _ => {}
        }
    }
}

/// torchvision's `_blend` of one 8-bit value with `other`, ratio `r` (f32 as torch computes).
fn blend(value: u8, other: f32, ratio: f32, rest: f32) -> u8 {
    (ratio * f32::from(value) + rest * other).clamp(0.0, 255.0) as u8
}

/// The blend weights (r, 1 − r) as torch rounds them: each computed in double, then f32.
fn weights(ratio: f64) -> (f32, f32) {
    (ratio as f32, (1.0 - ratio) as f32)
}

/// torchvision's `rgb_to_grayscale` of one pixel: trunc(0.2989 R + 0.587 G + 0.114 B) in f32.
pub fn gray(p: &[u8]) -> u8 {
    (0.2989f32 * f32::from(p[0]) + 0.587f32 * f32::from(p[1]) + 0.114f32 * f32::from(p[2])) as u8
}

/// `adjust_brightness`: blend with black.
pub fn brightness(rgb: &mut [u8], factor: f64) {
    let (r, rest) = weights(factor);
    apply_table(rgb, &std::array::from_fn(|v| blend(v as u8, 0.0, r, rest)));
}

/// `adjust_contrast`: blend with the mean gray level of the image (of its `valid` pixels,
/// when given: see [`colour_jitter`]).
pub fn contrast(rgb: &mut [u8], factor: f64, valid: Option<&[u8]>) {
    let (sum, pixels) = (picture(rgb, valid)).fold((0u64, 0u64), |(sum, n), p| {
        (sum + u64::from(gray(p)), n + 1)
    });
    let mean = (sum as f64 / pixels.max(1) as f64) as f32;
    let (r, rest) = weights(factor);
    apply_table(rgb, &std::array::from_fn(|v| blend(v as u8, mean, r, rest)));
}

/// `adjust_saturation`: blend every pixel with its own gray level.
pub fn saturation(rgb: &mut [u8], factor: f64) {
    let (r, rest) = weights(factor);
    for p in rgb.chunks_exact_mut(3) {
        let g = f32::from(gray(p));
        for v in p.iter_mut() {
            *v = blend(*v, g, r, rest);
        }
    }
}

/// `adjust_hue`: rotate the HSV hue by `shift` turns.
pub fn hue(rgb: &mut [u8], shift: f64) {
    let shift = shift as f32;
    for p in rgb.chunks_exact_mut(3) {
        let [r, g, b] = [p[0], p[1], p[2]].map(|v| f32::from(v) / 255.0);
        let (h, s, v) = rgb_to_hsv(r, g, b);
        let h = h + shift;
        let rotated = hsv_to_rgb(h - h.floor(), s, v);
        for (out, x) in p.iter_mut().zip(rotated) {
            *out = (x * 255.999f32) as u8;
        }
    }
}

/// torchvision's `_rgb2hsv` for one pixel, operation for operation in f32.
fn rgb_to_hsv(r: f32, g: f32, b: f32) -> (f32, f32, f32) {
    let maxc = r.max(g).max(b);
    let minc = r.min(g).min(b);
    let equal = maxc == minc;
    let cr = maxc - minc;
    let s = cr / if equal { 1.0 } else { maxc };
    let divisor = if equal { 1.0 } else { cr };
    let (rc, gc, bc) = (
        (maxc - r) / divisor,
        (maxc - g) / divisor,
        (maxc - b) / divisor,
    );
    let h = if maxc == r {
        bc - gc
    } else if maxc == g {
        2.0 + rc - bc
    } else {
        4.0 + gc - rc
    };
    // torch.fmod(h / 6 + 1, 1): the argument is positive, so fmod is x − trunc(x).
    let h = h / 6.0 + 1.0;
    (h - h.trunc(), s, maxc)
}

/// torchvision's `_hsv2rgb` for one pixel, operation for operation in f32.
fn hsv_to_rgb(h: f32, s: f32, v: f32) -> [f32; 3] {
    let i = (h * 6.0).floor();
    let f = h * 6.0 - i;
    let p = (v * (1.0 - s)).clamp(0.0, 1.0);
    let q = (v * (1.0 - s * f)).clamp(0.0, 1.0);
    let t = (v * (1.0 - s * (1.0 - f))).clamp(0.0, 1.0);
    // torchvision stacks (v, q, p, p, t, v), (t, v, v, q, p, p), (p, p, t, v, v, q) and picks
    // entry i mod 6 of each.
    let sector = (i as i32).rem_euclid(6) as usize;
    [[v, q, p, p, t, v], [t, v, v, q, p, p], [p, p, t, v, v, q]].map(|channel| channel[sector])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::{assert_uniform, test_image, test_stream};

    /// The torchvision formulas written out by hand in double precision for one pixel; the
    /// f32 implementation must agree to the 8-bit level.
    fn by_hand_blend(value: f64, other: f64, r: f64) -> u8 {
        (r * value + (1.0 - r) * other).clamp(0.0, 255.0).trunc() as u8
    }

    #[test]
    fn brightness_contrast_and_saturation_follow_the_torchvision_formulas() {
        // Two pixels: (200, 100, 50) and (10, 20, 30).
        let px = [200u8, 100, 50, 10, 20, 30];
        let gray0 = (0.2989 * 200.0 + 0.587 * 100.0 + 0.114 * 50.0f64).trunc(); // 124
        let gray1 = (0.2989 * 10.0 + 0.587 * 20.0 + 0.114 * 30.0f64).trunc(); // 18
        assert_eq!((gray(&px[..3]), gray(&px[3..])), (124, 18));

        let mut b = px;
        // Factors exact in binary, so the f32 arithmetic is exact too.
        brightness(&mut b, 1.25);
        assert_eq!(b, px.map(|v| by_hand_blend(f64::from(v), 0.0, 1.25)));
        assert_eq!(b, [250, 125, 62, 12, 25, 37]);

        let mut c = px;
        contrast(&mut c, 0.5, None);
        let mean = 0.5 * (gray0 + gray1);
        assert_eq!(c, px.map(|v| by_hand_blend(f64::from(v), mean, 0.5)));

        let mut s = px;
        saturation(&mut s, 1.5);
        for (i, g) in [gray0, gray1].into_iter().enumerate() {
            for k in 0..3 {
                let v = f64::from(px[3 * i + k]);
                assert_eq!(s[3 * i + k], by_hand_blend(v, g, 1.5));
            }
        }
    }

    #[test]
    fn hue_rotates_the_hsv_hue() {
        // Pure red turned by a third of a turn is pure green; by a half, cyan.
        let mut p = [255u8, 0, 0];
        hue(&mut p, 1.0 / 3.0);
        assert_eq!(p, [0, 255, 0]);
        let mut p = [255u8, 0, 0];
        hue(&mut p, -0.5);
        assert_eq!(p, [0, 255, 255]);
        // (200, 100, 50): h = (100 − 50)/150/6 = 1/18, s = 0.75, v = 200/255. Shifted by
        // +0.1 → h = 0.1556, sector 0: (v, t, p) with f = 6h = 0.9333 and
        // t = v(1 − s(1 − f)) = 0.745, by hand in double precision:
        let (v, s, h) = (200.0 / 255.0, 0.75, 1.0 / 18.0 + 0.1f64);
        let f = 6.0 * h;
        let expected =
            [v, v * (1.0 - s * (1.0 - f)), v * (1.0 - s)].map(|x: f64| (x * 255.999).trunc() as u8);
        let mut p = [200u8, 100, 50];
        hue(&mut p, 0.1);
        assert_eq!(p, expected);
        assert_eq!(expected, [200, 190, 50]);
    }

    #[test]
    fn identity_parameters_leave_the_image_unchanged() {
        let original = test_image(31, 17, "identity");
        let mut img = original.clone();
        colour_jitter(&mut img, 31, 17, &ColourJitter::IDENTITY, None);
        assert_eq!(img, original);
        // The formulas themselves are exact at their identity, not only skipped.
        for op in [
            brightness,
            |i: &mut [u8], f| contrast(i, f, None),
            saturation,
        ] {
            let mut img = original.clone();
            op(&mut img, 1.0);
            assert_eq!(img, original);
        }
        let mut img = original.clone();
        hue(&mut img, 0.0);
        assert_eq!(img, original);
    }

    #[test]
    fn the_order_is_applied_as_recorded() {
        let original = test_image(8, 8, "order");
        let jitter = |order| ColourJitter {
            brightness: 1.4,
            contrast: 0.6,
            saturation: 1.0,
            hue: 0.0,
            order,
        };
        use ColourOp::*;
        let mut a = original.clone();
        colour_jitter(
            &mut a,
            8,
            8,
            &jitter([Brightness, Contrast, Saturation, Hue]),
            None,
        );
        let mut by_hand = original.clone();
        brightness(&mut by_hand, 1.4);
        contrast(&mut by_hand, 0.6, None);
        assert_eq!(a, by_hand);
        let mut b = original.clone();
        colour_jitter(
            &mut b,
            8,
            8,
            &jitter([Contrast, Brightness, Saturation, Hue]),
            None,
        );
        assert_ne!(a, b);
    }

    #[test]
    fn draws_follow_the_spec() {
        let mut s = test_stream("jitter");
        let spec = ColourJitterSpec::paper();
        spec.validate("colour_jitter").unwrap();
        let mut first = [0u32; 4];
        for _ in 0..4000 {
            let j = spec.draw(&mut s).unwrap();
            assert!((0.8..1.2).contains(&j.brightness) && (-0.1..0.1).contains(&j.hue));
            let mut sorted = j.order;
            sorted.sort_by_key(|op| *op as u8);
            assert_eq!(sorted, ColourJitter::IDENTITY.order);
            first[j.order[0] as usize] += 1;
        }
        // Each operation comes first in a quarter of the permutations.
        assert!(first.iter().all(|&c| (900..1100).contains(&c)), "{first:?}");
        let never = ColourJitterSpec {
            probability: 0.0,
            ..spec
        };
        assert!(never.draw(&mut s).is_none());
        let bad = ColourJitterSpec {
            hue: Range::Fixed(0.7),
            ..spec
        };
        assert!(
            bad.validate("colour_jitter")
                .unwrap_err()
                .contains("colour_jitter.hue")
        );
    }

    #[test]
    fn every_factor_is_uniform_in_its_range_and_every_order_equally_likely() {
        let mut s = test_stream("jitter draws");
        let spec = ColourJitterSpec {
            brightness: Range::Span([0.8, 1.2]),
            contrast: Range::Span([0.5, 1.5]),
            saturation: Range::Span([0.0, 2.0]),
            hue: Range::Span([-0.1, 0.3]),
            probability: 1.0,
        };
        let n = 6000;
        let drawn: Vec<ColourJitter> = (0..n).map(|_| spec.draw(&mut s).unwrap()).collect();
        let of = |f: fn(&ColourJitter) -> f64| drawn.iter().map(f).collect::<Vec<f64>>();
        assert_uniform(&of(|j| j.brightness), (0.8, 1.2), "brightness");
        assert_uniform(&of(|j| j.contrast), (0.5, 1.5), "contrast");
        assert_uniform(&of(|j| j.saturation), (0.0, 2.0), "saturation");
        assert_uniform(&of(|j| j.hue), (-0.1, 0.3), "hue");
        // The 24 orders, each expected n/24 times: Pearson's χ² with 23 degrees of freedom
        // stays below 49.7 (its 0.1 % critical value).
        let mut counts = std::collections::BTreeMap::new();
        for j in &drawn {
            *counts.entry(j.order.map(|op| op as u8)).or_insert(0u32) += 1;
        }
        assert_eq!(counts.len(), 24);
        let expected = f64::from(n) / 24.0;
        let chi2: f64 = (counts.values())
            .map(|&c| (f64::from(c) - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 49.7, "χ² = {chi2}: {counts:?}");
    }

    #[test]
    fn contrast_blends_towards_the_mean_of_the_picture_alone() {
        // A grey picture beside pixels without picture (black, valid 0): the mean it blends
        // towards is the picture's grey, so a contrast change leaves the picture as it is.
        let mut rgb = [[100u8; 3], [100; 3], [0; 3], [0; 3]].concat();
        let valid = [255, 255, 0, 0];
        contrast(&mut rgb, 0.5, Some(&valid));
        // torchvision's gray of (100, 100, 100) is 99 (its weights sum to 0.9999).
        assert_eq!(&rgb[..6], &[by_hand_blend(100.0, 99.0, 0.5); 6]);
        let mut all = [[100u8; 3], [100; 3], [0; 3], [0; 3]].concat();
        contrast(&mut all, 0.5, None);
        assert_eq!(
            all[0],
            by_hand_blend(100.0, 49.5, 0.5),
            "black pulls the mean down"
        );
    }
}
