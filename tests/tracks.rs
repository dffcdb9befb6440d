//! True point tracks (`point_tracks`) seen from outside: the crossing of tests/sequences.rs run
//! by the binary, each frame's tracks read from its `tracks.npy` and compared with the
//! closed-form beam (`ModalBeam`): each query point of the first frame carried by the beam's
//! kinematics and projected through each frame's written camera; with the mount shaking too.
//! A still asking for tracks is refused at its `dataset(` call. `shmgen eval` scores predicted
//! tracks in TAP-Vid's layout: the truth itself scores 0 px and δ_avg 1, the truth moved by
//! (1.5, 0) px an RMSE of 1.5 px, and malformed files are refused with what they hold.

mod common;
mod crossing;

use common::{render, run, shmgen, stderr, write, write_npy};
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

/// The truth of view 0 in TAP-Vid's layout: [N, T, 2] x, y, and [N, T] occluded.
fn stacked_truth(out: &Path) -> (Vec<[f64; 2]>, Vec<bool>, usize) {
    let frames: Vec<Vec<[f64; 3]>> = (0..CROSSING_FRAMES).map(|k| frame_tracks(out, k)).collect();
    let points = frames[0].len();
    let mut xy = Vec::new();
    let mut occluded = Vec::new();
    for n in 0..points {
        for frame in &frames {
            xy.push([frame[n][0], frame[n][1]]);
            occluded.push(frame[n][2] != 1.0);
        }
    }
    (xy, occluded, points)
}

/// Writes predicted tracks (moved by `shift`) and occlusion for view 0 under `predictions`.
fn write_prediction(predictions: &Path, out: &Path, shift: [f64; 2]) -> usize {
    let (xy, occluded, points) = stacked_truth(out);
    let data: Vec<u8> = (xy.iter())
        .flat_map(|p| [p[0] + shift[0], p[1] + shift[1]])
        .flat_map(f64::to_le_bytes)
        .collect();
    let folder = predictions.join("0000");
    let shape = [points, CROSSING_FRAMES, 2];
    write_npy(&folder.join("000000_00.tracks.npy"), "<f8", &shape, &data);
    let flags: Vec<u8> = occluded.iter().map(|&o| u8::from(o)).collect();
    let flag_shape = [points, CROSSING_FRAMES];
    write_npy(
        &folder.join("000000_00.occluded.npy"),
        "|b1",
        &flag_shape,
        &flags,
    );
    points
}

/// `shmgen eval OUT PREDICTIONS --json`: its exit status, stderr and JSON report's `tracks`.
fn eval_tracks(out: &Path, predictions: &Path) -> (bool, String, serde_json::Value) {
    let json = predictions.with_extension("json");
    let _ = std::fs::remove_file(&json);
    let output = shmgen(&[
        "eval".as_ref(),
        out.as_os_str(),
        predictions.as_os_str(),
        "--json".as_ref(),
        json.as_os_str(),
    ]);
    let report = std::fs::read(&json)
        .ok()
        .map_or(serde_json::Value::Null, |b| {
            serde_json::from_slice(&b).unwrap()
        });
    (
        output.status.success(),
        stderr(&output),
        report["tracks"].clone(),
    )
}

#[test]
fn eval_scores_predicted_tracks_against_the_truth_and_refuses_malformed_ones() {
    let stride = format!(", track_stride: {STRIDE}");
    let (dir, out) = render(&crossing_recipe(&stride, TRACK_OUTPUTS), &[]);
    let predictions = dir.path().join("predicted");
    // The truth itself: no error, every point within every threshold, occlusion all right.
    write_prediction(&predictions, &out, [0.0, 0.0]);
    let (success, text, tracks) = eval_tracks(&out, &predictions);
    assert!(success, "{text}");
    assert_eq!(tracks["rmse"], 0.0, "{tracks}");
    assert_eq!(tracks["max_error"], 0.0, "{tracks}");
    assert_eq!(tracks["delta_avg"], 1.0, "{tracks}");
    assert_eq!(tracks["occlusion_accuracy"], 1.0, "{tracks}");
    assert_eq!(tracks["average_jaccard"], 1.0, "{tracks}");
    assert_eq!(tracks["counts"]["images"], 1, "{tracks}");
    // Moved by 1.5 px: RMSE 1.5 px exactly, outside the 1 px threshold only.
    let points = write_prediction(&predictions, &out, [1.5, 0.0]);
    let (success, text, tracks) = eval_tracks(&out, &predictions);
    assert!(success, "{text}");
    let rmse = tracks["rmse"].as_f64().unwrap();
    assert!((rmse - 1.5).abs() < 1e-9, "{tracks}");
    assert!(
        (tracks["delta_avg"].as_f64().unwrap() - 0.8).abs() < 1e-12,
        "{tracks}"
    );
    // Every pair after the query frame is scored.
    let pairs = points * (CROSSING_FRAMES - 1);
    assert_eq!(tracks["counts"]["pixels"], pairs as u64, "{tracks}");
    // A prediction of the wrong shape is refused with its shape and the one expected.
    let file = predictions.join("0000/000000_00.tracks.npy");
    write_npy(&file, "<f8", &[points, 3, 2], &vec![0; points * 3 * 16]);
    let (success, text, _) = eval_tracks(&out, &predictions);
    assert!(!success);
    let expected = format!(
        "shape [{points}, 3, 2]; the truth has {points} query points over {CROSSING_FRAMES} frames: expected [{points}, {CROSSING_FRAMES}, 2]"
    );
    assert!(
        text.contains("000000_00.tracks.npy") && text.contains(&expected),
        "{text}"
    );
    // Integers, and a pickle, are refused with the dtype.
    write_npy(
        &file,
        "<i8",
        &[points, CROSSING_FRAMES, 2],
        &vec![0; points * CROSSING_FRAMES * 16],
    );
    let (success, text, _) = eval_tracks(&out, &predictions);
    assert!(
        !success && text.contains("\"<i8\" is not float32 or float64"),
        "{text}"
    );
    write_npy(&file, "|O", &[1], b"\x80\x04N.");
    let (success, text, _) = eval_tracks(&out, &predictions);
    assert!(!success && text.contains("\"|O\""), "{text}");
    // Occlusion flags of the wrong shape too.
    write_prediction(&predictions, &out, [0.0, 0.0]);
    let flags = predictions.join("0000/000000_00.occluded.npy");
    write_npy(&flags, "|b1", &[points], &vec![0; points]);
    let (success, text, _) = eval_tracks(&out, &predictions);
    let expected = format!("shape [{points}]; expected [{points}, {CROSSING_FRAMES}]");
    assert!(!success && text.contains(&expected), "{text}");
    // A link is not followed.
    std::fs::remove_file(&file).unwrap();
    std::os::unix::fs::symlink(&flags, &file).unwrap();
    let (success, text, _) = eval_tracks(&out, &predictions);
    assert!(!success && text.contains("000000_00.tracks.npy"), "{text}");
    // A misnamed prediction (a frame's stem) is reported with the name eval reads.
    std::fs::remove_file(&file).unwrap();
    std::fs::remove_file(&flags).unwrap();
    write_prediction(&predictions, &out, [0.0, 0.0]);
    let stray = predictions.join("0000/000000_00_f0000.tracks_pred.npy");
    write_npy(&stray, "<f8", &[1], &[0; 8]);
    let (success, text, _) = eval_tracks(&out, &predictions);
    assert!(success, "{text}");
    assert!(
        text.contains("tracks_pred.npy") && text.contains("000000_00"),
        "{text}"
    );
}
