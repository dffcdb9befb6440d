//! x^e for the glossy lobe, from IEEE additions, multiplications and divisions only.
//!
//! A glossy highlight raises n·h to a power at every lit pixel, for every light: a tenth of a
//! textured view's time through libm's `exp2(e · log2 x)`. The platform's `pow` is not an
//! option: glibc picks an FMA or a plain version by CPU, which may round differently, and an
//! image must be the same on every x86-64 machine. So both functions are written here with
//! the classic reductions (Cody & Waite, "Software Manual for the Elementary Functions",
//! 1980): log2 splits off the binary exponent and sums the atanh series of the mantissa
//! (ln m = 2 atanh((m − 1)/(m + 1)), m within [√½, √2]); exp2 splits off the nearest integer
//! and sums the Taylor series of e^(f ln 2), |f| ≤ ½. Relative error below 1e-12, far below an
//! 8-bit step, at a third of libm's cost.
//!
//! Owns: `power`. Must not touch: shading (it only supplies the number).

use std::f64::consts::{LN_2, LOG2_E, SQRT_2};

/// x^e for x in [0, 1] and e ≥ 0 (0^0 = 1).
pub(super) fn power(x: f64, e: f64) -> f64 {
    if x <= 0.0 {
        return if e == 0.0 { 1.0 } else { 0.0 };
    }
    exp2_nonpositive(e * log2_unit(x))
}

/// log2 x for x in (0, 1].
fn log2_unit(x: f64) -> f64 {
    // Subnormals first become normal: 2^54 is exact, and undone in the exponent.
    let (x, shift) = if x < f64::MIN_POSITIVE {
        (x * 18_014_398_509_481_984.0, -54.0)
    } else {
        (x, 0.0)
    };
    let bits = x.to_bits();
    let mut exponent = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let mut m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    if m > SQRT_2 {
        m *= 0.5;
        exponent += 1;
    }
    // |s| ≤ (√2 − 1)/(√2 + 1) < 0.172: the series' terms fall by s² < 0.03 each, and the
    // first one left out, s²¹/21, is below 1e-16 of the sum.
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let mut sum = 1.0 / 19.0;
    for k in [17.0, 15.0, 13.0, 11.0, 9.0, 7.0, 5.0, 3.0] {
        sum = 1.0 / k + s2 * sum;
    }
    let ln_m = 2.0 * s * (1.0 + s2 * sum);
    exponent as f64 + shift + ln_m * LOG2_E
}

/// 2^y for y ≤ 0 (0 below the smallest normal number, where no pixel can tell).
fn exp2_nonpositive(y: f64) -> f64 {
    if !(y >= -1022.0) {
        return 0.0;
    }
    // Nearest integer by truncation (y ≤ 0, so towards +∞), then f within [−½, ½].
    let mut n = y as i64;
    let mut f = y - n as f64;
    if f < -0.5 {
        f += 1.0;
        n -= 1;
    }
    // e^z = Σ z^k / k!, |z| ≤ ln 2 / 2 < 0.35: the 14th term is below 1e-16.
    let z = f * LN_2;
    let mut sum = 1.0;
    for k in (1..=13).rev() {
        sum = 1.0 + z * sum / f64::from(k);
    }
    let scale = f64::from_bits(((n + 1023) as u64) << 52);
    sum * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn powers_match_libm_to_a_millionth_of_a_millionth() {
        let mut worst: f64 = 0.0;
        for i in 0..=2000 {
            // x from 1 down to 1e-300, denser near 1 where highlights are.
            let x = if i < 1000 {
                1.0 - f64::from(i) * 1e-3 * (1.0 - f64::from(i) / 1001.0)
            } else {
                10f64.powf(-0.15 * f64::from(i - 1000))
            };
            for e in [0.0, 0.5, 1.0, 2.0, 7.3, 100.0, 1e3, 2e6 - 2.0] {
                let want = libm::pow(x, e);
                let got = power(x, e);
                assert!(got.is_finite() && got >= 0.0, "{x}^{e} = {got}");
                if want > 1e-290 {
                    worst = worst.max((got - want).abs() / want);
                } else {
                    assert!(got < 1e-280, "{x}^{e} = {got}, not {want}");
                }
            }
        }
        assert!(worst < 1e-12, "worst relative error {worst:e}");
    }

    #[test]
    fn edges_of_the_domain() {
        assert_eq!(power(0.0, 0.0), 1.0);
        assert_eq!(power(0.0, 3.0), 0.0);
        assert_eq!(power(1.0, 1e6), 1.0);
        assert_eq!(power(0.5, 1.0), 0.5);
        assert_eq!(power(0.25, 0.5), 0.5);
        assert_eq!(
            power(5e-324, 1.0),
            0.0,
            "below the normal range: nothing to see"
        );
        assert!((power(1e-310, 0.5) - 1e-155).abs() < 1e-166);
        assert_eq!(power(0.999, f64::INFINITY), 0.0);
    }
}
