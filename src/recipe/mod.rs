//! The recipe runtime: runs a Rhai recipe and turns it into plain scene descriptions.
//!
//! Owns: the sandboxed engine, module imports, recipe parameters (`param` and `--set`),
//! the recipe API (structures, materials from prompts, light, backgrounds), error reporting
//! with file:line:col and warnings. Must not touch: meshing, rendering, or files other than the
//! recipe, the modules it imports and the mesh, texture and background images it names (all
//! inside the recipe's folder or `stdlib/`). A recipe is evaluated once to get the dataset
//! settings; its scene function is then called once per sample with a random
//! source derived from (seed, sample, "scene"), so samples can be drawn in any order, on any
//! thread, with the same result.

mod access;
mod api;
mod augment_api;
mod beam_api;
mod damage_api;
mod diagnostics;
mod engine;
mod environment_api;
mod files;
mod frame_api;
mod frame_damage_api;
mod ground_api;
mod material_api;
mod memory;
mod option_sites;
mod options;
mod result;
mod sensor_api;
mod shape_api;
mod time_api;

use diagnostics::Callable;
pub use diagnostics::RecipeError;
pub use engine::stdlib_dir;
pub use memory::CountingAllocator;

use crate::scene::{
    AssemblySpec, BeamSpec, DatasetSpec, FrameSpec, SceneSpec, SourceSite, Structure,
};
use crate::seeds::{self, Scope as StreamScope, Stream};
use api::{Dataset, Params, ScriptRng};
use engine::{Resolver, Sources};
use rhai::{AST, ASTNode, Array, Dynamic, Engine, FnPtr, Position, Scope, Stmt};
use std::collections::BTreeMap;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A loaded recipe, ready to draw samples from.
pub struct Recipe {
    /// The recipe file.
    pub path: PathBuf,
    /// The dataset the recipe declared, with every value resolved and validated.
    pub dataset: DatasetSpec,
    /// Resolved value of every declared parameter.
    pub params: BTreeMap<String, serde_json::Value>,
    /// Content hash (blake3, hex) of the recipe, every module it imports and every file it
    /// reads (meshes, textures, images).
    pub hash: String,
    label: String,
    engine: Engine,
    ast: AST,
    scene: FnPtr,
    /// Where the recipe calls `dataset(...)`.
    dataset_site: SourceSite,
    sources: Arc<Sources>,
}

impl Recipe {
    /// Compiles and evaluates the recipe at `path` with `--set` overrides.
    pub fn load(path: &Path, overrides: &[(String, String)]) -> Result<Recipe, RecipeError> {
        on_script_stack(|| Self::load_here(path, overrides))?
    }

    fn load_here(path: &Path, overrides: &[(String, String)]) -> Result<Recipe, RecipeError> {
        let _budget = memory::Budget::start();
        let text = access::read_regular(path, access::Kind::Source)
            .and_then(access::source_text)
            .map_err(|e| {
                RecipeError::plain(format!("cannot read recipe {}: {e}", path.display()))
            })?;
        let label = path.display().to_string();
        let sources = Arc::new(Sources::default());
        sources.insert(&label, &text);
        let folder = match path.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let resolver = Arc::new(Resolver::new(&folder, sources.clone()));
        let params = Arc::new(Params {
            overrides: overrides.iter().cloned().collect(),
            ..Params::default()
        });
        let materials = material_api::MaterialContext {
            files: Arc::new(files::RecipeFiles::new(&folder, sources.clone())),
            warnings: Arc::new(diagnostics::Warnings::new(sources.clone())),
            label: label.clone(),
        };

        let new_engine = || {
            let mut engine = engine::sandboxed(resolver.clone());
            api::register(&mut engine, params.clone(), materials.clone());
            engine
        };
        let engine = new_engine();
        let mut ast = engine
            .compile(&text)
            .map_err(|e| RecipeError::parse(&e, &label, &sources))?;
        ast.set_source(label.as_str());
        let callable = Callable {
            engine: &engine,
            ast: Some(&ast),
        };
        let result: Dynamic = engine
            .eval_ast_with_scope(&mut Scope::new(), &ast)
            .map_err(|e| RecipeError::eval(&e, &label, &sources, None, &callable))?;
        let type_name = result.type_name().to_string();
        let Some(Dataset { spec, scene, site }) = result.try_cast::<Dataset>() else {
            return Err(RecipeError::plain(format!(
                "{label}: the recipe must end with `dataset(#{{ ... }})` as its last expression (it produced {type_name})"
            )));
        };

        // Closures called later no longer see the recipe's imports: give them the imported
        // modules as static modules under the same aliases.
        let mut sample_engine = new_engine();
        for (module, alias) in imports(&ast) {
            let m = resolver
                .resolve(&engine, &module, Position::NONE)
                .map_err(|e| RecipeError::eval(&e, &label, &sources, None, &callable))?;
            sample_engine.register_static_module(alias, m);
        }
        let mut recipe = Recipe {
            path: path.to_path_buf(),
            dataset: spec,
            params: BTreeMap::new(),
            hash: String::new(),
            label,
            engine: sample_engine,
            ast,
            scene,
            dataset_site: site,
            sources: sources.clone(),
        };
        // Parameters may also be declared inside the scene function: draw one scene before
        // deciding which `--set` names are unknown.
        recipe.scene_here(0)?;
        recipe.params = resolved_params(&params, overrides)?;
        recipe.hash = sources.hash();
        Ok(recipe)
    }

    /// Draws the scene of one sample.
    pub fn scene(&self, sample: u64) -> Result<SceneSpec, RecipeError> {
        on_script_stack(|| self.scene_here(sample))?
    }

    /// Draws the scenes of `samples` in order, handing each outcome to `visit`, until it
    /// returns `Break`. All on one script thread: setting one up per sample would take as long
    /// as drawing a small scene.
    pub fn each_scene(
        &self,
        samples: std::ops::Range<u64>,
        mut visit: impl FnMut(u64, Result<SceneSpec, RecipeError>) -> ControlFlow<()> + Send,
    ) -> Result<(), RecipeError> {
        on_script_stack(|| {
            for sample in samples {
                if visit(sample, self.scene_here(sample)).is_break() {
                    break;
                }
            }
        })
    }

    fn scene_here(&self, sample: u64) -> Result<SceneSpec, RecipeError> {
        let context = format!("while drawing the scene of sample {sample}");
        let rng = ScriptRng::new(
            Stream::new(self.dataset.seed, StreamScope::Sample(sample), seeds::SCENE),
            sample,
        );
        let _budget = memory::Budget::start();
        // Captured variables are shared cells; give each call private copies so that a scene
        // function that mutates them cannot make one sample depend on another.
        let mut scene = self.scene.clone();
        let private: Vec<Dynamic> = scene.curry().iter().map(Dynamic::flatten_clone).collect();
        scene.set_curry(private);
        let callable = Callable {
            engine: &self.engine,
            ast: Some(&self.ast),
        };
        let value: Dynamic = scene.call(&self.engine, &self.ast, (rng,)).map_err(|e| {
            RecipeError::eval(&e, &self.label, &self.sources, Some(&context), &callable)
        })?;
        let structures = structures(value)
            .map_err(|m| RecipeError::plain(format!("{}: {m} ({context})", self.label)))?;
        Ok(SceneSpec { structures })
    }

    /// An error found while building what the recipe described, pointing at the call that
    /// declared it when that is known.
    pub fn locate(&self, message: &str, site: Option<&SourceSite>, context: &str) -> RecipeError {
        match site {
            // Calls inside the scene closure carry no source name: they are in the recipe.
            Some(site) if site.source.is_empty() => {
                let site = SourceSite {
                    source: self.label.clone(),
                    ..site.clone()
                };
                RecipeError::at(message, &site, &self.sources, Some(context))
            }
            Some(site) => RecipeError::at(message, site, &self.sources, Some(context)),
            None => RecipeError::plain(format!("{}: {message} ({context})", self.label)),
        }
    }

    /// An error found in the dataset's settings once a sample exists (its cameras against its
    /// structures), shown at the recipe's `dataset(...)` call.
    pub fn locate_dataset(&self, message: &str, context: &str) -> RecipeError {
        self.locate(message, Some(&self.dataset_site), context)
    }

    /// The files this recipe was built from so far, for a watcher: the recipe, the modules it
    /// imported from disk and the mesh and image files its scenes read (a file named only by
    /// a sample not yet drawn is not known yet). Built-in modules have no file and are left out.
    pub fn watched_paths(&self) -> Vec<PathBuf> {
        self.sources
            .labels()
            .into_iter()
            .map(PathBuf::from)
            .filter(|p| p.is_file())
            .collect()
    }
}

/// Stack for evaluating a script, bytes. Rhai evaluates recursively: the deepest nesting its
/// limits allow (64 calls, each 64 expressions deep) overflows the 2 MiB of a worker thread.
/// Only the pages a script touches are committed.
const SCRIPT_STACK: usize = 64 << 20;

/// Runs `f` on a thread of its own with `SCRIPT_STACK` of stack, so that a deep script ends in
/// Rhai's error for its limits rather than a stack overflow of the whole process.
fn on_script_stack<T: Send>(f: impl FnOnce() -> T + Send) -> Result<T, RecipeError> {
    std::thread::scope(|scope| {
        let thread = std::thread::Builder::new()
            .name("recipe script".into())
            .stack_size(SCRIPT_STACK)
            .spawn_scoped(scope, f)
            .map_err(|e| {
                RecipeError::plain(format!("cannot start a thread for the recipe: {e}"))
            })?;
        Ok(thread
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
    })
}

/// The structures a scene function returned: one structure, or a list of them.
fn structures(value: Dynamic) -> Result<Vec<Structure>, String> {
    let type_name = value.type_name().to_string();
    let list = if value.is_array() {
        value.cast::<Array>()
    } else {
        vec![value]
    };
    if list.is_empty() {
        return Err("the scene function returned an empty list; it must return a structure or a list of them".into());
    }
    list.into_iter()
        .map(|item| {
            let t = item.type_name().to_string();
            let item = match item.try_cast_result::<BeamSpec>() {
                Ok(beam) => return Ok(Structure::Beam(beam)),
                Err(other) => other,
            };
            let item = match item.try_cast_result::<FrameSpec>() {
                Ok(frame) => return Ok(Structure::Frame(frame)),
                Err(other) => other,
            };
            item.try_cast::<AssemblySpec>().map(Structure::Assembly).ok_or(format!(
                "the scene function must return structures (beams, frames or assemblies), or a list of them, not {}",
                if t == type_name { t } else { format!("a list containing {t}") }
            ))
        })
        .collect()
}

fn resolved_params(
    params: &Params,
    overrides: &[(String, String)],
) -> Result<BTreeMap<String, serde_json::Value>, RecipeError> {
    let resolved = params.resolved.lock().unwrap().clone();
    for (name, value) in overrides {
        if !resolved.contains_key(name) {
            let known: Vec<&str> = resolved.keys().map(String::as_str).collect();
            let hint = crate::words::nearest(name, &known)
                .map(|k| format!("; did you mean `{k}`?"))
                .unwrap_or_default();
            return Err(RecipeError::plain(format!(
                "--set {name}={value}: the recipe declares no parameter `{name}`{hint} (it declares: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            )));
        }
    }
    Ok(resolved)
}

/// (module path, alias) of every `import` in the recipe's top level.
fn imports(ast: &AST) -> Vec<(String, String)> {
    let mut found = Vec::new();
    ast.walk(&mut |path: &[ASTNode]| {
        if let [ASTNode::Stmt(Stmt::Import(x, _))] = path {
            let module =
                x.0.get_literal_value(None)
                    .and_then(|v| v.into_immutable_string().ok());
            if let (Some(module), alias) = (module, &x.1.name)
                && !alias.is_empty()
            {
                found.push((module.to_string(), alias.to_string()));
            }
        }
        true
    });
    found
}
