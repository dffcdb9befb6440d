//! The frame part of the recipe API: `frame(name)` and its nodes, members, bars, supports,
//! springs and loads. The recipe builds a plain description; Rust analyses it when the sample
//! is built, and an error found then points back at the last call that changed the model.
//! Methods that add a node or a member return its index, so later calls can refer to it.

use super::beam_api::vibration_snapshot;
use super::diagnostics::call_site;
use super::options::{OptResult, Options, number};
use super::result::{Fallible, fail};
use crate::mechanics::frame::{
    Axes, Lane, MassMatrix, Member, MemberLoad, MemberTheory, NodalLoad, NodalMass, NodeSupport,
    Plane, Release,
};
use crate::mechanics::{Load, Section};
use crate::scene::FrameSpec;
use rhai::{Array, Dynamic, Engine, INT, ImmutableString, Map, NativeCallContext};

pub fn register(engine: &mut Engine) {
    engine.register_type_with_name::<FrameSpec>("Frame");
    engine.register_fn("frame", |ctx: NativeCallContext, name: ImmutableString| {
        let mut f = FrameSpec::new(&name);
        f.declared_at = Some(call_site(&ctx));
        f
    });
    engine.register_fn(
        "frame",
        |ctx: NativeCallContext, name: ImmutableString, map: Map| -> Fallible<FrameSpec> {
            let mut f = FrameSpec::new(&name);
            f.declared_at = Some(call_site(&ctx));
            frame_options(&mut f, map)?;
            Ok(f)
        },
    );
    engine.register_get("nodes", |f: &mut FrameSpec| f.model.nodes.len() as INT);
    engine.register_get("members", |f: &mut FrameSpec| f.model.members.len() as INT);
    register_structure(engine);
    register_loads(engine);
    register_vibration(engine);
}

/// Masses at nodes and vibration snapshots of the whole frame.
fn register_vibration(engine: &mut Engine) {
    engine.register_fn(
        "mass",
        |ctx: NativeCallContext, f: &mut FrameSpec, n: INT, kg: Dynamic| {
            nodal_mass(&ctx, f, n, &kg, &Array::new())
        },
    );
    engine.register_fn(
        "mass",
        |ctx: NativeCallContext, f: &mut FrameSpec, n: INT, kg: Dynamic, inertia: Array| {
            nodal_mass(&ctx, f, n, &kg, &inertia)
        },
    );
    // The members time loads move along, in order (a lane of the deck): f.lane([m1, m2, ...]).
    engine.register_fn(
        "lane",
        |ctx: NativeCallContext, f: &mut FrameSpec, members: Array| -> Fallible<FrameSpec> {
            changed(&ctx, f, |f| {
                let lane = members
                    .iter()
                    .map(|m| match m.as_int() {
                        Ok(m) => member(f, m, "lane"),
                        Err(_) => Err(format!("lane: {m} must be a member index")),
                    })
                    .collect::<OptResult<Vec<usize>>>()?;
                Lane::new(&f.model, &lane)?;
                f.lane = lane;
                Ok(())
            })
        },
    );
    // A snapshot of free vibration of the whole frame: [[mode, amplitude], ...], amplitudes
    // in metres, as for a beam.
    engine.register_fn(
        "vibration",
        |ctx: NativeCallContext, f: &mut FrameSpec, modes: Array| -> Fallible<FrameSpec> {
            changed(&ctx, f, |f| {
                f.model.vibration = vibration_snapshot(&modes)?;
                Ok(())
            })
        },
    );
}

/// A mass `kg` on node `n`, with rotary inertia `[ix, iy, iz]` kg·m² about world axes (empty
/// for none).
fn nodal_mass(
    ctx: &NativeCallContext,
    f: &mut FrameSpec,
    n: INT,
    kg: &Dynamic,
    inertia: &Array,
) -> Fallible<FrameSpec> {
    changed(ctx, f, |f| {
        let node = node(f, n, "mass")?;
        let mass = number(kg, "mass")?;
        let inertia = if inertia.is_empty() {
            [0.0; 3]
        } else {
            triple(inertia, "mass inertia")?
        };
        if !inertia.iter().chain([&mass]).all(|x| *x >= 0.0) {
            return Err(format!(
                "mass {mass} kg and inertia {inertia:?} kg·m² on node {node} must not be negative"
            ));
        }
        f.model.masses.push(NodalMass {
            node,
            mass,
            inertia,
        });
        Ok(())
    })
}

/// `frame(name, #{ plane, self_weight, second_order, mass, display_scale })`.
fn frame_options(f: &mut FrameSpec, map: Map) -> OptResult<()> {
    let mut o = Options::new(map, "frame");
    f.model.plane = match o.choice("plane", &["space", "xz", "yz", "xy"], Some("space"))? {
        "xz" => Some(Plane::Xz),
        "yz" => Some(Plane::Yz),
        "xy" => Some(Plane::Xy),
        _ => None,
    };
    f.model.self_weight = o.flag("self_weight", false)?;
    f.model.second_order = o.flag("second_order", false)?;
    f.model.mass_matrix = match o.choice("mass", &["consistent", "lumped"], Some("consistent"))? {
        "lumped" => MassMatrix::Lumped,
        _ => MassMatrix::Consistent,
    };
    f.display_scale = o.number("display_scale", 1.0)?;
    if !(f.display_scale >= 0.0) {
        return Err(format!(
            "frame.display_scale = {} must not be negative",
            f.display_scale
        ));
    }
    o.finish()
}

/// Applies `change` to the frame, which now points errors found when analysing it at this
/// call, and returns the frame (so calls chain).
pub(super) fn changed(
    ctx: &NativeCallContext,
    f: &mut FrameSpec,
    change: impl FnOnce(&mut FrameSpec) -> OptResult<()>,
) -> Fallible<FrameSpec> {
    f.declared_at = Some(call_site(ctx));
    change(f)?;
    Ok(f.clone())
}

/// Node index `n` of `f`, checked.
fn node(f: &FrameSpec, n: INT, what: &str) -> OptResult<usize> {
    usize::try_from(n)
        .ok()
        .filter(|&i| i < f.model.nodes.len())
        .ok_or_else(|| {
            format!(
                "{what}: node {n} does not exist (the frame has {} nodes, 0 to {})",
                f.model.nodes.len(),
                f.model.nodes.len() as INT - 1
            )
        })
}

/// Member index `m` of `f`, checked.
pub(super) fn member(f: &FrameSpec, m: INT, what: &str) -> OptResult<usize> {
    usize::try_from(m)
        .ok()
        .filter(|&i| i < f.model.members.len())
        .ok_or_else(|| {
            format!(
                "{what}: member {m} does not exist (the frame has {} members)",
                f.model.members.len()
            )
        })
}

/// Three numbers from `[x, y, z]`.
fn triple(v: &Array, what: &str) -> OptResult<[f64; 3]> {
    match v.as_slice() {
        [x, y, z] => Ok([number(x, what)?, number(y, what)?, number(z, what)?]),
        _ => Err(format!("{what} must be [x, y, z], not {} values", v.len())),
    }
}

/// A release by name.
fn release(name: &str, path: &str) -> OptResult<Release> {
    match name {
        "rigid" => Ok(Release::default()),
        "pin" => Ok(Release::PIN),
        "pin_y" => Ok(Release {
            moment_y: true,
            ..Release::default()
        }),
        "pin_z" => Ok(Release {
            moment_z: true,
            ..Release::default()
        }),
        "ball" => Ok(Release::ALL),
        other => Err(format!(
            "{path} = \"{other}\" is unknown (known: \"rigid\", \"pin\" (both bending moments), \"pin_y\", \"pin_z\", \"ball\" (torsion too))"
        )),
    }
}

/// Applies `#{ theory, start, end, roll, part, elastic_modulus, poisson, yield_strength,
/// density, stiffness_factor }` to a member.
fn member_options(m: &mut Member, map: Map) -> OptResult<()> {
    let mut o = Options::new(map, "member");
    m.theory = match o.choice(
        "theory",
        &["euler_bernoulli", "timoshenko"],
        Some("euler_bernoulli"),
    )? {
        "timoshenko" => MemberTheory::Timoshenko,
        _ => MemberTheory::EulerBernoulli,
    };
    for (end, key) in [(0, "start"), (1, "end")] {
        if let Some(v) = o.take(key) {
            m.releases[end] = release(&v.to_string(), &format!("member.{key}"))?;
        }
    }
    m.roll = o.number("roll", m.roll)?;
    m.part = o.string("part", &m.part.clone())?;
    m.elastic_modulus = o.number("elastic_modulus", m.elastic_modulus)?;
    m.poisson = o.number("poisson", m.poisson)?;
    m.yield_strength = o.number("yield_strength", m.yield_strength)?;
    m.density = o.number("density", m.density)?;
    m.stiffness_factor = o.number("stiffness_factor", m.stiffness_factor)?;
    o.finish()
}

fn add_member(
    ctx: &NativeCallContext,
    f: &mut FrameSpec,
    (a, b): (INT, INT),
    section: Section,
    made: fn(usize, usize, Section) -> Member,
    options: Map,
) -> Fallible<INT> {
    f.declared_at = Some(call_site(ctx));
    let (a, b) = (node(f, a, "member start")?, node(f, b, "member end")?);
    if a == b {
        return fail(format!(
            "a member must join two different nodes, not node {a} to itself"
        ));
    }
    let mut m = made(a, b, section);
    member_options(&mut m, options)?;
    f.model.members.push(m);
    Ok(f.model.members.len() as INT - 1)
}

fn register_structure(engine: &mut Engine) {
    engine.register_fn(
        "node",
        |ctx: NativeCallContext,
         f: &mut FrameSpec,
         x: Dynamic,
         y: Dynamic,
         z: Dynamic|
         -> Fallible<INT> {
            f.declared_at = Some(call_site(&ctx));
            let p = [
                number(&x, "node x")?,
                number(&y, "node y")?,
                number(&z, "node z")?,
            ];
            f.model.nodes.push(p);
            Ok(f.model.nodes.len() as INT - 1)
        },
    );
    for (name, made) in [
        ("member", Member::new as fn(usize, usize, Section) -> Member),
        ("bar", Member::bar),
    ] {
        engine.register_fn(
            name,
            move |ctx: NativeCallContext, f: &mut FrameSpec, a: INT, b: INT, s: Section| {
                add_member(&ctx, f, (a, b), s, made, Map::new())
            },
        );
        engine.register_fn(
            name,
            move |ctx: NativeCallContext, f: &mut FrameSpec, a: INT, b: INT, s: Section, o: Map| {
                add_member(&ctx, f, (a, b), s, made, o)
            },
        );
    }
    engine.register_fn(
        "support",
        |ctx: NativeCallContext, f: &mut FrameSpec, n: INT, kind: ImmutableString| -> Fallible<FrameSpec> {
            changed(&ctx, f, |f| {
                let n = node(f, n, "support")?;
                f.model.supports.push(match kind.as_str() {
                    "fixed" => NodeSupport::fixed(n),
                    "pinned" => NodeSupport::pinned(n),
                    "roller" => NodeSupport::roller(n),
                    other => return Err(format!(
                        "support kind \"{other}\" is unknown (known: \"fixed\", \"pinned\", \"roller\" (uz held); springs: .spring(node, [kx, ky, kz, krx, kry, krz]))"
                    )),
                });
                Ok(())
            })
        },
    );
    engine.register_fn(
        "spring",
        |ctx: NativeCallContext, f: &mut FrameSpec, n: INT, k: Array| -> Fallible<FrameSpec> {
            changed(&ctx, f, |f| {
                let n = node(f, n, "spring")?;
                if k.len() != 6 {
                    return Err(format!(
                        "spring stiffnesses must be [kx, ky, kz, krx, kry, krz] (N/m, N·m/rad), not {} values",
                        k.len()
                    ));
                }
                let mut s = NodeSupport::new(n, "spring", [false; 6]);
                for (i, v) in k.iter().enumerate() {
                    let v = number(v, "spring stiffness")?;
                    if !(v >= 0.0) {
                        return Err(format!("spring stiffness {v} must not be negative"));
                    }
                    s.springs[i] = v;
                }
                f.model.supports.push(s);
                Ok(())
            })
        },
    );
    engine.register_fn(
        "damage",
        |ctx: NativeCallContext, f: &mut FrameSpec, m: INT, factor: Dynamic| -> Fallible<FrameSpec> {
            changed(&ctx, f, |f| {
                let m = member(f, m, "damage")?;
                let factor = number(&factor, "damage stiffness factor")?;
                if !(factor > 0.0 && factor <= 1.0) {
                    return Err(format!(
                        "damage stiffness factor = {factor} must lie in (0, 1]: the share of E the member keeps"
                    ));
                }
                f.model.members[m].stiffness_factor = factor;
                Ok(())
            })
        },
    );
    engine.register_fn("self_weight", |f: &mut FrameSpec, on: bool| {
        f.model.self_weight = on;
        f.clone()
    });
    engine.register_fn(
        "display_scale",
        |f: &mut FrameSpec, s: Dynamic| -> Fallible<FrameSpec> {
            let s = number(&s, "display_scale")?;
            if !(s >= 0.0) {
                return fail(format!("display_scale = {s} must not be negative"));
            }
            f.display_scale = s;
            Ok(f.clone())
        },
    );
}

/// A member load on member `m` along `direction` (world), checked against its length.
fn member_load(
    ctx: &NativeCallContext,
    f: &mut FrameSpec,
    m: INT,
    load: Load,
    direction: [f64; 3],
) -> Fallible<FrameSpec> {
    changed(ctx, f, |f| {
        let m = member(f, m, "member load")?;
        let norm = direction.iter().map(|d| d * d).sum::<f64>().sqrt();
        if !(norm > 0.0) {
            return Err(format!("load direction {direction:?} must not be zero"));
        }
        f.model.members[m].loads.push(MemberLoad {
            load,
            direction: direction.map(|d| d / norm),
            axes: Axes::Global,
        });
        Ok(())
    })
}

const DOWN: [f64; 3] = [0.0, 0.0, -1.0];

/// A force `[fx, fy, fz]` (N) and a moment `[mx, my, mz]` (N·m; empty for none) on node `n`.
fn node_load(
    ctx: &NativeCallContext,
    f: &mut FrameSpec,
    n: INT,
    force: &Array,
    moment: &Array,
) -> Fallible<FrameSpec> {
    changed(ctx, f, |f| {
        let node = node(f, n, "node_load")?;
        let force = triple(force, "node_load force")?;
        let moment = if moment.is_empty() {
            [0.0; 3]
        } else {
            triple(moment, "node_load moment")?
        };
        f.model.loads.push(NodalLoad {
            node,
            force,
            moment,
        });
        Ok(())
    })
}

fn register_loads(engine: &mut Engine) {
    engine.register_fn(
        "node_load",
        |ctx: NativeCallContext, f: &mut FrameSpec, n: INT, force: Array| {
            node_load(&ctx, f, n, &force, &Array::new())
        },
    );
    engine.register_fn(
        "node_load",
        |ctx: NativeCallContext, f: &mut FrameSpec, n: INT, force: Array, moment: Array| {
            node_load(&ctx, f, n, &force, &moment)
        },
    );
    engine.register_fn(
        "member_point_load",
        |ctx: NativeCallContext, f: &mut FrameSpec, m: INT, at: Dynamic, force: Dynamic| {
            member_load(&ctx, f, m, point(&at, &force)?, DOWN)
        },
    );
    engine.register_fn(
        "member_point_load",
        |ctx: NativeCallContext,
         f: &mut FrameSpec,
         m: INT,
         at: Dynamic,
         force: Dynamic,
         dir: Array| {
            let dir = triple(&dir, "member_point_load direction")?;
            member_load(&ctx, f, m, point(&at, &force)?, dir)
        },
    );
    engine.register_fn(
        "member_distributed_load",
        |ctx: NativeCallContext, f: &mut FrameSpec, m: INT, q: Dynamic| {
            let whole = length_of(f, member(f, m, "member_distributed_load")?);
            let load = spread(&Dynamic::from_float(0.0), &Dynamic::from_float(whole), &q)?;
            member_load(&ctx, f, m, load, DOWN)
        },
    );
    engine.register_fn(
        "member_distributed_load",
        |ctx: NativeCallContext,
         f: &mut FrameSpec,
         m: INT,
         from: Dynamic,
         to: Dynamic,
         q: Dynamic| { member_load(&ctx, f, m, spread(&from, &to, &q)?, DOWN) },
    );
    engine.register_fn(
        "member_distributed_load",
        |ctx: NativeCallContext,
         f: &mut FrameSpec,
         m: INT,
         from: Dynamic,
         to: Dynamic,
         q: Dynamic,
         dir: Array| {
            let dir = triple(&dir, "member_distributed_load direction")?;
            member_load(&ctx, f, m, spread(&from, &to, &q)?, dir)
        },
    );
}

/// A point load `force` N at `at` metres from the member's start.
fn point(at: &Dynamic, force: &Dynamic) -> OptResult<Load> {
    Ok(Load::Point {
        at: number(at, "member_point_load position")?,
        force: number(force, "member_point_load force")?,
    })
}

/// A uniform load `q` N/m from `from` to `to` metres along the member.
fn spread(from: &Dynamic, to: &Dynamic, q: &Dynamic) -> OptResult<Load> {
    Ok(Load::Distributed {
        from: number(from, "member_distributed_load from")?,
        to: number(to, "member_distributed_load to")?,
        intensity: number(q, "member_distributed_load intensity")?,
    })
}

/// Length of member `m`, metres.
fn length_of(f: &FrameSpec, m: usize) -> f64 {
    let member = &f.model.members[m];
    let (a, b) = (f.model.nodes[member.start], f.model.nodes[member.end]);
    (0..3).map(|i| (b[i] - a[i]).powi(2)).sum::<f64>().sqrt()
}
