//! Lambert shading with a key and a fill light, fixed relative to the camera so that every
//! view is lit the same way whatever its direction.

use super::trace::{GBuffer, NO_HIT, TraceMesh};
use crate::cameras::Camera;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::OnceLock;

/// Light intensities and directions (towards the light, camera axes: x right, y down, z forward).
#[derive(Clone, Copy, Debug)]
pub struct Lighting {
    pub ambient: f64,
    pub key: (DVec3, f64),
    pub fill: (DVec3, f64),
}

impl Default for Lighting {
    fn default() -> Self {
        Lighting {
            ambient: 0.12,
            // Key above-left and behind the camera; fill from the right, weaker.
            key: (DVec3::new(-0.45, -0.6, -0.66).normalize(), 0.85),
            fill: (DVec3::new(0.7, -0.1, -0.7).normalize(), 0.3),
        }
    }
}

/// Sub-pixel positions for pixels on an edge: a fixed 2 × 2 grid, so the result is the same
/// on every run.
const EDGE_SAMPLES: [(f64, f64); 4] = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];

/// RGB8 image (sRGB) of the G-buffer. `albedo_of(triangle)` gives the linear albedo of the
/// surface a pixel sees; `background` is sRGB 0–255. A first pass shades one centre ray per
/// pixel, as for the geometric labels; pixels whose colour differs from a neighbour's by more
/// than one 8-bit level (silhouettes, creases, material boundaries) are then re-shaded from
/// four sub-pixel rays averaged in linear light. Smooth shading changes cost nothing extra.
pub fn shade(
    g: &GBuffer,
    mesh: &TraceMesh,
    camera: &Camera,
    lighting: &Lighting,
    albedo_of: impl Fn(u32) -> [f64; 3] + Sync,
    background: [u8; 3],
    antialias: bool,
) -> Vec<u8> {
    let width = g.width as usize;
    let background_linear = background.map(|c| srgb_to_linear(f64::from(c) / 255.0));
    let to_camera = camera.rotation.transpose();
    let radiance = |tri: Option<u32>, view: DVec3| -> [f64; 3] {
        let Some(tri) = tri else {
            return background_linear;
        };
        let mut n = to_camera * mesh.normal(tri);
        // Two-sided: light the face the camera sees.
        if n.dot(view) > 0.0 {
            n = -n;
        }
        let light = lighting.ambient
            + lighting.key.1 * n.dot(lighting.key.0).max(0.0)
            + lighting.fill.1 * n.dot(lighting.fill.0).max(0.0);
        albedo_of(tri).map(|c| (c * light).clamp(0.0, 1.0))
    };
    let background_bytes = encode(background_linear);
    let mut centre = vec![0u8; g.triangle.len() * 3];
    centre
        .par_chunks_mut(width * 3)
        .enumerate()
        .for_each(|(row, out)| {
            for col in 0..width {
                let tri = g.triangle[row * width + col];
                // Most of a frame is background: no ray, no shading.
                let colour = if tri == NO_HIT {
                    background_bytes
                } else {
                    encode(radiance(
                        Some(tri),
                        camera.intrinsics.ray_through_pixel(row as u32, col as u32),
                    ))
                };
                out[3 * col..3 * col + 3].copy_from_slice(&colour);
            }
        });
    if !antialias {
        return centre;
    }
    let pixel = |i: usize| &centre[3 * i..3 * i + 3];
    let differs = |i: usize, j: usize| {
        pixel(i)
            .iter()
            .zip(pixel(j))
            .any(|(a, b)| a.abs_diff(*b) > 1)
    };
    let mut rgb = centre.clone();
    rgb.par_chunks_mut(width * 3)
        .enumerate()
        .for_each(|(row, out)| {
            for col in 0..width {
                let i = row * width + col;
                let neighbours = [
                    (col > 0).then(|| i - 1),
                    (col + 1 < width).then(|| i + 1),
                    (row > 0).then(|| i - width),
                    (i + width < g.triangle.len()).then(|| i + width),
                ];
                let near_surface = g.triangle[i] != NO_HIT
                    || neighbours
                        .iter()
                        .flatten()
                        .any(|&j| g.triangle[j] != NO_HIT);
                if !near_surface || !neighbours.into_iter().flatten().any(|j| differs(i, j)) {
                    continue;
                }
                let mean = EDGE_SAMPLES.iter().fold([0.0; 3], |acc, &(du, dv)| {
                    let view = camera
                        .intrinsics
                        .ray_through(col as f64 + du, row as f64 + dv);
                    let c = radiance(mesh.first_hit(camera, view), view);
                    [
                        acc[0] + c[0] / 4.0,
                        acc[1] + c[1] / 4.0,
                        acc[2] + c[2] / 4.0,
                    ]
                });
                out[3 * col..3 * col + 3].copy_from_slice(&encode(mean));
            }
        });
    rgb
}

/// Linear colour → sRGB 8-bit.
fn encode(linear: [f64; 3]) -> [u8; 3] {
    let lut = srgb_lut();
    linear.map(|c| lut[(c * (LUT_SIZE - 1) as f64).round() as usize])
}

const LUT_SIZE: usize = 4096;

/// Linear → sRGB 8-bit encoding table.
fn srgb_lut() -> &'static [u8; LUT_SIZE] {
    static LUT: OnceLock<[u8; LUT_SIZE]> = OnceLock::new();
    LUT.get_or_init(|| {
        std::array::from_fn(|i| {
            let l = i as f64 / (LUT_SIZE - 1) as f64;
            let s = if l <= 0.003_130_8 {
                12.92 * l
            } else {
                1.055 * l.powf(1.0 / 2.4) - 0.055
            };
            (s * 255.0).round() as u8
        })
    })
}

/// sRGB (0–1) → linear, for albedos given by users as sRGB colours.
pub fn srgb_to_linear(s: f64) -> f64 {
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}
