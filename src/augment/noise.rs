//! Sensor noise: additive Gaussian noise on the encoded values, or signal-dependent
//! Poisson–Gaussian noise in linear light.
//!
//! The Poisson–Gaussian model is that of Foi, Trimeche, Katkovnik and Egiazarian, "Practical
//! Poissonian-Gaussian noise modeling and fitting for single-image raw-data", IEEE Trans.
//! Image Processing 17(10), 2008: an observation z = y + σ(y)·ξ of the linear signal
//! y ∈ [0, 1], ξ standard normal, with variance σ²(y) = a·y + b (a: the Poissonian,
//! signal-dependent part; b: the Gaussian floor), clipped to [0, 1]. Like their
//! heteroskedastic normal approximation, the Poisson part is drawn as a normal of that
//! variance.
//!
//! The noise field is not drawn at apply time from a caller's stream: the parameters hold a
//! `seed` drawn from the view's stream, and row r of the image takes its normals from
//! `Stream::new(seed, Scope::Sample(r), "augment.noise")`. So the recorded parameters
//! re-create the exact noise, and rows are filled in parallel with the same result whatever
//! the thread count.

use super::draw::{Range, check_probability, check_range, happens};
use super::{rgb_pixels, srgb};
use crate::seeds::{Scope, Stream};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Name of the per-row streams the noise field is drawn from.
const ROW_STREAM: &str = "augment.noise";

/// The noise model and its drawn parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "model", rename_all = "snake_case")]
pub enum NoiseModel {
    /// Additive, signal-independent normal noise on the encoded 8-bit values.
    Gaussian {
        /// Standard deviation, 8-bit levels (a fraction f of full scale is 255·f levels).
        sigma: f64,
    },
    /// Foi et al. (2008) noise in linear light: variance a·y + b for linear signal y ∈ [0, 1].
    PoissonGaussian {
        /// Signal-dependent coefficient a, linear full-scale units (variance per unit signal).
        a: f64,
        /// Signal-independent variance b, linear full-scale units squared.
        b: f64,
    },
}

/// The noise drawn for one view.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Noise {
    /// The model (`"model": "gaussian"` or `"poisson_gaussian"`) and its parameters, inline.
    #[serde(flatten)]
    pub model: NoiseModel,
    /// Seed of the noise field (row r uses the stream keyed by this seed, row r and
    /// "augment.noise").
    pub seed: u64,
}

/// How a Gaussian σ is given in a spec.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SigmaUnit {
    /// 8-bit levels (0–255).
    #[default]
    Levels,
    /// A fraction of full scale (1 = 255 levels).
    Fraction,
}

/// Where noise is drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "model", rename_all = "snake_case")]
pub enum NoiseSpec {
    /// Additive Gaussian noise on the encoded values.
    Gaussian {
        /// Range of the standard deviation, in `unit`s: within [0, 255] levels, or [0, 1] as
        /// a fraction.
        sigma: Range,
        /// Unit of `sigma`: 8-bit levels (default) or a fraction of full scale.
        #[serde(default)]
        unit: SigmaUnit,
        /// Probability of applying it to a view, in [0, 1].
        probability: f64,
    },
    /// Poisson–Gaussian noise in linear light (Foi et al. 2008).
    PoissonGaussian {
        /// Range of the signal-dependent coefficient a, linear full-scale units, within [0, 1].
        a: Range,
        /// Range of the constant variance b, linear full-scale units squared, within [0, 1].
        b: Range,
        /// Probability of applying it to a view, in [0, 1].
        probability: f64,
    },
}

impl NoiseSpec {
    /// Checks every range; the error names the parameter by its path under `at` and shows
    /// its value.
    pub fn validate(&self, at: &str) -> Result<(), String> {
        match self {
            NoiseSpec::Gaussian {
                sigma,
                unit,
                probability,
            } => {
                // At most full scale, in the unit given.
                let most = if *unit == SigmaUnit::Fraction {
                    1.0
                } else {
                    255.0
                };
                check_range(&format!("{at}.sigma"), sigma, 0.0, most)?;
                check_probability(at, *probability)
            }
            NoiseSpec::PoissonGaussian { a, b, probability } => {
                check_range(&format!("{at}.a"), a, 0.0, 1.0)?;
                check_range(&format!("{at}.b"), b, 0.0, 1.0)?;
                check_probability(at, *probability)
            }
        }
    }

    /// Draws one view's noise, or `None` when the probability says skip.
    pub fn draw(&self, stream: &mut Stream) -> Option<Noise> {
        let model = match *self {
            NoiseSpec::Gaussian {
                sigma,
                unit,
                probability,
            } => {
                let scale = if unit == SigmaUnit::Fraction {
                    255.0
                } else {
                    1.0
                };
                happens(stream, probability).then(|| NoiseModel::Gaussian {
                    sigma: sigma.draw(stream) * scale,
                })
            }
            NoiseSpec::PoissonGaussian { a, b, probability } => {
                happens(stream, probability).then(|| NoiseModel::PoissonGaussian {
                    a: a.draw(stream),
                    b: b.draw(stream),
                })
            }
        }?;
        Some(Noise {
            model,
            seed: stream.next_u64(),
        })
    }
}

/// Standard normal deviates by the Box–Muller transform, two per pair of uniforms, with
/// `libm` so that the values are the same on every CPU.
pub struct Normals {
    stream: Stream,
    spare: Option<f64>,
}

impl Normals {
    /// Normals drawn from `stream`.
    pub fn new(stream: Stream) -> Self {
        Normals {
            stream,
            spare: None,
        }
    }

    /// The next standard normal deviate.
    pub fn sample(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let radius = libm::sqrt(-2.0 * libm::log(1.0 - self.stream.unit()));
        let (sin, cos) = libm::sincos(std::f64::consts::TAU * self.stream.unit());
        self.spare = Some(radius * sin);
        radius * cos
    }
}

/// Adds `noise` to an sRGB8 image in place.
pub fn add_noise(rgb: &mut [u8], width: usize, height: usize, noise: &Noise) {
    rgb_pixels(rgb, width, height);
    if width == 0 {
        return;
    }
    rgb.par_chunks_mut(3 * width)
        .enumerate()
        .for_each(|(row, values)| {
            let stream = Stream::new(noise.seed, Scope::Sample(row as u64), ROW_STREAM);
            let mut normals = Normals::new(stream);
            match noise.model {
                NoiseModel::Gaussian { sigma } => gaussian_row(values, sigma, &mut normals),
                NoiseModel::PoissonGaussian { a, b } => {
                    poisson_gaussian_row(values, a, b, &mut normals)
                }
            }
        });
}

fn gaussian_row(values: &mut [u8], sigma: f64, normals: &mut Normals) {
    for v in values.iter_mut() {
        let z = f64::from(*v) + sigma * normals.sample();
        *v = z.round().clamp(0.0, 255.0) as u8;
    }
}

fn poisson_gaussian_row(values: &mut [u8], a: f64, b: f64, normals: &mut Normals) {
    for v in values.iter_mut() {
        let y = f64::from(srgb::decode(*v));
        let sigma = (a * y + b).max(0.0).sqrt();
        *v = srgb::encode((y + sigma * normals.sample()) as f32);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::{assert_frequency, assert_uniform, on_threads, test_stream};

    fn moments(values: impl Iterator<Item = f64>) -> (f64, f64) {
        let (mut n, mut sum, mut sum2) = (0.0, 0.0, 0.0);
        for v in values {
            n += 1.0;
            sum += v;
            sum2 += v * v;
        }
        let mean = sum / n;
        (mean, sum2 / n - mean * mean)
    }

    #[test]
    fn normals_have_zero_mean_and_unit_variance() {
        let mut normals = Normals::new(test_stream("normals"));
        let (mean, var) = moments((0..200_000).map(|_| normals.sample()));
        assert!(
            mean.abs() < 0.01 && (var - 1.0).abs() < 0.015,
            "{mean} {var}"
        );
    }

    #[test]
    fn gaussian_noise_has_the_drawn_sigma() {
        let (w, h) = (400, 300);
        let mut img = vec![128u8; w * h * 3];
        let noise = Noise {
            model: NoiseModel::Gaussian { sigma: 10.0 },
            seed: 7,
        };
        add_noise(&mut img, w, h, &noise);
        let (mean, var) = moments(img.iter().map(|&v| f64::from(v)));
        // Rounding to levels adds 1/12 to the variance.
        assert!((mean - 128.0).abs() < 0.1, "{mean}");
        assert!((var / (100.0 + 1.0 / 12.0) - 1.0).abs() < 0.02, "{var}");
    }

    #[test]
    fn poisson_gaussian_noise_has_variance_a_y_plus_b_in_linear_light() {
        let (w, h) = (400, 300);
        let (a, b) = (0.01, 0.0004);
        for code in [128u8, 200] {
            let mut img = vec![code; w * h * 3];
            let noise = Noise {
                model: NoiseModel::PoissonGaussian { a, b },
                seed: 11,
            };
            add_noise(&mut img, w, h, &noise);
            let y = f64::from(srgb::decode(code));
            let (mean, var) = moments(img.iter().map(|&v| f64::from(srgb::decode(v))));
            assert!((mean - y).abs() < 0.002, "{code}: {mean} vs {y}");
            assert!((var / (a * y + b) - 1.0).abs() < 0.04, "{code}: {var}");
        }
    }

    #[test]
    fn the_noise_field_depends_on_the_seed_only() {
        let (w, h) = (50, 40);
        let noise = |seed| Noise {
            model: NoiseModel::Gaussian { sigma: 5.0 },
            seed,
        };
        let run = |threads: usize, seed| {
            let mut img = vec![100u8; w * h * 3];
            on_threads(threads, || add_noise(&mut img, w, h, &noise(seed)));
            img
        };
        assert_eq!(run(1, 3), run(2, 3));
        assert_ne!(run(1, 3), run(1, 4));
    }

    #[test]
    fn draws_convert_fractions_to_levels() {
        let mut s = test_stream("noise spec");
        let spec = NoiseSpec::Gaussian {
            sigma: Range::Fixed(0.02),
            unit: SigmaUnit::Fraction,
            probability: 1.0,
        };
        spec.validate("noise").unwrap();
        let drawn = spec.draw(&mut s).unwrap();
        assert_eq!(
            drawn.model,
            NoiseModel::Gaussian {
                sigma: 0.02 * 255.0
            }
        );
        let pg = NoiseSpec::PoissonGaussian {
            a: Range::Span([0.0, 0.01]),
            b: Range::Fixed(-1.0),
            probability: 1.0,
        };
        assert!(pg.validate("noise").unwrap_err().contains("noise.b"));
    }

    /// The σ of drawn Gaussian noise.
    fn sigma(noise: &Noise) -> f64 {
        match noise.model {
            NoiseModel::Gaussian { sigma } => sigma,
            NoiseModel::PoissonGaussian { .. } => panic!("not Gaussian: {noise:?}"),
        }
    }

    #[test]
    fn drawn_parameters_follow_the_declared_ranges_and_probabilities() {
        let mut s = test_stream("noise draws");
        let n = 4000;
        let draws = |spec: NoiseSpec, s: &mut Stream| -> Vec<Noise> {
            (0..n).filter_map(|_| spec.draw(s)).collect()
        };
        let gaussian = |sigma: [f64; 2], unit, probability| NoiseSpec::Gaussian {
            sigma: Range::Span(sigma),
            unit,
            probability,
        };
        let levels = draws(gaussian([2.0, 8.0], SigmaUnit::Levels, 0.5), &mut s);
        assert_frequency(levels.len(), n, 0.5, "noise.probability");
        let sigmas: Vec<f64> = levels.iter().map(sigma).collect();
        assert_uniform(&sigmas, (2.0, 8.0), "noise.sigma in levels");
        // A fraction of full scale is drawn uniformly in its own unit, recorded in levels.
        let fraction = draws(gaussian([0.01, 0.03], SigmaUnit::Fraction, 1.0), &mut s);
        let fractions: Vec<f64> = fraction.iter().map(|d| sigma(d) / 255.0).collect();
        assert_uniform(&fractions, (0.01, 0.03), "noise.sigma as a fraction");
        let pg = draws(
            NoiseSpec::PoissonGaussian {
                a: Range::Span([0.001, 0.01]),
                b: Range::Span([1e-5, 1e-4]),
                probability: 1.0,
            },
            &mut s,
        );
        let (a, b): (Vec<f64>, Vec<f64>) = pg
            .iter()
            .map(|d| match d.model {
                NoiseModel::PoissonGaussian { a, b } => (a, b),
                NoiseModel::Gaussian { .. } => panic!("not Poisson–Gaussian"),
            })
            .unzip();
        assert_uniform(&a, (0.001, 0.01), "noise.a");
        assert_uniform(&b, (1e-5, 1e-4), "noise.b");
        // Every noise field has a seed of its own.
        let seeds: std::collections::BTreeSet<u64> = pg.iter().map(|d| d.seed).collect();
        assert_eq!(seeds.len(), pg.len());
    }
}
