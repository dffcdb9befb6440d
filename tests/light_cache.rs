//! The lighting cache (`shading: "cached"`, the default) against its reference, every pixel
//! tracing its own shadow and occlusion rays (`shading: "per_pixel"`), run through the binary
//! on a beam standing on drawn supports on a ground, under a sun and a sky: only the RGB image
//! may change, within the error docs/daylight.md states, in the hard cases (shadow edges, the
//! contact of supports and ground, a grazing sun, a sun at the horizon); and the cached bytes
//! do not depend on the thread count or the sharding.

mod common;

use common::{hashes, read_png, render, run, write};
use std::path::Path;

/// A 3 m beam, bent, on a pin and a roller on abutments standing on a ground, under a sun at
/// `elevation` degrees (30° azimuth) and a sky: shadow edges on the ground and on the
/// supports, contacts of abutments and ground, of beam and bearings.
fn beam_on_ground(elevation: f64, shading: &str) -> String {
    format!(
        r#"import "beam" as beam;
dataset(#{{
    seed: 3, samples: 1, views: 2,
    outputs: ["rgb", "depth", "mask", "parts", "normals"],
    camera: #{{ width: 160, height: 120, fov_y: deg(60), pitch: [deg(15), deg(35)], distance: "frame" }},
    light: #{{ sun: #{{ elevation: deg({elevation}), azimuth: deg(30) }}, sky: #{{}}, shadows: true }},
    background: "sky",
    ground: #{{ material: "grass" }},
    shading: "{shading}",
    scene: |rng| {{
        let b = beam::paper_cuboid(3.0, 0.3, 0.4);
        b.simply_supported();
        b.point_load(1.5, 0.06);
        b.supports_drawn(true);
        b.colour([0.6, 0.6, 0.6])
    }},
}});
"#
    )
}

/// RMS and 99th percentile of the absolute difference of two 8-bit images, in levels, over
/// every channel of every pixel.
fn difference(a: &[u8], b: &[u8]) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let mut d: Vec<u8> = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).collect();
    let rms = (d.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>() / d.len() as f64).sqrt();
    d.sort_unstable();
    (rms, f64::from(d[(d.len() * 99) / 100]))
}

/// The error bound of the default cache against the reference on these renders (worst
/// view), docs/daylight.md "Speed against error".
const MAX_RMS: f64 = 1.5;
const MAX_P99: f64 = 5.0;

/// Every file of a dataset but its images, the run record (which names the shading) and the
/// manifest (which hashes the images).
fn non_rgb_files(out: &Path) -> Vec<(String, String)> {
    let skipped = [".rgb.png", "run.json", "manifest.jsonl"];
    hashes(out)
        .into_iter()
        .filter(|(name, _)| !skipped.iter().any(|end| name.ends_with(end)))
        .collect()
}

fn worst_rgb_error(cached: &Path, reference: &Path) -> (f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    for (name, _) in hashes(reference) {
        if !name.ends_with(".rgb.png") {
            continue;
        }
        let (_, _, _, a) = read_png(&cached.join(&name));
        let (_, _, _, b) = read_png(&reference.join(&name));
        let (rms, p99) = difference(&a, &b);
        worst = (worst.0.max(rms), worst.1.max(p99));
    }
    worst
}

/// The hard cases: a high sun (shadow edges across the ground and the abutments' contacts),
/// a grazing sun (long shadows, a stretched penumbra) and a sun at the horizon (faces lit
/// edge-on, shadows reaching far across the ground).
#[test]
fn only_rgb_changes_and_within_the_stated_error_in_every_hard_case() {
    for elevation in [50.0, 8.0, 0.5] {
        let (_a, cached) = render(&beam_on_ground(elevation, "cached"), &[]);
        let (_b, reference) = render(&beam_on_ground(elevation, "per_pixel"), &[]);
        assert_eq!(
            non_rgb_files(&cached),
            non_rgb_files(&reference),
            "sun at {elevation}°: the labels and records are the reference's, byte for byte"
        );
        let (rms, p99) = worst_rgb_error(&cached, &reference);
        eprintln!("sun at {elevation}°: worst view RMS {rms:.2}, p99 {p99} levels");
        assert!(
            rms <= MAX_RMS && p99 <= MAX_P99,
            "sun at {elevation}°: RMS {rms:.2} (≤ {MAX_RMS}), p99 {p99} (≤ {MAX_P99}) levels"
        );
    }
}

/// The cache is filled by whichever view and thread gets to a corner first; what it holds
/// must not depend on that.
#[test]
fn cached_images_are_the_same_bytes_on_any_thread_count_and_sharding() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = beam_on_ground(40.0, "cached").replace("samples: 1", "samples: 2");
    let path = write(dir.path(), "r.rhai", recipe);
    let one = dir.path().join("one");
    let two = dir.path().join("two");
    let shards = dir.path().join("shards");
    assert!(run(&path, &one, &["--threads", "1"]).status.success());
    assert!(run(&path, &two, &["--threads", "2"]).status.success());
    for shard in ["0/2", "1/2"] {
        let out = run(&path, &shards, &["--threads", "2", "--shard", shard]);
        assert!(out.status.success(), "{}", common::stderr(&out));
    }
    let images = |out: &Path| {
        hashes(out)
            .into_iter()
            .filter(|(name, _)| name.ends_with(".rgb.png"))
            .collect::<Vec<_>>()
    };
    assert_eq!(images(&one).len(), 4);
    assert_eq!(images(&one), images(&two));
    assert_eq!(images(&one), images(&shards));
}

#[test]
fn an_unknown_shading_is_a_named_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "r.rhai", beam_on_ground(40.0, "per_vertex"));
    let out = run(&path, &dir.path().join("out"), &[]);
    assert!(!out.status.success());
    let message = common::stderr(&out);
    assert!(
        message.contains("dataset.shading") && message.contains("per_vertex"),
        "{message}"
    );
    assert!(
        message.contains("r.rhai:"),
        "names the recipe file: {message}"
    );
}
