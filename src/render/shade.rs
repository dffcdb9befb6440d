//! Lambert shading with a key and a fill light, fixed relative to the camera so that every
//! view is lit the same way whatever its direction.

use super::trace::{GBuffer, TraceMesh, NO_HIT};
use crate::cameras::Camera;
use glam::DVec3;
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

/// RGB8 image (sRGB) of the G-buffer. `albedo_of(triangle)` gives the linear albedo of the
/// surface a pixel sees; `background` is sRGB 0–255.
pub fn shade(
    g: &GBuffer,
    mesh: &TraceMesh,
    camera: &Camera,
    lighting: &Lighting,
    albedo_of: impl Fn(u32) -> [f64; 3],
    background: [u8; 3],
) -> Vec<u8> {
    let to_cam = camera.rotation.transpose();
    let mut rgb = Vec::with_capacity(g.triangle.len() * 3);
    let lut = srgb_lut();
    for (i, &tri) in g.triangle.iter().enumerate() {
        if tri == NO_HIT {
            rgb.extend_from_slice(&background);
            continue;
        }
        let (row, col) = ((i / g.width as usize) as u32, (i % g.width as usize) as u32);
        let view = camera.intrinsics.ray_through_pixel(row, col);
        let mut n = to_cam * mesh.normal(tri);
        // Two-sided: light the face the camera sees.
        if n.dot(view) > 0.0 {
            n = -n;
        }
        let light = lighting.ambient
            + lighting.key.1 * n.dot(lighting.key.0).max(0.0)
            + lighting.fill.1 * n.dot(lighting.fill.0).max(0.0);
        for channel in albedo_of(tri) {
            let linear = (channel * light).clamp(0.0, 1.0);
            rgb.push(lut[(linear * (LUT_SIZE - 1) as f64).round() as usize]);
        }
    }
    rgb
}

const LUT_SIZE: usize = 4096;

/// Linear → sRGB 8-bit encoding table.
fn srgb_lut() -> &'static [u8; LUT_SIZE] {
    static LUT: OnceLock<[u8; LUT_SIZE]> = OnceLock::new();
    LUT.get_or_init(|| {
        std::array::from_fn(|i| {
            let l = i as f64 / (LUT_SIZE - 1) as f64;
            let s = if l <= 0.003_130_8 { 12.92 * l } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 };
            (s * 255.0).round() as u8
        })
    })
}

/// sRGB (0–1) → linear, for albedos given by users as sRGB colours.
pub fn srgb_to_linear(s: f64) -> f64 {
    if s <= 0.040_45 { s / 12.92 } else { ((s + 0.055) / 1.055).powf(2.4) }
}
