//! The standard library's whole structures (stdlib/bridge.rhai, stdlib/tower.rhai) through the
//! CLI: each is built by a recipe, analysed, and its labels read from the view JSON are checked
//! against statics done here by hand — reactions that balance the deck load and the weight
//! of every member (areas from the section dimensions in the JSON), the symmetry a symmetric
//! bridge under a symmetric load must show, the three-moment equation for a continuous girder,
//! and a tower's base shear and overturning moment under wind.

mod common;

use common::{read_json, render, view_path};
use serde_json::Value;
use std::f64::consts::PI;
use std::path::Path;

const GRAVITY: f64 = 9.80665;

/// The frame a recipe's `scene` expression builds (after `import "bridge"` and `import
/// "tower"`), analysed: its model and its analysis, from view 0's JSON (schema-checked).
fn analysed(scene: &str) -> (Value, Value) {
    let recipe = format!(
        r#"
import "bridge" as bridge;
import "tower" as tower;
dataset(#{{
    name: "structure", seed: 1, samples: 1, views: 1, outputs: ["depth"],
    camera: #{{ width: 32, height: 32, fov_y: deg(60), distance: "frame" }},
    scene: |rng| {{ {scene} }},
}});
"#
    );
    let (_dir, out) = render(&recipe, &[]);
    let record = read_json(&view_path(&out, 0, 0, None, "json"));
    let schema: Value = serde_json::from_str(
        &std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/schema/view.schema.json"),
        )
        .unwrap(),
    )
    .unwrap();
    assert!(
        jsonschema::validator_for(&schema)
            .unwrap()
            .is_valid(&record)
    );
    let structure = &record["scene"]["structures"][0];
    (structure["model"].clone(), structure["analysis"].clone())
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

fn vec3(v: &Value) -> [f64; 3] {
    [f(&v[0]), f(&v[1]), f(&v[2])]
}

/// Cross-section area of a section as the JSON gives it, m².
fn area(section: &Value) -> f64 {
    let d = |k: &str| f(&section[k]);
    match section["shape"].as_str().unwrap() {
        "rectangle" => d("width") * d("height"),
        "hollow_box" => {
            let t = d("wall");
            d("width") * d("height") - (d("width") - 2.0 * t) * (d("height") - 2.0 * t)
        }
        "i_section" => {
            2.0 * d("width") * d("flange") + (d("height") - 2.0 * d("flange")) * d("web")
        }
        "circular_hollow" => {
            let (o, t) = (d("diameter"), d("wall"));
            PI / 4.0 * (o * o - (o - 2.0 * t).powi(2))
        }
        other => panic!("section {other}"),
    }
}

/// Total weight of the members (ρ g A L), N.
fn self_weight(model: &Value) -> f64 {
    let nodes: Vec<[f64; 3]> = model["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(vec3)
        .collect();
    model["members"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            let (a, b) = (
                nodes[m["start"].as_u64().unwrap() as usize],
                nodes[m["end"].as_u64().unwrap() as usize],
            );
            let length = (0..3).map(|i| (b[i] - a[i]).powi(2)).sum::<f64>().sqrt();
            f(&m["density"]) * GRAVITY * area(&m["section"]) * length
        })
        .sum()
}

/// Each reaction: the node's position and the force and moment the support exerts.
fn reactions(model: &Value, analysis: &Value) -> Reactions {
    analysis["reactions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let node = r["node"].as_u64().unwrap() as usize;
            (
                vec3(&model["nodes"][node]),
                vec3(&r["force"]),
                vec3(&r["moment"]),
            )
        })
        .collect()
}

/// Sum of the reactions' components `i`, N.
fn total(reactions: &Reactions, i: usize) -> f64 {
    reactions.iter().map(|r| r.1[i]).sum()
}

/// Vertical reaction of the supports at x = `x` (all of them across the bridge), N.
fn line_reaction(reactions: &Reactions, x: f64) -> f64 {
    reactions
        .iter()
        .filter(|r| (r.0[0] - x).abs() < 1e-9)
        .map(|r| r.1[2])
        .sum()
}

/// Each support's node position, and the force and moment the support exerts.
type Reactions = Vec<([f64; 3], [f64; 3], [f64; 3])>;

/// The frame `scene` builds, analysed: its model, its analysis and its reactions.
fn solved(scene: &str) -> (Value, Value, Reactions) {
    let (model, analysis) = analysed(scene);
    let r = reactions(&model, &analysis);
    (model, analysis, r)
}

fn close(got: f64, want: f64, relative: f64) -> bool {
    (got - want).abs() <= relative * want.abs()
}

#[test]
fn a_truss_bridges_reactions_carry_its_deck_load_and_the_weight_of_every_member() {
    for kind in ["pratt", "warren"] {
        let (model, analysis, r) = solved(&format!(
            r#"bridge::truss_bridge(#{{ kind: "{kind}", panels: 6, panel: 5.0, depth: 4.0, width: 7.6, deck_load: 4.0e3 }})"#
        ));
        // Deck 7.6 − 0.6 = 7.0 m wide between the chords, 30 m long.
        let want = 4.0e3 * 7.0 * 30.0 + self_weight(&model);
        let up = total(&r, 2);
        assert!(close(up, want, 1e-9), "{kind}: {up} vs {want}");
        for i in [0, 1] {
            assert!(
                total(&r, i).abs() < 1e-9 * want,
                "{kind}: {:?}",
                total(&r, i)
            );
        }
        // Symmetric about mid-span and about the bridge's axis: the four bearings carry the
        // same vertical force.
        for (_, force, _) in &r {
            assert!(close(force[2], want / 4.0, 1e-9), "{kind}: {force:?}");
        }
        assert_eq!(analysis["physically_plausible"], true);
    }
}

#[test]
fn a_truss_bridge_loaded_on_its_first_half_puts_three_quarters_on_the_near_bearings() {
    // Without self-weight, a uniform load q over the first half of a simply supported span
    // L gives the near bearings 3/8 q L and the far ones 1/8 q L: statics of the whole, which
    // the truss (statically determinate along its length) must reproduce.
    let (_, _, r) = solved(
        r#"bridge::truss_bridge(#{ panels: 8, panel: 5.0, depth: 4.0, width: 7.6, deck_load: 6.0e3, load_to: 0.5, self_weight: false })"#,
    );
    let q_l = 6.0e3 * 7.0 * 40.0;
    assert!(close(line_reaction(&r, 0.0), 3.0 / 8.0 * q_l, 1e-9));
    assert!(close(line_reaction(&r, 40.0), 1.0 / 8.0 * q_l, 1e-9));
}

#[test]
fn a_two_span_girder_bridge_follows_the_three_moment_equation_over_its_pier() {
    // Two equal spans, rigid bearings, no self-weight, the deck load on the girders: each
    // girder is a two-span continuous beam, whose pier reaction is 10/8 w L (three-moment
    // equation) and end reactions 3/8 w L, whatever the cross-frames, which stay unstrained
    // when every girder carries the same load.
    let (_, _, r) = solved(
        r#"bridge::girder_bridge(#{ spans: [20.0, 20.0], girders: 3, spacing: 3.0, deck: false, bearings: "rigid", self_weight: false, deck_load: 5.0e3 })"#,
    );
    let w_l = 5.0e3 * 3.0 * 3.0 * 20.0;
    assert!(close(line_reaction(&r, 20.0), 10.0 / 8.0 * w_l, 1e-9));
    for end in [0.0, 40.0] {
        assert!(close(line_reaction(&r, end), 3.0 / 8.0 * w_l, 1e-9));
    }
}

#[test]
fn a_composite_girder_bridge_on_elastomeric_bearings_balances_its_load_symmetrically() {
    // Three spans 20 + 26 + 20, the deck grillage on the girders, elastomeric bearings (all
    // springs) and the railing: the reactions balance the deck load and the members' weight,
    // nothing horizontal, and the symmetric bridge has mirror-image reactions.
    let (model, analysis, r) = solved(
        r#"bridge::girder_bridge(#{ spans: [20.0, 26.0, 20.0], girders: 3, spacing: 3.0, deck_load: 5.0e3 })"#,
    );
    let want = 5.0e3 * 9.0 * 66.0 + self_weight(&model);
    assert!(
        close(total(&r, 2), want, 1e-9),
        "{} vs {want}",
        total(&r, 2)
    );
    for i in [0, 1] {
        assert!(total(&r, i).abs() < 1e-9 * want);
    }
    for (x, mirror) in [(0.0, 66.0), (20.0, 46.0)] {
        let (a, b) = (line_reaction(&r, x), line_reaction(&r, mirror));
        assert!(close(a, b, 1e-9), "{a} vs {b}");
    }
    // The piers carry more than the abutments (continuity), as the three-moment equation says
    // of any continuous girder.
    assert!(line_reaction(&r, 20.0) > 2.0 * line_reaction(&r, 0.0));
    assert_eq!(analysis["physically_plausible"], true);
}

#[test]
fn a_lattice_towers_base_carries_the_wind_shear_and_overturning_moment() {
    // w N per metre of height on an H m tower: base shear w H along +x, overturning moment
    // w H² / 2 about the y axis, balanced by the four fixed feet (their forces and moments).
    for bracing in ["x", "k"] {
        let (_, _, r) = solved(&format!(
            r#"tower::lattice_tower(#{{ height: 30.0, panels: 10, wind: 2.0e3, bracing: "{bracing}", self_weight: false }})"#
        ));
        let (w, h) = (2.0e3, 30.0);
        assert!(close(-total(&r, 0), w * h, 1e-9), "{bracing}");
        let turning: f64 = r
            .iter()
            .map(|(p, f, m)| p[2] * f[0] - p[0] * f[2] + m[1])
            .sum();
        assert!(
            close(-turning, w * h * h / 2.0, 1e-9),
            "{bracing}: {turning}"
        );
    }
}

#[test]
fn a_damaged_girder_deflects_its_bridge_more() {
    // The same bridge with one girder segment at a fifth of its stiffness deflects more
    // (stiffness lost can only add compliance), and the damaged member is labelled.
    let scene = |damage: &str| {
        format!(
            r#"bridge::girder_bridge(#{{ spans: [20.0, 20.0], girders: 2, deck_load: 8.0e3, damage: {damage} }})"#
        )
    };
    let (_, sound) = analysed(&scene("[]"));
    let (model, damaged) = analysed(&scene("[0.25, 0.2]"));
    assert!(f(&damaged["max_displacement"]) > f(&sound["max_displacement"]));
    let weakened: Vec<usize> = model["members"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .filter(|(_, m)| f(&m["stiffness_factor"]) < 1.0)
        .map(|(i, _)| i)
        .collect();
    assert_eq!(weakened.len(), 1);
    assert_eq!(model["members"][weakened[0]]["part"], "girders");
}
