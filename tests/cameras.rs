//! Camera rigs and augmentations against independent truth, read back from written datasets:
//! back-projecting depth with the written K and pose lands on the analytic box, image-space
//! warps agree with the exact re-render and with the similarity they record, photometric
//! operations leave every label alone, a distorted render matches OpenCV's undistortion
//! (implemented here from its documentation), and stereo pairs satisfy the epipolar
//! constraint with disparity f·b/z.

mod common;

use common::{
    load, matrix, off_box, read_png, render, run, transform, undistort, view_path, write,
};

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
    let image = box_recipe(
        camera,
        &format!("augment: #{{ copies: 2, mode: \"image\", {operations} }},"),
    );
    let exact = box_recipe(camera, &format!("augment: #{{ copies: 2, {operations} }},"));
    let (_a, warped) = render(&image, &[]);
    let (_b, rendered) = render(&exact, &[]);
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
        let d = &v.json["camera"]["distortion"];
        let coefficients = ["k1", "k2", "p1", "p2", "k3"].map(|k| d[k].as_f64().unwrap());
        let k = v.k();
        let (mut agree, mut hits) = (0, 0);
        for row in 0..150 {
            for col in 0..200 {
                // Each distorted pixel's ray, undistorted by OpenCV's model, meets the box at
                // the depth written.
                let (xd, yd) = (
                    (col as f64 + 0.5 - k[0][2]) / k[0][0],
                    (row as f64 + 0.5 - k[1][2]) / k[1][1],
                );
                let (x, y) = undistort(&coefficients, xd, yd);
                let truth = box_depth(&v.c2w(), x, y);
                let z = v.depth[row * 200 + col];
                match truth {
                    Some(t) if z > 0.0 => {
                        hits += 1;
                        assert!(
                            (f64::from(z) - t).abs() < 1e-5 * t,
                            "({row},{col}) {z} vs {t}"
                        );
                        // And the pinhole render sees the same point where OpenCV's
                        // undistortion sends the pixel.
                        let (u, w) = (k[0][0] * x + k[0][2], k[1][1] * y + k[1][2]);
                        let (c, r) = (u.floor() as isize, w.floor() as isize);
                        if (1..199).contains(&c)
                            && (1..149).contains(&r)
                            && p.inside(r as usize, c as usize)
                        {
                            let there = f64::from(p.depth[r as usize * 200 + c as usize]);
                            if (there - t).abs() < 0.02 * t {
                                agree += 1;
                            }
                        }
                    }
                    None if z == 0.0 => {}
                    // Coverage may differ only along the silhouette.
                    _ => assert!(!v.inside(row, col), "({row},{col}) {z} vs {truth:?}"),
                }
            }
        }
        assert!(hits > 1000 && agree * 10 > hits * 8, "{agree}/{hits}");
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
                        if ur >= 1.0 && ur < 159.0 && r.inside(rr, c) {
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
            !output.status.success() && text.contains(expected),
            "{camera}: {text}"
        );
        assert!(!dir.path().join("out").exists());
    }
}
