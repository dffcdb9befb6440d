//! Texture and background images: decoded once (PNG or JPEG, through the `image` crate) into
//! linear light, with a box-filtered mip pyramid so a tile seen from afar is averaged rather
//! than aliased.

use std::path::Path;
use std::sync::Arc;

/// Widest or tallest texture or background image, pixels.
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// Most pixels in one texture or background image (8192 × 8192); decoded with its mip levels
/// it takes 16 bytes a pixel.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 26;

/// A decoded image with the name and hash it is recorded under.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageFile {
    /// Path relative to the recipe's folder, with `/` separators.
    pub name: String,
    /// blake3 of the file's bytes.
    pub hash: String,
    /// The decoded image.
    pub image: Arc<TextureImage>,
}

/// A decoded image in linear RGB, with its mip levels (level 0 = full size).
#[derive(Debug, PartialEq)]
pub struct TextureImage {
    levels: Vec<Level>,
}

#[derive(Debug, PartialEq)]
struct Level {
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
}

impl TextureImage {
    /// The width and height `bytes` announce in their header, refusing images wider or taller
    /// than [`MAX_IMAGE_SIDE`] or with more than [`MAX_IMAGE_PIXELS`]; nothing is decoded.
    /// `name` is only used in error messages.
    pub fn size(bytes: &[u8], name: &Path) -> Result<(u32, u32), String> {
        let (w, h) = reader(bytes, name)?
            .into_dimensions()
            .map_err(|e| cannot_read(name, &decode_failure(&e)))?;
        if w > MAX_IMAGE_SIDE
            || h > MAX_IMAGE_SIDE
            || u64::from(w) * u64::from(h) > MAX_IMAGE_PIXELS
        {
            return Err(format!(
                "image {} is {w}×{h} pixels, over the limit of {MAX_IMAGE_SIDE} pixels a side and {} million pixels",
                name.display(),
                MAX_IMAGE_PIXELS / 1_000_000
            ));
        }
        Ok((w, h))
    }

    /// Decodes `bytes` (after checking their size, see [`TextureImage::size`]); `name` is only
    /// used in error messages.
    pub fn decode(bytes: &[u8], name: &Path) -> Result<Self, String> {
        Self::size(bytes, name)?;
        let reader = reader(bytes, name)?;
        if let Some(missing) = reader.format().and_then(|f| missing_end(f, bytes)) {
            return Err(cannot_read(
                name,
                &format!("the file is truncated: {missing}"),
            ));
        }
        let decoded = reader
            .decode()
            .map_err(|e| cannot_read(name, &decode_failure(&e)))?
            .into_rgb8();
        let (width, height) = (decoded.width() as usize, decoded.height() as usize);
        if width == 0 || height == 0 {
            return Err(format!("image {} is empty", name.display()));
        }
        let lut: Vec<f32> = (0..256)
            .map(|i| super::srgb_to_linear(f64::from(i) / 255.0) as f32)
            .collect();
        let texels = decoded
            .pixels()
            .map(|p| p.0.map(|c| lut[usize::from(c)]))
            .collect();
        let mut levels = vec![Level {
            width,
            height,
            texels,
        }];
        while let Some(next) = levels.last().and_then(Level::halved) {
            levels.push(next);
        }
        Ok(TextureImage { levels })
    }

    /// Width of the full-size image, pixels.
    pub fn width(&self) -> usize {
        self.levels[0].width
    }

    /// Height of the full-size image, pixels.
    pub fn height(&self) -> usize {
        self.levels[0].height
    }

    /// Bilinear sample at (u, v) in tile units (the image repeats every 1 in u and v; v grows
    /// downwards in the image), from the mip level whose texels are about `texel` tile units
    /// wide (the pixel footprint divided by the tile size).
    pub fn sample(&self, u: f64, v: f64, texel: f64) -> [f64; 3] {
        let wanted = (texel * self.width() as f64).max(1.0).log2().floor() as usize;
        self.levels[wanted.min(self.levels.len() - 1)].bilinear(u, v)
    }
}

fn reader<'a>(
    bytes: &'a [u8],
    name: &Path,
) -> Result<::image::ImageReader<std::io::Cursor<&'a [u8]>>, String> {
    ::image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| cannot_read(name, &e))
}

fn cannot_read(name: &Path, e: &dyn std::fmt::Display) -> String {
    format!("cannot read image {}: {e}", name.display())
}

/// What a decoder's refusal says about the file: one that ends early is truncated; one whose
/// data do not decode is corrupt, or truncated (decoders cannot always tell which); the
/// decoder's own words follow. Bare, they read like a program's fault ("failed to fill whole
/// buffer").
pub(crate) fn decode_failure(e: &::image::ImageError) -> String {
    use ::image::ImageError;
    let words = e.to_string();
    let words = words.trim();
    match e {
        ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "the file is truncated: it ends before the image does".into()
        }
        ImageError::Decoding(_) | ImageError::IoError(_) => {
            format!("the file is truncated or corrupt ({words})")
        }
        _ => words.into(),
    }
}

/// What a file cut short lacks, if it lacks it: the decoders read as far as the pixels go, a
/// JPEG's filling the missing rows with grey, a PNG's not needing the closing chunk.
///
/// A JPEG's end-of-image marker (FF D9) must follow its first scan (FF DA): entropy-coded data
/// escape every FF byte, so the marker cannot occur inside a scan. A PNG ends with its IEND
/// chunk, whole. Data appended after either (camera trailers) do not matter.
fn missing_end(format: ::image::ImageFormat, bytes: &[u8]) -> Option<&'static str> {
    let find = |from: usize, m: &[u8]| {
        bytes
            .get(from..)?
            .windows(m.len())
            .position(|w| w == m)
            .map(|at| from + at)
    };
    match format {
        ::image::ImageFormat::Jpeg => {
            let ended = find(0, &[0xFF, 0xDA]).and_then(|scan| find(scan, &[0xFF, 0xD9]));
            ended
                .is_none()
                .then_some("the JPEG ends before its end-of-image marker")
        }
        ::image::ImageFormat::Png => {
            // The chunk's type, then its 4-byte CRC.
            let ended = find(8, b"IEND").is_some_and(|at| at + 8 <= bytes.len());
            (!ended).then_some("the PNG ends before its IEND chunk does")
        }
        _ => None,
    }
}

impl Level {
    /// The next mip level: 2 × 2 box filter (the last row or column repeats on odd sizes).
    fn halved(&self) -> Option<Level> {
        if self.width == 1 && self.height == 1 {
            return None;
        }
        let (width, height) = (self.width.div_ceil(2), self.height.div_ceil(2));
        let at = |x: usize, y: usize| {
            self.texels[y.min(self.height - 1) * self.width + x.min(self.width - 1)]
        };
        let texels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| {
                let quad = [
                    at(2 * x, 2 * y),
                    at(2 * x + 1, 2 * y),
                    at(2 * x, 2 * y + 1),
                    at(2 * x + 1, 2 * y + 1),
                ];
                std::array::from_fn(|c| quad.iter().map(|t| t[c]).sum::<f32>() / 4.0)
            })
            .collect();
        Some(Level {
            width,
            height,
            texels,
        })
    }

    fn bilinear(&self, u: f64, v: f64) -> [f64; 3] {
        let x = u.rem_euclid(1.0) * self.width as f64 - 0.5;
        let y = v.rem_euclid(1.0) * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let wrap = |i: f64, n: usize| (i as i64).rem_euclid(n as i64) as usize;
        let texel = |dx: f64, dy: f64| {
            self.texels[wrap(y0 + dy, self.height) * self.width + wrap(x0 + dx, self.width)]
        };
        let (a, b, c, d) = (
            texel(0.0, 0.0),
            texel(1.0, 0.0),
            texel(0.0, 1.0),
            texel(1.0, 1.0),
        );
        std::array::from_fn(|k| {
            let top = f64::from(a[k]) * (1.0 - fx) + f64::from(b[k]) * fx;
            let bottom = f64::from(c[k]) * (1.0 - fx) + f64::from(d[k]) * fx;
            top * (1.0 - fy) + bottom * fy
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A PNG encoded by the `png` crate (an independent writer), decoded here.
    fn png(width: u32, height: u32, rgb: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(rgb).unwrap();
        writer.finish().unwrap();
        out
    }

    #[test]
    fn texel_centres_read_back_and_tiles_repeat() {
        // 2 × 1 image: black | white (sRGB 255 = linear 1).
        let img =
            TextureImage::decode(&png(2, 1, &[0, 0, 0, 255, 255, 255]), Path::new("t")).unwrap();
        assert_eq!(img.sample(0.25, 0.5, 0.0), [0.0; 3]);
        assert_eq!(img.sample(0.75, 0.5, 0.0), [1.0; 3]);
        assert_eq!(img.sample(1.75, -3.5, 0.0), [1.0; 3]);
        // Half-way between texel centres (and across the wrap) is the average.
        assert!((img.sample(0.5, 0.5, 0.0)[0] - 0.5).abs() < 1e-6);
        assert!((img.sample(0.0, 0.5, 0.0)[0] - 0.5).abs() < 1e-6);
    }

    #[test]
    fn far_away_tiles_read_their_mean() {
        let checker: Vec<u8> = (0..64 * 64)
            .flat_map(|i| {
                let on = ((i % 64) + (i / 64)) % 2 == 0;
                [if on { 255 } else { 0 }; 3]
            })
            .collect();
        let img = TextureImage::decode(&png(64, 64, &checker), Path::new("c")).unwrap();
        // A footprint of a whole tile reads the 1 × 1 level: the mean, 0.5 in linear light.
        for (u, v) in [(0.1, 0.2), (0.77, 0.31)] {
            assert!((img.sample(u, v, 1.0)[1] - 0.5).abs() < 1e-6);
        }
    }

    #[test]
    fn oversized_images_are_refused_from_their_header() {
        let big = png(20_000, 1, &[0; 60_000]);
        let e = TextureImage::decode(&big, Path::new("huge.png")).unwrap_err();
        assert!(
            e.contains("huge.png is 20000×1 pixels, over the limit"),
            "{e}"
        );
    }

    #[test]
    fn broken_files_are_errors_naming_the_file() {
        let e = TextureImage::decode(b"not an image", Path::new("textures/rust.png")).unwrap_err();
        assert!(e.contains("textures/rust.png"), "{e}");
    }

    fn refusal(bytes: &[u8], name: &str, share: f64) -> String {
        match TextureImage::decode(bytes, Path::new(name)) {
            Ok(_) => panic!("{name} ({share} of it) decoded"),
            Err(e) => e,
        }
    }

    /// A file cut short, or damaged, says which file and that it is truncated or corrupt,
    /// whatever the decoder's own words; a JPEG missing only its last bytes is not decoded
    /// into grey rows.
    #[test]
    fn truncated_and_corrupt_images_say_so() {
        let pixels = ::image::RgbImage::from_fn(64, 32, |x, y| ::image::Rgb([x as u8, y as u8, 7]));
        for (name, format) in [
            ("rust.png", ::image::ImageFormat::Png),
            ("rust.jpg", ::image::ImageFormat::Jpeg),
        ] {
            let mut file = Vec::new();
            pixels
                .write_to(&mut std::io::Cursor::new(&mut file), format)
                .unwrap();
            for share in [0.05, 0.3, 0.6, 0.99] {
                let cut = &file[..(file.len() as f64 * share) as usize];
                let e = refusal(cut, name, share);
                assert!(e.contains(name) && e.contains("truncated"), "{share}: {e}");
                assert!(!e.contains('\n'), "{e:?}");
            }
            let mut damaged = file.clone();
            let middle = damaged.len() / 2;
            for b in &mut damaged[middle..middle + 40] {
                *b ^= 0x5a;
            }
            let e = refusal(&damaged, name, 1.0);
            assert!(e.contains(name) && e.contains("corrupt"), "{e}");
        }
    }
}
