//! An action's parameters in the order the action declares them
//! ([`Params`]): written as a JSON object whose keys keep that order in the
//! AAC protocol, the trace, the live log and the mock, and read back in the
//! order they arrive.
//!
//! serde_json's `Map` sorts its keys (its `preserve_order` feature would
//! change the order of every JSON object of the workspace), hence this type.

use std::fmt;

use serde::de::{MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::Value;

/// Parameter values by name, in declaration order. A name appears once:
/// [`Params::insert`] replaces the value of a name already there, in place.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params(Vec<(String, Value)>);

static NULL: Value = Value::Null;

impl Params {
    /// No parameters.
    pub fn new() -> Self {
        Params(Vec::new())
    }

    /// The value of `name`.
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.0.iter().find(|(k, _)| k == name).map(|(_, v)| v)
    }

    /// Whether `name` has a value.
    pub fn contains_key(&self, name: &str) -> bool {
        self.get(name).is_some()
    }

    /// Sets `name` to `value`: in place when `name` is there (its old value
    /// is returned), else last.
    pub fn insert(&mut self, name: impl Into<String>, value: Value) -> Option<Value> {
        let name = name.into();
        match self.0.iter_mut().find(|(k, _)| *k == name) {
            Some((_, v)) => Some(std::mem::replace(v, value)),
            None => {
                self.0.push((name, value));
                None
            }
        }
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The parameters in order.
    pub fn iter(&self) -> impl Iterator<Item = (&String, &Value)> {
        self.0.iter().map(|(k, v)| (k, v))
    }

    /// The names in order.
    pub fn keys(&self) -> impl Iterator<Item = &String> {
        self.0.iter().map(|(k, _)| k)
    }

    /// The parameters as a JSON object (serde_json's `Map` sorts the keys).
    pub fn to_json_map(&self) -> serde_json::Map<String, Value> {
        self.0.iter().cloned().collect()
    }
}

/// `params["name"]`: the value, or `null` when there is none.
impl std::ops::Index<&str> for Params {
    type Output = Value;
    fn index(&self, name: &str) -> &Value {
        self.get(name).unwrap_or(&NULL)
    }
}

/// Later values of a repeated name replace earlier ones, in place.
impl<K: Into<String>> FromIterator<(K, Value)> for Params {
    fn from_iter<I: IntoIterator<Item = (K, Value)>>(iter: I) -> Self {
        let mut p = Params::new();
        for (k, v) in iter {
            p.insert(k, v);
        }
        p
    }
}

impl From<serde_json::Map<String, Value>> for Params {
    fn from(m: serde_json::Map<String, Value>) -> Self {
        m.into_iter().collect()
    }
}

impl IntoIterator for Params {
    type Item = (String, Value);
    type IntoIter = std::vec::IntoIter<(String, Value)>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

impl<'a> IntoIterator for &'a Params {
    type Item = (&'a String, &'a Value);
    type IntoIter = std::iter::Map<std::slice::Iter<'a, (String, Value)>, fn(&'a (String, Value)) -> Self::Item>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter().map(|(k, v)| (k, v))
    }
}

impl Serialize for Params {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for Params {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Params;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a JSON object of parameters")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut a: A) -> Result<Params, A::Error> {
                let mut p = Params::new();
                while let Some((k, v)) = a.next_entry::<String, Value>()? {
                    p.insert(k, v);
                }
                Ok(p)
            }
        }
        d.deserialize_map(V)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_declaration_order_through_json() {
        let p: Params = [("z", Value::from(1)), ("a", Value::from("x")), ("m", Value::Null)].into_iter().collect();
        let text = serde_json::to_string(&p).unwrap();
        assert_eq!(text, r#"{"z":1,"a":"x","m":null}"#);
        let back: Params = serde_json::from_str(&text).unwrap();
        assert_eq!(back, p);
        assert_eq!(back.keys().map(String::as_str).collect::<Vec<_>>(), ["z", "a", "m"]);
    }

    #[test]
    fn lookup_and_replace_in_place() {
        let mut p = Params::new();
        assert!(p.insert("b", 1.into()).is_none());
        p.insert("a", 2.into());
        assert_eq!(p.insert("b", 3.into()), Some(1.into()));
        assert_eq!((p.len(), p["b"].as_i64(), p["a"].as_i64()), (2, Some(3), Some(2)));
        assert_eq!((p.get("c"), &p["c"]), (None, &Value::Null));
        assert_eq!(p.keys().map(String::as_str).collect::<Vec<_>>(), ["b", "a"]);
        assert!(serde_json::from_str::<Params>("[1]").is_err());
    }
}
