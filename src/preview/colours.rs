//! The contact sheet's false colours: a ramp for scalars (depth, displacement magnitude), one
//! colour per label, surface normals as (n + 1) / 2, and optical flow in the Middlebury colour
//! code.
//!
//! Owns: value → colour. Knows nothing of the sheet's layout; the legends draw these same
//! functions, so a legend and its cells cannot disagree.

use super::canvas::Rgb;

/// Colour of `t` in [0, 1] on the sheet's scalar ramp, from dark blue (0) to dark red (1).
/// Both ends of Turbo are nearly black, so the ramp uses the part from 0.1 to 0.95 and stays
/// distinct from the black of "no surface".
pub fn ramp(t: f64) -> Rgb {
    turbo(0.1 + 0.85 * t.clamp(0.0, 1.0))
}

/// Google's Turbo colour map (Mikhailov 2019) by its published polynomial fit (Ruofei Du),
/// `x` in [0, 1] from blue to red.
fn turbo(x: f64) -> Rgb {
    const RED: [f64; 6] = [
        0.13572138,
        4.61539260,
        -42.66032258,
        132.13108234,
        -152.94239396,
        59.28637943,
    ];
    const GREEN: [f64; 6] = [
        0.09140261,
        2.19418839,
        4.84296658,
        -14.18503333,
        4.27729857,
        2.82956604,
    ];
    const BLUE: [f64; 6] = [
        0.10667330,
        12.64194608,
        -60.58204836,
        110.36276771,
        -89.90310912,
        27.34824973,
    ];
    let x = x.clamp(0.0, 1.0);
    let channel = |c: &[f64; 6]| {
        let v = c.iter().rev().fold(0.0, |acc, k| acc * x + k);
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    [channel(&RED), channel(&GREEN), channel(&BLUE)]
}

/// A deterministic, well-spread colour for a label (0 = background = black): hues step by the
/// golden angle so consecutive labels never look alike.
pub fn id_colour(id: u32) -> Rgb {
    if id == 0 {
        return [0; 3];
    }
    let hue = (f64::from(id) * 0.618_033_988_749_895).fract() * 6.0;
    // Alternate the brightness too, so labels whose hues come close still differ.
    let (s, v) = if id.is_multiple_of(2) {
        (0.55, 1.0)
    } else {
        (0.8, 0.85)
    };
    let f = hue.fract();
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    let rgb = match hue as u32 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    };
    rgb.map(|c| (c * 255.0).round() as u8)
}

/// A unit normal as (n + 1) / 2 per channel (x → red, y → green, z → blue); the zero vector
/// (no surface) is black.
pub fn normal_colour(n: [f32; 3]) -> Rgb {
    if n == [0.0; 3] || n.iter().any(|c| !c.is_finite()) {
        return [0; 3];
    }
    n.map(|c| ((f64::from(c).clamp(-1.0, 1.0) + 1.0) * 0.5 * 255.0).round() as u8)
}

/// Hue segments of the Middlebury flow colour wheel (Baker et al. 2011, "A Database and
/// Evaluation Methodology for Optical Flow", IJCV 92; its `colorcode.cpp`): red → yellow →
/// green → cyan → blue → magenta → red, with more steps where the eye tells hues apart.
const WHEEL_SEGMENTS: [(u32, [f64; 3], [f64; 3]); 6] = [
    (15, [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]),
    (6, [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
    (4, [0.0, 1.0, 0.0], [0.0, 1.0, 1.0]),
    (11, [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]),
    (13, [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]),
    (6, [1.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
];

/// Entry `k` of the wheel (55 entries), each channel in [0, 1], stepped as the reference code
/// steps them (floor(255 · i / n) / 255).
fn wheel_entry(mut k: u32) -> [f64; 3] {
    for (steps, from, to) in WHEEL_SEGMENTS {
        if k < steps {
            let f = (255.0 * f64::from(k) / f64::from(steps)).floor() / 255.0;
            return [0, 1, 2].map(|c| from[c] + (to[c] - from[c]) * f);
        }
        k -= steps;
    }
    unreachable!("the wheel has 55 entries")
}

const WHEEL_SIZE: u32 = 55;

/// Colour of the flow (u, v) pixels (u right, v down) with `max` pixels mapped to the rim: the
/// direction picks the hue (right = red, down = yellow-green... as the Middlebury wheel), the
/// magnitude the saturation (white at rest). Beyond the rim colours darken by 0.75, as the
/// reference code does. A non-finite vector or `max` ≤ 0 gives white (no motion shown).
pub fn flow_colour(u: f32, v: f32, max: f32) -> Rgb {
    let (u, v) = (f64::from(u), f64::from(v));
    if !(max > 0.0) || !u.is_finite() || !v.is_finite() {
        return [255; 3];
    }
    let (u, v) = (u / f64::from(max), v / f64::from(max));
    let radius = (u * u + v * v).sqrt();
    let angle = (-v).atan2(-u) / std::f64::consts::PI;
    let position = (angle + 1.0) / 2.0 * f64::from(WHEEL_SIZE - 1);
    let k0 = (position.floor() as u32).min(WHEEL_SIZE - 1);
    let k1 = (k0 + 1) % WHEEL_SIZE;
    let f = position - f64::from(k0);
    let (a, b) = (wheel_entry(k0), wheel_entry(k1));
    [0, 1, 2].map(|c| {
        let colour = (1.0 - f) * a[c] + f * b[c];
        let shaded = if radius <= 1.0 {
            1.0 - radius * (1.0 - colour)
        } else {
            colour * 0.75
        };
        (255.0 * shaded).floor().clamp(0.0, 255.0) as u8
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_runs_from_dark_blue_to_dark_red_and_never_reaches_black() {
        let [r0, _, b0] = ramp(0.0);
        assert!(b0 > r0, "low end is blue: {:?}", ramp(0.0));
        let [r1, _, b1] = ramp(1.0);
        assert!(r1 > 150 && b1 < 40, "high end is red: {:?}", ramp(1.0));
        // The middle of Turbo is a light green-yellow.
        assert!(turbo(0.5)[1] > 200, "{:?}", turbo(0.5));
        for i in 0..=20 {
            let c = ramp(f64::from(i) / 20.0);
            assert!(c.iter().map(|&v| u32::from(v)).sum::<u32>() > 60, "{c:?}");
        }
    }

    #[test]
    fn label_colours_are_distinct_and_background_is_black() {
        assert_eq!(id_colour(0), [0; 3]);
        let colours: Vec<Rgb> = (1..=64).map(id_colour).collect();
        for (i, a) in colours.iter().enumerate() {
            assert_ne!(*a, [0; 3]);
            for b in &colours[i + 1..] {
                let d: i32 = a
                    .iter()
                    .zip(b)
                    .map(|(&x, &y)| (x as i32 - y as i32).abs())
                    .sum();
                assert!(d > 8, "labels {i} and another look alike: {a:?} {b:?}");
            }
        }
    }

    #[test]
    fn normals_map_each_axis_to_its_channel() {
        assert_eq!(normal_colour([1.0, 0.0, 0.0]), [255, 128, 128]);
        assert_eq!(normal_colour([0.0, -1.0, 0.0]), [128, 0, 128]);
        assert_eq!(normal_colour([0.0, 0.0, -1.0]), [128, 128, 0]);
        assert_eq!(normal_colour([0.0; 3]), [0; 3]);
    }

    /// Reference values of the Middlebury code (as ported in the `flow_vis` package, Tom
    /// Runia): at rest white; at the rim pure wheel colours.
    #[test]
    fn flow_colours_follow_the_middlebury_wheel() {
        assert_eq!(flow_colour(0.0, 0.0, 1.0), [255; 3]);
        // Moving right (u > 0): angle = atan2(0, -1)/π = 1, the wheel's last entry, which
        // runs magenta → red: red with a little blue.
        let right = flow_colour(1.0, 0.0, 1.0);
        assert_eq!(right[0], 255);
        assert!(right[1] == 0 && right[2] < 50, "{right:?}");
        // Moving left: angle 0, position 27 of 55: in the cyan → blue segment.
        let left = flow_colour(-1.0, 0.0, 1.0);
        assert!(left[0] == 0 && left[2] == 255 && left[1] > 100, "{left:?}");
        // Moving up (v < 0): angle = atan2(1, 0)/π = 0.5, position 40.5: blue → magenta.
        let up = flow_colour(0.0, -1.0, 1.0);
        assert!(up[2] == 255 && up[1] == 0 && up[0] > 60, "{up:?}");
        // Moving down: position 13.5, the end of red → yellow.
        let down = flow_colour(0.0, 1.0, 1.0);
        assert!(down[0] == 255 && down[1] > 200 && down[2] == 0, "{down:?}");
        // Half way to the rim is paler; beyond it darker.
        let half = flow_colour(0.5, 0.0, 1.0);
        assert!(half[1] > 100 && half[0] == 255, "{half:?}");
        let beyond = flow_colour(2.0, 0.0, 1.0);
        assert_eq!(beyond[0], 191);
    }
}
