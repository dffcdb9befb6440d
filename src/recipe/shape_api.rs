//! The assembly part of the recipe API: `shape::` primitives, their placement and part labels,
//! and `assembly(name, [...])`, which gathers shapes (and merges other assemblies) into one
//! structure. Descriptions only: tessellation happens in Rust when the scene is built.

use super::diagnostics::call_site;
use super::files::RecipeFiles;
use super::options::{Options, number, positive, shown};
use super::result::{Fallible, fail};
use crate::geometry::primitives::Primitive;
use crate::mechanics::ShellPattern;
use crate::scene::{AssemblySpec, BeamSpec, Bending, LabelledPattern, ShapeSpec, Tolerance};
use glam::{DAffine3, DVec3};
use rhai::{
    Array, Dynamic, Engine, EvalAltResult, ImmutableString, Map, Module, NativeCallContext,
};
use std::sync::Arc;

pub fn register(engine: &mut Engine, files: Arc<RecipeFiles>) {
    engine.register_type_with_name::<ShapeSpec>("Shape");
    engine.register_type_with_name::<AssemblySpec>("Assembly");
    let mut shapes = primitives();
    let one = files.clone();
    shapes.set_native_fn(
        "mesh",
        move |ctx: NativeCallContext, file: ImmutableString| {
            imported(&ctx, &one, &file, Map::new())
        },
    );
    shapes.set_native_fn(
        "mesh",
        move |ctx: NativeCallContext, file: ImmutableString, options: Map| {
            imported(&ctx, &files, &file, options)
        },
    );
    engine.register_static_module("shape", shapes.into());
    register_placement(engine);
    // Bend a shape (an imported mesh, say) as a beam: along `axis`, deflecting `towards`.
    engine.register_fn("deform_as_beam", |s: &mut ShapeSpec, axis: ImmutableString, towards: ImmutableString, beam: BeamSpec| -> Fallible<ShapeSpec> {
        let (a, t) = (direction(&axis)?, direction(&towards)?);
        if a.dot(t).abs() > 1e-12 {
            return fail(format!("deform_as_beam: the deflection direction \"{towards}\" must be perpendicular to the axis \"{axis}\""));
        }
        s.bending = Some(Bending { axis: a.to_array(), towards: t.to_array(), beam });
        Ok(s.clone())
    });
    register_shell_patterns(engine);
    register_tolerances(engine);
    engine.register_fn(
        "detail",
        |s: &mut ShapeSpec, segments: i64, rings: i64| -> Fallible<ShapeSpec> {
            if !(3..=100_000).contains(&segments) || !(1..=100_000).contains(&rings) {
                return fail(format!(
                    "detail({segments}, {rings}): segments must be 3–100000 and rings 1–100000"
                ));
            }
            s.detail = Some([segments as u32, rings as u32]);
            Ok(s.clone())
        },
    );
    engine.register_fn("part", |s: &mut ShapeSpec, name: ImmutableString| {
        s.part = name.to_string();
        s.clone()
    });
    engine.register_fn(
        "assembly",
        |ctx: NativeCallContext, name: ImmutableString, items: Array| -> Fallible<AssemblySpec> {
            let mut assembly = AssemblySpec::new(&name);
            assembly.declared_at = Some(call_site(&ctx));
            for item in items {
                let item = match item.try_cast_result::<ShapeSpec>() {
                    Ok(shape) => {
                        assembly.shapes.push(shape);
                        continue;
                    }
                    Err(other) => other,
                };
                match item.try_cast_result::<AssemblySpec>() {
                    Ok(other) => assembly.shapes.extend(other.shapes),
                    Err(other) => {
                        return fail(format!(
                            "assembly \"{name}\": {} ({}) is neither a shape nor an assembly",
                            shown(&other),
                            other.type_name()
                        ));
                    }
                }
            }
            if assembly.shapes.is_empty() {
                return fail(format!("assembly \"{name}\" has no shapes"));
            }
            Ok(assembly)
        },
    );
}

/// `shape::box(w, d, h)` and friends; a bad dimension is reported at the call.
fn primitives() -> Module {
    let mut m = Module::new();
    m.set_native_fn(
        "box",
        |ctx: NativeCallContext, w: Dynamic, d: Dynamic, h: Dynamic| {
            make(&ctx, || {
                Ok(Primitive::Box {
                    size: [
                        number(&w, "box width")?,
                        number(&d, "box depth")?,
                        number(&h, "box height")?,
                    ],
                })
            })
        },
    );
    m.set_native_fn(
        "cylinder",
        |ctx: NativeCallContext, r: Dynamic, h: Dynamic| {
            make(&ctx, || {
                let r = number(&r, "cylinder radius")?;
                Ok(Primitive::Frustum {
                    bottom_radius: r,
                    top_radius: r,
                    height: number(&h, "cylinder height")?,
                })
            })
        },
    );
    m.set_native_fn("cone", |ctx: NativeCallContext, r: Dynamic, h: Dynamic| {
        make(&ctx, || {
            Ok(Primitive::Frustum {
                bottom_radius: number(&r, "cone radius")?,
                top_radius: 0.0,
                height: number(&h, "cone height")?,
            })
        })
    });
    m.set_native_fn(
        "frustum",
        |ctx: NativeCallContext, r0: Dynamic, r1: Dynamic, h: Dynamic| {
            make(&ctx, || {
                Ok(Primitive::Frustum {
                    bottom_radius: number(&r0, "frustum bottom radius")?,
                    top_radius: number(&r1, "frustum top radius")?,
                    height: number(&h, "frustum height")?,
                })
            })
        },
    );
    for name in ["tube", "ring"] {
        m.set_native_fn(
            name,
            move |ctx: NativeCallContext, r: Dynamic, h: Dynamic, t: Dynamic| {
                make(&ctx, || {
                    Ok(Primitive::Tube {
                        radius: number(&r, "tube radius")?,
                        height: number(&h, "tube height")?,
                        wall: number(&t, "tube wall")?,
                    })
                })
            },
        );
    }
    m.set_native_fn("cap", |ctx: NativeCallContext, r: Dynamic, h: Dynamic| {
        make(&ctx, || {
            Ok(Primitive::SphericalCap {
                radius: number(&r, "cap sphere radius")?,
                height: number(&h, "cap height")?,
            })
        })
    });
    m.set_native_fn(
        "extrude",
        |ctx: NativeCallContext, profile: Array, length: Dynamic| {
            make(&ctx, || {
                Ok(Primitive::Extrusion {
                    profile: profile_points(&profile)?,
                    length: number(&length, "extrude length")?,
                })
            })
        },
    );
    m.set_native_fn(
        "bend",
        |ctx: NativeCallContext, profile: Array, radius: Dynamic, angle: Dynamic| {
            make(&ctx, || {
                Ok(Primitive::Bend {
                    profile: profile_points(&profile)?,
                    radius: number(&radius, "bend radius")?,
                    angle: number(&angle, "bend angle")?,
                })
            })
        },
    );
    m
}

/// Silo and tank damage states on tubes: `.ovalise(A, n, towards)`, `.hoop_expansion(A)`,
/// `.dimple(A, angle, height, radius)`, `.buckle(A, angle, height, radius, wavelength)`,
/// `.elephant_foot(A, height)`; amplitudes in metres.
fn register_shell_patterns(engine: &mut Engine) {
    fn add(s: &mut ShapeSpec, pattern: ShellPattern) -> Fallible<ShapeSpec> {
        let Some(shell) = s.shell() else {
            return fail("shell patterns apply to tubes (shape::tube)".to_string());
        };
        let mut patterns: Vec<ShellPattern> = s.shell.iter().map(|l| l.pattern.clone()).collect();
        patterns.push(pattern.clone());
        ShellPattern::validate_together(&patterns, &shell).or_else(fail)?;
        s.shell.push(LabelledPattern::new(pattern, &shell));
        Ok(s.clone())
    }
    engine.register_fn(
        "ovalise",
        |s: &mut ShapeSpec, a: Dynamic, n: i64, towards: Dynamic| -> Fallible<ShapeSpec> {
            let n = u32::try_from(n)
                .map_err(|_| format!("ovalisation n = {n} must be between 1 and 64"))?;
            add(
                s,
                ShellPattern::Ovalisation {
                    amplitude: number(&a, "ovalise amplitude")?,
                    n,
                    towards: number(&towards, "ovalise towards")?,
                },
            )
        },
    );
    engine.register_fn(
        "hoop_expansion",
        |s: &mut ShapeSpec, a: Dynamic| -> Fallible<ShapeSpec> {
            add(
                s,
                ShellPattern::HoopExpansion {
                    amplitude: number(&a, "hoop_expansion amplitude")?,
                },
            )
        },
    );
    engine.register_fn(
        "dimple",
        |s: &mut ShapeSpec,
         a: Dynamic,
         angle: Dynamic,
         height: Dynamic,
         radius: Dynamic|
         -> Fallible<ShapeSpec> {
            add(
                s,
                ShellPattern::Dimple {
                    amplitude: number(&a, "dimple amplitude")?,
                    angle: number(&angle, "dimple angle")?,
                    height: number(&height, "dimple height")?,
                    radius: number(&radius, "dimple radius")?,
                },
            )
        },
    );
    engine.register_fn(
        "buckle",
        |s: &mut ShapeSpec,
         a: Dynamic,
         angle: Dynamic,
         height: Dynamic,
         radius: Dynamic,
         wavelength: Dynamic|
         -> Fallible<ShapeSpec> {
            add(
                s,
                ShellPattern::Buckle {
                    amplitude: number(&a, "buckle amplitude")?,
                    angle: number(&angle, "buckle angle")?,
                    height: number(&height, "buckle height")?,
                    radius: number(&radius, "buckle radius")?,
                    wavelength: number(&wavelength, "buckle wavelength")?,
                },
            )
        },
    );
    engine.register_fn(
        "elephant_foot",
        |s: &mut ShapeSpec, a: Dynamic, height: Dynamic| -> Fallible<ShapeSpec> {
            add(
                s,
                ShellPattern::ElephantFoot {
                    amplitude: number(&a, "elephant_foot amplitude")?,
                    height: number(&height, "elephant_foot height")?,
                },
            )
        },
    );
}

/// `.pixel_tolerance(px)` and `.chord_tolerance(m)` on assemblies, as on beams: how closely
/// curved surfaces are followed.
fn register_tolerances(engine: &mut Engine) {
    engine.register_fn(
        "chord_tolerance",
        |a: &mut AssemblySpec, metres: Dynamic| -> Fallible<AssemblySpec> {
            a.tessellation = Tolerance::Chord(positive(&metres, "chord_tolerance", "metres")?);
            Ok(a.clone())
        },
    );
    engine.register_fn(
        "pixel_tolerance",
        |a: &mut AssemblySpec, pixels: Dynamic| -> Fallible<AssemblySpec> {
            a.tessellation = Tolerance::Pixels(positive(&pixels, "pixel_tolerance", "pixels")?);
            Ok(a.clone())
        },
    );
}

/// "x", "-z", ...: a signed coordinate axis.
fn direction(name: &str) -> Fallible<DVec3> {
    Ok(match name {
        "x" | "+x" => DVec3::X,
        "-x" => -DVec3::X,
        "y" | "+y" => DVec3::Y,
        "-y" => -DVec3::Y,
        "z" | "+z" => DVec3::Z,
        "-z" => -DVec3::Z,
        other => {
            return fail(format!(
                "direction \"{other}\" is not one of x, y, z, -x, -y, -z"
            ));
        }
    })
}

/// `shape::mesh("file", #{ normalize: true })`.
fn imported(
    ctx: &NativeCallContext,
    files: &RecipeFiles,
    file: &str,
    options: Map,
) -> Result<ShapeSpec, Box<EvalAltResult>> {
    make(ctx, || {
        let mut o = Options::new(options, "shape::mesh options");
        let normalize = o.flag("normalize", false)?;
        o.finish()?;
        Ok(Primitive::Imported {
            file: file.to_string(),
            normalize,
            mesh: files.mesh(file, normalize)?,
        })
    })
}

fn make(
    ctx: &NativeCallContext,
    build: impl FnOnce() -> Result<Primitive, String>,
) -> Result<ShapeSpec, Box<EvalAltResult>> {
    let at = |msg: String| Box::new(EvalAltResult::ErrorRuntime(msg.into(), ctx.call_position()));
    let primitive = build().map_err(at)?;
    primitive.validate().map_err(at)?;
    Ok(ShapeSpec::new(primitive))
}

/// Most points in an `extrude` or `bend` profile: checking and triangulating a profile takes
/// time growing with the square of its points (8000 take over a second).
pub const MAX_PROFILE_POINTS: usize = 10_000;

fn profile_points(profile: &Array) -> Result<Vec<[f64; 2]>, String> {
    if profile.len() > MAX_PROFILE_POINTS {
        return Err(format!(
            "the profile has {} points, more than the {MAX_PROFILE_POINTS} a profile may have",
            profile.len()
        ));
    }
    profile
        .iter()
        .map(|p| match p.clone().try_cast::<Array>().as_deref() {
            Some([x, y]) => Ok([number(x, "profile x")?, number(y, "profile y")?]),
            _ => Err(format!("profile point {} must be [x, y]", shown(p))),
        })
        .collect()
}

/// Placement applies after what came before, to shapes and to whole assemblies alike.
fn register_placement(engine: &mut Engine) {
    fn on_shape(s: &mut ShapeSpec, m: DAffine3) -> ShapeSpec {
        s.then(m);
        s.clone()
    }
    fn on_assembly(a: &mut AssemblySpec, m: DAffine3) -> AssemblySpec {
        a.shapes.iter_mut().for_each(|s| s.then(m));
        a.clone()
    }
    macro_rules! placement {
        ($name:literal, |$($arg:ident),*| $map:expr) => {
            engine.register_fn($name, |s: &mut ShapeSpec, $($arg: Dynamic),*| -> Fallible<ShapeSpec> {
                $(let $arg = number(&$arg, concat!($name, " ", stringify!($arg)))?;)*
                Ok(on_shape(s, $map))
            });
            engine.register_fn($name, |a: &mut AssemblySpec, $($arg: Dynamic),*| -> Fallible<AssemblySpec> {
                $(let $arg = number(&$arg, concat!($name, " ", stringify!($arg)))?;)*
                Ok(on_assembly(a, $map))
            });
        };
    }
    placement!("translate", |x, y, z| DAffine3::from_translation(
        DVec3::new(x, y, z)
    ));
    placement!("rotate_x", |angle| DAffine3::from_rotation_x(angle));
    placement!("rotate_y", |angle| DAffine3::from_rotation_y(angle));
    placement!("rotate_z", |angle| DAffine3::from_rotation_z(angle));
    placement!("scale", |factor| DAffine3::from_scale(DVec3::splat(factor)));
    placement!("scale", |x, y, z| DAffine3::from_scale(DVec3::new(x, y, z)));
}
