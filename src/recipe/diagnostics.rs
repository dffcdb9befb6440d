//! Turning Rhai errors into messages that point into the user's files:
//! `error: ...` then `--> file:line:col`, the source line and a caret, then the call chain.
//! Warnings take the same form.

use super::engine::{MAX_OPERATIONS, Sources};
use crate::scene::SourceSite;
use rhai::{EvalAltResult, NativeCallContext, ParseError, Position};
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
        RecipeError(format!("error: {}", message.into()))
    }

    /// A syntax error, shown at its place in the file labelled `label`.
    pub fn parse(err: &ParseError, label: &str, sources: &Sources) -> Self {
        let at = Located {
            label: label.to_string(),
            pos: err.1,
        };
        RecipeError(render("error", &err.0.to_string(), &at, &[], None, sources))
    }

    /// `context` says what was being evaluated, e.g. "while drawing the scene of sample 3".
    pub fn eval(
        err: &EvalAltResult,
        main_label: &str,
        sources: &Sources,
        context: Option<&str>,
    ) -> Self {
        let mut chain = Vec::new();
        let (message, at) = innermost(err, main_label, &mut chain);
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

/// Follows calls and imports down to the error itself, collecting where each step happened.
fn innermost(
    err: &EvalAltResult,
    label: &str,
    chain: &mut Vec<(String, Located)>,
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
            innermost(inner, inner_label, chain)
        }
        EvalAltResult::ErrorInModule(module, inner, pos) => {
            chain.push((
                format!("while importing {module}"),
                Located {
                    label: label.to_string(),
                    pos: *pos,
                },
            ));
            innermost(inner, module, chain)
        }
        EvalAltResult::ErrorParsing(kind, pos) => (
            kind.to_string(),
            Located {
                label: label.to_string(),
                pos: *pos,
            },
        ),
        EvalAltResult::ErrorRuntime(value, pos) => (
            value.to_string(),
            Located {
                label: label.to_string(),
                pos: *pos,
            },
        ),
        EvalAltResult::ErrorTooManyOperations(pos) => (
            format!(
                "the script ran more than {MAX_OPERATIONS} operations; is there an endless loop?"
            ),
            Located {
                label: label.to_string(),
                pos: *pos,
            },
        ),
        other => {
            let pos = other.position();
            let text = other.to_string();
            let message = text
                .strip_suffix(&format!(" ({pos})"))
                .unwrap_or(&text)
                .to_string();
            (
                message,
                Located {
                    label: label.to_string(),
                    pos,
                },
            )
        }
    }
}

fn render(
    severity: &str,
    message: &str,
    at: &Located,
    chain: &[(String, Located)],
    context: Option<&str>,
    sources: &Sources,
) -> String {
    let mut out = format!("{severity}: {message}\n");
    out += &format!("  --> {}\n", place(at));
    if let (Some(line), Some(col)) = (at.pos.line(), at.pos.position()) {
        if let Some(text) = sources.line(&at.label, line) {
            let gutter = line.to_string().len();
            out += &format!(
                "{:gutter$} |\n{line} | {text}\n{:gutter$} | {:>col$}\n",
                "", "", "^"
            );
        }
    }
    for (what, site) in chain.iter().rev().filter(|(_, l)| !l.pos.is_none()) {
        out += &format!("  = note: {what}, called at {}\n", place(site));
    }
    if let Some(context) = context {
        out += &format!("  = note: {context}\n");
    }
    out.trim_end().to_string()
}

fn place(at: &Located) -> String {
    match (at.pos.line(), at.pos.position()) {
        (Some(l), Some(c)) => format!("{}:{l}:{c}", at.label),
        (Some(l), None) => format!("{}:{l}", at.label),
        _ => at.label.clone(),
    }
}
