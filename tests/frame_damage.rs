//! Damage on frame members through the CLI: a crack placed on a column is drawn and labelled
//! where its 3-D line is (pixels back-projected through depth and camera, minus the written
//! displacement); a reinforced-concrete portal swayed by a lateral force cracks on the faces its
//! double-curvature columns stretch (the windward face at the base, the leeward one at the
//! top), is analysed softer than the sound portal, and its JSON is valid against the schema; a
//! wrong damage call points at the recipe.

mod common;

use common::{damage_view, read_json, render, run, schema_valid, stderr, write};
use serde_json::Value;
use std::path::Path;

/// A 3 m column along world z from the origin (local z = world +x, local y = world −y) under a
/// small lateral force, filmed face-on from −y (its `side_pos_y` face, at y = −0.15 m).
const COLUMN: &str = r#"
dataset(#{
    name: "column", seed: 1, samples: 1, views: 1,
    outputs: ["rgb", "depth", "displacement", "damage"],
    camera: #{ width: 320, height: 240, fov_y: deg(40), distance: [1.2, 1.2],
               pitch: [0.0, 0.0], yaw: [deg(-90), deg(-90)] },
    scene: |rng| {
        let f = frame("column", #{ plane: "xz" });
        let a = f.node(0, 0, 0);
        let b = f.node(0, 0, 3.0);
        let m = f.member(a, b, rectangle(0.3, 0.3));
        f.support(a, "fixed");
        f.node_load(b, [100.0, 0.0, 0.0]);
        DAMAGE
        f
    },
});
"#;

fn view_json(out: &Path) -> Value {
    read_json(&out.join("samples/0000/000000_00.json"))
}

#[test]
fn a_crack_placed_on_a_column_is_labelled_on_its_3d_line() {
    // Flexural crack at 1.5 m up, across the −x face (the member's "bottom") and 0.2 m into
    // each side: on the side seen, the segment z = 1.5, x from −0.15 to 0.05, y = −0.15.
    let w = 2e-3;
    let damage = r#"f.damage(#{ member: m, type: "crack", kind: "flexural", at: 1.5, face: "bottom", width_mm: 2.0, depth: 0.2 });"#;
    let (_dir, out) = render(&COLUMN.replace("DAMAGE", damage), &[]);
    let v = damage_view(&out);
    let json = view_json(&out);
    let items = &json["scene"]["structures"][0]["analysis"]["damage"]["items"];
    assert_eq!(items.as_array().unwrap().len(), 1);
    assert_eq!(items[0]["member"], "members[0]");
    assert_eq!(items[0]["cause"]["kind"], "placed");
    let mut crack_pixels = 0;
    for (i, &class) in v.class.iter().enumerate() {
        let Some(p) = v.rest[i] else {
            assert_eq!(class, 0);
            continue;
        };
        let f = f64::from(v.depth[i]) / v.k[0][0];
        let on_face = (p[1] + 0.15).abs() < 1e-3;
        if class == 0 {
            continue;
        }
        assert!(
            on_face,
            "pixel {i}: class {class} off the seen face at {p:?}"
        );
        assert_eq!(class, 1);
        assert_eq!(v.instance[i], 1);
        assert!(
            (p[2] - 1.5).abs() <= 0.75 * f + 0.5 * w + 1e-3
                && p[0] >= -0.15 - f
                && p[0] <= 0.05 + f,
            "pixel {i}: crack label at {p:?}, footprint {f}"
        );
        crack_pixels += 1;
    }
    // 0.2 m of crack at ~3.6 mm a pixel: a line of about 55 pixels, at least one wide.
    assert!(crack_pixels >= 50, "{crack_pixels} crack pixels");
}

/// A reinforced-concrete portal (C30/37, 0.3 × 0.3 m columns 3 m tall, 3 m apart, a 0.3 ×
/// 0.5 m beam) clamped at its bases, swayed by 60 kN at its top left, seen from −y.
const PORTAL: &str = r#"
dataset(#{
    name: "portal", seed: 2, samples: 1, views: 1,
    outputs: ["rgb", "depth", "displacement", "damage"],
    camera: #{ width: 480, height: 480, fov_y: deg(40), distance: [6.5, 6.5],
               pitch: [0.0, 0.0], yaw: [deg(-90), deg(-90)] },
    scene: |rng| {
        let f = frame("portal", #{ plane: "xz" });
        let a = f.node(0, 0, 0);
        let b = f.node(0, 0, 3.0);
        let c = f.node(3.0, 0, 3.0);
        let d = f.node(3.0, 0, 0);
        f.member(a, b, rectangle(0.3, 0.3));
        f.member(b, c, rectangle(0.3, 0.5));
        f.member(d, c, rectangle(0.3, 0.3));
        f.support(a, "fixed");
        f.support(d, "fixed");
        f.node_load(b, [6.0e4, 0.0, 0.0]);
        CONCRETE
        f
    },
});
"#;

#[test]
fn an_rc_portal_under_sway_cracks_on_the_faces_its_moment_diagram_stretches() {
    let (_dir, out) = render(
        &PORTAL.replace("CONCRETE", "f.reinforced_concrete(#{ bars: 3 });"),
        &[],
    );
    let json = view_json(&out);
    schema_valid(&json);
    let analysis = &json["scene"]["structures"][0]["analysis"];
    let damage = &analysis["damage"];
    assert_eq!(damage["stiffness_changed"], true);
    let sound = damage["sound_max_displacement"].as_f64().unwrap();
    let max = analysis["max_displacement"].as_f64().unwrap();
    assert!(max > 1.2 * sound, "{max} vs sound {sound}");
    for m in damage["members"].as_array().unwrap() {
        let strong = m["section_scale"]["strong"].as_f64().unwrap();
        assert!(strong < 1.0 && strong > 0.0, "{m}");
    }
    // The left column (member 0) bends in double curvature: pushed along +x at its top, it is
    // stretched on its windward (−x) face at the clamp and on its leeward (+x) face under the
    // beam. Its local z is world +x, so "bottom" (−z) is the −x face.
    let items = damage["items"].as_array().unwrap();
    let left: Vec<(f64, &str)> = items
        .iter()
        .filter(|d| d["member"] == "members[0]" && d["type"] == "flexural_crack")
        .map(|d| {
            let p = &d["position"];
            (p["along"].as_f64().unwrap(), p["face"].as_str().unwrap())
        })
        .collect();
    assert!(
        left.iter().any(|c| c.0 < 1.0) && left.iter().any(|c| c.0 > 2.0),
        "{left:?}"
    );
    for (along, face) in &left {
        if *along < 1.0 {
            assert_eq!(*face, "bottom", "{along}");
        } else if *along > 2.0 {
            assert_eq!(*face, "top", "{along}");
        }
    }
    // In the pixels: crack labels on the left column's seen side rise from its tension face
    // to the cracked neutral axis, x from the compression face — near the clamp from x = −0.15
    // up to 0.15 − x, under the beam from x = 0.15 down to −0.15 + x — and reach the tension
    // edge.
    let x_na = damage["members"][0]["concrete"]["neutral_axis"]
        .as_f64()
        .unwrap();
    assert!(x_na > 0.0 && x_na < 0.15, "{x_na}");
    let v = damage_view(&out);
    let (mut low, mut high) = (0, 0);
    let (mut low_edge, mut high_edge) = (false, false);
    for (i, &class) in v.class.iter().enumerate() {
        let Some(p) = v.rest[i] else { continue };
        let on_left_column = p[0].abs() < 0.16 && (p[1] + 0.15).abs() < 1e-3 && p[2] < 2.7;
        if class != 1 || !on_left_column {
            continue;
        }
        let f = f64::from(v.depth[i]) / v.k[0][0];
        if p[2] < 1.0 {
            assert!(p[0] < 0.15 - x_na + f, "clamp crack pixel at {p:?}");
            low_edge |= p[0] < -0.15 + 2.0 * f;
            low += 1;
        } else if p[2] > 2.0 {
            assert!(p[0] > -0.15 + x_na - f, "top crack pixel at {p:?}");
            high_edge |= p[0] > 0.15 - 2.0 * f;
            high += 1;
        }
    }
    assert!(
        low_edge && high_edge,
        "cracks do not reach the tension faces"
    );
    assert!(low > 0 && high > 0, "{low} / {high} crack pixels");
}

#[test]
fn a_wrong_frame_damage_call_points_at_the_recipe() {
    let dir = tempfile::tempdir().unwrap();
    let damage = r#"f.damage(#{ member: m, type: "crack", at: 4.0 });"#;
    let path = write(dir.path(), "recipe.rhai", COLUMN.replace("DAMAGE", damage));
    let output = run(&path, &dir.path().join("out"), &[]);
    assert!(!output.status.success());
    let err = stderr(&output);
    assert!(err.contains("recipe.rhai:14:"), "{err}");
    assert!(
        err.contains("damage(crack).at = 4 m lies outside the span [0, 3] m"),
        "{err}"
    );
    let damage = r#"f.damage(#{ member: m, type: "spall", at: 1.0 });"#;
    let path = write(dir.path(), "recipe.rhai", COLUMN.replace("DAMAGE", damage));
    let err = stderr(&run(&path, &dir.path().join("out2"), &[]));
    assert!(
        err.contains("spalls and dents are cut only into beams"),
        "{err}"
    );
}

#[test]
fn cracks_on_frame_members_no_view_resolves_are_named_where_the_frame_lists_them() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = PORTAL
        .replace("CONCRETE", "f.reinforced_concrete();")
        .replace("width: 480, height: 480", "width: 48, height: 48");
    let path = write(dir.path(), "recipe.rhai", recipe);
    let output = run(&path, &dir.path().join("out"), &[]);
    assert!(output.status.success());
    let err = stderr(&output);
    assert!(
        err.contains("structures[0].analysis.damage.items[0] ("),
        "{err}"
    );
}
