//! The scene's values as the file and the builder hold them before they become a [`Scene`](super::Scene):
//! a number or an array of numbers (`beam.length`, `beam.mass`, `beam.stiffness`), and counts
//! as the file's integers.

use std::fmt;

use serde::de::{SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::SceneError;

/// A number, or an array of numbers (`length`, `mass`, `stiffness`).
#[derive(Clone, Debug, PartialEq)]
pub(super) enum NumOrArray {
    Number(f64),
    Array(Vec<f64>),
}

impl<'de> Deserialize<'de> for NumOrArray {
    // Hand-written rather than `#[serde(untagged)]`: a bad element of an array is then reported at
    // its own index, and a bad value says what the key takes.
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct NumOrArrayVisitor;
        impl<'de> Visitor<'de> for NumOrArrayVisitor {
            type Value = NumOrArray;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number or an array of numbers")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<NumOrArray, E> {
                Ok(NumOrArray::Number(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<NumOrArray, E> {
                Ok(NumOrArray::Number(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<NumOrArray, E> {
                Ok(NumOrArray::Number(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<NumOrArray, A::Error> {
                let mut values = Vec::new();
                while let Some(v) = seq.next_element::<f64>()? {
                    values.push(v);
                }
                Ok(NumOrArray::Array(values))
            }
        }
        deserializer.deserialize_any(NumOrArrayVisitor)
    }
}

impl Serialize for NumOrArray {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Number(x) => serializer.serialize_f64(*x),
            Self::Array(v) => serializer.collect_seq(v),
        }
    }
}

impl NumOrArray {
    /// A number if all values are bitwise equal (and there is at least one), else an array.
    pub(super) fn compact(values: &[f64]) -> Self {
        match values.first() {
            Some(first) if values.iter().all(|v| v.to_bits() == first.to_bits()) => {
                Self::Number(*first)
            }
            _ => Self::Array(values.to_vec()),
        }
    }

    /// `count` values: the number repeated, or the array if it has exactly `count` values.
    pub(super) fn expand(self, key: &str, count: usize) -> Result<Vec<f64>, SceneError> {
        match self {
            Self::Number(x) => Ok(vec![x; count]),
            Self::Array(v) if v.len() == count => Ok(v),
            Self::Array(v) => Err(SceneError::count(key, count, v.len())),
        }
    }
}

/// `control.values` as written: one number (every value equal), or the array of values.
pub(super) enum RawValues {
    /// One number: every value equal.
    One(f64),
    /// The values, each a number or a pair [u_x, u_z].
    Many(Vec<NumOrArray>),
}

impl Serialize for RawValues {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            RawValues::One(u) => s.serialize_f64(*u),
            RawValues::Many(v) => v.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for RawValues {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawValues;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number, an array of numbers or an array of pairs [u_x, u_z]")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<RawValues, E> {
                Ok(RawValues::One(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<RawValues, E> {
                Ok(RawValues::One(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<RawValues, E> {
                Ok(RawValues::One(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<RawValues, A::Error> {
                let mut out = Vec::new();
                while let Some(x) = seq.next_element::<NumOrArray>()? {
                    out.push(x);
                }
                Ok(RawValues::Many(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// A count as the file's integer (saturating at `i64::MAX`).
pub(super) fn to_i64(x: usize) -> i64 {
    i64::try_from(x).unwrap_or(i64::MAX)
}
