//! Damage drawn and labelled per pixel, through the CLI: a placed flexural crack seen face-on
//! from a known distance lands where its 3-D line is (pixels back-projected through depth and
//! camera, minus the written displacement, lie on the line within the pixel footprint), covers
//! w/f of a pixel row (f = depth/f_x, the footprint of a fronto-parallel face), is drawn darker
//! by that coverage, and pixels off it are labelled 0; a recipe without damage writes the same
//! bytes with or without the damage layers asked for; the layers are the same on 1 and 2
//! threads; a crack no view resolves is warned about with its width and the pixel footprint.

mod common;

use common::{damage_view, hashes, read_exr, read_json, read_png, read_png16};
use common::{render, run, stderr, view_path, write};
use std::path::Path;

/// A 4 m simply supported 300 × 500 mm beam along x, centred on the origin, with a flexural
/// crack at mid-span (world x = 0) rising 0.4 m from the bottom; the camera stands on −y
/// at `DISTANCE` looking at the side face `side_neg_y` (y = −0.15 m) face-on.
const RECIPE: &str = r#"
dataset(#{
    name: "crack", seed: 1, samples: 1, views: 1,
    outputs: param("outputs", ["rgb", "depth", "mask", "displacement", "damage"]),
    camera: #{ width: WIDTH, height: HEIGHT, fov_y: deg(FOV), distance: [DISTANCE, DISTANCE],
               pitch: [0.0, 0.0], yaw: [deg(-90), deg(-90)] },
    scene: |rng| {
        beam(#{ length: 4.0, width: 0.3, height: 0.5 })
            .point_force(2.0, 1.0e3)CRACK
    },
});
"#;

/// Where the crack is: world x, the side face's y, and the crack's z range.
const CRACK_X: f64 = 0.0;
const FACE_Y: f64 = -0.15;
const CRACK_Z: (f64, f64) = (-0.25, 0.15);

struct Setup {
    size: (u32, u32),
    fov_deg: f64,
    distance: f64,
    width_mm: f64,
}

fn recipe(s: &Setup, cracked: bool) -> String {
    let crack = format!(
        ".crack(#{{ kind: \"flexural\", at: 2.0, face: \"bottom\", width_mm: {}, depth: 0.4 }})",
        s.width_mm
    );
    RECIPE
        .replace("WIDTH", &s.size.0.to_string())
        .replace("HEIGHT", &s.size.1.to_string())
        .replace("FOV", &s.fov_deg.to_string())
        .replace("DISTANCE", &format!("{:.3}", s.distance))
        .replace("CRACK", if cracked { &crack } else { "" })
}

/// The layers of view 0 of sample 0.
struct Layers {
    width: usize,
    depth: Vec<f32>,
    class: Vec<u8>,
    instance: Vec<u16>,
    crack_width: Vec<f32>,
    coverage: Vec<f32>,
    rgb: Vec<u8>,
    /// World rest point (back-projected hit minus displacement) of every pixel seen.
    rest: Vec<Option<[f64; 3]>>,
    /// Planar depth over f_x: the footprint of a face-on surface, metres per pixel.
    footprint: Vec<f64>,
}

fn layers(out: &Path) -> Layers {
    let v = damage_view(out);
    let file = |kind: &str| view_path(out, 0, 0, None, kind);
    Layers {
        width: v.width,
        footprint: v.depth.iter().map(|&z| f64::from(z) / v.k[0][0]).collect(),
        depth: v.depth,
        class: v.class,
        instance: v.instance,
        crack_width: read_exr(&file("crack_width.exr")),
        coverage: read_exr(&file("crack_coverage.exr")),
        rgb: v.rgb,
        rest: v.rest,
    }
}

/// A face-on crack at a distance, with its expected width over footprint.
fn check_crack(s: &Setup) {
    let (_dir, out) = render(&recipe(s, true), &[]);
    let l = layers(&out);
    let w = s.width_mm * 1e-3;
    let mut rows_checked = 0;
    for (row, pixels) in l.class.chunks(l.width).enumerate() {
        let idx = |col: usize| row * l.width + col;
        let on_face: Vec<usize> = (0..l.width)
            .filter(|&c| l.rest[idx(c)].is_some_and(|p| (p[1] - FACE_Y).abs() < 1e-3))
            .collect();
        for &col in &on_face {
            let i = idx(col);
            let p = l.rest[i].unwrap();
            let f = l.footprint[i];
            // Half a pixel diagonal plus half the crack, and the beam's sub-millimetre sag.
            let near = (p[0] - CRACK_X).abs() <= 0.75 * f + 0.5 * w + 1e-3
                && p[2] >= CRACK_Z.0 - f
                && p[2] <= CRACK_Z.1 + f;
            if pixels[col] == 1 {
                assert!(
                    near,
                    "row {row} col {col}: crack pixel at {p:?}, footprint {f}"
                );
                assert_eq!(l.instance[i], 1);
                assert!((f64::from(l.crack_width[i]) - s.width_mm).abs() < 1e-6);
            } else {
                assert_eq!(pixels[col], 0, "row {row} col {col}");
                assert_eq!((l.instance[i], l.coverage[i]), (0, 0.0));
            }
        }
        // Rows well inside the crack's height: the coverage along the row sums to w/f.
        let inside = on_face.iter().any(|&c| {
            let p = l.rest[idx(c)].unwrap();
            p[2] > CRACK_Z.0 + 2.0 * l.footprint[idx(c)]
                && p[2] < CRACK_Z.1 - 2.0 * l.footprint[idx(c)]
        });
        if !inside {
            continue;
        }
        let crack: Vec<usize> = on_face
            .iter()
            .map(|&c| idx(c))
            .filter(|&i| l.class[i] == 1)
            .collect();
        assert!(!crack.is_empty(), "row {row}: no crack pixel");
        let sum: f64 = crack.iter().map(|&i| f64::from(l.coverage[i])).sum();
        let expected = w / l.footprint[crack[0]];
        assert!(
            (sum / expected - 1.0).abs() < 0.01,
            "row {row}: coverage {sum} vs w/f = {expected}"
        );
        rows_checked += 1;
    }
    assert!(rows_checked > 5, "{rows_checked}");
    // The record names the class and the instance points at the damage item of that type.
    let json = read_json(&view_path(&out, 0, 0, None, "json"));
    let item = &json["scene"]["structures"][0]["damage"]["items"][0];
    assert_eq!(json["damage"]["classes"][1], item["type"]);
    assert_eq!(item["type"], "flexural_crack");
    // Drawn: the most covered pixel is darker than the sound beam's same pixel by about its
    // coverage (blended towards a near-black gap, in linear light).
    let (_dir2, sound_out) = render(&recipe(s, false), &[]);
    let sound = layers(&sound_out);
    let darkest = (0..l.coverage.len())
        .max_by(|&a, &b| l.coverage[a].total_cmp(&l.coverage[b]))
        .unwrap();
    let lin = |b: u8| {
        let c = f64::from(b) / 255.0;
        match c <= 0.04045 {
            true => c / 12.92,
            false => ((c + 0.055) / 1.055).powf(2.4),
        }
    };
    let (cracked, clean) = (lin(l.rgb[3 * darkest + 1]), lin(sound.rgb[3 * darkest + 1]));
    let c = f64::from(l.coverage[darkest]);
    assert!(
        cracked < clean * (1.0 - 0.8 * c) + 0.01,
        "coverage {c}: {cracked} vs {clean}"
    );
    assert_eq!(l.depth, sound.depth, "the crack is drawn, not modelled");
}

#[test]
fn a_hairline_crack_at_inspection_distance_covers_w_over_f_of_a_pixel() {
    // 0.3 mm at about 2 cm/pixel: fy = 60 / tan 15° = 224 px, depth 4.35 m.
    check_crack(&Setup {
        size: (160, 120),
        fov_deg: 30.0,
        distance: 4.5,
        width_mm: 0.3,
    });
}

#[test]
fn a_wide_crack_close_up_is_a_band_of_fully_covered_pixels() {
    // 2 mm at about 1 mm/pixel: fy = 100 / tan 5° = 1143 px, depth 1.15 m.
    let s = Setup {
        size: (200, 200),
        fov_deg: 10.0,
        distance: 1.3,
        width_mm: 2.0,
    };
    check_crack(&s);
    let (_dir, out) = render(&recipe(&s, true), &[]);
    let full = read_exr(&view_path(&out, 0, 0, None, "crack_coverage.exr"))
        .iter()
        .filter(|&&c| c > 0.99)
        .count();
    // The line falls on a pixel edge here: two pixels a row, each 0.994 covered.
    assert!(full > 100, "{full} fully covered pixels");
}

#[test]
fn without_damage_the_damage_layers_are_empty_and_the_other_files_unchanged() {
    let s = Setup {
        size: (64, 48),
        fov_deg: 30.0,
        distance: 4.5,
        width_mm: 0.3,
    };
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "recipe.rhai", recipe(&s, false));
    let with = dir.path().join("with");
    common::ok(run(&path, &with, &[]));
    let without = dir.path().join("without");
    let outputs = "outputs=rgb,depth,mask,displacement";
    common::ok(run(&path, &without, &["--set", outputs]));
    let (a, b) = (hashes(&with), hashes(&without));
    for (file, hash) in &b {
        if file.ends_with(".png") || file.ends_with(".exr") {
            assert_eq!(a.get(file), Some(hash), "{file}");
        }
    }
    let file = |kind: &str| view_path(&with, 0, 0, None, kind);
    assert!(
        read_png(&file("damage_class.png"))
            .3
            .iter()
            .all(|&c| c == 0)
    );
    assert!(
        read_png16(&file("damage_instance.png"))
            .2
            .iter()
            .all(|&c| c == 0)
    );
    assert!(read_exr(&file("crack_width.exr")).iter().all(|&c| c == 0.0));
    assert!(
        read_exr(&file("crack_coverage.exr"))
            .iter()
            .all(|&c| c == 0.0)
    );
}

/// A cracked, corroded, spalled reinforced-concrete beam from several views.
const BUSY: &str = r#"
dataset(#{
    name: "busy", seed: 5, samples: 2, views: 3, outputs: ["rgb", "damage"],
    camera: #{ width: 64, height: 48, fov_y: deg(60), distance: [3.0, 5.0] },
    scene: |rng| {
        beam(#{ length: 6.0, width: 0.3, height: 0.5 })
            .reinforced_concrete().theory("euler_bernoulli")
            .point_force(3.0, 9.0e4)
            .map_cracking(#{ from: 0.5, to: 1.5, face: "side_neg_y" })
            .corrosion(#{ from: 4.5, to: 6.0, faces: ["top", "side_neg_y"], section_loss: 0.0, stain_length: 0.3 })
            .spall(#{ at: 2.0, face: "side_neg_y", length: 0.3, breadth: 0.2, depth: 0.03 })
    },
});
"#;

#[test]
fn damage_layers_are_the_same_on_one_and_two_threads() {
    let (_a, one) = render(BUSY, &["--threads", "1"]);
    let (_b, two) = render(BUSY, &["--threads", "2"]);
    let (h1, h2) = (hashes(&one), hashes(&two));
    assert_eq!(h1, h2);
    // Every class the recipe places shows up somewhere.
    let mut seen = std::collections::BTreeSet::new();
    for sample in 0..2 {
        for view in 0..3 {
            let (_, _, _, class) =
                read_png(&view_path(&one, sample, view, None, "damage_class.png"));
            seen.extend(class);
        }
    }
    assert!(
        [0u8, 1, 3, 4, 5].iter().all(|c| seen.contains(c)),
        "{seen:?}"
    );
    // The webdataset export reads the damage EXRs by the record's channel.
    let exported = tempfile::tempdir().unwrap();
    let to = exported.path().join("wds");
    let output = common::shmgen(&[
        "export".as_ref(),
        one.as_os_str(),
        "--format".as_ref(),
        "webdataset".as_ref(),
        "--out".as_ref(),
        to.as_os_str(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
}

#[test]
fn a_crack_no_view_resolves_is_warned_about_with_its_width_and_pixel_size() {
    let far = Setup {
        size: (64, 48),
        fov_deg: 60.0,
        distance: 14.0,
        width_mm: 0.3,
    };
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "far.rhai", recipe(&far, true));
    let output = run(&path, &dir.path().join("far"), &[]);
    let text = stderr(&output);
    assert!(output.status.success(), "{text}");
    // fy = 24 / tan 30° = 41.57 px; the check takes the crack at the beam's mid-plane, 14 m
    // away: 336.8 mm a pixel, so 0.3 mm covers 0.0009.
    assert!(
        text.contains("warning: sample 0: 1 crack no view resolves")
            && text.contains(
                "structures[0].damage.items[0] (0.30 mm wide; smallest pixel footprint 336.8 mm"
            )
            && text.contains("camera.distance"),
        "{text}"
    );
    let near = Setup {
        distance: 1.0,
        width_mm: 2.0,
        ..far
    };
    let path = write(dir.path(), "near.rhai", recipe(&near, true));
    let output = run(&path, &dir.path().join("near"), &[]);
    assert!(!stderr(&output).contains("warning"), "{}", stderr(&output));
}

/// A 4 m steel I-girder (300 × 500 mm, 30 mm flanges, 15 mm web) along x, centred on the
/// origin, seen from −y and 25° above, its bottom corroded along the whole span (or sound).
fn girder_recipe(corroded: bool) -> String {
    let corrosion = r#".corrosion(#{ from: 0.0, to: 4.0, faces: ["bottom"], section_loss: 0.05, stain_length: 0.1 })"#;
    format!(
        r#"
dataset(#{{
    name: "girder", seed: 3, samples: 1, views: 1,
    outputs: ["rgb", "depth", "mask", "displacement", "damage"],
    camera: #{{ width: 320, height: 240, fov_y: deg(40), distance: [1.5, 1.5],
               pitch: [deg(25), deg(25)], yaw: [deg(-90), deg(-90)] }},
    scene: |rng| {{
        beam(#{{ length: 4.0, section: i_section(0.3, 0.5, 0.03, 0.015) }})
            .point_force(2.0, 1.0e3){}
            .material("A photo of a painted steel beam")
    }},
}});
"#,
        if corroded { corrosion } else { "" }
    )
}

#[test]
fn a_corroded_bottom_flange_is_rusty_on_top_and_at_its_junction_with_the_web() {
    let (_a, out) = render(&girder_recipe(true), &[]);
    let (_b, sound_out) = render(&girder_recipe(false), &[]);
    let (v, sound) = (damage_view(&out), damage_view(&sound_out));
    // The bottom flange (z from −0.25 to −0.22) and one flange thickness of web above it.
    let reach = -0.25 + 2.0 * 0.03;
    let (mut band, mut above) = (Vec::new(), Vec::new());
    for (i, rest) in v.rest.iter().enumerate() {
        let Some(p) = rest else { continue };
        if p[0].abs() > 1.5 {
            continue;
        }
        if p[2] < reach - 2e-3 {
            band.push(i);
        } else if p[2] > reach + 2e-3 {
            above.push(i);
        }
    }
    // The camera looks down on the flange: its top surface and edge are in view.
    assert!(band.len() > 500, "{} flange pixels", band.len());
    let rusty = band.iter().filter(|&&i| v.class[i] == 4).count();
    assert!(
        rusty as f64 > 0.98 * band.len() as f64,
        "{rusty} of {} flange pixels labelled corrosion",
        band.len()
    );
    assert!(above.iter().all(|&i| v.class[i] == 0));
    // Drawn so: browner and darker than the sound girder's same pixels.
    let mean = |rgb: &[u8], channel: usize| {
        band.iter()
            .map(|&i| f64::from(rgb[3 * i + channel]))
            .sum::<f64>()
            / band.len() as f64
    };
    let (r, b) = (mean(&v.rgb, 0), mean(&v.rgb, 2));
    let (r0, b0) = (mean(&sound.rgb, 0), mean(&sound.rgb, 2));
    assert!(
        r / b > 1.3 * (r0 / b0),
        "red/blue {r}/{b} against sound {r0}/{b0}"
    );
    assert!(
        r + b < 0.8 * (r0 + b0),
        "{r} + {b} against sound {r0} + {b0}"
    );
}
