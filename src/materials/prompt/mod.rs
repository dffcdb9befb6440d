//! Text prompt → material: compiles a plain-English description such as
//! "A photo of rusty steel beam for construction" into a [`Material`](super::Material), deterministically and
//! offline. (The 3DGEN paper sent such prompts to a diffusion model; here they are read.)
//!
//! Owns: the prompt vocabulary (bases, colours, shades, conditions, intensities, finishes,
//! spelling variants and the words that are ignored) and the rules that turn words into a
//! material. Must not touch: noise, texture images, rendering or files — the result is plain
//! data that `procedural` evaluates later.
//!
//! `vocabulary` holds the word tables, `reader` reads a prompt and applies the rules below,
//! and `messages` words every warning and error, so what the user reads is in one file.
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
//! 1. **Base.** Every base word has a natural colour, roughness and specular (see `vocabulary::BASES`;
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

mod messages;
mod reader;
mod vocabulary;

pub use reader::{Compiled, compile};
pub use vocabulary::{PAPER_PROMPTS, ignored_words, known_words};
