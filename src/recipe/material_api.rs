//! The material part of the recipe API: `.material("a photo of rusty steel")` and
//! `.material("...", #{ ... })` on beams and assemblies, and `.colour([r, g, b])`.
//!
//! A prompt compiles into a procedural material (`materials::prompt`). An image in the recipe's
//! `textures/` folder named after the prompt (`textures/rusty-steel.png` for "rusty steel")
//! replaces the procedural albedo, so textures made elsewhere drop in without editing the
//! recipe; `texture: "file.png"` names one explicitly. `plain: true` keeps only the colour of
//! the prompt's substance or paint, flat and matte (no conditions, texture or gloss): a run
//! that needs the geometry more than the look is several times faster (see
//! docs/benchmarks.md).

use super::diagnostics::Warnings;
use super::files::RecipeFiles;
use super::options::{self, OptResult, Options};
use super::result::Fallible;
use crate::materials::{Material, Texture, prompt};
use crate::scene::{AssemblySpec, BeamSpec};
use crate::words::{clip, number};
use rhai::{Array, Dynamic, Engine, EvalAltResult, ImmutableString, Map, NativeCallContext};
use std::sync::Arc;

/// Longest material prompt, characters. Every warning about a prompt quotes it, so a prompt of
/// many unknown words would otherwise take memory quadratic in its length.
pub const MAX_PROMPT_CHARS: usize = 1000;

/// Where textures keyed by prompt live, relative to the recipe.
pub const TEXTURES_FOLDER: &str = "textures";

/// What the material calls need from the recipe.
#[derive(Clone)]
pub struct MaterialContext {
    pub files: Arc<RecipeFiles>,
    pub warnings: Arc<Warnings>,
    /// Label of the recipe, for warnings raised where no other source is known.
    pub label: String,
}

pub fn register(engine: &mut Engine, context: MaterialContext) {
    register_for::<BeamSpec>(engine, &context, |b| &mut b.material);
    register_for::<AssemblySpec>(engine, &context, |a| &mut a.material);
    register_for::<crate::scene::FrameSpec>(engine, &context, |f| &mut f.material);
}

fn register_for<T: Clone + Send + Sync + 'static>(
    engine: &mut Engine,
    context: &MaterialContext,
    material: fn(&mut T) -> &mut Material,
) {
    let c = context.clone();
    engine.register_fn(
        "material",
        move |ctx: NativeCallContext, s: &mut T, text: ImmutableString| -> Fallible<T> {
            *material(s) = compile(&ctx, &c, &text, Map::new())?;
            Ok(s.clone())
        },
    );
    let c = context.clone();
    engine.register_fn(
        "material",
        move |ctx: NativeCallContext, s: &mut T, text: ImmutableString, o: Map| -> Fallible<T> {
            *material(s) = compile(&ctx, &c, &text, o)?;
            Ok(s.clone())
        },
    );
    engine.register_fn("colour", move |s: &mut T, rgb: Array| -> Fallible<T> {
        *material(s) = Material::plain(options::colour(&Dynamic::from(rgb), "colour")?);
        Ok(s.clone())
    });
}

/// Compiles `text` with the options of `.material(text, #{ ... })`, reporting warnings at the
/// call.
fn compile(
    ctx: &NativeCallContext,
    c: &MaterialContext,
    text: &str,
    options: Map,
) -> Result<Material, Box<EvalAltResult>> {
    let at = |msg: String| Box::new(EvalAltResult::ErrorRuntime(msg.into(), ctx.call_position()));
    let mut o = Options::new(options, "material options");
    let strict = o.flag("strict", false).map_err(at)?;
    if text.chars().nth(MAX_PROMPT_CHARS).is_some() {
        return Err(at(format!(
            "material prompt \"{}\" is longer than {MAX_PROMPT_CHARS} characters; a prompt is a short description such as \"a photo of rusty steel\"",
            clip(text, 40)
        )));
    }
    let compiled = prompt::compile(text, strict).map_err(at)?;
    let label = ctx.call_source().unwrap_or(&c.label);
    for warning in &compiled.warnings {
        c.warnings.warn(warning, label, ctx.call_position());
    }
    let mut material = compiled.material;
    adjust(&mut material, &mut o, &c.files, text).map_err(at)?;
    o.finish().map_err(at)?;
    Ok(material)
}

/// Applies the explicit options over the compiled prompt.
fn adjust(m: &mut Material, o: &mut Options, files: &RecipeFiles, text: &str) -> OptResult<()> {
    if let Some(v) = o.take("colour") {
        m.colour = options::colour(&v, "material options.colour")?;
    }
    if o.flag("plain", false)? {
        return make_plain(m, o);
    }
    m.roughness = o.number("roughness", m.roughness)?;
    m.specular = o.number("specular", m.specular)?;
    m.scale = o.number("scale", m.scale)?;
    let size = o.number("texture_size", 1.0)?;
    if !(m.roughness > 0.0 && m.roughness <= 1.0) {
        return Err(format!(
            "material options.roughness = {} must lie in (0, 1]",
            number(m.roughness)
        ));
    }
    if !(0.0..=1.0).contains(&m.specular) {
        return Err(format!(
            "material options.specular = {} must lie in [0, 1]",
            number(m.specular)
        ));
    }
    for (name, value) in [("scale", m.scale), ("texture_size", size)] {
        if value <= 0.0 {
            return Err(format!(
                "material options.{name} = {} must be positive (metres)",
                number(value)
            ));
        }
    }
    let explicit = o.string("texture", "")?;
    let chosen = if explicit.is_empty() {
        files
            .image_named(TEXTURES_FOLDER, &slug(text))?
            .map(|f| (f, "prompt"))
    } else {
        Some((
            files.image(&explicit, "material options.texture")?,
            "explicit",
        ))
    };
    if let Some((file, how)) = chosen {
        m.texture = Texture::Image {
            file: file.name,
            hash: file.hash,
            size,
            chosen: how.to_string(),
            pixels: file.image,
        };
    }
    Ok(())
}

/// The material's colour alone, flat and matte (`plain: true`); an option that would shape
/// what it leaves out is an error rather than ignored.
fn make_plain(m: &mut Material, o: &mut Options) -> OptResult<()> {
    for unused in ["roughness", "specular", "scale", "texture", "texture_size"] {
        if let Some(value) = o.take(unused) {
            return Err(format!(
                "material options.{unused} = {} has no effect beside material options.plain = \
                 true (a flat matte colour): drop one of them",
                options::shown(&value)
            ));
        }
    }
    // The prompt stays in the record: what this flat colour stands in for.
    *m = Material {
        prompt: m.prompt.take(),
        ..Material::plain(m.colour)
    };
    Ok(())
}

/// The file name a prompt's texture goes by: lower case, words joined by '-'.
pub fn slug(text: &str) -> String {
    text.to_lowercase()
        .split(|c: char| !c.is_alphanumeric())
        .filter(|w| !w.is_empty())
        .collect::<Vec<_>>()
        .join("-")
}
