//! Reading option maps (`#{ length: 3.0, ... }`) into validated Rust values.
//!
//! Every value is checked where it is read, and an error names the option by its full path
//! and shows the value given. Options that nobody asked for are reported with the nearest
//! known name, so a typo never passes silently.

use crate::words::{clip, number as number_shown};
use rhai::{Dynamic, Map};

pub type OptResult<T> = Result<T, String>;

/// How the message about an unknown option begins; the option's full path follows, up to a
/// backtick (`unknown_option_path` reads it back, to point at the key in the source).
const UNKNOWN_OPTION: &str = "unknown option `";

/// The path of the option that `message` says is unknown, if it says so.
pub fn unknown_option_path(message: &str) -> Option<&str> {
    let rest = &message[message.find(UNKNOWN_OPTION)? + UNKNOWN_OPTION.len()..];
    rest.split_once('`').map(|(path, _)| path)
}

pub struct Options {
    map: Map,
    context: String,
    known: Vec<&'static str>,
}

/// A number from a Rhai value (integers are accepted wherever floats are).
pub fn number(value: &Dynamic, name: &str) -> OptResult<f64> {
    let x = if let Ok(f) = value.as_float() {
        f
    } else if let Ok(i) = value.as_int() {
        i as f64
    } else {
        return Err(format!(
            "{name} = {} ({}) must be a number",
            shown(value),
            value.type_name()
        ));
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!(
            "{name} = {} is not a finite number",
            number_shown(x)
        ))
    }
}

/// Longest rendering of a script value in a message, characters.
const MAX_SHOWN_CHARS: usize = 80;

/// A script value as messages show it: as Rhai prints it (large and small floats in exponent
/// form), strings in quotes and the unit as `()` (so `"true"` is not mistaken for `true`, nor
/// a missing value for nothing), cut to a readable length.
pub fn shown(value: &Dynamic) -> String {
    let text = if value.is_string() {
        format!("\"{value}\"")
    } else if value.is_unit() {
        "()".to_string()
    } else {
        value.to_string()
    };
    clip(&text, MAX_SHOWN_CHARS).into_owned()
}

pub fn positive(value: &Dynamic, name: &str, unit: &str) -> OptResult<f64> {
    let x = number(value, name)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(format!(
            "{name} = {} must be positive ({unit})",
            number_shown(x)
        ))
    }
}

impl Options {
    pub fn new(map: Map, context: impl Into<String>) -> Self {
        Options {
            map,
            context: context.into(),
            known: Vec::new(),
        }
    }

    /// The same options under another name: a list item once its kind is known.
    pub fn renamed(self, context: impl Into<String>) -> Options {
        Options {
            context: context.into(),
            ..self
        }
    }

    /// The full name of option `key`, as messages show it.
    pub fn path(&self, key: &str) -> String {
        if self.context.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.context)
        }
    }

    /// Removes and returns an option, recording its name as known.
    pub fn take(&mut self, key: &'static str) -> Option<Dynamic> {
        self.known.push(key);
        self.map.remove(key)
    }

    pub fn required(&mut self, key: &'static str) -> OptResult<Dynamic> {
        let path = self.path(key);
        self.take(key)
            .ok_or_else(|| format!("missing option `{path}`"))
    }

    pub fn number(&mut self, key: &'static str, default: f64) -> OptResult<f64> {
        let path = self.path(key);
        self.take(key).map_or(Ok(default), |v| number(&v, &path))
    }

    pub fn positive(&mut self, key: &'static str, unit: &str) -> OptResult<f64> {
        let path = self.path(key);
        positive(&self.required(key)?, &path, unit)
    }

    /// An integer in [min, max].
    pub fn integer(
        &mut self,
        key: &'static str,
        default: i64,
        min: i64,
        max: i64,
    ) -> OptResult<i64> {
        let path = self.path(key);
        let Some(v) = self.take(key) else {
            return Ok(default);
        };
        let i = v
            .as_int()
            .map_err(|_| format!("{path} = {} must be a whole number", shown(&v)))?;
        if (min..=max).contains(&i) {
            Ok(i)
        } else {
            Err(format!("{path} = {i} must be between {min} and {max}"))
        }
    }

    /// A whole number in 0..=u64::MAX. Rhai integers stop at 2⁶³ − 1 and larger literals become
    /// floats, which are exact only up to 2⁵³; so beyond 2⁵³ a value is given as a string of
    /// digits, and a float is taken only when it is an exact integer no larger than 2⁵³.
    pub fn unsigned(&mut self, key: &'static str, default: u64) -> OptResult<u64> {
        let path = self.path(key);
        let Some(v) = self.take(key) else {
            return Ok(default);
        };
        const EXACT: f64 = (1u64 << f64::MANTISSA_DIGITS) as f64;
        let whole = if let Ok(i) = v.as_int() {
            u64::try_from(i).ok()
        } else if let Ok(f) = v.as_float() {
            if f.fract() != 0.0 || !f.is_finite() {
                None
            } else if f.abs() > EXACT {
                return Err(format!(
                    "{path} = {}: a number this large is not held exactly (Rhai integers stop at {}); write it as a string of digits, e.g. {key}: \"{}\"",
                    number_shown(f),
                    i64::MAX,
                    i64::MAX as u64 + 1
                ));
            } else {
                (f >= 0.0).then_some(f as u64)
            }
        } else if v.is_string() {
            v.to_string().trim().parse::<u64>().ok()
        } else {
            None
        };
        whole.ok_or_else(|| {
            format!(
                "{path} = {} must be a whole number from 0 to {} (a string of digits above {})",
                shown(&v),
                u64::MAX,
                i64::MAX
            )
        })
    }

    pub fn string(&mut self, key: &'static str, default: &str) -> OptResult<String> {
        let path = self.path(key);
        match self.take(key) {
            None => Ok(default.to_string()),
            Some(v) => v
                .into_immutable_string()
                .map(|s| s.to_string())
                .map_err(|t| format!("{path} must be a string, not {t}")),
        }
    }

    pub fn flag(&mut self, key: &'static str, default: bool) -> OptResult<bool> {
        let path = self.path(key);
        self.take(key).map_or(Ok(default), |v| {
            v.as_bool()
                .map_err(|_| format!("{path} = {} must be true or false", shown(&v)))
        })
    }

    /// A range `[lo, hi]` (lo ≤ hi), or a single number meaning `[x, x]`.
    pub fn range(&mut self, key: &'static str, default: [f64; 2]) -> OptResult<[f64; 2]> {
        let path = self.path(key);
        self.take(key)
            .map_or(Ok(default), |v| range(&v, &path).map(|(r, _)| r))
    }

    /// A required range: `[lo, hi]` (lo ≤ hi) or a single number, and whether it was written
    /// as one number.
    pub fn required_range(&mut self, key: &'static str) -> OptResult<([f64; 2], bool)> {
        let path = self.path(key);
        range(&self.required(key)?, &path)
    }

    /// A required number.
    pub fn required_number(&mut self, key: &'static str) -> OptResult<f64> {
        let path = self.path(key);
        number(&self.required(key)?, &path)
    }

    /// One of the words `choices` (`default` when left out); a typo gets the nearest word.
    pub fn choice(
        &mut self,
        key: &'static str,
        choices: &[&'static str],
        default: Option<&'static str>,
    ) -> OptResult<&'static str> {
        let path = self.path(key);
        let given = match (self.take(key), default) {
            (None, Some(word)) => return Ok(word),
            (None, None) => return Err(format!("missing option `{path}`")),
            (Some(v), _) => v,
        };
        let word = given
            .clone()
            .into_immutable_string()
            .map_err(|t| format!("{path} = {} ({t}) must be a string", shown(&given)))?;
        if let Some(&known) = choices.iter().find(|c| **c == word.as_str()) {
            return Ok(known);
        }
        let hint = crate::words::nearest(&word, choices)
            .map(|k| format!("; did you mean \"{k}\"?"))
            .unwrap_or_default();
        Err(format!(
            "{path} = \"{}\" is not one of {}{hint}",
            clip(&word, MAX_SHOWN_CHARS),
            choices
                .iter()
                .map(|c| format!("\"{c}\""))
                .collect::<Vec<_>>()
                .join(", ")
        ))
    }

    /// A point `[x, y, z]` (metres), if given.
    pub fn point(&mut self, key: &'static str) -> OptResult<Option<[f64; 3]>> {
        let path = self.path(key);
        let Some(v) = self.take(key) else {
            return Ok(None);
        };
        match v.clone().try_cast::<rhai::Array>().as_deref() {
            Some([x, y, z]) => Ok(Some([
                number(x, &path)?,
                number(y, &path)?,
                number(z, &path)?,
            ])),
            _ => Err(format!("{path} = {} must be a point [x, y, z]", shown(&v))),
        }
    }

    /// A colour `[r, g, b]`, sRGB components in [0, 1].
    pub fn colour(&mut self, key: &'static str, default: [f64; 3]) -> OptResult<[f64; 3]> {
        let path = self.path(key);
        self.take(key).map_or(Ok(default), |v| colour(&v, &path))
    }

    pub fn sub(&mut self, key: &'static str) -> OptResult<Option<Options>> {
        let path = self.path(key);
        match self.take(key) {
            None => Ok(None),
            Some(v) => match v.try_cast::<Map>() {
                Some(map) => Ok(Some(Options::new(map, path))),
                None => Err(format!("{path} must be a map like #{{ ... }}")),
            },
        }
    }

    /// Fails on any option that was never asked for.
    pub fn finish(self) -> OptResult<()> {
        let Some((key, _)) = self.map.iter().next() else {
            return Ok(());
        };
        let mut known = self.known.clone();
        known.sort_unstable();
        known.dedup();
        let hint = crate::words::nearest(key, &known)
            .map(|k| format!("; did you mean `{k}`?"))
            .unwrap_or_default();
        Err(format!(
            "{UNKNOWN_OPTION}{}`{hint} (known: {})",
            self.path(key),
            known.join(", ")
        ))
    }
}

/// A range `[lo, hi]` (lo ≤ hi) or a single number meaning `[x, x]`, and whether it was one
/// number.
fn range(v: &Dynamic, path: &str) -> OptResult<([f64; 2], bool)> {
    let (r, single) = if let Some(arr) = v.clone().try_cast::<rhai::Array>() {
        match arr.as_slice() {
            [lo, hi] => ([number(lo, path)?, number(hi, path)?], false),
            _ => {
                return Err(format!(
                    "{path} = {} must be a number or a range [low, high]",
                    shown(v)
                ));
            }
        }
    } else {
        let x = number(v, path)?;
        ([x, x], true)
    };
    if r[0] <= r[1] {
        Ok((r, single))
    } else {
        Err(format!(
            "{path} = [{}, {}]: the low end exceeds the high end",
            number_shown(r[0]),
            number_shown(r[1])
        ))
    }
}

pub fn colour(v: &Dynamic, path: &str) -> OptResult<[f64; 3]> {
    let arr = v.clone().try_cast::<rhai::Array>().filter(|a| a.len() == 3);
    let Some(arr) = arr else {
        return Err(format!(
            "{path} = {} must be [red, green, blue] with components in 0..1",
            shown(v)
        ));
    };
    let mut c = [0.0; 3];
    for (slot, x) in c.iter_mut().zip(&arr) {
        *slot = number(x, path)?;
        if !(0.0..=1.0).contains(slot) {
            return Err(format!(
                "{path} = {}: colour components must lie in 0..1",
                shown(v)
            ));
        }
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_and_bad_values_are_named() {
        let mut map = Map::new();
        map.insert("widht".into(), Dynamic::from(0.2));
        map.insert("height".into(), Dynamic::from(f64::NAN));
        let mut o = Options::new(map, "beam");
        assert_eq!(
            o.number("height", 1.0).unwrap_err(),
            "beam.height = NaN is not a finite number"
        );
        assert_eq!(o.number("width", 1.0), Ok(1.0));
        let e = o.finish().unwrap_err();
        assert!(
            e.starts_with("unknown option `beam.widht`; did you mean `width`?"),
            "{e}"
        );
        assert_eq!(unknown_option_path(&e), Some("beam.widht"));
        assert_eq!(unknown_option_path("beam.width = 0 must be positive"), None);
    }
}
