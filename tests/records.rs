//! The records of a dataset — `run.json` and every view's JSON — against their published JSON
//! Schemas, checked by a validator that is not ours (the `jsonschema` crate); the published
//! schemas against the types they are generated from; and the field reference
//! (`docs/reference.md`) against the schemas.
//!
//! After changing a record type: `SHMGEN_BLESS=1 cargo test --release --test records`
//! rewrites `docs/schema/*.json` and the field reference in `docs/reference.md`.

mod common;

use common::{bundled_rhai, ok, read_json, run};
use serde_json::{Value, json};
use shmgen::pipeline::{run_schema, view_schema};
use std::collections::{BTreeSet, VecDeque};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn blessing() -> bool {
    std::env::var_os("SHMGEN_BLESS").is_some()
}

fn pretty(value: &Value) -> String {
    serde_json::to_string_pretty(value).unwrap() + "\n"
}

/// Compares `path` with `expected`, or rewrites it when blessing.
fn check_generated(path: &Path, expected: &str) {
    if blessing() {
        std::fs::write(path, expected).unwrap();
        return;
    }
    let actual = std::fs::read_to_string(path).unwrap_or_default();
    assert!(
        actual == expected,
        "{} is out of date; regenerate it with SHMGEN_BLESS=1 cargo test --release --test records",
        path.display()
    );
}

#[test]
fn published_schemas_are_generated_from_the_record_types() {
    for (name, schema) in [("view", view_schema()), ("run", run_schema())] {
        let path = repo().join(format!("docs/schema/{name}.schema.json"));
        check_generated(&path, &pretty(&schema));
    }
}

fn published(name: &str) -> Value {
    read_json(&repo().join(format!("docs/schema/{name}.schema.json")))
}

fn validator(name: &str) -> jsonschema::Validator {
    jsonschema::validator_for(&published(name)).expect("the published schema compiles")
}

fn assert_valid(validator: &jsonschema::Validator, file: &Path) {
    let record = read_json(file);
    let errors: Vec<String> = validator
        .iter_errors(&record)
        .map(|e| format!("{} at {}", e, e.instance_path()))
        .take(5)
        .collect();
    assert!(errors.is_empty(), "{}: {errors:#?}", file.display());
}

/// The small values of the parameters a recipe declares, so every recipe runs in seconds.
fn smoke_settings(recipe: &str) -> Vec<String> {
    let small = [
        ("samples", "2"),
        ("views", "2"),
        ("size", "160"),
        ("damage", "1.0"),
    ];
    small
        .iter()
        .filter(|(name, _)| recipe.contains(&format!("param(\"{name}\"")))
        .flat_map(|(name, value)| ["--set".to_string(), format!("{name}={value}")])
        .collect()
}

#[test]
fn every_recipe_in_scripts_writes_records_that_validate() {
    let (views, runs) = (validator("view"), validator("run"));
    let dir = tempfile::tempdir().unwrap();
    let recipes = bundled_rhai("scripts");
    assert!(recipes.len() >= 4, "{recipes:?}");
    for recipe in &recipes {
        let out = dir.path().join(recipe.file_stem().unwrap());
        let settings = smoke_settings(&std::fs::read_to_string(recipe).unwrap());
        let args: Vec<&str> = settings.iter().map(String::as_str).collect();
        ok(run(recipe, &out, &args));
        assert_valid(&runs, &out.join("run.json"));
        let mut checked = 0;
        for line in std::fs::read_to_string(out.join("manifest.jsonl"))
            .unwrap()
            .lines()
        {
            let entry: Value = serde_json::from_str(line).unwrap();
            for file in entry["files"].as_array().unwrap() {
                let file = file.as_str().unwrap();
                if file.ends_with(".json") {
                    assert_valid(&views, &out.join(file));
                    checked += 1;
                }
            }
        }
        assert!(checked >= 2, "{}: {checked} views", recipe.display());
    }
}

#[test]
fn the_validator_rejects_records_that_break_the_schema() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = repo().join("scripts/quickstart.rhai");
    ok(run(
        &recipe,
        dir.path(),
        &["--set", "samples=1", "--set", "views=1"],
    ));
    let views = validator("view");
    let record = read_json(&dir.path().join("samples/0000/000000_00.json"));
    assert!(views.is_valid(&record));
    type Damage = fn(&mut Value);
    let broken: [(&str, Damage); 4] = [
        ("a non-finite matrix entry (written as null)", |r| {
            r["camera"]["K"][0][0] = Value::Null
        }),
        ("another schema version", |r| {
            r["schema"] = json!("shmgen.view/1")
        }),
        ("a missing field", |r| {
            r["camera"].as_object_mut().unwrap().remove("c2w_opencv");
        }),
        ("a wrong type", |r| r["sample"] = json!("zero")),
    ];
    for (what, damage) in broken {
        let mut bad = record.clone();
        damage(&mut bad);
        assert!(!views.is_valid(&bad), "accepted {what}");
    }
}

#[test]
fn the_field_reference_is_generated_from_the_schemas() {
    let reference = field_reference(&[
        ("run.json", published("run")),
        ("view JSON", published("view")),
    ]);
    let path = repo().join("docs/reference.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let (begin, end) = (
        "<!-- field reference: generated from docs/schema -->\n",
        "<!-- end of field reference -->",
    );
    let start = readme
        .find(begin)
        .expect("docs/reference.md has the field reference markers")
        + begin.len();
    let stop = readme
        .find(end)
        .expect("docs/reference.md has the field reference end marker");
    let expected = format!("{}{reference}{}", &readme[..start], &readme[stop..]);
    check_generated(&path, &expected);
    // Every field is described.
    let undocumented: Vec<&str> = reference
        .lines()
        .filter(|l| l.starts_with("| `") && l.ends_with("|  |"))
        .collect();
    assert!(undocumented.is_empty(), "{undocumented:#?}");
}

/// Markdown tables of every record and every type they use, each type once, in the order
/// they are first met from the records.
fn field_reference(records: &[(&str, Value)]) -> String {
    let mut out = String::new();
    let mut seen = BTreeSet::new();
    let mut queue = VecDeque::new();
    for (title, schema) in records {
        let tags = resolve(schema, &schema["properties"]["schema"]);
        let tag = tag_value(tags)
            .or_else(|| tags["oneOf"].as_array()?.first().and_then(tag_value))
            .and_then(Value::as_str)
            .expect("a record's schema tag has one current value");
        out += &format!("#### {title} (`{tag}`)\n\n");
        out += &describe(schema, schema, &mut queue);
        while let Some(name) = queue.pop_front() {
            if seen.insert(name.clone()) {
                out += &format!("#### {name}\n\n");
                out += &describe(schema, &schema["$defs"][&name], &mut queue);
            }
        }
    }
    out
}

/// A type's description and its fields (or, for a choice of forms, each form's).
fn describe(root: &Value, node: &Value, queue: &mut VecDeque<String>) -> String {
    let mut out = String::new();
    if let Some(text) = node["description"].as_str() {
        out += &format!("{}\n\n", one_line(text));
    }
    if node.get("properties").is_some() {
        out += &table(root, node, None, queue);
    }
    for key in ["oneOf", "anyOf"] {
        let Some(forms) = node[key].as_array() else {
            continue;
        };
        for form in forms {
            out += &describe_form(root, form, queue);
        }
        out += "\n";
    }
    if node.get("enum").is_some() || node.get("const").is_some() {
        out += &format!("Values: {}\n\n", type_name(root, node, queue));
    }
    out
}

/// One form of a choice: a tagged variant (its tag shown once, its other fields in a
/// table), a variant wrapped in a single key, a plain value, or another type.
fn describe_form(root: &Value, form: &Value, queue: &mut VecDeque<String>) -> String {
    let text = form["description"]
        .as_str()
        .map(|t| format!(": {}", one_line(t)))
        .unwrap_or_default();
    if let Some(value) = form.get("const") {
        return format!("- `{value}`{text}\n");
    }
    let Some(properties) = form["properties"].as_object() else {
        return format!("- {}{text}\n", type_name(root, form, queue));
    };
    if let Some((tag, value)) = properties
        .iter()
        .find_map(|(k, p)| Some((k, tag_value(p)?)))
    {
        let rows = table(root, form, Some(tag.as_str()), queue);
        return format!("- `{tag}: {value}`{text}\n\n{rows}");
    }
    if let [(key, inner)] = properties.iter().collect::<Vec<_>>()[..]
        && inner.get("properties").is_some()
    {
        let rows = table(root, inner, None, queue);
        return format!("- `{key}`{text}\n\n{rows}");
    }
    let rows = table(root, form, None, queue);
    format!("- {}\n\n{rows}", text.trim_start_matches(": "))
}

/// The one value a tag property can take.
fn tag_value(property: &Value) -> Option<&Value> {
    property
        .get("const")
        .or_else(|| match property["enum"].as_array()?.as_slice() {
            [only] => Some(only),
            _ => None,
        })
}

/// The fields of an object, but for its tag (shown with the form).
fn table(root: &Value, node: &Value, tag: Option<&str>, queue: &mut VecDeque<String>) -> String {
    let mut out = String::from("| field | type | meaning |\n|---|---|---|\n");
    let required: BTreeSet<&str> = node["required"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .collect();
    for (name, property) in node["properties"].as_object().unwrap() {
        if Some(name.as_str()) == tag {
            continue;
        }
        let optional = if required.contains(name.as_str()) {
            ""
        } else {
            " (optional)"
        };
        let meaning = property["description"]
            .as_str()
            .map(one_line)
            .unwrap_or_default();
        out += &format!(
            "| `{name}`{optional} | {} | {meaning} |\n",
            type_name(root, property, queue).replace('|', "\\|")
        );
    }
    out + "\n"
}

/// The definition a `$ref` names, or the node itself.
fn resolve<'a>(root: &'a Value, node: &'a Value) -> &'a Value {
    match node["$ref"].as_str() {
        Some(reference) => &root["$defs"][reference.trim_start_matches("#/$defs/")],
        None => node,
    }
}

/// A short name for a schema's type; referenced definitions are queued for their own table,
/// except plain lists of values, which are shown in place.
fn type_name(root: &Value, node: &Value, queue: &mut VecDeque<String>) -> String {
    if let Some(reference) = node["$ref"].as_str() {
        let target = resolve(root, node);
        if target.get("enum").is_some() {
            return type_name(root, target, queue);
        }
        let name = reference.trim_start_matches("#/$defs/").to_string();
        queue.push_back(name.clone());
        return format!("[{name}](#{})", name.to_lowercase());
    }
    if let Some(value) = node.get("const") {
        return format!("`{value}`");
    }
    if let Some(values) = node["enum"].as_array() {
        return values
            .iter()
            .map(|v| format!("`{v}`"))
            .collect::<Vec<_>>()
            .join(" or ");
    }
    for key in ["anyOf", "oneOf"] {
        if let Some(forms) = node[key].as_array() {
            return forms
                .iter()
                .map(|f| type_name(root, f, queue))
                .collect::<Vec<_>>()
                .join(" or ");
        }
    }
    let kind = match &node["type"] {
        Value::String(s) => s.clone(),
        Value::Array(kinds) => {
            return kinds
                .iter()
                .map(|k| type_name(root, &json!({ "type": k, "items": node["items"], "prefixItems": node["prefixItems"], "additionalProperties": node["additionalProperties"], "minItems": node["minItems"], "maxItems": node["maxItems"] }), queue))
                .collect::<Vec<_>>()
                .join(" or ");
        }
        _ => return "any".into(),
    };
    match kind.as_str() {
        "array" => {
            if let Some(items) = node["prefixItems"].as_array() {
                let parts: Vec<String> = items.iter().map(|i| type_name(root, i, queue)).collect();
                return format!("({})", parts.join(", "));
            }
            let item = type_name(root, &node["items"], queue);
            match (node["minItems"].as_u64(), node["maxItems"].as_u64()) {
                (Some(a), Some(b)) if a == b => format!("[{item}; {a}]"),
                _ => format!("[{item}]"),
            }
        }
        "object" => match node.get("additionalProperties") {
            Some(values) if values.is_object() => {
                format!("map of {}", type_name(root, values, queue))
            }
            _ => "object".into(),
        },
        other => other.to_string(),
    }
}

fn one_line(text: &str) -> String {
    text.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .replace('|', "\\|")
}
