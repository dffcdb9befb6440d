//! The layering of the crate, read from its source: every module imports only the modules
//! the table below allows, so data flows one way (recipe → scene → build → render → output)
//! and no two modules import each other.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Each top-level module and the modules it may import. `main` is the binary.
const ALLOWED: &[(&str, &[&str])] = &[
    (
        "main",
        &[
            "preview", "pipeline", "recipe", "words", "export", "eval", "dataset",
        ],
    ),
    ("export", &["dataset", "output"]),
    ("eval", &["dataset", "geometry", "output", "words"]),
    ("dataset", &["cameras"]),
    (
        "preview",
        &["pipeline", "recipe", "build", "output", "scene"],
    ),
    (
        "pipeline",
        &[
            "recipe",
            "build",
            "render",
            "output",
            "scene",
            "augment",
            "mechanics",
            "materials",
            "cameras",
            "seeds",
        ],
    ),
    (
        "recipe",
        &[
            "scene",
            "output",
            "mechanics",
            "geometry",
            "materials",
            "cameras",
            "seeds",
            "words",
        ],
    ),
    (
        "build",
        &[
            "scene",
            "mechanics",
            "geometry",
            "materials",
            "cameras",
            "seeds",
        ],
    ),
    ("render", &["geometry", "cameras", "materials"]),
    (
        "scene",
        &["augment", "mechanics", "geometry", "materials", "cameras"],
    ),
    ("augment", &["seeds"]),
    ("output", &[]),
    ("mechanics", &[]),
    ("geometry", &[]),
    ("materials", &["seeds", "words"]),
    ("cameras", &["seeds", "words"]),
    ("seeds", &[]),
    ("words", &[]),
];

fn src() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a source file belongs to.
fn module_of(file: &Path) -> String {
    let relative = file.strip_prefix(src()).unwrap();
    let first = relative
        .iter()
        .next()
        .unwrap()
        .to_string_lossy()
        .to_string();
    first.trim_end_matches(".rs").to_string()
}

/// Names of the crate's modules a file uses through `prefix` (`crate::` in the library,
/// `shmgen::` in the binary), comments left out.
fn imports(text: &str, prefix: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(at) = rest.find(prefix) {
            rest = &rest[at + prefix.len()..];
            if let Some(group) = rest.strip_prefix('{') {
                let inner = group.split('}').next().unwrap_or("");
                for item in inner.split(',') {
                    let name: String = item
                        .trim()
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    found.insert(name);
                }
            } else {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                found.insert(name);
            }
        }
    }
    found.retain(|n| !n.is_empty());
    found
}

fn imports_by_module() -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut by_module: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in files {
        let module = module_of(&file);
        if module == "lib" {
            continue;
        }
        let text = std::fs::read_to_string(&file).unwrap();
        let prefix = if module == "main" {
            "shmgen::"
        } else {
            "crate::"
        };
        let used = imports(&text, prefix);
        by_module
            .entry(module.clone())
            .or_default()
            .extend(used.into_iter().filter(|m| *m != module));
    }
    by_module
}

#[test]
fn every_module_imports_only_what_the_layering_allows() {
    let allowed: BTreeMap<&str, &[&str]> = ALLOWED.iter().copied().collect();
    let actual = imports_by_module();
    let mut violations = Vec::new();
    for (module, used) in &actual {
        let Some(may) = allowed.get(module.as_str()) else {
            violations.push(format!("{module} is not in the layering table"));
            continue;
        };
        for dependency in used {
            if !may.contains(&dependency.as_str()) {
                violations.push(format!("{module} imports {dependency}"));
            }
        }
    }
    assert!(violations.is_empty(), "{violations:#?}");
    // Every module in the table exists, so the table cannot silently go stale.
    for (module, _) in ALLOWED {
        assert!(actual.contains_key(*module), "{module} has no source");
    }
}

#[test]
fn the_layering_has_no_cycles() {
    // Repeatedly remove modules whose allowed imports are all removed; a cycle would remain.
    let mut left: BTreeMap<&str, &[&str]> = ALLOWED.iter().copied().collect();
    let mut order = Vec::new();
    while !left.is_empty() {
        let ready: Vec<&str> = left
            .iter()
            .filter(|(_, deps)| deps.iter().all(|d| !left.contains_key(d)))
            .map(|(m, _)| *m)
            .collect();
        assert!(!ready.is_empty(), "cycle among {:?}", left.keys());
        for m in ready {
            left.remove(m);
            order.push(m);
        }
    }
    // The steps of the data flow come in order.
    let rank = |m: &str| order.iter().position(|o| *o == m).unwrap();
    assert!(rank("scene") < rank("recipe") && rank("scene") < rank("build"));
    assert!(rank("build") < rank("pipeline") && rank("render") < rank("pipeline"));
    assert!(rank("pipeline") < rank("preview") && rank("preview") < rank("main"));
    assert!(rank("dataset") < rank("export") && rank("export") < rank("main"));
    assert!(rank("dataset") < rank("eval") && rank("eval") < rank("main"));
}

#[test]
fn the_import_reader_sees_grouped_and_plain_paths() {
    let text = "use crate::{scene::X, build};\nlet a = crate::render::f(); // crate::output\n";
    let found = imports(text, "crate::");
    assert_eq!(
        found,
        BTreeSet::from(["build".into(), "render".into(), "scene".into()])
    );
}
