//! Where an option is written in a recipe's source, so that an error about one option points
//! at its key (`widht:` inside `beam(#{ ... })`) rather than at the call that received the map.
//!
//! Owns: finding a key's position from the source text, the call's position and the option's
//! path as messages name it. The values reach the API as plain maps, without positions, so
//! the source is parsed again (without optimisation, which could fold a map of constants into
//! one value and lose its keys) and the key is looked up in the map literals written in the
//! call's arguments: through nested maps and lists, quoted keys included. A map built
//! elsewhere and passed by name is found when its key is written in one place only. Must not
//! touch: evaluation (nothing is run) or the messages themselves.

use super::engine::{MAX_EXPR_DEPTH, MAX_FUNCTION_EXPR_DEPTH};
use rhai::{ASTNode, Engine, Expr, OptimizationLevel, Position};

/// A key written in a map literal: its path from the outermost literal (keys, and `[i]` for
/// list items) and where it is written.
struct Written {
    path: Vec<String>,
    pos: Position,
}

/// Where the key of option `path` (as messages show it, e.g. `dataset.camera.widht` or
/// `dataset.augment.operations[2] (gamma).gmma`) is written in `text`, for an error raised
/// by the call at `call`. None when the text does not parse, the key is written nowhere, or
/// it is written in several places none of which the call's arguments hold.
pub fn key_position(text: &str, call: Position, path: &str) -> Option<Position> {
    let mut engine = Engine::new_raw();
    engine.set_optimization_level(OptimizationLevel::None);
    engine.set_max_expr_depths(MAX_EXPR_DEPTH, MAX_FUNCTION_EXPR_DEPTH);
    let ast = engine.compile(text).ok()?;
    let mut in_call = Vec::new();
    let mut anywhere = Vec::new();
    ast.walk(&mut |nodes: &[ASTNode]| {
        let Some(ASTNode::Expr(expr)) = nodes.last() else {
            return true;
        };
        match expr {
            Expr::FnCall(f, pos) | Expr::MethodCall(f, pos) if *pos == call => {
                for arg in &f.args {
                    written(arg, &mut Vec::new(), &mut in_call);
                }
            }
            // Only outermost literals: nested ones are reached from them, with their path.
            Expr::Map(..) if !inside_literal(nodes) => {
                written(expr, &mut Vec::new(), &mut anywhere);
            }
            _ => {}
        }
        true
    });
    let names = |w: &&Written| names_option(&w.path, path);
    if let Some(found) = in_call.iter().find(names) {
        return Some(found.pos);
    }
    match anywhere.iter().filter(names).collect::<Vec<_>>().as_slice() {
        [only] => Some(only.pos),
        _ => None,
    }
}

/// Whether the innermost node before the last is a map or list literal.
fn inside_literal(nodes: &[ASTNode]) -> bool {
    matches!(
        nodes.iter().rev().nth(1),
        Some(ASTNode::Expr(Expr::Map(..) | Expr::Array(..)))
    )
}

/// Every key written in the map and list literals of `expr` (not inside calls, whose maps
/// are another function's options).
fn written(expr: &Expr, path: &mut Vec<String>, out: &mut Vec<Written>) {
    match expr {
        Expr::Map(map, _) => {
            for (key, value) in &map.0 {
                path.push(key.name.to_string());
                out.push(Written {
                    path: path.clone(),
                    pos: key.pos,
                });
                written(value, path, out);
                path.pop();
            }
        }
        Expr::Array(items, _) => {
            for (i, item) in items.iter().enumerate() {
                path.push(format!("[{i}]"));
                written(item, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

/// Whether a key written at `written` (a path inside its literal) can be the option a message
/// names as `option`: the option ends with the key, and every enclosing key and list index
/// of the literal appears in the option's path, in order. The option's path may begin with
/// more (the function's name, `dataset.`) and carry notes (`operations[2] (gamma)`).
fn names_option(written: &[String], option: &str) -> bool {
    let Some((key, enclosing)) = written.split_last() else {
        return false;
    };
    let Some(before) = option
        .strip_suffix(key.as_str())
        .filter(|rest| rest.is_empty() || rest.ends_with('.'))
    else {
        return false;
    };
    let mut rest = before;
    enclosing.iter().all(|part| match rest.find(part.as_str()) {
        Some(at) => {
            rest = &rest[at + part.len()..];
            true
        }
        None => false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strings(parts: &[&str]) -> Vec<String> {
        parts.iter().map(|p| p.to_string()).collect()
    }

    #[test]
    fn a_written_key_names_the_option_with_its_enclosing_keys_in_order() {
        let yes = [
            (&["camera", "widht"][..], "dataset.camera.widht"),
            (&["widht"], "beam.widht"),
            (&["roughnes"], "material options.roughnes"),
            (
                &["augment", "operations", "[2]", "gmma"],
                "dataset.augment.operations[2] (gamma).gmma",
            ),
            (&["a.b"], "dataset.a.b"),
        ];
        for (written, option) in yes {
            assert!(names_option(&strings(written), option), "{written:?}");
        }
        let no = [
            (&["light", "widht"][..], "dataset.camera.widht"),
            (
                &["augment", "operations", "[0]", "gmma"],
                "dataset.augment.operations[2] (gamma).gmma",
            ),
            (&["idht"], "dataset.camera.widht"),
            (&["camera", "widht"], "dataset.widht"),
        ];
        for (written, option) in no {
            assert!(!names_option(&strings(written), option), "{written:?}");
        }
    }
}
