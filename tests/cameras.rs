//! Camera rigs and augmentations against independent truth, read back from written datasets:
//! back-projecting depth with the written K and pose lands on the analytic box, image-space
//! warps agree with the exact re-render and with the similarity they record, photometric
//! operations leave every label alone, a distorted render matches OpenCV's undistortion
//! (implemented here from its documentation), and stereo pairs satisfy the epipolar
//! constraint with disparity f·b/z.

mod common;

use common::{
    View, load, matrix, off_box, ok, read_json, read_png, render, run, transform, view_path, write,
};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The box every test looks at: 2 × 1 × 0.5 m, centred on the origin.
const HALF: [f64; 3] = [1.0, 0.5, 0.25];

/// A recipe looking at the box, with `camera` and `augment` options.
fn box_recipe(camera: &str, augment: &str) -> String {
    format!(
        "dataset(#{{ name: \"cameras\", seed: 4, samples: 1, views: 3,
            outputs: [\"rgb\", \"depth\", \"mask\", \"parts\", \"valid\"],
            camera: #{{ {camera} }},
            {augment}
            scene: |rng| assembly(\"box\", [shape::box(2.0, 1.0, 0.5)]),
        }})\n"
    )
}

/// The box seen by `camera`, with two copies made by `operations` warping the rendered
/// images, and again rendering them exactly: (folders to keep, image mode, exact mode).
fn both_modes(camera: &str, operations: &str) -> ([tempfile::TempDir; 2], PathBuf, PathBuf) {
    let recipe = |mode: &str| {
        box_recipe(
            camera,
            &format!("augment: #{{ copies: 2, mode: \"{mode}\", {operations} }},"),
        )
    };
    let (image_dir, image) = render(&recipe("image"), &[]);
    let (exact_dir, exact) = render(&recipe("exact"), &[]);
    ([image_dir, exact_dir], image, exact)
}

#[test]
fn exact_geometric_copies_back_project_onto_the_box_and_agree_across_views() {
    let recipe = box_recipe(
        "width: 160, height: 120, pitch: [0.3, 0.9], yaw: [0.2, 1.3]",
        "augment: #{ copies: 2, operations: [
            #{ op: \"warp\", zoom: [0.8, 1.3], rotation: [-3.0, 3.0], shift_x: [-0.1, 0.1], shift_y: [-0.1, 0.1], probability: 1.0 }] },",
    );
    let (_dir, out) = render(&recipe, &[]);
    let clean = load(&out, 0, None);
    for view in 0..3 {
        for copy in [None, Some(0), Some(1)] {
            let v = load(&out, view, copy);
            let mut seen = 0;
            for row in 0..v.height {
                for col in 0..v.width {
                    let Some(p) = v.point(row, col) else { continue };
                    seen += 1;
                    assert!(
                        off_box(p, HALF) < 1e-4,
                        "view {view} {copy:?} ({row},{col}): {p:?}"
                    );
                    // Seen from the clean view 0 too (unless hidden or off its frame), the
                    // point is where that view's own depth puts it.
                    let ([u, w], z) = clean.project(p);
                    let (c, r) = (u.floor(), w.floor());
                    if (0.0..160.0).contains(&c) && (0.0..120.0).contains(&r) {
                        let (r, c) = (r as usize, c as usize);
                        if clean.inside(r, c) && v.inside(row, col) {
                            // The nearest surface view 0 sees around there (depth varies
                            // within a pixel on a slanted face).
                            let nearest = (r - 1..=r + 1)
                                .flat_map(|i| (c - 1..=c + 1).map(move |j| (i, j)))
                                .map(|(i, j)| f64::from(clean.depth[i * 160 + j]))
                                .fold(f64::INFINITY, f64::min);
                            // Hidden points lie behind what view 0 sees, never in front (but
                            // for the dip of a crease between pixel centres, well under 0.5 %;
                            // a wrong pose would put points a box's thickness off).
                            assert!(z >= nearest * (1.0 - 5e-3), "{z} in front of {nearest}");
                        }
                    }
                }
            }
            assert!(seen > 500, "view {view} {copy:?} sees {seen} pixels");
        }
    }
}

#[test]
fn image_space_warps_agree_with_the_exact_render_and_their_record() {
    let camera = "width: 160, height: 120, pitch: [0.3, 0.9], yaw: [0.2, 1.3]";
    let operations = "operations: [#{ op: \"warp\", zoom: [0.9, 1.2], rotation: [-0.6, 0.6], shift_x: [-0.05, 0.05], shift_y: 0.0, probability: 1.0 }]";
    let (_dirs, warped, rendered) = both_modes(camera, operations);
    for view in 0..3 {
        let clean = load(&warped, view, None);
        for copy in [0, 1] {
            let w = load(&warped, view, Some(copy));
            let e = load(&rendered, view, Some(copy));
            // The same draws give the same camera in both modes.
            assert_eq!(w.json["camera"]["K"], e.json["camera"]["K"]);
            assert_eq!(
                w.json["camera"]["c2w_opencv"],
                e.json["camera"]["c2w_opencv"]
            );
            // The record's K and pose reproduce the warp it records: a clean pixel's surface
            // point projects with them where the similarity sends the pixel.
            let sim = &w.json["augmentation"]["operations"][0];
            assert_eq!(sim["op"], "warp");
            let (s, a) = (
                sim["zoom"].as_f64().unwrap(),
                sim["angle"].as_f64().unwrap(),
            );
            let c = [
                sim["centre"][0].as_f64().unwrap(),
                sim["centre"][1].as_f64().unwrap(),
            ];
            let t = [
                sim["shift"][0].as_f64().unwrap(),
                sim["shift"][1].as_f64().unwrap(),
            ];
            let mut checked = 0;
            for row in (0..120).step_by(7) {
                for col in (0..160).step_by(7) {
                    let Some(p) = clean.point(row, col) else {
                        continue;
                    };
                    let (x, y) = (col as f64 + 0.5 - c[0], row as f64 + 0.5 - c[1]);
                    let moved = [
                        s * (a.cos() * x - a.sin() * y) + c[0] + t[0],
                        s * (a.sin() * x + a.cos() * y) + c[1] + t[1],
                    ];
                    let (projected, _) = w.project(p);
                    assert!(
                        (projected[0] - moved[0]).abs() < 1e-3
                            && (projected[1] - moved[1]).abs() < 1e-3,
                        "{projected:?} vs {moved:?}"
                    );
                    checked += 1;
                }
            }
            assert!(checked > 10);
            // Away from edges the warped depth is the re-rendered one, to the depth change
            // over half a pixel.
            let (mut close, mut compared) = (0, 0);
            for row in 1..119 {
                for col in 1..159 {
                    if w.inside(row, col) && e.inside(row, col) {
                        compared += 1;
                        let (dw, de) = (w.depth[row * 160 + col], e.depth[row * 160 + col]);
                        if (dw - de).abs() <= 0.02 * de {
                            close += 1;
                        }
                    }
                }
            }
            assert!(
                compared > 500 && close * 100 >= compared * 98,
                "{close}/{compared}"
            );
            // Pixels without a source are invalid: depth 0 and mask 0.
            let (_, _, _, valid) = read_png(&view_path(&warped, 0, view, Some(copy), "valid.png"));
            for (i, &ok) in valid.iter().enumerate() {
                if ok == 0 {
                    assert!(w.depth[i] == 0.0 && w.mask[i] == 0);
                }
            }
        }
    }
}

#[test]
fn photometric_copies_leave_depth_masks_and_labels_byte_identical() {
    let recipe = box_recipe(
        "width: 96, height: 64",
        "augment: #{ copies: 2, operations: [
            #{ op: \"colour_jitter\", brightness: [0.8, 1.2], contrast: [0.8, 1.2], saturation: [0.8, 1.2], hue: [-0.1, 0.1], probability: 1.0 },
            #{ op: \"noise\", model: \"gaussian\", sigma: 5.0, probability: 1.0 },
            #{ op: \"blur\", kind: \"gaussian\", sigma: 1.5, probability: 1.0 },
            #{ op: \"jpeg\", quality: 40.0, probability: 1.0 },
            #{ op: \"erase\", count: 2, area: [0.05, 0.1], aspect: [0.5, 2.0], probability: 1.0 }] },",
    );
    let (_dir, out) = render(&recipe, &[]);
    for view in 0..3 {
        for kind in ["depth.exr", "mask.png", "parts.png", "valid.png"] {
            let clean = std::fs::read(view_path(&out, 0, view, None, kind)).unwrap();
            for copy in [0, 1] {
                let copied = std::fs::read(view_path(&out, 0, view, Some(copy), kind)).unwrap();
                assert!(clean == copied, "view {view} copy {copy}: {kind} changed");
            }
        }
        let clean = std::fs::read(view_path(&out, 0, view, None, "rgb.png")).unwrap();
        let copied = std::fs::read(view_path(&out, 0, view, Some(0), "rgb.png")).unwrap();
        assert!(clean != copied, "the RGB image must change");
    }
}

/// Planar depth of the first hit of the camera ray (x, y, 1) with the box, slab method.
fn box_depth(c2w: &[[f64; 4]; 4], x: f64, y: f64) -> Option<f64> {
    let d: [f64; 3] = std::array::from_fn(|i| c2w[i][0] * x + c2w[i][1] * y + c2w[i][2]);
    let o = [c2w[0][3], c2w[1][3], c2w[2][3]];
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for i in 0..3 {
        let (a, b) = ((-HALF[i] - o[i]) / d[i], (HALF[i] - o[i]) / d[i]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1 && t0 > 0.0).then_some(t0)
}

/// Checks every pixel of `v` against the box: where its ray (the written camera's, undistorted
/// as OpenCV does) meets the box, the depth written is that hit's; elsewhere nothing, but for
/// the silhouette. Returns the pixels that see the box.
fn assert_depth_is_the_box_through_the_written_lens(v: &View) -> usize {
    let mut hits = 0;
    for row in 0..v.height {
        for col in 0..v.width {
            let (x, y) = v.ray(row, col);
            let truth = box_depth(&v.c2w(), x, y);
            let z = v.depth[row * v.width + col];
            match truth {
                Some(t) if z > 0.0 => {
                    hits += 1;
                    let off = (f64::from(z) - t).abs();
                    assert!(off < 1e-5 * t, "({row},{col}) {z} vs {t}");
                }
                None if z == 0.0 => {}
                // Coverage may differ only along the silhouette.
                _ => assert!(!v.inside(row, col), "({row},{col}) {z} vs {truth:?}"),
            }
        }
    }
    hits
}

#[test]
fn a_distorted_render_is_the_pinhole_render_seen_through_opencvs_lens_model() {
    let lens = "distortion: #{ k1: -0.25, k2: 0.06, p1: 0.0012, p2: -0.0008, k3: -0.004 }";
    let pose = "fixed: [#{ position: [4.0, -3.0, 2.0] }, #{ position: [-3.5, -2.0, -1.0] }, #{ position: [0.5, 4.0, 3.0] }]";
    let (_a, distorted) = render(
        &box_recipe(
            &format!("width: 200, height: 150, fov_y: 0.9, {lens}, {pose}"),
            "",
        ),
        &[],
    );
    let (_b, pinhole) = render(
        &box_recipe(&format!("width: 200, height: 150, fov_y: 0.9, {pose}"), ""),
        &[],
    );
    for view in 0..3 {
        let v = load(&distorted, view, None);
        let p = load(&pinhole, view, None);
        assert_eq!(v.json["camera"]["model"], "opencv");
        // Each distorted pixel's ray, undistorted by OpenCV's model, meets the box at the
        // depth written.
        let hits = assert_depth_is_the_box_through_the_written_lens(&v);
        // And the pinhole render sees the same point where OpenCV's undistortion sends the
        // pixel.
        let k = v.k();
        let mut agree = 0;
        for row in 0..150 {
            for col in 0..200 {
                let (x, y) = v.ray(row, col);
                let Some(t) = box_depth(&v.c2w(), x, y) else {
                    continue;
                };
                let (u, w) = (k[0][0] * x + k[0][2], k[1][1] * y + k[1][2]);
                let (c, r) = (u.floor() as isize, w.floor() as isize);
                if v.depth[row * 200 + col] > 0.0
                    && (1..199).contains(&c)
                    && (1..149).contains(&r)
                    && p.inside(r as usize, c as usize)
                {
                    let there = f64::from(p.depth[r as usize * 200 + c as usize]);
                    if (there - t).abs() < 0.02 * t {
                        agree += 1;
                    }
                }
            }
        }
        assert!(hits > 1000 && agree * 10 > hits * 8, "{agree}/{hits}");
    }
}

/// A fixed rig of three cameras around the box, `size` pixels, field of view `fov_y`, with
/// `lens`.
fn lens_rig(size: &str, fov_y: &str, lens: &str) -> String {
    format!(
        "{size}, fov_y: {fov_y}, distortion: #{{ {lens} }}, fixed: [#{{ position: [4.0, -3.0, 2.0] }}, #{{ position: [-3.5, -2.0, -1.0] }}, #{{ position: [0.5, 4.0, 3.0] }}]"
    )
}

#[test]
fn an_exact_zoom_out_past_the_lens_fold_is_refused_and_within_it_every_pixel_has_its_ray() {
    // k1 = −0.19 at 60° on a square image: the lens is one-to-one out to a distorted radius
    // of about 0.88, just past the clean corners (0.816); zooming out to 0.8 would show it out
    // to 1.02.
    let lens = "k1: -0.19, p1: 0.002, p2: -0.0015";
    let rig = lens_rig("width: 96, height: 96", "deg(60)", lens);
    let warp = |zoom: &str| {
        format!(
            "augment: #{{ copies: 2, operations: [#{{ op: \"warp\", zoom: {zoom}, rotation: [-3.0, 3.0], shift_x: [-0.002, 0.002], shift_y: 0.0, probability: 1.0 }}] }},"
        )
    };
    let dir = tempfile::tempdir().unwrap();
    let refused = write(dir.path(), "r.rhai", box_recipe(&rig, &warp("0.8")));
    let output = run(&refused, &dir.path().join("out"), &[]);
    let text = common::stderr(&output);
    assert!(!output.status.success(), "{text}");
    for part in [
        "operations[0] (warp).zoom = 0.8",
        "k1 = -0.19",
        "no ray",
        "r.rhai:1:1",
    ] {
        assert!(text.contains(part), "{part}: {text}");
    }
    assert!(!dir.path().join("out").exists());
    // Zoomed out a little only (and turned, and shifted): every pixel of every copy has the
    // ray of the camera written with it.
    let recipe = box_recipe(&rig, &warp("[1.0, 1.2]"));
    let (_dir, out) = render(&recipe, &[]);
    for view in 0..3 {
        for copy in [None, Some(0), Some(1)] {
            let v = load(&out, view, copy);
            assert!(assert_depth_is_the_box_through_the_written_lens(&v) > 300);
        }
    }
}

#[test]
fn image_space_warps_of_a_decentred_lens_are_reproduced_by_the_written_camera() {
    // Tangential distortion turns with the picture: the copy's written K, pose and lens must
    // send each surface point where the warp moved its pixel.
    let lens = "k1: -0.12, p1: 0.01, p2: -0.01";
    let operations = "operations: [#{ op: \"warp\", zoom: [0.95, 1.1], rotation: [0.7, 2.5], shift_x: [-0.05, 0.05], shift_y: 0.03, probability: 1.0 }]";
    let camera = lens_rig("width: 100, height: 80", "0.9", lens);
    let (_dirs, warped, rendered) = both_modes(&camera, operations);
    for view in 0..3 {
        let clean = load(&warped, view, None);
        for copy in [0, 1] {
            let w = load(&warped, view, Some(copy));
            // Both modes write one camera: the exact render is through it.
            assert_eq!(
                w.json["camera"],
                load(&rendered, view, Some(copy)).json["camera"]
            );
            let sim = &w.json["augmentation"]["operations"][0];
            let number = |v: &Value| v.as_f64().unwrap();
            let (s, a) = (number(&sim["zoom"]), number(&sim["angle"]));
            let (c, t) = (&sim["centre"], &sim["shift"]);
            let mut checked = 0;
            for row in 0..80 {
                for col in 0..100 {
                    let Some(p) = clean.point_through_lens(row, col) else {
                        continue;
                    };
                    let (x, y) = (
                        col as f64 + 0.5 - number(&c[0]),
                        row as f64 + 0.5 - number(&c[1]),
                    );
                    let moved = [
                        s * (a.cos() * x - a.sin() * y) + number(&c[0]) + number(&t[0]),
                        s * (a.sin() * x + a.cos() * y) + number(&c[1]) + number(&t[1]),
                    ];
                    let projected = w.project_through_lens(p);
                    let off = (projected[0] - moved[0]).hypot(projected[1] - moved[1]);
                    assert!(off < 1e-6, "view {view} copy {copy}: {off} px");
                    checked += 1;
                }
            }
            assert!(checked > 100, "{checked}");
        }
    }
}

#[test]
fn stereo_pairs_satisfy_the_epipolar_constraint_and_disparity_is_f_b_over_z() {
    for toe_in in [0.0, 0.05] {
        let recipe = box_recipe(
            &format!(
                "width: 160, height: 120, pitch: [0.2, 0.7], stereo: #{{ baseline: 0.3, toe_in: {toe_in} }}"
            ),
            "",
        );
        let (_dir, out) = render(&recipe, &[]);
        for pair in 0..3 {
            let (l, r) = (load(&out, 2 * pair, None), load(&out, 2 * pair + 1, None));
            let stereo = &l.json["camera"]["stereo"];
            assert_eq!(stereo["eye"], "left");
            assert_eq!(stereo["partner_view"], 2 * pair + 1);
            assert_eq!(r.json["camera"]["stereo"]["eye"], "right");
            // The relative pose written agrees with the two poses written.
            let right_from_left: [[f64; 4]; 4] = matrix(&stereo["right_from_left"]);
            let f = l.k()[0][0];
            let mut checked = 0;
            for row in (1..119).step_by(3) {
                for col in (1..159).step_by(3) {
                    if !l.inside(row, col) {
                        continue;
                    }
                    let p = l.point(row, col).unwrap();
                    let left_cam = transform(&l.w2c(), p);
                    let right_cam = transform(&r.w2c(), p);
                    let via = transform(&right_from_left, left_cam);
                    assert!((0..3).all(|i| (via[i] - right_cam[i]).abs() < 1e-9));
                    // Epipolar constraint: x_rᵀ E x_l = 0 with E = [t]× R.
                    let m = right_from_left;
                    let t = [m[0][3], m[1][3], m[2][3]];
                    let rx: [f64; 3] = std::array::from_fn(|i| {
                        (0..3).map(|j| m[i][j] * left_cam[j] / left_cam[2]).sum()
                    });
                    let e = [
                        t[1] * rx[2] - t[2] * rx[1],
                        t[2] * rx[0] - t[0] * rx[2],
                        t[0] * rx[1] - t[1] * rx[0],
                    ];
                    let xr = [
                        right_cam[0] / right_cam[2],
                        right_cam[1] / right_cam[2],
                        1.0,
                    ];
                    let residual: f64 = (0..3).map(|i| xr[i] * e[i]).sum();
                    assert!(residual.abs() < 1e-9, "{residual}");
                    if toe_in == 0.0 {
                        // A rectified pair: same row, disparity f·b/z.
                        let ([ul, vl], z) = l.project(p);
                        let ([ur, vr], _) = r.project(p);
                        assert!((vl - vr).abs() < 1e-6);
                        assert!(((ul - ur) - f * 0.3 / z).abs() < 1e-6 * f);
                        // And the right eye's own depth sees the same point.
                        let (c, rr) = (ur.floor() as usize, vr.floor() as usize);
                        if (1.0..159.0).contains(&ur) && r.inside(rr, c) {
                            let there = f64::from(r.depth[rr * 160 + c]);
                            assert!((there - right_cam[2]).abs() < 0.02 * there);
                        }
                    }
                    checked += 1;
                }
            }
            assert!(checked > 50, "{checked}");
        }
    }
}

#[test]
fn degenerate_rigs_are_clear_errors_at_the_recipe() {
    for (camera, expected) in [
        (
            "line: #{ from: [1.0, 2.0, 3.0], to: [1.0, 2.0, 3.0] }",
            "length zero",
        ),
        (
            "fixed: [#{ position: [0.0, 0.0, 3.0], target: [0.0, 0.0, 3.0] }, #{ position: [1.0, 0.0, 3.0] }, #{ position: [2.0, 0.0, 3.0] }]",
            "own position",
        ),
        ("stereo: #{ baseline: 0.0 }", "baseline"),
        ("distortion: #{ k1: -2.0 }", "folds the image"),
        (
            "fixed: [#{ position: [0.0, 0.0, 3.0] }]",
            "each view is one fixed camera",
        ),
        (
            "orbit: #{ sweep: 0.0 }",
            "sweep = 0 puts all 3 views at one azimuth",
        ),
        ("orbit: #{ sweep: deg(720) }", "whole number of turns"),
        // The box's centre is the origin: a camera there, looking at the default target (the
        // centre), or a flight line whose middle view stands there.
        (
            "fixed: [#{ position: [0.0, 0.0, 0.0] }, #{ position: [1.0, 0.0, 3.0] }, #{ position: [2.0, 0.0, 3.0] }]",
            "dataset.camera.fixed[0] stands at (0, 0, 0), the very point it aims at",
        ),
        (
            "line: #{ from: [-3.0, 0.0, 0.0], to: [3.0, 0.0, 0.0] }",
            "dataset.camera.line, view 1, stands at (0, 0, 0)",
        ),
        (
            "line: #{ from: [-3.0, 0.0, 2.0], to: [3.0, 0.0, 2.0], target: [1.0, 0.0, 2.0] }",
            "passes through its target [1.0, 0.0, 2.0]: a view standing there would aim at its own position",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = write(
            dir.path(),
            "r.rhai",
            box_recipe(&format!("width: 32, height: 32, {camera}"), ""),
        );
        let output = run(&path, &dir.path().join("out"), &[]);
        let text = common::stderr(&output);
        assert!(
            !output.status.success() && text.contains(expected) && text.contains("r.rhai:1:1"),
            "{camera}: {text}"
        );
        assert!(!text.contains("NaN"), "{text}");
        assert!(!dir.path().join("out").exists());
    }
}

#[test]
fn augmentation_and_camera_options_are_checked_by_name() {
    let op = |fields: &str| format!("augment: #{{ copies: 1, operations: [{fields}] }},");
    for (camera, augment, expected) in [
        (
            "",
            op("#{ op: \"erase\", count: 1, area: 0.1, aspect: 1.0, fil: \"noise\", probability: 1.0 }"),
            "unknown option `dataset.augment.operations[0] (erase).fil`; did you mean `fill`?",
        ),
        (
            "",
            op("#{ op: \"noise\", model: \"gaussian\", sigma: 0.02, units: \"fraction\", probability: 1.0 }"),
            "unknown option `dataset.augment.operations[0] (noise).units`; did you mean `unit`?",
        ),
        (
            "",
            "augment: #{ copies: 1, operations: #{ op: \"gamma\", gamma: 1.0, probability: 1.0 } },".into(),
            "dataset.augment.operations = #{",
        ),
        (
            "",
            op("#{ op: \"gamma\", gamma: 1.0, probability: [0.1, 0.2] }"),
            "dataset.augment.operations[0] (gamma).probability = [0.1, 0.2] (array) must be a number",
        ),
        (
            "",
            op("#{ op: \"jpeg\", quality: 50.0, probability: 1.0 }, #{ op: \"gamma\", gamma: 100.0, probability: 1.0 }"),
            "dataset.augment.operations[1] (gamma).gamma = 100 must lie within [0.05, 20]",
        ),
        (
            "",
            op("#{ op: \"gama\", gamma: 1.0, probability: 1.0 }"),
            "did you mean \"gamma\"?",
        ),
        (
            "",
            op("#{ op: \"erase\", count: [0.2, 0.8], area: 0.1, aspect: 1.0, probability: 1.0 }"),
            "(erase).count = [0.2, 0.8] holds no whole number",
        ),
        (
            "",
            op("#{ op: \"jpeg\", quality: [20.2, 20.8], probability: 1.0 }"),
            "(jpeg).quality = [20.2, 20.8] holds no whole number",
        ),
        (
            "",
            op("#{ op: \"blur\", kind: \"gausian\", sigma: 1.0, probability: 1.0 }"),
            "did you mean \"gaussian\"?",
        ),
        (
            "",
            op("#{ op: \"warp\", zoom: 1.1, probability: 1.0 }"),
            "missing option `dataset.augment.operations[0] (warp).rotation`",
        ),
        (
            "",
            "augment: #{ copies: 1, mode: \"imag\" },".into(),
            "did you mean \"image\"?",
        ),
        (
            "stereo: #{ baseline: 0.2, toein: 0.1 },",
            String::new(),
            "unknown option `dataset.camera.stereo.toein`; did you mean `toe_in`?",
        ),
        (
            "distortion: #{ k_1: -0.1 },",
            String::new(),
            "unknown option `dataset.camera.distortion.k_1`; did you mean `k1`?",
        ),
        (
            "orbit: #{ swep: 1.0 },",
            String::new(),
            "unknown option `dataset.camera.orbit.swep`; did you mean `sweep`?",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let recipe = box_recipe(&format!("{camera} width: 32, height: 32"), &augment);
        let path = write(dir.path(), "r.rhai", &recipe);
        let output = run(&path, &dir.path().join("out"), &[]);
        let text = common::stderr(&output);
        // An unknown option is shown at its key (`fil:`), any other error at `dataset(`.
        let place = match expected.strip_prefix("unknown option `") {
            Some(path) => {
                let key = format!("{}:", path.split('`').next().unwrap().rsplit('.').next().unwrap());
                let (line, col) = recipe
                    .lines()
                    .enumerate()
                    .find_map(|(i, l)| l.find(&key).map(|c| (i + 1, c + 1)))
                    .unwrap();
                format!("r.rhai:{line}:{col}\n")
            }
            None => "r.rhai:1:1".to_string(),
        };
        assert!(
            !output.status.success() && text.contains(expected) && text.contains(&place),
            "{expected} at {place}: {text}"
        );
    }
}

#[test]
fn both_eyes_of_a_stereo_pair_photograph_one_backdrop() {
    // Photographs as backdrops, each eye a random window of one: a stereo pair is one moment,
    // so its eyes must show the same photograph through the same window. Three photographs of
    // distinct flat colours, so a mismatch shows in the pixels as well as in the record.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("bg")).unwrap();
    for (name, grey) in [("a.png", 40u8), ("b.png", 120), ("c.png", 200)] {
        image::GrayImage::from_pixel(64, 48, image::Luma([grey]))
            .save(dir.path().join("bg").join(name))
            .unwrap();
    }
    let recipe = write(
        dir.path(),
        "recipe.rhai",
        box_recipe(
            "width: 80, height: 60, stereo: #{ baseline: 0.3 }",
            "background: #{ images: \"bg\" },",
        )
        .replace("views: 3", "views: 6"),
    );
    let out = dir.path().join("out");
    ok(run(&recipe, &out, &[]));
    let backdrops: Vec<Value> = (0..12)
        .map(|view| load(&out, view, None).json["background"].clone())
        .collect();
    for pair in backdrops.chunks(2) {
        assert_eq!(pair[0], pair[1], "left and right eye backdrops");
    }
    // Six poses draw their photographs independently: not all alike.
    assert!(
        backdrops.iter().any(|b| b != &backdrops[0]),
        "{backdrops:?}"
    );
    for pair in 0..6 {
        let rgb = |view| read_png(&view_path(&out, 0, view, None, "rgb.png")).3;
        let (left, right) = (rgb(2 * pair), rgb(2 * pair + 1));
        let (lm, rm) = (
            load(&out, 2 * pair, None).mask,
            load(&out, 2 * pair + 1, None).mask,
        );
        // Away from the box: anti-aliasing blends silhouettes into the pixels next to them.
        let clear = |i: usize| {
            let (row, col) = ((i / 80) as i64, (i % 80) as i64);
            (-1..=1).all(|dr| {
                (-1..=1).all(|dc| {
                    let (r, c) = ((row + dr).clamp(0, 59), (col + dc).clamp(0, 79));
                    let j = (r * 80 + c) as usize;
                    lm[j] == 0 && rm[j] == 0
                })
            })
        };
        let mut compared = 0;
        for i in (0..lm.len()).filter(|&i| clear(i)) {
            assert_eq!(left[3 * i..3 * i + 3], right[3 * i..3 * i + 3], "pixel {i}");
            compared += 1;
        }
        assert!(compared > 1000, "{compared} background pixels");
    }
}

#[test]
fn stereo_copies_record_the_relative_pose_they_are_written_with() {
    for mode in ["exact", "image"] {
        let recipe = box_recipe(
            "width: 96, height: 72, pitch: [0.2, 0.7], stereo: #{ baseline: 0.3, toe_in: 0.04 }",
            &format!(
                "augment: #{{ copies: 2, mode: \"{mode}\", operations: [#{{ op: \"warp\", zoom: [0.9, 1.1], rotation: [-1.0, 1.0], shift_x: [-0.05, 0.05], shift_y: 0.0, probability: 1.0 }}] }},"
            ),
        );
        let (_dir, out) = render(&recipe, &[]);
        for pair in 0..3 {
            for copy in [None, Some(0), Some(1)] {
                let (l, r) = (load(&out, 2 * pair, copy), load(&out, 2 * pair + 1, copy));
                // w2c_right · c2w_left from the two poses written.
                let (w2c, c2w) = (r.w2c(), l.c2w());
                let truth: [[f64; 4]; 4] = std::array::from_fn(|i| {
                    std::array::from_fn(|j| (0..4).map(|k| w2c[i][k] * c2w[k][j]).sum())
                });
                for v in [&l, &r] {
                    let written: [[f64; 4]; 4] =
                        matrix(&v.json["camera"]["stereo"]["right_from_left"]);
                    for i in 0..4 {
                        for j in 0..4 {
                            assert!(
                                (written[i][j] - truth[i][j]).abs() < 1e-9,
                                "{mode} pair {pair} copy {copy:?}: {written:?} vs {truth:?}"
                            );
                        }
                    }
                }
                // One warp per pair: both eyes' copies have one K and stay a rigid pair, the
                // right eye one baseline from the left.
                assert_eq!(l.json["camera"]["K"], r.json["camera"]["K"]);
                let t = [truth[0][3], truth[1][3], truth[2][3]];
                assert!(((t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt() - 0.3).abs() < 1e-9);
            }
        }
    }
}

#[test]
fn pixels_without_a_source_stay_black_under_every_photometric_operation() {
    let recipe = box_recipe(
        "width: 80, height: 60",
        "augment: #{ copies: 2, mode: \"image\", operations: [
            #{ op: \"warp\", zoom: 0.6, rotation: [-0.5, 0.5], shift_x: 0.0, shift_y: 0.0, probability: 1.0 },
            #{ op: \"colour_jitter\", brightness: 1.2, contrast: 0.5, saturation: 1.0, hue: 0.0, probability: 1.0 },
            #{ op: \"noise\", model: \"gaussian\", sigma: 20.0, probability: 1.0 },
            #{ op: \"blur\", kind: \"gaussian\", sigma: 2.0, probability: 1.0 },
            #{ op: \"erase\", count: 3, area: [0.2, 0.3], aspect: [0.5, 2.0], fill: \"noise\", probability: 1.0 },
            #{ op: \"jpeg\", quality: 20, probability: 1.0 }] },",
    );
    let (_dir, out) = render(&recipe, &[]);
    for view in 0..3 {
        for copy in [0, 1] {
            let (_, _, _, valid) = read_png(&view_path(&out, 0, view, Some(copy), "valid.png"));
            let (_, _, _, rgb) = read_png(&view_path(&out, 0, view, Some(copy), "rgb.png"));
            let invalid = valid.iter().filter(|&&v| v == 0).count();
            assert!(invalid > 1000, "{invalid}");
            for (k, &v) in valid.iter().enumerate() {
                if v == 0 {
                    assert_eq!(
                        rgb[3 * k..3 * k + 3],
                        [0, 0, 0],
                        "view {view} copy {copy} pixel {k}"
                    );
                }
            }
        }
    }
}

#[test]
fn the_a1_recipe_writes_the_masks_its_augmented_copies_need() {
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/a1_beams.rhai");
    for (augment, extra) in [
        ("none", &[][..]),
        ("paper", &["erased"][..]),
        ("paper_image", &["erased", "valid"][..]),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a1");
        let set = format!("augment={augment}");
        let args = ["--set", "samples=1", "--set", "views=1", "--set", &set];
        ok(run(&recipe, &out, &args));
        let copies: &[Option<u32>] = if augment == "none" {
            &[None]
        } else {
            &[None, Some(0)]
        };
        for &copy in copies {
            let files = &read_json(&view_path(&out, 0, 0, copy, "json"))["files"];
            let mut written: Vec<&str> = files
                .as_object()
                .unwrap()
                .keys()
                .map(|k| k.as_str())
                .collect();
            written.sort_unstable();
            let mut expected = vec!["depth", "mask", "rgb"];
            expected.extend(extra);
            expected.sort_unstable();
            assert_eq!(written, expected, "{augment} {copy:?}");
        }
    }
}

/// Each view's record says how its images were found, and says it truly: a pinhole view of
/// the box is rasterised (centre and edge rays), a lens's curved rays are traced; the unloaded
/// image and the flow's occlusion rays appear exactly when flow is written, shadow rays only
/// under a sun that casts shadows, and no edge rays without anti-aliasing. In every case the
/// depth written lies on the analytic box.
///
/// Flow (which adds the unloaded image and its occlusion rays) needs a loaded beam: see
/// `a_flow_record_lists_the_unloaded_image_and_its_occlusion_rays`.
#[test]
fn each_record_says_which_visibility_path_found_its_pixels() {
    let lens = "distortion: #{ k1: -0.25, k2: 0.06, p1: 0.0012, p2: -0.0008, k3: -0.004 }";
    let pinhole = "width: 96, height: 72, distance: 6.0";
    let cases = [
        (
            pinhole.to_string(),
            "",
            r#"{"primary":"rasterised","edge_rays":"rasterised","unloaded":null,"secondary":[]}"#,
        ),
        (
            format!("{pinhole}, {lens}"),
            "",
            r#"{"primary":"traced","edge_rays":"traced","unloaded":null,"secondary":[]}"#,
        ),
        (
            pinhole.to_string(),
            "antialias: false,",
            r#"{"primary":"rasterised","edge_rays":null,"unloaded":null,"secondary":[]}"#,
        ),
        (
            pinhole.to_string(),
            r#"light: #{ sun: #{ elevation: deg(50) }, shadows: true },"#,
            r#"{"primary":"rasterised","edge_rays":"rasterised","unloaded":null,"secondary":["shadow"]}"#,
        ),
    ];
    for (camera, extra, expected) in cases {
        let (_dir, out) = render(&box_recipe(&camera, extra), &[]);
        for view in 0..3 {
            let record = read_json(&view_path(&out, 0, view, None, "json"));
            let expected: Value = serde_json::from_str(expected).unwrap();
            assert_eq!(
                record["visibility"], expected,
                "{camera} {extra} view {view}"
            );
            // A pinhole's lens is all zeros: its rays are the pinhole's.
            let on_box = assert_depth_is_the_box_through_the_written_lens(&load(&out, view, None));
            assert!(on_box > 100, "{camera}: {on_box} pixels on the box");
        }
    }
}
