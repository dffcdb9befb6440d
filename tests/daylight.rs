//! Daylight and the camera, run through the binary: the sky's floor under a sun, occlusion
//! where a block stands on a plate, exposure and the filmic curve, the sensor's effects on the
//! clean image, depth of field, and the errors bad options give.

mod common;

use common::{
    encoded, hashes, inside, load, read_exr, read_json, render, rgb, run, stderr, view_path, write,
};
use std::path::Path;

/// sRGB 0–1 → linear.
fn linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

const SKY: [f64; 3] = [0.75, 0.83, 0.95];
const GROUND: [f64; 3] = [0.4, 0.36, 0.3];

/// A grey box floating alone under a sun and the default sky, seen from all round (below too).
fn floating_box(light_extra: &str) -> String {
    format!(
        r#"dataset(#{{
    seed: 4, samples: 1, views: 6,
    outputs: ["rgb", "depth", "mask"],
    camera: #{{ width: 160, height: 120, pitch: [deg(-80), deg(80)], distance: 6.0 }},
    light: #{{ sun: #{{ elevation: deg(50), azimuth: deg(30), intensity: 1.0 }},
               sky: #{{ intensity: 0.3 }}, ambient: 0.02 {light_extra} }},
    scene: |rng| [ assembly("box", [shape::box(1.2, 0.8, 0.6)]).colour([0.6, 0.6, 0.6]) ],
}});
"#
    )
}

/// The issue's guard: on a sunlit scene no structure pixel is darker than the ambient floor
/// unless something occludes it. A lone box hides nothing from itself (it is convex), so with
/// sky occlusion on every face gets at least the ambient light plus the hemispherical sky of
/// its worst facing, min(sky, ground) per channel (straight up or straight down).
#[test]
fn a_lone_box_under_a_sun_is_nowhere_darker_than_the_sky_floor() {
    let (_dir, out) = render(&floating_box(""), &[]);
    let albedo = linear(0.6);
    let floor: Vec<f64> = (0..3)
        .map(|k| {
            let sky = 0.3 * linear(SKY[k]).min(linear(GROUND[k]));
            encoded(albedo * (0.02 + sky)) - 1.0
        })
        .collect();
    let mut darkest = [255u8; 3];
    for view in 0..6 {
        let v = load(&out, view, None);
        let pixels = rgb(&out, view);
        let inside = inside(&v.mask, v.width, 255);
        assert!(inside.len() > 200, "view {view} sees the box");
        for i in inside {
            for k in 0..3 {
                darkest[k] = darkest[k].min(pixels[i][k]);
            }
        }
    }
    for k in 0..3 {
        assert!(
            f64::from(darkest[k]) >= floor[k],
            "channel {k}: darkest {} below the sky floor {:.1}",
            darkest[k],
            floor[k]
        );
    }
    // And even the underside, lit by the dark ground alone, is well above the 0.02 ambient.
    let ambient_only = encoded(albedo * 0.02);
    assert!(
        darkest.iter().all(|&c| f64::from(c) > 1.5 * ambient_only),
        "{darkest:?} vs {ambient_only:.1}"
    );
}

/// A block standing on a plate under the sky alone: with occlusion, the plate darkens towards
/// the block's foot (the block hides part of its sky); without, it is lit evenly.
#[test]
fn sky_occlusion_darkens_the_plate_at_the_foot_of_a_block() {
    let recipe = |rays: u32| {
        format!(
            r#"dataset(#{{
    seed: 1, samples: 1, views: 1,
    outputs: ["rgb", "depth", "mask"],
    camera: #{{ fixed: [#{{ position: [0.0, -0.01, 9.0], target: [0.0, 0.0, 0.0] }}], width: 200, height: 200, fov_y: deg(50) }},
    light: #{{ sky: #{{ intensity: 1.0, occlusion_rays: {rays} }}, ambient: 0.0 }},
    scene: |rng| [
        assembly("plate", [shape::box(6.0, 6.0, 0.1).translate(0.0, 0.0, -0.05)]).colour([0.5, 0.5, 0.5]),
        assembly("block", [shape::box(1.0, 1.0, 1.5).translate(0.0, 0.0, 0.75)]).colour([0.5, 0.5, 0.5]),
    ],
}});
"#
        )
    };
    let mut ratios = Vec::new();
    for rays in [0, 64] {
        let (_dir, out) = render(&recipe(rays), &[]);
        let v = load(&out, 0, None);
        let pixels = rgb(&out, 0);
        // Plate pixels (depth ≈ 9 m) by distance from the block's side along image x.
        let luma_at = |lo: f64, hi: f64| -> f64 {
            let (mut sum, mut n) = (0.0, 0.0);
            for (i, &d) in v.depth.iter().enumerate() {
                let (row, col) = ((i / v.width) as f64, (i % v.width) as f64);
                let metres_per_px = 2.0 * 9.0 * (25f64.to_radians()).tan() / 200.0;
                let (x, y) = (
                    (col + 0.5 - 100.0) * metres_per_px,
                    (row + 0.5 - 100.0) * metres_per_px,
                );
                let gap = x.abs() - 0.5;
                if (f64::from(d) - 9.0).abs() < 0.02 && y.abs() < 0.3 && (lo..hi).contains(&gap) {
                    sum += f64::from(pixels[i][1]);
                    n += 1.0;
                }
            }
            assert!(n > 5.0, "plate pixels at gap {lo}–{hi} m");
            sum / n
        };
        // From straight above, the block's top hides the plate within 0.1 m of its foot.
        ratios.push(luma_at(0.1, 0.2) / luma_at(2.0, 2.4));
    }
    assert!(
        (ratios[0] - 1.0).abs() < 0.01,
        "no occlusion: even, {ratios:?}"
    );
    assert!(ratios[1] < 0.85, "occluded at the foot: {ratios:?}");
}

/// Exposure +2 stops over-exposes the sunlit faces: clipping flattens them to white, the
/// filmic curve keeps them below white and keeps their order. Exposure 0 with the clip curve
/// is the default, byte for byte.
#[test]
fn the_filmic_curve_keeps_highlights_that_clipping_loses() {
    // White structure pixels over every view, and the first view's pixels.
    let saturated = |extra: &str| -> (usize, Vec<[u8; 3]>) {
        let (_dir, out) = render(&floating_box(extra), &[]);
        let mut white = 0;
        for view in 0..6 {
            let pixels = rgb(&out, view);
            let v = load(&out, view, None);
            let inside = inside(&v.mask, v.width, 255);
            white += inside
                .iter()
                .filter(|&&i| pixels[i].iter().all(|&c| c == 255))
                .count();
        }
        (white, rgb(&out, 0))
    };
    let (clipped, _) = saturated(", exposure: 2.0");
    let (filmic, _) = saturated(", exposure: 2.0, tone: \"filmic\"");
    assert!(clipped > 100, "over-exposed faces clip: {clipped}");
    assert_eq!(filmic, 0, "the filmic curve stays below white");
    let (_, plain) = saturated("");
    let (_, explicit) = saturated(", exposure: 0.0, tone: \"clip\"");
    assert!(plain == explicit, "the defaults change nothing");
}

/// The sensor's vignetting darkens the corners of the clean image, is recorded in the view's
/// record, and the sensor's noise is the same on any thread count.
#[test]
fn sensor_effects_apply_to_the_clean_image_and_are_recorded() {
    let recipe = |sensor: &str| {
        format!(
            r#"dataset(#{{
    seed: 3, samples: 1, views: 2,
    outputs: ["rgb", "depth", "mask"],
    camera: #{{ width: 96, height: 64 }},
    background: [0.5, 0.5, 0.5],
    {sensor}
    scene: |rng| [ assembly("box", [shape::box(1.0, 1.0, 1.0)]) ],
}});
"#
        )
    };
    let (_d0, plain) = render(&recipe(""), &[]);
    let (_d1, vignetted) = render(
        &recipe(r#"sensor: [ #{ op: "vignette", strength: 0.5, probability: 1.0 } ],"#),
        &[],
    );
    assert!(
        read_json(&view_path(&plain, 0, 0, None, "json"))
            .get("sensor")
            .is_none()
    );
    let record = read_json(&view_path(&vignetted, 0, 0, None, "json"));
    assert_eq!(
        record["sensor"][0]["op"], "vignette",
        "{}",
        record["sensor"]
    );
    let (a, b) = (rgb(&plain, 0), rgb(&vignetted, 0));
    assert!(
        b[0][0] < a[0][0] - 20,
        "corner darker: {:?} → {:?}",
        a[0],
        b[0]
    );
    let centre = 32 * 96 + 48;
    assert!(a[centre][1].abs_diff(b[centre][1]) <= 2, "centre kept");
    // Depth and masks are the same bytes with and without the sensor.
    for kind in ["depth.exr", "mask.png"] {
        let read = |out: &Path| std::fs::read(view_path(out, 0, 1, None, kind)).unwrap();
        assert!(read(&plain) == read(&vignetted), "{kind}");
    }
    let noisy = recipe(
        r#"sensor: [ #{ op: "noise", model: "gaussian", sigma: [2.0, 6.0], probability: 1.0 } ],"#,
    );
    let (_d2, one) = render(&noisy, &["--threads", "1"]);
    let (_d3, two) = render(&noisy, &["--threads", "2"]);
    let (h1, h2) = (hashes(&one), hashes(&two));
    for (name, hash) in &h1 {
        if name.ends_with(".png") {
            assert_eq!(Some(hash), h2.get(name), "{name}");
        }
    }
}

/// Focused on the box, its faces stay sharp; focused far behind it at f/1.4, its silhouette
/// spreads over several pixels. Depth is the pinhole's either way.
#[test]
fn depth_of_field_blurs_what_lies_off_the_focus_distance() {
    let recipe = |lens: &str| {
        format!(
            r#"dataset(#{{
    seed: 5, samples: 1, views: 1,
    outputs: ["rgb", "depth", "mask"],
    camera: #{{ fixed: [#{{ position: [0.0, -4.0, 0.0], target: [0.0, 0.0, 0.0] }}], width: 120, height: 120, fov_y: deg(40) {lens} }},
    background: [0.9, 0.9, 0.9],
    scene: |rng| [ assembly("box", [shape::box(1.0, 0.2, 1.0)]).colour([0.1, 0.1, 0.1]) ],
}});
"#
        )
    };
    // Grey levels strictly between the box's and the backdrop's: the width of the edge.
    let between = |out: &Path| -> usize {
        let pixels = rgb(out, 0);
        let (dark, light) = (pixels[60 * 120 + 60][1], pixels[5 * 120 + 5][1]);
        pixels
            .iter()
            .filter(|p| p[1] > dark + 8 && p[1] < light - 8)
            .count()
    };
    let (_d0, pinhole) = render(&recipe(""), &[]);
    let (_d1, focused) = render(
        &recipe(", depth_of_field: #{ f_number: 1.4, focus_distance: 3.9, sensor_width: 0.2 }"),
        &[],
    );
    let (_d2, far) = render(
        &recipe(", depth_of_field: #{ f_number: 1.4, focus_distance: 40.0, sensor_width: 0.2 }"),
        &[],
    );
    let (sharp, near_focus, blurred) = (between(&pinhole), between(&focused), between(&far));
    // f_x = 60 / tan 20° = 165 px, f = 0.2 m · 165 / 120 = 0.27 m, A = f/1.4; at 3.9 m with the
    // focus at 40 m the circle is A f_x |d − s| / (d (s − f)) ≈ 7.5 px across: the box's
    // 42 px square silhouette spreads over a band about 3 px wide, some 500 pixels.
    assert!(near_focus <= sharp + 8, "in focus: {near_focus} vs {sharp}");
    assert!(blurred > sharp + 250, "out of focus: {blurred} vs {sharp}");
    let depth = |out: &Path| read_exr(&view_path(out, 0, 0, None, "depth.exr"));
    assert!(depth(&pinhole) == depth(&far), "depth stays the pinhole's");
}

#[test]
fn bad_light_and_lens_options_are_named_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            r#"light: #{ sun: #{ diameter: 1.0 } },"#,
            "dataset.light.sun.diameter",
        ),
        (r#"light: #{ tone: "filmc" },"#, "did you mean \"filmic\""),
        (
            r#"light: #{ sky: #{ occlusion_rays: 1000 } },"#,
            "dataset.light.sky.occlusion_rays",
        ),
        (
            r#"camera: #{ depth_of_field: #{ focus_distance: 0.01 } },"#,
            "focus_distance",
        ),
        (
            r#"sensor: [ #{ op: "warp", zoom: 1.0, rotation: 0.0, shift_x: 0.0, shift_y: 0.0, probability: 1.0 } ],"#,
            "dataset.sensor[0] (warp)",
        ),
    ];
    for (i, (option, expected)) in cases.iter().enumerate() {
        let recipe = write(
            dir.path(),
            &format!("bad{i}.rhai"),
            format!(
                "dataset(#{{\n    samples: 1, views: 1,\n    {option}\n    scene: |rng| [ assembly(\"b\", [shape::box(1.0, 1.0, 1.0)]) ],\n}});\n"
            ),
        );
        let output = run(&recipe, &dir.path().join(format!("out{i}")), &[]);
        let text = stderr(&output);
        assert!(!output.status.success(), "{option} must fail");
        assert!(
            text.contains(expected),
            "{option}: expected `{expected}` in\n{text}"
        );
        assert!(
            text.contains(&format!("bad{i}.rhai:")),
            "names the file: {text}"
        );
    }
}
