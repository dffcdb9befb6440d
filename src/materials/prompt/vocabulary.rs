//! The prompt vocabulary: every word a prompt may use and what it means — bases with their
//! natural look and precision, colours and shades, conditions and intensities, finishes,
//! spelling variants and the words read and skipped. Data and the arithmetic that defines a
//! shade; the rules that combine words are the reader's.

use crate::materials::{Base, ConditionKind, Species};
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
pub(super) enum Family {
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
pub(super) struct BaseDef {
    pub(super) base: Base,
    pub(super) family: Family,
    /// sRGB, 0–1.
    pub(super) colour: [f64; 3],
    pub(super) roughness: f64,
    pub(super) specular: f64,
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

/// Metals differ in finish as well as colour, so each sets its own roughness and specular.
const fn metal(base: Base, colour: [f64; 3], rough: f64, spec: f64) -> BaseDef {
    def(base, Family::Metal, colour, rough, spec)
}

/// Mineral surfaces: matte, dielectric.
const fn mineral(base: Base, family: Family, colour: [f64; 3], rough: f64) -> BaseDef {
    def(base, family, colour, rough, 0.03)
}

// Bare (blast-cleaned or mill-scale) steel: mid grey, slightly blue, a metal.
// Specular values are kept low: with a single sun and no reflected environment, a higher
// F0 turns whole flat faces into glare.
// Hot-rolled steel as delivered: mill scale, a dark blue-grey oxide skin.
const STEEL: BaseDef = metal(Base::Steel, [0.4, 0.41, 0.44], 0.6, 0.15);
// Zinc coat: lighter and a little shinier than bare steel.
const GALVANISED: BaseDef = metal(Base::GalvanisedSteel, [0.7, 0.72, 0.74], 0.5, 0.25);
// The brown oxide patina is what is seen, and it is not metallic: rough and dull.
const WEATHERING: BaseDef = metal(Base::WeatheringSteel, [0.36, 0.2, 0.12], 0.75, 0.1);
// Stainless: the renderer has no own base for it; steel, lighter, smoother, more specular.
const STAINLESS: BaseDef = metal(Base::Steel, [0.72, 0.73, 0.74], 0.35, 0.4);
const ALUMINIUM: BaseDef = metal(Base::Aluminium, [0.8, 0.81, 0.83], 0.4, 0.35);
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
pub(super) const PAINT: BaseDef = def(Base::Painted, Family::Paint, [0.68, 0.7, 0.7], 0.5, 0.05);

/// Base words, most typical first in each family (warnings list the first few).
pub(super) const BASES: &[(&str, u8, BaseDef)] = &[
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
pub(super) const COLOURS: &[(&str, [f64; 3])] = &[
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
pub(super) const METAL_COLOUR: &str = "silver";

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Shade {
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
pub(super) fn shade(colour: [f64; 3], shade: Shade) -> [f64; 3] {
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
pub(super) fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
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
pub(super) const DEFAULT_INTENSITY: f64 = 0.6;
pub(super) const SLIGHT: f64 = 0.3;
pub(super) const HEAVY: f64 = 1.0;

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
pub(super) const AGEING: &[ConditionKind] = &[
    ConditionKind::Rusty,
    ConditionKind::Corroded,
    ConditionKind::Weathered,
    ConditionKind::Stained,
    ConditionKind::Mossy,
    ConditionKind::Worn,
];

/// The material a condition implies when no base is named (rule 2).
pub(super) fn implied_base(kind: ConditionKind) -> Option<BaseDef> {
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
pub(super) struct Finish {
    pub(super) roughness: f64,
    pub(super) specular: f64,
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

pub(super) const FINISHES: &[(&str, Finish)] = &[
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

/// The spelling the tables use for a word (itself unless it is a variant).
pub(super) fn normalise_spelling(word: &str) -> String {
    SPELLINGS
        .iter()
        .find(|(variant, _)| *variant == word)
        .map_or(word, |(_, standard)| standard)
        .to_string()
}

/// Read and skipped without a warning: what a civil engineer writes around the material.
#[rustfmt::skip]
pub(super) const IGNORED: &[&str] = &[
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
pub(super) enum Meaning {
    Base { rank: u8, def: BaseDef },
    Colour { name: &'static str, rgb: [f64; 3] },
    Shade(Shade),
    Intensity(f64),
    Condition(ConditionKind),
    Finish(Finish),
}

/// What kind of word a vocabulary term is, for warnings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Category {
    Bases,
    Colours,
    Shades,
    Conditions,
    Intensities,
    Finishes,
}

impl Category {
    pub(super) const ALL: [Category; 6] = [
        Category::Bases,
        Category::Colours,
        Category::Conditions,
        Category::Finishes,
        Category::Intensities,
        Category::Shades,
    ];

    pub(super) fn of(meaning: &Meaning) -> Category {
        match meaning {
            Meaning::Base { .. } => Category::Bases,
            Meaning::Colour { .. } => Category::Colours,
            Meaning::Shade(_) => Category::Shades,
            Meaning::Intensity(_) => Category::Intensities,
            Meaning::Condition(_) => Category::Conditions,
            Meaning::Finish(_) => Category::Finishes,
        }
    }

    /// The category's terms in table order (most typical first).
    pub(super) fn words(self) -> Vec<&'static str> {
        LEXICON
            .iter()
            .filter(|e| Category::of(&e.meaning) == self)
            .map(|e| e.phrase)
            .collect()
    }
}

pub(super) struct Entry {
    pub(super) phrase: &'static str,
    pub(super) words: Vec<&'static str>,
    /// The phrase written as one word ("darkblue"), for compound spellings.
    pub(super) joined: String,
    pub(super) meaning: Meaning,
}

pub(super) static LEXICON: LazyLock<Vec<Entry>> = LazyLock::new(|| {
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
