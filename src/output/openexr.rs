//! The OpenEXR writer: single-part scanline files of float32 channels, ZIP-compressed
//! (zlib over blocks of 16 scanlines), scanlines in increasing order.
//!
//! Owns: the bytes of an EXR file (header, offset table, chunks) and OpenEXR's ZIP transform
//! (bytes split into even and odd halves, then each byte replaced by its difference from the
//! one before plus 128, then zlib). Must not touch: what the channels mean or their validity
//! (`encode` checks values are finite and names the layers).
//!
//! Written here rather than through the `exr` crate because that crate's ZIP is miniz at level
//! 4 on one thread plus several copies of the image: most of what a depth file cost. Here the
//! blocks are compressed at miniz level 1 (pure Rust, no code path that depends on CPU
//! features, so the same bytes on every x86-64 machine) in parallel and assembled in block
//! order, so the bytes never depend on the thread count either. Each thread keeps its
//! compressor and buffers between blocks and files (`Zipper`): a fresh compressor's tables
//! cost more than compressing a mostly empty block, and the depth of a 960² quickstart view
//! is written in 0.7–2.7 ms instead of 2.3–4.6. Values are stored exactly; only the
//! compressed bytes differ from the `exr` crate's.

use miniz_oxide::deflate::core::{
    CompressorOxide, TDEFLFlush, TDEFLStatus, compress, create_comp_flags_from_zip_params,
};
use rayon::prelude::*;

/// Scanlines per ZIP block (OpenEXR's `ZIP_COMPRESSION`).
const LINES_PER_BLOCK: usize = 16;

/// OpenEXR's code of `ZIP_COMPRESSION`.
const ZIP_COMPRESSION: u8 = 3;

/// OpenEXR's pixel type code of float32 samples.
const FLOAT: i32 = 2;

/// miniz level: its fastest matcher (one probe, greedy). Level 4, the `exr` crate's, makes
/// files about a fifth smaller at three and a half times the time.
const DEFLATE_LEVEL: u8 = 1;

/// A float32 EXR of `width` × `height` pixels whose channels are `(name, values)`, row-major,
/// in the given order (which must be EXR's: sorted by name), with one extra text attribute
/// `note` = (name, text). Names must be 1 to 31 bytes (no long-name flag).
pub fn float_exr(
    (width, height): (u32, u32),
    channels: &[(&str, &[f32])],
    note: (&str, &str),
) -> Vec<u8> {
    let (w, h) = (width as usize, height as usize);
    debug_assert!(channels.windows(2).all(|p| p[0].0 < p[1].0), "sorted names");
    debug_assert!(channels.iter().all(|(_, v)| v.len() == w * h));
    let header = header((width, height), channels, note);
    let blocks: Vec<Vec<u8>> = (0..h.div_ceil(LINES_PER_BLOCK))
        .into_par_iter()
        .map(|block| {
            let rows = block * LINES_PER_BLOCK..((block + 1) * LINES_PER_BLOCK).min(h);
            let pixels = rows.start * w..rows.end * w;
            let background = (rows.len() == LINES_PER_BLOCK)
                && channels
                    .iter()
                    .all(|(_, values)| all_zero(&values[pixels.clone()]));
            ZIPPER.with_borrow_mut(|zipper| {
                if background {
                    zipper.background(w, channels.len()).to_vec()
                } else {
                    zipper.zip(rows, w, channels)
                }
            })
        })
        .collect();
    let table = 8 * blocks.len();
    let body: usize = blocks.iter().map(|b| 8 + b.len()).sum();
    let mut out = Vec::with_capacity(header.len() + table + body);
    out.extend_from_slice(&header);
    let mut offset = (header.len() + table) as u64;
    for block in &blocks {
        out.extend_from_slice(&offset.to_le_bytes());
        offset += 8 + block.len() as u64;
    }
    for (index, block) in blocks.iter().enumerate() {
        let y = (index * LINES_PER_BLOCK) as i32;
        out.extend_from_slice(&y.to_le_bytes());
        out.extend_from_slice(&(block.len() as i32).to_le_bytes());
        out.extend_from_slice(block);
    }
    out
}

/// Whether every value is +0.0 (a background pixel), in runs the compiler can vectorise.
fn all_zero(values: &[f32]) -> bool {
    values
        .chunks(64)
        .all(|run| run.iter().fold(0, |any, v| any | v.to_bits()) == 0)
}

/// Magic number, version 2 (single-part scanline, short names) and the header's attributes,
/// ending with the empty name that closes the header.
fn header((width, height): (u32, u32), channels: &[(&str, &[f32])], note: (&str, &str)) -> Vec<u8> {
    let mut out = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
    let mut list = Vec::new();
    for (name, _) in channels {
        list.extend_from_slice(&c_string(name));
        list.extend_from_slice(&FLOAT.to_le_bytes());
        list.extend_from_slice(&[0, 0, 0, 0]); // pLinear, reserved
        list.extend_from_slice(&1i32.to_le_bytes()); // x sampling
        list.extend_from_slice(&1i32.to_le_bytes()); // y sampling
    }
    list.push(0);
    let window: Vec<u8> = [0, 0, width as i32 - 1, height as i32 - 1]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let one = 1.0f32.to_le_bytes();
    let attributes: [(&str, &str, &[u8]); 9] = [
        ("channels", "chlist", &list),
        ("compression", "compression", &[ZIP_COMPRESSION]),
        ("dataWindow", "box2i", &window),
        ("displayWindow", "box2i", &window),
        ("lineOrder", "lineOrder", &[0]), // increasing y
        ("pixelAspectRatio", "float", &one),
        ("screenWindowCenter", "v2f", &[0; 8]),
        ("screenWindowWidth", "float", &one),
        (note.0, "string", note.1.as_bytes()),
    ];
    for (name, kind, value) in attributes {
        out.extend_from_slice(&c_string(name));
        out.extend_from_slice(&c_string(kind));
        out.extend_from_slice(&(value.len() as i32).to_le_bytes());
        out.extend_from_slice(value);
    }
    out.push(0);
    out
}

/// A name as EXR stores it: its bytes and a terminating zero.
fn c_string(name: &str) -> Vec<u8> {
    assert!(
        (1..32).contains(&name.len()) && !name.contains('\0'),
        "EXR name {name:?}: 1 to 31 bytes without NUL"
    );
    let mut bytes = name.as_bytes().to_vec();
    bytes.push(0);
    bytes
}

/// What compressing a block needs, kept by each thread between blocks and files: a zlib
/// compressor (some 300 kB of tables, which allocating and zeroing anew for each block cost
/// more than compressing a mostly empty one), the block's bytes as the predictor leaves them,
/// the compressed output, and the compressed block of background alone (all zeros) for each
/// line width and channel count met, which every file has many of.
struct Zipper {
    compressor: Box<CompressorOxide>,
    split: Vec<u8>,
    predicted: Vec<u8>,
    out: Vec<u8>,
    background: Vec<((usize, usize), Vec<u8>)>,
}

thread_local! {
    static ZIPPER: std::cell::RefCell<Zipper> = std::cell::RefCell::new(Zipper {
        compressor: Box::new(CompressorOxide::new(create_comp_flags_from_zip_params(
            DEFLATE_LEVEL.into(),
            1, // a zlib stream
            0, // the default strategy
        ))),
        split: Vec::new(),
        predicted: Vec::new(),
        out: Vec::new(),
        background: Vec::new(),
    });
}

impl Zipper {
    /// OpenEXR's ZIP of scanlines `rows` of `channels` (each line holds every channel's samples
    /// in turn, little-endian): the predictor and interleave, then zlib; the raw bytes instead
    /// when compression would not make them smaller (readers tell the two apart by the size).
    fn zip(
        &mut self,
        rows: std::ops::Range<usize>,
        width: usize,
        channels: &[(&str, &[f32])],
    ) -> Vec<u8> {
        let lines = rows.clone().flat_map(|row| {
            channels
                .iter()
                .map(move |(_, values)| &values[row * width..(row + 1) * width])
        });
        split_bytes(lines, width, &mut self.split);
        predict(&self.split, &mut self.predicted);
        let size = self.split.len();
        let compressed = self.compress();
        if compressed.len() < size {
            compressed.to_vec()
        } else {
            raw_block(rows, width, channels)
        }
    }

    /// The ZIP of a full block of zeros, `width` samples a line, `channels` channels.
    fn background(&mut self, width: usize, channels: usize) -> &[u8] {
        let key = (width, channels);
        if let Some(i) = self.background.iter().position(|(k, _)| *k == key) {
            return &self.background[i].1;
        }
        let zeros = vec![0.0f32; width];
        let lines = std::iter::repeat_n(zeros.as_slice(), LINES_PER_BLOCK * channels);
        split_bytes(lines, width, &mut self.split);
        predict(&self.split, &mut self.predicted);
        let zipped = self.compress().to_vec();
        self.background.push((key, zipped));
        &self.background.last().expect("just pushed").1
    }

    /// zlib at `DEFLATE_LEVEL` of the predicted bytes.
    fn compress(&mut self) -> &[u8] {
        // Deflate's worst case adds 5 bytes per 64 kB stored block, zlib 6 in all: one call
        // always finishes.
        self.out
            .resize(self.predicted.len() + self.predicted.len() / 1024 + 64, 0);
        self.compressor.reset();
        let (status, _, written) = compress(
            &mut self.compressor,
            &self.predicted,
            &mut self.out,
            TDEFLFlush::Finish,
        );
        assert_eq!(status, TDEFLStatus::Done, "zlib output fits its buffer");
        &self.out[..written]
    }
}

/// The uncompressed bytes of scanlines `rows`: each line holds every channel's samples in
/// turn, little-endian.
fn raw_block(rows: std::ops::Range<usize>, width: usize, channels: &[(&str, &[f32])]) -> Vec<u8> {
    let line = 4 * width;
    let mut raw = vec![0u8; rows.len() * channels.len() * line];
    let mut lines = raw.chunks_exact_mut(line);
    for row in rows {
        for (_, values) in channels {
            let out = lines.next().expect("one line per row and channel");
            let samples = &values[row * width..(row + 1) * width];
            for (bytes, v) in out.chunks_exact_mut(4).zip(samples) {
                bytes.copy_from_slice(&v.to_le_bytes());
            }
        }
    }
    raw
}

/// The bytes of `lines` of `width` samples each, as `raw_block` lays them out, split into the
/// even bytes first and the odd ones after (so the bytes of like significance of neighbouring
/// values follow each other): of a little-endian float32, bytes 0 and 2 are even, 1 and 3 odd.
fn split_bytes<'a>(lines: impl Iterator<Item = &'a [f32]>, width: usize, split: &mut Vec<u8>) {
    let lines: Vec<&[f32]> = lines.collect();
    let half = 2 * width * lines.len();
    split.resize(2 * half, 0);
    let (evens, odds) = split.split_at_mut(half);
    let out = evens
        .chunks_exact_mut(2 * width)
        .zip(odds.chunks_exact_mut(2 * width));
    for (samples, (even, odd)) in lines.into_iter().zip(out) {
        for ((v, e), o) in samples
            .iter()
            .zip(even.chunks_exact_mut(2))
            .zip(odd.chunks_exact_mut(2))
        {
            let [b0, b1, b2, b3] = v.to_le_bytes();
            e.copy_from_slice(&[b0, b2]);
            o.copy_from_slice(&[b1, b3]);
        }
    }
}

/// OpenEXR's predictor over split bytes: the first kept, then each replaced by its difference
/// from the one before, plus 128.
fn predict(split: &[u8], out: &mut Vec<u8>) {
    out.clear();
    out.extend_from_slice(split);
    // Each difference is of two split bytes, not of an earlier difference: the loop carries
    // nothing from one byte to the next.
    if let Some(rest) = out.get_mut(1..) {
        for ((out, &current), &previous) in rest.iter_mut().zip(&split[1..]).zip(split) {
            *out = current.wrapping_sub(previous).wrapping_add(128);
        }
    }
}

/// Even bytes first, then odd ones, then OpenEXR's predictor (`predict`), of any bytes.
#[cfg(test)]
fn predicted(raw: &[u8]) -> Vec<u8> {
    let split: Vec<u8> = raw
        .iter()
        .step_by(2)
        .chain(raw.iter().skip(1).step_by(2))
        .copied()
        .collect();
    let mut out = Vec::new();
    predict(&split, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn predictor_matches_openexr_on_a_small_block() {
        // ImfZip.cpp: reorder [1, 2, 3, 4, 5] → [1, 3, 5, 2, 4], then d = t[i] − t[i−1] + 128.
        assert_eq!(
            predicted(&[1, 2, 3, 4, 5]),
            vec![1, 130, 130, 125, 130],
            "first byte kept, then differences + 128 (mod 256)"
        );
        assert_eq!(predicted(&[]), Vec::<u8>::new());
        assert_eq!(predicted(&[7]), vec![7]);
    }

    /// Scanlines of depth-like values: background (zeros) around a band of smooth depths
    /// with noisy low bits, `width` wide, over `height` lines.
    fn depth_like(width: usize, height: usize) -> Vec<f32> {
        (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as f32, (i / width) as f32);
                let inside = (x - 0.4 * width as f32).abs() < 0.2 * width as f32 + y;
                if inside {
                    3.0 + 0.01 * x + 0.001 * (i as f32 * 0.37).sin()
                } else {
                    0.0
                }
            })
            .collect()
    }

    #[test]
    fn blocks_are_the_one_shot_zlib_of_the_predicted_bytes() {
        // Kept state (compressor, buffers) changes nothing: every block, the first or after
        // others of other sizes, is what miniz's one-shot zlib at the same level gives.
        let (width, height) = (37, 40);
        let (depth, other) = (depth_like(width, height), depth_like(width, height + 3));
        let channels = [("Y", &other[..width * height]), ("Z", &depth[..])];
        let mut compressed = 0;
        ZIPPER.with_borrow_mut(|zipper| {
            for channels in [&channels[1..], &channels[..], &channels[1..]] {
                for rows in [0..16, 16..32, 32..40] {
                    let raw = raw_block(rows.clone(), width, channels);
                    let want = miniz_oxide::deflate::compress_to_vec_zlib(&predicted(&raw), 1);
                    compressed += usize::from(want.len() < raw.len());
                    let want = if want.len() < raw.len() { want } else { raw };
                    assert_eq!(zipper.zip(rows, width, channels), want);
                }
                let zeros = vec![0.0f32; width * LINES_PER_BLOCK];
                let blank: Vec<(&str, &[f32])> =
                    channels.iter().map(|(n, _)| (*n, &zeros[..])).collect();
                let raw = raw_block(0..LINES_PER_BLOCK, width, &blank);
                let want = miniz_oxide::deflate::compress_to_vec_zlib(&predicted(&raw), 1);
                assert_eq!(zipper.background(width, channels.len()), want);
            }
        });
        assert!(compressed >= 6, "{compressed} of 9 blocks compressed");
    }

    #[test]
    fn incompressible_blocks_are_stored_raw() {
        // Four samples whose bytes repeat nothing: zlib's header and checksum alone make the
        // compressed block longer than the 16 raw bytes.
        let values = [
            1.234_567_8e-3f32,
            -7.654_321e5,
            std::f32::consts::PI,
            2.718_281_7e-9,
        ];
        let channels = [("Z", &values[..])];
        let raw = raw_block(0..1, 4, &channels);
        assert_eq!(ZIPPER.with_borrow_mut(|z| z.zip(0..1, 4, &channels)), raw);
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        assert_eq!(raw, bytes);
    }
}
