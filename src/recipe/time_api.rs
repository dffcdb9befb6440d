//! Time in the recipe API: the sequence a dataset films (`dataset.sequence`) and the force
//! histories a beam carries over it (vehicles, hammer blows, ramps and steps, ambient
//! excitation), with its modal damping, number of modes and density.
//!
//! Every call validates what it is given; a bad value fails the call, so the error points at it
//! (file:line:col) with the parameter and its value. Ambient excitation is drawn here, from the
//! sample's own random source passed as `rng`, never from global state.

use super::api::ScriptRng;
use super::diagnostics::call_site;
use super::options::{OptResult, Options, number};
use super::result::{Fallible, fail};
use crate::mechanics::dynamics::{Axle, TimeLoad};
use crate::scene::{
    BeamMotion, BeamSpec, DEFAULT_EXPOSURE_FRACTION, MountShake, SequenceSpec,
};
use rhai::{Array, Dynamic, Engine, NativeCallContext};

/// `dataset.sequence`: `#{ duration, fps, exposure, mount: #{ rotation, translation, band } }`.
/// Duration and fps are required; exposure defaults to half the frame interval.
pub(super) fn sequence(options: Option<Options>) -> OptResult<Option<SequenceSpec>> {
    let Some(mut o) = options else {
        return Ok(None);
    };
    let duration = o.positive("duration", "seconds")?;
    let fps = o.positive("fps", "frames per second")?;
    let exposure = o.number("exposure", DEFAULT_EXPOSURE_FRACTION / fps)?;
    let mount = match o.sub("mount")? {
        Some(mut m) => {
            let shake = MountShake {
                rotation: m.number("rotation", 0.0)?,
                translation: m.number("translation", 0.0)?,
                band: m.number("band", 5.0)?,
            };
            m.finish()?;
            Some(shake)
        }
        None => None,
    };
    o.finish()?;
    let spec = SequenceSpec {
        duration,
        fps,
        exposure,
        mount,
    };
    match spec.problem() {
        Some(why) => Err(format!("dataset.{why}")),
        None => Ok(Some(spec)),
    }
}

pub fn register(engine: &mut Engine) {
    register_time_loads(engine);
    register_modal_model(engine);
}

/// Adds `load` to the beam's motion after checking it against the span.
fn add_load(ctx: &NativeCallContext, b: &mut BeamSpec, load: TimeLoad) -> Fallible<BeamSpec> {
    b.declared_at = Some(call_site(ctx));
    if let Err(why) = load.check(b.length) {
        return fail(why);
    }
    b.motion.get_or_insert_with(BeamMotion::default).loads.push(load);
    Ok(b.clone())
}

/// `[[behind, force], ...]`: the axles of a vehicle, leading axle first (behind = 0).
fn axles(list: &Array) -> OptResult<Vec<Axle>> {
    list.iter()
        .map(|item| {
            let pair = item.clone().try_cast::<Array>().filter(|p| p.len() == 2);
            let Some(pair) = pair else {
                return Err(format!(
                    "vehicle: axle {item} must be [behind, force] (metres behind the leading axle, newtons)"
                ));
            };
            Ok(Axle {
                behind: number(&pair[0], "vehicle axle behind")?,
                force: number(&pair[1], "vehicle axle force")?,
            })
        })
        .collect()
}

fn register_time_loads(engine: &mut Engine) {
    engine.register_fn(
        "vehicle",
        |ctx: NativeCallContext,
         b: &mut BeamSpec,
         list: Array,
         speed: Dynamic,
         enters: Dynamic|
         -> Fallible<BeamSpec> {
            let load = TimeLoad::Vehicle {
                axles: axles(&list)?,
                speed: number(&speed, "vehicle speed")?,
                enters: number(&enters, "vehicle enters")?,
            };
            add_load(&ctx, b, load)
        },
    );
    engine.register_fn(
        "hammer",
        |ctx: NativeCallContext,
         b: &mut BeamSpec,
         at: Dynamic,
         force: Dynamic,
         start: Dynamic,
         duration: Dynamic|
         -> Fallible<BeamSpec> {
            let load = TimeLoad::Pulse {
                at: number(&at, "hammer position")?,
                force: number(&force, "hammer force")?,
                start: number(&start, "hammer start")?,
                duration: number(&duration, "hammer duration")?,
            };
            add_load(&ctx, b, load)
        },
    );
    engine.register_fn(
        "ramp",
        |ctx: NativeCallContext,
         b: &mut BeamSpec,
         at: Dynamic,
         force: Dynamic,
         start: Dynamic,
         rise: Dynamic|
         -> Fallible<BeamSpec> {
            let load = TimeLoad::Ramp {
                at: number(&at, "ramp position")?,
                force: number(&force, "ramp force")?,
                start: number(&start, "ramp start")?,
                rise: number(&rise, "ramp rise")?,
            };
            add_load(&ctx, b, load)
        },
    );
    engine.register_fn(
        "ambient",
        |ctx: NativeCallContext,
         b: &mut BeamSpec,
         rng: ScriptRng,
         at: Dynamic,
         rms: Dynamic,
         band: Dynamic,
         start: Dynamic,
         duration: Dynamic|
         -> Fallible<BeamSpec> {
            let rms = non_negative(&rms, "ambient rms", "newtons")?;
            let band = strictly_positive(&band, "ambient band", "Hz")?;
            let duration = strictly_positive(&duration, "ambient duration", "seconds")?;
            let (step, values) = rng.stream().band_limited_noise(rms, band, duration);
            let load = TimeLoad::Sampled {
                at: number(&at, "ambient position")?,
                start: number(&start, "ambient start")?,
                step,
                values,
            };
            add_load(&ctx, b, load)
        },
    );
}

fn non_negative(value: &Dynamic, name: &str, unit: &str) -> OptResult<f64> {
    let x = number(value, name)?;
    if x >= 0.0 {
        Ok(x)
    } else {
        Err(format!("{name} = {x} must be ≥ 0 ({unit})"))
    }
}

fn strictly_positive(value: &Dynamic, name: &str, unit: &str) -> OptResult<f64> {
    let x = number(value, name)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(format!("{name} = {x} must be positive ({unit})"))
    }
}

/// Edits the beam's modal model through `edit`, recording the call as the beam's mechanics site.
fn edit_motion(
    ctx: &NativeCallContext,
    b: &mut BeamSpec,
    edit: impl FnOnce(&mut BeamMotion),
) -> BeamSpec {
    b.declared_at = Some(call_site(ctx));
    edit(b.motion.get_or_insert_with(BeamMotion::default));
    b.clone()
}

fn register_modal_model(engine: &mut Engine) {
    engine.register_fn(
        "damping",
        |ctx: NativeCallContext, b: &mut BeamSpec, ratio: Dynamic| -> Fallible<BeamSpec> {
            let ratio = number(&ratio, "damping ratio")?;
            if !(0.0..1.0).contains(&ratio) {
                return fail(format!(
                    "damping ratio = {ratio} must lie in [0, 1) (a fraction of critical damping, e.g. 0.02)"
                ));
            }
            Ok(edit_motion(&ctx, b, |m| m.damping = ratio))
        },
    );
    engine.register_fn(
        "modes",
        |ctx: NativeCallContext, b: &mut BeamSpec, n: Dynamic| -> Fallible<BeamSpec> {
            let n = match n.as_int() {
                Ok(n) if (1..=200).contains(&n) => n as u32,
                _ => {
                    return fail(format!(
                        "modes = {n} must be a whole number from 1 to 200"
                    ));
                }
            };
            Ok(edit_motion(&ctx, b, |m| m.modes = n))
        },
    );
    engine.register_fn(
        "density",
        |ctx: NativeCallContext, b: &mut BeamSpec, rho: Dynamic| -> Fallible<BeamSpec> {
            let rho = strictly_positive(&rho, "density", "kg/m³")?;
            Ok(edit_motion(&ctx, b, |m| m.density = rho))
        },
    );
    engine.register_fn(
        "quasi_static",
        |ctx: NativeCallContext, b: &mut BeamSpec, on: bool| -> BeamSpec {
            edit_motion(&ctx, b, |m| m.quasi_static = on)
        },
    );
}
