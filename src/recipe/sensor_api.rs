//! Virtual sensors in the recipe API: `beam.sensor(#{ kind, at, rate, noise, name, fibre })`
//! declares a sensor recorded over the dataset's sequence, and
//! `frame.sensor(#{ member, at, direction, … })` one on a frame's member (`docs/sensors.md`).
//!
//! The call validates what it is given against the beam as declared so far; a bad value fails
//! the call, so the error points at it (file:line:col) with the option and its value.

use super::diagnostics::call_site;
use super::options::{OptResult, Options};
use super::result::{Fallible, fail};
use crate::scene::{BeamSpec, FrameSpec, SensorQuantity, SensorSpec};
use rhai::{Engine, Map, NativeCallContext};

pub fn register(engine: &mut Engine) {
    engine.register_fn(
        "sensor",
        |ctx: NativeCallContext, b: &mut BeamSpec, options: Map| -> Fallible<BeamSpec> {
            let mut o = Options::new(options, "sensor");
            for refused in ["member", "direction"] {
                if o.take(refused).is_some() {
                    return fail(format!(
                        "sensor.{refused} is for a sensor on a frame's member, not on a beam"
                    ));
                }
            }
            let spec = sensor(&b.sensors, o)?;
            // The duration is the sequence's, not known here: check everything else.
            if let Err(why) = spec.sensor(b).check(b.length, 0.0) {
                return fail(why);
            }
            b.declared_at = Some(call_site(&ctx));
            b.sensors.push(spec);
            Ok(b.clone())
        },
    );
    engine.register_fn(
        "sensor",
        |ctx: NativeCallContext, f: &mut FrameSpec, options: Map| -> Fallible<FrameSpec> {
            let mut o = Options::new(options, "sensor");
            let members = f.model.members.len() as i64;
            let member = o.integer("member", -1, -1, members - 1)?;
            if member < 0 {
                return fail(format!(
                    "sensor.member is needed on a frame: the index of the member it is fixed to (0 to {})",
                    members - 1
                ));
            }
            let direction = o.point("direction")?;
            let mut spec = sensor(&f.sensors, o)?;
            spec.member = Some(member as usize);
            spec.direction = direction;
            if let Err(why) = spec.member_sensor(f).check(&f.model, 0.0) {
                return fail(why);
            }
            f.declared_at = Some(call_site(&ctx));
            f.sensors.push(spec);
            Ok(f.clone())
        },
    );
}

/// The sensor the options describe, after the structure's `declared` sensors; `name` defaults
/// to `sensor{n}`, n counting them from 1, and `noise` to 0.
fn sensor(declared: &[SensorSpec], mut o: Options) -> OptResult<SensorSpec> {
    let kind_name = o.string("kind", "")?;
    let Some(kind) = SensorQuantity::ALL
        .into_iter()
        .find(|k| k.name() == kind_name)
    else {
        let known = SensorQuantity::ALL.map(SensorQuantity::name).join(", ");
        return Err(format!(
            "sensor.kind = {kind_name:?} is not a sensor kind: expected one of {known}"
        ));
    };
    let at = o.required_number("at")?;
    let rate = o.positive("rate", "Hz")?;
    let noise = o.number("noise", 0.0)?;
    let default_name = format!("sensor{}", declared.len() + 1);
    let name = o.string("name", &default_name)?;
    if declared.iter().any(|s| s.name == name) {
        return Err(format!(
            "sensor name {name:?} is already used on this structure"
        ));
    }
    let fibre = match o.take("fibre") {
        None => None,
        Some(_)
            if !matches!(
                kind,
                SensorQuantity::StrainTop | SensorQuantity::StrainBottom
            ) =>
        {
            return Err(format!(
                "sensor.fibre is for strain gauges, not a {} sensor",
                kind.name()
            ));
        }
        Some(v) => Some(super::options::positive(&v, "sensor.fibre", "m")?),
    };
    o.finish()?;
    Ok(SensorSpec {
        name,
        kind,
        at,
        rate,
        noise,
        fibre,
        member: None,
        direction: None,
    })
}
