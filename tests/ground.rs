//! The ground and drawn supports, checked through the written files against truth of their
//! own: the plane z = height every ground pixel must back-project onto, the structures resting
//! on it within a pixel, the structures' layers unchanged by a ground they do not see, and the
//! bytes unchanged by the thread count.

mod common;
use common::*;
use std::path::Path;

/// A dataset of one sample: a bent beam on drawn supports, or the stdlib water silo on its
/// legs, in the sun over `ground` (a recipe value, or "" for none).
fn recipe(dir: &Path, structure: &str, ground: &str, outputs: &str) -> std::path::PathBuf {
    let scene = match structure {
        "beam" => beam_at(0.0),
        _ => "silo::water_silo(#{})".to_string(),
    };
    let ground = if ground.is_empty() {
        String::new()
    } else {
        format!("ground: {ground},")
    };
    write(
        dir,
        "ground.rhai",
        format!(
            r#"import "beam" as beam;
import "silo" as silo;
dataset(#{{
    name: "ground", seed: 7, samples: 1, views: 4,
    outputs: [{outputs}],
    camera: #{{ width: 240, height: 200, pitch: [deg(8), deg(40)], distance: "frame" }},
    light: #{{ sun: #{{ elevation: deg(35) }}, sky: #{{}} }},
    background: "sky",
    {ground}
    scene: |rng| {scene},
}});
"#
        ),
    )
}

/// The bent beam on drawn supports, its centre raised to height `z` (metres).
fn beam_at(z: f64) -> String {
    format!(
        "beam::simply_supported(4.0, 0.2, 0.4, 1.2, 0.1).material(\"rusty steel\").supports_drawn(true).at(0.0, 0.0, {z:?})"
    )
}

/// Index of `name` in the view's `segmentation.part_ids`.
fn part_id(view: &View, name: &str) -> u8 {
    let ids = view.json["segmentation"]["part_ids"].as_array().unwrap();
    ids.iter().position(|p| p == name).unwrap() as u8
}

/// Every ground pixel back-projects onto the plane z = height; no structure point lies below
/// it; the lowest structure point seen lies on it within one pixel's footprint there (the
/// footings touch: a gap would leave them a pixel or more above); the ground is labelled in
/// the part and instance images and never in the mask.
#[test]
fn structures_stand_on_the_ground_within_a_pixel() {
    for structure in ["beam", "silo"] {
        let dir = tempfile::tempdir().unwrap();
        let outputs = r#""rgb", "depth", "mask", "parts", "instances""#;
        let path = recipe(
            dir.path(),
            structure,
            r#"#{ material: "gravel", in_depth: true }"#,
            outputs,
        );
        let out = dir.path().join("out");
        ok(run(&path, &out, &[]));
        for v in 0..4 {
            let view = load(&out, v, None);
            let ground = &view.json["ground"];
            let height = ground["height"].as_f64().unwrap();
            assert_eq!(ground["in_depth"], true);
            let ground_part = part_id(&view, "ground");
            assert_eq!(ground["part_id"].as_u64().unwrap(), u64::from(ground_part));
            let instance = ground["instance_id"].as_u64().unwrap() as u8;
            assert_eq!(
                view.json["segmentation"]["instance_ids"][instance as usize]["kind"],
                "ground"
            );
            let (_, _, _, parts) = read_png(&view_path(&out, 0, v, None, "parts.png"));
            let (_, _, _, instances) = read_png(&view_path(&out, 0, v, None, "instances.png"));
            let f = view.k()[1][1];
            let (mut ground_pixels, mut lowest) = (0, (f64::INFINITY, 0.0));
            for row in 0..view.height {
                for col in 0..view.width {
                    let i = row * view.width + col;
                    let Some(p) = view.point(row, col) else {
                        continue;
                    };
                    let footprint = f64::from(view.depth[i]) / f;
                    if parts[i] == ground_part {
                        ground_pixels += 1;
                        assert_eq!(instances[i], instance);
                        assert_eq!(view.mask[i], 0, "the mask is the structure's alone");
                        let tolerance = 1e-5 * f64::from(view.depth[i]) + 1e-6;
                        assert!(
                            (p[2] - height).abs() < tolerance,
                            "{structure} view {v}: ground pixel at z = {} against {height}",
                            p[2]
                        );
                    } else {
                        assert_eq!(view.mask[i], 255);
                        assert!(
                            p[2] > height - 1e-6,
                            "{structure}: a structure point below the ground"
                        );
                        if p[2] < lowest.0 {
                            lowest = (p[2], footprint);
                        }
                    }
                }
            }
            assert!(
                ground_pixels > view.width * view.height / 10,
                "{structure} view {v}: {ground_pixels}"
            );
            let (z, footprint) = lowest;
            assert!(
                z - height <= footprint,
                "{structure} view {v}: the lowest point seen is {} m above the ground, a pixel is {footprint} m",
                z - height
            );
        }
    }
}

/// Without `in_depth` the structures' geometric layers and mask are byte for byte those of a
/// run without a ground (the ground lies below everything and hides nothing), while the RGB
/// image shows the ground.
#[test]
fn a_ground_outside_depth_leaves_every_structure_layer_unchanged() {
    let outputs = r#""rgb", "depth", "mask", "normals", "ray_distance", "displacement", "rest_depth", "flow", "mesh", "points""#;
    let dir = tempfile::tempdir().unwrap();
    let bare = recipe(&dir.path().join("bare"), "beam", "", outputs);
    let grass = recipe(&dir.path().join("grass"), "beam", r#""grass""#, outputs);
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    ok(run(&bare, &a, &[]));
    ok(run(&grass, &b, &[]));
    let (ha, hb) = (hashes(&a), hashes(&b));
    let compared = assert_structure_layers_equal(&ha, &hb, "a ground at the structures' feet");
    assert!(compared >= 4 * 8 + 3, "{compared}");
    for v in 0..4 {
        assert_ne!(
            ha[&format!("samples/0000/000000_{v:02}.rgb.png")],
            hb[&format!("samples/0000/000000_{v:02}.rgb.png")]
        );
        let view = load(&b, v, None);
        assert_eq!(view.json["ground"]["in_depth"], false);
        assert_eq!(view.json["ground"]["material"]["prompt"], "grass");
    }
}

/// Asserts that every file of the samples but the views' JSON and RGB images (which show
/// the ground) has the same bytes in the runs hashed as `bare` and `grounded`; how many.
fn assert_structure_layers_equal(
    bare: &std::collections::BTreeMap<String, String>,
    grounded: &std::collections::BTreeMap<String, String>,
    case: &str,
) -> usize {
    let mut compared = 0;
    for (file, hash) in bare {
        if file.ends_with(".json") || file.ends_with("rgb.png") || !file.starts_with("samples/") {
            continue;
        }
        assert_eq!(Some(hash), grounded.get(file), "{case}: {file} differs");
        compared += 1;
    }
    compared
}

/// The structures' layers are independent of where a ground they do not see lies: byte for
/// byte a run without it with the ground at the coordinate limit (−10⁷ m) and just inside it
/// 10⁷ m below the beam, and with the beam raised to the top of the range over a ground just
/// below it. (A ground 10⁷ m below once quantised the beam to half-metre steps: the tracer
/// stored every vertex in f32 about the centre of the bounds, ground included.)
#[test]
fn a_ground_anywhere_within_the_limit_leaves_every_structure_layer_unchanged() {
    let outputs = r#""rgb", "depth", "mask", "normals", "ray_distance", "displacement", "rest_depth", "flow""#;
    let limit = 1e7;
    for (beam_z, ground) in [
        (0.0, -limit),
        (0.0, -(limit - 1.0)),
        (limit - 10.0, limit - 12.0),
        (-(limit - 30.0), -limit),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let raise = |path: std::path::PathBuf| {
            let text = std::fs::read_to_string(&path).unwrap();
            std::fs::write(&path, text.replace(&beam_at(0.0), &beam_at(beam_z))).unwrap();
            path
        };
        let ground_value = format!(r#"#{{ material: "grass", height: {ground:?} }}"#);
        let bare = raise(recipe(&dir.path().join("bare"), "beam", "", outputs));
        let grounded = raise(recipe(
            &dir.path().join("g"),
            "beam",
            &ground_value,
            outputs,
        ));
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        ok(run(&bare, &a, &[]));
        ok(run(&grounded, &b, &[]));
        let case = format!("beam at z = {beam_z}, ground at {ground}");
        let compared = assert_structure_layers_equal(&hashes(&a), &hashes(&b), &case);
        assert_eq!(compared, 4 * 8, "{case}");
        let view = load(&b, 0, None);
        assert_eq!(
            view.json["ground"]["height"].as_f64(),
            Some(ground),
            "{case}"
        );
        assert!(view.mask.contains(&255), "{case}: the beam is seen");
    }
}

/// A ground however far below is a ground out to the horizon, at its height: seen in depth
/// from cameras just above the horizon, with the ground at the coordinate limit 10⁷ m below,
/// every pixel that sees no structure and whose centre ray dips more than two pixels below
/// the horizon sees the ground, each back-projecting onto z = height (to the depth's f32
/// precision), and no ray that rises sees it. (A square of 2000 scene radii showed there as
/// a speck straight below, the backdrop everywhere else.)
#[test]
fn a_ground_far_below_reaches_the_horizon_at_its_height() {
    let dir = tempfile::tempdir().unwrap();
    let height = -1e7;
    let path = recipe(
        dir.path(),
        "beam",
        &format!(r#"#{{ material: "soil", in_depth: true, height: {height:?} }}"#),
        r#""depth", "mask", "parts""#,
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let low = text.replace("pitch: [deg(8), deg(40)]", "pitch: [deg(2), deg(8)]");
    std::fs::write(&path, low).unwrap();
    let out = dir.path().join("out");
    ok(run(&path, &out, &[]));
    for v in 0..4 {
        let view = load(&out, v, None);
        let ground_part = part_id(&view, "ground");
        let (_, _, _, parts) = read_png(&view_path(&out, 0, v, None, "parts.png"));
        let (k, c2w) = (view.k(), view.c2w());
        let camera_z = c2w[2][3];
        let pixel_angle = 1.0 / k[1][1];
        let (mut ground_pixels, mut sky_pixels) = (0, 0);
        for row in 0..view.height {
            for col in 0..view.width {
                let i = row * view.width + col;
                if view.mask[i] == 255 {
                    continue;
                }
                let (x, y) = view.ray(row, col);
                let d: [f64; 3] =
                    std::array::from_fn(|a| c2w[a][0] * x + c2w[a][1] * y + c2w[a][2]);
                let dip = -(d[2] / d.iter().map(|c| c * c).sum::<f64>().sqrt()).asin();
                if parts[i] == ground_part {
                    ground_pixels += 1;
                    assert!(
                        dip > 0.0,
                        "view {v} ({row}, {col}): ground above the horizon"
                    );
                    let z = view.point(row, col).unwrap()[2];
                    let tolerance = 1e-6 * (camera_z - height);
                    assert!(
                        (z - height).abs() < tolerance,
                        "view {v} ({row}, {col}): ground at z = {z}, declared {height}"
                    );
                } else {
                    sky_pixels += 1;
                    assert!(
                        dip < 2.0 * pixel_angle,
                        "view {v} ({row}, {col}): {dip} rad below the horizon, no ground"
                    );
                }
            }
        }
        assert!(
            ground_pixels > 0 && sky_pixels > 0,
            "view {v}: the horizon is in view"
        );
    }
}

/// A ground's height beyond the coordinate limit is refused on either side, naming the option
/// and its value at the recipe's line, as is a light's ground plane there.
#[test]
fn a_ground_beyond_the_limit_is_refused_on_either_side() {
    let dir = tempfile::tempdir().unwrap();
    let path = recipe(dir.path(), "beam", r#""grass""#, r#""rgb""#);
    let text = std::fs::read_to_string(&path).unwrap();
    for (height, shown) in [(-1.0000001e7, "-10000001"), (1.0000001e7, "10000001")] {
        for (from, to, option) in [
            (
                r#"ground: "grass""#,
                format!(r#"ground: #{{ material: "grass", height: {height:?} }}"#),
                "dataset.ground.height",
            ),
            (
                "sky: #{} }",
                format!("sky: #{{}}, ground: #{{ height: {height:?} }} }}"),
                "dataset.light.ground.height",
            ),
        ] {
            let bad = write(dir.path(), "far.rhai", text.replace(from, &to));
            let output = run(&bad, &dir.path().join("out"), &[]);
            assert!(!output.status.success(), "{option} = {height} accepted");
            let err = stderr(&output);
            assert!(
                err.contains(&format!("{option} = {shown} m lies beyond ±1e7 m"))
                    && err.contains("far.rhai:"),
                "{err}"
            );
        }
    }
}

/// The same bytes on one thread and on two, with a ground seen in depth.
#[test]
fn a_ground_renders_the_same_on_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let outputs = r#""rgb", "depth", "mask", "parts", "instances", "normals""#;
    let path = recipe(
        dir.path(),
        "beam",
        r#"#{ material: "asphalt", in_depth: true }"#,
        outputs,
    );
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    ok(run(&path, &one, &["--threads", "1"]));
    ok(run(&path, &two, &["--threads", "2"]));
    assert_eq!(hashes(&one), hashes(&two));
}

/// A camera drawn below the ground is refused with the view and a pitch that would do; an
/// unknown ground names the nearest known one; a misspelt key is caught.
#[test]
fn cameras_below_the_ground_and_unknown_grounds_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = recipe(dir.path(), "beam", r#""grass""#, r#""rgb""#);
    let text = std::fs::read_to_string(&path).unwrap();
    let below = write(
        dir.path(),
        "below.rhai",
        text.replace("pitch: [deg(8), deg(40)]", "pitch: [deg(-40), deg(-30)]"),
    );
    let output = run(&below, &dir.path().join("o1"), &[]);
    assert!(!output.status.success());
    let err = stderr(&output);
    assert!(
        err.contains("below the ground") && err.contains("view 0"),
        "{err}"
    );
    for (ground, expected) in [
        (r#""gras""#, "did you mean \"grass\""),
        (r#"#{ material: "lava" }"#, "unknown ground \"lava\""),
        (
            r#"#{ material: "soil", in_dept: true }"#,
            "did you mean `in_depth`",
        ),
    ] {
        let bad = write(
            dir.path(),
            "bad.rhai",
            text.replace(r#"ground: "grass""#, &format!("ground: {ground}")),
        );
        let output = run(&bad, &dir.path().join("o2"), &[]);
        assert!(!output.status.success());
        let err = stderr(&output);
        assert!(err.contains(expected) && err.contains("bad.rhai:"), "{err}");
    }
}
