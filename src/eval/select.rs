//! `--where FIELD=VALUE`: which views are scored, chosen by any field of their JSON record.
//!
//! Owns: parsing a condition, reading a dotted path in a record, and the rule of a match.
//! FIELD is a dotted path through objects and lists (`scene.structures.0.material.prompt`,
//! `scene.structures.0.support`, `camera.width`). Conditions on the same field are
//! alternatives, conditions on different fields must all hold: `--where sample=3 --where
//! sample=7 --where view=0` scores view 0 of samples 3 and 7 (a held-out split of samples is
//! one `--where sample=N` per sample). A field the view's record lacks does not hold (a clean view has no
//! `augmentation.copy`); a field no view has is an error, since it is surely misspelt. VALUE
//! matches a string field by its text, a number by its value (`1` matches `1.0`), a bool by
//! `true`/`false`, null by `null`, and a list or object by its compact JSON.

use crate::dataset::{Dataset, View};
use anyhow::{Result, bail};
use serde_json::Value;

/// One `--where FIELD=VALUE`.
#[derive(Clone, Debug, PartialEq)]
pub struct Condition {
    /// The dotted path, split.
    path: Vec<String>,
    /// The value asked for, as written.
    value: String,
}

impl std::str::FromStr for Condition {
    type Err = String;
    fn from_str(s: &str) -> Result<Condition, String> {
        let (field, value) = s.split_once('=').ok_or_else(|| {
            format!("--where {s}: expected FIELD=VALUE, e.g. scene.structures.0.support=cantilever")
        })?;
        let path: Vec<String> = field.split('.').map(str::to_string).collect();
        if path.iter().any(String::is_empty) {
            return Err(format!(
                "--where {s}: the field {field:?} has an empty name between its dots"
            ));
        }
        Ok(Condition {
            path,
            value: value.to_string(),
        })
    }
}

impl std::fmt::Display for Condition {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}", self.path.join("."), self.value)
    }
}

impl Condition {
    /// The record's value at the path; None where the record lacks it.
    fn field<'a>(&self, record: &'a Value) -> Option<&'a Value> {
        self.path.iter().try_fold(record, |value, key| match value {
            Value::Object(map) => map.get(key),
            Value::Array(list) => list.get(key.parse::<usize>().ok()?),
            _ => None,
        })
    }

    /// Whether `value` is what the condition asks for.
    fn matches(&self, value: &Value) -> bool {
        match value {
            Value::String(s) => *s == self.value,
            Value::Number(n) => match (n.as_f64(), self.value.trim().parse::<f64>()) {
                (Some(a), Ok(b)) => a == b,
                _ => false,
            },
            Value::Bool(b) => self.value == b.to_string(),
            Value::Null => self.value == "null",
            other => serde_json::to_string(other).is_ok_and(|json| json == self.value),
        }
    }
}

/// The views of `dataset` for which every condition holds, in dataset order (all of them
/// without conditions). An error names a field no view's record has.
pub(super) fn select<'a>(dataset: &'a Dataset, conditions: &[Condition]) -> Result<Vec<&'a View>> {
    if conditions.is_empty() {
        return Ok(dataset.views().collect());
    }
    let mut chosen = Vec::new();
    let mut seen = vec![false; conditions.len()];
    let mut first_record = None;
    for view in dataset.views() {
        let record = dataset.record(view)?;
        // Per field (the first condition on it stands for all): whether any holds.
        let mut holds = vec![false; conditions.len()];
        for (k, (c, seen)) in conditions.iter().zip(&mut seen).enumerate() {
            let value = c.field(&record);
            *seen |= value.is_some();
            let field = first_on_field(conditions, k);
            holds[field] |= value.is_some_and(|v| c.matches(v));
        }
        if (0..conditions.len()).all(|k| first_on_field(conditions, k) != k || holds[k]) {
            chosen.push(view);
        }
        first_record.get_or_insert(record);
    }
    if let Some(k) = seen.iter().position(|seen| !seen) {
        let c = &conditions[k];
        let hint = first_record
            .as_ref()
            .map(|record| hint(record, &c.path))
            .unwrap_or_default();
        bail!(
            "--where {c}: no view's record has the field {}{hint}",
            c.path.join(".")
        );
    }
    Ok(chosen)
}

/// The first of `conditions` on the same field as condition `k`.
fn first_on_field(conditions: &[Condition], k: usize) -> usize {
    conditions
        .iter()
        .position(|c| c.path == conditions[k].path)
        .unwrap_or(k)
}

/// What a record has where a path stops: `; scene has: structures` or the top-level fields.
fn hint(record: &Value, path: &[String]) -> String {
    let mut value = record;
    let mut walked: Vec<&str> = Vec::new();
    for key in path {
        let next = match value {
            Value::Object(map) => map.get(key),
            Value::Array(list) => key.parse::<usize>().ok().and_then(|i| list.get(i)),
            _ => None,
        };
        match next {
            Some(v) => {
                value = v;
                walked.push(key);
            }
            None => break,
        }
    }
    let at = if walked.is_empty() {
        "the record".to_string()
    } else {
        walked.join(".")
    };
    match value {
        Value::Object(map) => {
            let keys: Vec<&str> = map.keys().map(String::as_str).collect();
            format!("; {at} has: {}", keys.join(", "))
        }
        Value::Array(list) => format!("; {at} is a list of {} (index it: {at}.0)", list.len()),
        _ => format!("; {at} is a value, not an object"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn c(s: &str) -> Condition {
        s.parse().unwrap()
    }

    #[test]
    fn dotted_paths_reach_into_objects_and_lists() {
        let record = json!({"scene": {"structures": [{"material": {"prompt": "A timber"}, "length": 1.0}]},
                            "camera": {"width": 64}, "augmentation": null, "flag": true});
        let at = |s: &str| {
            let c = c(s);
            c.field(&record).is_some_and(|v| c.matches(v))
        };
        assert!(at("scene.structures.0.material.prompt=A timber"));
        assert!(!at("scene.structures.0.material.prompt=A timbe"));
        assert!(at("scene.structures.0.length=1"), "1 matches 1.0");
        assert!(at("camera.width=64.0"));
        assert!(at("augmentation=null") && at("flag=true") && !at("flag=1"));
        assert!(!at("scene.structures.1.length=1"), "no second structure");
        assert!(at("scene.structures.0.material={\"prompt\":\"A timber\"}"));
        assert!("a..b=1".parse::<Condition>().is_err() && "ab".parse::<Condition>().is_err());
        let h = hint(&record, &c("scene.structure.0=x").path);
        assert_eq!(h, "; scene has: structures");
    }
}
