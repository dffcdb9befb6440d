//! The functions and types a recipe can call. Each builds or edits plain scene data and
//! validates what it is given; none does per-vertex or per-pixel work.

use super::files::RecipeFiles;
use super::options::{self, OptResult, Options, number, shown};
use super::result::{Fallible, fail};
use crate::cameras::{
    CameraRig, DepthOfField, Distance, DistortionRanges, FixedCamera, Poses, Stereo,
};
use crate::output::{DEFAULT_OUTPUTS, output_names};
use crate::scene::{
    AugmentSpec, Background, DEFAULT_POINTS, DatasetSpec, GeometryMode, GroundBounceSpec,
    ImageRecord, LightSpec, NormalsFrame, OUTDOOR_AMBIENT, Operation, Outputs, Shading,
    SkyGradient, SkySpec, SourceSite, SunSpec, Tone,
};
use crate::seeds::Stream;
use crate::words::number as number_shown;
use rhai::{Array, Dynamic, Engine, FnPtr, ImmutableString, Map, NativeCallContext};
use std::collections::BTreeMap;
use std::num::IntErrorKind;
use std::sync::{Arc, Mutex};

/// What `dataset(#{...})` returns: the dataset settings plus the function that draws a scene.
#[derive(Clone)]
pub struct Dataset {
    pub spec: DatasetSpec,
    pub scene: FnPtr,
    /// Where `dataset(...)` was called: errors found once samples are built (a camera that
    /// stands on its target) point there.
    pub site: SourceSite,
}

/// Recipe parameters: values from `--set name=value`, and the resolved value of every
/// `param(...)` the recipe declared (recorded in run.json).
#[derive(Default)]
pub struct Params {
    pub overrides: BTreeMap<String, String>,
    pub resolved: Mutex<BTreeMap<String, serde_json::Value>>,
}

/// The random source handed to a recipe's scene function, plus the index of the sample being
/// drawn (`rng.sample`, for recipes that walk a grid). Clones share one stream, so passing it
/// to helper functions never repeats values.
#[derive(Clone)]
pub struct ScriptRng(Arc<Mutex<Stream>>, u64);

impl ScriptRng {
    pub fn new(stream: Stream, sample: u64) -> Self {
        ScriptRng(Arc::new(Mutex::new(stream)), sample)
    }

    /// The sample's stream, for recipe calls that draw many values (ambient excitation).
    pub(super) fn stream(&self) -> std::sync::MutexGuard<'_, Stream> {
        self.0.lock().unwrap()
    }
}

pub fn register(
    engine: &mut Engine,
    params: Arc<Params>,
    materials: super::material_api::MaterialContext,
) {
    let files = materials.files.clone();
    engine.register_fn("param", move |name: ImmutableString, default: Dynamic| {
        param(&params, &name, default)
    });
    engine.register_fn("deg", |x: Dynamic| -> Fallible<f64> {
        Ok(number(&x, "deg(x)")?.to_radians())
    });
    engine.register_type_with_name::<Dataset>("Dataset");
    let images = files.clone();
    engine.register_fn(
        "dataset",
        move |ctx: NativeCallContext, map: Map| -> Fallible<Dataset> {
            let dataset = dataset(map, &images, super::diagnostics::call_site(&ctx))?;
            check_scene(&ctx, &dataset.scene)?;
            Ok(dataset)
        },
    );
    super::beam_api::register(engine);
    super::damage_api::register(engine);
    super::frame_api::register(engine);
    super::frame_damage_api::register(engine);
    super::time_api::register(engine);
    super::sensor_api::register(engine);
    super::shape_api::register(engine, files);
    super::material_api::register(engine, materials);
    register_rng(engine);
}

fn param(params: &Params, name: &str, default: Dynamic) -> Fallible<Dynamic> {
    let value = match params.overrides.get(name) {
        None => default.clone(),
        Some(text) => parse_override(name, text, &default)?,
    };
    let json = if let Ok(i) = value.as_int() {
        serde_json::json!(i)
    } else if let Ok(f) = value.as_float() {
        if !f.is_finite() {
            return fail(format!(
                "param \"{name}\" = {} is not a finite number",
                number_shown(f)
            ));
        }
        serde_json::json!(f)
    } else if let Ok(b) = value.as_bool() {
        serde_json::json!(b)
    } else if value.is_string() {
        serde_json::json!(value.to_string())
    } else if let Some(words) = string_list(&value) {
        serde_json::json!(words)
    } else {
        return fail(format!(
            "param \"{name}\": the default must be a number, a bool, a string or a list of strings, not {}",
            default.type_name()
        ));
    };
    params
        .resolved
        .lock()
        .unwrap()
        .insert(name.to_string(), json);
    Ok(value)
}

fn parse_override(name: &str, text: &str, default: &Dynamic) -> Fallible<Dynamic> {
    let bad = |kind: &str| {
        format!(
            "--set {name}={text}: expected {kind} (the recipe's default is {})",
            shown(default)
        )
    };
    if default.is_int() {
        let text = text.trim();
        match text.parse::<i64>() {
            Ok(i) => Ok(Dynamic::from(i)),
            Err(e)
                if matches!(
                    e.kind(),
                    IntErrorKind::PosOverflow | IntErrorKind::NegOverflow
                ) =>
            {
                fail(format!(
                    "{}; a larger value, such as a seed up to 2^64 - 1, needs a parameter whose default is a string: param(\"{name}\", \"0\")",
                    bad(&format!("a whole number from {} to {}", i64::MIN, i64::MAX))
                ))
            }
            Err(_) => fail(bad("a whole number")),
        }
    } else if default.is_float() {
        match text.trim().parse::<f64>() {
            Ok(f) if f.is_finite() => Ok(Dynamic::from(f)),
            _ => fail(bad("a finite number")),
        }
    } else if default.is_bool() {
        text.trim()
            .parse::<bool>()
            .map(Dynamic::from)
            .map_err(|_| bad("true or false").into())
    } else if string_list(default).is_some() {
        list_override(text).map_err(|why| bad(&format!("a comma-separated list ({why})")).into())
    } else {
        Ok(Dynamic::from(text.to_string()))
    }
}

/// The strings of a list whose every item is a string (`["rgb", "depth"]`); None otherwise.
fn string_list(value: &Dynamic) -> Option<Vec<String>> {
    let list = value.read_lock::<Array>()?;
    list.iter()
        .map(|item| item.is_string().then(|| item.to_string()))
        .collect()
}

/// `--set outputs=rgb,depth,mesh` for a parameter whose default is a list of strings: the
/// items, trimmed; an empty item (`rgb,,depth`, or nothing at all) is refused rather than
/// read as a name.
fn list_override(text: &str) -> Result<Dynamic, &'static str> {
    let items: Vec<&str> = text.split(',').map(str::trim).collect();
    if items.iter().any(|item| item.is_empty()) {
        return Err("an item is empty");
    }
    Ok(Dynamic::from_array(
        items
            .into_iter()
            .map(|item| Dynamic::from(item.to_string()))
            .collect(),
    ))
}

fn dataset(map: Map, files: &RecipeFiles, site: SourceSite) -> OptResult<Dataset> {
    let mut o = Options::new(map, "dataset");
    let name = o.string("name", "dataset")?;
    let seed = o.unsigned("seed", 0)?;
    let samples = o.integer("samples", 1, 1, 1 << 40)? as u64;
    let views = o.integer("views", 1, 1, 100_000)? as u32;
    let background = background(o.take("background"), files)?;
    let light = match o.sub("light")? {
        Some(l) => light(l, files)?,
        None => LightSpec::default(),
    };
    let antialias = o.flag("antialias", true)?;
    let shading = o.choice("shading", &Shading::NAMES, Some("cached"))?;
    let shading = Shading::named(shading).expect("one of the names");
    let ground = super::ground_api::ground(o.take("ground"))?;
    let augment = super::augment_api::augment(o.take("augment"))?;
    let sensor = super::augment_api::sensor(o.take("sensor"))?;
    let sequence = super::time_api::sequence(o.sub("sequence")?, views)?;
    let outputs = outputs(o.take("outputs"))?;
    check_flow_warps(&outputs, &augment)?;
    check_frame_flow(&outputs, sequence.is_some())?;
    let normals = normals_frame(o.string("normals", "camera")?)?;
    let points = o.integer(
        "points",
        i64::from(DEFAULT_POINTS),
        1,
        i64::from(MAX_POINTS),
    )? as u32;
    let camera = match o.sub("camera")? {
        Some(c) => camera(c, views)?,
        None => CameraRig::default(),
    };
    augment.validate_with(&camera)?;
    let scene = o.required("scene")?;
    let scene = scene
        .try_cast::<FnPtr>()
        .ok_or("dataset.scene must be a function of the random source, like |rng| { ... }")?;
    o.finish()?;
    Ok(Dataset {
        spec: DatasetSpec {
            name,
            seed,
            samples,
            views,
            camera,
            outputs,
            background,
            light,
            antialias,
            shading,
            augment,
            sensor,
            normals,
            points,
            ground,
            sequence,
        },
        scene,
        site,
    })
}

/// The scene function must take the random source. Checked where the error can point at
/// `dataset(...)`, rather than left to Rhai's "function not found" when the scene is drawn.
fn check_scene(ctx: &NativeCallContext, scene: &FnPtr) -> OptResult<()> {
    let curried = scene.curry().len();
    let takes: Vec<usize> = ctx
        .iter_namespaces()
        .flat_map(|m| m.iter_script_fn_info())
        .filter(|(_, _, name, ..)| *name == scene.fn_name())
        .map(|(_, _, _, params, _)| params.saturating_sub(curried))
        .collect();
    match takes.as_slice() {
        [] => Ok(()),
        found if found.contains(&1) => Ok(()),
        [n, ..] => Err(format!(
            "dataset.scene takes {n} parameter{}; it must take one, the random source: |rng| {{ ... }}",
            if *n == 1 { "" } else { "s" }
        )),
    }
}

/// `outputs: ["rgb", "depth", ...]`: names of writers (see `output::WRITERS`).
fn outputs(value: Option<Dynamic>) -> OptResult<Outputs> {
    let known = output_names();
    let Some(value) = value else {
        return Ok(Outputs::new(&known, &DEFAULT_OUTPUTS));
    };
    let list = value
        .try_cast::<Array>()
        .ok_or("dataset.outputs must be a list like [\"rgb\", \"depth\", \"mask\"]")?;
    let mut chosen = Vec::new();
    for item in list {
        let name = item.to_string();
        match known.iter().find(|k| **k == name) {
            Some(&k) => chosen.push(k),
            None => {
                let hint = crate::words::nearest(&name, &known)
                    .map(|k| format!("; did you mean \"{k}\"?"))
                    .unwrap_or_default();
                return Err(format!(
                    "unknown output \"{name}\" in dataset.outputs{hint} (known: {})",
                    known.join(", ")
                ));
            }
        }
    }
    Ok(Outputs::new(&known, &chosen))
}

/// `normals: "camera"` (the view's OpenCV axes) or `"world"`.
fn normals_frame(name: String) -> OptResult<NormalsFrame> {
    match name.as_str() {
        "camera" => Ok(NormalsFrame::Camera),
        "world" => Ok(NormalsFrame::World),
        other => Err(format!(
            "dataset.normals = \"{}\": expected \"camera\" (the view's OpenCV axes: x right, y down, z forward) or \"world\" (+z up)",
            crate::words::clip(other, 80)
        )),
    }
}

/// The most points the `points` output may draw per sample (about 360 MB of PLY).
const MAX_POINTS: u32 = 10_000_000;

/// Flow relates the unloaded and loaded images pixel by pixel through one camera; an
/// image-space warp would move both images but leave the flow measured in the old frame (the
/// vectors would need turning and scaling, and targets leaving or entering the frame
/// re-checking), so the combination is refused rather than written subtly wrong.
fn check_flow_warps(outputs: &Outputs, augment: &AugmentSpec) -> OptResult<()> {
    let warps = augment.copies > 0
        && augment.mode == GeometryMode::Image
        && augment.operations.iter().any(Operation::is_geometric);
    for flow in ["flow", "frame_flow", "point_tracks"] {
        if warps && outputs.wants(flow) {
            return Err(format!(
                "dataset.outputs has \"{flow}\" and dataset.augment warps the images (mode \"image\"): flow is not defined on a warped image; use mode \"exact\" (the camera moves and the view is rendered again, flow included) or leave \"{flow}\" out"
            ));
        }
    }
    Ok(())
}

/// The flow between frames and the point tracks need frames: a still asking for them is
/// refused rather than given files no pixel or point of which is valid.
fn check_frame_flow(outputs: &Outputs, sequence: bool) -> OptResult<()> {
    let needing_frames = [
        ("frame_flow", "flow between consecutive frames"),
        ("point_tracks", "points tracked from the first frame"),
    ];
    for (output, what) in needing_frames {
        if outputs.wants(output) && !sequence {
            return Err(format!(
                "dataset.outputs has \"{output}\" ({what}) but the dataset has no dataset.sequence: declare one, or use \"flow\" (unloaded -> loaded image) for a still"
            ));
        }
    }
    Ok(())
}

/// `camera: #{ width, height, fov_y, principal_offset, distortion, aim_jitter, stereo, ... }`
/// with the poses on a sphere (`yaw`, `pitch`, `roll`, `distance`, `margin`), or one of
/// `fixed: [...]`, `orbit: #{...}`, `line: #{...}`.
fn camera(mut o: Options, views: u32) -> OptResult<CameraRig> {
    let d = CameraRig::default();
    let depth_of_field = match o.sub("depth_of_field")? {
        None => None,
        Some(mut l) => {
            let lens = DepthOfField {
                f_number: l.number("f_number", 2.8)?,
                focus_distance: l.required_number("focus_distance")?,
                sensor_width: l.number("sensor_width", 0.036)?,
            };
            l.finish()?;
            Some(lens)
        }
    };
    let width = o.integer("width", i64::from(d.width), 1, 16_384)? as u32;
    let height = o.integer("height", i64::from(d.height), 1, 16_384)? as u32;
    let fov_y = o.range("fov_y", d.fov_y)?;
    let principal_offset = match o.sub("principal_offset")? {
        None => d.principal_offset,
        Some(mut p) => {
            let offset = [p.range("x", [0.0; 2])?, p.range("y", [0.0; 2])?];
            p.finish()?;
            offset
        }
    };
    let distortion = match o.sub("distortion")? {
        None => d.distortion,
        Some(mut l) => {
            let lens = DistortionRanges {
                k1: l.range("k1", [0.0; 2])?,
                k2: l.range("k2", [0.0; 2])?,
                p1: l.range("p1", [0.0; 2])?,
                p2: l.range("p2", [0.0; 2])?,
                k3: l.range("k3", [0.0; 2])?,
            };
            l.finish()?;
            lens
        }
    };
    let aim_jitter = o.number("aim_jitter", d.aim_jitter)?;
    let stereo = match o.sub("stereo")? {
        None => None,
        Some(mut s) => {
            let stereo = Stereo {
                baseline: s.positive("baseline", "metres")?,
                toe_in: s.number("toe_in", 0.0)?,
            };
            s.finish()?;
            Some(stereo)
        }
    };
    let poses = poses(&mut o)?;
    o.finish()?;
    let rig = CameraRig {
        width,
        height,
        fov_y,
        principal_offset,
        distortion,
        poses,
        aim_jitter,
        stereo,
        depth_of_field,
    };
    rig.validate(views)?;
    if let Some(lens) = &rig.depth_of_field {
        lens.validate((width, height), fov_y[0])?;
    }
    Ok(rig)
}

/// `distance: [min, max]` or a number (metres), or `"frame"` (with `margin`, default 1.05).
fn distance(o: &mut Options) -> OptResult<Distance> {
    let margin = o.number("margin", 1.05)?;
    Ok(match o.take("distance") {
        None => Distance::Frame { margin },
        Some(v) if v.is_string() && v.to_string() == "frame" => Distance::Frame { margin },
        Some(v) => {
            let mut wrap = Map::new();
            wrap.insert("distance".into(), v);
            let [min, max] = Options::new(wrap, "dataset.camera").range("distance", [0.0, 0.0])?;
            Distance::Range { min, max }
        }
    })
}

/// The poses: `fixed`, `orbit` or `line` when given (only one), else the sphere's ranges.
fn poses(o: &mut Options) -> OptResult<Poses> {
    let fixed = o.take("fixed");
    let orbit = o.sub("orbit")?;
    let line = o.sub("line")?;
    match (fixed, orbit, line) {
        (None, None, None) => {
            let Poses::Sphere {
                yaw, pitch, roll, ..
            } = CameraRig::default().poses
            else {
                unreachable!("the default rig is a sphere")
            };
            Ok(Poses::Sphere {
                yaw: o.range("yaw", yaw)?,
                pitch: o.range("pitch", pitch)?,
                roll: o.range("roll", roll)?,
                distance: distance(o)?,
            })
        }
        (Some(list), None, None) => {
            let list = list.try_cast::<Array>().ok_or(
                "dataset.camera.fixed must be a list like [#{ position: [x, y, z], target: [x, y, z] }, ...]",
            )?;
            let cameras = list
                .into_iter()
                .enumerate()
                .map(|(i, item)| {
                    let path = format!("dataset.camera.fixed[{i}]");
                    let map = item.try_cast::<Map>().ok_or(format!(
                        "{path} must be a map like #{{ position: [x, y, z] }}"
                    ))?;
                    let mut c = Options::new(map, path.clone());
                    let camera = FixedCamera {
                        position: c
                            .point("position")?
                            .ok_or(format!("{path}.position is required"))?,
                        target: c.point("target")?,
                        roll: c.number("roll", 0.0)?,
                    };
                    c.finish()?;
                    Ok(camera)
                })
                .collect::<OptResult<Vec<_>>>()?;
            Ok(Poses::Fixed { cameras })
        }
        (None, Some(mut c), None) => {
            let poses = Poses::Orbit {
                distance: distance(&mut c)?,
                pitch: c.number("pitch", 0.0)?,
                yaw_start: c.number("yaw_start", 0.0)?,
                sweep: c.number("sweep", std::f64::consts::TAU)?,
                roll: c.number("roll", 0.0)?,
            };
            c.finish()?;
            Ok(poses)
        }
        (None, None, Some(mut c)) => {
            let poses = Poses::Line {
                from: c
                    .point("from")?
                    .ok_or("dataset.camera.line.from is required")?,
                to: c.point("to")?.ok_or("dataset.camera.line.to is required")?,
                target: c.point("target")?,
                roll: c.number("roll", 0.0)?,
            };
            c.finish()?;
            Ok(poses)
        }
        _ => Err("dataset.camera: give at most one of `fixed`, `orbit` and `line`".into()),
    }
}

/// `background: [r, g, b]`, `"black"`, `"sky"`, `#{ sky: #{ zenith, horizon, ground } }`,
/// `#{ images: "folder" }` or `#{ environment: "sky.hdr" }`.
fn background(value: Option<Dynamic>, files: &RecipeFiles) -> OptResult<Background> {
    let Some(value) = value else {
        return Ok(Background::Colour([0.0; 3]));
    };
    if value.is_string() {
        return match value.to_string().as_str() {
            "black" => Ok(Background::Colour([0.0; 3])),
            "sky" => Ok(Background::Sky {
                sky: SkyGradient::default(),
            }),
            other => Err(format!(
                "dataset.background = \"{other}\": expected \"black\", \"sky\", a colour [r, g, b], #{{ sky: #{{ ... }} }} or #{{ images: \"folder\" }}"
            )),
        };
    }
    if value.is_array() {
        return Ok(Background::Colour(options::colour(
            &value,
            "dataset.background",
        )?));
    }
    let map = value.try_cast::<Map>().ok_or(
        "dataset.background must be \"black\", \"sky\", a colour [r, g, b] or a map like #{ images: \"backgrounds\" }",
    )?;
    let mut o = Options::new(map, "dataset.background");
    let result = if let Some(mut sky) = o.sub("sky")? {
        let d = SkyGradient::default();
        let gradient = SkyGradient {
            zenith: sky.colour("zenith", d.zenith)?,
            horizon: sky.colour("horizon", d.horizon)?,
            ground: sky.colour("ground", d.ground)?,
        };
        sky.finish()?;
        Background::Sky { sky: gradient }
    } else if let Some(map) = o.take("environment") {
        Background::Environment {
            environment: super::environment_api::background_environment(map, files)?,
        }
    } else {
        let folder = o.string("images", "")?;
        if folder.is_empty() {
            return Err("dataset.background needs `sky`, `images` or `environment`".into());
        }
        let decoded = files.images_in(&folder, "dataset.background.images")?;
        Background::Images {
            images: folder,
            files: decoded
                .iter()
                .map(|f| ImageRecord {
                    file: f.name.clone(),
                    hash: f.hash.clone(),
                })
                .collect(),
            decoded,
        }
    };
    o.finish()?;
    Ok(result)
}

/// `light: #{ sun: #{ ... }, sky: #{ ... }, environment, ambient, shadows, studio, ground:
/// #{ height, albedo }, exposure, tone }`.
fn light(mut o: Options, files: &RecipeFiles) -> OptResult<LightSpec> {
    let sun = match o.sub("sun")? {
        None => None,
        Some(mut s) => {
            let d = SunSpec::default();
            let spec = SunSpec {
                elevation: s.range("elevation", d.elevation)?,
                azimuth: s.range("azimuth", d.azimuth)?,
                intensity: s.range("intensity", d.intensity)?,
                colour: s.colour("colour", d.colour)?,
                diameter: s.number("diameter", d.diameter)?,
                shadow_rays: s.integer("shadow_rays", i64::from(d.shadow_rays), 1, 256)? as u32,
            };
            s.finish()?;
            Some(spec)
        }
    };
    let sky = match o.sub("sky")? {
        None => None,
        Some(mut s) => {
            let d = SkySpec::default();
            let spec = SkySpec {
                intensity: s.range("intensity", d.intensity)?,
                colour: s.colour("colour", d.colour)?,
                ground: s.colour("ground", d.ground)?,
                occlusion_rays: s.integer("occlusion_rays", i64::from(d.occlusion_rays), 0, 256)?
                    as u32,
            };
            s.finish()?;
            Some(spec)
        }
    };
    let environment = super::environment_api::light_environment(o.take("environment"), files)?;
    let outdoor = sun.is_some() || sky.is_some() || environment.is_some();
    let default_ambient = if outdoor {
        [OUTDOOR_AMBIENT; 2]
    } else {
        LightSpec::default().ambient
    };
    let ambient = o.range("ambient", default_ambient)?;
    let shadows = o.flag("shadows", outdoor)?;
    let studio = o.flag("studio", !outdoor)?;
    let ground = match o.sub("ground")? {
        None => None,
        Some(mut g) => {
            let spec = GroundBounceSpec {
                height: g.number("height", 0.0)?,
                albedo: g.colour("albedo", [0.35, 0.33, 0.3])?,
            };
            g.finish()?;
            Some(spec)
        }
    };
    let exposure = o.number("exposure", 0.0)?;
    let tone = match o.choice("tone", &["clip", "filmic"], Some("clip"))? {
        "filmic" => Tone::Filmic,
        _ => Tone::Clip,
    };
    o.finish()?;
    let spec = LightSpec {
        studio,
        sun,
        sky,
        environment,
        ambient,
        shadows,
        ground,
        exposure,
        tone,
    };
    spec.validate()?;
    Ok(spec)
}

fn register_rng(engine: &mut Engine) {
    engine.register_type_with_name::<ScriptRng>("Rng");
    engine.register_get("sample", |r: &mut ScriptRng| r.1 as i64);
    engine.register_fn(
        "uniform",
        |r: &mut ScriptRng, lo: Dynamic, hi: Dynamic| -> Fallible<f64> {
            let (lo, hi) = (number(&lo, "uniform low")?, number(&hi, "uniform high")?);
            if lo > hi {
                return fail(format!(
                    "uniform({}, {}): the low end exceeds the high end",
                    number_shown(lo),
                    number_shown(hi)
                ));
            }
            Ok(r.0.lock().unwrap().uniform(lo, hi))
        },
    );
    engine.register_fn(
        "integer",
        |r: &mut ScriptRng, lo: i64, hi: i64| -> Fallible<i64> {
            if lo > hi {
                return fail(format!(
                    "integer({lo}, {hi}): the low end exceeds the high end"
                ));
            }
            Ok(r.0.lock().unwrap().integer(lo, hi))
        },
    );
    engine.register_fn(
        "chance",
        |r: &mut ScriptRng, p: Dynamic| -> Fallible<bool> {
            let p = number(&p, "chance probability")?;
            if !(0.0..=1.0).contains(&p) {
                return fail(format!(
                    "chance({}): the probability must lie in 0..1",
                    number_shown(p)
                ));
            }
            Ok(r.0.lock().unwrap().unit() < p)
        },
    );
    engine.register_fn(
        "choice",
        |r: &mut ScriptRng, items: Array| -> Fallible<Dynamic> {
            if items.is_empty() {
                return fail("choice([]): cannot choose from an empty list".to_string());
            }
            let i = r.0.lock().unwrap().integer(0, items.len() as i64 - 1);
            Ok(items[i as usize].clone())
        },
    );
}
