//! Time in the recipe API: the sequence a dataset films (`dataset.sequence`) and the force
//! histories a beam or a frame carries over it (vehicles, hammer blows, ramps and steps,
//! ambient excitation), with its modal damping, number of modes and (for a beam) density. A
//! beam's loads run along its span; a frame's along its lane (`f.lane([members])`), which must
//! come first.
//!
//! Every call validates what it is given; a bad value fails the call, so the error points at it
//! (file:line:col) with the parameter and its value. Ambient excitation is drawn here, from the
//! sample's own random source passed as `rng`, never from global state.

use super::api::ScriptRng;
use super::diagnostics::call_site;
use super::options::{OptResult, Options, number};
use super::result::{Fallible, fail};
use crate::mechanics::dynamics::{Axle, TimeLoad};
use crate::mechanics::frame::Lane;
use crate::scene::{
    BeamMotion, BeamSpec, CameraPath, DEFAULT_EXPOSURE_FRACTION, DEFAULT_TRACK_STRIDE, FrameSpec,
    MAX_MOTION_BLUR, MAX_TRACK_STRIDE, MountShake, SequenceSpec, SourceSite, Waypoint,
};
use rhai::{Array, Dynamic, Engine, NativeCallContext, Variant};

/// `dataset.sequence`: `#{ duration, fps, exposure, motion_blur, mount: #{ rotation,
/// translation, band }, paths, track_stride }`. Duration and fps are required; exposure defaults to half the frame
/// interval; motion_blur (sub-instants averaged over the exposure) to 0, none.
pub(super) fn sequence(options: Option<Options>, views: u32) -> OptResult<Option<SequenceSpec>> {
    let Some(mut o) = options else {
        return Ok(None);
    };
    let duration = o.positive("duration", "seconds")?;
    let fps = o.positive("fps", "frames per second")?;
    let exposure = o.number("exposure", DEFAULT_EXPOSURE_FRACTION / fps)?;
    let motion_blur = o.integer("motion_blur", 0, 0, i64::from(MAX_MOTION_BLUR))? as u32;
    let track_stride = o.integer(
        "track_stride",
        i64::from(DEFAULT_TRACK_STRIDE),
        1,
        i64::from(MAX_TRACK_STRIDE),
    )? as u32;
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
    let paths = match o.take("paths") {
        Some(list) => camera_paths(&list, &o.path("paths"), duration)?,
        None => Vec::new(),
    };
    o.finish()?;
    let spec = SequenceSpec {
        duration,
        fps,
        exposure,
        motion_blur,
        mount,
        paths,
        track_stride,
    };
    let path_problem = (spec.paths.iter().enumerate()).find_map(|(i, p)| p.problem(i, views));
    let twice = (spec.paths.iter().enumerate())
        .find(|(i, p)| spec.paths[..*i].iter().any(|q| q.view == p.view));
    let twice = twice.map(|(i, p)| {
        format!(
            "sequence.paths[{i}].view = {}: that view already has a path",
            p.view
        )
    });
    match spec.problem().or(path_problem).or(twice) {
        Some(why) => Err(format!("dataset.{why}")),
        None => Ok(Some(spec)),
    }
}

/// `sequence.paths`: `[#{ view, waypoints: [[time, [x, y, z]], ...], target }, ...]`, each
/// waypoint optionally with its own target (`[time, [x, y, z], [tx, ty, tz]]`, `target` then
/// the default of the others), or a straight flight `#{ view, from, to, target }` from `from`
/// at t = 0 to `to` at the end.
fn camera_paths(list: &Dynamic, at: &str, duration: f64) -> OptResult<Vec<CameraPath>> {
    let items = list.clone().try_cast::<Array>().ok_or_else(|| {
        format!("{at} = {list} must be a list of paths like [#{{ view, waypoints, target }}]")
    })?;
    items
        .iter()
        .enumerate()
        .map(|(i, item)| {
            let here = format!("{at}[{i}]");
            let map = item.clone().try_cast::<rhai::Map>().ok_or_else(|| {
                format!("{here} = {item} must be a map like #{{ view, waypoints, target }}")
            })?;
            camera_path(Options::new(map, here.clone()), &here, duration)
        })
        .collect()
}

fn camera_path(mut o: Options, here: &str, duration: f64) -> OptResult<CameraPath> {
    let view = o.required("view")?;
    let view = (view.as_int().ok())
        .and_then(|v| u32::try_from(v).ok())
        .ok_or_else(|| format!("{here}.view = {view} must be a view index, a whole number ≥ 0"))?;
    let target = o.point("target")?;
    let missing_target = format!("missing option `{}`", o.path("target"));
    let waypoints = match (o.take("waypoints"), o.point("from")?, o.point("to")?) {
        (Some(list), None, None) => waypoints(&list, &o.path("waypoints"), target)?,
        (None, Some(from), Some(to)) => {
            let target = target.ok_or(missing_target)?;
            let at = |time, position| Waypoint {
                time,
                position,
                target,
            };
            vec![at(0.0, from), at(duration, to)]
        }
        _ => {
            return Err(format!(
                "{here} takes either waypoints: [[time, [x, y, z]], ...] or both from and to"
            ));
        }
    };
    o.finish()?;
    Ok(CameraPath { view, waypoints })
}

/// `[[time, [x, y, z]], ...]`, an entry `[time, [x, y, z], [tx, ty, tz]]` with its own target;
/// the others look at `target`, which they then need.
fn waypoints(list: &Dynamic, at: &str, target: Option<[f64; 3]>) -> OptResult<Vec<Waypoint>> {
    let shape = || {
        format!(
            "{at} = {list} must be a list of [time, [x, y, z]] or [time, [x, y, z], [tx, ty, tz]]"
        )
    };
    let point = |item: &Dynamic, what: &str| -> OptResult<[f64; 3]> {
        let xyz = item.clone().try_cast::<Array>().filter(|p| p.len() == 3);
        let xyz = xyz.ok_or_else(shape)?;
        let axis = |i: usize, name: &str| number(&xyz[i], &format!("{at} {what}{name}"));
        Ok([axis(0, "x")?, axis(1, "y")?, axis(2, "z")?])
    };
    let items = list.clone().try_cast::<Array>().ok_or_else(shape)?;
    items
        .iter()
        .enumerate()
        .map(|(j, item)| {
            let entry = item.clone().try_cast::<Array>();
            let entry = entry
                .filter(|p| (2..=3).contains(&p.len()))
                .ok_or_else(shape)?;
            let target = match entry.get(2) {
                Some(own) => point(own, "t")?,
                None => target.ok_or_else(|| {
                    format!("{at}[{j}] = {item} has no target of its own and the path no `target`")
                })?,
            };
            Ok(Waypoint {
                time: number(&entry[0], &format!("{at} time"))?,
                position: point(&entry[1], "")?,
                target,
            })
        })
        .collect()
}

pub fn register(engine: &mut Engine) {
    register_time_loads::<BeamSpec>(engine);
    register_modal_model::<BeamSpec>(engine);
    register_time_loads::<FrameSpec>(engine);
    register_modal_model::<FrameSpec>(engine);
    engine.register_fn(
        "density",
        |ctx: NativeCallContext, b: &mut BeamSpec, rho: Dynamic| -> Fallible<BeamSpec> {
            let rho = strictly_positive(&rho, "density", "kg/m³")?;
            Ok(edit_motion(&ctx, b, |m| m.density = rho))
        },
    );
}

/// A structure that carries time loads: a beam along its span, a frame along its lane.
trait Moving: Variant + Clone {
    /// The length load positions run over, metres; why there is none yet.
    fn span(&self) -> Result<f64, String>;
    /// Its motion, created with the defaults on first use.
    fn motion(&mut self) -> &mut BeamMotion;
    /// Records the call as the one errors found in its mechanics point at.
    fn mark(&mut self, site: SourceSite);
}

impl Moving for BeamSpec {
    fn span(&self) -> Result<f64, String> {
        Ok(self.length)
    }
    fn motion(&mut self) -> &mut BeamMotion {
        self.motion.get_or_insert_with(BeamMotion::default)
    }
    fn mark(&mut self, site: SourceSite) {
        self.declared_at = Some(site);
    }
}

impl Moving for FrameSpec {
    fn span(&self) -> Result<f64, String> {
        if self.lane.is_empty() {
            return Err(
                "a frame's time loads run along its lane: declare it first, f.lane([member, ...])"
                    .into(),
            );
        }
        Lane::new(&self.model, &self.lane).map(|lane| lane.length())
    }
    fn motion(&mut self) -> &mut BeamMotion {
        self.motion.get_or_insert_with(BeamMotion::default)
    }
    fn mark(&mut self, site: SourceSite) {
        self.declared_at = Some(site);
    }
}

/// Adds `load` to the structure's motion after checking it against the span or lane.
fn add_load<T: Moving>(ctx: &NativeCallContext, s: &mut T, load: TimeLoad) -> Fallible<T> {
    s.mark(call_site(ctx));
    if let Err(why) = s.span().and_then(|span| load.check(span)) {
        return fail(why);
    }
    s.motion().loads.push(load);
    Ok(s.clone())
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

fn register_time_loads<T: Moving>(engine: &mut Engine) {
    engine.register_fn(
        "vehicle",
        |ctx: NativeCallContext,
         b: &mut T,
         list: Array,
         speed: Dynamic,
         enters: Dynamic|
         -> Fallible<T> {
            let load = TimeLoad::Vehicle {
                axles: axles(&list)?,
                speed: number(&speed, "vehicle speed")?,
                enters: number(&enters, "vehicle enters")?,
            };
            add_load(&ctx, b, load)
        },
    );
    // Forces at one point, each given by (position, force, start, a time): `duration` of a
    // hammer blow, `rise` of a ramp.
    point_history::<T>(
        engine,
        "hammer",
        "duration",
        |at, force, start, duration| TimeLoad::Pulse {
            at,
            force,
            start,
            duration,
        },
    );
    point_history::<T>(engine, "ramp", "rise", |at, force, start, rise| {
        TimeLoad::Ramp {
            at,
            force,
            start,
            rise,
        }
    });
    engine.register_fn(
        "ambient",
        |ctx: NativeCallContext,
         b: &mut T,
         rng: ScriptRng,
         at: Dynamic,
         rms: Dynamic,
         band: Dynamic,
         start: Dynamic,
         duration: Dynamic|
         -> Fallible<T> {
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

/// Registers `name(at, force, start, <time>)` on `T`, adding the force history `make` builds.
fn point_history<T: Moving>(
    engine: &mut Engine,
    name: &'static str,
    time: &'static str,
    make: fn(f64, f64, f64, f64) -> TimeLoad,
) {
    engine.register_fn(
        name,
        move |ctx: NativeCallContext,
              b: &mut T,
              at: Dynamic,
              force: Dynamic,
              start: Dynamic,
              span: Dynamic|
              -> Fallible<T> {
            let load = make(
                number(&at, &format!("{name} position"))?,
                number(&force, &format!("{name} force"))?,
                number(&start, &format!("{name} start"))?,
                number(&span, &format!("{name} {time}"))?,
            );
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

/// Edits the structure's modal model through `edit`, recording the call as its mechanics site.
fn edit_motion<T: Moving>(
    ctx: &NativeCallContext,
    s: &mut T,
    edit: impl FnOnce(&mut BeamMotion),
) -> T {
    s.mark(call_site(ctx));
    edit(s.motion());
    s.clone()
}

fn register_modal_model<T: Moving>(engine: &mut Engine) {
    engine.register_fn(
        "damping",
        |ctx: NativeCallContext, b: &mut T, ratio: Dynamic| -> Fallible<T> {
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
        |ctx: NativeCallContext, b: &mut T, n: Dynamic| -> Fallible<T> {
            let n = match n.as_int() {
                Ok(n) if (1..=200).contains(&n) => n as u32,
                _ => {
                    return fail(format!("modes = {n} must be a whole number from 1 to 200"));
                }
            };
            Ok(edit_motion(&ctx, b, |m| m.modes = n))
        },
    );
    engine.register_fn(
        "quasi_static",
        |ctx: NativeCallContext, b: &mut T, on: bool| -> T {
            edit_motion(&ctx, b, |m| m.quasi_static = on)
        },
    );
}
