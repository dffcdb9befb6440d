//! Reading a prompt: words → tokens → vocabulary terms, and the rules (numbered in the module
//! doc) that turn those terms into a [`Material`]. Problems found on the way are handed to
//! `messages` to be worded.

use super::messages::{
    Conflict, conflict_warning, nothing_known_error, nothing_known_warning, unknown_word_warning,
};
use super::vocabulary::{
    AGEING, BaseDef, DEFAULT_INTENSITY, Entry, Family, Finish, IGNORED, LEXICON, METAL_COLOUR,
    Meaning, PAINT, SLIGHT, Shade, implied_base, mix, normalise_spelling, shade,
};
use crate::materials::{Condition, ConditionKind, Material, Texture};

/// The result of compiling a prompt.
#[derive(Clone, Debug, PartialEq)]
pub struct Compiled {
    /// prompt: Some(original text), texture: Texture::Procedural, scale 1.0.
    pub material: Material,
    /// One per unknown word, plus one per conflict (two materials, two colours) and one when
    /// no word is known.
    pub warnings: Vec<String>,
    /// The vocabulary terms that drove the material, in prompt order (e.g. ["rusty", "steel"]).
    pub recognised: Vec<String>,
}

/// Compiles a prompt. Errors only in strict mode, when the prompt has no known word at all.
pub fn compile(prompt: &str, strict: bool) -> Result<Compiled, String> {
    let pieces = read(&tokenise(prompt));
    let unknown: Vec<&str> = pieces
        .iter()
        .filter_map(|p| match p {
            Piece::Unknown(word) => Some(word.as_str()),
            Piece::Term(_) => None,
        })
        .collect();
    let terms: Vec<Term> = pieces
        .iter()
        .filter_map(|p| match p {
            Piece::Term(term) => Some(*term),
            Piece::Unknown(_) => None,
        })
        .collect();
    let mut warnings: Vec<String> = unknown
        .iter()
        .map(|word| unknown_word_warning(word, prompt))
        .collect();

    if terms.is_empty() {
        if strict {
            return Err(nothing_known_error(prompt, &unknown));
        }
        warnings.push(nothing_known_warning(prompt));
        let material = Material {
            prompt: Some(prompt.to_string()),
            ..Material::default()
        };
        return Ok(Compiled {
            material,
            warnings,
            recognised: Vec::new(),
        });
    }

    let reading = interpret(&terms);
    let conflicts = reading.conflicts.iter();
    warnings.extend(conflicts.map(|c| conflict_warning(prompt, c)));
    Ok(Compiled {
        material: build(&reading, prompt),
        warnings,
        recognised: terms.iter().map(|t| t.phrase.to_string()).collect(),
    })
}

// ---------------------------------------------------------------------------------------------
// Reading: text → tokens → terms

/// Lower-case words with their spelling normalised; numbers, single letters and punctuation
/// dropped; hyphenated words joined if known, else split.
fn tokenise(prompt: &str) -> Vec<String> {
    let cleaned: String = prompt
        .to_lowercase()
        .chars()
        .filter(|c| !matches!(c, '\'' | '’'))
        .map(|c| {
            if c.is_alphanumeric() || c == '-' {
                c
            } else {
                ' '
            }
        })
        .collect();
    let mut tokens = Vec::new();
    for chunk in cleaned.split_whitespace() {
        let parts: Vec<&str> = chunk.split('-').filter(|p| !p.is_empty()).collect();
        let joined = parts.concat();
        if parts.len() == 1 || is_single_word(&normalise_spelling(&joined)) {
            tokens.push(joined);
        } else {
            tokens.extend(parts.into_iter().map(str::to_string));
        }
    }
    tokens
        .into_iter()
        .filter(|t| t.chars().count() > 1 && !t.chars().any(|c| c.is_ascii_digit()))
        .map(|t| normalise_spelling(&t))
        .collect()
}

/// Whether a token is a one-word term or an ignored word ("corten", "sandblasted", "closeup").
/// Other hyphenated words are read as their parts, which phrases then match
/// ("off-white", "cast-in-place").
fn is_single_word(token: &str) -> bool {
    let one_word = |e: &&Entry| e.words.len() == 1 && same_word(token, e.phrase);
    LEXICON.iter().any(|e| one_word(&e)) || is_ignored(token)
}

/// A plural's singular, for "cracks", "beams", "boxes"; never for "moss" or "glass".
fn singular(word: &str) -> Option<String> {
    if word.len() <= 3 || word.ends_with("ss") {
        return None;
    }
    if let Some(stem) = word.strip_suffix("ies") {
        return Some(format!("{stem}y"));
    }
    if let Some(stem) = word.strip_suffix("es")
        && (stem.ends_with(['s', 'x']) || stem.ends_with("ch") || stem.ends_with("sh"))
    {
        return Some(stem.to_string());
    }
    word.strip_suffix('s').map(str::to_string)
}

/// The token as written, or its singular.
fn same_word(token: &str, word: &str) -> bool {
    token == word || singular(token).is_some_and(|s| s == word)
}

fn is_ignored(token: &str) -> bool {
    IGNORED.iter().any(|w| same_word(token, w))
}

/// A vocabulary term read from a prompt.
#[derive(Clone, Copy, Debug)]
struct Term {
    phrase: &'static str,
    meaning: Meaning,
}

enum Piece {
    Term(Term),
    Unknown(String),
}

/// The longest term starting at `tokens[0]`, and how many tokens it takes.
fn longest_term(tokens: &[String]) -> Option<(Term, usize)> {
    LEXICON
        .iter()
        .filter_map(|entry| {
            let n = entry.words.len();
            let as_phrase = tokens.len() >= n
                && entry
                    .words
                    .iter()
                    .zip(tokens)
                    .all(|(word, token)| same_word(token, word));
            let as_compound = n > 1 && same_word(&tokens[0], &entry.joined);
            let taken = if as_phrase {
                n
            } else {
                usize::from(as_compound)
            };
            // At equal length a word as written beats a compound ("sandblasted").
            (taken > 0).then_some((entry, taken, as_phrase))
        })
        .max_by_key(|(_, taken, as_phrase)| (*taken, *as_phrase))
        .map(|(entry, taken, _)| {
            let term = Term {
                phrase: entry.phrase,
                meaning: entry.meaning,
            };
            (term, taken)
        })
}

/// Terms and unknown words in prompt order; ignored words vanish.
fn read(tokens: &[String]) -> Vec<Piece> {
    let mut pieces = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        if let Some((term, taken)) = longest_term(&tokens[i..]) {
            pieces.push(Piece::Term(term));
            i += taken;
            continue;
        }
        if !is_ignored(&tokens[i]) {
            pieces.push(Piece::Unknown(tokens[i].clone()));
        }
        i += 1;
    }
    pieces
}

// ---------------------------------------------------------------------------------------------
// Interpreting: terms → what the prompt asks for

/// What the terms asked for, before the rules combine it into a material.
#[derive(Default)]
struct Reading {
    /// The chosen base with the rank and word that chose it.
    base: Option<(BaseDef, u8, &'static str)>,
    painted: bool,
    colour: Option<(&'static str, [f64; 3])>,
    /// Shades that did not precede a colour: applied to the final colour.
    material_shades: Vec<Shade>,
    conditions: Vec<Condition>,
    finishes: Vec<Finish>,
    conflicts: Vec<Conflict>,
}

fn interpret(terms: &[Term]) -> Reading {
    let mut reading = Reading::default();
    // An intensity qualifies the condition right after it; shades wait for a colour.
    let mut intensity: Option<f64> = None;
    let mut shades: Vec<Shade> = Vec::new();
    for term in terms {
        // A shade not followed by a colour changes the material's own colour ("dark oak").
        if !matches!(term.meaning, Meaning::Shade(_) | Meaning::Colour { .. }) {
            reading.material_shades.append(&mut shades);
        }
        let pending = intensity.take();
        match term.meaning {
            Meaning::Intensity(x) => intensity = Some(x),
            Meaning::Shade(s) => shades.push(s),
            Meaning::Colour { name, rgb } => {
                let rgb = shades.drain(..).fold(rgb, shade);
                choose_colour(&mut reading, term.phrase, name, rgb);
            }
            Meaning::Base { rank, def } => choose_base(&mut reading, term.phrase, rank, def),
            Meaning::Condition(kind) => {
                let x = pending.unwrap_or(DEFAULT_INTENSITY);
                add_condition(&mut reading.conditions, kind, x);
            }
            Meaning::Finish(f) => reading.finishes.push(f),
        }
    }
    reading.material_shades.append(&mut shades);
    if reading
        .conditions
        .iter()
        .any(|c| c.kind == ConditionKind::New)
    {
        for c in &mut reading.conditions {
            if AGEING.contains(&c.kind) {
                c.intensity = c.intensity.min(SLIGHT);
            }
        }
    }
    reading
}

/// Rule 1: paint wins; within a family the more precise word; between families the last.
fn choose_base(reading: &mut Reading, word: &'static str, rank: u8, def: BaseDef) {
    if def.family == Family::Paint {
        reading.painted = true;
        return;
    }
    let Some((old, old_rank, old_word)) = reading.base else {
        reading.base = Some((def, rank, word));
        return;
    };
    if old.family == def.family && old_rank > rank {
        return;
    }
    let more_precise = old.family == def.family && rank > old_rank;
    if old != def && !more_precise {
        reading.conflicts.push(Conflict::Bases {
            earlier: old_word,
            used: word,
        });
    }
    reading.base = Some((def, rank, word));
}

/// Rule 3: the first colour wins.
fn choose_colour(reading: &mut Reading, word: &'static str, name: &'static str, rgb: [f64; 3]) {
    match reading.colour {
        None => reading.colour = Some((name, rgb)),
        Some((first, _)) if first != name => reading.conflicts.push(Conflict::Colours {
            used: first,
            ignored: word,
        }),
        Some(_) => {}
    }
}

/// Rule 5: prompt order; a repeated condition keeps its place and the higher intensity.
fn add_condition(conditions: &mut Vec<Condition>, kind: ConditionKind, intensity: f64) {
    match conditions.iter_mut().find(|c| c.kind == kind) {
        Some(c) => c.intensity = c.intensity.max(intensity),
        None => conditions.push(Condition { kind, intensity }),
    }
}

// ---------------------------------------------------------------------------------------------
// Building: the rules → a material

/// Roughness 0 is a perfect mirror, which the microfacet model cannot shade.
const MIN_ROUGHNESS: f64 = 0.02;

fn build(reading: &Reading, prompt: &str) -> Material {
    let plain = Material::default();
    let def = resolve_base(reading);
    let (base, natural, roughness, specular) = match def {
        Some(def) => (def.base, def.colour, def.roughness, def.specular),
        None => (plain.base, plain.colour, plain.roughness, plain.specular),
    };
    // A colour always has a base: paint if nothing else (rule 2).
    let colour = match (def, reading.colour) {
        (Some(def), Some((_, rgb))) => mix(natural, rgb, colour_weight(def.family)),
        _ => natural,
    };
    let colour = reading.material_shades.iter().copied().fold(colour, shade);
    let (roughness, specular) = reading
        .finishes
        .iter()
        .fold((roughness, specular), |(r, s), f| {
            (
                (r * f.roughness).clamp(MIN_ROUGHNESS, 1.0),
                (s * f.specular).clamp(0.0, 1.0),
            )
        });
    Material {
        prompt: Some(prompt.to_string()),
        base,
        colour,
        roughness,
        specular,
        conditions: reading.conditions.clone(),
        scale: 1.0,
        texture: Texture::Procedural,
    }
}

/// Rules 1–3: the base that shows, or None for the plain default.
fn resolve_base(reading: &Reading) -> Option<BaseDef> {
    let named = reading.base.map(|(def, _, _)| def);
    let coloured_metal = matches!(
        (named, reading.colour),
        (Some(def), Some((name, _))) if def.family == Family::Metal && name != METAL_COLOUR
    );
    if reading.painted || coloured_metal || (named.is_none() && reading.colour.is_some()) {
        return Some(PAINT);
    }
    named.or_else(|| reading.conditions.iter().find_map(|c| implied_base(c.kind)))
}

/// Rule 3: how much of a named colour shows on each family.
fn colour_weight(family: Family) -> f64 {
    match family {
        Family::Paint | Family::Plastic => 1.0,
        Family::Concrete | Family::Masonry => 0.5,
        Family::Timber => 0.4,
        // Only "silver" reaches here: bare metal keeps its own colour.
        Family::Metal => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::prompt::vocabulary::{
        BASES, COLOURS, FINISHES, HEAVY, PAPER_PROMPTS, known_words,
    };
    use crate::materials::{Base, Species};

    fn material(prompt: &str) -> Material {
        let compiled = compile(prompt, true).unwrap();
        assert!(
            compiled.warnings.is_empty(),
            "{prompt}: {:?}",
            compiled.warnings
        );
        compiled.material
    }

    fn conditions(m: &Material) -> Vec<(ConditionKind, f64)> {
        m.conditions.iter().map(|c| (c.kind, c.intensity)).collect()
    }

    /// Relative luminance (Rec. 709 weights on linear light).
    fn luminance(m: &Material) -> f64 {
        let [r, g, b] = m.albedo();
        0.2126 * r + 0.7152 * g + 0.0722 * b
    }

    /// Hue-free test of "mostly this channel".
    fn dominant(colour: [f64; 3]) -> usize {
        (0..3)
            .max_by(|&a, &b| colour[a].total_cmp(&colour[b]))
            .unwrap()
    }

    #[test]
    fn paper_rusty_steel_beam() {
        let c = compile(PAPER_PROMPTS[0], true).unwrap();
        assert_eq!(c.material.base, Base::Steel);
        assert_eq!(
            conditions(&c.material),
            [(ConditionKind::Rusty, DEFAULT_INTENSITY)]
        );
        assert_eq!(c.recognised, ["rusty", "steel"]);
        assert_eq!(c.material.prompt.as_deref(), Some(PAPER_PROMPTS[0]));
        assert_eq!(c.material.texture, Texture::Procedural);
        assert_eq!(c.material.scale, 1.0);
    }

    #[test]
    fn paper_plastic_board() {
        let m = material(PAPER_PROMPTS[1]);
        assert_eq!(m.base, Base::Plastic);
        assert!(m.conditions.is_empty());
    }

    #[test]
    fn paper_cracked_timber() {
        let m = material(PAPER_PROMPTS[2]);
        assert_eq!(m.base, Base::Timber(Species::Pine));
        assert_eq!(
            conditions(&m),
            [(ConditionKind::Cracked, DEFAULT_INTENSITY)]
        );
    }

    #[test]
    fn paper_rosewood_block() {
        let m = material(PAPER_PROMPTS[3]);
        assert_eq!(m.base, Base::Timber(Species::Rosewood));
        assert!(m.conditions.is_empty());
    }

    #[test]
    fn paper_steel_silo_is_bare_steel() {
        let m = material(PAPER_PROMPTS[4]);
        assert_eq!(m.base, Base::Steel);
        assert!(m.conditions.is_empty());
    }

    #[test]
    fn paper_coloured_silos_are_painted() {
        let blue = material(PAPER_PROMPTS[5]);
        let yellow = material(PAPER_PROMPTS[6]);
        assert_eq!(blue.base, Base::Painted);
        assert_eq!(yellow.base, Base::Painted);
        assert_eq!(dominant(blue.colour), 2);
        // Yellow: red and green high, blue low.
        assert!(yellow.colour[0] > 0.7 && yellow.colour[1] > 0.6 && yellow.colour[2] < 0.3);
    }

    #[test]
    fn paper_materials_are_pairwise_different() {
        // Without the prompt text, which alone would make them differ.
        let all: Vec<Material> = PAPER_PROMPTS
            .iter()
            .map(|p| Material {
                prompt: None,
                ..material(p)
            })
            .collect();
        for i in 0..all.len() {
            for j in i + 1..all.len() {
                assert_ne!(
                    all[i], all[j],
                    "{} vs {}",
                    PAPER_PROMPTS[i], PAPER_PROMPTS[j]
                );
            }
        }
    }

    #[test]
    fn intensity_words() {
        let cases = [
            ("slightly rusty steel", SLIGHT),
            ("lightly rusted steel", SLIGHT),
            ("mildly rusty", SLIGHT),
            ("moderately rusty steel", DEFAULT_INTENSITY),
            ("partly rusted", DEFAULT_INTENSITY),
            ("rusty steel", DEFAULT_INTENSITY),
            ("heavily rusted steel", HEAVY),
            ("badly rusted", HEAVY),
            ("severely rusty", HEAVY),
            ("very rusty", HEAVY),
        ];
        for (prompt, intensity) in cases {
            let m = material(prompt);
            assert_eq!(m.base, Base::Steel, "{prompt}");
            assert_eq!(
                conditions(&m),
                [(ConditionKind::Rusty, intensity)],
                "{prompt}"
            );
        }
        // An intensity qualifies only the next condition.
        let m = material("heavily cracked and stained concrete");
        assert_eq!(
            conditions(&m),
            [
                (ConditionKind::Cracked, HEAVY),
                (ConditionKind::Stained, DEFAULT_INTENSITY)
            ]
        );
    }

    #[test]
    fn conditions_keep_order_and_the_higher_intensity() {
        let m = material("slightly rusty, cracked and badly rusted steel");
        assert_eq!(
            conditions(&m),
            [
                (ConditionKind::Rusty, HEAVY),
                (ConditionKind::Cracked, DEFAULT_INTENSITY)
            ]
        );
    }

    #[test]
    fn new_caps_ageing_but_not_cracks() {
        let m = material("new heavily rusted steel with severe cracks");
        assert_eq!(
            conditions(&m),
            [
                (ConditionKind::New, DEFAULT_INTENSITY),
                (ConditionKind::Rusty, SLIGHT),
                (ConditionKind::Cracked, HEAVY)
            ]
        );
    }

    #[test]
    fn conditions_alone_imply_a_base() {
        assert_eq!(material("rusty").base, Base::Steel);
        assert_eq!(material("corroded member").base, Base::Steel);
        assert_eq!(material("cracked").base, Base::Concrete);
        assert_eq!(material("a mossy wall").base, Base::Concrete);
        assert_eq!(material("worn").base, Base::Painted);
        assert_eq!(material("new").base, Base::Plain);
    }

    #[test]
    fn multi_word_bases() {
        let steel = material("steel");
        let galvanised = material("galvanised steel");
        let stainless = material("stainless steel beam");
        assert_eq!(galvanised.base, Base::GalvanisedSteel);
        assert_eq!(material("weathering steel").base, Base::WeatheringSteel);
        assert_eq!(material("Cor-Ten steel").base, Base::WeatheringSteel);
        assert_eq!(material("corten").base, Base::WeatheringSteel);
        assert_eq!(stainless.base, Base::Steel);
        assert!(stainless.roughness < steel.roughness);
        assert!(stainless.specular > steel.specular);
        assert!(luminance(&stainless) > luminance(&steel));
        assert_eq!(material("plastic board").base, Base::Plastic);
        assert_eq!(material("painted steel").base, Base::Painted);
        for prompt in [
            "reinforced concrete",
            "precast concrete",
            "cast-in-place concrete",
            "in-situ concrete",
        ] {
            let c = compile(prompt, true).unwrap();
            assert_eq!(c.material.base, Base::Concrete, "{prompt}");
            assert_eq!(c.recognised.len(), 1, "{prompt}: {:?}", c.recognised);
        }
    }

    #[test]
    fn precise_base_beats_generic_and_last_family_wins() {
        assert_eq!(
            material("galvanised structural steel").base,
            Base::GalvanisedSteel
        );
        assert_eq!(material("oak timber beam").base, Base::Timber(Species::Oak));
        assert_eq!(material("timber, oak").base, Base::Timber(Species::Oak));
        assert_eq!(material("stone masonry").base, Base::Stone);
        assert_eq!(material("fir").base, Base::Timber(Species::Spruce));
        let c = compile("steel-reinforced concrete", true).unwrap();
        assert_eq!(c.material.base, Base::Concrete);
        assert_eq!(c.warnings.len(), 1, "{:?}", c.warnings);
        assert!(c.warnings[0].contains("\"steel\""));
    }

    #[test]
    fn colour_rules() {
        let red = COLOURS.iter().find(|(n, _)| *n == "red").unwrap().1;
        let red_steel = material("red steel beam");
        assert_eq!((red_steel.base, red_steel.colour), (Base::Painted, red));
        assert_eq!(material("silver aluminium").base, Base::Aluminium);
        assert_eq!(material("red plastic").colour, red);
        assert_eq!(material("red painted concrete").colour, red);
        let concrete = material("concrete");
        let red_concrete = material("red concrete");
        assert_eq!(red_concrete.base, Base::Concrete);
        assert_eq!(red_concrete.colour, mix(concrete.colour, red, 0.5));
        let oak = material("oak");
        let red_oak = material("red oak");
        assert_eq!(red_oak.base, Base::Timber(Species::Oak));
        assert_eq!(red_oak.colour, mix(oak.colour, red, 0.4));
        let c = compile("blue and yellow silo", true).unwrap();
        assert_eq!(c.material.colour, material("blue").colour);
        assert_eq!(c.warnings.len(), 1);
    }

    #[test]
    fn multi_word_colours() {
        for prompt in [
            "dark blue",
            "light grey",
            "sky blue",
            "navy blue",
            "olive green",
            "safety yellow",
            "off-white",
            "offwhite",
            "red oxide",
        ] {
            let c = compile(prompt, true).unwrap();
            assert!(c.warnings.is_empty(), "{prompt}: {:?}", c.warnings);
            assert_eq!(c.recognised.len(), 1, "{prompt}: {:?}", c.recognised);
            assert_eq!(c.material.base, Base::Painted);
        }
        assert_eq!(material("navy").colour, material("navy blue").colour);
    }

    #[test]
    fn shades_darken_and_lighten() {
        let blue = luminance(&material("blue"));
        assert!(luminance(&material("dark blue")) < blue);
        assert!(luminance(&material("deep blue")) < blue);
        assert!(luminance(&material("light blue")) > blue);
        assert!(luminance(&material("pale blue")) > blue);
        assert!(luminance(&material("bright blue")) > blue);
        let red = luminance(&material("red"));
        assert!(luminance(&material("dark red")) < red);
        assert!(luminance(&material("dark orange")) < luminance(&material("orange")));
        // Without a colour after it, a shade changes the material's own colour.
        assert!(luminance(&material("dark oak")) < luminance(&material("oak")));
        assert!(luminance(&material("pale concrete")) > luminance(&material("concrete")));
    }

    #[test]
    fn spellings() {
        let pairs = [
            ("galvanized steel", "galvanised steel"),
            ("gray", "grey"),
            ("light gray", "light grey"),
            ("aluminum", "aluminium"),
            ("oxidized steel", "oxidised steel"),
            ("Rusted", "rusty"),
            ("RUST", "rusty"),
            ("cracks", "crack"),
            ("mossed", "mossy"),
            ("aged", "weathered"),
            ("old", "weathered"),
            ("stain", "stained"),
            ("damp", "wet"),
            ("rain-soaked", "wet"),
            ("clean", "new"),
            ("fresh", "new"),
            ("iron", "steel"),
            ("wooden", "timber"),
            ("lumber", "timber"),
            ("pvc", "plastic"),
            ("brickwork", "brick"),
            ("gloss", "glossy"),
        ];
        for (a, b) in pairs {
            let (mut ma, mut mb) = (material(a), material(b));
            (ma.prompt, mb.prompt) = (None, None);
            assert_eq!(ma, mb, "{a} vs {b}");
        }
    }

    #[test]
    fn finishes_scale_roughness_and_specular() {
        let steel = material("steel");
        assert!(material("polished steel").roughness < steel.roughness);
        assert!(material("matte steel").roughness > steel.roughness);
        assert!(material("glossy paint").roughness < material("paint").roughness);
        assert!(material("sandblasted steel").specular < steel.specular);
    }

    #[test]
    fn stop_words_numbers_and_letters_never_warn() {
        let prompt = format!(
            "{} 3 10m S355 C30/37 I-beam H-pile; steel!",
            IGNORED.join(" ")
        );
        let c = compile(&prompt, true).unwrap();
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        assert_eq!(c.recognised, ["steel"]);
        assert!(
            compile("steel beams, columns and boxes", true)
                .unwrap()
                .warnings
                .is_empty()
        );
    }

    #[test]
    fn every_known_word_compiles_alone() {
        for word in known_words() {
            let c = compile(word, true).unwrap_or_else(|e| panic!("{word}: {e}"));
            assert!(c.warnings.is_empty(), "{word}: {:?}", c.warnings);
            assert_eq!(c.recognised.len(), 1, "{word}: {:?}", c.recognised);
        }
    }

    #[test]
    fn roughness_and_specular_stay_in_range_for_every_base_and_finish() {
        let finishes: Vec<&str> = FINISHES.iter().map(|(f, _)| *f).collect();
        for &(base, _, _) in BASES {
            for first in &finishes {
                for second in finishes.iter().chain([&""]) {
                    let prompt = format!("{first} {second} {base}");
                    let m = compile(&prompt, true).unwrap().material;
                    assert!(m.roughness > 0.0 && m.roughness <= 1.0, "{prompt}");
                    assert!((0.0..=1.0).contains(&m.specular), "{prompt}");
                    assert!(m.colour.iter().all(|c| (0.0..=1.0).contains(c)));
                }
            }
        }
    }
}
