//! What a recipe call returns: a value, or an error Rhai reports at the call's position.

use rhai::EvalAltResult;

/// The result of a function registered with the recipe engine.
pub type Fallible<T> = Result<T, Box<EvalAltResult>>;

/// Fails the current recipe call with `msg`.
pub fn fail<T>(msg: String) -> Fallible<T> {
    Err(msg.into())
}
