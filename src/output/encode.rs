//! Encoders: RGB and mask PNG (fast deflate), NumPy `.npy` arrays, float OpenEXR (one float32 channel per
//! component, named so OpenCV reads every one: see [`ExrChannels`]; scanlines in increasing
//! order, lossless ZIP), each into memory so callers decide where bytes go.
//!
//! Owns: the channel names of every float layer, as written now and as datasets of
//! `shmgen.view/1` wrote them, so that writers, records and readers share one table.

/// The channels of a float EXR layer, in component order: those written now, and those the
/// same components had in datasets of `shmgen.view/1` (which readers still accept).
///
/// The names are the ones OpenCV's EXR decoder maps (`R`, `G`, `B`, `A`, and `Y` for grey):
/// it reads any other name as nothing, so a depth in `Z` came back all zeros, vectors in
/// `X Y Z` as their `Y` alone and flow in `U V` not at all. A scalar is `Y` (OpenCV returns a
/// 2-D float32 array), a 3-vector `R G B` (OpenCV returns B, G, R: the last axis reversed), a
/// 2-vector `R G` (OpenCV returns three channels, B filled with 0, then G, R).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExrChannels {
    /// The channel of each component, in component order, as written now.
    pub names: &'static [&'static str],
    /// The channel of each component in files of `shmgen.view/1` datasets.
    pub legacy: &'static [&'static str],
}

impl ExrChannels {
    /// The names written now, then those of `shmgen.view/1`: what a reader looks for, in order.
    pub fn sets(&self) -> [&'static [&'static str]; 2] {
        [self.names, self.legacy]
    }
}

/// One value per pixel (planar depth, unloaded depth, ray distance), in metres.
pub const SCALAR_CHANNELS: ExrChannels = ExrChannels {
    names: &["Y"],
    legacy: &["Z"],
};

/// A 3-vector per pixel (normals, displacement): x, y, z.
pub const VECTOR_CHANNELS: ExrChannels = ExrChannels {
    names: &["R", "G", "B"],
    legacy: &["X", "Y", "Z"],
};

/// A 2-vector per pixel (flow): u, v.
pub const FLOW_CHANNELS: ExrChannels = ExrChannels {
    names: &["R", "G"],
    legacy: &["U", "V"],
};

/// Name of the EXR channel holding planar depth (metres, float32).
pub const DEPTH_CHANNEL: &str = SCALAR_CHANNELS.names[0];

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
    // Label images (masks, ids, millimetres) are flat over large regions: the "up" filter
    // (`Fastest`) packs them within 4 % of the per-row best filter (`Fast`) in half the time
    // (a 960² mask: 0.24 against 0.5 ms). Photographs keep the per-row choice, whose files are
    // 5–27 % smaller than "up" alone for twice the time (a 960² A1 view: 2.2 against 1.3 ms).
    encoder.set_compression(match colour {
        ::png::ColorType::Grayscale => ::png::Compression::Fastest,
        _ => ::png::Compression::Fast,
    });
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

/// 16-bit RGB, row-major, three samples per pixel (KITTI's flow images); big-endian in the file.
pub fn rgb16_png(width: u32, height: u32, values: &[[u16; 3]]) -> Vec<u8> {
    let bytes: Vec<u8> = values
        .iter()
        .flatten()
        .flat_map(|v| v.to_be_bytes())
        .collect();
    png(
        width,
        height,
        ::png::ColorType::Rgb,
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

/// A NumPy `.npy` file (format 1.0, NEP 1) of C-ordered `data` of dtype `descr`: the magic,
/// the version, the header's length and a header padded with spaces to a multiple of 64
/// bytes, as NumPy writes it.
pub fn npy(descr: &str, shape: &[usize], data: &[u8]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let shape = match dims.as_slice() {
        [one] => format!("({one},)"),
        _ => format!("({})", dims.join(", ")),
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
    header.push('\n');
    let mut bytes = Vec::with_capacity(10 + header.len() + data.len());
    bytes.extend_from_slice(b"\x93NUMPY\x01\x00");
    let length = u16::try_from(header.len()).expect("a short header");
    bytes.extend_from_slice(&length.to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend_from_slice(data);
    bytes
}

/// Planar depth in metres, 0 where no surface was hit.
pub fn depth_exr(width: u32, height: u32, depth: &[f32]) -> Vec<u8> {
    float_exr(
        (width, height),
        &[(DEPTH_CHANNEL, depth)],
        (
            "shmgen_depth",
            "Y = planar z along the optical axis, metres, 0 = no surface",
        ),
    )
    .expect("depth layers are finite")
}

/// Float32 EXR of one value or vector per pixel: `names` are the channels of the vector's
/// components, in order (N of them); `note` = (attribute name, text) says what the values
/// mean. Refuses a non-finite value, so none ever reaches a file.
pub fn vector_exr<const N: usize>(
    (width, height): (u32, u32),
    names: &[&str],
    values: &[[f32; N]],
    note: (&str, &str),
) -> anyhow::Result<Vec<u8>> {
    assert_eq!(names.len(), N, "one channel name per component");
    let components: Vec<Vec<f32>> = (0..N)
        .map(|k| values.iter().map(|v| v[k]).collect())
        .collect();
    let channels: Vec<(&str, &[f32])> = names
        .iter()
        .zip(&components)
        .map(|(name, values)| (*name, values.as_slice()))
        .collect();
    float_exr((width, height), &channels, note)
}

/// Whether no value is infinite or NaN, in runs the compiler can vectorise.
fn all_finite(values: &[f32]) -> bool {
    values
        .chunks(256)
        .all(|run| run.iter().fold(true, |finite, v| finite & v.is_finite()))
}

/// The one EXR encoder: float32 channels, lossless ZIP over 16 scanlines, scanlines in
/// increasing order (see `openexr`), so the same values give the same bytes on any machine and
/// thread count. Channels are stored in name order, as EXR requires.
fn float_exr(
    (width, height): (u32, u32),
    channels: &[(&str, &[f32])],
    (key, text): (&str, &str),
) -> anyhow::Result<Vec<u8>> {
    if let Some((name, _)) = channels.iter().find(|(_, values)| !all_finite(values)) {
        anyhow::bail!("{key}: channel {name} holds a value that is not finite");
    }
    let mut sorted = channels.to_vec();
    sorted.sort_by_key(|(name, _)| *name);
    Ok(super::openexr::float_exr(
        (width, height),
        &sorted,
        (key, text),
    ))
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use exr::prelude::*;
    use std::io::Cursor;

    /// Channels by name with their values, in the order the file lists them.
    pub(in crate::output) type NamedChannels = Vec<(String, Vec<f32>)>;

    /// Reads an EXR back with the exr crate's own reader (a separate code path): its size and
    /// every channel by name, which must be float32.
    pub(in crate::output) fn read_channels(bytes: &[u8]) -> ((usize, usize), NamedChannels) {
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .all_layers()
            .all_attributes()
            .from_buffered(Cursor::new(bytes))
            .unwrap();
        assert_eq!(image.layer_data.len(), 1);
        let layer = &image.layer_data[0];
        let channels = layer.channel_data.list.iter().map(|channel| {
            let FlatSamples::F32(values) = &channel.sample_data else {
                panic!("float32 channels only")
            };
            (channel.name.to_string(), values.clone())
        });
        (
            (layer.size.width(), layer.size.height()),
            channels.collect(),
        )
    }

    /// A depth EXR: its size and its one channel, which must be `Z`.
    fn read_depth(bytes: &[u8]) -> (usize, usize, Vec<f32>) {
        let ((w, h), mut channels) = read_channels(bytes);
        assert_eq!(channels.len(), 1);
        let (name, values) = channels.pop().unwrap();
        assert_eq!(name, DEPTH_CHANNEL);
        (w, h, values)
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

    /// A reproducible stream of f32 bit patterns that are finite: depths, zeros, extremes.
    fn finite_values(count: usize, seed: u64) -> Vec<f32> {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        (0..count)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let v = f32::from_bits(state as u32);
                match state >> 61 {
                    0 => 0.0,
                    1 => 1.0 + (state >> 40) as f32 * 1e-6,
                    _ if v.is_finite() => v,
                    _ => -0.0,
                }
            })
            .collect()
    }

    #[test]
    fn depth_files_decode_bit_exactly_at_every_size() {
        let sizes = [
            (1, 1),
            (1, 40),
            (40, 1),
            (7, 15),
            (7, 16),
            (7, 17),
            (33, 47),
            (960, 33),
        ];
        for (i, (w, h)) in sizes.into_iter().enumerate() {
            let mut cases = vec![finite_values(w * h, i as u64 + 1), vec![0.0; w * h]];
            let mut extremes = vec![f32::MAX; w * h];
            extremes[0] = f32::MIN_POSITIVE;
            extremes[w * h - 1] = -f32::from_bits(1); // a negative subnormal
            cases.push(extremes);
            for depth in cases {
                let bytes = depth_exr(w as u32, h as u32, &depth);
                let (rw, rh, back) = read_depth(&bytes);
                assert_eq!((rw, rh), (w, h));
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&back), bits(&depth), "{w}×{h}");
            }
        }
    }

    #[test]
    fn encoding_does_not_depend_on_the_thread_count() {
        let depth = finite_values(300 * 70, 9);
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| depth_exr(300, 70, &depth))
        };
        assert_eq!(on(1), on(3));
    }

    #[test]
    fn vector_layers_round_trip_by_channel_name_and_refuse_non_finite_values() {
        let values: Vec<[f32; 3]> = (0..12)
            .map(|i| [i as f32, -0.5 * i as f32, 1e-7 * i as f32])
            .collect();
        let names = VECTOR_CHANNELS.names;
        let bytes = vector_exr((4, 3), names, &values, ("note", "test")).unwrap();
        let ((w, h), channels) = read_channels(&bytes);
        assert_eq!((w, h), (4, 3));
        for (k, name) in names.iter().enumerate() {
            let (_, back) = channels.iter().find(|(n, _)| n == name).unwrap();
            assert_eq!(*back, values.iter().map(|v| v[k]).collect::<Vec<_>>());
        }
        let mut bad = values.clone();
        bad[5][1] = f32::NAN;
        let error = vector_exr((4, 3), names, &bad, ("shmgen_x", "t")).unwrap_err();
        assert!(error.to_string().contains("channel G"), "{error}");
        bad[5][1] = f32::INFINITY;
        assert!(vector_exr((4, 3), names, &bad, ("shmgen_x", "t")).is_err());
    }

    #[test]
    fn channels_are_stored_in_name_order_whatever_order_they_are_given_in() {
        // (x, y, z) given as R, G, B: the file lists B, G, R, as EXR requires, each channel
        // with its own component.
        let given = vector_exr(
            (2, 1),
            &["R", "G", "B"],
            &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
            ("n", "t"),
        );
        let expected = vec![
            ("B".to_string(), vec![3.0, 6.0]),
            ("G".to_string(), vec![2.0, 5.0]),
            ("R".to_string(), vec![1.0, 4.0]),
        ];
        assert_eq!(read_channels(&given.unwrap()), ((2, 1), expected));
        // The same components given in name order make the same file, to the byte.
        let reversed = [[3.0, 2.0, 1.0], [6.0, 5.0, 4.0]];
        let in_order = vector_exr((2, 1), &["B", "G", "R"], &reversed, ("n", "t"));
        assert_eq!(
            vector_exr(
                (2, 1),
                &["R", "G", "B"],
                &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
                ("n", "t")
            )
            .unwrap(),
            in_order.unwrap()
        );
    }

    #[test]
    fn the_note_is_a_string_attribute_readers_decode() {
        // OpenEXR's type for text is "string"; a note typed otherwise reaches readers as
        // opaque bytes (the OpenEXR package's OpaqueAttribute).
        let bytes = depth_exr(2, 1, &[1.0, 0.0]);
        let meta = exr::meta::MetaData::read_from_buffered(&bytes[..], false).unwrap();
        let note = &meta.headers[0].own_attributes.other[&Text::from("shmgen_depth")];
        let AttributeValue::Text(text) = note else {
            panic!("{note:?}")
        };
        assert!(text.to_string().starts_with("Y = planar z"), "{text}");
    }

    #[test]
    fn every_channel_name_is_one_opencv_reads() {
        // OpenCV's EXR decoder maps R, G, B, A and Y (grey) and reads any other channel as
        // nothing (a depth in Z came back all zeros); the Python tests read every layer with it.
        for channels in [SCALAR_CHANNELS, VECTOR_CHANNELS, FLOW_CHANNELS] {
            let grey = channels.names == ["Y"];
            let colour = channels.names.iter().all(|n| ["R", "G", "B"].contains(n));
            assert!(grey || colour, "{channels:?}");
            assert_eq!(channels.names.len(), channels.legacy.len());
        }
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

    #[test]
    fn npy_headers_are_numpys() {
        let bytes = npy("<f4", &[2, 3], &[0; 24]);
        // NumPy's own header for np.zeros((2, 3), np.float32), padded to 64 bytes.
        let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }";
        assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
        assert_eq!(u16::from_le_bytes([bytes[8], bytes[9]]), 118);
        assert_eq!(&bytes[10..10 + header.len()], header.as_bytes());
        assert_eq!(bytes[127], b'\n');
        assert_eq!(bytes.len(), 128 + 24);
    }
}
