//! Blur that varies over the image: each pixel spread over its own circle of confusion (a
//! lens's depth of field, computed by the caller from exact depth), gathered in linear light.
//!
//! Owns: the gather. Must not touch: how the circles are computed (`cameras::DepthOfField`).
//! A pixel's light spreads uniformly over a disk of its own radius (scatter), evaluated as a
//! gather: a pixel receives from every neighbour whose disk covers it, weighted by that disk's
//! 1/area, normalised by the weights received (Potmesil & Chakravarty 1981, as a gather in the
//! manner of real-time renderers). A pixel farther than the receiver spreads no wider than the
//! receiver's own disk, so a blurred backdrop does not bleed over a sharp structure in front.
//! Rows are independent; sums run in a fixed order: the same bytes on any thread count.

use super::srgb;
use rayon::prelude::*;

/// Largest circle radius gathered, pixels: wider disks are clipped to it (the cost grows with
/// its square).
pub const MAX_DEFOCUS_RADIUS: f32 = 16.0;

/// Blurs the sRGB8 image `rgb` (`width` × `height`) where pixel k spreads over a disk of
/// `radius[k]` pixels and lies `distance[k]` from the camera (any monotone measure; larger is
/// farther). Radii of half a pixel or less leave a pixel as it is.
pub fn defocus_by_depth(
    rgb: &mut [u8],
    width: usize,
    height: usize,
    radius: &[f32],
    distance: &[f32],
) {
    super::rgb_pixels(rgb, width, height);
    assert!(radius.len() == width * height && distance.len() == width * height);
    let clipped = |r: f32| r.clamp(0.5, MAX_DEFOCUS_RADIUS);
    let widest = radius.iter().copied().fold(0.5f32, f32::max);
    if widest <= 0.5 {
        return;
    }
    let reach = clipped(widest).ceil() as isize;
    // How far each pixel must look: the widest circle within the farthest reach of it.
    let near_reach = widest_nearby(
        &radius.iter().map(|&r| clipped(r)).collect::<Vec<_>>(),
        width,
        reach as usize,
    );
    let decode = srgb::decode_table();
    let linear: Vec<[f32; 3]> = rgb
        .chunks_exact(3)
        .map(|p| [0, 1, 2].map(|c| decode[usize::from(p[c])]))
        .collect();
    let (w, h) = (width as isize, height as isize);
    rgb.par_chunks_mut(width * 3)
        .enumerate()
        .for_each(|(row, out)| {
            let y = row as isize;
            for x in 0..w {
                let at = (y * w + x) as usize;
                let (own, here) = (clipped(radius[at]), distance[at]);
                let (mut sum, mut weights) = ([0f32; 3], 0f32);
                let reach = near_reach[at].ceil() as isize;
                for qy in (y - reach).max(0)..=(y + reach).min(h - 1) {
                    for qx in (x - reach).max(0)..=(x + reach).min(w - 1) {
                        let q = (qy * w + qx) as usize;
                        let mut r = clipped(radius[q]);
                        if distance[q] > here {
                            r = r.min(own);
                        }
                        let (dx, dy) = ((qx - x) as f32, (qy - y) as f32);
                        if dx * dx + dy * dy > r * r {
                            continue;
                        }
                        let weight = 1.0 / (r * r);
                        for c in 0..3 {
                            sum[c] += weight * linear[q][c];
                        }
                        weights += weight;
                    }
                }
                let px = x as usize * 3;
                for c in 0..3 {
                    out[px + c] = srgb::encode(sum[c] / weights);
                }
            }
        });
}

/// For every pixel, the largest of `values` within `reach` pixels along both axes (a square
/// window), as a row pass and a column pass.
fn widest_nearby(values: &[f32], width: usize, reach: usize) -> Vec<f32> {
    let height = values.len() / width;
    let mut rows = vec![0f32; values.len()];
    rows.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let line = &values[y * width..(y + 1) * width];
        for (x, o) in out.iter_mut().enumerate() {
            let span = &line[x.saturating_sub(reach)..(x + reach + 1).min(width)];
            *o = span.iter().copied().fold(0.0, f32::max);
        }
    });
    let mut both = vec![0f32; values.len()];
    both.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        for (x, o) in out.iter_mut().enumerate() {
            let ys = y.saturating_sub(reach)..(y + reach + 1).min(height);
            *o = ys.map(|qy| rows[qy * width + x]).fold(0.0, f32::max);
        }
    });
    both
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A white square on black, all at one distance, blurred by disks of radius r: far inside
    /// and far outside nothing changes; at the square's straight edge the gather is the share
    /// of a disk (centred on each contributing pixel) — half light right on the edge.
    #[test]
    fn an_edge_blurs_over_its_circle_and_keeps_its_light() {
        let (w, h, r) = (64usize, 64usize, 6.0f32);
        let mut rgb = vec![0u8; w * h * 3];
        for y in 0..h {
            for x in 0..w / 2 {
                rgb[(y * w + x) * 3..(y * w + x) * 3 + 3].fill(255);
            }
        }
        let before = rgb.clone();
        defocus_by_depth(&mut rgb, w, h, &vec![r; w * h], &vec![1.0; w * h]);
        let at = |x: usize| srgb::decode(rgb[(32 * w + x) * 3]);
        assert_eq!(at(5), 1.0);
        assert_eq!(at(60), 0.0);
        // Across the edge (between columns 31 and 32) the light falls from 1 to 0 over 2r.
        let (inside, outside) = (at(31), at(32));
        assert!(
            (inside + outside - 1.0).abs() < 0.02,
            "{inside} + {outside}"
        );
        assert!(at(31 - 7) > 0.99 && at(32 + 7) < 0.01);
        assert!(at(28) > at(30) && at(30) > at(33) && at(33) > at(35));
        // Total light is kept (up to 8-bit rounding) away from the image's borders.
        let total = |img: &[u8]| -> f32 {
            (8..56)
                .map(|y| {
                    (0..w)
                        .map(|x| srgb::decode(img[(y * w + x) * 3]))
                        .sum::<f32>()
                })
                .sum()
        };
        let (a, b) = (total(&before), total(&rgb));
        assert!((a - b).abs() < 0.01 * a, "{a} → {b}");
    }

    #[test]
    fn a_sharp_near_pixel_gets_nothing_from_a_blurred_far_one() {
        let (w, h) = (32usize, 32usize);
        let mut rgb = vec![0u8; w * h * 3];
        let mut radius = vec![8.0f32; w * h];
        let mut distance = vec![100.0f32; w * h];
        // The far half is white and blurred; a sharp black column stands in front of it.
        for y in 0..h {
            for x in 0..w {
                let k = y * w + x;
                if x == 16 {
                    radius[k] = 0.0;
                    distance[k] = 1.0;
                } else {
                    rgb[k * 3..k * 3 + 3].fill(255);
                }
            }
        }
        defocus_by_depth(&mut rgb, w, h, &radius, &distance);
        assert!((0..h).all(|y| rgb[(y * w + 16) * 3] == 0));
        // The near pixel spreads not at all, so the white around it stays nearly white.
        assert!(rgb[(16 * w + 14) * 3] > 240);
    }

    #[test]
    fn pixels_in_focus_are_left_alone() {
        let (w, h) = (8usize, 8usize);
        let mut rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 37 % 256) as u8).collect();
        let before = rgb.clone();
        defocus_by_depth(&mut rgb, w, h, &vec![0.4; w * h], &vec![1.0; w * h]);
        assert_eq!(rgb, before);
    }
}
