//! Dents on shells through the CLI: a silo's dent is a damage record in the view JSON (type,
//! position, size, depth, severity, cause, and its EN 1993-1-6 dimple tolerance), the depth of
//! every pixel on and around it is where the pixel's ray meets the dent's analytic surface
//! r + w(θ, z) (to the chord tolerance), and the pixels whose undeformed point lies inside
//! it, and only those, are labelled `dent` with its instance.

mod common;

use common::{damage_view, read_json, render, view_path};
use std::f64::consts::{FRAC_PI_2, PI};

/// A 3 m × 8 m steel shell (8 mm wall) standing on z = 0, with a 62 mm dent of 0.6 m radius
/// facing −y at mid-height, seen face-on from 1.5 m in front of it (60°: 7 mm pixels, the view 1.7 m wide, the dent
/// 1.2 m). Chords within 0.2 mm.
const RECIPE: &str = r#"
dataset(#{
    name: "silo dent", seed: 1, samples: 1, views: 1,
    outputs: ["rgb", "depth", "mask", "displacement", "damage"],
    camera: #{ width: 240, height: 240, fov_y: deg(60), distance: [4.5, 4.5],
               pitch: [0.0, 0.0], yaw: [deg(-90), deg(-90)] },
    scene: |rng| {
        assembly("silo", [shape::tube(3.0, 8.0, 0.008).dimple(0.062, -PI() / 2.0, 4.0, 0.6).part("shell")])
            .chord_tolerance(2e-4)
    },
});
"#;

const R: f64 = 3.0;
const A: f64 = 0.062;
const DENT_R: f64 = 0.6;
const Z0: f64 = 4.0;
const TOLERANCE: f64 = 2e-4;

/// Outward radial displacement of the dent at world point (x, y, z).
fn w(p: [f64; 3]) -> f64 {
    let turn = (p[1].atan2(p[0]) + FRAC_PI_2 + PI).rem_euclid(2.0 * PI) - PI;
    let d = (R * turn).hypot(p[2] - Z0);
    if d < DENT_R {
        -A * (PI * d / (2.0 * DENT_R)).cos().powi(2)
    } else {
        0.0
    }
}

/// Where the ray o + t·dir (dir with camera z = 1, so t is the planar depth) first meets the
/// dented surface ρ = R + w: bisection between a point outside and one inside.
fn analytic_depth(o: [f64; 3], dir: [f64; 3]) -> Option<f64> {
    let at = |t: f64| std::array::from_fn::<f64, 3, _>(|k| o[k] + t * dir[k]);
    let outside = |t: f64| {
        let p = at(t);
        p[0].hypot(p[1]) - (R + w(p))
    };
    let (mut lo, mut hi) = (0.0, 3.0);
    if outside(hi) > 0.0 {
        return None;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if outside(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[test]
fn a_silo_dent_is_recorded_meshed_to_its_surface_and_labelled() {
    let (_dir, out) = render(RECIPE, &[]);
    let json = read_json(&view_path(&out, 0, 0, None, "json"));
    let items = &json["scene"]["structures"][0]["damage"]["items"];
    let dent = &items[0];
    assert_eq!(items.as_array().map(Vec::len), Some(1), "{items}");
    assert_eq!(dent["type"], "dent");
    assert_eq!(dent["member"], "shell");
    assert_eq!(dent["cause"]["kind"], "placed");
    assert_eq!(dent["severity"], "severe");
    assert!((dent["position"]["angle"].as_f64().unwrap() - 1.5 * PI).abs() < 1e-12);
    assert_eq!(dent["position"]["height"], 4.0);
    assert_eq!(
        (dent["depth"].as_f64(), dent["radius"].as_f64()),
        (Some(A), Some(DENT_R))
    );
    // ℓ_gx = 4√(r t) = 0.61968 m; U₀ = 0.062/ℓ_gx = 0.10005: 6.25 times class C's limit.
    assert_eq!(dent["tolerance"]["class_met"], "none");
    let u0 = dent["tolerance"]["dimple_parameter"].as_f64().unwrap();
    assert!((u0 - 0.062 / (4.0 * 0.024f64.sqrt())).abs() < 1e-12, "{u0}");
    assert_eq!(json["damage"]["classes"][6], "dent");

    let v = damage_view(&out);
    let (mut inside, mut centre, mut around) = (0, false, 0);
    for (i, rest) in v.rest.iter().enumerate() {
        let Some(rest) = rest else { continue };
        let (origin, dir) = v.ray(i);
        // Every pixel's depth is where its ray meets the analytic surface, to the chord
        // tolerance over the cosine of the ray's angle to the surface's normal (≥ 0.7 in this
        // 60° view of a curved shell) and f32 rounding.
        let want = analytic_depth(origin, dir).expect("the ray meets the shell");
        let depth = f64::from(v.depth[i]);
        assert!(
            (depth - want).abs() < TOLERANCE / 0.7 + 1e-6,
            "pixel {i}: depth {depth} vs {want}"
        );
        // Labels by the undeformed point's surface distance from the dent's centre.
        let turn = (rest[1].atan2(rest[0]) + FRAC_PI_2 + PI).rem_euclid(2.0 * PI) - PI;
        let s = (R * turn).hypot(rest[2] - Z0) / DENT_R;
        if s < 0.99 {
            assert_eq!(
                (v.class[i], v.instance[i]),
                (6, 1),
                "pixel {i} at s/R = {s}"
            );
            inside += 1;
        } else if s > 1.01 {
            assert_eq!(
                (v.class[i], v.instance[i]),
                (0, 0),
                "pixel {i} at s/R = {s}"
            );
            around += 1;
        }
        if s < 0.01 {
            // The depth at the dent's centre: the face's 1.5 m plus the dent's 62 mm.
            assert!((depth - (1.5 + A)).abs() < 2e-4, "centre depth {depth}");
            centre = true;
        }
    }
    assert!(
        centre && inside > 15_000 && around > 5_000,
        "{inside} {around}"
    );
}
