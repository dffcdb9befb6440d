//! Tonal operations: exposure and vignetting act on linear light (decoded with the sRGB
//! transfer function, scaled, re-encoded to the nearest code), gamma on the encoded values
//! as torchvision's `adjust_gamma` does.

use super::draw::{Range, happens, one_parameter_spec};
use super::{apply_table, rgb_pixels, srgb};
use crate::seeds::Stream;
use serde::{Deserialize, Serialize};

/// Bounds of the exposure change, stops.
const STOPS: [f64; 2] = [-16.0, 16.0];
/// Bounds of the gamma exponent.
const GAMMA: [f64; 2] = [0.05, 20.0];
/// Bounds of the vignetting strength.
const STRENGTH: [f64; 2] = [0.0, 0.99];

/// An exposure change drawn for one view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Exposure {
    /// Exposure change, stops: linear light is multiplied by 2^stops, then clipped at white.
    pub stops: f64,
}

/// Where exposure changes are drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ExposureSpec {
    /// Range of the exposure change, stops, within [−16, 16].
    pub stops: Range,
    /// Probability of applying it to a view, in [0, 1].
    pub probability: f64,
}

one_parameter_spec!(ExposureSpec, Exposure { stops }, STOPS);

/// Multiplies the linear light of an sRGB8 image by 2^stops, in place.
pub fn exposure(rgb: &mut [u8], width: usize, height: usize, params: &Exposure) {
    rgb_pixels(rgb, width, height);
    let gain = libm::exp2(params.stops);
    let table: [u8; 256] =
        std::array::from_fn(|k| srgb::encode((f64::from(srgb::decode(k as u8)) * gain) as f32));
    apply_table(rgb, &table);
}

/// A gamma curve drawn for one view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Gamma {
    /// Exponent applied to the encoded values scaled to [0, 1], dimensionless, > 0
    /// (1 = unchanged; > 1 darkens the mid-tones).
    pub gamma: f64,
}

/// Where gamma curves are drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct GammaSpec {
    /// Range of the exponent, dimensionless, within [0.05, 20].
    pub gamma: Range,
    /// Probability of applying it to a view, in [0, 1].
    pub probability: f64,
}

one_parameter_spec!(GammaSpec, Gamma { gamma }, GAMMA);

/// torchvision's `adjust_gamma` (gain 1) in place: x ← x^γ on values scaled to [0, 1], back
/// to 8 bits as `convert_image_dtype` does, trunc(x · 255.999).
pub fn gamma(rgb: &mut [u8], width: usize, height: usize, params: &Gamma) {
    rgb_pixels(rgb, width, height);
    let table: [u8; 256] = std::array::from_fn(|k| {
        let x = libm::pow(k as f64 / 255.0, params.gamma).clamp(0.0, 1.0);
        (x * 255.999) as u8
    });
    apply_table(rgb, &table);
}

/// A vignetting drawn for one view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Vignette {
    /// Fraction of the linear light lost at the image corners, in [0, 1); the falloff is the
    /// cos⁴ law of a pinhole whose focal length makes the corners lose exactly this much.
    pub strength: f64,
}

/// Where vignetting is drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct VignetteSpec {
    /// Range of the light lost at the corners, fraction within [0, 0.99].
    pub strength: Range,
    /// Probability of applying it to a view, in [0, 1].
    pub probability: f64,
}

one_parameter_spec!(VignetteSpec, Vignette { strength }, STRENGTH);

/// Relative illumination at ρ (distance from the image centre over the half-diagonal):
/// cos⁴ of the field angle, (1 + c·ρ²)⁻², with c chosen so that the corners (ρ = 1) keep
/// 1 − strength of their light.
pub fn vignette_gain(strength: f64, rho: f64) -> f64 {
    let c = 1.0 / (1.0 - strength).sqrt() - 1.0;
    let cos2 = 1.0 / (1.0 + c * rho * rho);
    cos2 * cos2
}

/// Darkens an sRGB8 image towards its corners in linear light, in place. The centre is the
/// image centre (width/2, height/2) with pixel centres at +0.5.
pub fn vignette(rgb: &mut [u8], width: usize, height: usize, params: &Vignette) {
    rgb_pixels(rgb, width, height);
    let (cx, cy) = (0.5 * width as f64, 0.5 * height as f64);
    let inv_half_diagonal = 1.0 / (cx * cx + cy * cy).sqrt();
    for (i, row) in rgb.chunks_exact_mut(3 * width).enumerate() {
        let dy = i as f64 + 0.5 - cy;
        for (j, p) in row.chunks_exact_mut(3).enumerate() {
            let dx = j as f64 + 0.5 - cx;
            let rho = (dx * dx + dy * dy).sqrt() * inv_half_diagonal;
            let gain = vignette_gain(params.strength, rho) as f32;
            for v in p.iter_mut() {
                *v = srgb::encode(srgb::decode(*v) * gain);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::{assert_frequency, assert_uniform, test_image, test_stream};

    #[test]
    fn exposure_scales_linear_light_by_two_to_the_stops() {
        let mut img = vec![10u8, 60, 128, 200, 255, 0];
        exposure(&mut img, 2, 1, &Exposure { stops: -1.0 });
        for (out, input) in img.iter().zip([10u8, 60, 128, 200, 255, 0]) {
            let want = srgb::to_encoded(0.5 * srgb::to_linear(f64::from(input) / 255.0));
            assert_eq!(*out, (want * 255.0).round() as u8, "{input}");
        }
        // One stop up then down returns mid-tones (nothing clipped) to within a level.
        let mut img = vec![100u8; 3];
        exposure(&mut img, 1, 1, &Exposure { stops: 1.0 });
        exposure(&mut img, 1, 1, &Exposure { stops: -1.0 });
        assert!(img.iter().all(|v| v.abs_diff(100) <= 1), "{img:?}");
        let original = test_image(5, 4, "exposure");
        let mut same = original.clone();
        exposure(&mut same, 5, 4, &Exposure { stops: 0.0 });
        assert_eq!(same, original);
    }

    #[test]
    fn gamma_follows_torchvision_adjust_gamma() {
        let mut img = vec![0u8, 64, 128, 255, 1, 200];
        gamma(&mut img, 2, 1, &Gamma { gamma: 2.0 });
        // (64/255)² · 255.999 = 16.13 → 16; (128/255)² · 255.999 = 64.50 → 64;
        // (200/255)² · 255.999 = 157.47 → 157.
        assert_eq!(img, vec![0, 16, 64, 255, 0, 157]);
        let original = test_image(5, 4, "gamma");
        let mut same = original.clone();
        gamma(&mut same, 5, 4, &Gamma { gamma: 1.0 });
        assert_eq!(same, original);
    }

    #[test]
    fn vignetting_keeps_the_centre_and_darkens_the_corners_by_the_strength() {
        assert_eq!(vignette_gain(0.4, 0.0), 1.0);
        assert!((vignette_gain(0.4, 1.0) - 0.6).abs() < 1e-12);
        // cos⁴ law: with tan θ = ρ·√c, the gain is cos⁴ θ.
        let c = 1.0 / 0.6f64.sqrt() - 1.0;
        let theta = (0.5 * c.sqrt()).atan();
        assert!((vignette_gain(0.4, 0.5) - theta.cos().powi(4)).abs() < 1e-12);
        let (w, h) = (64, 48);
        let mut img = vec![180u8; w * h * 3];
        vignette(&mut img, w, h, &Vignette { strength: 0.4 });
        let at = |i: usize, j: usize| img[3 * (i * w + j)];
        assert_eq!(at(h / 2, w / 2), 180);
        let corner = srgb::decode(at(0, 0)) / srgb::decode(180);
        // The corner pixel centre is at ρ slightly below 1.
        let rho = ((31.5f64).powi(2) + 23.5f64.powi(2)).sqrt() / (32.0f64.hypot(24.0));
        assert!(
            (f64::from(corner) - vignette_gain(0.4, rho)).abs() < 0.01,
            "{corner}"
        );
        assert!(at(0, 0) < at(h / 4, w / 4) && at(h / 4, w / 4) < at(h / 2, w / 2));
    }

    #[test]
    fn draws_stay_in_range_and_respect_the_probability() {
        let mut s = test_stream("tone");
        let spec = ExposureSpec {
            stops: Range::Span([-1.0, 0.5]),
            probability: 0.5,
        };
        spec.validate("exposure").unwrap();
        let drawn: Vec<_> = (0..4000).filter_map(|_| spec.draw(&mut s)).collect();
        assert!((1850..2150).contains(&drawn.len()), "{}", drawn.len());
        assert!(drawn.iter().all(|e| (-1.0..0.5).contains(&e.stops)));
        let g = GammaSpec {
            gamma: Range::Fixed(0.0),
            probability: 1.0,
        };
        assert!(g.validate("gamma").unwrap_err().contains("gamma.gamma"));
        let v = VignetteSpec {
            strength: Range::Span([0.1, 0.3]),
            probability: 1.0,
        };
        assert!((0.1..0.3).contains(&v.draw(&mut s).unwrap().strength));
    }

    #[test]
    fn drawn_values_follow_the_declared_ranges_and_probabilities() {
        let mut s = test_stream("tone draws");
        let n = 5000;
        let exposure = ExposureSpec {
            stops: Range::Span([-1.0, 0.5]),
            probability: 0.3,
        };
        let gamma = GammaSpec {
            gamma: Range::Span([0.8, 1.25]),
            probability: 0.7,
        };
        let vignette = VignetteSpec {
            strength: Range::Span([0.1, 0.5]),
            probability: 1.0,
        };
        let stops: Vec<f64> = (0..n)
            .filter_map(|_| exposure.draw(&mut s).map(|e| e.stops))
            .collect();
        assert_frequency(stops.len(), n, 0.3, "exposure.probability");
        assert_uniform(&stops, (-1.0, 0.5), "exposure.stops");
        let gammas: Vec<f64> = (0..n)
            .filter_map(|_| gamma.draw(&mut s).map(|g| g.gamma))
            .collect();
        assert_frequency(gammas.len(), n, 0.7, "gamma.probability");
        assert_uniform(&gammas, (0.8, 1.25), "gamma.gamma");
        let strengths: Vec<f64> = (0..n)
            .filter_map(|_| vignette.draw(&mut s).map(|v| v.strength))
            .collect();
        assert_eq!(strengths.len(), n);
        assert_uniform(&strengths, (0.1, 0.5), "vignette.strength");
    }
}
