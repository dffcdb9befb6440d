//! Writing datasets: the writers of every output kind (per view and per sample), file
//! encodings (PNG, EXR, PLY, GLB), the folder layout and the atomic, resumable commit of each
//! sample.
//!
//! `series` writes the time series of virtual sensors (CSV and `.npy`).
//!
//! Owns: bytes on disk. Must not touch: recipes, mechanics or tracing; it receives finished
//! per-pixel layers, a sample's meshes as plain arrays and serialised records, and imports
//! nothing else of the crate. Every file
//! is written under a temporary name and renamed into place, so a killed run never leaves a
//! truncated file under a final name, and a sample appears in the manifest only after all of
//! its files are complete. File locks keep one process per shard and let shards share a
//! folder; whatever a crash leaves is ignored, then removed (`folder`); `status` reads that
//! state (samples done per shard, locks held or left) without writing. `fault` injects
//! crashes and full disks for the robustness tests. `guard` refuses any output path that is
//! or lies inside a dataset or an export, for every command that writes.

mod encode;
mod fault;
mod folder;
mod guard;
mod lock;
mod merge;
mod meshes;
mod openexr;
mod series;
mod status;
mod writers;

pub use encode::{
    DEPTH_CHANNEL, ExrChannels, FLOW_CHANNELS, MAX_SEGMENTATION_ID, SCALAR_CHANNELS,
    VECTOR_CHANNELS, depth_exr, grey16_png, id_png, mask_png, npy, rgb_png, rgb16_png, vector_exr,
};
pub use folder::{
    DatasetFolder, FrameUnits, Identity, SampleSet, SampleStage, differences, write_atomic,
};
pub use guard::refuse_data_target;
pub use merge::{Arrival, MergeTarget, hard_link_opened};
pub use meshes::{MeshLayer, PointLayer};
pub use series::{RateGroup, SensorColumn, TIME_LABEL, series_files};
pub use status::{EXIT_COMPLETE, EXIT_INCOMPLETE, EXIT_RUNNING, Status, status};
pub use writers::{
    DEFAULT_OUTPUTS, DamageLayers, Flow, FrameFlow, SAMPLE_WRITERS, SampleLayers, SampleWriter,
    ViewLayers, WRITERS, Writer, output_names,
};

/// Relative path of one view's file of the given kind (`rgb.png`, `depth.exr`, ...):
/// samples are grouped a thousand to a folder so no folder grows unboundedly. Augmented copy
/// k of a view is `…_{view:02}a{k}.{kind}`.
pub fn view_file(sample: u64, view: u32, copy: Option<u32>, kind: &str) -> String {
    let copy = copy.map(|k| format!("a{k}")).unwrap_or_default();
    format!(
        "samples/{:04}/{sample:06}_{view:02}{copy}.{kind}",
        sample / 1000
    )
}

/// Relative path of one of a sample's own files (`mesh.ply`, `points.ply`, ...), beside the
/// files of its views: `samples/{sample/1000:04}/{sample:06}.{kind}`.
pub fn sample_file(sample: u64, kind: &str) -> String {
    format!("samples/{:04}/{sample:06}.{kind}", sample / 1000)
}

/// The path of a sample's or view's file (`view_file`, `sample_file`) in frame `frame` of a
/// sequence: `_f{frame:04}` after the sample and view, before the kind, so the frames of a view
/// sort together and WebDataset keys stay free of dots (`000007_01_f0042.rgb.png`).
pub fn in_frame(path: &str, frame: u32) -> String {
    let name_start = path.rfind('/').map_or(0, |i| i + 1);
    let dot = path[name_start..]
        .find('.')
        .map_or(path.len(), |i| name_start + i);
    format!("{}_f{frame:04}{}", &path[..dot], &path[dot..])
}

#[cfg(test)]
mod tests {
    #[test]
    fn frame_files_keep_the_kind_after_the_first_dot() {
        let f = super::in_frame(&super::view_file(1234, 7, Some(2), "depth.exr"), 42);
        assert_eq!(f, "samples/0001/001234_07a2_f0042.depth.exr");
        let m = super::in_frame(&super::sample_file(3, "mesh.ply"), 0);
        assert_eq!(m, "samples/0000/000003_f0000.mesh.ply");
    }

    #[test]
    fn layout_keys_have_no_dots_before_the_kind() {
        // WebDataset splits the key at the first dot of the file name.
        let f = super::view_file(1234, 7, None, "depth.exr");
        assert_eq!(f, "samples/0001/001234_07.depth.exr");
        let copy = super::view_file(1234, 7, Some(2), "depth.exr");
        assert_eq!(copy, "samples/0001/001234_07a2.depth.exr");
        assert_eq!(
            super::sample_file(1234, "mesh.ply"),
            "samples/0001/001234.mesh.ply"
        );
    }
}
