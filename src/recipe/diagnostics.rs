//! Turning Rhai errors into messages that point into the user's files:
//! `error: ...` then `--> file:line:col`, the source line and a caret, then the call chain.
//! Warnings take the same form. A call to a function or method that does not exist gets the
//! nearest name the script could have meant, as an unknown option does; an unknown option is
//! shown at its key where the key is written (see `option_sites`).

use super::engine::{
    MAX_ARRAY_ELEMENTS, MAX_CALL_LEVELS, MAX_EXPR_DEPTH, MAX_FUNCTION_EXPR_DEPTH,
    MAX_MAP_PROPERTIES, MAX_OPERATIONS, MAX_STRING_BYTES, OUT_OF_MEMORY, Sources,
};
use super::memory::MAX_SCRIPT_BYTES;
use crate::scene::SourceSite;
use crate::words::{clip, short_numbers};
use rhai::{AST, Engine, EvalAltResult, NativeCallContext, ParseError, ParseErrorType, Position};
use std::collections::BTreeSet;
use std::fmt;
use std::sync::{Arc, Mutex};

/// A recipe error, fully formatted for the terminal.
#[derive(Debug, Clone)]
pub struct RecipeError(String);

impl fmt::Display for RecipeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for RecipeError {}

struct Located {
    label: String,
    pos: Position,
}

impl RecipeError {
    /// An error with no place in the recipe's sources.
    pub fn plain(message: impl Into<String>) -> Self {
        let message = message.into();
        RecipeError(format!(
            "error: {}",
            clip(&short_numbers(&message), MAX_MESSAGE_CHARS)
        ))
    }

    /// A syntax error, shown at its place in the file labelled `label`.
    pub fn parse(err: &ParseError, label: &str, sources: &Sources) -> Self {
        let at = Located {
            label: label.to_string(),
            pos: err.1,
        };
        RecipeError(render(
            "error",
            &parse_message(&err.0),
            &at,
            &[],
            None,
            sources,
        ))
    }

    /// `context` says what was being evaluated, e.g. "while drawing the scene of sample 3";
    /// `callable` what the script could call, for the nearest name to a missing function.
    pub fn eval(
        err: &EvalAltResult,
        main_label: &str,
        sources: &Sources,
        context: Option<&str>,
        callable: &Callable,
    ) -> Self {
        let mut chain = Vec::new();
        let (message, mut at) = innermost(err, main_label, &mut chain, callable);
        if let Some(key) = option_key(&message, &at, sources) {
            at.pos = key;
        }
        RecipeError(render("error", &message, &at, &chain, context, sources))
    }
}

impl RecipeError {
    /// An error found after the recipe ran (while building what it described), pointing at
    /// the call that declared it.
    pub fn at(message: &str, site: &SourceSite, sources: &Sources, context: Option<&str>) -> Self {
        let at = Located {
            label: site.source.clone(),
            pos: Position::new(
                u16::try_from(site.line).unwrap_or(u16::MAX),
                u16::try_from(site.column).unwrap_or(u16::MAX),
            ),
        };
        RecipeError(render("error", message, &at, &[], context, sources))
    }
}

/// Where a registered function was called from, to keep in what it builds.
pub fn call_site(ctx: &NativeCallContext) -> SourceSite {
    let pos = ctx.call_position();
    SourceSite {
        source: ctx.call_source().unwrap_or_default().to_string(),
        line: pos.line().unwrap_or(0),
        column: pos.position().unwrap_or(0),
    }
}

/// Warnings about a recipe, each printed once however many samples repeat it, pointing at the
/// call that caused it.
pub struct Warnings {
    sources: Arc<Sources>,
    seen: Mutex<BTreeSet<String>>,
}

impl Warnings {
    pub fn new(sources: Arc<Sources>) -> Self {
        Warnings {
            sources,
            seen: Mutex::default(),
        }
    }

    pub fn warn(&self, message: &str, label: &str, pos: Position) {
        let at = Located {
            label: label.to_string(),
            pos,
        };
        let text = render("warning", message, &at, &[], None, &self.sources);
        if self.seen.lock().unwrap().insert(text.clone()) {
            eprintln!("{text}");
        }
    }
}

/// Where the key is written of the unknown option that `message` names, the error being
/// raised by the call at `at`.
fn option_key(message: &str, at: &Located, sources: &Sources) -> Option<Position> {
    let path = super::options::unknown_option_path(message)?;
    super::option_sites::key_position(&sources.text(&at.label)?, at.pos, path)
}

/// Follows calls and imports down to the error itself, collecting where each step happened.
fn innermost(
    err: &EvalAltResult,
    label: &str,
    chain: &mut Vec<(String, Located)>,
    callable: &Callable,
) -> (String, Located) {
    match err {
        EvalAltResult::ErrorInFunctionCall(name, source, inner, pos) => {
            let what = if name.starts_with("anon$") {
                "in the closure".to_string()
            } else {
                format!("in call to `{name}`")
            };
            chain.push((
                what,
                Located {
                    label: label.to_string(),
                    pos: *pos,
                },
            ));
            let inner_label = if source.is_empty() {
                label
            } else {
                source.as_str()
            };
            innermost(inner, inner_label, chain, callable)
        }
        EvalAltResult::ErrorInModule(module, inner, pos) => {
            chain.push((
                format!("while importing {module}"),
                Located {
                    label: label.to_string(),
                    pos: *pos,
                },
            ));
            innermost(inner, module, chain, callable)
        }
        leaf => (
            message(leaf, callable),
            Located {
                label: label.to_string(),
                pos: leaf.position(),
            },
        ),
    }
}

/// What went wrong, in the user's terms where Rhai's own words are unclear: the limits are
/// named with their values.
fn message(err: &EvalAltResult, callable: &Callable) -> String {
    match err {
        EvalAltResult::ErrorParsing(kind, _) => parse_message(kind),
        EvalAltResult::ErrorRuntime(value, _) => value.to_string(),
        EvalAltResult::ErrorTerminated(token, _) if token.to_string() == OUT_OF_MEMORY => format!(
            "the script holds more than {} MiB; is a list, map or string growing without end?",
            MAX_SCRIPT_BYTES >> 20
        ),
        EvalAltResult::ErrorFunctionNotFound(signature, _) if signature.starts_with("anon$") => {
            closure_not_found(signature)
        }
        EvalAltResult::ErrorFunctionNotFound(signature, _) => format!(
            "function not found: {signature}{}",
            callable.hint(signature)
        ),
        EvalAltResult::ErrorStackOverflow(_) => format!(
            "function calls nested more than {MAX_CALL_LEVELS} deep; does a function call itself without end?"
        ),
        EvalAltResult::ErrorTooManyOperations(_) => format!(
            "the script ran more than {MAX_OPERATIONS} operations; is there an endless loop?"
        ),
        EvalAltResult::ErrorDataTooLarge(what, _) => match what.as_str() {
            "Length of string" => {
                format!("a string would be longer than {MAX_STRING_BYTES} bytes, the limit")
            }
            "Size of array/BLOB" => format!(
                "a list would hold more than {MAX_ARRAY_ELEMENTS} elements (counting those of the lists and maps inside it), the limit"
            ),
            "Size of object map" => format!(
                "a map would hold more than {MAX_MAP_PROPERTIES} properties (counting those of the maps inside it), the limit"
            ),
            _ => format!("{what} too large"),
        },
        other => {
            let pos = other.position();
            let text = other.to_string();
            text.strip_suffix(&format!(" ({pos})"))
                .unwrap_or(&text)
                .to_string()
        }
    }
}

/// What a script can call: the engine's functions and methods (its static modules' under
/// their `module::` names) and the functions the script defines.
pub struct Callable<'a> {
    pub engine: &'a Engine,
    pub ast: Option<&'a AST>,
}

impl Callable<'_> {
    /// Names a script can call, qualified by module (`shape::box`); operators, getters and
    /// closures (which have no name to type) are left out.
    fn names(&self) -> Vec<String> {
        let mut names = self.engine.collect_fn_metadata(
            None,
            |info| {
                let name = info.metadata.name.as_str();
                is_identifier(name).then(|| match info.namespace.as_str() {
                    "" => name.to_string(),
                    module => format!("{module}::{name}"),
                })
            },
            true,
        );
        if let Some(ast) = self.ast {
            names.extend(ast.iter_functions().map(|f| f.name.to_string()));
        }
        names.sort_unstable();
        names.dedup();
        names
    }

    /// What to add to "function not found: `signature`": the nearest name in the same module
    /// (`; did you mean `material`?`), or that the name exists but takes other arguments.
    fn hint(&self, signature: &str) -> String {
        let called = signature
            .split_once(" (")
            .map_or(signature, |(name, _)| name);
        let module = |name: &str| name.rsplit_once("::").map(|(m, _)| m.to_string());
        let names = self.names();
        if names.iter().any(|n| n == called) {
            return format!("; `{called}` exists, but not for these arguments");
        }
        let same_module: Vec<&str> = names
            .iter()
            .filter(|n| module(n) == module(called))
            .map(String::as_str)
            .collect();
        crate::words::nearest(called, &same_module)
            .map(|name| format!("; did you mean `{name}`?"))
            .unwrap_or_default()
    }
}

/// Whether `name` can be typed as a function name: letters, digits and `_`, not starting
/// with a digit.
fn is_identifier(name: &str) -> bool {
    name.chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_')
        && name.chars().all(|c| c.is_alphanumeric() || c == '_')
}

/// A syntax error's message.
fn parse_message(kind: &ParseErrorType) -> String {
    match kind {
        ParseErrorType::ExprTooDeep => format!(
            "expressions or blocks nested too deeply (at most {MAX_EXPR_DEPTH} levels, {MAX_FUNCTION_EXPR_DEPTH} inside functions); split them with `let`"
        ),
        other => other.to_string(),
    }
}

/// Longest message shown, characters (a message may quote a value the script built).
const MAX_MESSAGE_CHARS: usize = 2000;
/// Calls shown at each end of a long call chain.
const CHAIN_ENDS: usize = 5;
/// Source lines longer than this many characters are shown in part, around the caret.
const MAX_LINE_CHARS: usize = 160;
/// Characters of a long source line shown on each side of the caret.
const LINE_CONTEXT: usize = 60;

fn render(
    severity: &str,
    message: &str,
    at: &Located,
    chain: &[(String, Located)],
    context: Option<&str>,
    sources: &Sources,
) -> String {
    let mut out = format!(
        "{severity}: {}\n",
        clip(&short_numbers(message), MAX_MESSAGE_CHARS)
    );
    out += &format!("  --> {}\n", place(at));
    if let (Some(line), Some(col)) = (at.pos.line(), at.pos.position()) {
        let exact = line < usize::from(u16::MAX) && col < usize::from(u16::MAX);
        if let Some(text) = sources.line(&at.label, line).filter(|_| exact) {
            let (text, col) = excerpt(&text, col);
            let gutter = line.to_string().len();
            out += &format!(
                "{:gutter$} |\n{line} | {text}\n{:gutter$} | {:>col$}\n",
                "", "", "^"
            );
        }
    }
    let calls: Vec<_> = chain
        .iter()
        .rev()
        .filter(|(_, l)| !l.pos.is_none())
        .collect();
    for (i, (what, site)) in calls.iter().enumerate() {
        let hidden = calls.len().saturating_sub(2 * CHAIN_ENDS);
        if hidden > 0 && i == CHAIN_ENDS {
            out += &format!("  = note: ... {hidden} more calls ...\n");
        }
        if hidden == 0 || i < CHAIN_ENDS || i >= CHAIN_ENDS + hidden {
            out += &format!("  = note: {what}, called at {}\n", place(site));
        }
    }
    if let Some(context) = context {
        out += &format!("  = note: {context}\n");
    }
    out.trim_end().to_string()
}

/// The part of a long source line around column `col` (counted from 1), with `…` where it
/// was cut, and the caret's column in what is shown.
fn excerpt(text: &str, col: usize) -> (String, usize) {
    if text.chars().nth(MAX_LINE_CHARS).is_none() {
        return (text.to_string(), col);
    }
    let skip = col.saturating_sub(1 + LINE_CONTEXT);
    let mut shown: String = text.chars().skip(skip).take(2 * LINE_CONTEXT + 1).collect();
    if text.chars().nth(skip + 2 * LINE_CONTEXT + 1).is_some() {
        shown.push('…');
    }
    if skip == 0 {
        (shown, col)
    } else {
        (format!("…{shown}"), col - skip + 1)
    }
}

/// Rhai names a closure `anon$<hash>`; its "function not found" means the closure was called
/// with a number of arguments it does not take.
fn closure_not_found(signature: &str) -> String {
    let args = signature.split_once(' ').map_or("", |(_, args)| {
        args.trim_start_matches('(').trim_end_matches(')')
    });
    let given = if args.is_empty() {
        0
    } else {
        args.split(',').count()
    };
    format!(
        "a closure was called with {given} argument{} ({args}), which is not the number of parameters it takes",
        if given == 1 { "" } else { "s" }
    )
}

fn place(at: &Located) -> String {
    // Rhai counts lines and columns in 16 bits; beyond, it stops at the largest.
    let last = usize::from(u16::MAX);
    match (at.pos.line(), at.pos.position()) {
        (Some(l), Some(c)) if l >= last || c >= last => {
            format!("{}:{l}:{c} (or further: Rhai counts no further)", at.label)
        }
        (Some(l), Some(c)) => format!("{}:{l}:{c}", at.label),
        (Some(l), None) => format!("{}:{l}", at.label),
        _ => at.label.clone(),
    }
}
