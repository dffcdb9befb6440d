//! The writers: one per output kind, registered in two tables — per view (`WRITERS`, reading
//! the layers of a rendered view) and per sample (`SAMPLE_WRITERS`, reading the sample's
//! geometry). Each returns its files; adding an output is adding a writer here.

use super::encode::{
    FLOW_CHANNELS, SCALAR_CHANNELS, VECTOR_CHANNELS, depth_exr, grey16_png, id_png, mask_png, npy,
    rgb_png, vector_exr,
};
use super::meshes::{MeshLayer, PointLayer, mesh_glb, mesh_ply, points_ply};
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
    /// Unit normal of the surface seen (its triangle's, turned towards the camera), in the
    /// axes the dataset asks for; 0 where no surface is seen.
    fn normals(&self) -> Vec<[f32; 3]>;
    /// Distance from the camera centre to the surface point along the ray, metres; 0 where no
    /// surface is seen.
    fn ray_distance(&self) -> Vec<f32>;
    /// Displacement of the surface point seen from the unloaded structure to the loaded one,
    /// world axes, metres; 0 where no surface is seen.
    fn displacement(&self) -> Vec<[f32; 3]>;
    /// Where each surface point of the unloaded image moves in the loaded one.
    fn flow(&self) -> Flow;
    /// In a sequence, where each surface point of this frame's image moves in the next frame's
    /// and in the previous frame's (no pixel valid at the ends of the sequence).
    fn frame_flow(&self) -> FrameFlow;
    /// sRGB colour of the unloaded structure seen through the same camera, three bytes a pixel.
    fn rest_rgb(&self) -> &[u8];
    /// Planar depth of the unloaded structure, metres, 0 where no surface is seen.
    fn rest_depth(&self) -> &[f32];
    /// The damage each pixel's surface point lies on (see `DamageLayers`).
    fn damage(&self) -> DamageLayers;
    /// In a sequence, the true point tracks at this frame: one row per query point of the
    /// first frame (docs/sequences.md), `[x, y, state]`: the image position in pixels (pixel
    /// centres at half-integers) and 1 where it is seen, 0 where it is hidden or outside the
    /// frame (x, y its projection still), −1 where it has no image (behind the camera, or not
    /// on this frame's structure; x = y = 0).
    fn point_tracks(&self) -> Vec<[f64; 3]>;

    /// Share of the pixels that see a structure.
    fn coverage(&self) -> f64 {
        let mask = self.mask();
        mask.iter().filter(|&&m| m != 0).count() as f64 / mask.len().max(1) as f64
    }
}

/// Optical flow from the unloaded image to the loaded one, per pixel of the unloaded image.
pub struct Flow {
    /// (u, v) displacement in pixels, 0 where `valid` is 0.
    pub vectors: Vec<[f32; 2]>,
    /// 255 where the point moves to a pixel inside the frame and is seen there, else 0.
    pub valid: Vec<u8>,
}

impl Flow {
    /// The flow of a per-pixel field: a vector where the pixel has one, 0 and invalid
    /// elsewhere.
    pub fn from_field(field: &[Option<[f32; 2]>]) -> Flow {
        Flow {
            vectors: field.iter().map(|f| f.unwrap_or_default()).collect(),
            valid: field
                .iter()
                .map(|f| if f.is_some() { 255 } else { 0 })
                .collect(),
        }
    }

    /// A flow of `pixels` pixels none of which is valid.
    pub fn invalid(pixels: usize) -> Flow {
        Flow {
            vectors: vec![[0.0; 2]; pixels],
            valid: vec![0; pixels],
        }
    }
}

/// Optical flow between consecutive frames of a sequence, per pixel of this frame's image.
pub struct FrameFlow {
    /// To the next frame's image (invalid everywhere at the last frame).
    pub next: Flow,
    /// To the previous frame's image (invalid everywhere at the first frame).
    pub prev: Flow,
}

/// The per-pixel damage labels of a view, from its centre rays (docs/damage.md).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DamageLayers {
    /// Damage class: 0 none, 1 flexural crack, 2 shear crack, 3 map cracking, 4 corrosion
    /// (and its stains), 5 spall, 6 dent.
    pub class: Vec<u8>,
    /// Index + 1 of the damage in its structure's `damage.items` (the structure is the
    /// pixel's instance id); 0 none.
    pub instance: Vec<u16>,
    /// Width of the crack the pixel's footprint touches, millimetres; 0 elsewhere.
    pub crack_width_mm: Vec<f32>,
    /// Share of the pixel's footprint the crack covers, 0–1.
    pub crack_coverage: Vec<f32>,
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
pub const WRITERS: [Writer; 17] = [
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
    Writer {
        output: "normals",
        files: &["normals.exr"],
        write: |v| {
            let note = "R, G, B = x, y, z of the unit normal of the surface seen, facing the camera, in the axes of the view record's normals.axes; 0 = no surface";
            Ok(vec![vector_exr(
                v.size(),
                VECTOR_CHANNELS.names,
                &v.normals(),
                ("shmgen_normals", note),
            )?])
        },
    },
    Writer {
        output: "displacement",
        files: &["displacement.exr"],
        write: |v| {
            let note = "R, G, B = x, y, z of the displacement unloaded -> loaded of the surface point seen, world axes, metres; 0 = no surface";
            Ok(vec![vector_exr(
                v.size(),
                VECTOR_CHANNELS.names,
                &v.displacement(),
                ("shmgen_displacement", note),
            )?])
        },
    },
    Writer {
        output: "flow",
        files: &["flow.exr", "flow_valid.png"],
        write: |v| {
            let (w, h) = v.size();
            let flow = v.flow();
            let note = "R, G = u, v: pixels from the unloaded image to the loaded one; 0 where flow_valid is 0";
            let names = FLOW_CHANNELS.names;
            Ok(vec![
                vector_exr((w, h), names, &flow.vectors, ("shmgen_flow", note))?,
                mask_png(w, h, &flow.valid),
            ])
        },
    },
    Writer {
        output: "frame_flow",
        files: &[
            "flow_next.exr",
            "flow_next_valid.png",
            "flow_prev.exr",
            "flow_prev_valid.png",
        ],
        write: |v| {
            let (w, h) = v.size();
            let FrameFlow { next, prev } = v.frame_flow();
            let names = FLOW_CHANNELS.names;
            let next_note = "R, G = u, v: pixels from this frame's image to the next frame's; 0 where flow_next_valid is 0";
            let prev_note = "R, G = u, v: pixels from this frame's image to the previous frame's; 0 where flow_prev_valid is 0";
            Ok(vec![
                vector_exr(
                    (w, h),
                    names,
                    &next.vectors,
                    ("shmgen_flow_next", next_note),
                )?,
                mask_png(w, h, &next.valid),
                vector_exr(
                    (w, h),
                    names,
                    &prev.vectors,
                    ("shmgen_flow_prev", prev_note),
                )?,
                mask_png(w, h, &prev.valid),
            ])
        },
    },
    Writer {
        output: "point_tracks",
        files: &["tracks.npy"],
        write: |v| Ok(vec![tracks_npy(&v.point_tracks())]),
    },
    Writer {
        output: "rest_rgb",
        files: &["rest_rgb.png"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![rgb_png(w, h, v.rest_rgb())])
        },
    },
    Writer {
        output: "rest_depth",
        files: &["rest_depth.exr"],
        write: |v| {
            let (w, h) = v.size();
            Ok(vec![depth_exr(w, h, v.rest_depth())])
        },
    },
    Writer {
        output: "ray_distance",
        files: &["ray_distance.exr"],
        write: |v| {
            let note =
                "Y = distance from the camera centre to the surface point, metres; 0 = no surface";
            let distance: Vec<[f32; 1]> = v.ray_distance().into_iter().map(|d| [d]).collect();
            Ok(vec![vector_exr(
                v.size(),
                SCALAR_CHANNELS.names,
                &distance,
                ("shmgen_ray_distance", note),
            )?])
        },
    },
    Writer {
        output: "damage",
        files: &[
            "damage_class.png",
            "damage_instance.png",
            "crack_width.exr",
            "crack_coverage.exr",
        ],
        write: |v| {
            let (w, h) = v.size();
            let damage = v.damage();
            let scalar = |values: &[f32], note| {
                let values: Vec<[f32; 1]> = values.iter().map(|&x| [x]).collect();
                vector_exr((w, h), SCALAR_CHANNELS.names, &values, note)
            };
            let width =
                "Y = width of the crack the pixel's footprint touches, millimetres; 0 elsewhere";
            let coverage = "Y = share of the pixel's footprint the crack covers, 0-1";
            Ok(vec![
                mask_png(w, h, &damage.class),
                grey16_png(w, h, &damage.instance),
                scalar(&damage.crack_width_mm, ("shmgen_crack_width", width))?,
                scalar(&damage.crack_coverage, ("shmgen_crack_coverage", coverage))?,
            ])
        },
    },
];

/// The geometry of a built sample, for the per-sample writers.
pub trait SampleLayers {
    /// The loaded (deformed) mesh of every structure, merged.
    fn mesh(&self) -> MeshLayer<'_>;
    /// The same vertices, in the same order, before any load or damage; the same triangles.
    fn rest_mesh(&self) -> MeshLayer<'_>;
    /// Points drawn uniformly by area on the loaded mesh, with their normals.
    fn points(&self) -> PointLayer;
}

/// An output written once per sample: its name in `dataset.outputs`, its files (named
/// `{sample:06}.{kind}` beside the sample's views, listed in every view's record under
/// `sample_files` by kind) and how it encodes them.
pub struct SampleWriter {
    /// The output's name in `dataset.outputs`.
    pub output: &'static str,
    /// The kinds of its files, `{name}.{extension}`.
    pub files: &'static [&'static str],
    /// Encodes the sample's geometry into the output's files, in the order of `files`.
    pub write: fn(&dyn SampleLayers) -> Result<Vec<Vec<u8>>>,
}

/// Every per-sample output, in the order a sample's files are written.
pub const SAMPLE_WRITERS: [SampleWriter; 3] = [
    SampleWriter {
        output: "mesh",
        files: &["mesh.ply", "rest.ply"],
        write: |s| Ok(vec![mesh_ply(&s.mesh())?, mesh_ply(&s.rest_mesh())?]),
    },
    SampleWriter {
        output: "mesh_gltf",
        files: &["mesh.glb"],
        write: |s| Ok(vec![mesh_glb(&s.mesh())?]),
    },
    SampleWriter {
        output: "points",
        files: &["points.ply"],
        write: |s| Ok(vec![points_ply(&s.points())]),
    },
];

/// The names of every output, per view then per sample, in writing order.
pub fn output_names() -> Vec<&'static str> {
    let per_sample = SAMPLE_WRITERS.iter().map(|w| w.output);
    WRITERS.iter().map(|w| w.output).chain(per_sample).collect()
}

/// The point tracks of a frame as NumPy float64 `[queries, 3]`: x, y, state per row.
fn tracks_npy(rows: &[[f64; 3]]) -> Vec<u8> {
    let data: Vec<u8> = rows
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    npy("<f8", &[rows.len(), 3], &data)
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
        fn normals(&self) -> Vec<[f32; 3]> {
            vec![[0.0, 0.6, -0.8], [0.0; 3]]
        }
        fn ray_distance(&self) -> Vec<f32> {
            vec![2.6, 0.0]
        }
        fn displacement(&self) -> Vec<[f32; 3]> {
            vec![[1e-3, 0.0, -0.02], [0.0; 3]]
        }
        fn flow(&self) -> Flow {
            Flow {
                vectors: vec![[0.25, 1.5], [0.0; 2]],
                valid: vec![255, 0],
            }
        }
        fn frame_flow(&self) -> FrameFlow {
            FrameFlow {
                next: Flow {
                    vectors: vec![[-0.5, 0.125], [0.0; 2]],
                    valid: vec![255, 0],
                },
                prev: Flow::invalid(2),
            }
        }
        fn rest_rgb(&self) -> &[u8] {
            &[190, 100, 50, 0, 0, 0]
        }
        fn rest_depth(&self) -> &[f32] {
            &[2.45, 0.0]
        }
        fn damage(&self) -> DamageLayers {
            DamageLayers {
                class: vec![1, 0],
                instance: vec![3, 0],
                crack_width_mm: vec![0.3, 0.0],
                crack_coverage: vec![0.15, 0.0],
            }
        }
        fn point_tracks(&self) -> Vec<[f64; 3]> {
            vec![[0.5, 0.5, 1.0], [3.25, -1.0, 0.0]]
        }
    }

    /// One triangle of part 1, lifted by 1 cm when loaded.
    struct Triangle {
        rest: Vec<glam::DVec3>,
        loaded: Vec<glam::DVec3>,
    }

    impl Triangle {
        fn new() -> Self {
            let rest = vec![glam::DVec3::ZERO, glam::DVec3::X, glam::DVec3::Y];
            let loaded = rest.iter().map(|p| *p + 0.01 * glam::DVec3::Z).collect();
            Triangle { rest, loaded }
        }
    }

    impl SampleLayers for Triangle {
        fn mesh(&self) -> MeshLayer<'_> {
            MeshLayer {
                positions: &self.loaded,
                triangles: &[[0, 1, 2]],
                parts: &[1],
            }
        }
        fn rest_mesh(&self) -> MeshLayer<'_> {
            MeshLayer {
                positions: &self.rest,
                triangles: &[[0, 1, 2]],
                parts: &[1],
            }
        }
        fn points(&self) -> PointLayer {
            PointLayer {
                positions: vec![glam::DVec3::new(0.2, 0.2, 0.01)],
                normals: vec![[0.0, 0.0, 1.0]],
                colours: vec![[10, 20, 30]],
            }
        }
    }

    #[test]
    fn every_exr_file_holds_its_components_in_the_channels_opencv_reads() {
        // Tiny's layers by channel: Y for one value, R G B = x y z, R G = u v (flow).
        let expected = |kind: &str| -> Vec<(&str, Vec<f32>)> {
            match kind {
                "depth.exr" => vec![("Y", vec![2.5, 0.0])],
                "rest_depth.exr" => vec![("Y", vec![2.45, 0.0])],
                "ray_distance.exr" => vec![("Y", vec![2.6, 0.0])],
                "normals.exr" => vec![
                    ("B", vec![-0.8, 0.0]),
                    ("G", vec![0.6, 0.0]),
                    ("R", vec![0.0, 0.0]),
                ],
                "displacement.exr" => vec![
                    ("B", vec![-0.02, 0.0]),
                    ("G", vec![0.0, 0.0]),
                    ("R", vec![1e-3, 0.0]),
                ],
                "flow.exr" => vec![("G", vec![1.5, 0.0]), ("R", vec![0.25, 0.0])],
                "flow_next.exr" => vec![("G", vec![0.125, 0.0]), ("R", vec![-0.5, 0.0])],
                "flow_prev.exr" => vec![("G", vec![0.0, 0.0]), ("R", vec![0.0, 0.0])],
                "crack_width.exr" => vec![("Y", vec![0.3, 0.0])],
                "crack_coverage.exr" => vec![("Y", vec![0.15, 0.0])],
                other => panic!("no expected channels for {other}"),
            }
        };
        let mut checked = 0;
        for writer in &WRITERS {
            let files = (writer.write)(&Tiny).unwrap();
            for (kind, bytes) in writer.files.iter().zip(files) {
                if !kind.ends_with(".exr") {
                    continue;
                }
                let (_, stored) = super::super::encode::tests::read_channels(&bytes);
                let want: Vec<(String, Vec<f32>)> = (expected(kind).into_iter())
                    .map(|(n, v)| (n.to_string(), v))
                    .collect();
                assert_eq!(stored, want, "{kind}");
                checked += 1;
            }
        }
        assert_eq!(checked, 10);
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
        for writer in &SAMPLE_WRITERS {
            assert!(names.iter().filter(|n| **n == writer.output).count() == 1);
            let files = (writer.write)(&Triangle::new()).unwrap();
            assert_eq!(files.len(), writer.files.len(), "{}", writer.output);
            assert!(files.iter().all(|bytes| !bytes.is_empty()));
        }
    }
}
