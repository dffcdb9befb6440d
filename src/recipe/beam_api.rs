//! The beam part of the recipe API: sections, supports, loads, theory, tessellation.
//! Every method edits the beam in place and returns it, so calls chain.

use super::diagnostics::call_site;
use super::options::{OptResult, Options, number, positive};
use super::result::{Fallible, fail};
use crate::mechanics::{Axial, Load, Mapping, Section, Support, Target, Theory};
use crate::scene::{BeamSpec, Tessellation};
use rhai::{Array, Dynamic, Engine, ImmutableString, Map, NativeCallContext};

pub fn register(engine: &mut Engine) {
    register_sections(engine);
    engine.register_type_with_name::<BeamSpec>("Beam");
    engine.register_fn(
        "beam",
        |ctx: NativeCallContext, map: Map| -> Fallible<BeamSpec> {
            let mut beam = beam_from_map(map)?;
            beam.declared_at = Some(call_site(&ctx));
            Ok(beam)
        },
    );
    engine.register_get("length", |b: &mut BeamSpec| b.length);
    engine.register_get("width", |b: &mut BeamSpec| b.section.width());
    engine.register_get("height", |b: &mut BeamSpec| b.section.height());
    register_supports(engine);
    register_loads(engine);
    register_settings(engine);
}

/// `beam(#{ length, width, height })` for a rectangle, or `beam(#{ length, section })`; options
/// `segments` and `axial`.
fn beam_from_map(map: Map) -> OptResult<BeamSpec> {
    let mut o = Options::new(map, "beam");
    let length = o.positive("length", "metres")?;
    let section = match o.take("section") {
        Some(s) => s
            .try_cast::<Section>()
            .ok_or("beam.section must be a section, e.g. rectangle(0.2, 0.4) or tube(0.3, 0.01)")?,
        None => Section::Rectangle {
            width: o.positive("width", "metres")?,
            height: o.positive("height", "metres")?,
        },
    };
    section.validate()?;
    let mut beam = BeamSpec::new(length, section);
    if let Some(n) = o.take("segments") {
        beam.tessellation = Tessellation::Segments(segments(&n)?);
    }
    if let Some(a) = o.take("axial") {
        beam.axial = Some(axial(&a.to_string())?);
    }
    o.finish()?;
    Ok(beam)
}

/// An axial condition by name. Which supports it suits is checked when the beam is solved, as
/// the supports may be set after it.
fn axial(name: &str) -> OptResult<Axial> {
    match name {
        "restrained" => Ok(Axial::Restrained),
        "free" => Ok(Axial::Free),
        other => Err(format!(
            "axial = \"{other}\" is unknown (known: \"restrained\": both ends hold the axis, \"free\": one end slides)"
        )),
    }
}

fn segments(n: &Dynamic) -> OptResult<u32> {
    match n.as_int() {
        Ok(i) if (1..=100_000).contains(&i) => Ok(i as u32),
        _ => Err(format!(
            "segments = {n} must be a whole number between 1 and 100000"
        )),
    }
}

fn register_sections(engine: &mut Engine) {
    engine.register_type_with_name::<Section>("Section");
    let check = |s: Section| -> Fallible<Section> { s.validate().map(|()| s).or_else(fail) };
    engine.register_fn(
        "rectangle",
        move |w: Dynamic, h: Dynamic| -> Fallible<Section> {
            check(Section::Rectangle {
                width: number(&w, "rectangle width")?,
                height: number(&h, "rectangle height")?,
            })
        },
    );
    engine.register_fn(
        "i_section",
        move |w: Dynamic, h: Dynamic, tf: Dynamic, tw: Dynamic| -> Fallible<Section> {
            check(Section::ISection {
                width: number(&w, "i_section width")?,
                height: number(&h, "i_section height")?,
                flange: number(&tf, "i_section flange")?,
                web: number(&tw, "i_section web")?,
            })
        },
    );
    engine.register_fn(
        "hollow_box",
        move |w: Dynamic, h: Dynamic, t: Dynamic| -> Fallible<Section> {
            check(Section::HollowBox {
                width: number(&w, "hollow_box width")?,
                height: number(&h, "hollow_box height")?,
                wall: number(&t, "hollow_box wall")?,
            })
        },
    );
    engine.register_fn("tube", move |d: Dynamic, t: Dynamic| -> Fallible<Section> {
        check(Section::CircularHollow {
            diameter: number(&d, "tube diameter")?,
            wall: number(&t, "tube wall")?,
        })
    });
}

fn register_supports(engine: &mut Engine) {
    for (name, support) in [
        ("simply_supported", Support::SimplySupported),
        ("cantilever", Support::Cantilever),
        ("fixed_fixed", Support::FixedFixed),
        ("propped_cantilever", Support::ProppedCantilever),
    ] {
        engine.register_fn(name, move |ctx: NativeCallContext, b: &mut BeamSpec| {
            b.declared_at = Some(call_site(&ctx));
            b.support = support;
            b.clone()
        });
    }
}

fn on_span(b: &BeamSpec, what: &str, x: f64) -> Fallible<f64> {
    if (0.0..=b.length).contains(&x) {
        Ok(x)
    } else {
        let from = if matches!(b.support, Support::SimplySupported) {
            "pinned"
        } else {
            "clamped"
        };
        fail(format!(
            "{what} = {x} m lies outside the span [0, {}] m (measured from the {from} end)",
            b.length
        ))
    }
}

/// A position along the span given to `what` (metres from x = 0), checked to lie on it.
fn position(b: &BeamSpec, what: &str, x: &Dynamic) -> Fallible<f64> {
    on_span(b, what, number(x, what)?)
}

fn register_loads(engine: &mut Engine) {
    // Shape form: a unit load, scaled so that the beam's largest deflection is `deflection`.
    engine.register_fn(
        "point_load",
        |ctx: NativeCallContext,
         b: &mut BeamSpec,
         at: Dynamic,
         deflection: Dynamic|
         -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            let at = position(b, "point_load position", &at)?;
            let deflection = number(&deflection, "point_load deflection")?;
            b.loads.push(Load::Point { at, force: 1.0 });
            b.target = Target::Peak { deflection };
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "point_force",
        |ctx: NativeCallContext,
         b: &mut BeamSpec,
         at: Dynamic,
         force: Dynamic|
         -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            let at = position(b, "point_force position", &at)?;
            b.loads.push(Load::Point {
                at,
                force: number(&force, "point_force force")?,
            });
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "distributed_load",
        |ctx: NativeCallContext, b: &mut BeamSpec, q: Dynamic| -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            b.loads.push(Load::Distributed {
                from: 0.0,
                to: b.length,
                intensity: number(&q, "distributed_load intensity")?,
            });
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "distributed_load",
        |ctx: NativeCallContext,
         b: &mut BeamSpec,
         from: Dynamic,
         to: Dynamic,
         q: Dynamic|
         -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            let from = position(b, "distributed_load from", &from)?;
            let to = position(b, "distributed_load to", &to)?;
            if from >= to {
                return fail(format!(
                    "distributed_load from = {from} m must be less than to = {to} m"
                ));
            }
            b.loads.push(Load::Distributed {
                from,
                to,
                intensity: number(&q, "distributed_load intensity")?,
            });
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "end_moments",
        |ctx: NativeCallContext,
         b: &mut BeamSpec,
         start: Dynamic,
         end: Dynamic|
         -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            b.loads.push(Load::EndMoments {
                start: number(&start, "end_moments start")?,
                end: number(&end, "end_moments end")?,
            });
            Ok(b.clone())
        },
    );
    // A snapshot of free vibration: [[mode, amplitude], ...], amplitudes in metres.
    engine.register_fn(
        "vibration",
        |ctx: NativeCallContext, b: &mut BeamSpec, modes: Array| -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            b.vibration = vibration_snapshot(&modes)?;
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "target_deflection",
        |ctx: NativeCallContext, b: &mut BeamSpec, deflection: Dynamic| -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            b.target = Target::Peak {
                deflection: number(&deflection, "target_deflection")?,
            };
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "target_deflection_at",
        |ctx: NativeCallContext,
         b: &mut BeamSpec,
         at: Dynamic,
         deflection: Dynamic|
         -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            let at = position(b, "target_deflection_at position", &at)?;
            b.target = Target::At {
                at,
                deflection: number(&deflection, "target_deflection_at deflection")?,
            };
            Ok(b.clone())
        },
    );
}

fn register_settings(engine: &mut Engine) {
    engine.register_fn("theory", |ctx: NativeCallContext, b: &mut BeamSpec, name: ImmutableString| -> Fallible<BeamSpec> {
        b.declared_at = Some(call_site(&ctx));
        b.theory = match name.as_str() {
            "auto" => Theory::Auto,
            "euler_bernoulli" => Theory::EulerBernoulli,
            "timoshenko" => Theory::Timoshenko,
            "elastica" => Theory::Elastica,
            "von_karman" => Theory::VonKarman,
            other => return fail(format!("theory = \"{other}\" is unknown (known: \"auto\", \"euler_bernoulli\", \"timoshenko\", \"elastica\", \"von_karman\")")),
        };
        Ok(b.clone())
    });
    engine.register_fn(
        "axial",
        |ctx: NativeCallContext, b: &mut BeamSpec, name: ImmutableString| -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            b.axial = Some(axial(&name)?);
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "model_tolerance",
        |ctx: NativeCallContext, b: &mut BeamSpec, t: Dynamic| -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            b.model_tolerance =
                positive(&t, "model_tolerance", "a fraction of the peak deflection")?;
            Ok(b.clone())
        },
    );
    engine.register_fn("mapping", |ctx: NativeCallContext, b: &mut BeamSpec, name: ImmutableString| -> Fallible<BeamSpec> {
        b.declared_at = Some(call_site(&ctx));
        b.mapping = match name.as_str() {
            "rotate_sections" => Mapping::RotateSections,
            "add_deflection" | "3dgen" => Mapping::AddDeflection,
            other => return fail(format!("mapping = \"{other}\" is unknown (known: \"rotate_sections\", \"add_deflection\" alias \"3dgen\")")),
        };
        Ok(b.clone())
    });
    engine.register_fn(
        "segments",
        |b: &mut BeamSpec, n: Dynamic| -> Fallible<BeamSpec> {
            b.tessellation = Tessellation::Segments(segments(&n)?);
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "chord_tolerance",
        |b: &mut BeamSpec, metres: Dynamic| -> Fallible<BeamSpec> {
            b.tessellation = Tessellation::Chord(positive(&metres, "chord_tolerance", "metres")?);
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "pixel_tolerance",
        |b: &mut BeamSpec, pixels: Dynamic| -> Fallible<BeamSpec> {
            b.tessellation = Tessellation::Pixels(positive(&pixels, "pixel_tolerance", "pixels")?);
            Ok(b.clone())
        },
    );
    engine.register_fn("paper_mesh", |b: &mut BeamSpec| -> Fallible<BeamSpec> {
        if !matches!(b.section, Section::Rectangle { .. }) {
            return fail(
                "paper_mesh: the paper's 12,288-face mesh exists only for the rectangular section"
                    .to_string(),
            );
        }
        b.tessellation = Tessellation::Paper;
        Ok(b.clone())
    });
    engine.register_fn(
        "elastic_modulus",
        |ctx: NativeCallContext, b: &mut BeamSpec, e: Dynamic| -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            b.elastic_modulus = positive(&e, "elastic_modulus", "pascals")?;
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "poisson",
        |ctx: NativeCallContext, b: &mut BeamSpec, nu: Dynamic| -> Fallible<BeamSpec> {
            b.declared_at = Some(call_site(&ctx));
            let nu = number(&nu, "poisson")?;
            if !(0.0..0.5).contains(&nu) {
                return fail(format!("poisson = {nu} must lie in [0, 0.5)"));
            }
            b.poisson = nu;
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "yield_strength",
        |b: &mut BeamSpec, fy: Dynamic| -> Fallible<BeamSpec> {
            b.yield_strength = positive(&fy, "yield_strength", "pascals")?;
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "at",
        |b: &mut BeamSpec, x: Dynamic, y: Dynamic, z: Dynamic| -> Fallible<BeamSpec> {
            b.centre = [
                number(&x, "at x")?,
                number(&y, "at y")?,
                number(&z, "at z")?,
            ];
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "yaw",
        |b: &mut BeamSpec, angle: Dynamic| -> Fallible<BeamSpec> {
            b.yaw = number(&angle, "yaw")?;
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "supports_drawn",
        |b: &mut BeamSpec, drawn: bool| -> BeamSpec {
            b.supports_drawn = drawn;
            b.clone()
        },
    );
}

/// A snapshot of free vibration from `[[mode, amplitude], ...]` (modes from 1, amplitudes in
/// metres), as beams and frames take it.
pub(super) fn vibration_snapshot(modes: &Array) -> OptResult<Vec<(u32, f64)>> {
    let mut snapshot = Vec::with_capacity(modes.len());
    for m in modes {
        let pair = m.clone().try_cast::<Array>().filter(|p| p.len() == 2);
        let Some(pair) = pair else {
            return Err(format!("vibration: {m} must be [mode, amplitude]"));
        };
        let mode = pair[0].as_int().ok().filter(|n| (1..=10_000).contains(n));
        let Some(mode) = mode else {
            return Err(format!(
                "vibration: mode {} must be a whole number from 1 to 10000",
                pair[0]
            ));
        };
        snapshot.push((mode as u32, number(&pair[1], "vibration amplitude")?));
    }
    if snapshot.is_empty() {
        return Err("vibration([]) needs at least one [mode, amplitude]".to_string());
    }
    Ok(snapshot)
}
