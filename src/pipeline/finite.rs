//! A last guard before a record is written: every number in it must be finite. serde_json
//! writes NaN and ±∞ as `null`, which no reader could tell from a missing value, so a record
//! holding one is refused with the path of the field instead.

use serde::ser::{self, Serialize};
use std::fmt;

/// Where in a record a non-finite number was found, e.g. `camera.K[0][0]`.
#[derive(Debug)]
pub struct NonFinite(pub String);

impl fmt::Display for NonFinite {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "the record's field {} is not a finite number", self.0)
    }
}

impl std::error::Error for NonFinite {}

impl ser::Error for NonFinite {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        NonFinite(msg.to_string())
    }
}

/// Checks every floating-point number `value` would serialise.
pub fn check_finite(value: &impl Serialize) -> Result<(), NonFinite> {
    value.serialize(Checker {
        path: String::new(),
    })
}

/// Walks a value as serde presents it, remembering the path to the current field.
struct Checker {
    path: String,
}

impl Checker {
    fn child(&self, step: impl fmt::Display) -> Checker {
        Checker {
            path: format!("{}{step}", self.path),
        }
    }

    fn field(&self, key: &str) -> Checker {
        if self.path.is_empty() {
            Checker {
                path: key.to_string(),
            }
        } else {
            self.child(format_args!(".{key}"))
        }
    }

    /// A container at this path, from its first element.
    fn walk(self) -> Walk {
        Walk { at: self, index: 0 }
    }

    fn number(&self, x: f64) -> Result<(), NonFinite> {
        if x.is_finite() {
            Ok(())
        } else {
            Err(NonFinite(format!("{} (= {x})", self.path)))
        }
    }
}

/// A container being walked: counts its elements for the path.
struct Walk {
    at: Checker,
    index: usize,
}

impl Walk {
    fn element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), NonFinite> {
        let child = self.at.child(format_args!("[{}]", self.index));
        self.index += 1;
        value.serialize(child)
    }
}

macro_rules! accept {
    ($($name:ident($($arg:ty),*)),* $(,)?) => {
        $(fn $name(self, $(_: $arg),*) -> Result<(), NonFinite> { Ok(()) })*
    };
}

impl ser::Serializer for Checker {
    type Ok = ();
    type Error = NonFinite;
    type SerializeSeq = Walk;
    type SerializeTuple = Walk;
    type SerializeTupleStruct = Walk;
    type SerializeTupleVariant = Walk;
    type SerializeMap = Walk;
    type SerializeStruct = Walk;
    type SerializeStructVariant = Walk;

    accept!(
        serialize_bool(bool),
        serialize_i8(i8),
        serialize_i16(i16),
        serialize_i32(i32),
        serialize_i64(i64),
        serialize_u8(u8),
        serialize_u16(u16),
        serialize_u32(u32),
        serialize_u64(u64),
        serialize_char(char),
        serialize_str(&str),
        serialize_bytes(&[u8]),
        serialize_none(),
        serialize_unit(),
        serialize_unit_struct(&'static str),
        serialize_unit_variant(&'static str, u32, &'static str),
    );

    fn serialize_f32(self, v: f32) -> Result<(), NonFinite> {
        self.number(f64::from(v))
    }

    fn serialize_f64(self, v: f64) -> Result<(), NonFinite> {
        self.number(v)
    }

    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<(), NonFinite> {
        value.serialize(self)
    }

    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        value: &T,
    ) -> Result<(), NonFinite> {
        value.serialize(self)
    }

    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<(), NonFinite> {
        value.serialize(self.field(variant))
    }

    fn serialize_seq(self, _: Option<usize>) -> Result<Walk, NonFinite> {
        Ok(self.walk())
    }

    fn serialize_tuple(self, _: usize) -> Result<Walk, NonFinite> {
        Ok(self.walk())
    }

    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Walk, NonFinite> {
        Ok(self.walk())
    }

    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<Walk, NonFinite> {
        Ok(self.field(variant).walk())
    }

    fn serialize_map(self, _: Option<usize>) -> Result<Walk, NonFinite> {
        Ok(self.walk())
    }

    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Walk, NonFinite> {
        Ok(self.walk())
    }

    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<Walk, NonFinite> {
        Ok(self.field(variant).walk())
    }
}

/// The containers whose elements are walked in order, by index.
macro_rules! elements {
    ($($trait:ident::$method:ident),* $(,)?) => {
        $(impl ser::$trait for Walk {
            type Ok = ();
            type Error = NonFinite;
            fn $method<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), NonFinite> {
                self.element(value)
            }
            fn end(self) -> Result<(), NonFinite> {
                Ok(())
            }
        })*
    };
}

elements!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field,
);

impl ser::SerializeMap for Walk {
    type Ok = ();
    type Error = NonFinite;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, _: &T) -> Result<(), NonFinite> {
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), NonFinite> {
        self.element(value)
    }
    fn end(self) -> Result<(), NonFinite> {
        Ok(())
    }
}

/// The containers whose fields are walked by name.
macro_rules! fields {
    ($($trait:ident),* $(,)?) => {
        $(impl ser::$trait for Walk {
            type Ok = ();
            type Error = NonFinite;
            fn serialize_field<T: Serialize + ?Sized>(
                &mut self,
                key: &'static str,
                value: &T,
            ) -> Result<(), NonFinite> {
                value.serialize(self.at.field(key))
            }
            fn end(self) -> Result<(), NonFinite> {
                Ok(())
            }
        })*
    };
}

fields!(SerializeStruct, SerializeStructVariant);

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;

    #[derive(Serialize)]
    struct Camera {
        k: [[f64; 3]; 3],
        distance: Option<f64>,
    }

    #[derive(Serialize)]
    struct Record {
        camera: Camera,
        loads: Vec<(u32, f64)>,
    }

    #[test]
    fn the_path_of_a_non_finite_number_is_named() {
        let mut r = Record {
            camera: Camera {
                k: [[800.0, 0.0, 480.0], [0.0, 800.0, 480.0], [0.0, 0.0, 1.0]],
                distance: None,
            },
            loads: vec![(1, 2.5)],
        };
        assert!(check_finite(&r).is_ok());
        r.camera.k[1][2] = f64::NAN;
        assert!(
            check_finite(&r)
                .unwrap_err()
                .0
                .starts_with("camera.k[1][2]")
        );
        r.camera.k[1][2] = 1.0;
        r.camera.distance = Some(f64::INFINITY);
        assert!(
            check_finite(&r)
                .unwrap_err()
                .0
                .starts_with("camera.distance")
        );
        r.camera.distance = None;
        r.loads[0].1 = f64::NEG_INFINITY;
        assert!(check_finite(&r).unwrap_err().0.starts_with("loads[0][1]"));
    }
}
