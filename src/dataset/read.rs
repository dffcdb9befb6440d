//! Decoders of the files a view holds: OpenEXR layers by channel name (depth `Y`, flow `R G`,
//! displacement and normals `R G B`, or the names `shmgen.view/1` datasets used: `Z`, `U V`,
//! `X Y Z`: the callers pass both, from `output::ExrChannels`), grey PNGs of 8 or 16 bits
//! (masks, validity, depth in millimetres) and 8-bit RGB PNGs (images). They decode bytes already read (with a bound, see `files`), and check the
//! header against the size the view's record gives before decoding a pixel: a file declaring
//! 40000 × 40000 pixels costs a header read, not 15 GB. Errors name the file and what it
//! lacks.

use anyhow::{Context, Result, bail};
use std::io::Cursor;

/// The most channels an EXR read here may have (ours have 1–3; RGBA + Z from other software).
const MAX_CHANNELS: usize = 8;

/// Float channels of one image, row-major.
pub struct Layer {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// One plane per channel asked for, in that order.
    pub channels: Vec<Vec<f32>>,
}

/// A one-channel PNG.
pub struct GreyImage {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// 8 or 16.
    pub bits: u8,
    /// The samples, row-major.
    pub values: Vec<u16>,
}

/// The components of the first layer of the EXR `bytes` (of the file `name`), in component
/// order, which must be `size` = (width, height) pixels: the first of the channel sets `sets`
/// (one name per component; the names written now, then older ones) that the file has in
/// full. For a single component, a file holding just one channel is accepted whatever that
/// channel is called (a prediction written by other software may call depth `Z` or `R`).
pub fn decode_exr(bytes: &[u8], name: &str, sets: &[&[&str]], size: (u32, u32)) -> Result<Layer> {
    use exr::meta::MetaData;
    use exr::prelude::{ReadChannels, ReadLayers, read};
    let unreadable = || format!("{name}: not a readable OpenEXR file");
    let meta = MetaData::read_from_buffered(bytes, false).with_context(unreadable)?;
    let header = meta.headers.first().with_context(unreadable)?;
    let found = (header.layer_size.width(), header.layer_size.height());
    if found != (size.0 as usize, size.1 as usize) {
        bail!(
            "{name}: {}×{} pixels, the view has {}×{}",
            found.0,
            found.1,
            size.0,
            size.1
        );
    }
    if meta.headers.len() != 1 || header.deep {
        bail!(
            "{name}: {} parts{}; one flat image is expected",
            meta.headers.len(),
            if header.deep { ", deep data" } else { "" }
        );
    }
    // Each channel decodes to width × height floats whatever the file's size: a header may
    // not name more than a view ever has, with room for other software's extra channels.
    if header.channels.list.len() > MAX_CHANNELS {
        bail!(
            "{name}: {} channels; an image of a view has at most {MAX_CHANNELS}",
            header.channels.list.len()
        );
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_buffered(Cursor::new(bytes))
        .with_context(unreadable)?;
    let layer = image.layer_data;
    let channels = pick(&layer.channel_data.list, sets, name)?
        .iter()
        .map(|c| c.sample_data.values_as_f32().collect())
        .collect();
    Ok(self::Layer {
        width: layer.size.width(),
        height: layer.size.height(),
        channels,
    })
}

/// The channels of `list` holding the components, in component order: the first of `sets`
/// the file has in full, else a file's only channel for a single component; or an error naming
/// the sets and what the file `name` has.
fn pick<'a>(
    list: &'a [exr::image::AnyChannel<exr::image::FlatSamples>],
    sets: &[&[&str]],
    name: &str,
) -> Result<Vec<&'a exr::image::AnyChannel<exr::image::FlatSamples>>> {
    let find = |n: &&str| list.iter().find(|c| c.name.eq(n));
    for names in sets {
        let found: Vec<_> = names.iter().filter_map(find).collect();
        if found.len() == names.len() {
            return Ok(found);
        }
    }
    if let ([[_], ..], [only]) = (sets, list) {
        return Ok(vec![only]);
    }
    let wanted: Vec<String> = sets.iter().map(|names| names.join(", ")).collect();
    let have: Vec<String> = list.iter().map(|c| c.name.to_string()).collect();
    bail!(
        "{name}: no channels {}; it has {}",
        wanted.join(" nor "),
        have.join(", ")
    )
}

/// A PNG's decoder with its header read, refused unless it is `size` = (width, height)
/// pixels of colour type `colour`.
fn png_of_size<'a>(
    bytes: &'a [u8],
    name: &str,
    size: (u32, u32),
    colour: png::ColorType,
) -> Result<png::Reader<Cursor<&'a [u8]>>> {
    let reader = png::Decoder::new(Cursor::new(bytes))
        .read_info()
        .with_context(|| format!("{name}: not a readable PNG"))?;
    let header = reader.info();
    if (header.width, header.height) != size {
        bail!(
            "{name}: {}×{} pixels, the view has {}×{}",
            header.width,
            header.height,
            size.0,
            size.1
        );
    }
    if header.color_type != colour {
        bail!(
            "{name}: a {colour:?} PNG is needed, this one is {:?}",
            header.color_type
        );
    }
    Ok(reader)
}

/// The 8-bit RGB PNG `bytes` (of the file `name`), which must be `size` = (width, height)
/// pixels: its pixels, row-major.
pub fn decode_rgb_png(bytes: &[u8], name: &str, size: (u32, u32)) -> Result<Vec<[u8; 3]>> {
    let unreadable = || format!("{name}: not a readable PNG");
    let mut reader = png_of_size(bytes, name, size, png::ColorType::Rgb)?;
    let length = reader.output_buffer_size().with_context(unreadable)?;
    let mut buf = vec![0; length];
    let info = reader.next_frame(&mut buf).with_context(unreadable)?;
    if info.bit_depth != png::BitDepth::Eight {
        bail!("{name}: {:?}-bit RGB; 8-bit is needed", info.bit_depth);
    }
    Ok(buf[..info.buffer_size()]
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect())
}

/// The grey PNG of 8 or 16 bits `bytes` (of the file `name`), which must be `size` =
/// (width, height) pixels.
pub fn decode_grey_png(bytes: &[u8], name: &str, size: (u32, u32)) -> Result<GreyImage> {
    let unreadable = || format!("{name}: not a readable PNG");
    let mut reader = png_of_size(bytes, name, size, png::ColorType::Grayscale)?;
    let length = reader.output_buffer_size().with_context(unreadable)?;
    let mut buf = vec![0; length];
    let info = reader.next_frame(&mut buf).with_context(unreadable)?;
    let values: Vec<u16> = match info.bit_depth {
        png::BitDepth::Eight => buf[..info.buffer_size()]
            .iter()
            .map(|&v| u16::from(v))
            .collect(),
        // PNG stores 16-bit samples big-endian.
        png::BitDepth::Sixteen => buf[..info.buffer_size()]
            .chunks_exact(2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .collect(),
        other => bail!("{name}: {other:?}-bit grey is not supported (8 or 16 bits)"),
    };
    Ok(GreyImage {
        width: info.width as usize,
        height: info.height as usize,
        bits: if info.bit_depth == png::BitDepth::Sixteen {
            16
        } else {
            8
        },
        values,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names of a 3-vector written now and before (`output::VECTOR_CHANNELS`).
    const VECTOR: [&[&str]; 2] = [&["R", "G", "B"], &["X", "Y", "Z"]];

    /// A 2 × 1 EXR of the channels `(name, values)` through the `exr` crate.
    fn exr_of(channels: &[(&str, [f32; 2])]) -> Vec<u8> {
        use exr::prelude::*;
        let list: Vec<AnyChannel<FlatSamples>> = channels
            .iter()
            .map(|(name, v)| AnyChannel::new(*name, FlatSamples::F32(v.to_vec())))
            .collect();
        let image = Image::from_channels((2, 1), AnyChannels::sort(SmallVec::from_vec(list)));
        let mut out = Cursor::new(Vec::new());
        image.write().non_parallel().to_buffered(&mut out).unwrap();
        out.into_inner()
    }

    #[test]
    fn vectors_decode_in_component_order_from_the_names_written_now_or_before() {
        for names in VECTOR {
            let values = [[1.0, -4.0], [2.0, 0.5], [3.0, 0.0]];
            let channels: Vec<(&str, [f32; 2])> = names.iter().copied().zip(values).collect();
            let layer = decode_exr(&exr_of(&channels), "v.exr", &VECTOR, (2, 1)).unwrap();
            assert_eq!(layer.channels, values.map(|v| v.to_vec()), "{names:?}");
        }
    }

    #[test]
    fn a_file_with_both_sets_of_names_is_read_by_the_first() {
        let channels = [("R", [1.0; 2]), ("G", [2.0; 2]), ("B", [3.0; 2])];
        let old = [("X", [9.0; 2]), ("Y", [9.0; 2]), ("Z", [9.0; 2])];
        let bytes = exr_of(&[channels, old].concat());
        let layer = decode_exr(&bytes, "v.exr", &VECTOR, (2, 1)).unwrap();
        assert_eq!(layer.channels[2], vec![3.0, 3.0]);
    }

    #[test]
    fn one_value_is_read_from_a_files_only_channel_whatever_its_name() {
        let bytes = exr_of(&[("depth", [2.5, 0.0])]);
        let layer = decode_exr(&bytes, "d.exr", &[&["Y"], &["Z"]], (2, 1)).unwrap();
        assert_eq!(layer.channels, [vec![2.5, 0.0]]);
    }

    #[test]
    fn missing_channels_are_named_with_both_sets_and_what_the_file_has() {
        let bytes = exr_of(&[("U", [0.0; 2]), ("V", [0.0; 2]), ("W", [0.0; 2])]);
        let error = decode_exr(&bytes, "v.exr", &VECTOR, (2, 1))
            .err()
            .unwrap()
            .to_string();
        assert_eq!(
            error,
            "v.exr: no channels R, G, B nor X, Y, Z; it has U, V, W"
        );
    }
}
