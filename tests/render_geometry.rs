//! Rendered geometry against independent truth: analytic ray–box intersection, projected
//! triangles, and back-projection onto the mesh.

use glam::{DMat3, DVec2, DVec3};
use shmgen::build::mesh_beam;
use shmgen::cameras::{Camera, CameraRig, Distance, Intrinsics, Orbit, Poses};
use shmgen::geometry::Mesh;
use shmgen::mechanics::{Load, Section, Support, Target, Theory};
use shmgen::render::{NO_HIT, PixelSet, TraceMesh};
use shmgen::scene::{BeamSpec, Tessellation};
use shmgen::seeds::{Scope, Stream};

const HALF: DVec3 = DVec3::new(2.0, 0.3, 0.45);

/// The undeformed beam is exactly the box [−HALF, HALF] moved to `centre`.
fn box_mesh(centre: DVec3) -> Mesh {
    let mut b = BeamSpec::rectangular(2.0 * HALF.x, 2.0 * HALF.y, 2.0 * HALF.z);
    b.tessellation = Tessellation::Segments(7);
    b.centre = centre.to_array();
    mesh_beam(&b, 1e-3).unwrap().mesh
}

/// Planar depth of the first intersection of the pixel ray with the box (slab method, f64).
fn analytic_box_depth(cam: &Camera, row: u32, col: u32, centre: DVec3) -> Option<f64> {
    analytic_box_depth_at(cam, f64::from(col) + 0.5, f64::from(row) + 0.5, centre)
}

/// The same through any image point (u, v).
fn analytic_box_depth_at(cam: &Camera, u: f64, v: f64, centre: DVec3) -> Option<f64> {
    let d = cam.rotation * cam.intrinsics.ray_through(u, v);
    let o = cam.position - centre;
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for axis in 0..3 {
        if d[axis] == 0.0 {
            if o[axis].abs() > HALF[axis] {
                return None;
            }
            continue;
        }
        let (a, b) = (
            (-HALF[axis] - o[axis]) / d[axis],
            (HALF[axis] - o[axis]) / d[axis],
        );
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1 && t0 > 0.0).then_some(t0)
}

fn box_edges(centre: DVec3) -> Vec<(DVec3, DVec3)> {
    let corner = |i: u32| {
        centre
            + DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            ) * HALF
    };
    let mut edges = Vec::new();
    for i in 0..8u32 {
        for bit in [1, 2, 4] {
            if i & bit == 0 {
                edges.push((corner(i), corner(i | bit)));
            }
        }
    }
    edges
}

fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    p.distance(a + t * ab)
}

fn check_box_view(cam: &Camera, centre: DVec3, min_hits: usize) {
    let mesh = TraceMesh::build(&box_mesh(centre));
    let g = mesh.trace(cam);
    let k = cam.intrinsics;
    let edges: Vec<(DVec2, DVec2)> = box_edges(centre)
        .iter()
        .map(|(a, b)| {
            let (pa, pb) = (
                k.project(cam.world_to_camera(*a)),
                k.project(cam.world_to_camera(*b)),
            );
            (DVec2::new(pa.0, pa.1), DVec2::new(pb.0, pb.1))
        })
        .collect();
    let (mut hits, mut near_edge) = (0, 0);
    for row in 0..k.height {
        for col in 0..k.width {
            let i = (row * k.width + col) as usize;
            let centre_px = DVec2::new(f64::from(col) + 0.5, f64::from(row) + 0.5);
            let truth = analytic_box_depth(cam, row, col, centre);
            let z = g.depth[i];
            assert!(z.is_finite() && z >= 0.0);
            assert_eq!(z == 0.0, g.triangle[i] == NO_HIT);
            if let (Some(t), true) = (truth, z > 0.0) {
                hits += 1;
                assert!(
                    (f64::from(z) - t).abs() <= 1e-5 * t,
                    "pixel ({row},{col}): depth {z} vs analytic {t}"
                );
            } else if truth.is_some() != (z > 0.0) {
                let d = edges
                    .iter()
                    .map(|(a, b)| segment_distance(centre_px, *a, *b))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    d < 1e-3,
                    "pixel ({row},{col}) mask {} vs analytic {}, {d} px from an edge",
                    z > 0.0,
                    truth.is_some()
                );
                near_edge += 1;
            }
        }
    }
    assert!(
        hits >= min_hits,
        "the box must fill part of the view ({hits} hits)"
    );
    assert!(near_edge < 10);
}

#[test]
fn narrow_fields_of_view_are_exact() {
    // A camera framing the box from far away: at 1e-8 rad it stands 1.6e8 m off. Rays start
    // in f32 only where they reach the box's bounding sphere, and depths come from the
    // triangles' planes in f64, so masks and depths stay exact.
    let centre = DVec3::new(3.0, -2.0, 1.0);
    for fov in [1e-4, 1e-6, 1e-7, 1e-8] {
        let k = Intrinsics::from_fov_y(96, 96, fov);
        let distance = 1.05 * HALF.length() / (0.5 * fov).sin();
        let draw = Orbit {
            yaw: 0.6,
            pitch: 0.3,
            roll: 0.2,
            distance,
        };
        let cam = shmgen::cameras::orbit_camera(k, centre, &draw);
        check_box_view(&cam, centre, 1500);
    }
}

/// A closed solid (the beam box) seen from inside: every wall is turned away from the camera,
/// so leaving out the triangles of a solid seen from behind, which is right only for a camera
/// outside it, would leave the view empty. Every pixel must see the far wall, along the x
/// axis 2.0 m off, at its exact planar depth.
#[test]
fn a_camera_inside_a_closed_solid_sees_its_walls() {
    let mesh = box_mesh(DVec3::ZERO);
    assert_eq!(mesh.solids().count, 1, "the box is a closed solid");
    let trace = TraceMesh::build(&mesh);
    let k = Intrinsics::from_fov_y(64, 48, 0.2);
    let cam = Camera::look_at(k, DVec3::ZERO, DVec3::X, DVec3::Z);
    let g = trace.trace(&cam);
    for (i, (&tri, &depth)) in g.triangle.iter().zip(&g.depth).enumerate() {
        assert_ne!(tri, NO_HIT, "pixel {i}");
        assert!((f64::from(depth) - 2.0).abs() < 1e-6, "pixel {i}: {depth}");
    }
}

fn paper_intrinsics() -> Intrinsics {
    Intrinsics::from_fov_y(960, 960, std::f64::consts::FRAC_PI_3)
}

#[test]
fn box_head_on_depth_and_mask_match_analytic_geometry() {
    let k = paper_intrinsics();
    let cam = Camera::look_at(k, DVec3::new(0.0, -7.0, 0.0), DVec3::ZERO, DVec3::Z);
    check_box_view(&cam, DVec3::ZERO, 2000);
}

#[test]
fn box_oblique_depth_and_mask_match_analytic_geometry() {
    let k = paper_intrinsics();
    let cam = Camera::look_at(
        k,
        DVec3::new(4.1, -3.3, 2.7),
        DVec3::new(0.2, 0.1, -0.1),
        DVec3::Z,
    );
    check_box_view(&cam, DVec3::ZERO, 2000);
}

#[test]
fn box_one_kilometre_from_the_origin_keeps_its_accuracy() {
    let centre = DVec3::new(1000.0, -700.0, 30.0);
    let k = paper_intrinsics();
    let cam = Camera::look_at(k, centre + DVec3::new(3.9, -3.1, 2.2), centre, DVec3::Z);
    check_box_view(&cam, centre, 2000);
}

#[test]
fn grazing_view_along_a_face_has_no_nan_and_matches_the_box() {
    // The camera sits exactly in the plane of the top face.
    let k = Intrinsics::from_fov_y(320, 240, 1.0);
    let cam = Camera::look_at(
        k,
        DVec3::new(-8.0, 0.0, HALF.z),
        DVec3::new(0.0, 0.0, HALF.z),
        DVec3::Z,
    );
    check_box_view(&cam, DVec3::ZERO, 500);
}

fn deformed_beams() -> Vec<BeamSpec> {
    let target = |b: &mut BeamSpec, at: f64, deflection: f64| {
        b.loads = vec![Load::Point { at, force: 1.0 }];
        b.target = Target::Peak { deflection };
    };
    let mut cantilever = BeamSpec::rectangular(3.0, 0.2, 0.35);
    cantilever.support = Support::Cantilever;
    target(&mut cantilever, 2.0, 0.6);
    let mut ss = BeamSpec::new(
        5.0,
        Section::ISection {
            width: 0.3,
            height: 0.5,
            flange: 0.03,
            web: 0.02,
        },
    );
    target(&mut ss, 1e-9, 0.25); // load next to the pin
    // Timoshenko theory turns a load 1e-9 m from a pin into a shear step there and is refused
    // (docs/mechanics.md §5.3); Euler–Bernoulli keeps the shape smooth.
    ss.theory = Theory::EulerBernoulli;
    ss.yaw = 0.7;
    ss.centre = [0.3, -0.2, 1.0];
    let mut stocky = BeamSpec::new(
        1.0,
        Section::HollowBox {
            width: 0.6,
            height: 1.2,
            wall: 0.08,
        },
    );
    stocky.support = Support::FixedFixed;
    target(&mut stocky, 0.5, 0.05);
    let mut tube = BeamSpec::new(
        4.0,
        Section::CircularHollow {
            diameter: 0.4,
            wall: 0.05,
        },
    );
    tube.support = Support::ProppedCantilever;
    tube.loads = vec![Load::Distributed {
        from: 0.0,
        to: 4.0,
        intensity: 1.0,
    }];
    tube.target = Target::Peak { deflection: 0.3 };
    vec![cantilever, ss, stocky, tube]
}

fn built(beam: &BeamSpec) -> Mesh {
    mesh_beam(beam, 2e-3).unwrap().mesh
}

/// Pixel centres strictly inside a projected triangle (more than 1e-3 px from its edges) must
/// see a surface: a background pixel there is a hole.
fn holes(mesh: &Mesh, trace: &TraceMesh, cam: &Camera) -> usize {
    let g = trace.trace(cam);
    let k = cam.intrinsics;
    let mut holes = 0;
    for t in 0..mesh.triangles.len() {
        let p = mesh.triangle(t).map(|v| {
            let (u, v) = k.project(cam.world_to_camera(v));
            DVec2::new(u, v)
        });
        let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        if area.abs() < 1e-9 {
            continue;
        }
        let lo = p[0].min(p[1]).min(p[2]).max(DVec2::ZERO);
        let hi = p[0]
            .max(p[1])
            .max(p[2])
            .min(DVec2::new(f64::from(k.width), f64::from(k.height)));
        for row in (lo.y.floor() as u32)..(hi.y.ceil() as u32).min(k.height) {
            for col in (lo.x.floor() as u32)..(hi.x.ceil() as u32).min(k.width) {
                let c = DVec2::new(f64::from(col) + 0.5, f64::from(row) + 0.5);
                let inside = (0..3).all(|e| {
                    let (a, b) = (p[e], p[(e + 1) % 3]);
                    area.signum() * (b - a).perp_dot(c - a) / (b - a).length() > 1e-3
                });
                if inside && g.triangle[(row * k.width + col) as usize] == NO_HIT {
                    holes += 1;
                }
            }
        }
    }
    holes
}

#[test]
fn closed_meshes_have_no_holes_from_200_cameras_including_the_poles() {
    let rig = CameraRig {
        width: 160,
        height: 120,
        poses: Poses::Sphere {
            yaw: [0.0, std::f64::consts::TAU],
            pitch: [-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2],
            roll: [0.0, 0.0],
            distance: Distance::Frame { margin: 1.1 },
        },
        ..CameraRig::default()
    };
    for (b, beam) in deformed_beams().iter().enumerate() {
        let mesh = built(beam);
        let trace = TraceMesh::build(&mesh);
        let (centre, radius) = mesh.bounding_sphere().unwrap();
        for view in 0..200u32 {
            let cam = match view {
                // Exact poles and a camera exactly along the beam axis.
                0 => shmgen::cameras::orbit_camera(
                    rig.intrinsics(),
                    centre,
                    &Orbit {
                        yaw: 0.3,
                        pitch: std::f64::consts::FRAC_PI_2,
                        roll: 0.0,
                        distance: 3.0 * radius,
                    },
                ),
                1 => shmgen::cameras::orbit_camera(
                    rig.intrinsics(),
                    centre,
                    &Orbit {
                        yaw: 2.0,
                        pitch: -std::f64::consts::FRAC_PI_2,
                        roll: 0.4,
                        distance: 3.0 * radius,
                    },
                ),
                2 => shmgen::cameras::orbit_camera(
                    rig.intrinsics(),
                    centre,
                    &Orbit {
                        yaw: 0.0,
                        pitch: 0.0,
                        roll: 0.0,
                        distance: 3.0 * radius,
                    },
                ),
                _ => {
                    rig.draw(
                        &mut Stream::new(11, Scope::View(b as u64, view), "camera"),
                        0,
                        1,
                        centre,
                        radius,
                    )
                    .unwrap()
                    .0
                }
            };
            assert_eq!(holes(&mesh, &trace, &cam), 0, "beam {b}, view {view}");
        }
    }
}

/// Distance from `p` to triangle (a, b, c) (Ericson, Real-Time Collision Detection §5.1.5).
fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let n = (b - a).cross(c - a).normalize();
    let q = p - n * n.dot(p - a);
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| (v - u).cross(q - u).dot(n) >= -1e-12);
    if inside {
        return (p - q).length();
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|&(u, v)| {
            let t = ((p - u).dot(v - u) / (v - u).length_squared()).clamp(0.0, 1.0);
            p.distance(u + t * (v - u))
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn back_projected_depth_lies_on_the_mesh() {
    let rig = CameraRig {
        width: 240,
        height: 180,
        ..CameraRig::default()
    };
    for (b, beam) in deformed_beams().iter().enumerate() {
        let mesh = built(beam);
        let trace = TraceMesh::build(&mesh);
        let (lo, hi) = mesh.bounds().unwrap();
        let centre = 0.5 * (lo + hi);
        let size = (hi - lo).length();
        for view in 0..6u32 {
            let (cam, _) = rig
                .draw(
                    &mut Stream::new(5, Scope::View(b as u64, view), "camera"),
                    0,
                    1,
                    centre,
                    0.5 * size,
                )
                .unwrap();
            let g = trace.trace(&cam);
            let k = cam.intrinsics;
            let c2w = cam.c2w_cv();
            let mut worst: f64 = 0.0;
            for (i, &z) in g.depth.iter().enumerate() {
                if z == 0.0 {
                    continue;
                }
                let (row, col) = ((i as u32) / k.width, (i as u32) % k.width);
                let z = f64::from(z);
                let x_cam = DVec3::new(
                    (f64::from(col) + 0.5 - k.cx) * z / k.fx,
                    (f64::from(row) + 0.5 - k.cy) * z / k.fy,
                    z,
                );
                let world = c2w.transform_point3(x_cam);
                let [a, bb, c] = mesh.triangle(g.triangle[i] as usize);
                worst = worst.max(point_triangle_distance(world, a, bb, c));
            }
            assert!(
                worst < 1e-5 * size,
                "beam {b} view {view}: back-projection off the surface by {worst} m"
            );
        }
    }
}

#[test]
fn rotation_of_the_rig_is_a_proper_rotation() {
    let cam = Camera::look_at(
        paper_intrinsics(),
        DVec3::new(1.0, 2.0, 3.0),
        DVec3::ZERO,
        DVec3::Z,
    );
    let r: DMat3 = cam.rotation;
    assert!((r.determinant() - 1.0).abs() < 1e-12);
}

fn sagging(length: f64, width: f64, height: f64, deflection: f64) -> BeamSpec {
    let mut b = BeamSpec::rectangular(length, width, height);
    b.loads = vec![Load::Point {
        at: 0.5 * length,
        force: 1.0,
    }];
    b.target = Target::Peak { deflection };
    b
}

/// Depth at the image centre, seen from exactly below the beam centre (a pole of the sphere).
fn depth_from_below(beam: &BeamSpec, distance: f64) -> f64 {
    let mesh = built(beam);
    let k = Intrinsics::from_fov_y(65, 65, 0.2);
    let centre = DVec3::from_array(beam.centre);
    let cam = shmgen::cameras::orbit_camera(
        k,
        centre,
        &Orbit {
            yaw: 0.0,
            pitch: -std::f64::consts::FRAC_PI_2,
            roll: 0.0,
            distance,
        },
    );
    let g = TraceMesh::build(&mesh).trace(&cam);
    f64::from(g.depth[32 * 65 + 32])
}

#[test]
fn a_deflection_of_a_millionth_of_the_span_is_visible_in_depth() {
    // L/h = 1000, δ = 1e-6 L. The bottom face at mid-span moves towards a camera below by δ.
    // Vertices are f32 relative to the mesh centre, so positions carry ~3e-8 L of rounding:
    // the tolerance is 10 % of δ.
    let (l, delta) = (1.0, 1e-6);
    let straight = depth_from_below(&sagging(l, 0.01, l / 1000.0, 0.0), 0.3);
    let bent = depth_from_below(&sagging(l, 0.01, l / 1000.0, delta), 0.3);
    assert!(straight > 0.0 && bent > 0.0);
    assert!(
        ((straight - bent) - delta).abs() < 0.1 * delta,
        "depth moved by {} for δ = {delta}",
        straight - bent
    );
}

#[test]
fn a_deformed_beam_one_kilometre_away_renders_like_one_at_the_origin() {
    let near = sagging(6.0, 0.2, 0.4, 0.3);
    let mut far = near.clone();
    far.centre = [1000.0, -800.0, 250.0];
    let rig = CameraRig {
        width: 200,
        height: 150,
        ..CameraRig::default()
    };
    let render = |b: &BeamSpec| {
        let mesh = built(b);
        let (centre, radius) = mesh.bounding_sphere().unwrap();
        let (cam, _) = rig
            .draw(
                &mut Stream::new(2, Scope::View(0, 0), "camera"),
                0,
                1,
                centre,
                radius,
            )
            .unwrap();
        TraceMesh::build(&mesh).trace(&cam)
    };
    let (a, b) = (render(&near), render(&far));
    let mut compared = 0;
    for i in 0..a.depth.len() {
        if a.depth[i] > 0.0 && b.depth[i] > 0.0 {
            compared += 1;
            assert!(
                (a.depth[i] - b.depth[i]).abs() <= 1e-5 * a.depth[i],
                "pixel {i}: {} vs {}",
                a.depth[i],
                b.depth[i]
            );
        }
    }
    let mismatched = a
        .depth
        .iter()
        .zip(&b.depth)
        .filter(|(x, y)| (**x > 0.0) != (**y > 0.0))
        .count();
    assert!(
        compared > 300 && mismatched <= 2,
        "{compared} compared, {mismatched} silhouette pixels differ"
    );
}

/// The RGB image of `mesh` through `cam` under the default studio light on black.
fn shaded_on_black(
    mesh: &TraceMesh,
    cam: &Camera,
    surfaces: &impl shmgen::render::Surfaces,
    antialias: bool,
) -> Vec<u8> {
    use shmgen::materials::{Backdrop, Lighting};
    let g = mesh.trace(cam);
    let black = Backdrop::Colour([0, 0, 0]);
    shmgen::render::shade(
        &g,
        mesh,
        cam,
        (&Lighting::default(), None),
        surfaces,
        &black,
        antialias,
    )
    .rgb
}

#[test]
fn rgb_edges_are_antialiased_by_the_covered_fraction_and_nothing_else_changes() {
    use shmgen::materials::srgb_to_linear;
    // Head-on, the box shows one face of uniform colour on black: a silhouette pixel's linear
    // value must be the face's times the fraction of the 2 × 2 sub-pixel rays that hit it.
    let k = Intrinsics::from_fov_y(240, 180, 0.8);
    let cam = Camera::look_at(
        k,
        DVec3::new(0.13, -9.0, 0.07),
        DVec3::new(0.13, 0.0, 0.07),
        DVec3::Z,
    );
    let mesh = TraceMesh::build(&box_mesh(DVec3::ZERO));
    let g = mesh.trace(&cam);
    let grey = |_| [0.5, 0.5, 0.5];
    let rgb = shaded_on_black(&mesh, &cam, &grey, true);
    let plain = shaded_on_black(&mesh, &cam, &grey, false);
    assert!(
        plain
            .iter()
            .all(|&c| c == 0 || c == plain.iter().copied().max().unwrap()),
        "without anti-aliasing: face or background only"
    );
    let face = (0..g.depth.len())
        .filter(|&i| g.depth[i] > 0.0)
        .map(|i| rgb[3 * i])
        .max()
        .unwrap();
    let face_linear = srgb_to_linear(f64::from(face) / 255.0);
    let (mut partial, mut interior) = (0, 0);
    for row in 0..k.height {
        for col in 0..k.width {
            let covered = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)]
                .iter()
                .filter(|(du, dv)| {
                    analytic_box_depth_at(
                        &cam,
                        f64::from(col) + du,
                        f64::from(row) + dv,
                        DVec3::ZERO,
                    )
                    .is_some()
                })
                .count();
            let got = rgb[3 * (row * k.width + col) as usize];
            let want = face_linear * covered as f64 / 4.0;
            let got_linear = srgb_to_linear(f64::from(got) / 255.0);
            match covered {
                0 => assert_eq!(got, 0, "({row},{col}) is background"),
                4 => {
                    interior += 1;
                    assert_eq!(got, face, "({row},{col}) is inside the face");
                }
                _ => {
                    partial += 1;
                    assert!(
                        (got_linear - want).abs() < 0.01,
                        "({row},{col}): {got_linear} vs {want} ({covered}/4 covered)"
                    );
                }
            }
        }
    }
    assert!(
        partial > 100 && interior > 1000,
        "{partial} partial, {interior} interior pixels"
    );
}

/// The axis (0–2) along which `v` is longest.
fn dominant_axis(v: DVec3) -> usize {
    let v = v.abs();
    (0..3).max_by(|&a, &b| v[a].total_cmp(&v[b])).unwrap()
}

/// The axis (0–2) of the box face the ray through image point (u, v) meets first, if any.
fn analytic_box_face(cam: &Camera, u: f64, v: f64) -> Option<usize> {
    let t = analytic_box_depth_at(cam, u, v, DVec3::ZERO)?;
    let p = cam.position + cam.rotation * cam.intrinsics.ray_through(u, v) * t;
    Some(dominant_axis(p / HALF))
}

/// The fixed sub-pixel positions of anti-aliasing's rays.
const SUB_POINTS: [(f64, f64); 4] = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];

/// The face of the box (by axis) each sub-ray of pixel (row, col) meets, analytically.
fn sub_ray_faces(cam: &Camera, row: u32, col: u32) -> [Option<usize>; 4] {
    SUB_POINTS.map(|(du, dv)| analytic_box_face(cam, f64::from(col) + du, f64::from(row) + dv))
}

/// The face all four sub-rays of pixel (row, col) meet, if they meet one.
fn whole_face(cam: &Camera, row: u32, col: u32) -> Option<usize> {
    match sub_ray_faces(cam, row, col) {
        [Some(f), a, b, c] if [a, b, c] == [Some(f); 3] => Some(f),
        _ => None,
    }
}

/// Every pixel whose sub-rays meet two faces or more, with the face of each sub-ray.
fn crease_pixels(cam: &Camera) -> Vec<(u32, u32, [Option<usize>; 4])> {
    let k = cam.intrinsics;
    (0..k.height)
        .flat_map(|row| (0..k.width).map(move |col| (row, col)))
        .map(|(row, col)| (row, col, sub_ray_faces(cam, row, col)))
        .filter(|(_, _, faces)| {
            let distinct = faces
                .iter()
                .flatten()
                .collect::<std::collections::BTreeSet<_>>();
            distinct.len() >= 2
        })
        .collect()
}

#[test]
fn crease_pixels_mix_the_faces_their_sub_rays_meet() {
    use shmgen::materials::srgb_to_linear;
    // Seen obliquely, three faces of the box meet at creases; each face has its own flat
    // albedo, so a crease pixel's linear value must be the mean over its 2 × 2 sub-rays of the
    // face each meets (analytically), however the shading is shared among them.
    let k = Intrinsics::from_fov_y(200, 150, 0.9);
    let cam = Camera::look_at(k, DVec3::new(3.0, -6.0, 3.5), DVec3::ZERO, DVec3::Z);
    let mesh = TraceMesh::build(&box_mesh(DVec3::ZERO));
    let albedo = |tri: u32| [[0.8; 3], [0.35; 3], [0.08; 3]][dominant_axis(mesh.normal(tri))];
    let rgb = shaded_on_black(&mesh, &cam, &albedo, true);
    // Each face's shade, from pixels wholly inside it.
    let mut face_linear = [None; 3];
    for row in 0..k.height {
        for col in 0..k.width {
            if let Some(f) = whole_face(&cam, row, col) {
                let got = rgb[3 * (row * k.width + col) as usize];
                face_linear[f] = Some(srgb_to_linear(f64::from(got) / 255.0));
            }
        }
    }
    let face_linear = face_linear.map(|f| f.expect("every face seen"));
    let creases = crease_pixels(&cam);
    for &(row, col, faces) in &creases {
        let want: f64 = faces
            .iter()
            .map(|f| f.map_or(0.0, |f| face_linear[f]))
            .sum::<f64>()
            / 4.0;
        let got = srgb_to_linear(f64::from(rgb[3 * (row * k.width + col) as usize]) / 255.0);
        assert!(
            (got - want).abs() < 0.01,
            "({row},{col}): {got} vs {want}, faces {faces:?}"
        );
    }
    assert!(creases.len() > 40, "{} crease pixels", creases.len());
}

/// Depth bits and triangle of every pixel when each centre ray is traced on its own, with no
/// culling: what tiled, culled tracing must reproduce exactly.
fn one_ray_per_pixel(trace: &TraceMesh, cam: &Camera) -> (Vec<u32>, Vec<u32>) {
    let k = cam.intrinsics;
    let pixels = (0..k.height).flat_map(|row| (0..k.width).map(move |col| (row, col)));
    pixels
        .map(
            |(row, col)| match trace.first_hit(cam, k.ray_through_pixel(row, col)) {
                Some((depth, tri)) => (depth.to_bits(), tri),
                None => (0.0f32.to_bits(), NO_HIT),
            },
        )
        .unzip()
}

/// Distance in pixels from image point `c` to the nearest edge of triangle `t`'s projection.
fn edge_distance(mesh: &Mesh, t: u32, cam: &Camera, c: DVec2) -> f64 {
    let p = mesh.triangle(t as usize).map(|v| {
        let (u, v) = cam.intrinsics.project(cam.world_to_camera(v));
        DVec2::new(u, v)
    });
    (0..3)
        .map(|e| segment_distance(c, p[e], p[(e + 1) % 3]))
        .fold(f64::INFINITY, f64::min)
}

/// The view as `trace` gives it (rasterised, for a pinhole with the mesh in front) against
/// one ray per pixel: the same triangle and the same depth bits at every pixel, except where
/// the centre lies within a hundred-thousandth of a pixel of an edge of a triangle either saw
/// (f64 edge functions and the f32 ray test may decide such a graze differently).
fn rasterised_matches_traced(mesh: &Mesh, trace: &TraceMesh, cam: &Camera, c: usize) {
    let width = cam.intrinsics.width as usize;
    let pixels = width * cam.intrinsics.height as usize;
    assert!(
        mesh.triangles.len() <= 3 * pixels,
        "coarse enough to be rasterised"
    );
    let g = trace.trace(cam);
    let (want_depth, want_triangle) = one_ray_per_pixel(trace, cam);
    let mut grazes = 0;
    for (i, (&tri, &want)) in g.triangle.iter().zip(&want_triangle).enumerate() {
        if tri == want {
            assert_eq!(g.depth[i].to_bits(), want_depth[i], "camera {c}, pixel {i}");
            continue;
        }
        let centre = DVec2::new((i % width) as f64 + 0.5, (i / width) as f64 + 0.5);
        let near_edge = [tri, want]
            .iter()
            .filter(|&&t| t != NO_HIT)
            .any(|&t| edge_distance(mesh, t, cam, centre) < 1e-5);
        assert!(
            near_edge,
            "camera {c}, pixel {i}: {tri} rasterised, {want} traced"
        );
        grazes += 1;
    }
    assert!(
        grazes * 1000 <= g.triangle.len(),
        "camera {c}: {grazes} grazes"
    );
}

/// Cameras about a mesh at 203×117: near, at a pole, inside its bounding sphere, so far that
/// it is a speck, and through a distorting lens (last).
fn probing_cameras(mesh: &Mesh) -> Vec<Camera> {
    probing_cameras_of_size(mesh, (203, 117))
}

/// `probing_cameras` with images of `width` × `height` pixels.
fn probing_cameras_of_size(mesh: &Mesh, (width, height): (u32, u32)) -> Vec<Camera> {
    let mut lens = Intrinsics::from_fov_y(width, height, 1.1);
    lens.distortion.k1 = -0.04;
    lens.distortion.p2 = 0.002;
    let pinhole = Intrinsics::from_fov_y(width, height, 1.1);
    let (centre, radius) = mesh.bounding_sphere().unwrap();
    let orbit = |k, yaw: f64, pitch: f64, distance| {
        let o = Orbit {
            yaw,
            pitch,
            roll: 0.3,
            distance,
        };
        shmgen::cameras::orbit_camera(k, centre, &o)
    };
    vec![
        orbit(pinhole, 0.4, 0.3, 2.5 * radius),
        orbit(pinhole, 2.0, std::f64::consts::FRAC_PI_2, 3.0 * radius),
        orbit(pinhole, 1.0, -0.2, 0.6 * radius),
        orbit(pinhole, 5.0, 0.1, 40.0 * radius),
        orbit(lens, 0.8, 0.5, 2.0 * radius),
    ]
}

#[test]
fn tiled_culled_tracing_matches_one_ray_per_pixel() {
    for beam in deformed_beams() {
        let mesh = built(&beam);
        let trace = TraceMesh::build(&mesh);
        for (c, cam) in probing_cameras(&mesh).iter().enumerate() {
            let g = trace.trace_rays(cam);
            let depth: Vec<u32> = g.depth.iter().map(|d| d.to_bits()).collect();
            let (want_depth, want_triangle) = one_ray_per_pixel(&trace, cam);
            assert!(depth == want_depth, "camera {c}: depth");
            assert!(g.triangle == want_triangle, "camera {c}: triangles");
            assert!(
                want_triangle.contains(&NO_HIT),
                "camera {c} sees background"
            );
            assert!(
                want_triangle.iter().any(|&t| t != NO_HIT),
                "camera {c} sees the beam"
            );
        }
    }
}

#[test]
fn rasterised_views_match_one_ray_per_pixel() {
    for beam in deformed_beams() {
        // Coarse enough to be rasterised at 203×117 (meshes of over 3 triangles per pixel are
        // traced).
        let mesh = mesh_beam(&beam, 2e-2).unwrap().mesh;
        let trace = TraceMesh::build(&mesh);
        for (c, cam) in probing_cameras(&mesh).iter().enumerate() {
            rasterised_matches_traced(&mesh, &trace, cam, c);
        }
    }
}

/// Meshes with more triangles than the image has pixels (most triangles cover no pixel
/// centre, many pixels see several triangles' edges) are rasterised up to 3 triangles per
/// pixel, and must still find what one ray per pixel finds.
#[test]
fn meshes_finer_than_the_pixels_are_rasterised_exactly() {
    let beams = deformed_beams();
    // 1,196 and 2,024 triangles, seen at 31×18 = 558 and 40×23 = 920 pixels.
    let fine = [(&beams[1], 2e-3, (31, 18)), (&beams[3], 2e-2, (40, 23))];
    for (beam, tolerance, size) in fine {
        let mesh = mesh_beam(beam, tolerance).unwrap().mesh;
        assert!(mesh.triangles.len() > 2 * (size.0 * size.1) as usize);
        let trace = TraceMesh::build(&mesh);
        for (c, cam) in probing_cameras_of_size(&mesh, size).iter().enumerate() {
            rasterised_matches_traced(&mesh, &trace, cam, c);
        }
    }
}

/// Points within a pixel at which `sub_pixel_hits_match_one_ray_each` samples: the four of
/// anti-aliasing's pattern but one, and a pixel's corners on both sides (where two pixels'
/// samples meet).
const SUB_PIXEL_POINTS: [(f64, f64); 5] = [
    (0.25, 0.25),
    (0.75, 0.25),
    (0.25, 0.75),
    (0.0, 0.0),
    (1.0, 0.5),
];

/// The first hits of rays through points within pixels, as anti-aliasing asks for them (in
/// one call for many pixels, rasterised when that is exact and pays), against one ray per
/// point: the same triangle and depth bits at every point but grazes (within 10⁻⁵ px of an
/// edge of a triangle either saw), and at most one in a thousand of those. Every pixel of the
/// image, and a scattered fifth of them (so most triangles cover no pixel of the set).
#[test]
fn sub_pixel_hits_match_one_ray_each() {
    for beam in deformed_beams() {
        let mesh = mesh_beam(&beam, 2e-2).unwrap().mesh;
        let trace = TraceMesh::build(&mesh);
        for (c, cam) in probing_cameras(&mesh).iter().enumerate() {
            let k = cam.intrinsics;
            for every in [1, 5] {
                let rows: Vec<Vec<u32>> = (0..k.height)
                    .map(|row| {
                        (0..k.width)
                            .filter(|col| (row * 3 + col) % every == 0)
                            .collect()
                    })
                    .collect();
                let pixels = PixelSet::from_rows(&rows);
                let (hits, _) = trace.sample_hits(cam, &pixels, &SUB_PIXEL_POINTS);
                assert_eq!(hits.len(), pixels.len());
                let mut grazes = 0;
                for (i, samples) in hits.iter().enumerate() {
                    let (row, col) = pixels.at(i);
                    for (&got, (du, dv)) in samples.iter().zip(SUB_PIXEL_POINTS) {
                        let point = DVec2::new(col + du, row + dv);
                        let want = trace.first_hit(cam, k.ray_through(point.x, point.y));
                        if got.map(|(_, t)| t) == want.map(|(_, t)| t) {
                            let bits = |h: Option<(f32, u32)>| h.map(|(d, _)| d.to_bits());
                            assert_eq!(bits(got), bits(want), "camera {c}, {point}");
                            continue;
                        }
                        let near_edge = [got, want]
                            .iter()
                            .flatten()
                            .any(|&(_, t)| edge_distance(&mesh, t, cam, point) < 1e-5);
                        assert!(near_edge, "camera {c}, {point}: {got:?}, traced {want:?}");
                        grazes += 1;
                    }
                }
                assert!(grazes * 1000 <= hits.len(), "camera {c}: {grazes} grazes");
                assert!(
                    hits.iter().flatten().any(Option::is_none),
                    "camera {c}: background"
                );
                assert!(
                    hits.iter().flatten().any(Option::is_some),
                    "camera {c}: the beam"
                );
            }
        }
    }
}

/// Stripes across x on every face of the box, alternately light and dark every half
/// `STRIPE_PERIOD`: about a pixel wide in `edge_pixels_show_the_texture_their_centre_sees`, so
/// sub-rays of a pixel often land on other stripes than its centre.
const STRIPE_PERIOD: f64 = 0.09;

fn stripe(p: DVec3) -> f64 {
    if (p.x / STRIPE_PERIOD).rem_euclid(1.0) < 0.5 {
        0.8
    } else {
        0.1
    }
}

/// The box's faces, each textured with `stripe`; the material continues within a face only.
struct Striped<'a>(&'a TraceMesh);

impl shmgen::render::Surfaces for Striped<'_> {
    fn at(&self, _: u32, p: DVec3, _: f64) -> shmgen::materials::Surface {
        shmgen::materials::Surface {
            albedo: [stripe(p); 3],
            roughness: 1.0,
            specular: 0.0,
            crack: false,
        }
    }

    fn flat(&self, _: u32) -> [f64; 3] {
        [0.45; 3]
    }

    fn textured(&self, _: u32) -> bool {
        true
    }

    fn matte(&self, _: u32) -> bool {
        false
    }

    fn continues(&self, a: u32, b: u32) -> bool {
        dominant_axis(self.0.normal(a)) == dominant_axis(self.0.normal(b))
    }
}

#[test]
fn edge_pixels_show_the_texture_their_centre_sees() {
    use shmgen::materials::srgb_to_linear;
    // A textured face is filtered by its material over the whole pixel, so a crease pixel
    // must show on each face it meets the texture where the pixel's centre ray meets that
    // face's plane (what the pixel would show were the face all it saw), lit at each sub-ray:
    // its linear value is the mean over the 2 × 2 sub-rays of the face's irradiance times the
    // stripe at that centre point, all found analytically.
    let k = Intrinsics::from_fov_y(200, 150, 0.9);
    let cam = Camera::look_at(k, DVec3::new(3.0, -6.0, 3.5), DVec3::ZERO, DVec3::Z);
    let mesh = TraceMesh::build(&box_mesh(DVec3::ZERO));
    let rgb = shaded_on_black(&mesh, &cam, &Striped(&mesh), true);
    let linear = |row: u32, col: u32| {
        srgb_to_linear(f64::from(rgb[3 * (row * k.width + col) as usize]) / 255.0)
    };
    let ray = |u: f64, v: f64| cam.rotation * k.ray_through(u, v);
    // Where the ray through (u, v) meets the plane of the face across `axis` the camera sees.
    let on_face_plane = |axis: usize, u: f64, v: f64| {
        let d = ray(u, v);
        let side = HALF[axis] * cam.position[axis].signum();
        cam.position + d * ((side - cam.position[axis]) / d[axis])
    };
    // Each face's irradiance, from pixels wholly inside it on a light stripe.
    let mut irradiance = [None; 3];
    for row in 0..k.height {
        for col in 0..k.width {
            let (u, v) = (f64::from(col) + 0.5, f64::from(row) + 0.5);
            if let Some(f) = whole_face(&cam, row, col)
                && stripe(on_face_plane(f, u, v)) == 0.8
            {
                irradiance[f] = Some(linear(row, col) / 0.8);
            }
        }
    }
    let irradiance = irradiance.map(|e| e.expect("every face seen"));
    let creases = crease_pixels(&cam);
    let mut textured_differently = 0;
    for &(row, col, faces) in &creases {
        let (u, v) = (f64::from(col) + 0.5, f64::from(row) + 0.5);
        let want: f64 = faces
            .iter()
            .map(|f| f.map_or(0.0, |f| irradiance[f] * stripe(on_face_plane(f, u, v))))
            .sum::<f64>()
            / 4.0;
        let got = linear(row, col);
        assert!(
            (got - want).abs() < 0.01,
            "({row},{col}): {got} vs {want}, faces {faces:?}"
        );
        // Sub-rays that would have shown another stripe, had each been textured alone.
        if faces.iter().zip(SUB_POINTS).any(|(f, (du, dv))| {
            f.is_some_and(|f| {
                let own = on_face_plane(f, f64::from(col) + du, f64::from(row) + dv);
                stripe(own) != stripe(on_face_plane(f, u, v))
            })
        }) {
            textured_differently += 1;
        }
    }
    assert!(creases.len() > 40, "{} crease pixels", creases.len());
    assert!(
        textured_differently > 20,
        "{textured_differently} crease pixels whose sub-rays see other stripes than the centre"
    );
}

#[test]
fn only_untextured_surfaces_without_gloss_are_matte() {
    use shmgen::materials::{Base, Grain, Material, Shader};
    use shmgen::render::{SampleSurfaces, Surfaces};
    // One triangle per material: a plain matte colour, the same colour with a glint, and a
    // textured one. A glint moves with the eye and a texture with the point, so only the first
    // shows one radiance over a side under uniform light.
    let plain = Material::plain([0.5, 0.4, 0.3]);
    let glossy = Material {
        specular: 0.04,
        roughness: 0.3,
        ..plain.clone()
    };
    let textured = Material {
        base: Base::Concrete,
        ..plain.clone()
    };
    let mut stream = Stream::new(1, Scope::Sample(0), "material");
    let shaders: Vec<Shader> = [plain, glossy, textured]
        .iter()
        .map(|m| Shader::new(m, &mut stream))
        .collect();
    let mesh = Mesh {
        positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
        triangles: vec![[0, 1, 2]; 3],
    };
    let grain = Grain {
        axis: DVec3::X,
        centre: DVec3::ZERO,
        bottom: 0.0,
        top: 1.0,
    };
    let pieces: Vec<(u32, Grain)> = (0..3).map(|s| (s, grain)).collect();
    let surfaces = SampleSurfaces {
        mesh: &mesh,
        rest: &mesh.positions,
        piece: &[0, 1, 2],
        pieces: &pieces,
        shaders: &shaders,
        cache: None,
    };
    assert!(surfaces.matte(0));
    assert!(!surfaces.matte(1), "a glint is not the same everywhere");
    assert!(!surfaces.matte(2), "a texture is not the same everywhere");
}
