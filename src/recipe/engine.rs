//! The sandboxed Rhai engine and the module resolver.
//!
//! Recipes get no file, process, network or clock access. The only way to reach another file
//! is `import "name" as alias;`, which finds `name.rhai` in the recipe's own folder or in
//! `stdlib/` — nowhere else, symlinks included (see `access`). Limits bound the work and the
//! memory any script can use, so an endless loop or an ever-growing map becomes an error
//! instead of a hang or a crash, and `sleep` is refused.

use super::access::{Allowed, Kind, source_text};
use super::memory;
use super::result::{Fallible, fail};
use crate::words::clip;
use rhai::{Dynamic, Engine, EvalAltResult, Module, Position, Scope, Shared};
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

/// Operations one script evaluation (the recipe, or one sample's scene) may perform.
pub const MAX_OPERATIONS: u64 = 20_000_000;

/// The standard library shipped inside the binary, used when no `stdlib/` folder is found.
const EMBEDDED_STDLIB: &[(&str, &str)] = &[
    ("beam", include_str!("../../stdlib/beam.rhai")),
    ("column", include_str!("../../stdlib/column.rhai")),
    (
        "portal_frame",
        include_str!("../../stdlib/portal_frame.rhai"),
    ),
    ("silo", include_str!("../../stdlib/silo.rhai")),
];

/// The folder searched for standard-library modules: `$SHMGEN_STDLIB`, else the repository's.
pub fn stdlib_dir() -> PathBuf {
    std::env::var_os("SHMGEN_STDLIB")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("stdlib"))
}

/// Every source file a recipe used, by the label that appears in diagnostics; the first file
/// recorded is the recipe itself.
#[derive(Default)]
pub struct Sources(Mutex<BTreeMap<String, String>>, OnceLock<String>);

/// Label prefix of the modules of the standard library built into the binary (see
/// `Resolver::find`).
const BUILT_IN_STDLIB: &str = "<built-in stdlib>/";

impl Sources {
    pub fn insert(&self, label: &str, text: &str) {
        self.1.get_or_init(|| label.to_string());
        self.0
            .lock()
            .unwrap()
            .insert(label.to_string(), text.to_string());
    }

    pub fn line(&self, label: &str, line: usize) -> Option<String> {
        self.0
            .lock()
            .unwrap()
            .get(label)?
            .lines()
            .nth(line.checked_sub(1)?)
            .map(str::to_string)
    }

    /// The label of every file, in label order.
    pub fn labels(&self) -> Vec<String> {
        self.0.lock().unwrap().keys().cloned().collect()
    }

    /// Content hash over every file, whatever the spelling of the paths the run was given
    /// (`r.rhai`, `./r.rhai`, an absolute path, another working directory): the recipe counts
    /// by its content alone (a renamed or moved copy is the same recipe), every other file by
    /// the name the recipe reaches it by — its path inside the folder it was found in, the
    /// recipe's folder or the standard library — and its content. Files are hashed in order
    /// of that name, never of their labels.
    pub fn hash(&self) -> String {
        let files = self.0.lock().unwrap();
        let recipe = self.1.get();
        let folder = recipe.map(|label| match Path::new(label).parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
            _ => PathBuf::from("."),
        });
        let roots: Vec<PathBuf> = folder
            .into_iter()
            .chain([stdlib_dir()])
            .filter_map(|root| std::fs::canonicalize(root).ok())
            .collect();
        let mut entries: Vec<(String, &str)> = files
            .iter()
            .map(|(label, text)| {
                let name = if Some(label) == recipe {
                    String::new()
                } else {
                    name_in_roots(label, &roots)
                };
                (name, text.as_str())
            })
            .collect();
        entries.sort_unstable();
        let mut h = blake3::Hasher::new();
        for (name, text) in &entries {
            for part in [name.as_str(), text] {
                h.update(&(part.len() as u64).to_le_bytes());
                h.update(part.as_bytes());
            }
        }
        h.finalize().to_hex().to_string()
    }
}

/// The name a source file is reached by: its path (with `/`) inside the innermost of `roots`
/// (canonical folders) that holds it, else its file name.
fn name_in_roots(label: &str, roots: &[PathBuf]) -> String {
    if let Some(module) = label.strip_prefix(BUILT_IN_STDLIB) {
        return module.to_string();
    }
    let path = Path::new(label);
    let file_name = path.file_name().map(Path::new).unwrap_or(path);
    // Canonicalise the folder, not the file: a symlinked file keeps the name it was read by.
    let canonical = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => std::fs::canonicalize(parent),
        _ => std::fs::canonicalize("."),
    }
    .map(|folder| folder.join(file_name));
    roots
        .iter()
        .filter_map(|root| canonical.as_ref().ok()?.strip_prefix(root).ok())
        .min_by_key(|relative| relative.components().count())
        .map(|relative| {
            let parts: Vec<_> = relative.iter().map(|c| c.to_string_lossy()).collect();
            parts.join("/")
        })
        .unwrap_or_else(|| file_name.to_string_lossy().to_string())
}

/// Deepest nesting of expressions and blocks at the top level of a script.
pub const MAX_EXPR_DEPTH: usize = 128;
/// Deepest nesting of expressions and blocks inside a function.
pub const MAX_FUNCTION_EXPR_DEPTH: usize = 64;
/// Deepest nesting of function calls.
pub const MAX_CALL_LEVELS: usize = 64;
/// Longest string a script may build, bytes.
pub const MAX_STRING_BYTES: usize = 1 << 20;
/// Most elements an array may hold, nested arrays and maps included.
pub const MAX_ARRAY_ELEMENTS: usize = 1 << 20;
/// Most properties a map may hold, nested maps included.
pub const MAX_MAP_PROPERTIES: usize = 1 << 16;
/// Lines of `print` and `debug` output shown per recipe load.
pub const MAX_PRINT_LINES: usize = 1000;
/// Characters shown of one line of `print` or `debug` output.
pub const MAX_PRINT_CHARS: usize = 1000;

/// A fresh engine with the sandbox limits; `register` adds the shmgen API.
///
/// Rhai checks the size limits on each value a function returns, but not on a map or array
/// that an indexed assignment (`m[k] = v`) grows, and they bound neither the number of values
/// nor what they hold together; so the memory a script allocates is bounded as well
/// ([`memory::MAX_SCRIPT_BYTES`] per evaluation), checked at every operation.
pub fn sandboxed(resolver: Arc<Resolver>) -> Engine {
    let mut engine = Engine::new();
    engine
        .set_max_operations(MAX_OPERATIONS)
        .set_max_call_levels(MAX_CALL_LEVELS)
        .set_max_expr_depths(MAX_EXPR_DEPTH, MAX_FUNCTION_EXPR_DEPTH)
        .set_max_string_size(MAX_STRING_BYTES)
        .set_max_array_size(MAX_ARRAY_ELEMENTS)
        .set_max_map_size(MAX_MAP_PROPERTIES)
        .set_max_modules(64)
        .set_max_variables(10_000)
        .set_max_functions(10_000)
        .set_strict_variables(true)
        .set_fail_on_invalid_map_property(true)
        .set_module_resolver(SharedResolver(resolver.clone()));
    // `eval` would compile strings at run time, outside the positions we can report.
    engine.disable_symbol("eval");
    // Recipes never wait: a sample must take the same time whatever the script says.
    // Registered functions take precedence over Rhai's, by name and through `Fn("sleep")`.
    engine.register_fn("sleep", |_: i64| -> Fallible<()> { no_sleep() });
    engine.register_fn("sleep", |_: f64| -> Fallible<()> { no_sleep() });
    engine.on_progress(|_| memory::over_budget().then(|| Dynamic::from(OUT_OF_MEMORY)));
    let printer = resolver.clone();
    engine.on_print(move |s| printer.print(&format!("recipe: {s}")));
    engine.on_debug(move |s, src, pos| {
        resolver.print(&format!("recipe debug {}:{pos}: {s}", src.unwrap_or("")))
    });
    engine
}

/// What `on_progress` stops a script with when it allocated too much.
pub const OUT_OF_MEMORY: &str = "shmgen: script memory budget exceeded";

fn no_sleep() -> Fallible<()> {
    fail("sleep: recipes cannot wait (a recipe must run the same at any speed)".to_string())
}

/// Finds `import`ed modules in the recipe's folder, then in the standard library.
pub struct Resolver {
    folders: Vec<PathBuf>,
    allowed: Allowed,
    sources: Arc<Sources>,
    printed: AtomicUsize,
    cache: Mutex<BTreeMap<String, Shared<Module>>>,
    loading: Mutex<HashSet<(std::thread::ThreadId, String)>>,
}

impl Resolver {
    pub fn new(recipe_folder: &Path, sources: Arc<Sources>) -> Self {
        Resolver {
            folders: vec![recipe_folder.to_path_buf(), stdlib_dir()],
            allowed: Allowed::new(recipe_folder),
            sources,
            printed: AtomicUsize::new(0),
            cache: Mutex::default(),
            loading: Mutex::default(),
        }
    }

    pub fn resolve(
        &self,
        engine: &Engine,
        path: &str,
        pos: Position,
    ) -> Result<Shared<Module>, Box<EvalAltResult>> {
        let runtime = |msg: String| Box::new(EvalAltResult::ErrorRuntime(msg.into(), pos));
        if !is_module_name(path) {
            return Err(runtime(format!(
                "import \"{path}\": a module is named like \"beam\" or \"frames/portal\" (letters, digits, _ and -; no '..', no absolute paths, no extension)"
            )));
        }
        if let Some(m) = self.cache.lock().unwrap().get(path) {
            return Ok(m.clone());
        }
        let found = self
            .find(path)
            .map_err(|e| runtime(format!("import \"{path}\": {e}")))?;
        let (label, text) = found.ok_or_else(|| {
            let searched: Vec<String> = self
                .folders
                .iter()
                .map(|f| f.display().to_string())
                .collect();
            runtime(format!(
                "module \"{path}\" not found: looked for {path}.rhai in {}",
                searched.join(" and ")
            ))
        })?;
        let key = (std::thread::current().id(), path.to_string());
        if !self.loading.lock().unwrap().insert(key.clone()) {
            return Err(runtime(format!(
                "module \"{path}\" imports itself (circular import)"
            )));
        }
        self.sources.insert(&label, &text);
        let result = compile_module(engine, &label, &text, pos);
        self.loading.lock().unwrap().remove(&key);
        let module = result?;
        self.cache
            .lock()
            .unwrap()
            .insert(path.to_string(), module.clone());
        Ok(module)
    }

    /// Prints a line of the recipe's `print` or `debug` output, within the output limits.
    fn print(&self, line: &str) {
        match self.printed.fetch_add(1, Ordering::Relaxed) {
            n if n < MAX_PRINT_LINES => eprintln!("{}", clip(line, MAX_PRINT_CHARS)),
            MAX_PRINT_LINES => eprintln!(
                "recipe: (more than {MAX_PRINT_LINES} lines of print and debug output: the rest is not shown)"
            ),
            _ => {}
        }
    }

    /// The label and text of module `path`: the first `path.rhai` in the search folders, else
    /// the built-in copy. A file that is there but may not be read (outside the allowed folders,
    /// not a regular file, too large, not UTF-8) is an error, not a reason to look further.
    fn find(&self, path: &str) -> Result<Option<(String, String)>, String> {
        for folder in &self.folders {
            let file = folder.join(format!("{path}.rhai"));
            if let Some(bytes) = self.allowed.read(&file, Kind::Source)? {
                let text = source_text(bytes).map_err(|e| format!("{}: {e}", file.display()))?;
                return Ok(Some((file.display().to_string(), text)));
            }
        }
        Ok(EMBEDDED_STDLIB
            .iter()
            .find(|(name, _)| *name == path)
            .map(|(name, text)| (format!("<built-in stdlib>/{name}.rhai"), text.to_string())))
    }
}

fn compile_module(
    engine: &Engine,
    label: &str,
    text: &str,
    pos: Position,
) -> Result<Shared<Module>, Box<EvalAltResult>> {
    let in_module = |inner: Box<EvalAltResult>| {
        Box::new(EvalAltResult::ErrorInModule(label.into(), inner, pos))
    };
    let mut ast = engine.compile(text).map_err(|e| in_module(e.into()))?;
    ast.set_source(label);
    let mut module = Module::eval_ast_as_new(Scope::new(), &ast, engine).map_err(in_module)?;
    module.set_id(label);
    Ok(module.into())
}

fn is_module_name(path: &str) -> bool {
    !path.is_empty()
        && path.split('/').all(|seg| {
            !seg.is_empty()
                && seg != "."
                && seg != ".."
                && seg
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        })
}

struct SharedResolver(Arc<Resolver>);

impl rhai::ModuleResolver for SharedResolver {
    fn resolve(
        &self,
        engine: &Engine,
        _source: Option<&str>,
        path: &str,
        pos: Position,
    ) -> Result<Shared<Module>, Box<EvalAltResult>> {
        self.0.resolve(engine, path, pos)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn module_names_cannot_escape_the_search_folders() {
        for bad in [
            "../secret",
            "/etc/passwd",
            "a/../../b",
            "",
            "beam.rhai",
            "a//b",
            "C:\\x",
        ] {
            assert!(!is_module_name(bad), "{bad}");
        }
        for good in ["beam", "frames/portal", "my-silo_2"] {
            assert!(is_module_name(good), "{good}");
        }
    }
}
