//! The damage part of the frame API: damage on a frame's members, placed exactly
//! (`f.damage(#{ member, type, … })`), cracked where the frame's solved moment and shear put it
//! (`f.reinforced_concrete(#{ members, fck, … })`) or corroded by exposure
//! (`f.corrosion_by_exposure(#{ members, … })`). The options and their checks are the beam's
//! (`damage_api`), read on the member as on a beam of its length and section; a wrong value
//! fails at the call, with the recipe's file:line:col.

use super::damage_api::{self, Placer};
use super::frame_api::{changed, member};
use super::options::{OptResult, Options, number};
use crate::scene::{BeamSpec, FrameSpec};
use glam::DVec3;
use rhai::{Array, Engine, INT, Map, NativeCallContext};

/// An edit of the beam API applied to one member (as a beam).
type MemberEdit = fn(&mut BeamSpec, &mut Options) -> OptResult<()>;

pub fn register(engine: &mut Engine) {
    engine.register_fn(
        "damage",
        |ctx: NativeCallContext, f: &mut FrameSpec, map: Map| changed(&ctx, f, |f| place(f, map)),
    );
    let edits: [(&'static str, MemberEdit); 2] = [
        ("reinforced_concrete", damage_api::reinforced_concrete),
        ("corrosion_by_exposure", damage_api::corrosion_by_exposure),
    ];
    for (name, edit) in edits {
        engine.register_fn(
            name,
            move |ctx: NativeCallContext, f: &mut FrameSpec, map: Map| {
                changed(&ctx, f, |f| on_members(f, map, name, edit))
            },
        );
        engine.register_fn(name, move |ctx: NativeCallContext, f: &mut FrameSpec| {
            changed(&ctx, f, |f| on_members(f, Map::new(), name, edit))
        });
    }
}

/// Member `m` of `f` as a beam of its length, section and material, with the damage asked
/// for it so far.
fn as_beam(f: &FrameSpec, m: usize) -> BeamSpec {
    let member = &f.model.members[m];
    let length = DVec3::from_array(f.model.nodes[member.start])
        .distance(DVec3::from_array(f.model.nodes[member.end]));
    let mut b = BeamSpec::new(length, member.section.clone());
    b.elastic_modulus = member.elastic_modulus;
    b.poisson = member.poisson;
    b.yield_strength = member.yield_strength;
    b.damage_asked = f.model.damage.get(&m).cloned().unwrap_or_default();
    b
}

/// Writes what the beam API changed on `b` back to member `m`.
fn store(f: &mut FrameSpec, m: usize, b: BeamSpec) {
    let member = &mut f.model.members[m];
    member.elastic_modulus = b.elastic_modulus;
    member.poisson = b.poisson;
    member.yield_strength = b.yield_strength;
    f.model.damage.insert(m, b.damage_asked);
}

/// `damage(#{ member, type, … })`: a crack, map cracking or corrosion placed on one member,
/// with the options of the beam's `crack`, `map_cracking` and `corrosion`.
fn place(f: &mut FrameSpec, map: Map) -> OptResult<()> {
    let mut o = Options::new(map, "damage");
    let path = o.path("member");
    let m = o.required("member")?;
    let m = m
        .as_int()
        .map_err(|_| format!("{path} must be a member index (an integer)"))?;
    let m = member(f, m, &path)?;
    let kind = o.choice(
        "type",
        &["crack", "map_cracking", "corrosion", "spall", "dent"],
        None,
    )?;
    let placer: Placer = match kind {
        "crack" => damage_api::crack,
        "map_cracking" => damage_api::map_cracking,
        "corrosion" => damage_api::corrosion,
        other => {
            return Err(format!(
                "{} = \"{other}\": spalls and dents are cut only into beams so far, not into frame members",
                o.path("type")
            ));
        }
    };
    let mut b = as_beam(f, m);
    let mut o = o.renamed(format!("damage({kind})"));
    let d = placer(&b, &mut o)?;
    o.finish()?;
    b.damage_asked.placed.push(d);
    store(f, m, b);
    Ok(())
}

/// `reinforced_concrete(#{ members, … })` and `corrosion_by_exposure(#{ members, … })`: the
/// beam API's option on each listed member (every member when `members` is absent).
fn on_members(f: &mut FrameSpec, mut map: Map, name: &str, edit: MemberEdit) -> OptResult<()> {
    let path = format!("{name}.members");
    let members: Vec<usize> = match map.remove("members") {
        None => (0..f.model.members.len()).collect(),
        Some(v) => {
            let list = v
                .try_cast::<Array>()
                .ok_or_else(|| format!("{path} must be a list of member indices"))?;
            list.iter()
                .map(|m| {
                    let m = number(m, &path)?;
                    member(f, m as INT, &path)
                })
                .collect::<OptResult<_>>()?
        }
    };
    for m in members {
        let mut b = as_beam(f, m);
        let mut o = Options::new(map.clone(), name);
        edit(&mut b, &mut o).map_err(|e| format!("member {m}: {e}"))?;
        o.finish()?;
        store(f, m, b);
    }
    Ok(())
}
