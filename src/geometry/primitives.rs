//! Solid primitives for building structures in recipes: box, frustum (cylinder, cone), tube
//! (ring), spherical cap, and extrusions of a polygon along a straight or circular path.
//! Each is a section outline swept through frames, tessellated so that no chord strays more
//! than the given tolerance from the true surface — the same rule as beams.

use super::Mesh;
use super::outline::{annulus, circle, circle_segments, disc, polygon, rectangle};
use super::sweep::{Frame3, sweep};
use glam::DVec3;
use serde::Serialize;
use std::sync::Arc;

/// A primitive in its own frame (z up).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Primitive {
    /// Centred on the origin.
    Box {
        /// Edge lengths along x, y and z (width, depth, height), metres.
        size: [f64; 3],
    },
    /// Base circle at z = 0, top circle at z = height; a cylinder when the radii are equal, a
    /// cone when the top radius is 0.
    Frustum {
        /// Radius of the base circle at z = 0, metres.
        bottom_radius: f64,
        /// Radius of the top circle, metres (0 for a cone).
        top_radius: f64,
        /// Height along z, metres.
        height: f64,
    },
    /// Hollow cylinder (a ring when short): outer radius and wall, base at z = 0.
    Tube {
        /// Outer radius, metres.
        radius: f64,
        /// Height along z, metres.
        height: f64,
        /// Wall thickness, metres (less than the radius).
        wall: f64,
    },
    /// The cap of a sphere of `radius`, `height` tall, its base circle at z = 0.
    SphericalCap {
        /// Radius of the sphere, metres.
        radius: f64,
        /// Height of the cap above its base circle, metres (at most the sphere's diameter).
        height: f64,
    },
    /// A simple polygon in the (x, y) plane extruded along +z.
    Extrusion {
        /// Vertices (x, y) of the polygon, metres, in order around it.
        profile: Vec<[f64; 2]>,
        /// Length of the extrusion along +z, metres.
        length: f64,
    },
    /// A simple polygon swept along a circular arc that starts at the origin heading +z and
    /// bends towards +x with the given radius, through `angle` radians.
    Bend {
        /// Vertices (x, y) of the polygon, metres, in order around it; every x below `radius`.
        profile: Vec<[f64; 2]>,
        /// Radius of the arc the profile's origin follows, metres; its centre is at (radius, 0, 0).
        radius: f64,
        /// Angle swept, radians.
        angle: f64,
    },
    /// A mesh read from a file (path relative to the recipe), optionally normalised as in the
    /// 3DGEN paper (bounding box centred, diagonal 1).
    Imported {
        /// Path of the mesh file (OBJ, PLY, STL or glTF) relative to the recipe's folder.
        file: String,
        /// Whether the mesh was normalised: bounding box centred on the origin, its diagonal scaled
        /// to 1.
        normalize: bool,
        /// The mesh as read (not recorded).
        #[serde(skip)]
        mesh: Arc<Mesh>,
    },
}

impl Primitive {
    /// Checks dimensions; the message names the primitive, the parameter and its value.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |what: &str, x: f64| {
            if x > 0.0 && x.is_finite() {
                Ok(())
            } else {
                Err(format!(
                    "{} {what} = {x} must be positive (metres)",
                    self.name()
                ))
            }
        };
        match self {
            Primitive::Box { size } => size
                .iter()
                .zip(["width", "depth", "height"])
                .try_for_each(|(&x, n)| positive(n, x)),
            Primitive::Frustum {
                bottom_radius,
                top_radius,
                height,
            } => {
                positive("height", *height)?;
                positive("bottom_radius", *bottom_radius)?;
                if !(*top_radius >= 0.0 && top_radius.is_finite()) {
                    return Err(format!(
                        "{} top_radius = {top_radius} must be zero or positive (metres)",
                        self.name()
                    ));
                }
                Ok(())
            }
            Primitive::Tube {
                radius,
                height,
                wall,
            } => {
                positive("radius", *radius)?;
                positive("height", *height)?;
                positive("wall", *wall)?;
                if wall >= radius {
                    Err(format!(
                        "tube wall = {wall} m must be less than the radius ({radius} m)"
                    ))
                } else {
                    Ok(())
                }
            }
            Primitive::SphericalCap { radius, height } => {
                positive("radius", *radius)?;
                positive("height", *height)?;
                if height > &(2.0 * radius) {
                    Err(format!(
                        "cap height = {height} m must not exceed the sphere's diameter ({} m)",
                        2.0 * radius
                    ))
                } else {
                    Ok(())
                }
            }
            Primitive::Extrusion { profile, length } => {
                positive("length", *length)?;
                polygon(profile).map(drop)
            }
            Primitive::Bend {
                profile,
                radius,
                angle,
            } => {
                positive("radius", *radius)?;
                positive("angle", *angle)?;
                let reach = profile
                    .iter()
                    .map(|p| p[0])
                    .fold(f64::NEG_INFINITY, f64::max);
                if reach >= *radius {
                    return Err(format!(
                        "bend: the profile reaches x = {reach} m, past the bend radius {radius} m"
                    ));
                }
                polygon(profile).map(drop)
            }
            Primitive::Imported { .. } => Ok(()),
        }
    }

    fn name(&self) -> &'static str {
        match self {
            Primitive::Box { .. } => "box",
            Primitive::Frustum { .. } => "frustum",
            Primitive::Tube { .. } => "tube",
            Primitive::SphericalCap { .. } => "cap",
            Primitive::Extrusion { .. } => "extrusion",
            Primitive::Bend { .. } => "bend",
            Primitive::Imported { .. } => "mesh",
        }
    }

    /// Radius of a sphere about the local origin that contains the primitive.
    pub fn bounding_radius(&self) -> f64 {
        let far =
            |profile: &[[f64; 2]]| profile.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
        match self {
            Primitive::Box { size } => 0.5 * DVec3::from_array(*size).length(),
            Primitive::Frustum {
                bottom_radius,
                top_radius,
                height,
            } => bottom_radius.max(*top_radius).hypot(*height),
            Primitive::Tube { radius, height, .. } => radius.hypot(*height),
            Primitive::SphericalCap { radius, height } => radius.hypot(*height),
            Primitive::Extrusion { profile, length } => far(profile).hypot(*length),
            Primitive::Bend {
                profile, radius, ..
            } => 2.0 * radius + far(profile),
            Primitive::Imported { mesh, .. } => mesh
                .positions
                .iter()
                .map(|p| p.length())
                .fold(0.0, f64::max),
        }
    }

    /// The mesh, with chords within `tolerance` metres of curved surfaces. The primitive must
    /// be valid (see `validate`); fails when the mesh would exceed the triangle budget.
    pub fn mesh(&self, tolerance: f64) -> Result<Mesh, String> {
        match self {
            Primitive::Box { size: [w, d, h] } => sweep(
                &rectangle(*w, *d, 1),
                &straight(-0.5 * h, 0.5 * h, 1.0, 1.0, 1),
            ),
            Primitive::Frustum {
                bottom_radius,
                top_radius,
                height,
            } => {
                let disc = disc(circle_segments(bottom_radius.max(*top_radius), tolerance));
                sweep(
                    &disc,
                    &straight(0.0, *height, *bottom_radius, *top_radius, 1),
                )
            }
            Primitive::Tube { .. } => self.tube_mesh(tolerance, 1, 0).expect("a tube"),
            Primitive::SphericalCap { radius, height } => sweep(
                &disc(circle_segments(*radius, tolerance)),
                &cap_frames(*radius, *height, tolerance),
            ),
            Primitive::Extrusion { profile, length } => sweep(
                &polygon(profile).expect("validated"),
                &straight(0.0, *length, 1.0, 1.0, 1),
            ),
            Primitive::Bend {
                profile,
                radius,
                angle,
            } => {
                let reach = radius + profile.iter().map(|p| p[0].abs()).fold(0.0, f64::max);
                let steps = arc_steps(reach, *angle, tolerance);
                let frames = (0..=steps)
                    .map(|i| {
                        let (s, c) = (angle * i as f64 / steps as f64).sin_cos();
                        // Arc centre at (radius, 0, 0); u points along the outward normal of the
                        // arc's plane curve so that u × v is the tangent.
                        Frame3 {
                            origin: DVec3::new(radius * (1.0 - c), 0.0, radius * s),
                            u: DVec3::new(c, 0.0, -s),
                            v: DVec3::Y,
                        }
                    })
                    .collect::<Vec<_>>();
                sweep(&polygon(profile).expect("validated"), &frames)
            }
            Primitive::Imported { mesh, .. } => Ok((**mesh).clone()),
        }
    }
}

impl Primitive {
    /// A tube with at least `rings` intervals along its height and `segments` around it (for
    /// shell deformations that need them); None for other primitives.
    pub fn tube_mesh(
        &self,
        tolerance: f64,
        rings: usize,
        segments: usize,
    ) -> Option<Result<Mesh, String>> {
        let Primitive::Tube { radius, .. } = *self else {
            return None;
        };
        self.fixed_mesh(circle_segments(radius, tolerance).max(segments), rings)
    }

    /// Round primitives with exactly `segments` around and (tubes) `rings` along the height,
    /// for parity with meshes made elsewhere; None for the others.
    pub fn fixed_mesh(&self, segments: usize, rings: usize) -> Option<Result<Mesh, String>> {
        let n = segments.max(3);
        match *self {
            Primitive::Tube {
                radius,
                height,
                wall,
            } => Some(sweep(
                &annulus(circle(radius, n), circle(radius - wall, n)),
                &straight(0.0, height, 1.0, 1.0, rings),
            )),
            Primitive::Frustum {
                bottom_radius,
                top_radius,
                height,
            } => Some(sweep(
                &disc(n),
                &straight(0.0, height, bottom_radius, top_radius, 1),
            )),
            _ => None,
        }
    }
}

/// Frames from z0 to z1 along +z, `steps` intervals, whose (x, y) scale goes from s0 to s1.
fn straight(z0: f64, z1: f64, s0: f64, s1: f64, steps: usize) -> Vec<Frame3> {
    (0..=steps.max(1))
        .map(|i| {
            let f = i as f64 / steps.max(1) as f64;
            let s = s0 + (s1 - s0) * f;
            Frame3 {
                origin: DVec3::new(0.0, 0.0, z0 + (z1 - z0) * f),
                u: s * DVec3::X,
                v: s * DVec3::Y,
            }
        })
        .collect()
}

/// Latitude frames of a spherical cap, from its base circle up to the pole.
fn cap_frames(radius: f64, height: f64, tolerance: f64) -> Vec<Frame3> {
    let top = ((radius - height) / radius).clamp(-1.0, 1.0).acos();
    let steps = arc_steps(radius, top, tolerance);
    (0..=steps)
        .map(|i| {
            let theta = top * (1.0 - i as f64 / steps as f64);
            let (s, c) = theta.sin_cos();
            Frame3 {
                origin: DVec3::new(0.0, 0.0, height - radius + radius * c),
                u: radius * s * DVec3::X,
                v: radius * s * DVec3::Y,
            }
        })
        .collect()
}

/// Steps along an arc of `radius` through `angle` whose chords deviate by at most `tolerance`.
fn arc_steps(radius: f64, angle: f64, tolerance: f64) -> usize {
    let step = 2.0 * (1.0 - tolerance / radius).clamp(-1.0, 1.0).acos();
    let n = (angle / step).ceil();
    if n.is_finite() {
        (n as usize).clamp(1, 4096)
    } else {
        4096
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{PI, TAU};

    /// Area of a regular n-gon of circumradius r: the exact face of our tessellated circles.
    fn ngon(n: usize, r: f64) -> f64 {
        0.5 * n as f64 * r * r * (TAU / n as f64).sin()
    }

    #[test]
    fn volumes_and_areas_match_closed_forms() {
        let tol = 1e-3;
        let b = Primitive::Box {
            size: [2.0, 3.0, 0.5],
        }
        .mesh(tol)
        .unwrap();
        assert!(b.is_closed_and_oriented());
        assert!(
            (b.signed_volume() - 3.0).abs() < 1e-12
                && (b.area() - 2.0 * (6.0 + 1.0 + 1.5)).abs() < 1e-12
        );

        // Frustum of regular n-gons: V = h/3 (B₀ + B₁ + √(B₀B₁)).
        let (r0, r1, h) = (1.5, 0.6, 2.0);
        let f = Primitive::Frustum {
            bottom_radius: r0,
            top_radius: r1,
            height: h,
        }
        .mesh(tol)
        .unwrap();
        assert!(f.is_closed_and_oriented());
        let n = circle_segments(r0, tol);
        let (b0, b1) = (ngon(n, r0), ngon(n, r1));
        assert!((f.signed_volume() - h / 3.0 * (b0 + b1 + (b0 * b1).sqrt())).abs() < 1e-9);
        // And within the tolerance's reach of the smooth frustum.
        assert!(
            (f.signed_volume() / (PI * h / 3.0 * (r0 * r0 + r0 * r1 + r1 * r1)) - 1.0).abs()
                < 2.0 * tol / r1
        );

        let cone = Primitive::Frustum {
            bottom_radius: 1.0,
            top_radius: 0.0,
            height: 3.0,
        }
        .mesh(tol)
        .unwrap();
        assert!(cone.is_closed_and_oriented());
        assert!((cone.signed_volume() - ngon(circle_segments(1.0, tol), 1.0)).abs() < 1e-9);

        // Tube: h(B(r) − B(r − t)); lateral area = h × (outer + inner perimeters) + 2 annuli.
        let (r, t) = (1.0, 0.1);
        let tube = Primitive::Tube {
            radius: r,
            height: h,
            wall: t,
        }
        .mesh(tol)
        .unwrap();
        assert!(tube.is_closed_and_oriented());
        let n = circle_segments(r, tol);
        let side = |rr: f64| n as f64 * 2.0 * rr * (PI / n as f64).sin();
        assert!((tube.signed_volume() - h * (ngon(n, r) - ngon(n, r - t))).abs() < 1e-9);
        assert!(
            (tube.area() - (h * (side(r) + side(r - t)) + 2.0 * (ngon(n, r) - ngon(n, r - t))))
                .abs()
                < 1e-9
        );

        // Spherical cap: V = π h²(3R − h)/3, within the tessellation's reach.
        let cap = Primitive::SphericalCap {
            radius: 2.0,
            height: 0.8,
        }
        .mesh(1e-4)
        .unwrap();
        assert!(cap.is_closed_and_oriented());
        let exact = PI * 0.64 * (6.0 - 0.8) / 3.0;
        assert!(
            (cap.signed_volume() / exact - 1.0).abs() < 1e-3,
            "{}",
            cap.signed_volume() / exact
        );

        // Extrusion of an L-shaped (non-convex) profile: area × length.
        let l_shape = vec![
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 0.5],
            [0.5, 0.5],
            [0.5, 1.5],
            [0.0, 1.5],
        ];
        let e = Primitive::Extrusion {
            profile: l_shape.clone(),
            length: 4.0,
        }
        .mesh(tol)
        .unwrap();
        assert!(e.is_closed_and_oriented());
        assert!((e.signed_volume() - 4.0 * 1.5).abs() < 1e-12);
        // Clockwise input is accepted and turned around.
        let reversed: Vec<[f64; 2]> = l_shape.iter().rev().copied().collect();
        assert!(
            (Primitive::Extrusion {
                profile: reversed,
                length: 4.0
            }
            .mesh(tol)
            .unwrap()
            .signed_volume()
                - 6.0)
                .abs()
                < 1e-12
        );

        // Bend of a centred square: Pappus, V = area × radius × angle.
        let square = vec![[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]];
        let bend = Primitive::Bend {
            profile: square,
            radius: 2.0,
            angle: PI / 2.0,
        }
        .mesh(1e-5)
        .unwrap();
        assert!(bend.is_closed_and_oriented());
        assert!((bend.signed_volume() / (0.04 * 2.0 * PI / 2.0) - 1.0).abs() < 1e-4);
    }

    #[test]
    fn every_primitive_survives_a_ply_round_trip_exactly() {
        use crate::geometry::import::{ImportOptions, export_ply, import_mesh};
        let dir = tempfile::tempdir().unwrap();
        let profile = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 0.3],
            [0.2, 0.3],
            [0.2, 1.0],
            [0.0, 1.0],
        ];
        let all = [
            Primitive::Box {
                size: [1.0, 2.0, 3.0],
            },
            Primitive::Frustum {
                bottom_radius: 1.0,
                top_radius: 0.4,
                height: 2.0,
            },
            Primitive::Frustum {
                bottom_radius: 1.0,
                top_radius: 0.0,
                height: 2.0,
            },
            Primitive::Tube {
                radius: 1.0,
                height: 0.3,
                wall: 0.1,
            },
            Primitive::SphericalCap {
                radius: 1.0,
                height: 0.5,
            },
            Primitive::Extrusion {
                profile: profile.clone(),
                length: 2.0,
            },
            Primitive::Bend {
                profile: profile.iter().map(|p| [p[0] - 0.5, p[1]]).collect(),
                radius: 3.0,
                angle: 1.0,
            },
        ];
        for (i, p) in all.iter().enumerate() {
            let mesh = p.mesh(1e-3).unwrap();
            let file = dir.path().join(format!("{i}.ply"));
            std::fs::write(&file, export_ply(&mesh)).unwrap();
            let back = import_mesh(&file, ImportOptions::default()).unwrap();
            assert_eq!(back.mesh.positions, mesh.positions, "{p:?}");
            // Degenerate triangles (a cone's apex, a cap's pole) are dropped on import with a
            // warning; every other triangle comes back unchanged.
            let solid: Vec<[u32; 3]> = mesh
                .triangles
                .iter()
                .copied()
                .filter(|t| {
                    let [a, b, c] = t.map(|k| mesh.positions[k as usize]);
                    (b - a).cross(c - a).length()
                        > 1e-12 * (b - a).length_squared().max((c - a).length_squared())
                })
                .collect();
            assert_eq!(back.mesh.triangles, solid, "{p:?}");
            assert!((back.mesh.signed_volume() - mesh.signed_volume()).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_primitives_are_named() {
        assert!(
            Primitive::Tube {
                radius: 1.0,
                height: 1.0,
                wall: 1.5
            }
            .validate()
            .unwrap_err()
            .contains("wall = 1.5")
        );
        assert!(
            Primitive::Box {
                size: [1.0, f64::NAN, 1.0]
            }
            .validate()
            .unwrap_err()
            .contains("depth = NaN")
        );
        let bow_tie = vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(
            Primitive::Extrusion {
                profile: bow_tie,
                length: 1.0
            }
            .validate()
            .is_err()
        );
        assert!(
            Primitive::SphericalCap {
                radius: 1.0,
                height: 3.0
            }
            .validate()
            .is_err()
        );
    }
}
