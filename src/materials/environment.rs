//! Environment maps: an equirectangular image of the light arriving from every direction,
//! looked up along a ray (for the background) and projected once onto order-2 spherical
//! harmonics (for the diffuse light it casts, Ramamoorthi & Hanrahan 2001).
//!
//! Convention: world +z is up. Column 0's left edge is longitude 0, the +x axis; longitude
//! grows from +x towards +y (like the sun's azimuth) to the right of the image, and wraps.
//! Row 0's top edge looks straight up (+z), the last row's bottom edge straight down.
//!
//! Owns: decoding a map (Radiance .hdr, or OpenEXR by its `.exr` name) into linear radiance, bilinear lookup, the
//! projection onto nine SH coefficients and the irradiance they give. Must not touch:
//! reading files (the recipe's `RecipeFiles` hands the bytes over), shading, cameras.

use super::image::decode_failure;
use glam::DVec3;
use std::f64::consts::{PI, TAU};
use std::path::Path;

/// Most pixels an environment map may hold (16 megapixels: 8192 × 4096).
pub const MAX_ENVIRONMENT_PIXELS: u64 = 1 << 24;

/// An equirectangular map of linear radiance, with its irradiance coefficients.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    width: usize,
    height: usize,
    /// Linear RGB radiance, row-major from the top row.
    texels: Vec<[f32; 3]>,
    /// Order-2 SH coefficients L_lm of the radiance, per channel, in the order
    /// (0,0), (1,−1), (1,0), (1,1), (2,−2), (2,−1), (2,0), (2,1), (2,2).
    sh: [[f64; 3]; 9],
}

impl EnvironmentMap {
    /// The width and height of an encoded map (Radiance .hdr, or OpenEXR when `name` ends in
    /// `.exr`), from its header alone.
    pub fn size(bytes: &[u8], name: &Path) -> Result<(u32, u32), String> {
        if is_exr(name) {
            let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
                .map_err(|e| cannot_read(name, &exr_failure(&e)))?;
            let header = meta
                .headers
                .first()
                .ok_or_else(|| cannot_read(name, &"no layer"))?;
            let (w, h) = (header.layer_size.width(), header.layer_size.height());
            return Ok((
                u32::try_from(w).unwrap_or(u32::MAX),
                u32::try_from(h).unwrap_or(u32::MAX),
            ));
        }
        use image::ImageDecoder;
        let decoder = image::codecs::hdr::HdrDecoder::new(std::io::Cursor::new(bytes))
            .map_err(|e| cannot_read(name, &decode_failure(&e)))?;
        Ok(decoder.dimensions())
    }

    /// Decodes a map and checks it is equirectangular: twice as wide as high, finite
    /// non-negative radiance.
    pub fn decode(bytes: &[u8], name: &Path) -> Result<Self, String> {
        let (w, h) = Self::size(bytes, name)?;
        if w == 0 || h == 0 || w != 2 * h {
            return Err(format!(
                "environment map {} is {w}×{h} pixels: an equirectangular map is twice as wide as high (2:1)",
                name.display()
            ));
        }
        if u64::from(w) * u64::from(h) > MAX_ENVIRONMENT_PIXELS {
            return Err(format!(
                "environment map {} is {w}×{h} pixels, over the limit of {} million",
                name.display(),
                MAX_ENVIRONMENT_PIXELS / 1_000_000
            ));
        }
        let texels = if is_exr(name) {
            exr_texels(bytes, name)?
        } else {
            let decoder = image::codecs::hdr::HdrDecoder::new(std::io::Cursor::new(bytes))
                .map_err(|e| cannot_read(name, &decode_failure(&e)))?;
            let image = image::DynamicImage::from_decoder(decoder)
                .map_err(|e| cannot_read(name, &decode_failure(&e)))?
                .into_rgb32f();
            image.pixels().map(|p| p.0).collect()
        };
        if texels.len() != (w as usize) * (h as usize) {
            return Err(cannot_read(name, &"the pixels do not fill the image"));
        }
        if texels.iter().flatten().any(|c| !c.is_finite() || *c < 0.0) {
            return Err(format!(
                "environment map {}: radiance must be finite and not negative",
                name.display()
            ));
        }
        Ok(Self::from_texels(w as usize, h as usize, texels))
    }

    /// A map from linear radiance texels (row-major, top row first), `width` = 2 × `height`.
    pub fn from_texels(width: usize, height: usize, texels: Vec<[f32; 3]>) -> Self {
        assert!(width == 2 * height && texels.len() == width * height);
        let mut map = EnvironmentMap {
            width,
            height,
            texels,
            sh: [[0.0; 3]; 9],
        };
        map.sh = map.project();
        map
    }

    /// Radiance arriving from world direction `d` (need not be unit), bilinear between texel
    /// centres, wrapping in longitude and clamped at the poles.
    pub fn radiance(&self, d: DVec3) -> [f64; 3] {
        let d = d.normalize_or_zero();
        let longitude = libm::atan2(d.y, d.x).rem_euclid(TAU);
        let polar = libm::acos(d.z.clamp(-1.0, 1.0));
        // Texel centres sit at half-integers.
        let x = longitude / TAU * self.width as f64 - 0.5;
        let y = (polar / PI * self.height as f64 - 0.5).clamp(0.0, (self.height - 1) as f64);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let column = |i: f64| (i as i64).rem_euclid(self.width as i64) as usize;
        let (c0, c1) = (column(x0), column(x0 + 1.0));
        let r0 = y0 as usize;
        let r1 = (r0 + 1).min(self.height - 1);
        let at = |r: usize, c: usize| self.texels[r * self.width + c];
        std::array::from_fn(|k| {
            let top = f64::from(at(r0, c0)[k]) * (1.0 - fx) + f64::from(at(r0, c1)[k]) * fx;
            let bottom = f64::from(at(r1, c0)[k]) * (1.0 - fx) + f64::from(at(r1, c1)[k]) * fx;
            top * (1.0 - fy) + bottom * fy
        })
    }

    /// Radiance a white Lambertian face with unit normal `n` reflects (irradiance / π), from
    /// the nine SH coefficients: E(n) = Σ Â_l L_lm Y_lm(n) with Â = (π, 2π/3, π/4)
    /// (Ramamoorthi & Hanrahan 2001, eq. 7–8). Never negative.
    pub fn diffuse(&self, n: DVec3) -> [f64; 3] {
        let y = basis(n);
        const A: [f64; 9] = [
            PI,
            2.0 * PI / 3.0,
            2.0 * PI / 3.0,
            2.0 * PI / 3.0,
            PI / 4.0,
            PI / 4.0,
            PI / 4.0,
            PI / 4.0,
            PI / 4.0,
        ];
        std::array::from_fn(|k| {
            let e: f64 = (0..9).map(|i| A[i] * self.sh[i][k] * y[i]).sum();
            (e / PI).max(0.0)
        })
    }

    /// The SH coefficients L_lm = ∫ L(ω) Y_lm(ω) dω, integrated exactly over each texel
    /// (radiance constant within it): every basis function is a polynomial in z = cos θ times
    /// a harmonic in longitude φ, and dω = dz dφ, so each texel's weight is a product of two
    /// closed-form 1-D integrals.
    fn project(&self) -> [[f64; 3]; 9] {
        // Per row: ∫ over the row's z band of 1, z, z², s, s z with s = √(1 − z²).
        let rows: Vec<[f64; 5]> = (0..self.height)
            .map(|r| {
                let z_top = libm::cos(PI * r as f64 / self.height as f64);
                let z_bottom = libm::cos(PI * (r + 1) as f64 / self.height as f64);
                let primitive = |z: f64| {
                    let s = libm::sqrt((1.0 - z * z).max(0.0));
                    [
                        z,
                        z * z / 2.0,
                        z * z * z / 3.0,
                        (z * s + libm::asin(z.clamp(-1.0, 1.0))) / 2.0,
                        -s * s * s / 3.0,
                    ]
                };
                let (a, b) = (primitive(z_bottom), primitive(z_top));
                std::array::from_fn(|i| b[i] - a[i])
            })
            .collect();
        // Per column: ∫ over the column's φ band of 1, cos φ, sin φ, cos 2φ, sin 2φ.
        let columns: Vec<[f64; 5]> = (0..self.width)
            .map(|c| {
                let (p0, p1) = (
                    TAU * c as f64 / self.width as f64,
                    TAU * (c + 1) as f64 / self.width as f64,
                );
                [
                    p1 - p0,
                    libm::sin(p1) - libm::sin(p0),
                    libm::cos(p0) - libm::cos(p1),
                    (libm::sin(2.0 * p1) - libm::sin(2.0 * p0)) / 2.0,
                    (libm::cos(2.0 * p0) - libm::cos(2.0 * p1)) / 2.0,
                ]
            })
            .collect();
        let [c0, c1, c2, c3, c4] = CONSTANTS;
        let mut sh = [[0.0; 3]; 9];
        for (r, z) in rows.iter().enumerate() {
            let [one, z1, z2, s1, sz] = *z;
            for (c, p) in columns.iter().enumerate() {
                let [dphi, cos, sin, cos2, sin2] = *p;
                // x = s cos φ, y = s sin φ; xy = (1 − z²) sin 2φ / 2, x² − y² = (1 − z²) cos 2φ.
                let w = [
                    c0 * one * dphi,
                    c1 * s1 * sin,
                    c1 * z1 * dphi,
                    c1 * s1 * cos,
                    c2 * (one - z2) * sin2 / 2.0,
                    c2 * sz * sin,
                    c3 * (3.0 * z2 - one) * dphi,
                    c2 * sz * cos,
                    c4 * (one - z2) * cos2,
                ];
                let l = self.texels[r * self.width + c];
                for (i, wi) in w.iter().enumerate() {
                    for k in 0..3 {
                        sh[i][k] += wi * f64::from(l[k]);
                    }
                }
            }
        }
        sh
    }
}

/// Normalisation constants of the real SH basis: 1/(2√π), √(3/(4π)), √(15/(4π)),
/// √(5/(16π)), √(15/(16π)).
const CONSTANTS: [f64; 5] = [
    0.282_094_791_773_878_1,
    0.488_602_511_902_919_9,
    1.092_548_430_592_079_2,
    0.315_391_565_252_520_05,
    0.546_274_215_296_039_6,
];

/// The nine real SH basis functions at unit direction `n`.
fn basis(n: DVec3) -> [f64; 9] {
    let [c0, c1, c2, c3, c4] = CONSTANTS;
    let (x, y, z) = (n.x, n.y, n.z);
    [
        c0,
        c1 * y,
        c1 * z,
        c1 * x,
        c2 * x * y,
        c2 * y * z,
        c3 * (3.0 * z * z - 1.0),
        c2 * x * z,
        c4 * (x * x - y * y),
    ]
}

/// Whether `name` is an OpenEXR file (by its extension; anything else is read as .hdr).
fn is_exr(name: &Path) -> bool {
    name.extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case("exr"))
}

/// The R, G and B channels of an OpenEXR file's first layer with them, row-major from the top.
fn exr_texels(bytes: &[u8], name: &Path) -> Result<Vec<[f32; 3]>, String> {
    use exr::prelude::{ReadChannels, ReadLayers, read};
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, _| (size.width(), vec![[0.0f32; 3]; size.area()]),
            |(width, texels), at, (r, g, b): (f32, f32, f32)| {
                texels[at.y() * *width + at.x()] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| cannot_read(name, &exr_failure(&e)))?;
    Ok(image.layer_data.channel_data.pixels.1)
}

/// What the OpenEXR reader's refusal says about the file, as [`decode_failure`] does for the
/// other formats ("invalid: reference to missing bytes" is a file cut short).
fn exr_failure(e: &exr::error::Error) -> String {
    use exr::error::Error;
    match e {
        Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "the file is truncated: it ends before the image does".into()
        }
        Error::Invalid(_) | Error::Io(_) => format!("the file is truncated or corrupt ({e})"),
        _ => e.to_string(),
    }
}

fn cannot_read(name: &Path, e: &dyn std::fmt::Display) -> String {
    format!(
        "cannot read environment map {} (Radiance .hdr, or OpenEXR named .exr): {e}",
        name.display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map_of(height: usize, radiance: impl Fn(DVec3) -> f32) -> EnvironmentMap {
        let width = 2 * height;
        let texels = (0..height)
            .flat_map(|r| (0..width).map(move |c| (r, c)))
            .map(|(r, c)| {
                let polar = PI * (r as f64 + 0.5) / height as f64;
                let longitude = TAU * (c as f64 + 0.5) / width as f64;
                let d = DVec3::new(
                    polar.sin() * longitude.cos(),
                    polar.sin() * longitude.sin(),
                    polar.cos(),
                );
                [radiance(d); 3]
            })
            .collect();
        EnvironmentMap::from_texels(width, height, texels)
    }

    /// A constant map of radiance L: the irradiance of any face is π L, so a white
    /// Lambertian face reflects exactly L (only the (0,0) coefficient is non-zero, and the
    /// texel weights integrate 1 to exactly 4π).
    #[test]
    fn a_constant_map_lights_every_face_to_its_radiance() {
        let map = map_of(16, |_| 0.75);
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(0.3, -0.5, 0.2).normalize(),
        ] {
            for c in map.diffuse(n) {
                assert!((c - 0.75).abs() < 1e-12, "{n}: {c}");
            }
        }
    }

    /// Bright above the horizon only: the exact irradiance is π L (1 + n_z)/2, which lies in
    /// the span of the l ≤ 1 harmonics, so order 2 carries no truncation error (the l = 2
    /// zonal term of a hemisphere, ∫₀¹ P₂ = 0, vanishes) and the texel integrals are exact.
    #[test]
    fn a_bright_upper_hemisphere_lights_up_faces_and_not_down_faces() {
        let map = map_of(32, |d| if d.z > 0.0 { 2.0 } else { 0.0 });
        for (n, expected) in [
            (DVec3::Z, 2.0),
            (-DVec3::Z, 0.0),
            (DVec3::Y, 1.0),
            (DVec3::new(1.0, 0.0, 1.0).normalize(), 1.0 + 0.5f64.sqrt()),
        ] {
            let got = map.diffuse(n)[0];
            assert!((got - expected).abs() < 1e-9, "{n}: {got} vs {expected}");
        }
    }

    /// A small bright patch acts like a sun: the exact light on a face is the cosine-weighted
    /// sum over the patch, and order-2 SH approximates the clamped cosine to within 0.094 of
    /// the peak (the truncated series 1/4 + P₁/2 + 5 P₂/16 of max(cos, 0) errs most at the
    /// terminator, 1/4 − 5/32; Ramamoorthi & Hanrahan 2001, §3).
    #[test]
    fn a_bright_patch_is_lit_within_the_order_two_error() {
        let height = 64;
        let sun = DVec3::new(0.4, 0.2, 0.8).normalize();
        let map = map_of(height, |d| if d.dot(sun) > 0.995 { 10.0 } else { 0.0 });
        // Exact: sum over texels of L max(n·ω, 0) dω / π, by fine midpoint quadrature.
        let exact = |n: DVec3| {
            let (w, h) = (4 * 2 * height, 4 * height);
            let mut e = 0.0;
            for r in 0..h {
                let polar = PI * (r as f64 + 0.5) / h as f64;
                for c in 0..w {
                    let lon = TAU * (c as f64 + 0.5) / w as f64;
                    let d = DVec3::new(
                        polar.sin() * lon.cos(),
                        polar.sin() * lon.sin(),
                        polar.cos(),
                    );
                    let l = map.radiance(d)[0];
                    e += l * n.dot(d).max(0.0) * polar.sin() * (PI / h as f64) * (TAU / w as f64);
                }
            }
            e / PI
        };
        let peak = exact(sun);
        assert!(peak > 0.0);
        for n in [
            sun,
            DVec3::Z,
            DVec3::X,
            -DVec3::Z,
            sun.cross(DVec3::Z).normalize(),
        ] {
            let (got, want) = (map.diffuse(n)[0], exact(n));
            assert!(
                (got - want).abs() <= 0.094 * peak + 0.01 * peak,
                "{n}: SH {got:.4}, exact {want:.4}, peak {peak:.4}"
            );
        }
    }

    /// An OpenEXR map decodes to the very floats written, row 0 at the top.
    #[test]
    fn an_openexr_map_decodes_to_the_floats_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sky.exr");
        let value = |x: usize, y: usize| (0.1 * x as f32, 0.01 * y as f32 + 0.5, 3.25);
        exr::prelude::write_rgb_file(&path, 8, 4, value).unwrap();
        let map = EnvironmentMap::decode(&std::fs::read(&path).unwrap(), &path).unwrap();
        for (i, t) in map.texels.iter().enumerate() {
            let (r, g, b) = value(i % 8, i / 8);
            assert_eq!(*t, [r, g, b], "texel {i}");
        }
        exr::prelude::write_rgb_file(&path, 6, 4, value).unwrap();
        let error = EnvironmentMap::decode(&std::fs::read(&path).unwrap(), &path).unwrap_err();
        assert!(
            error.contains("sky.exr") && error.contains("2:1"),
            "{error}"
        );
    }

    /// Lookups at texel centres give the texel, and longitude wraps across the seam.
    #[test]
    fn lookup_hits_texel_centres_and_wraps_in_longitude() {
        let (width, height) = (8, 4);
        let texels = (0..width * height).map(|i| [i as f32; 3]).collect();
        let map = EnvironmentMap::from_texels(width, height, texels);
        let dir = |polar: f64, lon: f64| {
            DVec3::new(
                polar.sin() * lon.cos(),
                polar.sin() * lon.sin(),
                polar.cos(),
            )
        };
        // Row 1, column 2 centre.
        let centre = map.radiance(dir(PI * 1.5 / 4.0, TAU * 2.5 / 8.0))[0];
        assert!((centre - 10.0).abs() < 1e-9, "{centre}");
        // Longitude 0 is halfway between the last column (7) and the first (0) of row 1.
        let seam = map.radiance(dir(PI * 1.5 / 4.0, 0.0))[0];
        assert!((seam - (8.0 + 15.0) / 2.0).abs() < 1e-9, "{seam}");
    }

    /// A map cut short names the file and says it is truncated (the decoders' own words were
    /// "failed to fill whole buffer" and "invalid: reference to missing bytes").
    #[test]
    fn a_truncated_map_says_so() {
        let dir = tempfile::tempdir().unwrap();
        let exr_path = dir.path().join("sky.exr");
        exr::prelude::write_rgb_file(&exr_path, 64, 32, |x, y| (x as f32, y as f32, 1.0)).unwrap();
        let exr = std::fs::read(&exr_path).unwrap();
        let mut hdr = Vec::new();
        let texels = vec![image::Rgb([0.5f32, 1.0, 2.0]); 64 * 32];
        image::codecs::hdr::HdrEncoder::new(&mut hdr)
            .encode(&texels, 64, 32)
            .unwrap();
        for (path, file) in [(exr_path.as_path(), &exr), (Path::new("sky.hdr"), &hdr)] {
            assert!(EnvironmentMap::decode(file, path).is_ok());
            for share in [0.05, 0.5, 0.99] {
                let cut = &file[..(file.len() as f64 * share) as usize];
                let e = EnvironmentMap::decode(cut, path).unwrap_err();
                assert!(
                    e.contains(&path.display().to_string()) && e.contains("truncated"),
                    "{share}: {e}"
                );
            }
        }
    }
}
