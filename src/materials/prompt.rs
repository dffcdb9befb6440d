//! Text prompt → material: compiles a plain-English description such as
//! "A photo of rusty steel beam for construction" into a [`Material`], deterministically and
//! offline. (The 3DGEN paper sent such prompts to a diffusion model; here they are read.)
//!
//! Owns: the prompt vocabulary (bases, colours, shades, conditions, intensities, finishes,
//! spelling variants and the words that are ignored) and the rules that turn words into a
//! material. Must not touch: noise, texture images, rendering or files — the result is plain
//! data that `procedural` evaluates later.
//!
//! # Reading the words
//! - Case does not matter; punctuation is dropped. A hyphenated word is read joined when that
//!   is a known one-word term ("cor-ten", "sand-blasted"), otherwise as its parts, which
//!   phrases then match ("off-white", "rain-soaked", "cast-in-place concrete", "I-beam").
//! - UK and US spellings both work ("galvanised"/"galvanized", "grey"/"gray",
//!   "aluminium"/"aluminum"), and so does a plural in -s/-es ("cracks", "beams").
//! - Longest phrase first: "stainless steel", "plastic board", "dark blue", "sky blue",
//!   "reinforced concrete" are single terms. A multi-word term also matches written as one
//!   word ("darkblue", "offwhite").
//! - Ignored without a warning: stop words, structure nouns (beam, column, silo, tank, pier,
//!   …), words like "photo" or "colour", single letters (the I of I-beam) and anything with a
//!   digit (numbers, units like 10m, grades like S355 or C30/37).
//! - Any other word is unknown: a warning names the nearest known words.
//!
//! # Rules
//! 1. **Base.** Every base word has a natural colour, roughness and specular (see `BASES`;
//!    colours are sRGB approximations of the real material). When several are named, the
//!    most precise word of a family wins ("galvanised structural steel" is galvanised, "oak
//!    timber" is oak, "stone masonry" is stone); between families the last one named wins,
//!    since English puts the head noun last ("steel-reinforced concrete"), with a warning.
//!    "painted"/"paint" anywhere makes the base Painted: paint hides what it covers.
//! 2. **No base named.** A colour means paint ("a blue water silo" is a painted steel silo,
//!    which is what coloured silos and beams are). Otherwise the first condition that implies
//!    a material decides: rusty/corroded → steel (only iron rusts); cracked, weathered,
//!    stained and mossy → concrete (the commonest cracked, streaked or mossy surface on civil
//!    structures); worn → paint (worn describes paint). Otherwise (only "new", "wet", a
//!    finish or a shade) the material is the plain default grey.
//! 3. **Colour on a base.** Paint and plastic take the colour exactly. A colour on a metal
//!    ("red steel beam") means the metal is painted, except "silver", which is how bare
//!    metal looks. Concrete, brick and stone are pigmented: half the named colour, half their
//!    own. Timber is stained: 40 % stain, 60 % wood, so the grain still shows. When several
//!    colours are named the first one wins, with a warning.
//! 4. **Shades** (dark, deep, light, pale, bright) change the colour named right after them
//!    ("dark blue" is darker than "blue"); otherwise they change the material's final colour
//!    ("dark oak").
//! 5. **Conditions** keep prompt order; an intensity word right before one sets its
//!    intensity (slightly 0.3, moderately 0.6, heavily 1.0; 0.6 without one); a repeated
//!    condition keeps its first place and the higher intensity. "New" contradicts ageing
//!    (rusty, corroded, weathered, stained, mossy, worn) but the user named both, so both are
//!    kept and the ageing is capped at "slightly" (0.3): a new beam with a few rust spots.
//!    Cracks and wetness are not ageing (a new slab can crack; new steel can be wet).
//! 6. **Finishes** (matte, satin, glossy, polished, brushed, rough, smooth, sandblasted, raw)
//!    scale the base's roughness and specular, so "polished concrete" and "polished steel"
//!    both get shinier but stay different; results are clamped to roughness (0, 1] and
//!    specular [0, 1].
//! 7. **Nothing known.** A prompt without a single known word is an error in strict mode;
//!    otherwise it gives the default plain grey with a warning. Unknown words next to known
//!    ones are warnings in both modes, so one typo never stops a long run.
//!
//! The paper's prompts: "rusty steel beam" → steel, rusty 0.6; "plastic board" → plastic;
//! "cracked timber" → pine, cracked 0.6; "rosewood block" → rosewood; "steel water silo" →
//! bare steel, no conditions (it says steel, not galvanised, and a word the user did not
//! write is not invented — "galvanised steel silo" gives galvanised); "blue/yellow water silo"
//! → painted blue/yellow.

use super::{Base, Condition, ConditionKind, Material, Species, Texture};
use crate::words::{edit_distance, nearest};
use std::sync::LazyLock;

/// The texture prompts of the 3DGEN paper, in its words (experiments A1 and A2, and its
/// Figure 3 example).
pub const PAPER_PROMPTS: [&str; 7] = [
    "A photo of rusty steel beam for construction",
    "A photo of plastic board for construction",
    "A photo of cracked timber for construction",
    "A photo of a rosewood block for construction",
    "A photo of a steel water silo",
    "A photo of a blue water silo",
    "A photo of a yellow water silo",
];

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
        warnings.push(format!(
            "no known material word in prompt \"{prompt}\"; using plain grey"
        ));
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
    warnings.extend(conflicts.map(|c| format!("material prompt \"{prompt}\" {c}")));
    Ok(Compiled {
        material: build(&reading, prompt),
        warnings,
        recognised: terms.iter().map(|t| t.phrase.to_string()).collect(),
    })
}

/// The full vocabulary (every term and spelling variant), for docs and tests. Ignored words
/// are not vocabulary: see [`ignored_words`].
pub fn known_words() -> Vec<&'static str> {
    LEXICON
        .iter()
        .map(|e| e.phrase)
        .chain(SPELLINGS.iter().map(|(variant, _)| *variant))
        .collect()
}

/// Words that are read and skipped silently: stop words and structure nouns.
pub fn ignored_words() -> &'static [&'static str] {
    IGNORED
}

// ---------------------------------------------------------------------------------------------
// Bases

/// Base words that name the same kind of material at different precision.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Family {
    Metal,
    Concrete,
    Timber,
    Plastic,
    Masonry,
    Paint,
}

/// How precisely a base word names its material; within a family the higher rank wins.
const GENERIC: u8 = 0; // "metal", "timber", "masonry"
const MATERIAL: u8 = 1; // "steel", "brick", "stone", "concrete"
const SPECIFIC: u8 = 2; // "galvanised", "oak", "granite"

/// A base with its natural look.
#[derive(Clone, Copy, Debug, PartialEq)]
struct BaseDef {
    base: Base,
    family: Family,
    /// sRGB, 0–1.
    colour: [f64; 3],
    roughness: f64,
    specular: f64,
}

const fn def(base: Base, family: Family, colour: [f64; 3], rough: f64, spec: f64) -> BaseDef {
    BaseDef {
        base,
        family,
        colour,
        roughness: rough,
        specular: spec,
    }
}

/// Wood: fairly matte, dielectric; species differ in colour.
const fn wood(species: Species, colour: [f64; 3]) -> BaseDef {
    def(Base::Timber(species), Family::Timber, colour, 0.7, 0.04)
}

/// Mineral surfaces: matte, dielectric.
const fn mineral(base: Base, family: Family, colour: [f64; 3], rough: f64) -> BaseDef {
    def(base, family, colour, rough, 0.03)
}

// Bare (blast-cleaned or mill-scale) steel: mid grey, slightly blue, a metal.
// Specular values are kept low: with a single sun and no reflected environment, a higher
// F0 turns whole flat faces into glare.
const STEEL: BaseDef = def(Base::Steel, Family::Metal, [0.52, 0.54, 0.57], 0.6, 0.15);
// Zinc coat: lighter and a little shinier than bare steel.
const GALVANISED: BaseDef = def(
    Base::GalvanisedSteel,
    Family::Metal,
    [0.7, 0.72, 0.74],
    0.5,
    0.25,
);
// The brown oxide patina is what is seen, and it is not metallic: rough and dull.
const WEATHERING: BaseDef = def(
    Base::WeatheringSteel,
    Family::Metal,
    [0.36, 0.2, 0.12],
    0.75,
    0.1,
);
// Stainless: the renderer has no own base for it; steel, lighter, smoother, more specular.
const STAINLESS: BaseDef = def(Base::Steel, Family::Metal, [0.72, 0.73, 0.74], 0.35, 0.4);
const ALUMINIUM: BaseDef = def(Base::Aluminium, Family::Metal, [0.8, 0.81, 0.83], 0.4, 0.35);
const CONCRETE: BaseDef = mineral(Base::Concrete, Family::Concrete, [0.58, 0.57, 0.55], 0.9);
const PINE: BaseDef = wood(Species::Pine, [0.78, 0.62, 0.42]);
const SPRUCE: BaseDef = wood(Species::Spruce, [0.82, 0.7, 0.52]);
const OAK: BaseDef = wood(Species::Oak, [0.65, 0.48, 0.3]);
const ASH: BaseDef = wood(Species::Ash, [0.78, 0.68, 0.52]);
const BIRCH: BaseDef = wood(Species::Birch, [0.85, 0.75, 0.58]);
const CEDAR: BaseDef = wood(Species::Cedar, [0.66, 0.4, 0.25]);
const TEAK: BaseDef = wood(Species::Teak, [0.6, 0.42, 0.24]);
const WALNUT: BaseDef = wood(Species::Walnut, [0.4, 0.27, 0.17]);
const MAHOGANY: BaseDef = wood(Species::Mahogany, [0.48, 0.24, 0.15]);
const ROSEWOOD: BaseDef = wood(Species::Rosewood, [0.36, 0.16, 0.1]);
// Site boards and pipes are mostly off-white or light grey.
const PLASTIC: BaseDef = def(
    Base::Plastic,
    Family::Plastic,
    [0.88, 0.88, 0.86],
    0.4,
    0.05,
);
const BRICK: BaseDef = mineral(Base::Brick, Family::Masonry, [0.62, 0.3, 0.22], 0.9);
const STONE: BaseDef = mineral(Base::Stone, Family::Masonry, [0.62, 0.6, 0.55], 0.85);
const GRANITE: BaseDef = mineral(Base::Stone, Family::Masonry, [0.5, 0.49, 0.48], 0.8);
const LIMESTONE: BaseDef = mineral(Base::Stone, Family::Masonry, [0.8, 0.77, 0.68], 0.85);
const SANDSTONE: BaseDef = mineral(Base::Stone, Family::Masonry, [0.74, 0.62, 0.45], 0.9);
const MARBLE: BaseDef = mineral(Base::Stone, Family::Masonry, [0.88, 0.87, 0.85], 0.5);
const SLATE: BaseDef = mineral(Base::Stone, Family::Masonry, [0.3, 0.32, 0.34], 0.75);
// Paint without a named colour: light grey, like primed or RAL 7035 steelwork.
const PAINT: BaseDef = def(Base::Painted, Family::Paint, [0.68, 0.7, 0.7], 0.5, 0.05);

/// Base words, most typical first in each family (warnings list the first few).
const BASES: &[(&str, u8, BaseDef)] = &[
    ("steel", MATERIAL, STEEL),
    ("concrete", MATERIAL, CONCRETE),
    ("timber", GENERIC, PINE),
    ("wood", GENERIC, PINE),
    ("plastic", MATERIAL, PLASTIC),
    ("brick", MATERIAL, BRICK),
    ("stone", MATERIAL, STONE),
    ("aluminium", MATERIAL, ALUMINIUM),
    ("galvanised steel", SPECIFIC, GALVANISED),
    ("weathering steel", SPECIFIC, WEATHERING),
    ("stainless steel", SPECIFIC, STAINLESS),
    ("painted", SPECIFIC, PAINT),
    ("iron", MATERIAL, STEEL),
    ("cast iron", MATERIAL, STEEL),
    ("metal", GENERIC, STEEL),
    ("metallic", GENERIC, STEEL),
    ("galvanised", SPECIFIC, GALVANISED),
    ("hot dip galvanised", SPECIFIC, GALVANISED),
    ("zinc coated", SPECIFIC, GALVANISED),
    ("weathering", SPECIFIC, WEATHERING),
    ("corten", SPECIFIC, WEATHERING),
    ("stainless", SPECIFIC, STAINLESS),
    ("reinforced concrete", MATERIAL, CONCRETE),
    ("precast concrete", MATERIAL, CONCRETE),
    ("prestressed concrete", MATERIAL, CONCRETE),
    ("cast in place concrete", MATERIAL, CONCRETE),
    ("in situ concrete", MATERIAL, CONCRETE),
    ("reinforced", MATERIAL, CONCRETE),
    ("precast", MATERIAL, CONCRETE),
    ("prestressed", MATERIAL, CONCRETE),
    ("cast in place", MATERIAL, CONCRETE),
    ("in situ", MATERIAL, CONCRETE),
    ("rc", MATERIAL, CONCRETE),
    ("cement", MATERIAL, CONCRETE),
    ("shotcrete", MATERIAL, CONCRETE),
    ("wooden", GENERIC, PINE),
    ("lumber", GENERIC, PINE),
    ("plank", GENERIC, PINE),
    ("softwood", GENERIC, PINE),
    ("hardwood", SPECIFIC, OAK),
    ("pine", SPECIFIC, PINE),
    ("spruce", SPECIFIC, SPRUCE),
    ("fir", SPECIFIC, SPRUCE),
    ("douglas fir", SPECIFIC, SPRUCE),
    // Glued laminated and cross-laminated timber are made of spruce in most of Europe.
    ("glulam", SPECIFIC, SPRUCE),
    ("clt", SPECIFIC, SPRUCE),
    ("oak", SPECIFIC, OAK),
    ("ash", SPECIFIC, ASH),
    ("birch", SPECIFIC, BIRCH),
    ("cedar", SPECIFIC, CEDAR),
    ("teak", SPECIFIC, TEAK),
    ("walnut", SPECIFIC, WALNUT),
    ("mahogany", SPECIFIC, MAHOGANY),
    ("rosewood", SPECIFIC, ROSEWOOD),
    ("plastic board", MATERIAL, PLASTIC),
    ("pvc", MATERIAL, PLASTIC),
    ("upvc", MATERIAL, PLASTIC),
    ("hdpe", MATERIAL, PLASTIC),
    ("polyethylene", MATERIAL, PLASTIC),
    ("polymer", MATERIAL, PLASTIC),
    ("frp", MATERIAL, PLASTIC),
    ("gfrp", MATERIAL, PLASTIC),
    ("masonry", GENERIC, BRICK),
    ("brickwork", MATERIAL, BRICK),
    ("stonework", MATERIAL, STONE),
    ("rock", MATERIAL, STONE),
    ("granite", SPECIFIC, GRANITE),
    ("limestone", SPECIFIC, LIMESTONE),
    ("sandstone", SPECIFIC, SANDSTONE),
    ("marble", SPECIFIC, MARBLE),
    ("slate", SPECIFIC, SLATE),
    ("paint", SPECIFIC, PAINT),
    ("coated", SPECIFIC, PAINT),
    ("powder coated", SPECIFIC, PAINT),
    ("primed", SPECIFIC, PAINT),
    ("enamel", SPECIFIC, PAINT),
];

// ---------------------------------------------------------------------------------------------
// Colours and shades

/// Named colours as sRGB (0–1) approximations of the RAL / ANSI safety colours a site would
/// use, not exact conversions of any standard. Grey/gray and the like are spelling variants.
const COLOURS: &[(&str, [f64; 3])] = &[
    ("red", [0.75, 0.12, 0.11]),
    ("orange", [0.9, 0.42, 0.1]),
    ("yellow", [0.95, 0.8, 0.15]),
    ("green", [0.18, 0.5, 0.22]),
    ("blue", [0.12, 0.3, 0.62]),
    ("white", [0.93, 0.93, 0.91]),
    ("grey", [0.55, 0.55, 0.55]),
    ("black", [0.06, 0.06, 0.06]),
    ("brown", [0.4, 0.26, 0.16]),
    ("dark red", [0.45, 0.07, 0.07]),
    ("maroon", [0.4, 0.1, 0.12]),
    ("burgundy", [0.42, 0.1, 0.16]),
    // The red-brown anticorrosion primer seen on new steelwork.
    ("red oxide", [0.42, 0.18, 0.14]),
    ("terracotta", [0.75, 0.38, 0.25]),
    ("pink", [0.9, 0.6, 0.65]),
    ("safety orange", [1.0, 0.4, 0.0]),
    ("safety yellow", [0.93, 0.76, 0.02]),
    ("gold", [0.8, 0.62, 0.2]),
    ("dark green", [0.1, 0.28, 0.14]),
    ("light green", [0.55, 0.78, 0.5]),
    ("olive", [0.42, 0.42, 0.2]),
    ("olive green", [0.42, 0.42, 0.2]),
    ("lime", [0.6, 0.8, 0.2]),
    ("teal", [0.0, 0.45, 0.45]),
    ("turquoise", [0.2, 0.65, 0.65]),
    ("dark blue", [0.08, 0.16, 0.36]),
    ("navy", [0.07, 0.12, 0.28]),
    ("navy blue", [0.07, 0.12, 0.28]),
    ("light blue", [0.55, 0.72, 0.88]),
    ("sky blue", [0.3, 0.58, 0.82]),
    ("purple", [0.42, 0.22, 0.52]),
    ("violet", [0.42, 0.22, 0.52]),
    ("off white", [0.9, 0.88, 0.82]),
    ("cream", [0.92, 0.87, 0.72]),
    ("ivory", [0.93, 0.9, 0.8]),
    ("light grey", [0.76, 0.77, 0.76]),
    ("dark grey", [0.3, 0.31, 0.32]),
    ("anthracite", [0.22, 0.24, 0.26]),
    ("charcoal", [0.22, 0.22, 0.23]),
    ("silver", [0.72, 0.73, 0.75]),
    ("dark brown", [0.25, 0.16, 0.1]),
    ("tan", [0.82, 0.71, 0.55]),
    ("beige", [0.8, 0.74, 0.6]),
    ("khaki", [0.72, 0.66, 0.45]),
    ("sand", [0.85, 0.76, 0.58]),
];

/// The one colour that does not mean paint on a metal: bare metal looks silver.
const METAL_COLOUR: &str = "silver";

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Shade {
    Dark,
    Light,
    Pale,
    Bright,
}

const SHADES: &[(&str, Shade)] = &[
    ("dark", Shade::Dark),
    ("deep", Shade::Dark),
    ("light", Shade::Light),
    ("pale", Shade::Pale),
    ("bright", Shade::Bright),
];

const WHITE: [f64; 3] = [1.0, 1.0, 1.0];

/// A shade of an sRGB colour; every result stays in [0, 1].
fn shade(colour: [f64; 3], shade: Shade) -> [f64; 3] {
    match shade {
        Shade::Dark => colour.map(|c| c * 0.55),
        Shade::Light => mix(colour, WHITE, 0.4),
        Shade::Pale => mix(colour, WHITE, 0.6),
        // Brighter with the same hue: scale up until the largest component reaches 1.
        Shade::Bright => {
            let largest = colour.iter().copied().fold(0.0, f64::max);
            let gain = (1.0 / largest).min(1.3);
            colour.map(|c| (c * gain).min(1.0))
        }
    }
}

/// `(1 - t)·a + t·b`.
fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [0, 1, 2].map(|i| a[i] * (1.0 - t) + b[i] * t)
}

// ---------------------------------------------------------------------------------------------
// Conditions and intensities

const CONDITIONS: &[(&str, ConditionKind)] = &[
    ("rusty", ConditionKind::Rusty),
    ("corroded", ConditionKind::Corroded),
    ("cracked", ConditionKind::Cracked),
    ("weathered", ConditionKind::Weathered),
    ("stained", ConditionKind::Stained),
    ("mossy", ConditionKind::Mossy),
    ("new", ConditionKind::New),
    ("wet", ConditionKind::Wet),
    ("worn", ConditionKind::Worn),
    ("rust", ConditionKind::Rusty),
    ("rusted", ConditionKind::Rusty),
    ("rusting", ConditionKind::Rusty),
    ("oxidised", ConditionKind::Rusty),
    ("corrosion", ConditionKind::Corroded),
    ("corroding", ConditionKind::Corroded),
    ("pitted", ConditionKind::Corroded),
    ("crack", ConditionKind::Cracked),
    ("cracks", ConditionKind::Cracked),
    ("cracking", ConditionKind::Cracked),
    ("fractured", ConditionKind::Cracked),
    ("split", ConditionKind::Cracked),
    ("aged", ConditionKind::Weathered),
    ("ageing", ConditionKind::Weathered),
    ("old", ConditionKind::Weathered),
    ("faded", ConditionKind::Weathered),
    ("stain", ConditionKind::Stained),
    ("streaked", ConditionKind::Stained),
    ("streaky", ConditionKind::Stained),
    ("dirty", ConditionKind::Stained),
    ("grimy", ConditionKind::Stained),
    ("moss", ConditionKind::Mossy),
    ("mossed", ConditionKind::Mossy),
    ("algae", ConditionKind::Mossy),
    ("lichen", ConditionKind::Mossy),
    ("overgrown", ConditionKind::Mossy),
    ("clean", ConditionKind::New),
    ("fresh", ConditionKind::New),
    ("pristine", ConditionKind::New),
    ("brand new", ConditionKind::New),
    ("damp", ConditionKind::Wet),
    ("moist", ConditionKind::Wet),
    ("soaked", ConditionKind::Wet),
    ("rain", ConditionKind::Wet),
    ("rain soaked", ConditionKind::Wet),
    ("chipped", ConditionKind::Worn),
    ("peeling", ConditionKind::Worn),
    ("flaking", ConditionKind::Worn),
    ("abraded", ConditionKind::Worn),
];

/// Intensity of a condition not qualified by an intensity word.
const DEFAULT_INTENSITY: f64 = 0.6;
const SLIGHT: f64 = 0.3;
const HEAVY: f64 = 1.0;

const INTENSITIES: &[(&str, f64)] = &[
    ("slightly", SLIGHT),
    ("lightly", SLIGHT),
    ("somewhat", SLIGHT),
    ("mildly", SLIGHT),
    ("barely", SLIGHT),
    ("slight", SLIGHT),
    ("minor", SLIGHT),
    ("moderately", DEFAULT_INTENSITY),
    ("partly", DEFAULT_INTENSITY),
    ("partially", DEFAULT_INTENSITY),
    ("fairly", DEFAULT_INTENSITY),
    ("moderate", DEFAULT_INTENSITY),
    ("heavily", HEAVY),
    ("badly", HEAVY),
    ("severely", HEAVY),
    ("very", HEAVY),
    ("extremely", HEAVY),
    ("deeply", HEAVY),
    ("highly", HEAVY),
    ("thoroughly", HEAVY),
    ("completely", HEAVY),
    ("heavy", HEAVY),
    ("severe", HEAVY),
    ("major", HEAVY),
    ("extensive", HEAVY),
];

/// Conditions that mean age; "new" caps them (rule 5).
const AGEING: &[ConditionKind] = &[
    ConditionKind::Rusty,
    ConditionKind::Corroded,
    ConditionKind::Weathered,
    ConditionKind::Stained,
    ConditionKind::Mossy,
    ConditionKind::Worn,
];

/// The material a condition implies when no base is named (rule 2).
fn implied_base(kind: ConditionKind) -> Option<BaseDef> {
    match kind {
        ConditionKind::Rusty | ConditionKind::Corroded => Some(STEEL),
        ConditionKind::Cracked
        | ConditionKind::Weathered
        | ConditionKind::Stained
        | ConditionKind::Mossy => Some(CONCRETE),
        ConditionKind::Worn => Some(PAINT),
        ConditionKind::New | ConditionKind::Wet => None,
    }
}

// ---------------------------------------------------------------------------------------------
// Finishes

/// Factors on the base's roughness and specular, so a finish keeps the difference between
/// bases (polished concrete is still less specular than polished steel).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Finish {
    roughness: f64,
    specular: f64,
}

/// Factors on (roughness, specular).
const fn finish(roughness: f64, specular: f64) -> Finish {
    Finish {
        roughness,
        specular,
    }
}

const MATTE: Finish = finish(1.5, 0.8);
const GLOSSY: Finish = finish(0.35, 1.15);
const SANDBLASTED: Finish = finish(1.6, 0.8);
// As rolled or as cast, unfinished: a little rougher than the base's average.
const RAW: Finish = finish(1.15, 0.9);

const FINISHES: &[(&str, Finish)] = &[
    ("matte", MATTE),
    ("satin", finish(0.8, 1.0)),
    ("glossy", GLOSSY),
    ("polished", finish(0.25, 1.2)),
    // Brushed metal is only a little smoother on average; its streaks are the texture's job.
    ("brushed", finish(0.9, 1.0)),
    ("rough", finish(1.35, 0.85)),
    ("smooth", finish(0.7, 1.0)),
    ("sandblasted", SANDBLASTED),
    ("raw", RAW),
    ("matt", MATTE),
    ("dull", MATTE),
    ("semi gloss", finish(0.6, 1.05)),
    ("gloss", GLOSSY),
    ("shiny", GLOSSY),
    ("reflective", GLOSSY),
    ("high gloss", finish(0.2, 1.2)),
    ("sand blasted", SANDBLASTED),
    ("blasted", SANDBLASTED),
    ("grit blasted", SANDBLASTED),
    ("bare", RAW),
    ("unpainted", RAW),
];

/// Roughness 0 is a perfect mirror, which the microfacet model cannot shade.
const MIN_ROUGHNESS: f64 = 0.02;

// ---------------------------------------------------------------------------------------------
// Spellings and ignored words

/// Single-word spelling variants → the spelling the tables use. Phrases follow automatically
/// ("light gray", "galvanized steel").
const SPELLINGS: &[(&str, &str)] = &[
    ("galvanized", "galvanised"),
    ("aluminum", "aluminium"),
    ("gray", "grey"),
    ("oxidized", "oxidised"),
    ("aging", "ageing"),
];

/// Read and skipped without a warning: what a civil engineer writes around the material.
#[rustfmt::skip]
const IGNORED: &[&str] = &[
    // Stop words.
    "a", "an", "the", "of", "for", "with", "and", "or", "made", "in", "on", "from", "at", "by",
    "to", "into", "as", "is", "are", "it", "its", "this", "that", "some", "out", "like", "up",
    "under", "over", "which", "has", "have", "having", "being", "thing", "object", "item",
    // Picture words.
    "photo", "photograph", "picture", "image", "render", "rendering", "view", "shot", "scene",
    "closeup", "close", "realistic", "photorealistic", "detailed", "texture", "textured",
    "surface", "material", "finish", "colour", "color", "coloured", "colored", "style",
    "outdoor", "outdoors", "site", "high", "quality",
    // Civil engineering and structure nouns.
    "construction", "structural", "structure", "building", "civil", "engineering", "member",
    "element", "beam", "girder", "joist", "rafter", "purlin", "lintel", "column", "pillar",
    "post", "pole", "pile", "silo", "tank", "water", "grain", "storage", "block", "cuboid",
    "cube", "box", "frame", "portal", "truss", "arch", "bridge", "pier", "abutment", "deck",
    "wall", "slab", "plate", "sheet", "panel", "board", "pipe", "tube", "rod", "bar", "section",
    "profile", "channel", "angle", "stud", "tower", "chimney", "culvert", "tunnel", "dam",
    "footing", "foundation", "floor", "roof", "stair", "railing", "barrier", "cladding",
    "facade", "shell", "cylinder", "cylindrical", "rectangular", "square", "round",
    "circular", "hollow", "solid", "tall", "long", "short", "thin", "thick", "large", "small",
    "big", "simply", "supported", "cantilever", "cantilevered", "deformed", "bent", "deflected",
    "loaded", "load", "strength", "grade",
    // Units written apart from their number.
    "mm", "cm", "kn", "mpa", "gpa",
];

// ---------------------------------------------------------------------------------------------
// The lexicon: every table as one list of phrases with their meaning.

#[derive(Clone, Copy, Debug, PartialEq)]
enum Meaning {
    Base { rank: u8, def: BaseDef },
    Colour { name: &'static str, rgb: [f64; 3] },
    Shade(Shade),
    Intensity(f64),
    Condition(ConditionKind),
    Finish(Finish),
}

/// What kind of word a vocabulary term is, for warnings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Category {
    Bases,
    Colours,
    Shades,
    Conditions,
    Intensities,
    Finishes,
}

impl Category {
    const ALL: [Category; 6] = [
        Category::Bases,
        Category::Colours,
        Category::Conditions,
        Category::Finishes,
        Category::Intensities,
        Category::Shades,
    ];

    fn of(meaning: &Meaning) -> Category {
        match meaning {
            Meaning::Base { .. } => Category::Bases,
            Meaning::Colour { .. } => Category::Colours,
            Meaning::Shade(_) => Category::Shades,
            Meaning::Intensity(_) => Category::Intensities,
            Meaning::Condition(_) => Category::Conditions,
            Meaning::Finish(_) => Category::Finishes,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Category::Bases => "bases",
            Category::Colours => "colours",
            Category::Shades => "shades",
            Category::Conditions => "conditions",
            Category::Intensities => "intensities",
            Category::Finishes => "finishes",
        }
    }

    /// The category's terms in table order (most typical first).
    fn words(self) -> Vec<&'static str> {
        LEXICON
            .iter()
            .filter(|e| Category::of(&e.meaning) == self)
            .map(|e| e.phrase)
            .collect()
    }
}

struct Entry {
    phrase: &'static str,
    words: Vec<&'static str>,
    /// The phrase written as one word ("darkblue"), for compound spellings.
    joined: String,
    meaning: Meaning,
}

static LEXICON: LazyLock<Vec<Entry>> = LazyLock::new(|| {
    let bases = BASES
        .iter()
        .map(|&(p, rank, def)| (p, Meaning::Base { rank, def }));
    let colours = COLOURS
        .iter()
        .map(|&(p, rgb)| (p, Meaning::Colour { name: p, rgb }));
    let shades = SHADES.iter().map(|&(p, s)| (p, Meaning::Shade(s)));
    let intensities = INTENSITIES.iter().map(|&(p, x)| (p, Meaning::Intensity(x)));
    let conditions = CONDITIONS.iter().map(|&(p, k)| (p, Meaning::Condition(k)));
    let finishes = FINISHES.iter().map(|&(p, f)| (p, Meaning::Finish(f)));
    bases
        .chain(colours)
        .chain(shades)
        .chain(intensities)
        .chain(conditions)
        .chain(finishes)
        .map(|(phrase, meaning)| Entry {
            phrase,
            words: phrase.split(' ').collect(),
            joined: phrase.replace(' ', ""),
            meaning,
        })
        .collect()
});

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

fn normalise_spelling(word: &str) -> String {
    SPELLINGS
        .iter()
        .find(|(variant, _)| *variant == word)
        .map_or(word, |(_, standard)| standard)
        .to_string()
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
    conflicts: Vec<String>,
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
        reading.conflicts.push(format!(
            "names both \"{old_word}\" and \"{word}\"; using \"{word}\", the last material named"
        ));
    }
    reading.base = Some((def, rank, word));
}

/// Rule 3: the first colour wins.
fn choose_colour(reading: &mut Reading, word: &str, name: &'static str, rgb: [f64; 3]) {
    match reading.colour {
        None => reading.colour = Some((name, rgb)),
        Some((first, _)) if first != name => reading.conflicts.push(format!(
            "names several colours; using \"{first}\", the first, and ignoring \"{word}\""
        )),
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

// ---------------------------------------------------------------------------------------------
// Messages

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
    format!("known {}: {}{more}", category.name(), shown.join(", "))
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

fn unknown_word_warning(word: &str, prompt: &str) -> String {
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

fn nothing_known_error(prompt: &str, unknown: &[&str]) -> String {
    let mut message = format!("no known material word in prompt \"{prompt}\"");
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

#[cfg(test)]
mod tests {
    use super::*;

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
    fn vocabulary_has_no_duplicates_and_no_ignored_words() {
        let words = known_words();
        for (i, w) in words.iter().enumerate() {
            assert!(!words[i + 1..].contains(w), "{w} twice");
            assert!(!IGNORED.contains(w), "{w} is both known and ignored");
            assert_eq!(w.trim(), *w);
            assert!(w.chars().all(|c| c.is_ascii_lowercase() || c == ' '), "{w}");
        }
        for (i, w) in IGNORED.iter().enumerate() {
            assert!(!IGNORED[i + 1..].contains(w), "{w} ignored twice");
        }
    }

    #[test]
    fn colours_are_in_range() {
        for &(name, rgb) in COLOURS {
            assert!(rgb.iter().all(|c| (0.0..=1.0).contains(c)), "{name}");
            for &(_, s) in SHADES {
                let shaded = shade(rgb, s);
                assert!(shaded.iter().all(|c| (0.0..=1.0).contains(c)), "{name}");
            }
        }
        for &(word, _, def) in BASES {
            assert!(def.colour.iter().all(|c| (0.0..=1.0).contains(c)), "{word}");
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
