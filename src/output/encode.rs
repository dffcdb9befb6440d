//! Encoders: RGB and mask PNG (fast deflate), depth OpenEXR (float32 `Z`, scanlines in
//! increasing order, lossless ZIP), each into memory so callers decide where bytes go.

use exr::prelude::*;
use std::io::Cursor;

/// Name of the EXR channel holding planar depth (metres, float32).
pub const DEPTH_CHANNEL: &str = "Z";

fn png(
    width: u32,
    height: u32,
    colour: ::png::ColorType,
    depth: ::png::BitDepth,
    data: &[u8],
) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() / 4 + 1024);
    let mut encoder = ::png::Encoder::new(&mut out, width, height);
    encoder.set_color(colour);
    encoder.set_depth(depth);
    encoder.set_compression(::png::Compression::Fast);
    let mut writer = encoder.write_header().expect("PNG header into memory");
    writer.write_image_data(data).expect("PNG data into memory");
    writer.finish().expect("PNG end into memory");
    out
}

/// RGB8, row-major.
pub fn rgb_png(width: u32, height: u32, rgb: &[u8]) -> Vec<u8> {
    png(
        width,
        height,
        ::png::ColorType::Rgb,
        ::png::BitDepth::Eight,
        rgb,
    )
}

/// 8-bit grey, row-major (255 = structure, 0 = background for the mask).
pub fn mask_png(width: u32, height: u32, mask: &[u8]) -> Vec<u8> {
    png(
        width,
        height,
        ::png::ColorType::Grayscale,
        ::png::BitDepth::Eight,
        mask,
    )
}

/// 16-bit grey, row-major, whatever the values (depth in millimetres, ids beyond 255); PNG
/// stores the samples big-endian.
pub fn grey16_png(width: u32, height: u32, values: &[u16]) -> Vec<u8> {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
    png(
        width,
        height,
        ::png::ColorType::Grayscale,
        ::png::BitDepth::Sixteen,
        &bytes,
    )
}

/// The largest id a segmentation image holds (a 16-bit PNG).
pub const MAX_SEGMENTATION_ID: u32 = u16::MAX as u32;

/// Id image (0 = background): 8-bit grey when every id fits, else 16-bit (big-endian, as PNG
/// stores it). An id beyond 16 bits is an error, never wrapped.
pub fn id_png(width: u32, height: u32, ids: &[u32]) -> anyhow::Result<Vec<u8>> {
    let largest = ids.iter().copied().max().unwrap_or(0);
    if largest <= 255 {
        let bytes: Vec<u8> = ids.iter().map(|&i| i as u8).collect();
        return Ok(png(
            width,
            height,
            ::png::ColorType::Grayscale,
            ::png::BitDepth::Eight,
            &bytes,
        ));
    }
    if largest > MAX_SEGMENTATION_ID {
        anyhow::bail!(
            "segmentation id {largest} does not fit a 16-bit PNG (at most {MAX_SEGMENTATION_ID})"
        );
    }
    let narrow: Vec<u16> = ids.iter().map(|&i| i as u16).collect();
    Ok(grey16_png(width, height, &narrow))
}

/// Planar depth in metres, 0 where no surface was hit.
pub fn depth_exr(width: u32, height: u32, depth: &[f32]) -> Vec<u8> {
    let channel = AnyChannel::new(DEPTH_CHANNEL, FlatSamples::F32(depth.to_vec()));
    let mut attributes = LayerAttributes::default();
    attributes.other.insert(
        Text::from("shmgen_depth"),
        AttributeValue::Text(Text::from(
            "planar z along the optical axis, metres, 0 = no surface",
        )),
    );
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![channel]));
    let layer = Layer::new(
        (width as usize, height as usize),
        attributes,
        encoding,
        channels,
    );
    let mut out = Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(&mut out)
        .expect("EXR into memory");
    out.into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reads a depth EXR back with the exr crate's own reader (a separate code path).
    pub fn read_depth(bytes: &[u8]) -> (usize, usize, Vec<f32>) {
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .all_layers()
            .all_attributes()
            .from_buffered(Cursor::new(bytes))
            .unwrap();
        let layer = &image.layer_data[0];
        assert_eq!(image.layer_data.len(), 1);
        assert_eq!(layer.channel_data.list.len(), 1);
        let channel = &layer.channel_data.list[0];
        assert_eq!(channel.name, Text::from(DEPTH_CHANNEL));
        let FlatSamples::F32(values) = &channel.sample_data else {
            panic!("depth must be f32")
        };
        (layer.size.width(), layer.size.height(), values.clone())
    }

    #[test]
    fn depth_round_trips_exactly_and_deterministically() {
        let (w, h) = (37, 23);
        let depth: Vec<f32> = (0..w * h)
            .map(|i| {
                if i % 5 == 0 {
                    0.0
                } else {
                    1.0 + i as f32 * 1.234_567e-3
                }
            })
            .collect();
        let bytes = depth_exr(w as u32, h as u32, &depth);
        assert_eq!(
            bytes,
            depth_exr(w as u32, h as u32, &depth),
            "same input, same bytes"
        );
        let (rw, rh, back) = read_depth(&bytes);
        assert_eq!((rw, rh), (w, h));
        assert_eq!(back, depth);
        assert_eq!(
            &bytes[..4],
            &[0x76, 0x2f, 0x31, 0x01],
            "OpenEXR magic number"
        );
    }

    #[test]
    fn id_images_switch_to_16_bit_only_when_needed() {
        let decode = |bytes: Vec<u8>| {
            let mut reader = ::png::Decoder::new(Cursor::new(bytes)).read_info().unwrap();
            let mut buf = vec![0; reader.output_buffer_size().unwrap()];
            let info = reader.next_frame(&mut buf).unwrap();
            buf.truncate(info.buffer_size());
            (info.bit_depth, buf)
        };
        assert_eq!(
            decode(id_png(3, 1, &[0, 7, 255]).unwrap()),
            (::png::BitDepth::Eight, vec![0, 7, 255])
        );
        assert_eq!(
            decode(id_png(2, 1, &[1, 300]).unwrap()),
            (::png::BitDepth::Sixteen, vec![0, 1, 1, 44])
        );
        assert!(id_png(1, 1, &[65_536]).is_err(), "never wrapped");
    }

    #[test]
    fn png_round_trips() {
        let (w, h) = (19u32, 11u32);
        let rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 251) as u8).collect();
        let bytes = rgb_png(w, h, &rgb);
        let decoder = ::png::Decoder::new(Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(
            (info.width, info.height, info.color_type),
            (w, h, ::png::ColorType::Rgb)
        );
        assert_eq!(&buf[..info.buffer_size()], &rgb[..]);
    }
}
