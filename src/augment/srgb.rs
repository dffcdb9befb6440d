//! The sRGB transfer function (IEC 61966-2-1:1999) between 8-bit codes and linear light.
//!
//! Decoding is a 256-entry table. Encoding a linear value rounds to the nearest code through a
//! table of the 255 linear values halfway (in code units) between neighbouring codes, searched
//! by bisection: exact, branch-light and free of any per-pixel power function. Both tables
//! are computed once with `libm` (pure Rust, the same bits on every CPU).

use std::sync::OnceLock;

/// Linear light in [0, 1] of an sRGB-encoded value in [0, 1] (IEC 61966-2-1 EOTF).
pub fn to_linear(encoded: f64) -> f64 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        libm::pow((encoded + 0.055) / 1.055, 2.4)
    }
}

/// The sRGB-encoded value in [0, 1] of linear light in [0, 1] (inverse of [`to_linear`]).
pub fn to_encoded(linear: f64) -> f64 {
    if linear <= 0.0031308 {
        12.92 * linear
    } else {
        1.055 * libm::pow(linear, 1.0 / 2.4) - 0.055
    }
}

struct Tables {
    decode: [f32; 256],
    /// `halfway[k]`: linear value of code k + ½; code c is chosen for x when
    /// halfway[c − 1] ≤ x < halfway[c].
    halfway: [f32; 255],
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| Tables {
        decode: std::array::from_fn(|k| to_linear(k as f64 / 255.0) as f32),
        halfway: std::array::from_fn(|k| to_linear((k as f64 + 0.5) / 255.0) as f32),
    })
}

/// Linear light of an 8-bit code.
pub fn decode(code: u8) -> f32 {
    tables().decode[usize::from(code)]
}

/// The 256 linear values of the 8-bit codes.
pub fn decode_table() -> &'static [f32; 256] {
    &tables().decode
}

/// The nearest 8-bit code of linear light `x` (clamped to [0, 1]; NaN gives 0).
pub fn encode(x: f32) -> u8 {
    tables().halfway.partition_point(|&h| h <= x) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_transfer_function_matches_the_standard() {
        // IEC 61966-2-1 reference points: the breakpoint and mid grey.
        assert!((to_linear(0.04045) - 0.04045 / 12.92).abs() < 1e-15);
        assert!((to_linear(0.5) - 0.214_041_140_482_232_5).abs() < 1e-12);
        for k in 0..=255 {
            let v = k as f64 / 255.0;
            assert!((to_encoded(to_linear(v)) - v).abs() < 1e-12, "{k}");
        }
    }

    #[test]
    fn encoding_rounds_to_the_nearest_code_and_inverts_decoding() {
        for k in 0..=255u8 {
            assert_eq!(encode(decode(k)), k);
        }
        for i in 0..=10_000 {
            let x = i as f64 / 10_000.0;
            let nearest = (to_encoded(x) * 255.0).round() as u8;
            assert!(encode(x as f32).abs_diff(nearest) <= 1, "{x}");
        }
        assert_eq!(encode(-1.0), 0);
        assert_eq!(encode(2.0), 255);
        assert_eq!(encode(f32::NAN), 0);
    }
}
