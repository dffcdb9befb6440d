//! Decoders of the files a view holds: OpenEXR layers by channel name (depth `Z`, flow `U V`,
//! displacement and normals `X Y Z`) and grey PNGs of 8 or 16 bits (masks, validity, depth in
//! millimetres). Errors name the file and what it lacks.

use anyhow::{Context, Result, bail};
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

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

/// The channels `names` of the first layer of the EXR at `path`, in that order. With a single
/// name, a file holding just one channel is accepted whatever that channel is called (a
/// prediction written by other software may call depth `Y` or `R`).
pub fn read_exr(path: &Path, names: &[&str]) -> Result<Layer> {
    use exr::prelude::{ReadChannels, ReadLayers, Text, read};
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_file(path)
        .with_context(|| format!("{}: not a readable OpenEXR file", path.display()))?;
    let layer = image.layer_data;
    let list = &layer.channel_data.list;
    let mut channels = Vec::with_capacity(names.len());
    for name in names {
        let found = list
            .iter()
            .find(|c| c.name == Text::from(*name))
            .or_else(|| (names.len() == 1 && list.len() == 1).then(|| &list[0]));
        let Some(channel) = found else {
            let have: Vec<String> = list.iter().map(|c| c.name.to_string()).collect();
            bail!(
                "{}: no channel {name:?} (it has {})",
                path.display(),
                have.join(", ")
            );
        };
        channels.push(channel.sample_data.values_as_f32().collect());
    }
    Ok(self::Layer {
        width: layer.size.width(),
        height: layer.size.height(),
        channels,
    })
}

/// A grey PNG of 8 or 16 bits at `path`.
pub fn read_grey_png(path: &Path) -> Result<GreyImage> {
    let file = File::open(path).with_context(|| format!("opening {}", path.display()))?;
    let mut reader = png::Decoder::new(BufReader::new(file))
        .read_info()
        .with_context(|| format!("{}: not a readable PNG", path.display()))?;
    let size = reader
        .output_buffer_size()
        .with_context(|| format!("{}: image too large", path.display()))?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .with_context(|| format!("{}: not a readable PNG", path.display()))?;
    if info.color_type != png::ColorType::Grayscale {
        bail!(
            "{}: a one-channel grey PNG is needed, this one is {:?}",
            path.display(),
            info.color_type
        );
    }
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
        other => bail!(
            "{}: {other:?}-bit grey is not supported (8 or 16 bits)",
            path.display()
        ),
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
