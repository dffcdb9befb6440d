//! The writers: one per output kind, registered in one table. Each reads the layers of a
//! rendered view and returns its files; adding an output is adding a writer here.

use super::encode::{depth_exr, id_png, mask_png, rgb_png};
use anyhow::Result;

/// The per-pixel layers of one rendered view, row-major. Every geometric layer comes from one
/// centre ray per pixel. A layer is computed when a writer first asks for it.
pub trait ViewLayers {
    /// (width, height) in pixels.
    fn size(&self) -> (u32, u32);
    /// sRGB colour, three bytes a pixel.
    fn rgb(&self) -> &[u8];
    /// Planar depth along the optical axis in metres, 0 where no surface is seen.
    fn depth(&self) -> &[f32];
    /// 255 where a structure is seen, 0 elsewhere.
    fn mask(&self) -> Vec<u8>;
    /// Part id of every pixel (0 = background; the view's record names the ids).
    fn part_ids(&self) -> Vec<u32>;
    /// Structure index + 1 of every pixel (0 = background).
    fn instance_ids(&self) -> Vec<u32>;
    /// 255 where a crack is seen, 0 elsewhere.
    fn cracks(&self) -> &[u8];
}

/// One file of a view, named `{view stem}.{key}.{extension}` and listed in the view's record
/// under `key`.
pub struct ViewFile {
    /// Key of the file in the view's record, and the middle of its name ("rgb", "depth", …).
    pub key: &'static str,
    /// File name extension, without the dot.
    pub extension: &'static str,
    /// The encoded file.
    pub bytes: Vec<u8>,
}

/// An output kind: its name in `dataset.outputs` and how it turns a view into files.
pub struct Writer {
    /// The output's name in `dataset.outputs`.
    pub output: &'static str,
    /// Encodes a view's layers into the output's files.
    pub write: fn(&dyn ViewLayers) -> Result<Vec<ViewFile>>,
}

fn file(key: &'static str, extension: &'static str, bytes: Vec<u8>) -> Result<Vec<ViewFile>> {
    Ok(vec![ViewFile {
        key,
        extension,
        bytes,
    }])
}

/// Every output shmgen can write, in the order a view's files are written.
pub const WRITERS: [Writer; 6] = [
    Writer {
        output: "rgb",
        write: |v| {
            let (w, h) = v.size();
            file("rgb", "png", rgb_png(w, h, v.rgb()))
        },
    },
    Writer {
        output: "depth",
        write: |v| {
            let (w, h) = v.size();
            file("depth", "exr", depth_exr(w, h, v.depth()))
        },
    },
    Writer {
        output: "mask",
        write: |v| {
            let (w, h) = v.size();
            file("mask", "png", mask_png(w, h, &v.mask()))
        },
    },
    Writer {
        output: "cracks",
        write: |v| {
            let (w, h) = v.size();
            file("cracks", "png", mask_png(w, h, v.cracks()))
        },
    },
    Writer {
        output: "parts",
        write: |v| {
            let (w, h) = v.size();
            file("parts", "png", id_png(w, h, &v.part_ids())?)
        },
    },
    Writer {
        output: "instances",
        write: |v| {
            let (w, h) = v.size();
            file("instances", "png", id_png(w, h, &v.instance_ids())?)
        },
    },
];

/// The names of every output, in writing order.
pub fn output_names() -> Vec<&'static str> {
    WRITERS.iter().map(|w| w.output).collect()
}

/// The outputs written by default: the paper's image, depth and mask.
pub const DEFAULT_OUTPUTS: [&str; 3] = ["rgb", "depth", "mask"];

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 × 1 view: the left pixel sees part 1 of structure 0 at 2.5 m, the right one nothing.
    struct Tiny;

    impl ViewLayers for Tiny {
        fn size(&self) -> (u32, u32) {
            (2, 1)
        }
        fn rgb(&self) -> &[u8] {
            &[200, 100, 50, 0, 0, 0]
        }
        fn depth(&self) -> &[f32] {
            &[2.5, 0.0]
        }
        fn mask(&self) -> Vec<u8> {
            vec![255, 0]
        }
        fn part_ids(&self) -> Vec<u32> {
            vec![1, 0]
        }
        fn instance_ids(&self) -> Vec<u32> {
            vec![1, 0]
        }
        fn cracks(&self) -> &[u8] {
            &[0, 0]
        }
    }

    #[test]
    fn every_writer_names_its_file_after_its_output_and_names_are_unique() {
        let names = output_names();
        for (i, writer) in WRITERS.iter().enumerate() {
            assert!(!names[..i].contains(&writer.output), "{}", writer.output);
            let files = (writer.write)(&Tiny).unwrap();
            assert_eq!(files.len(), 1);
            assert_eq!(files[0].key, writer.output);
            assert!(!files[0].bytes.is_empty());
        }
        assert!(DEFAULT_OUTPUTS.iter().all(|d| names.contains(d)));
    }
}
