//! An RGB8 drawing surface for the contact sheet: filled rectangles, pasted images and text in
//! an 8 × 8 bitmap font (the glyphs of the `font8x8` crate, MIT, compiled in: nothing is
//! loaded at run time), everything clipped to the surface.
//!
//! Owns: the pixels, clipping, glyph lookup and text measurement. Knows nothing of what the
//! sheet says or where.

use font8x8::legacy::{BASIC_LEGACY, LATIN_LEGACY};

/// One sRGB pixel.
pub type Rgb = [u8; 3];

/// Side of a glyph at scale 1, pixels.
pub const GLYPH: u32 = 8;

/// An RGB8 image being drawn on.
pub struct Canvas {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
}

impl Canvas {
    /// A `width` × `height` canvas filled with `fill`.
    pub fn new(width: u32, height: u32, fill: Rgb) -> Self {
        Canvas {
            width,
            height,
            pixels: fill.repeat(width as usize * height as usize),
        }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Row-major RGB8 bytes.
    pub fn pixels(&self) -> &[u8] {
        &self.pixels
    }

    /// The pixel at (x, y); panics outside the canvas.
    #[cfg(test)]
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]]
    }

    /// Sets (x, y) to `colour`; a pixel off the canvas is skipped.
    pub fn set(&mut self, x: i64, y: i64, colour: Rgb) {
        if x < 0 || y < 0 || x >= i64::from(self.width) || y >= i64::from(self.height) {
            return;
        }
        let i = 3 * (y as usize * self.width as usize + x as usize);
        self.pixels[i..i + 3].copy_from_slice(&colour);
    }

    /// Fills the `width` × `height` rectangle at (x, y).
    pub fn fill(&mut self, x: u32, y: u32, width: u32, height: u32, colour: Rgb) {
        for row in y..y.saturating_add(height) {
            for column in x..x.saturating_add(width) {
                self.set(i64::from(column), i64::from(row), colour);
            }
        }
    }

    /// Copies a `width`-wide image, row-major, with its top-left corner at (x, y).
    pub fn paste(&mut self, x: u32, y: u32, width: u32, image: &[Rgb]) {
        for (i, &colour) in image.iter().enumerate() {
            let (dx, dy) = (i as u32 % width, i as u32 / width);
            self.set(i64::from(x + dx), i64::from(y + dy), colour);
        }
    }

    /// Draws `text` with its top-left corner at (x, y), each font pixel a `scale` × `scale`
    /// square; returns the width drawn.
    pub fn text(&mut self, x: u32, y: u32, text: &str, scale: u32, colour: Rgb) -> u32 {
        for (i, c) in text.chars().enumerate() {
            let left = x + i as u32 * GLYPH * scale;
            for (row, bits) in glyph(c).iter().enumerate() {
                for column in 0..GLYPH {
                    if bits & (1 << column) != 0 {
                        let (px, py) = (left + column * scale, y + row as u32 * scale);
                        self.fill(px, py, scale, scale, colour);
                    }
                }
            }
        }
        text_width(text, scale)
    }
}

/// The bitmap of `c`: byte `row`, bit `column` (bit 0 the leftmost pixel). Basic Latin and
/// Latin-1 (which has `·`, `×` and `µ`); any other character is drawn as `?`.
pub fn glyph(c: char) -> [u8; 8] {
    match u32::from(c) {
        code @ 0x20..=0x7e => BASIC_LEGACY[code as usize],
        code @ 0xa0..=0xff => LATIN_LEGACY[(code - 0xa0) as usize],
        _ => BASIC_LEGACY[usize::from(b'?')],
    }
}

/// Width of `text` drawn at `scale`, pixels.
pub fn text_width(text: &str, scale: u32) -> u32 {
    text.chars().count() as u32 * GLYPH * scale
}

/// The largest scale from `largest` down to 1 at which `text` fits in `width`; 1 if none does.
pub fn fitting_scale(text: &str, width: u32, largest: u32) -> u32 {
    (1..=largest)
        .rev()
        .find(|&s| text_width(text, s) <= width)
        .unwrap_or(1)
}

/// `text` cut to fit `width` at `scale`, ending in ".." when cut.
pub fn clipped(text: &str, width: u32, scale: u32) -> String {
    let fits = (width / (GLYPH * scale)) as usize;
    if text.chars().count() <= fits {
        return text.to_string();
    }
    let kept: String = text.chars().take(fits.saturating_sub(2)).collect();
    format!("{kept}..")
}

/// `text` in lines of at most `width` at `scale`, broken at spaces; a word too long for a line
/// is cut (see `clipped`).
pub fn wrapped(text: &str, width: u32, scale: u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(line) if text_width(&format!("{line} {word}"), scale) <= width => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines.iter().map(|l| clipped(l, width, scale)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_glyph_is_drawn_as_the_font_bitmap_at_scale() {
        let mut canvas = Canvas::new(40, 30, [0; 3]);
        let width = canvas.text(3, 5, "A", 2, [255; 3]);
        assert_eq!(width, 16);
        // The font's 'A' is 0x0C, 0x1E, 0x33, 0x33, 0x3F, 0x33, 0x33, 0x00 (IBM PC BIOS style).
        let a = [0x0C_u8, 0x1E, 0x33, 0x33, 0x3F, 0x33, 0x33, 0x00];
        for y in 0..30 {
            for x in 0..40 {
                let inside = (3..19).contains(&x) && (5..21).contains(&y);
                let lit = inside && a[((y - 5) / 2) as usize] & (1 << ((x - 3) / 2)) != 0;
                let expected = if lit { [255; 3] } else { [0; 3] };
                assert_eq!(canvas.get(x, y), expected, "({x}, {y})");
            }
        }
    }

    #[test]
    fn latin1_has_the_signs_the_sheet_uses_and_others_fall_back() {
        for c in ['·', '×', 'µ', '°'] {
            assert_ne!(glyph(c), [0; 8], "{c}");
            assert_ne!(glyph(c), glyph('?'), "{c}");
        }
        assert_eq!(glyph('→'), glyph('?'));
    }

    #[test]
    fn text_is_clipped_to_the_canvas_and_to_a_width() {
        let mut canvas = Canvas::new(10, 10, [0; 3]);
        canvas.text(6, 6, "WW", 3, [255; 3]);
        assert_eq!(canvas.pixels().len(), 300);
        assert_eq!(clipped("abcdef", 40, 1), "abc..");
        assert_eq!(clipped("abc", 40, 1), "abc");
        assert_eq!(fitting_scale("abc", 48, 3), 2);
        assert_eq!(fitting_scale("abc", 10, 3), 1);
        assert_eq!(wrapped("rest depth", 64, 1), ["rest", "depth"]);
        assert_eq!(wrapped("rest depth", 80, 1), ["rest depth"]);
        assert_eq!(wrapped("displacement", 64, 1), ["displa.."]);
    }
}
