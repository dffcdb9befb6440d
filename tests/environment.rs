//! Environment maps, run through the binary: the background along each pixel's exact ray, the
//! map's diffuse light on a white box against closed forms, errors naming the file, and the
//! same bytes on one thread or two. Maps are written by the tests (Radiance .hdr through the
//! image crate) and read back with it, so the expected values never come from shmgen.

mod common;

use common::{
    blake3_hex, encoded, hashes, inside, load, ok, read_json, rgb, run, stderr, transform,
    view_path, write,
};
use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};

/// Writes an equirectangular .hdr of `width` × `height` texels, radiance `f(row, col)`, and
/// returns the texels as the image crate decodes them (RGBE rounds).
fn write_map(
    path: &Path,
    width: usize,
    height: usize,
    f: impl Fn(usize, usize) -> [f32; 3],
) -> Vec<[f32; 3]> {
    let pixels: Vec<image::Rgb<f32>> = (0..height)
        .flat_map(|r| (0..width).map(move |c| (r, c)))
        .map(|(r, c)| image::Rgb(f(r, c)))
        .collect();
    let mut bytes = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut bytes)
        .encode(&pixels, width, height)
        .unwrap();
    std::fs::write(path, &bytes).unwrap();
    image::load_from_memory_with_format(&bytes, image::ImageFormat::Hdr)
        .unwrap()
        .into_rgb32f()
        .pixels()
        .map(|p| p.0)
        .collect()
}

/// Runs `recipe` from a fresh folder holding a map written by `map`; returns the folder and
/// the output path.
fn render_with_map(
    recipe: &str,
    map: impl FnOnce(&Path) -> Vec<[f32; 3]>,
    extra: &[&str],
) -> (tempfile::TempDir, PathBuf, Vec<[f32; 3]>) {
    let dir = tempfile::tempdir().unwrap();
    let texels = map(dir.path());
    let path = write(dir.path(), "recipe.rhai", recipe);
    let out = dir.path().join("out");
    ok(run(&path, &out, extra));
    (dir, out, texels)
}

const MAP_WIDTH: usize = 64;
const MAP_HEIGHT: usize = 32;

/// A smooth map that tells every direction apart: red and blue the cosine and sine of the
/// longitude, green the height above the horizon. All below 1, so the default
/// clipping film shows it unchanged.
fn telltale(r: usize, c: usize) -> [f32; 3] {
    let longitude = TAU * (c as f64 + 0.5) / MAP_WIDTH as f64;
    let polar = PI * (r as f64 + 0.5) / MAP_HEIGHT as f64;
    [
        (0.45 + 0.4 * longitude.cos()) as f32,
        (0.45 + 0.4 * polar.cos()) as f32,
        (0.45 + 0.4 * longitude.sin()) as f32,
    ]
}

/// Radiance along world direction `d` by bilinear interpolation between texel centres,
/// longitude from +x towards +y wrapping, polar angle from +z, clamped at the poles.
fn lookup(texels: &[[f32; 3]], d: [f64; 3]) -> [f64; 3] {
    let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let longitude = d[1].atan2(d[0]).rem_euclid(TAU);
    let polar = (d[2] / norm).clamp(-1.0, 1.0).acos();
    let x = longitude / TAU * MAP_WIDTH as f64 - 0.5;
    let y = (polar / PI * MAP_HEIGHT as f64 - 0.5).clamp(0.0, (MAP_HEIGHT - 1) as f64);
    let (fx, fy) = (x - x.floor(), y - y.floor());
    let c0 = (x.floor() as i64).rem_euclid(MAP_WIDTH as i64) as usize;
    let c1 = (c0 + 1) % MAP_WIDTH;
    let r0 = y.floor() as usize;
    let r1 = (r0 + 1).min(MAP_HEIGHT - 1);
    let t = |r: usize, c: usize, k: usize| f64::from(texels[r * MAP_WIDTH + c][k]);
    std::array::from_fn(|k| {
        (t(r0, c0, k) * (1.0 - fx) + t(r0, c1, k) * fx) * (1.0 - fy)
            + (t(r1, c0, k) * (1.0 - fx) + t(r1, c1, k) * fx) * fy
    })
}

const BACKGROUND_RECIPE: &str = r#"dataset(#{
    seed: 2, samples: 1, views: 3,
    outputs: ["rgb", "depth", "mask"],
    camera: #{ width: 96, height: 72, pitch: [deg(-60), deg(60)], distance: 8.0 },
    background: #{ environment: "sky.hdr" },
    scene: |rng| [ assembly("box", [shape::box(1.0, 1.0, 1.0)]).colour([0.5, 0.5, 0.5]) ],
});
"#;

/// Every background pixel away from the structure's edge shows the map along its ray, the ray
/// rebuilt here from the written K and camera-to-world pose (OpenCV axes); a Radiance .hdr and
/// an OpenEXR map alike.
#[test]
fn background_pixels_show_the_map_along_their_world_rays() {
    for format in ["hdr", "exr"] {
        let recipe = BACKGROUND_RECIPE.replace("sky.hdr", &format!("sky.{format}"));
        let (_dir, out, texels) = render_with_map(
            &recipe,
            |dir| match format {
                "hdr" => write_map(&dir.join("sky.hdr"), MAP_WIDTH, MAP_HEIGHT, telltale),
                _ => {
                    let rgb = |x: usize, y: usize| {
                        let [r, g, b] = telltale(y, x);
                        (r, g, b)
                    };
                    exr::prelude::write_rgb_file(dir.join("sky.exr"), MAP_WIDTH, MAP_HEIGHT, rgb)
                        .unwrap();
                    (0..MAP_WIDTH * MAP_HEIGHT)
                        .map(|i| telltale(i / MAP_WIDTH, i % MAP_WIDTH))
                        .collect()
                }
            },
            &[],
        );
        background_matches(&out, &texels);
    }
}

/// Checks every background pixel of the three views of `out` against `texels`.
fn background_matches(out: &Path, texels: &[[f32; 3]]) {
    for view in 0..3 {
        let v = load(out, view, None);
        let pixels = rgb(out, view);
        let (k, c2w) = (v.k(), v.c2w());
        let background = inside(&v.mask, v.width, 0);
        assert!(background.len() > 1000, "view {view}");
        let origin = transform(&c2w, [0.0; 3]);
        let mut worst: f64 = 0.0;
        for &i in &background {
            let (row, col) = (i / v.width, i % v.width);
            let camera = [
                (col as f64 + 0.5 - k[0][2]) / k[0][0],
                (row as f64 + 0.5 - k[1][2]) / k[1][1],
                1.0,
            ];
            let far = transform(&c2w, camera);
            let d = [far[0] - origin[0], far[1] - origin[1], far[2] - origin[2]];
            let want = lookup(texels, d);
            for ch in 0..3 {
                worst = worst.max((f64::from(pixels[i][ch]) - encoded(want[ch])).abs());
            }
        }
        // Rounding to 8 bits (0.5) and the renderer's 4096-step encoding table (< 0.6).
        assert!(worst <= 1.1, "view {view}: worst error {worst:.2} levels");
    }
}

/// A white box floating under a map: `constant` lights every face to the map's radiance; a map
/// bright only above the horizon lights a face with normal n to L (1 + n_z)/2 (exactly: that
/// irradiance lies in the span of the l ≤ 1 harmonics, so the order-2 projection is exact and
/// its only error is rounding). Faces are found from the back-projected depth: the top face at
/// the highest z, the bottom at the lowest, the sides between.
#[test]
fn a_white_box_is_lit_by_the_maps_irradiance() {
    const L: f32 = 0.5; // exact in RGBE
    let recipe = r#"dataset(#{
    seed: 3, samples: 1, views: 6,
    outputs: ["rgb", "depth", "mask"],
    camera: #{ width: 120, height: 90, pitch: [deg(-70), deg(70)], distance: 6.0 },
    light: #{ environment: #{ file: "sky.hdr", occlusion_rays: 0 }, ambient: 0.0 },
    scene: |rng| [ assembly("box", [shape::box(1.2, 0.8, 0.6)]).colour([1.0, 1.0, 1.0]) ],
});
"#;
    for upper_only in [false, true] {
        let (_dir, out, _) = render_with_map(
            recipe,
            |dir| {
                write_map(&dir.join("sky.hdr"), MAP_WIDTH, MAP_HEIGHT, |r, _| {
                    [if upper_only && r >= MAP_HEIGHT / 2 {
                        0.0
                    } else {
                        L
                    }; 3]
                })
            },
            &[],
        );
        let views: Vec<_> = (0..6)
            .map(|view| (load(&out, view, None), rgb(&out, view)))
            .collect();
        // The box's top and bottom heights, from every point seen.
        let heights = views.iter().flat_map(|(v, _)| {
            (0..v.depth.len()).filter_map(|i| v.point(i / v.width, i % v.width).map(|p| p[2]))
        });
        let (bottom, top) =
            heights.fold((f64::MAX, f64::MIN), |(lo, hi), z| (lo.min(z), hi.max(z)));
        assert!(
            (top - bottom - 0.6).abs() < 0.01,
            "the box is 0.6 m tall: {bottom}..{top}"
        );
        let mut seen = [0usize; 3]; // top, side, bottom pixels checked
        for (view, (v, pixels)) in views.iter().enumerate() {
            // 0 top (n_z = 1), 1 side (0), 2 bottom (−1), per pixel that sees the box.
            let face: Vec<Option<usize>> = (0..v.depth.len())
                .map(|i| {
                    let p = v.point(i / v.width, i % v.width)?;
                    Some(if p[2] > top - 1e-3 {
                        0
                    } else if p[2] < bottom + 1e-3 {
                        2
                    } else {
                        1
                    })
                })
                .collect();
            for i in inside(&v.mask, v.width, 255) {
                // Away from creases, where anti-aliasing mixes two faces.
                let w = v.width;
                let Some(f) = face[i] else { continue };
                if [i - 1, i + 1, i - w, i + w]
                    .iter()
                    .any(|&j| face[j] != Some(f))
                {
                    continue;
                }
                let n_z = 1.0 - f as f64;
                let want = if upper_only {
                    f64::from(L) * (1.0 + n_z) / 2.0
                } else {
                    f64::from(L)
                };
                for got in pixels[i].map(f64::from) {
                    assert!(
                        (got - encoded(want)).abs() <= 1.1,
                        "upper_only {upper_only}, view {view}, face {f}: {got} vs {:.1}",
                        encoded(want)
                    );
                }
                seen[f] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n > 50), "faces seen {seen:?}");
    }
}

/// A missing map, a map that is not 2:1 and one cut short are errors naming the file and the
/// recipe's line.
#[test]
fn a_missing_or_misshapen_map_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = write(dir.path(), "recipe.rhai", BACKGROUND_RECIPE);
    let failure = |out: &str| {
        let output = run(&recipe, &dir.path().join(out), &[]);
        assert!(!output.status.success());
        stderr(&output)
    };
    let message = failure("a");
    assert!(
        message.contains("sky.hdr") && message.contains("not found"),
        "{message}"
    );
    assert!(message.contains("recipe.rhai:1:"), "{message}");

    write_map(&dir.path().join("sky.hdr"), 40, 30, telltale);
    let message = failure("b");
    assert!(
        message.contains("sky.hdr") && message.contains("2:1"),
        "{message}"
    );

    std::fs::write(dir.path().join("sky.hdr"), b"not an image").unwrap();
    let message = failure("c");
    assert!(message.contains("sky.hdr"), "{message}");

    // Cut short (a download or copy that stopped): said so, not "failed to fill whole buffer".
    write_map(&dir.path().join("sky.hdr"), 64, 32, telltale);
    let whole = std::fs::read(dir.path().join("sky.hdr")).unwrap();
    std::fs::write(dir.path().join("sky.hdr"), &whole[..whole.len() / 2]).unwrap();
    let message = failure("d");
    assert!(
        message.contains("sky.hdr") && message.contains("truncated"),
        "{message}"
    );
}

/// Light and background from one map, with occlusion on and the map turned: the same bytes on
/// one thread or two, and the map's file and hash in each view's record.
#[test]
fn environment_light_is_the_same_on_one_thread_or_two() {
    let recipe = r#"dataset(#{
    seed: 5, samples: 2, views: 2,
    outputs: ["rgb", "depth", "mask"],
    camera: #{ width: 80, height: 60, distance: 6.0 },
    background: #{ environment: #{ file: "sky.hdr", rotation: 0.5 } },
    light: #{ environment: #{ file: "sky.hdr", rotation: 0.5, intensity: 1.5 },
              sun: #{ elevation: deg(40), azimuth: deg(20) } },
    scene: |rng| [
        assembly("plate", [shape::box(4.0, 4.0, 0.1).translate(0.0, 0.0, -0.05)]).colour([0.5, 0.5, 0.5]),
        assembly("block", [shape::box(1.0, 1.0, 1.5).translate(0.0, 0.0, 0.75)]).colour([0.7, 0.6, 0.5]),
    ],
});
"#;
    let dir = tempfile::tempdir().unwrap();
    write_map(&dir.path().join("sky.hdr"), MAP_WIDTH, MAP_HEIGHT, telltale);
    let path = write(dir.path(), "recipe.rhai", recipe);
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    ok(run(&path, &one, &["--threads", "1"]));
    ok(run(&path, &two, &["--threads", "2"]));
    assert_eq!(hashes(&one), hashes(&two));
    let json = read_json(&view_path(&one, 0, 1, None, "json"));
    let text = json.to_string();
    let hash = blake3_hex(&std::fs::read(dir.path().join("sky.hdr")).unwrap());
    assert!(
        text.contains(&hash),
        "the view records the map's hash: {text}"
    );
}
