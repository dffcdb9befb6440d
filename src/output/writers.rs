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
    /// 255 where an augmentation erased the image (cut-out), 0 elsewhere.
    fn erased(&self) -> Vec<u8>;
    /// 255 where the pixel has a source, 0 where an image-space warp left it without one
    /// (its depth, mask and ids are then 0).
    fn valid(&self) -> Vec<u8>;

    /// Share of the pixels that see a structure.
    fn coverage(&self) -> f64 {
        let mask = self.mask();
        mask.iter().filter(|&&m| m != 0).count() as f64 / mask.len().max(1) as f64
    }
}

/// An output kind: its name in `dataset.outputs`, the files it writes for each view and how
/// it turns a view's layers into them.
pub struct Writer {
    /// The output's name in `dataset.outputs`.
    pub output: &'static str,
    /// The files of each view, as `{key}.{extension}`: a view's file is named
    /// `{view stem}.{key}.{extension}` and listed in its record under `key`.
    pub files: &'static [&'static str],
    /// Encodes a view's layers into the output's files, in the order of `files`.
    pub write: fn(&dyn ViewLayers) -> Result<Vec<Vec<u8>>>,
}

impl Writer {
    /// The record key of each file: its name without the extension.
    pub fn keys(&self) -> impl Iterator<Item = &'static str> {
        self.files
            .iter()
            .map(|f| f.split_once('.').map_or(*f, |(key, _)| key))
    }
}

/// Every output shmgen can write, in the order a view's files are written.
pub const WRITERS: [Writer; 8] = [
    Writer {
        output: "rgb",
        files: &["rgb.png"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![rgb_png(w, h, v.rgb())])
        },
    },
    Writer {
        output: "depth",
        files: &["depth.exr"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![depth_exr(w, h, v.depth())])
        },
    },
    Writer {
        output: "mask",
        files: &["mask.png"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![mask_png(w, h, &v.mask())])
        },
    },
    Writer {
        output: "cracks",
        files: &["cracks.png"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![mask_png(w, h, v.cracks())])
        },
    },
    Writer {
        output: "erased",
        files: &["erased.png"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![mask_png(w, h, &v.erased())])
        },
    },
    Writer {
        output: "valid",
        files: &["valid.png"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![mask_png(w, h, &v.valid())])
        },
    },
    Writer {
        output: "parts",
        files: &["parts.png"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![id_png(w, h, &v.part_ids())?])
        },
    },
    Writer {
        output: "instances",
        files: &["instances.png"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![id_png(w, h, &v.instance_ids())?])
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
        fn erased(&self) -> Vec<u8> {
            vec![0, 255]
        }
        fn valid(&self) -> Vec<u8> {
            vec![255, 255]
        }
    }

    #[test]
    fn every_writer_writes_the_files_it_declares_and_names_are_unique() {
        let names = output_names();
        let mut keys = Vec::new();
        for (i, writer) in WRITERS.iter().enumerate() {
            assert!(!names[..i].contains(&writer.output), "{}", writer.output);
            let files = (writer.write)(&Tiny).unwrap();
            assert_eq!(files.len(), writer.files.len(), "{}", writer.output);
            assert!(files.iter().all(|bytes| !bytes.is_empty()));
            for key in writer.keys() {
                assert!(!keys.contains(&key) && key != "json", "{key}");
                keys.push(key);
            }
        }
        assert!(DEFAULT_OUTPUTS.iter().all(|d| names.contains(d)));
    }
}
