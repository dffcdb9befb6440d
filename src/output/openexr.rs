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
//! order, so the bytes never depend on the thread count either. Values are stored exactly;
//! only the compressed bytes differ from the `exr` crate's.

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
    // Blocks of background alone (all zeros) are common and compress to the same bytes:
    // compressed once.
    let empty = std::sync::OnceLock::new();
    let blocks: Vec<Vec<u8>> = (0..h.div_ceil(LINES_PER_BLOCK))
        .into_par_iter()
        .map(|block| {
            let rows = block * LINES_PER_BLOCK..((block + 1) * LINES_PER_BLOCK).min(h);
            let pixels = rows.start * w..rows.end * w;
            let background = (rows.len() == LINES_PER_BLOCK)
                && channels
                    .iter()
                    .all(|(_, values)| all_zero(&values[pixels.clone()]));
            if background {
                empty
                    .get_or_init(|| zip_block(&raw_block(rows.clone(), w, channels)))
                    .clone()
            } else {
                zip_block(&raw_block(rows, w, channels))
            }
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
        (note.0, "text", note.1.as_bytes()),
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

/// OpenEXR's ZIP of one block: the predictor and interleave, then zlib; the raw bytes instead
/// when compression would not make them smaller (readers tell the two apart by the size).
fn zip_block(raw: &[u8]) -> Vec<u8> {
    let compressed = miniz_oxide::deflate::compress_to_vec_zlib(&predicted(raw), DEFLATE_LEVEL);
    if compressed.len() < raw.len() {
        compressed
    } else {
        raw.to_vec()
    }
}

/// Even bytes first, then odd ones (so the bytes of like significance of neighbouring values
/// follow each other), then each byte replaced by its difference from the previous one + 128.
fn predicted(raw: &[u8]) -> Vec<u8> {
    let half = raw.len().div_ceil(2);
    let mut split = vec![0u8; raw.len()];
    let (evens, odds) = split.split_at_mut(half);
    let pairs = raw.chunks_exact(2);
    if let [last] = pairs.remainder() {
        evens[half - 1] = *last;
    }
    for ((pair, even), odd) in pairs.zip(evens.iter_mut()).zip(odds.iter_mut()) {
        *even = pair[0];
        *odd = pair[1];
    }
    // Each difference is of two split bytes, not of an earlier difference: the loop carries
    // nothing from one byte to the next.
    let mut out = split.clone();
    if let Some(rest) = out.get_mut(1..) {
        for ((out, &current), &previous) in rest.iter_mut().zip(&split[1..]).zip(&split) {
            *out = current.wrapping_sub(previous).wrapping_add(128);
        }
    }
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

    #[test]
    fn incompressible_blocks_are_stored_raw() {
        assert_eq!(zip_block(&[9, 8, 7, 6]), vec![9, 8, 7, 6]);
    }
}
