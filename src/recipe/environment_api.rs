//! `environment` options: an equirectangular environment map named by the recipe, as the
//! background (`dataset.background`) and/or the light (`dataset.light`). `environment:
//! "sky.hdr"` is short for `environment: #{ file: "sky.hdr" }`. Reads the file through
//! `RecipeFiles` (inside the recipe's folder, hashed into the dataset's identity); owns only
//! the option syntax and its checks.

use super::files::RecipeFiles;
use super::options::{OptResult, Options};
use crate::scene::{EnvironmentLightSpec, EnvironmentSpec};
use rhai::{Dynamic, Map};

/// Ambient-occlusion rays per shaded point under an environment map, unless the recipe says.
pub const DEFAULT_OCCLUSION_RAYS: u32 = 16;

/// The map of `dataset.<context>.environment`, from a file name or a map of options; the
/// options it does not know are left in the returned `Options` for the caller.
fn map_options(value: Dynamic, context: &str) -> OptResult<(String, Option<Options>)> {
    let what = format!("dataset.{context}.environment");
    if value.is_string() {
        return Ok((value.to_string(), None));
    }
    let map = value.try_cast::<Map>().ok_or_else(|| {
        format!("{what} must be a file name like \"sky.hdr\" or a map like #{{ file: \"sky.hdr\", intensity: 1.0, rotation: 0.0 }}")
    })?;
    let mut o = Options::new(map, what);
    let file = o.string("file", "")?;
    Ok((file, Some(o)))
}

/// Reads the map and its placement (`intensity`, `rotation`) from `o`, if given.
fn placed(
    file: String,
    o: Option<&mut Options>,
    files: &RecipeFiles,
    what: &str,
) -> OptResult<EnvironmentSpec> {
    if file.is_empty() {
        return Err(format!(
            "{what} needs a `file`, a Radiance .hdr image next to the recipe"
        ));
    }
    let (intensity, rotation) = match o {
        Some(o) => (o.number("intensity", 1.0)?, o.number("rotation", 0.0)?),
        None => (1.0, 0.0),
    };
    if !(0.0..=1e6).contains(&intensity) {
        return Err(format!(
            "{what}.intensity = {intensity} must lie within [0, 1e6]"
        ));
    }
    if !rotation.is_finite() {
        return Err(format!(
            "{what}.rotation = {rotation} must be a finite angle in radians"
        ));
    }
    let (hash, map) = files.environment(&file, what)?;
    Ok(EnvironmentSpec {
        file,
        hash,
        intensity,
        rotation,
        map,
    })
}

/// `dataset.background.environment`: `"sky.hdr"` or `#{ file, intensity, rotation }`.
pub fn background_environment(value: Dynamic, files: &RecipeFiles) -> OptResult<EnvironmentSpec> {
    let what = "dataset.background.environment";
    let (file, mut o) = map_options(value, "background")?;
    let spec = placed(file, o.as_mut(), files, what)?;
    o.map_or(Ok(()), Options::finish)?;
    Ok(spec)
}

/// `dataset.light.environment`: `"sky.hdr"` or `#{ file, intensity, rotation,
/// occlusion_rays }`.
pub fn light_environment(
    value: Option<Dynamic>,
    files: &RecipeFiles,
) -> OptResult<Option<EnvironmentLightSpec>> {
    let Some(value) = value else {
        return Ok(None);
    };
    let what = "dataset.light.environment";
    let (file, mut o) = map_options(value, "light")?;
    let map = placed(file, o.as_mut(), files, what)?;
    let occlusion_rays = match o.as_mut() {
        Some(o) => o.integer("occlusion_rays", i64::from(DEFAULT_OCCLUSION_RAYS), 0, 256)? as u32,
        None => DEFAULT_OCCLUSION_RAYS,
    };
    o.map_or(Ok(()), Options::finish)?;
    Ok(Some(EnvironmentLightSpec {
        map,
        occlusion_rays,
    }))
}
