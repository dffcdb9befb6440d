//! Image-space augmentations: pure functions on rendered images and their label layers, and
//! the specs their parameters are drawn from.
//!
//! Owns: the photometric operations on an sRGB8 image (3 bytes a pixel, row-major, `width` ×
//! `height`) — colour jitter with torchvision's `ColorJitter` semantics ([`colour`]),
//! exposure, gamma and vignetting ([`tone`]), Gaussian and Poisson–Gaussian sensor noise
//! ([`noise`]), Gaussian, motion and defocus blur ([`blur`]), blur by a per-pixel circle of
//! confusion (a lens's depth of field, [`defocus`]), JPEG re-compression
//! ([`jpeg`]); occlusion by random erasing with its erased mask ([`erase`]); the image-space
//! similarity warp of RGB and label layers with the intrinsics and camera rotation that make
//! it exact ([`warp`]); and for each operation a parameter struct holding the values drawn
//! (serialised into each view's record) and a spec with ranges and a probability whose
//! `draw` takes every random value from a [`Stream`](crate::seeds::Stream).
//!
//! Must not touch: the rest of the crate. It imports only `crate::seeds` (streams), so the
//! pipeline can call it and nothing here knows about recipes, scenes, cameras, rendering or
//! files; deciding which augmentations run, in which order, on which stream, and exact
//! geometric augmentations by re-rendering with a changed camera belong to the caller.
//!
//! Determinism: the same input and parameters give the same bytes on every x86-64 CPU and
//! for every thread count. Transcendental functions come from `libm` (pure Rust; the
//! platform's libm may pick FMA code paths at run time), sums run in a fixed order, parallel
//! work is split by output row with each row computed on its own, and JPEG uses a decoder
//! without CPU-dependent paths (see [`jpeg`]). Nothing allocates per pixel; operations work
//! in place except the warp, which writes a new image of the output size.

pub mod blur;
pub mod colour;
pub mod defocus;
pub mod draw;
pub mod erase;
pub mod jpeg;
pub mod noise;
pub mod srgb;
pub mod tone;
pub mod warp;

pub use blur::{Blur, BlurSpec, blur};
pub use colour::{ColourJitter, ColourJitterSpec, ColourOp, colour_jitter};
pub use defocus::defocus_by_depth;
pub use draw::Range;
pub use erase::{Erasing, ErasingSpec, Fill, Filled, Rect, erase};
pub use jpeg::{Jpeg, JpegSpec, jpeg};
pub use noise::{Noise, NoiseModel, NoiseSpec, SigmaUnit, add_noise};
pub use tone::{
    Exposure, ExposureSpec, Gamma, GammaSpec, Vignette, VignetteSpec, exposure, gamma, vignette,
};
pub use warp::{
    CropSpec, Frame, Pinhole, Similarity, WarpSpec, warp_labels, warp_rgb, warp_validity,
};

/// Checks that `rgb` holds `width` × `height` pixels of 3 bytes (a caller's bug otherwise).
fn rgb_pixels(rgb: &[u8], width: usize, height: usize) {
    assert_eq!(
        rgb.len(),
        3 * width * height,
        "sRGB8 buffer of {width}×{height}"
    );
}

/// The pixels (3 bytes each) of an sRGB8 image that hold picture: those `valid` marks
/// non-zero (a warp leaves pixels without a source at 0), or every pixel when None.
fn picture<'a>(rgb: &'a [u8], valid: Option<&'a [u8]>) -> impl Iterator<Item = &'a [u8]> {
    (rgb.chunks_exact(3).enumerate())
        .filter(move |(k, _)| valid.is_none_or(|v| v[*k] != 0))
        .map(|(_, p)| p)
}

/// Maps every byte through a 256-entry table.
fn apply_table(bytes: &mut [u8], table: &[u8; 256]) {
    for v in bytes.iter_mut() {
        *v = table[usize::from(*v)];
    }
}

/// A stream for tests, named after the test.
#[cfg(test)]
fn test_stream(name: &str) -> crate::seeds::Stream {
    crate::seeds::Stream::new(0, crate::seeds::Scope::Sample(0), name)
}

/// Checks that `values` (at least 1000 draws) follow the uniform distribution on [lo, hi]:
/// all inside, mean and variance within four standard errors of (lo + hi)/2 and
/// (hi − lo)²/12, and the Kolmogorov–Smirnov distance below its 0.1 % critical value 1.95/√n.
#[cfg(test)]
fn assert_uniform(values: &[f64], (lo, hi): (f64, f64), what: &str) {
    let n = values.len() as f64;
    assert!(n >= 1000.0, "{what}: only {n} draws");
    assert!(
        values.iter().all(|v| (lo..=hi).contains(v)),
        "{what}: a draw outside [{lo}, {hi}]"
    );
    let width = hi - lo;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    // Standard errors: σ/√n for the mean; for the variance of a uniform, √((μ₄ − σ⁴)/n) with
    // μ₄ = w⁴/80 and σ⁴ = w⁴/144.
    let mean_error = width / (12.0 * n).sqrt();
    let variance_error = width * width * ((1.0 / 80.0 - 1.0 / 144.0) / n).sqrt();
    assert!(
        (mean - 0.5 * (lo + hi)).abs() < 4.0 * mean_error,
        "{what}: mean {mean} of U[{lo}, {hi}]"
    );
    assert!(
        (variance - width * width / 12.0).abs() < 4.0 * variance_error,
        "{what}: variance {variance} of U[{lo}, {hi}]"
    );
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let distance = sorted
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let cdf = (v - lo) / width;
            (cdf - i as f64 / n)
                .abs()
                .max((((i + 1) as f64) / n - cdf).abs())
        })
        .fold(0.0, f64::max);
    assert!(
        distance < 1.95 / n.sqrt(),
        "{what}: Kolmogorov–Smirnov distance {distance} from U[{lo}, {hi}]"
    );
}

/// Checks that `hits` of `n` trials is within four binomial standard deviations of n·p.
#[cfg(test)]
fn assert_frequency(hits: usize, n: usize, p: f64, what: &str) {
    let (hits, n) = (hits as f64, n as f64);
    let sd = (n * p * (1.0 - p)).sqrt();
    assert!(
        (hits - n * p).abs() <= 4.0 * sd,
        "{what}: {hits} of {n}, expected {}",
        n * p
    );
}

/// `op` run in a pool of `threads` threads.
#[cfg(test)]
fn on_threads<T: Send>(threads: usize, op: impl FnOnce() -> T + Send) -> T {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build();
    pool.expect("a thread pool").install(op)
}

/// A `width` × `height` image of uniform random bytes.
#[cfg(test)]
fn test_image(width: usize, height: usize, name: &str) -> Vec<u8> {
    let mut s = test_stream(name);
    (0..3 * width * height)
        .map(|_| s.integer(0, 255) as u8)
        .collect()
}

/// A photograph-like test image: smooth shading, sharp edges and a little texture.
#[cfg(test)]
fn textured_image(width: usize, height: usize) -> Vec<u8> {
    let mut s = test_stream("texture");
    let mut rgb = Vec::with_capacity(3 * width * height);
    for i in 0..height {
        for j in 0..width {
            let (x, y) = (j as f64 / width as f64, i as f64 / height as f64);
            let block = if (j / 16 + i / 16) % 2 == 0 {
                40.0
            } else {
                -40.0
            };
            let grain = s.uniform(-6.0, 6.0);
            for (c, phase) in [0.0, 2.0, 4.0].into_iter().enumerate() {
                let wave = 60.0 * (6.0 * x + 4.0 * y + phase).sin();
                let v = 128.0 + wave + block + grain + 10.0 * c as f64;
                rgb.push(v.round().clamp(0.0, 255.0) as u8);
            }
        }
    }
    rgb
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drawn_parameters_serialise_as_tagged_records_with_a_schema() {
        let blur = serde_json::to_value(Blur::Motion {
            length: 3.0,
            angle: 0.5,
        })
        .unwrap();
        assert_eq!(blur["kind"], "motion");
        let noise = Noise {
            model: NoiseModel::PoissonGaussian { a: 0.01, b: 1e-4 },
            seed: 9,
        };
        let noise = serde_json::to_value(noise).unwrap();
        assert_eq!(noise["model"], "poisson_gaussian");
        assert_eq!(noise["seed"], 9);
        let jitter = serde_json::to_value(ColourJitter::IDENTITY).unwrap();
        assert_eq!(jitter["order"][3], "hue");
        let spec: ErasingSpec = serde_json::from_str(
            r#"{"count": 2, "area": [0.02, 0.05], "aspect": [0.08, 0.3], "probability": 1}"#,
        )
        .unwrap();
        assert_eq!(spec.fill, Fill::Black);
        for schema in [
            schemars::schema_for!(ColourJitter),
            schemars::schema_for!(Erasing),
            schemars::schema_for!(Similarity),
            schemars::schema_for!(Noise),
            schemars::schema_for!(BlurSpec),
        ] {
            let text = serde_json::to_string(&schema).unwrap();
            assert!(text.contains("description"), "{text}");
        }
    }
}
