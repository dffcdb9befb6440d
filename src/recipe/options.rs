//! Reading option maps (`#{ length: 3.0, ... }`) into validated Rust values.
//!
//! Every value is checked where it is read, and an error names the option by its full path
//! and shows the value given. Options that nobody asked for are reported with the nearest
//! known name, so a typo never passes silently.

use rhai::{Dynamic, Map};

pub type OptResult<T> = Result<T, String>;

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
            "{name} = {value} ({}) must be a number",
            value.type_name()
        ));
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!("{name} = {x} is not a finite number"))
    }
}

pub fn positive(value: &Dynamic, name: &str, unit: &str) -> OptResult<f64> {
    let x = number(value, name)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(format!("{name} = {x} must be positive ({unit})"))
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

    fn path(&self, key: &str) -> String {
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
            .map_err(|_| format!("{path} = {v} must be a whole number"))?;
        if (min..=max).contains(&i) {
            Ok(i)
        } else {
            Err(format!("{path} = {i} must be between {min} and {max}"))
        }
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
                .map_err(|_| format!("{path} = {v} must be true or false"))
        })
    }

    /// A range `[lo, hi]` (lo ≤ hi), or a single number meaning `[x, x]`.
    pub fn range(&mut self, key: &'static str, default: [f64; 2]) -> OptResult<[f64; 2]> {
        let path = self.path(key);
        let Some(v) = self.take(key) else {
            return Ok(default);
        };
        let r = if let Some(arr) = v.clone().try_cast::<rhai::Array>() {
            match arr.as_slice() {
                [lo, hi] => [number(lo, &path)?, number(hi, &path)?],
                _ => {
                    return Err(format!(
                        "{path} = {v} must be a number or a range [low, high]"
                    ));
                }
            }
        } else {
            let x = number(&v, &path)?;
            [x, x]
        };
        if r[0] <= r[1] {
            Ok(r)
        } else {
            Err(format!(
                "{path} = [{}, {}]: the low end exceeds the high end",
                r[0], r[1]
            ))
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
            "unknown option `{}`{hint} (known: {})",
            self.path(key),
            known.join(", ")
        ))
    }
}

pub fn colour(v: &Dynamic, path: &str) -> OptResult<[f64; 3]> {
    let arr = v.clone().try_cast::<rhai::Array>().filter(|a| a.len() == 3);
    let Some(arr) = arr else {
        return Err(format!(
            "{path} = {v} must be [red, green, blue] with components in 0..1"
        ));
    };
    let mut c = [0.0; 3];
    for (slot, x) in c.iter_mut().zip(&arr) {
        *slot = number(x, path)?;
        if !(0.0..=1.0).contains(slot) {
            return Err(format!("{path} = {v}: colour components must lie in 0..1"));
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
    }
}
