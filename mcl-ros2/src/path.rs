//! Field paths into messages: `data`, `pose.position.x`, `ranges[3]` (and
//! `[1]` into an array value); what
//! type a path names in a message type ([`kind_at`]), and the value it
//! names in a decoded message ([`get`]).

use crate::idl::{Array, BaseType, Registry};
use serde_json::Value;

/// One step of a path.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Step {
    Field(String),
    Index(usize),
}

/// The steps of `path`, or why it is not a path.
pub fn parse(path: &str) -> Result<Vec<Step>, String> {
    let mut steps = Vec::new();
    for (k, part) in path.split('.').enumerate() {
        let (name, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        // A path may start with an index (`[1]`, into an array value).
        let leading_index = k == 0 && name.is_empty() && !rest.is_empty();
        if !leading_index {
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(format!("`{path}` is not a field path (`a.b`, `a[2].b`)"));
            }
            steps.push(Step::Field(name.to_string()));
        }
        while !rest.is_empty() {
            let close = rest.find(']').ok_or_else(|| format!("`{path}`: expected `]`"))?;
            let n: usize =
                rest[1..close].parse().map_err(|_| format!("`{path}`: `{}` is not an index", &rest[1..close]))?;
            steps.push(Step::Index(n));
            rest = &rest[close + 1..];
            if !rest.is_empty() && !rest.starts_with('[') {
                return Err(format!("`{path}` is not a field path"));
            }
        }
    }
    Ok(steps)
}

/// What a path names, for checking the bridge file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Kind {
    Bool,
    /// Integers and floats.
    Number,
    String,
    /// A nested message (`pkg/msg/Name`).
    Message(String),
    /// An array or sequence.
    Array,
}

/// The kind of the field `path` names in the message `full`, or why none.
pub fn kind_at(reg: &Registry, full: &str, path: &str) -> Result<Kind, String> {
    let steps = parse(path)?;
    let mut owner = full.to_string();
    let mut cur: Option<(BaseType, Array)> = None;
    for step in steps {
        match step {
            Step::Field(name) => {
                if let Some((base, Array::No)) = &cur {
                    owner = reg.resolve(&owner, base).ok_or_else(|| format!("`{path}`: `{owner}` has no fields"))?;
                } else if cur.is_some() {
                    return Err(format!("`{path}`: an array has no field `{name}` (index it first)"));
                }
                let m = reg.message(&owner).ok_or_else(|| format!("unknown type `{owner}`"))?;
                let f = m.field(&name).ok_or_else(|| {
                    let known: Vec<&str> = m.fields.iter().map(|f| f.name.as_str()).collect();
                    format!("`{owner}` has no field `{name}` (its fields: {})", known.join(", "))
                })?;
                cur = Some((f.base.clone(), f.array));
            }
            Step::Index(i) => match &cur {
                Some((base, array)) if *array != Array::No => {
                    if let Array::Fixed(n) | Array::Bounded(n) = array {
                        if i >= *n {
                            return Err(format!("`{path}`: index {i} beyond the array's size {n}"));
                        }
                    }
                    cur = Some((base.clone(), Array::No));
                }
                _ => return Err(format!("`{path}`: only an array can be indexed")),
            },
        }
    }
    Ok(match cur {
        None => Kind::Message(owner),
        Some((_, a)) if a != Array::No => Kind::Array,
        Some((BaseType::Prim(p), _)) if p.is_bool() => Kind::Bool,
        Some((BaseType::Prim(_), _)) => Kind::Number,
        Some((BaseType::String(_) | BaseType::WString(_), _)) => Kind::String,
        Some((b @ BaseType::Named { .. }, _)) => Kind::Message(reg.resolve(&owner, &b).unwrap_or_default()),
    })
}

/// The value `path` names in `value`, if there is one.
pub fn get<'a>(value: &'a Value, path: &str) -> Option<&'a Value> {
    let mut cur = value;
    for step in parse(path).ok()? {
        cur = match step {
            Step::Field(n) => cur.get(n.as_str())?,
            Step::Index(i) => cur.get(i)?,
        };
    }
    Some(cur)
}

/// Sets `path` in `value` to `new`, creating objects on the way (not arrays).
pub fn set(value: &mut Value, path: &str, new: Value) -> Result<(), String> {
    let steps = parse(path)?;
    let mut cur = value;
    for step in steps {
        cur = match step {
            Step::Field(n) => {
                if !cur.is_object() {
                    *cur = Value::Object(serde_json::Map::new());
                }
                match cur {
                    Value::Object(o) => o.entry(n).or_insert(Value::Null),
                    _ => return Err(format!("`{path}`: not an object")),
                }
            }
            Step::Index(i) => cur.get_mut(i).ok_or_else(|| format!("`{path}`: no element {i}"))?,
        };
    }
    *cur = new;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn kinds_and_values_along_paths() {
        let r = Registry::bundled();
        assert_eq!(kind_at(&r, "geometry_msgs/msg/PoseStamped", "pose.position.x"), Ok(Kind::Number));
        assert_eq!(kind_at(&r, "std_msgs/msg/Bool", "data"), Ok(Kind::Bool));
        assert_eq!(kind_at(&r, "geometry_msgs/msg/PoseWithCovariance", "covariance[35]"), Ok(Kind::Number));
        assert!(kind_at(&r, "geometry_msgs/msg/PoseWithCovariance", "covariance[36]").is_err());
        let e = kind_at(&r, "std_msgs/msg/Bool", "value").unwrap_err();
        assert!(e.contains("no field `value`") && e.contains("data"), "{e}");
        assert!(parse("a..b").is_err());
        let v = json!({"pose": {"position": {"x": 1.5}}, "r": [1, 2]});
        assert_eq!(get(&v, "pose.position.x"), Some(&json!(1.5)));
        assert_eq!(get(&v, "r[1]"), Some(&json!(2)));
        assert_eq!(get(&v, "r[2]"), None);
        let mut w = json!({});
        set(&mut w, "target.position.x", json!(3)).unwrap();
        assert_eq!(w, json!({"target": {"position": {"x": 3}}}));
    }
}
