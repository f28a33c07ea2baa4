//! JSON that refuses a key given twice in one object.
//!
//! `serde_json` keeps the last value of a repeated key without a word; a recorded trace line or
//! an adapter's answer with `{"t_us":1,"t_us":2}` is ambiguous, so both are refused (issue 15).

use std::fmt;

use serde::de::{self, DeserializeSeed, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Value};

/// Parses JSON text into a [`Value`], refusing any object with a key given twice.
///
/// # Errors
///
/// Not JSON, or a duplicate key (the message names it: "duplicate key `t_us`").
pub fn from_slice(text: &[u8]) -> Result<Value, serde_json::Error> {
    let mut de = serde_json::Deserializer::from_slice(text);
    let v = Unique.deserialize(&mut de)?;
    de.end()?;
    Ok(v)
}

/// [`from_slice`] of a string.
///
/// # Errors
///
/// As [`from_slice`].
pub fn from_str(text: &str) -> Result<Value, serde_json::Error> {
    from_slice(text.as_bytes())
}

/// Whether a `serde_json` error is a duplicate key found by [`from_slice`].
pub fn is_duplicate(e: &serde_json::Error) -> bool {
    e.to_string().starts_with("duplicate key `")
}

/// The message of a `serde_json` error without its " at line L column C" (said elsewhere).
pub fn message(e: &serde_json::Error) -> String {
    let s = e.to_string();
    match s.rfind(" at line ") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}

struct Unique;

impl<'de> DeserializeSeed<'de> for Unique {
    type Value = Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        d.deserialize_any(UniqueVisitor)
    }
}

struct UniqueVisitor;

impl<'de> Visitor<'de> for UniqueVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        Ok(serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number))
    }
    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        Unique.deserialize(d)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut out = Vec::new();
        while let Some(v) = seq.next_element_seed(Unique)? {
            out.push(v);
        }
        Ok(Value::Array(out))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                let shown: String =
                    key.chars().take(60).map(|c| if c.is_control() { '?' } else { c }).collect();
                return Err(de::Error::custom(format!("duplicate key `{shown}`")));
            }
            let v = map.next_value_seed(Unique)?;
            out.insert(key, v);
        }
        Ok(Value::Object(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn duplicate_keys_are_refused_at_any_depth() {
        assert!(from_str(r#"{"t_us":1,"kind":"sample"}"#).is_ok());
        let e = from_str(r#"{"t_us":1,"t_us":2}"#).unwrap_err();
        assert!(is_duplicate(&e), "{e}");
        assert!(e.to_string().contains("duplicate key `t_us`"), "{e}");
        assert!(from_str(r#"{"axes":{"X":1,"X":2}}"#).is_err());
        assert!(from_str(r#"[{"a":1},{"a":1}]"#).is_ok());
        assert_eq!(from_str("1.5").unwrap(), serde_json::json!(1.5));
        assert!(from_str("{} x").is_err());
    }
}
