//! `dataset.augment`: the augmented copies a recipe asks for, read option by option like the
//! rest of the recipe API, so that a misspelt key, a wrong type or a bad value is an error at
//! the recipe naming the operation by its place in the list (`dataset.augment.operations[2]
//! (gamma).gamma = …`), never a silent default.

use super::options::{OptResult, Options};
use crate::scene::{
    AugmentSpec, BlurSpec, ColourJitterSpec, CropSpec, ErasingSpec, ExposureSpec, Fill, GammaSpec,
    GeometryMode, JpegSpec, NoiseSpec, OPERATION_NAMES, Operation, Range, SigmaUnit, VignetteSpec,
    WarpSpec,
};
use rhai::{Array, Dynamic, Map};

/// `augment: "paper"`, `"paper_image"`, `"none"`, or `#{ copies, keep_clean, mode,
/// operations: [#{ op, ... }] }` (see `scene::Operation` for the operations and their ranges).
pub fn augment(value: Option<Dynamic>) -> OptResult<AugmentSpec> {
    let spec = match value {
        None => AugmentSpec::default(),
        Some(v) if v.is_string() => named(&v.to_string())?,
        Some(v) => {
            let map = v.try_cast::<Map>().ok_or(
                "dataset.augment must be \"paper\", \"paper_image\", \"none\" or a map like #{ copies: 1, operations: [...] }",
            )?;
            declared(Options::new(map, "dataset.augment"))?
        }
    };
    spec.validate()?;
    Ok(spec)
}

/// A named set of augmentations.
fn named(name: &str) -> OptResult<AugmentSpec> {
    Ok(match name {
        "none" => AugmentSpec::default(),
        "paper" => AugmentSpec::paper(),
        "paper_image" => AugmentSpec {
            mode: GeometryMode::Image,
            ..AugmentSpec::paper()
        },
        other => {
            let hint = crate::words::nearest(other, &["paper", "paper_image", "none"])
                .map(|k| format!("; did you mean \"{k}\"?"))
                .unwrap_or_default();
            return Err(format!(
                "dataset.augment = \"{}\": expected \"paper\", \"paper_image\", \"none\" or a map like #{{ copies: 1, operations: [...] }}{hint}",
                crate::words::clip(other, 80)
            ));
        }
    })
}

/// `#{ copies, keep_clean, mode, operations }`.
fn declared(mut o: Options) -> OptResult<AugmentSpec> {
    let copies = o.integer("copies", 1, 0, 1000)? as u32;
    let keep_clean = o.flag("keep_clean", true)?;
    let mode = match o.choice("mode", &["exact", "image"], Some("exact"))? {
        "image" => GeometryMode::Image,
        _ => GeometryMode::Exact,
    };
    let operations = match o.take("operations") {
        None => Vec::new(),
        Some(list) => operations(list)?,
    };
    o.finish()?;
    Ok(AugmentSpec {
        copies,
        keep_clean,
        mode,
        operations,
    })
}

/// `operations: [#{ op: "warp", ... }, ...]`.
fn operations(list: Dynamic) -> OptResult<Vec<Operation>> {
    operation_list(list, "dataset.augment.operations")
}

/// `sensor: [#{ op: "vignette", ... }, #{ op: "noise", ... }, ...]`: what the camera's sensor
/// and lens do to every clean image, the augmentations' photometric operations drawn once per
/// view (none by default).
pub fn sensor(value: Option<Dynamic>) -> OptResult<Vec<Operation>> {
    let Some(list) = value else {
        return Ok(Vec::new());
    };
    let operations = operation_list(list, "dataset.sensor")?;
    for (i, op) in operations.iter().enumerate() {
        let at = format!("dataset.sensor[{i}] ({})", op.name());
        if op.is_geometric() || matches!(op, Operation::Erase(_)) {
            return Err(format!(
                "{at}: a sensor only changes the picture's light (colour_jitter, exposure, gamma, vignette, noise, blur, jpeg); warps, crops and cut-outs belong in dataset.augment"
            ));
        }
        op.validate(&at)?;
    }
    Ok(operations)
}

/// A list of operations at `list_path`.
fn operation_list(list: Dynamic, list_path: &str) -> OptResult<Vec<Operation>> {
    let items = list.clone().try_cast::<Array>().ok_or_else(|| {
        format!(
            "{list_path} = {} ({}) must be a list like [#{{ op: \"vignette\", ... }}, #{{ op: \"noise\", ... }}]",
            super::options::shown(&list),
            list.type_name()
        )
    })?;
    items
        .into_iter()
        .enumerate()
        .map(|(i, item)| operation(list_path, i, item))
        .collect()
}

/// Operation `i` of the list at `list_path`.
fn operation(list_path: &str, i: usize, item: Dynamic) -> OptResult<Operation> {
    let place = format!("{list_path}[{i}]");
    let map = item.clone().try_cast::<Map>().ok_or_else(|| {
        format!(
            "{place} = {} must be a map like #{{ op: \"gamma\", gamma: [0.8, 1.25], probability: 0.5 }}",
            super::options::shown(&item)
        )
    })?;
    let mut o = Options::new(map, place.clone());
    let name = o.choice("op", &OPERATION_NAMES, None)?;
    // Every other option of the operation is named by the operation's place and kind.
    let mut o = o.renamed(format!("{place} ({name})"));
    let op = match name {
        "warp" => Operation::Warp(warp(&mut o)?),
        "crop" => Operation::Crop(CropSpec {
            size: range(&mut o, "size")?,
            probability: probability(&mut o)?,
        }),
        "colour_jitter" => Operation::ColourJitter(colour_jitter(&mut o)?),
        "exposure" => Operation::Exposure(ExposureSpec {
            stops: range(&mut o, "stops")?,
            probability: probability(&mut o)?,
        }),
        "gamma" => Operation::Gamma(GammaSpec {
            gamma: range(&mut o, "gamma")?,
            probability: probability(&mut o)?,
        }),
        "vignette" => Operation::Vignette(VignetteSpec {
            strength: range(&mut o, "strength")?,
            probability: probability(&mut o)?,
        }),
        "noise" => Operation::Noise(noise(&mut o)?),
        "blur" => Operation::Blur(blur(&mut o)?),
        "jpeg" => Operation::Jpeg(JpegSpec {
            quality: range(&mut o, "quality")?,
            probability: probability(&mut o)?,
        }),
        _ => Operation::Erase(erase(&mut o)?),
    };
    o.finish()?;
    Ok(op)
}

/// A required range: one number (fixed) or `[lo, hi]`.
fn range(o: &mut Options, key: &'static str) -> OptResult<Range> {
    let ([lo, hi], single) = o.required_range(key)?;
    Ok(if single {
        Range::Fixed(lo)
    } else {
        Range::Span([lo, hi])
    })
}

/// The operation's required probability (checked to lie in [0, 1] with the spec).
fn probability(o: &mut Options) -> OptResult<f64> {
    o.required_number("probability")
}

fn warp(o: &mut Options) -> OptResult<WarpSpec> {
    Ok(WarpSpec {
        zoom: range(o, "zoom")?,
        rotation: range(o, "rotation")?,
        shift_x: range(o, "shift_x")?,
        shift_y: range(o, "shift_y")?,
        probability: probability(o)?,
    })
}

fn colour_jitter(o: &mut Options) -> OptResult<ColourJitterSpec> {
    Ok(ColourJitterSpec {
        brightness: range(o, "brightness")?,
        contrast: range(o, "contrast")?,
        saturation: range(o, "saturation")?,
        hue: range(o, "hue")?,
        probability: probability(o)?,
    })
}

fn noise(o: &mut Options) -> OptResult<NoiseSpec> {
    Ok(
        match o.choice("model", &["gaussian", "poisson_gaussian"], None)? {
            "gaussian" => NoiseSpec::Gaussian {
                sigma: range(o, "sigma")?,
                unit: match o.choice("unit", &["levels", "fraction"], Some("levels"))? {
                    "fraction" => SigmaUnit::Fraction,
                    _ => SigmaUnit::Levels,
                },
                probability: probability(o)?,
            },
            _ => NoiseSpec::PoissonGaussian {
                a: range(o, "a")?,
                b: range(o, "b")?,
                probability: probability(o)?,
            },
        },
    )
}

fn blur(o: &mut Options) -> OptResult<BlurSpec> {
    Ok(
        match o.choice("kind", &["gaussian", "motion", "defocus"], None)? {
            "gaussian" => BlurSpec::Gaussian {
                sigma: range(o, "sigma")?,
                probability: probability(o)?,
            },
            "motion" => BlurSpec::Motion {
                length: range(o, "length")?,
                angle: range(o, "angle")?,
                probability: probability(o)?,
            },
            _ => BlurSpec::Defocus {
                radius: range(o, "radius")?,
                probability: probability(o)?,
            },
        },
    )
}

fn erase(o: &mut Options) -> OptResult<ErasingSpec> {
    Ok(ErasingSpec {
        count: range(o, "count")?,
        area: range(o, "area")?,
        aspect: range(o, "aspect")?,
        fill: match o.choice("fill", &["black", "mean", "noise"], Some("black"))? {
            "mean" => Fill::Mean,
            "noise" => Fill::Noise,
            _ => Fill::Black,
        },
        probability: probability(o)?,
    })
}
