//! JPEG re-compression: encode at a quality and decode again, in memory.
//!
//! The bytes must be the same on every x86-64 CPU, so both halves were chosen by reading
//! their source (versions pinned in `Cargo.lock`):
//!
//! * **Encoder: `image` 0.25.10's `JpegEncoder`** — baseline JPEG (ITU-T T.81 | ISO/IEC
//!   10918-1), 4:4:4 (no chroma subsampling), the standard's Annex K tables scaled by the IJG
//!   quality rule, integer RGB→YCbCr and integer forward DCT (the IJG `jfdctint` algorithm),
//!   quantisation by one IEEE-754 single-precision division and `round` per coefficient. No
//!   SIMD, no runtime CPU detection, nothing that is not correctly rounded: deterministic.
//! * **Decoder: `jpeg-decoder` 0.3.2 with its `platform_independent` feature** — not the
//!   `image` crate's decoder, `zune-jpeg`. zune-jpeg 0.5.15 picks AVX2 IDCT, upsampling and
//!   colour-conversion routines at run time (`is_x86_feature_detected!("avx2")` in
//!   `zune-core`'s `DecoderOptions::use_avx2`). Read side by side, its AVX2 IDCT and colour
//!   conversion do the same wrapping `i32` arithmetic as the scalar code for in-range data,
//!   so in practice they agree, but that is a property of one version, not a promise, and it
//!   cannot be switched off: `DecoderOptions::set_use_unsafe(false)` clears only
//!   `zune_use_unsafe`, while `use_avx2()` tests `zune_use_avx2 | zune_use_unsafe` and the
//!   AVX2 flag is on by default with no public setter; building zune-jpeg without its `x86`
//!   feature is impossible while `image` enables its default features. jpeg-decoder's own
//!   changelog (0.2.2) states that its SSE3 paths are *not* bit-for-bit equal to its scalar
//!   code and that `platform_independent` makes the output the same on all platforms; with
//!   that feature the crate is `#![forbid(unsafe_code)]`, so no intrinsic can run at all. What
//!   remains is integer IDCT (stb_image's) and integer YCbCr→RGB (fixed point with 20
//!   fractional bits, constants from one f32 multiplication each); 4:4:4 files need no
//!   upsampling. Its rayon workers split the work by component and row and write
//!   each to its own place, so the result does not depend on the thread count either.

use super::draw::{Range, check_integers, check_one, happens};
use super::rgb_pixels;
use crate::seeds::Stream;
use serde::{Deserialize, Serialize};

/// Bounds of the quality.
const QUALITY: [f64; 2] = [1.0, 100.0];

/// A JPEG re-compression drawn for one view.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Jpeg {
    /// IJG quality, 1 (worst) to 100 (best), as in libjpeg and PIL.
    pub quality: u8,
}

/// Where JPEG qualities are drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct JpegSpec {
    /// Range of the quality, integers within [1, 100], each equally likely.
    pub quality: Range,
    /// Probability of applying it to a view, in [0, 1].
    pub probability: f64,
}

impl JpegSpec {
    /// Checks the range (which must hold a whole quality) and probability; the error names
    /// the parameter by its path under `at` and shows its value.
    pub fn validate(&self, at: &str) -> Result<(), String> {
        check_one(at, "quality", &self.quality, QUALITY, self.probability)?;
        check_integers(&format!("{at}.quality"), &self.quality)
    }

    /// Draws one view's quality, or `None` when the probability says skip.
    pub fn draw(&self, stream: &mut Stream) -> Option<Jpeg> {
        happens(stream, self.probability).then(|| Jpeg {
            quality: self.quality.draw_integer(stream).clamp(1, 100) as u8,
        })
    }
}

/// The JPEG file of an sRGB8 image at `quality` (baseline, 4:4:4, JFIF).
pub fn encode(rgb: &[u8], width: usize, height: usize, quality: u8) -> Result<Vec<u8>, String> {
    rgb_pixels(rgb, width, height);
    let too_large = || format!("a {width}×{height} image exceeds JPEG's 65535-pixel sides");
    let (w, h) = (
        u16::try_from(width).map_err(|_| too_large())?,
        u16::try_from(height).map_err(|_| too_large())?,
    );
    let mut file = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut file, quality)
        .encode(rgb, w.into(), h.into(), image::ExtendedColorType::Rgb8)
        .map_err(|e| format!("JPEG encoding failed: {e}"))?;
    Ok(file)
}

/// The RGB pixels of a baseline colour JPEG file (platform-independent decoder).
pub fn decode(file: &[u8]) -> Result<Vec<u8>, String> {
    let mut decoder = jpeg_decoder::Decoder::new(file);
    let pixels = decoder
        .decode()
        .map_err(|e| format!("JPEG decoding failed: {e}"))?;
    match decoder.info().map(|info| info.pixel_format) {
        Some(jpeg_decoder::PixelFormat::RGB24) => Ok(pixels),
        other => Err(format!("JPEG decoding gave {other:?}, not RGB")),
    }
}

/// Re-compresses an sRGB8 image in place: encode at `params.quality`, decode.
pub fn jpeg(rgb: &mut [u8], width: usize, height: usize, params: &Jpeg) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Ok(());
    }
    let pixels = decode(&encode(rgb, width, height, params.quality)?)?;
    rgb.copy_from_slice(&pixels);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::{on_threads, test_stream, textured_image};

    fn psnr(a: &[u8], b: &[u8]) -> f64 {
        let mse = a
            .iter()
            .zip(b)
            .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
            .sum::<f64>()
            / a.len() as f64;
        10.0 * (255.0 * 255.0 / mse).log10()
    }

    #[test]
    fn quality_raises_the_psnr_of_the_round_trip() {
        let (w, h) = (96, 80);
        let original = textured_image(w, h);
        let mut last = 0.0;
        for quality in [10, 30, 60, 90, 100] {
            let mut img = original.clone();
            jpeg(&mut img, w, h, &Jpeg { quality }).unwrap();
            let p = psnr(&original, &img);
            assert!(p > last + 1.0, "quality {quality}: {p} dB after {last} dB");
            last = p;
        }
        assert!(last > 40.0, "{last}");
    }

    #[test]
    fn the_round_trip_gives_the_same_bytes_twice() {
        let (w, h) = (53, 37);
        let original = textured_image(w, h);
        let run = |threads| {
            let mut img = original.clone();
            on_threads(threads, || jpeg(&mut img, w, h, &Jpeg { quality: 55 })).unwrap();
            img
        };
        let first = run(1);
        assert_eq!(first, run(1));
        assert_eq!(first, run(2));
        assert_ne!(first, original);
        // The file itself is the same too.
        assert_eq!(encode(&original, w, h, 55), encode(&original, w, h, 55));
    }

    #[test]
    fn a_flat_grey_survives_any_quality() {
        let mut img = vec![128u8; 16 * 16 * 3];
        jpeg(&mut img, 16, 16, &Jpeg { quality: 5 }).unwrap();
        assert!(img.iter().all(|&v| v.abs_diff(128) <= 1), "{:?}", &img[..6]);
    }

    #[test]
    fn draws_give_integer_qualities_in_range() {
        let mut s = test_stream("jpeg");
        let spec = JpegSpec {
            quality: Range::Span([30.0, 35.0]),
            probability: 1.0,
        };
        spec.validate("jpeg").unwrap();
        let mut seen = [false; 6];
        for _ in 0..300 {
            seen[usize::from(spec.draw(&mut s).unwrap().quality - 30)] = true;
        }
        assert!(seen.iter().all(|&x| x));
        let bad = JpegSpec {
            quality: Range::Fixed(0.0),
            probability: 1.0,
        };
        assert!(bad.validate("jpeg").unwrap_err().contains("jpeg.quality"));
    }
}
