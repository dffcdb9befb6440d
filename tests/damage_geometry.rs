//! Damage as geometry, through the CLI: a spall is a cavity in the mesh, so the depth written
//! for a pixel inside it is the depth of the cavity's floor (the analytic plane `depth` under
//! the face), pixels on an exposed bar back-project onto the bar's cylinder (at the cover depth
//! EN 1992-1-1 §4.4.1 gives, as the recipe states it), every ray through the cavity's region
//! meets the mesh (no holes where the surface was cut), and the cavity and its bars carry the
//! spall's instance id. A dent is a bowl depth·(1 − r²/R²)² pushed into the face: its pixels
//! back-project onto that bowl, the depth at its centre is the face's plus its depth, and the
//! normals tilt by the bowl's slope at its rim.

mod common;

use common::{damage_view, read_exr_channels, render, transform, view_path};
use std::path::Path;

/// A 4 m simply supported 300 × 500 mm reinforced-concrete beam along x, centred on the
/// origin, seen face-on from −y (the side face `side_neg_y` is the plane y = −0.15 m), with a
/// spall on that face: centred at x = 0 (2 m along), z = −0.12 m, 0.30 m long, 0.24 m tall,
/// 50 mm deep. Cover 35 mm, bars φ16: the bottom corner bar's axis is at y = −0.107, z = −0.207,
/// its face 35 mm inside the side face, so the 50 mm cavity lays it bare.
const RECIPE: &str = r#"
dataset(#{
    name: "spall", seed: 1, samples: 1, views: 1,
    outputs: ["rgb", "depth", "mask", "displacement", "normals", "damage"],
    camera: #{ width: 320, height: 240, fov_y: deg(30), distance: [1.5, 1.5],
               pitch: [0.0, 0.0], yaw: [deg(-90), deg(-90)] },
    scene: |rng| {
        beam(#{ length: 4.0, width: 0.3, height: 0.5 })
            .reinforced_concrete(#{ cover: 0.035, bar_diameter: 0.016, bars: 3 })
            .point_force(2.0, 1.0e3)SPALL
    },
});
"#;

const SPALL: &str = r#".spall(#{ at: 2.0, face: "side_neg_y", height: -0.12, length: 0.3, breadth: 0.24, depth: 0.05 })"#;
const FACE_Y: f64 = -0.15;
const DEPTH: f64 = 0.05;
const CENTRE: (f64, f64) = (0.0, -0.12);
const SEMI: (f64, f64) = (0.15, 0.12);
const BAR: (f64, f64, f64) = (-0.107, -0.207, 0.008);

/// What view 0 of sample 0 saw, per pixel.
struct Seen {
    depth: Vec<f32>,
    class: Vec<u8>,
    instance: Vec<u16>,
    rgb: Vec<u8>,
    /// The geometric normal of every pixel, camera axes.
    normals: Vec<[f64; 3]>,
    /// The camera centre and each pixel's ray (camera z = 1, world coordinates).
    origin: [f64; 3],
    rays: Vec<[f64; 3]>,
    /// World rest point (back-projected hit minus displacement) of every pixel seen.
    rest: Vec<Option<[f64; 3]>>,
}

fn seen(out: &Path) -> Seen {
    let v = damage_view(out);
    let (_, n) = read_exr_channels(&view_path(out, 0, 0, None, "normals.exr"));
    let normals = (0..v.depth.len())
        .map(|i| ["R", "G", "B"].map(|c| f64::from(n[c][i])))
        .collect();
    let origin = transform(&v.c2w, [0.0; 3]);
    let rays = (0..v.depth.len()).map(|i| v.ray(i).1).collect();
    Seen {
        depth: v.depth,
        class: v.class,
        instance: v.instance,
        rgb: v.rgb,
        normals,
        origin,
        rays,
        rest: v.rest,
    }
}

/// Where on the ellipse's scale (1 on the outline) a face point (x, z) lies.
fn in_outline(x: f64, z: f64) -> f64 {
    ((x - CENTRE.0) / SEMI.0).powi(2) + ((z - CENTRE.1) / SEMI.1).powi(2)
}

/// The planar depth at which pixel `i`'s ray meets the plane y = `y`, and the point it meets.
fn meets_plane(s: &Seen, i: usize, y: f64) -> (f64, [f64; 3]) {
    let ray = s.rays[i];
    let t = (y - s.origin[1]) / ray[1];
    (t, std::array::from_fn(|a| s.origin[a] + t * ray[a]))
}

/// Where pixel `i`'s ray first meets the cylinder of radius `r` about the bar's axis.
fn meets_bar(s: &Seen, i: usize, r: f64) -> Option<[f64; 3]> {
    let (o, d) = (s.origin, s.rays[i]);
    let (oy, oz) = (o[1] - BAR.0, o[2] - BAR.1);
    let (a, b, c) = (
        d[1] * d[1] + d[2] * d[2],
        2.0 * (oy * d[1] + oz * d[2]),
        oy * oy + oz * oz - r * r,
    );
    let disc = b * b - 4.0 * a * c;
    (disc >= 0.0).then(|| {
        let t = (-b - disc.sqrt()) / (2.0 * a);
        std::array::from_fn(|k| o[k] + t * d[k])
    })
}

#[test]
fn a_spall_is_a_cavity_whose_floor_is_at_its_depth_with_bars_on_their_cylinders() {
    let (_dir, out) = render(&RECIPE.replace("SPALL", SPALL), &[]);
    let s = seen(&out);
    let floor_y = FACE_Y + DEPTH;
    let to_axis = |p: [f64; 3]| (p[1] - BAR.0).hypot(p[2] - BAR.1);
    // The bar is a 12-gon: its faces lie between r cos 15° and r from the axis.
    let inscribed = BAR.2 * (std::f64::consts::PI / 12.0).cos();
    let (mut floor, mut bar, mut face) = (0, 0, 0);
    for i in 0..s.depth.len() {
        let (floor_depth, on_floor) = meets_plane(&s, i, floor_y);
        let (_, on_face) = meets_plane(&s, i, FACE_Y);
        // No holes: every ray through the beam's side meets the mesh, cut or not.
        if on_face[0].abs() < 1.9 && on_face[2].abs() < 0.24 {
            assert!(
                s.depth[i] > 0.0 && s.depth[i].is_finite(),
                "pixel {i} through the face at {on_face:?} met nothing"
            );
        }
        let Some(rest) = s.rest[i] else { continue };
        if let Some(hit) = meets_bar(&s, i, inscribed)
            && in_outline(hit[0], hit[2]) < 0.9
        {
            // A ray that meets the bar's inscribed cylinder inside the cavity: its pixel
            // back-projects onto the bar and is labelled the spall, drawn as rusty steel.
            let r = to_axis(rest);
            assert!(
                r > inscribed - 2e-4 && r < BAR.2 + 2e-4,
                "pixel {i}: r = {r} at {rest:?}"
            );
            assert_eq!((s.class[i], s.instance[i]), (5, 1), "pixel {i}");
            let [red, _, blue] = [0, 1, 2].map(|c| s.rgb[3 * i + c]);
            assert!(red > blue, "pixel {i}: rgb {red} {blue}");
            bar += 1;
            continue;
        }
        if to_axis(rest) < BAR.2 + 2e-4 {
            continue; // the bar's silhouette
        }
        if in_outline(on_floor[0], on_floor[2]) < 0.7 {
            // Inside the outline (away from its walls): the floor, at the analytic depth.
            assert!(
                (f64::from(s.depth[i]) - floor_depth).abs() < 1e-4,
                "pixel {i}: depth {} vs the floor's {floor_depth}",
                s.depth[i]
            );
            assert!((rest[1] - floor_y).abs() < 1e-4, "{rest:?}");
            assert_eq!((s.class[i], s.instance[i]), (5, 1), "pixel {i}");
            floor += 1;
        } else if in_outline(on_face[0], on_face[2]) > 1.3 && s.class[i] == 0 {
            face += 1;
        }
    }
    assert!(
        floor > 2000 && bar > 100 && face > 10_000,
        "{floor} {bar} {face}"
    );
}

#[test]
fn a_dent_is_a_bowl_of_its_depth_whose_normals_tilt_by_its_slope() {
    let (a, radius, centre) = (0.02, 0.15, (0.0, 0.05));
    let dent =
        r#".dent(#{ at: 2.0, face: "side_neg_y", height: 0.05, radius: 0.15, depth: 0.02 })"#;
    let (_dir, out) = render(&RECIPE.replace("SPALL", dent), &[]);
    let s = seen(&out);
    let at = |p: [f64; 3]| ((p[0] - centre.0).powi(2) + (p[2] - centre.1).powi(2)).sqrt() / radius;
    let angle = |u: [f64; 3], v: [f64; 3]| {
        let dot: f64 = (0..3).map(|k| u[k] * v[k]).sum();
        dot.clamp(-1.0, 1.0).acos().to_degrees()
    };
    // The face's own normal, from the pixels well off the dent.
    let flat = (0..s.depth.len())
        .find(|&i| s.rest[i].is_some_and(|p| at(p) > 1.5 && p[2].abs() < 0.2))
        .map(|i| s.normals[i])
        .unwrap();
    let (mut bowl, mut rim, mut centre_checked) = (0, 0, false);
    for i in 0..s.depth.len() {
        let Some(rest) = s.rest[i] else { continue };
        if (rest[1] - FACE_Y).abs() > 0.03 {
            continue;
        }
        let t = at(rest);
        let want = if t < 1.0 {
            a * (1.0 - t * t).powi(2)
        } else {
            0.0
        };
        // On the bowl to its interpolation error: 24 cells a diameter, a cell's diagonal d =
        // 17.7 mm, the bowl's curvature at most 8a/R² (at its rim): d²κ/8 = 2.8e-4 m.
        assert!(
            (rest[1] - FACE_Y - want).abs() < 3e-4,
            "pixel {i} at r/R = {t}: pushed {} vs {want}",
            rest[1] - FACE_Y
        );
        bowl += usize::from(t < 1.0);
        if t < 0.02 {
            let (face_depth, _) = meets_plane(&s, i, FACE_Y);
            let dz = f64::from(s.depth[i]) - face_depth;
            assert!(
                (dz - a).abs() < 2e-4,
                "pixel {i}: depth below the face {dz}"
            );
            centre_checked = true;
        }
        if (0.45..0.7).contains(&t) {
            // The slope of the bowl there, d/dr of a(1 − r²/R²)²: 4 a r/R² (1 − r²/R²).
            let r = t * radius;
            let slope = 4.0 * a * r / (radius * radius) * (1.0 - t * t);
            let tilt = angle(s.normals[i], flat);
            assert!(
                (tilt - slope.atan().to_degrees()).abs() < 1.5,
                "pixel {i} at r/R = {t}: tilt {tilt}° vs {}°",
                slope.atan().to_degrees()
            );
            rim += 1;
        }
        if t < 1.0 {
            assert_eq!((s.class[i], s.instance[i]), (6, 1), "pixel {i}");
        }
    }
    assert!(centre_checked && bowl > 3000 && rim > 500, "{bowl} {rim}");
}
