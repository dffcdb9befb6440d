//! The bundled recipes' common parameters, seen from the command line: every recipe in
//! `scripts/` takes `--set size=N` (square images of side N) and `--set outputs=a,b,c` (the
//! outputs written, replacing the recipe's list), through `param` with a list default. What is
//! checked is what a user sees: the images' sizes read from the files and the files listed.

mod common;

use common::{
    bundled_rhai, manifest_files as listed, ok, read_json, read_png, run, shmgen, stderr, write,
};
use std::ffi::OsStr;
use std::path::Path;

/// `--set` arguments for a quick run of `recipe`: one sample and one view where the recipe
/// declares those parameters, plus `extra`.
fn quick_settings(recipe: &Path, extra: &[&str]) -> Vec<String> {
    let text = std::fs::read_to_string(recipe).unwrap();
    let mut sets: Vec<String> = ["samples=1", "views=1"]
        .into_iter()
        .filter(|s| text.contains(&format!("param(\"{}\"", s.split('=').next().unwrap())))
        .map(String::from)
        .collect();
    sets.extend(extra.iter().map(|s| s.to_string()));
    sets.into_iter()
        .flat_map(|s| ["--set".to_string(), s])
        .collect()
}

#[test]
fn every_bundled_recipe_takes_size_and_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let recipes = bundled_rhai("scripts");
    assert!(recipes.len() >= 9, "{recipes:?}");
    for recipe in &recipes {
        let name = recipe.file_stem().unwrap().to_string_lossy().to_string();
        let out = dir.path().join(&name);
        let sets = quick_settings(recipe, &["size=48", "outputs=rgb,depth,mesh"]);
        let args: Vec<&str> = sets.iter().map(String::as_str).collect();
        ok(run(recipe, &out, &args));
        let files = listed(&out);
        let rgb: Vec<&String> = files.iter().filter(|f| f.ends_with(".rgb.png")).collect();
        assert!(!rgb.is_empty(), "{name}: {files:?}");
        for file in &rgb {
            let (w, h, _, _) = read_png(&out.join(file));
            assert_eq!((w, h), (48, 48), "{name}: {file}");
        }
        let count = |kind: &str| files.iter().filter(|f| f.ends_with(kind)).count();
        assert_eq!(count(".depth.exr"), rgb.len(), "{name}: {files:?}");
        assert!(count(".mesh.ply") >= 1, "{name}: no mesh in {files:?}");
        // Only what was asked for (an augmenting recipe may add what its copies need).
        for dropped in [".mask.png", ".parts.png", ".normals.exr", ".points.ply"] {
            assert_eq!(count(dropped), 0, "{name}: {dropped} written: {files:?}");
        }
        let run_json = read_json(&out.join("run.json"));
        assert_eq!(
            run_json["params"]["outputs"],
            serde_json::json!(["rgb", "depth", "mesh"]),
            "{name}: {run_json}"
        );
    }
}

#[test]
fn a1_beams_writes_meshes_for_chamfer_and_keeps_its_copies_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/a1_beams.rhai");
    let out = dir.path().join("a1");
    let sets = quick_settings(
        &recipe,
        &[
            "size=32",
            "samples=2",
            "outputs=rgb,depth,mask,mesh",
            "augment=paper",
        ],
    );
    let args: Vec<&str> = sets.iter().map(String::as_str).collect();
    ok(run(&recipe, &out, &args));
    let files = listed(&out);
    for kind in ["000000.mesh.ply", "000001.mesh.ply", "000000_00.mask.png"] {
        assert!(files.iter().any(|f| f.ends_with(kind)), "{kind}: {files:?}");
    }
    // An augmented copy needs `erased`: added to the list given, not lost with it.
    assert!(
        files.iter().any(|f| f.ends_with("a0.erased.png")),
        "{files:?}"
    );
}

#[test]
fn a_list_parameter_is_set_as_comma_separated_names() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(
        dir.path(),
        "r.rhai",
        r#"dataset(#{ samples: 1, outputs: param("outputs", ["rgb", "depth"]),
            camera: #{ width: 16, height: 16 },
            scene: |rng| beam(#{ length: 2.0, width: 0.1, height: 0.2 }) })"#,
    );
    let out = dir.path().join("spaces");
    ok(run(&recipe, &out, &["--set", "outputs= rgb , mask"]));
    let files = listed(&out);
    assert!(files.iter().any(|f| f.ends_with(".mask.png")), "{files:?}");
    assert!(
        !files.iter().any(|f| f.ends_with(".depth.exr")),
        "{files:?}"
    );
    for (value, expected) in [
        (
            "outputs=rgb,,depth",
            "expected a comma-separated list (an item is empty)",
        ),
        (
            "outputs=",
            "expected a comma-separated list (an item is empty)",
        ),
        ("outputs=rgb,dpeth", "unknown output \"dpeth\""),
    ] {
        let bad = dir.path().join("bad");
        let args = ["run", "--out", "--quiet", "--set"].map(OsStr::new);
        let output = shmgen(&[
            args[0],
            recipe.as_os_str(),
            args[1],
            bad.as_os_str(),
            args[2],
            args[3],
            OsStr::new(value),
        ]);
        assert!(!output.status.success(), "{value}");
        assert!(
            stderr(&output).contains(expected),
            "{value}: {}",
            stderr(&output)
        );
    }
}
