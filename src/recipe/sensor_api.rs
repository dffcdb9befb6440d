//! Virtual sensors in the recipe API: `beam.sensor(#{ kind, at, rate, noise, name, fibre })`
//! declares a sensor recorded over the dataset's sequence (`docs/sensors.md`).
//!
//! The call validates what it is given against the beam as declared so far; a bad value fails
//! the call, so the error points at it (file:line:col) with the option and its value.

use super::diagnostics::call_site;
use super::options::{OptResult, Options};
use super::result::{Fallible, fail};
use crate::scene::{BeamSpec, SensorQuantity, SensorSpec};
use rhai::{Engine, Map, NativeCallContext};

pub fn register(engine: &mut Engine) {
    engine.register_fn(
        "sensor",
        |ctx: NativeCallContext, b: &mut BeamSpec, options: Map| -> Fallible<BeamSpec> {
            let spec = sensor(b, Options::new(options, "sensor"))?;
            // The duration is the sequence's, not known here: check everything else.
            if let Err(why) = spec.sensor(b).check(b.length, 0.0) {
                return fail(why);
            }
            if b.sensors.iter().any(|s| s.name == spec.name) {
                return fail(format!(
                    "sensor name {:?} is already used on this beam",
                    spec.name
                ));
            }
            b.declared_at = Some(call_site(&ctx));
            b.sensors.push(spec);
            Ok(b.clone())
        },
    );
}

/// The sensor the options describe; `name` defaults to `sensor{n}`, n counting the beam's
/// sensors from 1, and `noise` to 0.
fn sensor(b: &BeamSpec, mut o: Options) -> OptResult<SensorSpec> {
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
    let default_name = format!("sensor{}", b.sensors.len() + 1);
    let name = o.string("name", &default_name)?;
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
    })
}
