//! What the user reads when a prompt is not fully understood: unknown words with the nearest
//! known ones, conflicting bases or colours, and a prompt with no known word. All the wording
//! is here; the reader only says what it found.

use super::vocabulary::{Category, IGNORED, LEXICON, known_words, normalise_spelling};
use crate::words::{edit_distance, nearest};

/// Two words that cannot both hold; the reader keeps one and the user is told which.
pub(super) enum Conflict {
    /// Two materials where neither refines the other (rule 1): the last one named wins.
    Bases {
        earlier: &'static str,
        used: &'static str,
    },
    /// Two colours: the first one named wins.
    Colours {
        used: &'static str,
        ignored: &'static str,
    },
}

pub(super) fn conflict_warning(prompt: &str, conflict: &Conflict) -> String {
    let what = match conflict {
        Conflict::Bases { earlier, used } => format!(
            "names both \"{earlier}\" and \"{used}\"; using \"{used}\", the last material named"
        ),
        Conflict::Colours { used, ignored } => format!(
            "names several colours; using \"{used}\", the first, and ignoring \"{ignored}\""
        ),
    };
    format!("material prompt \"{prompt}\" {what}")
}

pub(super) fn unknown_word_warning(word: &str, prompt: &str) -> String {
    let head = format!("unknown word \"{word}\" in material prompt \"{prompt}\"");
    match suggestions(word) {
        (near, Some(category)) => format!(
            "{head}; did you mean {}? ({})",
            quoted_alternatives(&near),
            examples(category)
        ),
        (near, None) if !near.is_empty() => format!(
            "{head}; did you mean {}? (\"{}\" is a structure or filler word, ignored in \
             material prompts)",
            quoted_alternatives(&near),
            near[0]
        ),
        _ => format!("{head} was ignored ({})", examples(closest_category(word))),
    }
}

pub(super) fn nothing_known_warning(prompt: &str) -> String {
    format!("{}; using plain grey", nothing_known(prompt))
}

pub(super) fn nothing_known_error(prompt: &str, unknown: &[&str]) -> String {
    let mut message = nothing_known(prompt);
    let notes: Vec<String> = unknown
        .iter()
        .map(|word| match suggestions(word).0.as_slice() {
            [] => format!("\"{word}\" is unknown"),
            near => format!("\"{word}\": did you mean {}?", quoted_alternatives(near)),
        })
        .collect();
    if !notes.is_empty() {
        message += &format!(" ({})", notes.join("; "));
    }
    message += &format!(
        "; name a base, a colour or a condition ({})",
        examples(Category::Bases)
    );
    message
}

fn nothing_known(prompt: &str) -> String {
    format!("no known material word in prompt \"{prompt}\"")
}

/// Up to three known words near `word`, closest first, and the category of the closest (None
/// for an ignored word: "beem" → "beam" tells the user the word is understood and skipped).
/// Ignored words of one or two letters would only add noise to the suggestions.
fn suggestions(word: &str) -> (Vec<&'static str>, Option<Category>) {
    let vocabulary = known_words();
    let ignored = IGNORED.iter().copied().filter(|w| w.len() > 2);
    let candidates: Vec<&'static str> = vocabulary.iter().copied().chain(ignored).collect();
    let near = nearest_few(word, &candidates, 3);
    let category = near
        .first()
        .filter(|w| vocabulary.contains(w))
        .map(|w| category_of(w));
    (near, category)
}

/// The `n` nearest known words, using the shared typo rule of `words::nearest`.
fn nearest_few(word: &str, known: &[&'static str], n: usize) -> Vec<&'static str> {
    let mut left = known.to_vec();
    let mut found = Vec::new();
    while found.len() < n {
        let Some(best) = nearest(word, &left) else {
            break;
        };
        found.push(best);
        left.retain(|k| *k != best);
    }
    found
}

/// The category of a vocabulary word (a spelling variant counts as its standard spelling).
fn category_of(word: &str) -> Category {
    let standard = normalise_spelling(word);
    LEXICON
        .iter()
        .find(|e| e.phrase == standard)
        .map_or(Category::Bases, |e| Category::of(&e.meaning))
}

/// The category holding the word closest to `word`, when nothing is close enough to suggest.
fn closest_category(word: &str) -> Category {
    Category::ALL
        .into_iter()
        .min_by_key(|c| {
            c.words()
                .iter()
                .map(|w| edit_distance(word, w))
                .min()
                .unwrap_or(usize::MAX)
        })
        .unwrap_or(Category::Bases)
}

/// "steel, galvanised steel, …" — the first few words of a category.
fn examples(category: Category) -> String {
    let words = category.words();
    let shown: Vec<&str> = words.iter().take(8).copied().collect();
    let more = if words.len() > shown.len() {
        ", …"
    } else {
        ""
    };
    format!(
        "known {}: {}{more}",
        category_name(category),
        shown.join(", ")
    )
}

fn category_name(category: Category) -> &'static str {
    match category {
        Category::Bases => "bases",
        Category::Colours => "colours",
        Category::Shades => "shades",
        Category::Conditions => "conditions",
        Category::Intensities => "intensities",
        Category::Finishes => "finishes",
    }
}

/// `"a"`, `"a" or "b"`, `"a", "b" or "c"`.
fn quoted_alternatives(words: &[&str]) -> String {
    let quoted: Vec<String> = words.iter().map(|w| format!("\"{w}\"")).collect();
    match quoted.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        Some((last, _)) => last.clone(),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use crate::materials::prompt::compile;
    use crate::materials::{Base, Material};

    #[test]
    fn unknown_word_names_the_nearest_known_word() {
        let c = compile("A photo of rustty steel", true).unwrap();
        assert_eq!(c.warnings.len(), 1);
        assert!(
            c.warnings[0].contains("did you mean \"rusty\""),
            "{}",
            c.warnings[0]
        );
        assert!(c.warnings[0].contains("A photo of rustty steel"));
        let c = compile("concret pier", false).unwrap();
        assert!(c.warnings[0].contains("\"concrete\""), "{}", c.warnings[0]);
        let c = compile("steel beem", true).unwrap();
        assert!(
            c.warnings[0].contains("did you mean \"beam\""),
            "{}",
            c.warnings[0]
        );
        // Nothing near: the word is reported as ignored with examples.
        let c = compile("xqzzyv steel", true).unwrap();
        assert!(
            c.warnings[0].contains("was ignored (known"),
            "{}",
            c.warnings[0]
        );
        assert_eq!(c.material.base, Base::Steel);
    }

    #[test]
    fn nothing_known_is_an_error_when_strict_and_a_warning_otherwise() {
        let prompt = "A photo of a concret thing";
        let error = compile(prompt, true).unwrap_err();
        assert!(error.contains(prompt), "{error}");
        assert!(error.contains("\"concrete\""), "{error}");
        assert!(error.contains("steel"), "{error}");
        let c = compile(prompt, false).unwrap();
        assert_eq!(
            c.material,
            Material {
                prompt: Some(prompt.to_string()),
                ..Material::default()
            }
        );
        assert!(
            c.warnings
                .iter()
                .any(|w| w.contains("no known material word"))
        );
        assert!(c.recognised.is_empty());
        assert!(compile("", true).is_err());
        assert!(compile("A photo of a beam", true).is_err());
    }
}
