//! Decoders of the files a view holds: OpenEXR layers by channel name (depth `Z`, flow `U V`,
//! displacement and normals `X Y Z`), grey PNGs of 8 or 16 bits (masks, validity, depth in
//! millimetres) and 8-bit RGB PNGs (images). They decode bytes already read (with a bound, see `files`), and check the
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

/// The channels `names` of the first layer of the EXR `bytes` (of the file `name`), in that
/// order, which must be `size` = (width, height) pixels. With a single name, a file holding
/// just one channel is accepted whatever that channel is called (a prediction written by other
/// software may call depth `Y` or `R`).
pub fn decode_exr(bytes: &[u8], name: &str, names: &[&str], size: (u32, u32)) -> Result<Layer> {
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
    let list = &layer.channel_data.list;
    let mut channels = Vec::with_capacity(names.len());
    for wanted in names {
        let found = list
            .iter()
            .find(|c| c.name.eq(wanted))
            .or_else(|| (names.len() == 1 && list.len() == 1).then(|| &list[0]));
        let Some(channel) = found else {
            let have: Vec<String> = list.iter().map(|c| c.name.to_string()).collect();
            bail!("{name}: no channel {wanted:?} (it has {})", have.join(", "));
        };
        channels.push(channel.sample_data.values_as_f32().collect());
    }
    Ok(self::Layer {
        width: layer.size.width(),
        height: layer.size.height(),
        channels,
    })
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
