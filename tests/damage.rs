//! Damage through the CLI: a reinforced-concrete beam is cracked by the mechanics where the
//! moment exceeds the cracking moment and deflects more than the sound beam, its damage lands
//! in the view JSON (valid against the published schema); damage that leaves the stiffness
//! alone leaves depth and mask byte for byte unchanged (only the RGB draws it); a wrong damage
//! call points at the recipe.

mod common;

use common::{hashes, read_json, render, run, schema_valid, stderr, write};
use serde_json::Value;
use std::path::Path;

/// A 6 m simply supported 300 × 500 mm beam under 60 kN at mid-span; `BEAM_EXTRA` is replaced
/// by further calls on the beam.
const RECIPE: &str = r#"
dataset(#{
    name: "damage", seed: 3, samples: 1, views: 2, outputs: ["rgb", "depth", "mask"],
    camera: #{ width: 48, height: 32, fov_y: deg(60), distance: [9.0, 10.0] },
    scene: |rng| {
        beam(#{ length: 6.0, width: 0.3, height: 0.5 })
            .point_force(3.0, 6.0e4)BEAM_EXTRA
    },
});
"#;

fn recipe(extra: &str) -> String {
    RECIPE.replace("BEAM_EXTRA", extra)
}

fn view_json(out: &Path) -> Value {
    read_json(&out.join("samples/0000/000000_00.json"))
}

#[test]
fn a_reinforced_concrete_beam_cracks_where_the_moment_exceeds_the_cracking_moment() {
    let (_dir, out) = render(
        &recipe(".reinforced_concrete().theory(\"euler_bernoulli\")"),
        &[],
    );
    let record = view_json(&out);
    schema_valid(&record);
    let beam = &record["scene"]["structures"][0];
    let damage = &beam["damage"];
    let concrete = &damage["concrete"];
    let m_cr = concrete["cracking_moment"].as_f64().unwrap();
    // By hand (C30/37, 300 × 500): M_cr = f_ctm b h²/6 = 2.8965 MPa · 0.0125 m³ = 36.206 kN·m.
    assert!((m_cr - 36_205.85).abs() < 0.1, "{m_cr}");
    // M(x) = P x/2: cracks only beyond x₀ = 2 M_cr/P from either support.
    let x0 = 2.0 * m_cr / 6.0e4;
    let items = damage["items"].as_array().unwrap();
    let flexural: Vec<&Value> = items
        .iter()
        .filter(|d| d["type"] == "flexural_crack")
        .collect();
    assert!(flexural.len() > 5, "{}", flexural.len());
    for d in &flexural {
        let x = d["position"]["along"].as_f64().unwrap();
        assert!(x > x0 && x < 6.0 - x0, "{x}");
        assert_eq!(d["position"]["face"], "bottom");
        assert_eq!(d["cause"]["kind"], "stress");
        assert!(d["width_mm"].as_f64().unwrap() > 0.0);
    }
    // The cracked beam deflects more than the sound one under the same load; the sound one is
    // P L³/(48 E_cm I).
    let e = concrete["concrete_modulus"].as_f64().unwrap();
    let sound = 6.0e4 * 216.0 / (48.0 * e * 0.3 * 0.125 / 12.0);
    let got_sound = damage["sound_max_deflection"].as_f64().unwrap();
    assert!(
        (got_sound / sound - 1.0).abs() < 1e-9,
        "{got_sound} vs {sound}"
    );
    assert!(damage["max_deflection"].as_f64().unwrap() > 1.2 * sound);
    assert_eq!(damage["stiffness_changed"], true);
}

#[test]
fn the_meshed_beam_follows_the_damaged_deflection() {
    // Depth changes where the deflection does: the cracked beam renders differently from the
    // same beam in concrete that is not reinforced (sound, same E).
    let (_a, cracked) = render(
        &recipe(".reinforced_concrete().theory(\"euler_bernoulli\")"),
        &[],
    );
    let e = view_json(&cracked)["scene"]["structures"][0]["elastic_modulus"].clone();
    let (_b, sound) = render(
        &recipe(&format!(
            ".elastic_modulus({e}).poisson(0.2).theory(\"euler_bernoulli\")"
        )),
        &[],
    );
    let depth = |out: &Path| {
        hashes(out)
            .into_iter()
            .filter(|(k, _)| k.contains("depth"))
            .collect::<Vec<_>>()
    };
    assert_ne!(depth(&cracked), depth(&sound));
}

#[test]
fn damage_that_leaves_the_stiffness_alone_is_drawn_and_only_spalls_and_dents_change_the_geometry() {
    let files = |out: &Path, ending: &str| {
        hashes(out)
            .into_iter()
            .filter(|(k, _)| k.ends_with(ending))
            .collect::<Vec<_>>()
    };
    let (_a, sound) = render(&recipe(""), &[]);
    let drawn = ".corrosion(#{ from: 0.0, to: 1.0, section_loss: 0.0 }).map_cracking(#{ from: 4.5, to: 5.5 })";
    let placed = format!(
        ".crack(#{{ at: 2.0, width_mm: 0.3 }}).spall(#{{ at: 4.0, depth: 0.02 }}).dent(#{{ at: 1.0, depth: 0.005 }}){drawn}"
    );
    let (_b, damaged) = render(&recipe(&placed), &[]);
    let (_c, marked) = render(
        &recipe(&format!(".crack(#{{ at: 2.0, width_mm: 0.3 }}){drawn}")),
        &[],
    );
    for geometric in ["depth.exr", "mask.png"] {
        assert_eq!(files(&sound, geometric), files(&marked, geometric));
    }
    // Spalls and dents are cut into the mesh (tests/damage_geometry.rs measures them).
    assert_ne!(files(&sound, "depth.exr"), files(&damaged, "depth.exr"));
    // The RGB shows it (docs/damage.md, "What is drawn").
    let rgb = |out: &Path| files(out, "rgb.png");
    assert!(rgb(&sound).iter().zip(rgb(&damaged)).any(|(a, b)| *a != b));
    let record = view_json(&damaged);
    schema_valid(&record);
    let items = record["scene"]["structures"][0]["damage"]["items"]
        .as_array()
        .unwrap()
        .clone();
    let types: Vec<&str> = items.iter().map(|d| d["type"].as_str().unwrap()).collect();
    assert_eq!(
        types,
        [
            "flexural_crack",
            "spall",
            "dent",
            "corrosion",
            "map_cracking"
        ]
    );
    assert!(items.iter().all(|d| d["cause"]["kind"] == "placed"));
    // The sound record has no damage at all.
    assert!(
        view_json(&sound)["scene"]["structures"][0]
            .get("damage")
            .is_none()
    );
}

#[test]
fn section_loss_softens_a_steel_beam_by_the_exposure_rules() {
    let (_dir, out) = render(
        &recipe(
            ".theory(\"euler_bernoulli\").corrosion_by_exposure(#{ end_loss: 0.2, bottom_loss: 0.0 })",
        ),
        &[],
    );
    let damage = &view_json(&out)["scene"]["structures"][0]["damage"];
    let rules: Vec<&str> = damage["items"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["cause"]["rule"].as_str().unwrap())
        .collect();
    assert_eq!(rules, ["support_end", "support_end", "bottom_flange"]);
    assert!((damage["min_stiffness_ratio"].as_f64().unwrap() - 0.8).abs() < 1e-12);
    let (sound, damaged) = (
        damage["sound_max_deflection"].as_f64().unwrap(),
        damage["max_deflection"].as_f64().unwrap(),
    );
    // Softer ends (0.6 m each) of a simply supported beam under a central load, by the
    // unit-load method: δ = (P/2)[a³/(3·0.8 EI) + ((L/2)³ − a³)/(3EI)], a = 0.6 m; the sound
    // δ = P L³/(48 EI), so the ratio is [a³/0.8 + (27 − a³)]/27.
    let a3 = 0.6f64.powi(3);
    let ratio = (a3 / 0.8 + 27.0 - a3) / 27.0;
    assert!(
        (damaged / sound / ratio - 1.0).abs() < 1e-6,
        "{} vs {ratio}",
        damaged / sound
    );
}

#[test]
fn a_damage_call_off_the_span_points_at_the_recipe() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "recipe.rhai", recipe(".crack(#{ at: 9.0 })"));
    let out = run(&path, &dir.path().join("out"), &[]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("recipe.rhai:7:") && err.contains("crack.at = 9 m lies outside the span"),
        "{err}"
    );
    let path = write(
        dir.path(),
        "recipe.rhai",
        recipe(".corrosion(#{ from: 0.0, to: 1.0, faces: [\"under\"] })"),
    );
    let err = stderr(&run(&path, &dir.path().join("out2"), &[]));
    assert!(
        err.contains("recipe.rhai:7:") && err.contains("\"under\" is unknown"),
        "{err}"
    );
    // A spall is cut into the mesh: it may not cut through an I's 15 mm flange, nor into a
    // tube, which has no flat face.
    for (section, spall, message) in [
        (
            "i_section(0.2, 0.4, 0.015, 0.01)",
            ".spall(#{ at: 1.0, depth: 0.02 })",
            "spall.depth = 0.02 m must be less than the flange (0.015 m)",
        ),
        (
            "tube(0.4, 0.02)",
            ".dent(#{ at: 1.0 })",
            "a circular hollow section has none",
        ),
    ] {
        let text = recipe(spall).replace("width: 0.3, height: 0.5", &format!("section: {section}"));
        let path = write(dir.path(), "recipe.rhai", text);
        let err = stderr(&run(&path, &dir.path().join("out3"), &[]));
        assert!(
            err.contains("recipe.rhai:7:") && err.contains(message),
            "{err}"
        );
    }
}
