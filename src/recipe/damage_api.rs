//! The damage part of the recipe API: reinforced concrete (cracked by the mechanics),
//! corrosion by exposure, and damage placed exactly (cracks, map cracking, corrosion, spalls,
//! dents). Every method edits the beam in place and returns it, so calls chain; a wrong value
//! fails at the call, with the recipe's file:line:col.

use super::diagnostics::call_site;
use super::options::{OptResult, Options};
use super::result::Fallible;
use crate::mechanics::Section;
use crate::mechanics::damage::{
    Cause, Damage, DamageShape, ExposureRules, Face, Reinforcement, Severity, SurfacePoint,
    concrete_modulus,
};
use crate::scene::BeamSpec;
use rhai::{Array, Engine, Map, NativeCallContext};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, TAU};

/// Poisson's ratio of concrete (EN 1992-1-1 §3.1.3(4), uncracked).
const CONCRETE_NU: f64 = 0.2;
/// Points on a spall's or dent's outline.
const OUTLINE_POINTS: usize = 12;

pub fn register(engine: &mut Engine) {
    engine.register_fn(
        "reinforced_concrete",
        |ctx: NativeCallContext, b: &mut BeamSpec| edit(&ctx, b, Map::new(), reinforced_concrete),
    );
    engine.register_fn(
        "reinforced_concrete",
        |ctx: NativeCallContext, b: &mut BeamSpec, m: Map| edit(&ctx, b, m, reinforced_concrete),
    );
    engine.register_fn(
        "corrosion_by_exposure",
        |ctx: NativeCallContext, b: &mut BeamSpec| edit(&ctx, b, Map::new(), corrosion_by_exposure),
    );
    engine.register_fn(
        "corrosion_by_exposure",
        |ctx: NativeCallContext, b: &mut BeamSpec, m: Map| edit(&ctx, b, m, corrosion_by_exposure),
    );
    let placed: [(&str, Placer); 5] = [
        ("crack", crack),
        ("map_cracking", map_cracking),
        ("corrosion", corrosion),
        ("spall", spall),
        ("dent", dent),
    ];
    for (name, place) in placed {
        engine.register_fn(
            name,
            move |ctx: NativeCallContext, b: &mut BeamSpec, m: Map| {
                edit(&ctx, b, m, |b, o| {
                    let d = place(b, o)?;
                    b.damage_asked.placed.push(d);
                    Ok(())
                })
            },
        );
    }
}

pub(super) type Placer = fn(&BeamSpec, &mut Options) -> OptResult<Damage>;

/// Runs `change` on the beam with the options of `map` (all of which it must read), marking
/// the call as where the beam's mechanics was declared.
fn edit(
    ctx: &NativeCallContext,
    b: &mut BeamSpec,
    map: Map,
    change: impl FnOnce(&mut BeamSpec, &mut Options) -> OptResult<()>,
) -> Fallible<BeamSpec> {
    let name = ctx.fn_name().to_string();
    let mut o = Options::new(map, name);
    change(b, &mut o)?;
    o.finish()?;
    b.declared_at = Some(call_site(ctx));
    Ok(b.clone())
}

/// `reinforced_concrete(#{ fck, cover, bar_diameter, bars, sustained })`: the beam becomes
/// reinforced concrete (E = E_cm, ν = 0.2, strength f_ck for the plausibility label).
pub(super) fn reinforced_concrete(b: &mut BeamSpec, o: &mut Options) -> OptResult<()> {
    if !matches!(b.section, Section::Rectangle { .. }) {
        return Err(format!(
            "reinforced_concrete needs a rectangular section; this beam's is {:?}",
            b.section
        ));
    }
    let d = Reinforcement::default();
    let bars = Reinforcement {
        fck: o.number("fck", d.fck)?,
        cover: o.number("cover", d.cover)?,
        bar_diameter: o.number("bar_diameter", d.bar_diameter)?,
        bars: o.integer("bars", d.bars as i64, 1, 1000)? as u32,
        sustained: o.flag("sustained", d.sustained)?,
    };
    bars.validate(b.section.height())?;
    b.elastic_modulus = concrete_modulus(bars.fck);
    b.poisson = CONCRETE_NU;
    b.yield_strength = bars.fck;
    b.damage_asked.reinforcement = Some(bars);
    Ok(())
}

/// `corrosion_by_exposure(#{ end_length, end_loss, bottom_loss })`.
pub(super) fn corrosion_by_exposure(b: &mut BeamSpec, o: &mut Options) -> OptResult<()> {
    let d = ExposureRules::default();
    let end_length = match o.take("end_length") {
        None => None,
        Some(v) => Some(super::options::positive(
            &v,
            "corrosion_by_exposure.end_length",
            "metres",
        )?),
    };
    let rules = ExposureRules {
        end_length,
        end_loss: loss(
            o.number("end_loss", d.end_loss)?,
            "corrosion_by_exposure.end_loss",
        )?,
        bottom_loss: loss(
            o.number("bottom_loss", d.bottom_loss)?,
            "corrosion_by_exposure.bottom_loss",
        )?,
    };
    if b.damage_asked.reinforcement.is_some() {
        return Err(
            "corrosion_by_exposure is for steel members; this beam is reinforced concrete".into(),
        );
    }
    b.damage_asked.corrosion_by_exposure = Some(rules);
    Ok(())
}

fn loss(value: f64, path: &str) -> OptResult<f64> {
    if (0.0..=0.9).contains(&value) {
        Ok(value)
    } else {
        Err(format!("{path} = {value} must be a fraction in [0, 0.9]"))
    }
}

/// A position along the span.
fn along(b: &BeamSpec, o: &mut Options, key: &'static str) -> OptResult<f64> {
    let path = o.path(key);
    let x = o.required_number(key)?;
    if (0.0..=b.length).contains(&x) {
        Ok(x)
    } else {
        Err(format!(
            "{path} = {x} m lies outside the span [0, {}] m",
            b.length
        ))
    }
}

fn face(o: &mut Options, default: &'static str) -> OptResult<Face> {
    let word = o.choice(
        "face",
        &["bottom", "top", "side_neg_y", "side_pos_y"],
        Some(default),
    )?;
    Face::named(word)
}

/// Half the extent of `face` across the axis: half the height on the sides, half the width
/// on top and bottom.
fn half_across(b: &BeamSpec, face: Face) -> f64 {
    0.5 * if face.is_side() {
        b.section.height()
    } else {
        b.section.width()
    }
}

/// A height on `face` (key `height`, default 0), checked to lie on it.
fn on_face(b: &BeamSpec, o: &mut Options, face: Face) -> OptResult<f64> {
    let path = o.path("height");
    let h = o.number("height", 0.0)?;
    let half = half_across(b, face);
    if h.abs() <= half {
        Ok(h)
    } else {
        Err(format!(
            "{path} = {h} m lies off the face (within ±{half} m of the axis)"
        ))
    }
}

fn positive(o: &mut Options, key: &'static str, default: f64, unit: &str) -> OptResult<f64> {
    let path = o.path(key);
    let v = o.number(key, default)?;
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{path} = {v} must be positive ({unit})"))
    }
}

fn placed(
    shape: DamageShape,
    position: SurfacePoint,
    size: [f64; 2],
    orientation: f64,
    severity: Severity,
) -> Damage {
    Damage {
        shape,
        member: "beam".into(),
        position,
        size,
        orientation,
        severity,
        cause: Cause::Placed,
    }
}

/// `crack(#{ kind, at, face, width_mm, depth, height, angle, length })`: a flexural crack
/// across the top or bottom face rising `depth` up both sides, or a straight (shear) crack on
/// a side face through (at, height) at `angle` from the axis.
pub(super) fn crack(b: &BeamSpec, o: &mut Options) -> OptResult<Damage> {
    let kind = o.choice("kind", &["flexural", "shear"], Some("flexural"))?;
    let at = along(b, o, "at")?;
    let width_mm = positive(o, "width_mm", 0.3, "millimetres")?;
    let severity = Severity::grade(width_mm, 0.2, 0.4);
    let (h, w) = (b.section.height(), b.section.width());
    if kind == "flexural" {
        let face = face(o, "bottom")?;
        if face.is_side() {
            return Err(format!(
                "{} = a side: a flexural crack starts on \"bottom\" or \"top\"",
                o.path("face")
            ));
        }
        let path_depth = o.path("depth");
        let depth = positive(o, "depth", h / 3.0, "metres")?;
        if depth > h {
            return Err(format!(
                "{path_depth} = {depth} m exceeds the section height {h} m"
            ));
        }
        let (edge, tip) = match face {
            Face::Bottom => (-0.5 * h, -0.5 * h + depth),
            _ => (0.5 * h, 0.5 * h - depth),
        };
        let p = |face, height| SurfacePoint {
            along: at,
            face,
            height,
        };
        let path = vec![
            p(Face::SideNegY, tip),
            p(Face::SideNegY, edge),
            p(face, -0.5 * w),
            p(face, 0.5 * w),
            p(Face::SidePosY, edge),
            p(Face::SidePosY, tip),
        ];
        return Ok(placed(
            DamageShape::FlexuralCrack { path, width_mm },
            p(face, 0.0),
            [width_mm * 1e-3, w + 2.0 * depth],
            FRAC_PI_2,
            severity,
        ));
    }
    let face = face(o, "side_neg_y")?;
    if !face.is_side() {
        return Err(format!(
            "{} must be a side (\"side_neg_y\" or \"side_pos_y\") for a shear crack",
            o.path("face")
        ));
    }
    let height = on_face(b, o, face)?;
    let angle = o.number("angle", FRAC_PI_4)?;
    let length = positive(o, "length", 0.5 * h, "metres")?;
    let (dx, dz) = (0.5 * length * angle.cos(), 0.5 * length * angle.sin());
    let p = |along: f64, height: f64| SurfacePoint {
        along: along.clamp(0.0, b.length),
        face,
        height: height.clamp(-0.5 * h, 0.5 * h),
    };
    Ok(placed(
        DamageShape::ShearCrack {
            path: vec![p(at - dx, height - dz), p(at + dx, height + dz)],
            width_mm,
        },
        p(at, height),
        [2.0 * dx.abs(), 2.0 * dz.abs()],
        angle,
        severity,
    ))
}

/// `map_cracking(#{ from, to, face, cell, width_mm })`.
pub(super) fn map_cracking(b: &BeamSpec, o: &mut Options) -> OptResult<Damage> {
    let (from, to) = stretch(b, o)?;
    let face = face(o, "bottom")?;
    let cell = positive(o, "cell", 0.15, "metres")?;
    let width_mm = positive(o, "width_mm", 0.1, "millimetres")?;
    Ok(placed(
        DamageShape::MapCracking {
            from,
            to,
            face,
            cell,
            width_mm,
        },
        SurfacePoint {
            along: 0.5 * (from + to),
            face,
            height: 0.0,
        },
        [to - from, 2.0 * half_across(b, face)],
        0.0,
        Severity::grade(width_mm, 0.2, 0.4),
    ))
}

/// `from` < `to` on the span.
fn stretch(b: &BeamSpec, o: &mut Options) -> OptResult<(f64, f64)> {
    let from = along(b, o, "from")?;
    let to = along(b, o, "to")?;
    if from < to {
        Ok((from, to))
    } else {
        Err(format!(
            "{} = {from} m must be less than {} = {to} m",
            o.path("from"),
            o.path("to")
        ))
    }
}

/// `corrosion(#{ from, to, faces, section_loss, stain_length })`.
pub(super) fn corrosion(b: &BeamSpec, o: &mut Options) -> OptResult<Damage> {
    let (from, to) = stretch(b, o)?;
    let faces_path = o.path("faces");
    let faces = match o.take("faces") {
        None => vec![Face::Bottom],
        Some(v) => {
            let list = v
                .try_cast::<Array>()
                .filter(|a| !a.is_empty())
                .ok_or_else(|| {
                    format!(
                        "{faces_path} must be a list of faces, e.g. [\"bottom\", \"side_neg_y\"]"
                    )
                })?;
            list.iter()
                .map(|f| Face::named(&f.to_string()).map_err(|e| format!("{faces_path}: {e}")))
                .collect::<OptResult<Vec<Face>>>()?
        }
    };
    let section_loss = loss(o.number("section_loss", 0.05)?, &o.path("section_loss"))?;
    let stain_length = positive(o, "stain_length", b.section.height(), "metres")?;
    Ok(placed(
        DamageShape::Corrosion {
            from,
            to,
            faces: faces.clone(),
            section_loss,
            stain_direction: [0.0, 0.0, -1.0],
            stain_length,
        },
        SurfacePoint {
            along: 0.5 * (from + to),
            face: faces[0],
            height: 0.0,
        },
        [to - from, 2.0 * half_across(b, faces[0])],
        0.0,
        Severity::grade(section_loss, 0.05, 0.15),
    ))
}

/// An ellipse of `OUTLINE_POINTS` on `face` about (at, height), semi-axes `a` along and `c`
/// across, kept on the face.
fn ellipse(b: &BeamSpec, face: Face, at: f64, height: f64, a: f64, c: f64) -> Vec<SurfacePoint> {
    let half = half_across(b, face);
    (0..OUTLINE_POINTS)
        .map(|k| {
            let t = TAU * k as f64 / OUTLINE_POINTS as f64;
            SurfacePoint {
                along: (at + a * t.cos()).clamp(0.0, b.length),
                face,
                height: (height + c * t.sin()).clamp(-half, half),
            }
        })
        .collect()
}

/// `spall(#{ at, face, height, length, breadth, depth })`: an elliptical cavity.
fn spall(b: &BeamSpec, o: &mut Options) -> OptResult<Damage> {
    let at = along(b, o, "at")?;
    let face = face(o, "bottom")?;
    let height = on_face(b, o, face)?;
    let length = positive(o, "length", 0.2, "metres")?;
    let breadth = positive(o, "breadth", 0.1, "metres")?;
    let depth = thinner_than_section(b, o, "depth", 0.02, face)?;
    Ok(placed(
        DamageShape::Spall {
            outline: ellipse(b, face, at, height, 0.5 * length, 0.5 * breadth),
            depth,
        },
        SurfacePoint {
            along: at,
            face,
            height,
        },
        [length, breadth],
        0.0,
        Severity::grade(depth, 0.01, 0.025),
    ))
}

/// A spall's or dent's depth (key `key`): it is cut into the mesh, so it must leave material
/// behind the face — less than half the section, and less than the plate it is cut into (an
/// I's flange under its top or bottom, half the overhang of the flange beside the web on its
/// sides, a box's wall); a tube has no flat face to cut.
fn thinner_than_section(
    b: &BeamSpec,
    o: &mut Options,
    key: &'static str,
    default: f64,
    face: Face,
) -> OptResult<f64> {
    let path = o.path(key);
    let v = positive(o, key, default, "metres")?;
    let half = 0.5 * b.section.width().min(b.section.height());
    let (limit, what) = match b.section {
        Section::CircularHollow { .. } => {
            return Err(format!(
                "{path}: a spall or dent is cut into a flat face, and a circular hollow section has none"
            ));
        }
        Section::ISection {
            width, flange, web, ..
        } => match face.is_side() {
            false => (flange.min(half), "the flange"),
            true => ((0.5 * (width - web)).min(half), "the flange's overhang"),
        },
        Section::HollowBox { wall, .. } => (wall.min(half), "the wall"),
        Section::Rectangle { .. } => (half, "half the section"),
    };
    if v < limit {
        Ok(v)
    } else {
        Err(format!(
            "{path} = {v} m must be less than {what} ({limit} m)"
        ))
    }
}

/// `dent(#{ at, face, height, depth, radius })`.
fn dent(b: &BeamSpec, o: &mut Options) -> OptResult<Damage> {
    let at = along(b, o, "at")?;
    let face = face(o, "side_neg_y")?;
    let height = on_face(b, o, face)?;
    let radius = positive(o, "radius", 0.1, "metres")?;
    let depth = thinner_than_section(b, o, "depth", 0.01, face)?;
    Ok(placed(
        DamageShape::Dent { depth, radius },
        SurfacePoint {
            along: at,
            face,
            height,
        },
        [2.0 * radius, 2.0 * radius],
        0.0,
        Severity::grade(depth, 0.01, 0.025),
    ))
}
