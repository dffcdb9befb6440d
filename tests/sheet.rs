//! The contact sheet of `shmgen watch --once` seen from outside: it fits a full-HD screen
//! however many samples and views are asked for, says when images were left out, and the same
//! recipe gives the same bytes. What each cell, title and legend shows is tested beside the
//! sheet (src/preview/sheet.rs).

use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_shmgen");

/// A full-HD screen.
const SCREEN: (u32, u32) = (1920, 1080);

/// A recipe of `samples` samples × `views` views of a box, with depth and mask.
fn recipe(dir: &Path, samples: u32, views: u32) -> std::path::PathBuf {
    let text = format!(
        r#"dataset(#{{
    name: "many",
    seed: 4,
    samples: {samples},
    views: {views},
    outputs: ["rgb", "depth", "mask"],
    camera: #{{ width: 320, height: 240, pitch: [deg(10), deg(60)] }},
    scene: |rng| [assembly("box", [shape::box(rng.uniform(0.8, 1.2), 0.5, 0.3)])],
}});
"#
    );
    let path = dir.join("many.rhai");
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs `watch --once` with `args`; returns its stdout and the sheet's (width, height, bytes).
fn once(recipe: &Path, out: &Path, args: &[&str]) -> (String, (u32, u32), Vec<u8>) {
    let output = Command::new(BIN)
        .arg("watch")
        .arg(recipe)
        .arg("--once")
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(output.status.success(), "{output:?}");
    let bytes = std::fs::read(out).unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes.clone()));
    let info = decoder.read_info().unwrap().info().clone();
    let stdout = String::from_utf8(output.stdout).unwrap();
    (stdout, (info.width, info.height), bytes)
}

#[test]
fn a_thousand_images_still_fit_a_screen_and_the_rest_are_counted() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = recipe(dir.path(), 10, 100);
    let out = dir.path().join("sheet.png");
    let args = ["--samples", "10", "--views", "100", "--size", "64"];
    let (stdout, (width, height), _) = once(&recipe, &out, &args);
    assert!(width <= SCREEN.0 && height <= SCREEN.1, "{width}×{height}");
    // 10 × 100 images of 64 × 48 cannot all be shown at a readable size.
    let shown = stdout
        .split(" of 1000 images shown")
        .next()
        .and_then(|s| s.rsplit('(').next())
        .and_then(|n| n.parse::<u32>().ok());
    assert!(matches!(shown, Some(1..1000)), "{stdout}");
}

#[test]
fn the_default_preview_shows_every_image_on_one_screen() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = recipe(dir.path(), 4, 4);
    let out = dir.path().join("sheet.png");
    // The defaults: 4 samples × 4 views at 240 px.
    let (stdout, (width, height), _) = once(&recipe, &out, &[]);
    assert!(width <= SCREEN.0 && height <= SCREEN.1, "{width}×{height}");
    assert!(
        stdout.starts_with("preview: 4 samples × 4 views"),
        "{stdout}"
    );
    assert!(
        !stdout.contains("images shown"),
        "nothing left out: {stdout}"
    );
}

#[test]
fn the_same_recipe_writes_the_same_sheet() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = recipe(dir.path(), 3, 5);
    let args = ["--samples", "3", "--views", "5"];
    let (_, _, a) = once(&recipe, &dir.path().join("a.png"), &args);
    let (_, _, b) = once(&recipe, &dir.path().join("b.png"), &args);
    assert!(a == b, "two sheets of one recipe differ");
}
