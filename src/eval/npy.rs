//! A reader of NumPy `.npy` arrays of float32 or float64 (and, for flags, bool or uint8), as
//! the format is specified in NumPy's NEP 1 ("A simple file format for NumPy arrays"): the magic `\x93NUMPY`, a version
//! (1.0, 2.0 or 3.0), the header's length (2 bytes little-endian in 1.0, 4 in 2.0 and 3.0),
//! and the header itself, a Python dict literal with `descr`, `fortran_order` and `shape`,
//! followed by the data.
//!
//! Written here rather than taken from a crate: the reader crates parse the header with a
//! general Python-literal parser and its dependencies, while the three keys need a few lines.
//! Everything else (other dtypes, object arrays, pickles) is refused with a clear error.

use anyhow::{Result, bail};

/// An array: its shape and its values in C (row-major) order, as f64.
pub(super) struct Array {
    pub(super) shape: Vec<usize>,
    pub(super) values: Vec<f64>,
}

/// Parses a `.npy` file's bytes (float32 or float64).
pub(super) fn parse(bytes: &[u8]) -> Result<Array> {
    parse_of(bytes, false)
}

/// Parses a `.npy` file of flags: bool or uint8 (as 0.0, 1.0, …), or float32 or float64.
pub(super) fn parse_flags(bytes: &[u8]) -> Result<Array> {
    parse_of(bytes, true)
}

/// Parses a `.npy` file's bytes; one-byte dtypes (bool, uint8) only with `flags`.
fn parse_of(bytes: &[u8], flags: bool) -> Result<Array> {
    let Some(rest) = bytes.strip_prefix(b"\x93NUMPY") else {
        bail!("not a .npy file (no \\x93NUMPY magic)");
    };
    let (header, data) = match rest {
        [1, _, a, b, rest @ ..] => split(rest, u16::from_le_bytes([*a, *b]) as usize)?,
        [2 | 3, _, a, b, c, d, rest @ ..] => {
            split(rest, u32::from_le_bytes([*a, *b, *c, *d]) as usize)?
        }
        [major, ..] => bail!(".npy format version {major} is not supported (1, 2 or 3)"),
        [] => bail!("truncated .npy header"),
    };
    let header =
        std::str::from_utf8(header).map_err(|_| anyhow::anyhow!(".npy header is not text"))?;
    let fields = Dict::parse(header)?;
    let (size, big_endian) = match fields.descr.as_str() {
        "<f4" => (4, false),
        "<f8" => (8, false),
        ">f4" => (4, true),
        ">f8" => (8, true),
        "|b1" | "|u1" if flags => (1, false),
        other if flags => bail!(
            ".npy dtype {other:?} is not bool, uint8, float32 or float64 ('|b1', '|u1', '<f4', '<f8')"
        ),
        other => bail!(".npy dtype {other:?} is not float32 or float64 ('<f4', '<f8')"),
    };
    let count = fields
        .shape
        .iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d))
        .filter(|n| n.checked_mul(size).is_some())
        .ok_or_else(|| anyhow::anyhow!(".npy shape {:?} is too large", fields.shape))?;
    if data.len() != count * size {
        bail!(
            ".npy data is {} bytes, shape {:?} of {}-byte values needs {}",
            data.len(),
            fields.shape,
            size,
            count * size
        );
    }
    let stored: Vec<f64> = data
        .chunks_exact(size)
        .map(|c| match (size, big_endian) {
            (1, _) => f64::from(c[0]),
            (4, false) => f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            (4, true) => f64::from(f32::from_be_bytes([c[0], c[1], c[2], c[3]])),
            (_, false) => f64::from_le_bytes(c.try_into().unwrap_or_default()),
            (_, true) => f64::from_be_bytes(c.try_into().unwrap_or_default()),
        })
        .collect();
    let values = if fields.fortran_order {
        c_order(&stored, &fields.shape)
    } else {
        stored
    };
    Ok(Array {
        shape: fields.shape,
        values,
    })
}

fn split(rest: &[u8], len: usize) -> Result<(&[u8], &[u8])> {
    if rest.len() < len {
        bail!("truncated .npy header");
    }
    Ok(rest.split_at(len))
}

/// Values stored column-major (Fortran order: the first index varies fastest) in row-major
/// order.
fn c_order(stored: &[f64], shape: &[usize]) -> Vec<f64> {
    let mut out = vec![0.0; stored.len()];
    let mut index = vec![0usize; shape.len()];
    for value in out.iter_mut() {
        // `index` walks C order; its Fortran offset has the first index fastest.
        let mut offset = 0;
        for (axis, &i) in index.iter().enumerate().rev() {
            offset = offset * shape[axis] + i;
        }
        *value = stored[offset];
        for axis in (0..shape.len()).rev() {
            index[axis] += 1;
            if index[axis] < shape[axis] {
                break;
            }
            index[axis] = 0;
        }
    }
    out
}

/// The three keys of the header dict.
struct Dict {
    descr: String,
    fortran_order: bool,
    shape: Vec<usize>,
}

impl Dict {
    /// Parses `{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }` (keys in any
    /// order, trailing comma and padding spaces allowed, as NumPy writes them).
    fn parse(text: &str) -> Result<Dict> {
        let bad = || anyhow::anyhow!(".npy header is not a dict literal: {:?}", text.trim());
        let inner = text
            .trim()
            .strip_prefix('{')
            .and_then(|t| t.strip_suffix('}'))
            .ok_or_else(bad)?;
        let (mut descr, mut fortran, mut shape) = (None, None, None);
        let mut rest = inner.trim_start();
        while !rest.is_empty() {
            let (key, after) = quoted(rest).ok_or_else(bad)?;
            let after = after
                .trim_start()
                .strip_prefix(':')
                .ok_or_else(bad)?
                .trim_start();
            rest = match key {
                "descr" => {
                    let (value, after) = quoted(after).ok_or_else(bad)?;
                    descr = Some(value.to_string());
                    after
                }
                "fortran_order" => {
                    let (value, after) = if let Some(a) = after.strip_prefix("True") {
                        (true, a)
                    } else if let Some(a) = after.strip_prefix("False") {
                        (false, a)
                    } else {
                        return Err(bad());
                    };
                    fortran = Some(value);
                    after
                }
                "shape" => {
                    let body = after.strip_prefix('(').ok_or_else(bad)?;
                    let (tuple, after) = body.split_once(')').ok_or_else(bad)?;
                    let dims = tuple
                        .split(',')
                        .map(str::trim)
                        .filter(|d| !d.is_empty())
                        .map(|d| d.trim_end_matches('L').parse::<usize>())
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(|_| bad())?;
                    shape = Some(dims);
                    after
                }
                _ => return Err(bad()),
            };
            rest = rest.trim_start();
            rest = rest.strip_prefix(',').unwrap_or(rest).trim_start();
        }
        match (descr, fortran, shape) {
            (Some(descr), Some(fortran_order), Some(shape)) => Ok(Dict {
                descr,
                fortran_order,
                shape,
            }),
            _ => Err(bad()),
        }
    }
}

/// A Python string literal in single or double quotes at the start of `text` (no escapes:
/// the header's keys and dtype strings have none), and what follows it.
fn quoted(text: &str) -> Option<(&str, &str)> {
    let quote = text.chars().next().filter(|c| *c == '\'' || *c == '"')?;
    let body = &text[1..];
    let end = body.find(quote)?;
    Some((&body[..end], &body[end + 1..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A version 1.0 file, byte by byte as NEP 1 lays it out (header padded with spaces and
    /// ended by a newline so the data starts on a multiple of 64 bytes).
    fn npy(header: &str, data: &[u8]) -> Vec<u8> {
        let mut h = header.to_string();
        while !(10 + h.len() + 1).is_multiple_of(64) {
            h.push(' ');
        }
        h.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(h.len() as u16).to_le_bytes());
        out.extend_from_slice(h.as_bytes());
        out.extend_from_slice(data);
        out
    }

    #[test]
    fn float32_and_float64_in_c_and_fortran_order() {
        let f32s: Vec<u8> = [1.5f32, -2.0, 3.25, 0.0, 5.0, 6.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let a = parse(&npy(
            "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }",
            &f32s,
        ))
        .unwrap();
        assert_eq!(a.shape, [2, 3]);
        assert_eq!(a.values, [1.5, -2.0, 3.25, 0.0, 5.0, 6.0]);
        // The same bytes in Fortran order are the transpose's rows: column 0 is (1.5, -2).
        let f = parse(&npy(
            "{'descr': '<f4', 'fortran_order': True, 'shape': (2, 3), }",
            &f32s,
        ))
        .unwrap();
        assert_eq!(f.values, [1.5, 3.25, 5.0, -2.0, 0.0, 6.0]);
        let f64s: Vec<u8> = [0.1f64, 0.2].iter().flat_map(|v| v.to_be_bytes()).collect();
        let b = parse(&npy(
            "{'shape': (1, 2), 'fortran_order': False, 'descr': '>f8'}",
            &f64s,
        ))
        .unwrap();
        assert_eq!((b.shape, b.values), (vec![1, 2], vec![0.1, 0.2]));
    }

    #[test]
    fn wrong_files_say_what_is_wrong() {
        let err = |bytes: &[u8]| format!("{}", parse(bytes).err().unwrap());
        assert!(err(b"PK\x03\x04").contains("magic"));
        assert!(
            err(&npy(
                "{'descr': '<i8', 'fortran_order': False, 'shape': (1,), }",
                &[0; 8]
            ))
            .contains("\"<i8\" is not float32")
        );
        assert!(
            err(&npy(
                "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), }",
                &[0; 12]
            ))
            .contains("12 bytes")
        );
        assert!(err(&npy("{'descr': '<f4'}", &[])).contains("not a dict"));
        assert!(err(b"\x93NUMPY\x01\x00\xff\x00{").contains("truncated"));
    }
}
