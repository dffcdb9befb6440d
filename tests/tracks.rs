//! True point tracks (`point_tracks`) seen from outside: the crossing of tests/sequences.rs run
//! by the binary, each frame's tracks read from its `tracks.npy` and compared with the
//! closed-form beam (`ModalBeam`): each query point of the first frame carried by the beam's
//! kinematics and projected through each frame's written camera; with the mount shaking too.
//! A still asking for tracks is refused at its `dataset(` call.

mod common;
mod crossing;

use common::{render, run, stderr, write};
use crossing::{CROSSING_FRAMES, Crossing, crossing_recipe, frame_view};
use std::path::Path;

const TRACK_OUTPUTS: &str = r#""depth", "mask", "point_tracks""#;

/// The query grid's stride the tests ask for.
const STRIDE: usize = 6;

/// The rows of a float64 `[Q, 3]` `.npy` file: the header checked, the data read.
fn read_rows(path: &Path) -> Vec<[f64; 3]> {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00", "{}", path.display());
    let length = usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
    let header = std::str::from_utf8(&bytes[10..10 + length]).unwrap();
    assert!(header.contains("'descr': '<f8'"), "{header}");
    let data = &bytes[10 + length..];
    let rows: Vec<[f64; 3]> = data
        .chunks_exact(24)
        .map(|row| {
            let value = |i: usize| f64::from_le_bytes(row[8 * i..8 * i + 8].try_into().unwrap());
            [value(0), value(1), value(2)]
        })
        .collect();
    assert!(
        header.contains(&format!("'shape': ({}, 3)", rows.len())),
        "{header}"
    );
    rows
}

/// Frame `frame`'s tracks of view 0 of sample 0.
fn frame_tracks(out: &Path, frame: usize) -> Vec<[f64; 3]> {
    read_rows(&out.join(format!("samples/0000/000000_00_f{frame:04}.tracks.npy")))
}

/// The query pixels, (row, col): the first frame's structure pixels on the stride grid.
fn query_pixels(first: &common::View) -> Vec<(usize, usize)> {
    let half = STRIDE / 2;
    let rows = (half..first.height).step_by(STRIDE);
    rows.flat_map(|row| {
        (half..first.width)
            .step_by(STRIDE)
            .map(move |col| (row, col))
    })
    .filter(|&(row, col)| first.mask[row * first.width + col] == 255)
    .collect()
}

/// Compares every frame's tracks with the closed-form kinematics of each query point carried
/// from the first frame, projected through the frame's written camera; returns the largest
/// error (px) and the largest distance a point moved from its query pixel (px).
fn check_tracks(out: &Path, crossing: &Crossing) -> (f64, f64) {
    let first = frame_view(out, 0);
    let queries = query_pixels(&first);
    assert!(queries.len() > 100, "{} queries", queries.len());
    eprintln!("{} queries", queries.len());
    let (mut worst, mut travel) = (0.0f64, 0.0f64);
    for k in 0..CROSSING_FRAMES {
        let view = frame_view(out, k);
        let tracks = frame_tracks(out, k);
        assert_eq!(tracks.len(), queries.len(), "frame {k}");
        let mut seen = 0;
        for (&(row, col), &[x, y, state]) in queries.iter().zip(&tracks) {
            assert!(
                [1.0, 0.0, -1.0].contains(&state),
                "frame {k}: state {state}"
            );
            if state < 0.0 {
                continue;
            }
            seen += usize::from(state == 1.0);
            let at_rest = first.point(row, col).unwrap();
            let ([tx, ty], _) = view.project(crossing.carried(at_rest, 0, k));
            let error = (x - tx).hypot(y - ty);
            // The chord error of the two tessellations and the neglected second-order terms
            // of the kinematics, as for the flow between frames.
            assert!(
                error < 5e-3,
                "frame {k}, query ({row}, {col}): track ({x}, {y}), truth ({tx}, {ty}), error {error} px"
            );
            worst = worst.max(error);
            travel = travel.max((x - (col as f64 + 0.5)).hypot(y - (row as f64 + 0.5)));
        }
        // Side-on, nothing hides the beam: every query is seen in every frame.
        assert_eq!(seen, queries.len(), "frame {k}");
    }
    (worst, travel)
}

#[test]
fn tracks_are_the_closed_form_motion_of_the_first_frames_points_through_each_frames_camera() {
    let stride = format!(", track_stride: {STRIDE}");
    let (_dir, out) = render(&crossing_recipe(&stride, TRACK_OUTPUTS), &[]);
    let crossing = Crossing::new();
    let (worst, travel) = check_tracks(&out, &crossing);
    eprintln!("still mounts: error {worst:.2e} px, points moved up to {travel:.3} px");
    assert!(travel > 0.5, "points moved {travel} px only");
    // At the first frame each query is its own pixel's centre.
    let first = frame_view(&out, 0);
    for (&(row, col), &[x, y, _]) in query_pixels(&first).iter().zip(&frame_tracks(&out, 0)) {
        let off = (x - (col as f64 + 0.5)).hypot(y - (row as f64 + 0.5));
        assert!(off < 1e-6, "query ({row}, {col}) at ({x}, {y})");
    }
    let record = common::read_json(&out.join("samples/0000/000000_00_f0003.json"));
    assert_eq!(
        record["files"]["tracks"],
        "samples/0000/000000_00_f0003.tracks.npy"
    );
    assert!(record["point_tracks"]["meaning"].is_string(), "{record}");
}

#[test]
fn tracks_follow_each_frames_camera_when_the_mount_shakes() {
    let sequence = format!(
        ", track_stride: {STRIDE}, mount: #{{ rotation: 2e-3, translation: 1e-3, band: 5.0 }}"
    );
    let (_dir, out) = render(&crossing_recipe(&sequence, TRACK_OUTPUTS), &[]);
    let (worst, travel) = check_tracks(&out, &Crossing::new());
    eprintln!("shaken mounts: error {worst:.2e} px, points moved up to {travel:.3} px");
    assert!(travel > 1.0, "points moved {travel} px only");
}

#[test]
fn point_tracks_are_refused_for_a_still_at_the_dataset_call() {
    let dir = tempfile::tempdir().unwrap();
    let recipe: String = (crossing_recipe("", TRACK_OUTPUTS).lines())
        .filter(|line| !line.contains("sequence:"))
        .map(|line| format!("{line}\n"))
        .collect();
    let path = write(dir.path(), "still.rhai", recipe);
    let out = run(&path, &dir.path().join("out"), &[]);
    assert!(!out.status.success());
    let text = stderr(&out);
    assert!(
        text.contains("\"point_tracks\"") && text.contains("dataset.sequence"),
        "{text}"
    );
    assert!(text.contains("still.rhai:1:"), "{text}");
}
