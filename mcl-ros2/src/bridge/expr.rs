//! The mapping language of a bridge file.
//!
//! A **field value** (what a published message, a service request or an
//! action goal holds) is a TOML boolean or number (a constant), a string
//! (a constant; `$$` at the start is a literal `$`), or a string starting
//! with `$`: an MCL parameter of the command, optionally a path into it and
//! a unit scaling, `"$depth"`, `"$way-point[0]"`, `"$target.x"`, `"$depth * 0.01"`,
//! `"$heading + 90"`.
//!
//! A **condition** (when a message raises an event) compares a field of the
//! message with a constant: `data == true`, `range < 2.5`,
//! `status.code != 0`, `message == "done"`; the operators are `==`, `!=`,
//! `<`, `<=`, `>`, `>=`. A bare field path (`data`) means `data == true`.

use serde_json::Value;

/// Where a field's value comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// A constant.
    Const(Value),
    /// An MCL parameter, a path into its value, then `value * scale + offset`.
    Param { name: String, path: Option<String>, scale: f64, offset: f64 },
}

impl Source {
    /// Reads a field value of the bridge file.
    pub fn parse(v: &toml::Value) -> Result<Source, String> {
        match v {
            toml::Value::Boolean(b) => Ok(Source::Const(Value::Bool(*b))),
            toml::Value::Integer(i) => Ok(Source::Const(Value::from(*i))),
            toml::Value::Float(f) => serde_json::Number::from_f64(*f)
                .map(|n| Source::Const(Value::Number(n)))
                .ok_or_else(|| format!("{f} is not a finite number")),
            toml::Value::String(s) if s.starts_with("$$") => Ok(Source::Const(Value::String(s[1..].to_string()))),
            toml::Value::String(s) if s.starts_with('$') => parse_param(&s[1..]),
            toml::Value::String(s) => Ok(Source::Const(Value::String(s.clone()))),
            toml::Value::Array(items) => {
                let consts: Result<Vec<Value>, String> = items
                    .iter()
                    .map(|i| match Source::parse(i)? {
                        Source::Const(c) => Ok(c),
                        Source::Param { .. } => Err("an array holds constants only".to_string()),
                    })
                    .collect();
                Ok(Source::Const(Value::Array(consts?)))
            }
            _ => Err("a field's value is a boolean, a number, a string or `$parameter`".into()),
        }
    }

    /// The value for a command whose parameters are `params`; `Err` names
    /// what is missing or not a number.
    pub fn eval(&self, params: &serde_json::Map<String, Value>) -> Result<Value, String> {
        match self {
            Source::Const(c) => Ok(c.clone()),
            Source::Param { name, path, scale, offset } => {
                let base = params.get(name).ok_or_else(|| format!("the command has no parameter `{name}`"))?;
                let v = match path {
                    Some(p) => crate::path::get(base, p).ok_or_else(|| format!("`{name}` has no `{p}`"))?,
                    None => base,
                };
                if *scale == 1.0 && *offset == 0.0 {
                    return Ok(v.clone());
                }
                let x = v.as_f64().ok_or_else(|| format!("`${name}` is not a number: {v}"))?;
                serde_json::Number::from_f64(x * scale + offset)
                    .map(Value::Number)
                    .ok_or_else(|| format!("`${name}` scaled is not finite"))
            }
        }
    }
}

fn parse_param(text: &str) -> Result<Source, String> {
    let bad = || format!("`${text}`: expected `$name`, `$name.path`, `$name * k` or `$name + k`");
    let (head, op) = match text.find(['*', '+']).or_else(|| text.find(" -")) {
        Some(i) => (text[..i].trim(), Some(text[i..].trim())),
        None => (text.trim(), None),
    };
    // MCL parameter names may hold `-` (`way-point`); the path starts at the first `.`.
    let (name, path) = match head.find(['.', '[']) {
        Some(i) if head[i..].starts_with('.') => (&head[..i], Some(head[i + 1..].to_string())),
        Some(i) => (&head[..i], Some(head[i..].to_string())),
        None => (head, None),
    };
    if name.is_empty() || !name.chars().all(|c| c.is_alphanumeric() || c == '_' || c == '-') {
        return Err(bad());
    }
    if let Some(p) = &path {
        crate::path::parse(p)?;
    }
    let (mut scale, mut offset) = (1.0, 0.0);
    if let Some(op) = op {
        let num = |s: &str| s.trim().parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(bad);
        match op.split_at(1) {
            ("*", k) => scale = num(k)?,
            ("+", k) => offset = num(k)?,
            ("-", k) => offset = -num(k)?,
            _ => return Err(bad()),
        }
    }
    Ok(Source::Param { name: name.to_string(), path, scale, offset })
}

/// A comparison operator of a condition.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
}

/// `field OP constant`.
#[derive(Clone, Debug, PartialEq)]
pub struct Condition {
    pub field: String,
    pub op: Op,
    pub value: Value,
}

impl Condition {
    /// Reads a condition (see the module's documentation).
    pub fn parse(text: &str) -> Result<Condition, String> {
        let ops = [("==", Op::Eq), ("!=", Op::Ne), ("<=", Op::Le), (">=", Op::Ge), ("<", Op::Lt), (">", Op::Gt)];
        let found = ops
            .iter()
            .filter_map(|(s, op)| text.find(s).map(|i| (i, *s, *op)))
            .min_by_key(|(i, s, _)| (*i, usize::MAX - s.len()));
        let (field, op, value) = match found {
            Some((i, s, op)) => (text[..i].trim(), op, text[i + s.len()..].trim()),
            None => (text.trim(), Op::Eq, "true"),
        };
        crate::path::parse(field).map_err(|e| format!("condition `{text}`: {e}"))?;
        let value = match value {
            "true" => Value::Bool(true),
            "false" => Value::Bool(false),
            v if v.len() >= 2 && v.starts_with('"') && v.ends_with('"') => Value::String(v[1..v.len() - 1].to_string()),
            v => v
                .parse::<f64>()
                .ok()
                .and_then(serde_json::Number::from_f64)
                .map(Value::Number)
                .ok_or_else(|| format!("condition `{text}`: `{v}` is not true, false, a number or a \"string\""))?,
        };
        if matches!(value, Value::Bool(_) | Value::String(_)) && !matches!(op, Op::Eq | Op::Ne) {
            return Err(format!("condition `{text}`: only numbers are ordered"));
        }
        Ok(Condition { field: field.to_string(), op, value })
    }

    /// Whether `msg` meets the condition (a missing field or another type does not).
    pub fn holds(&self, msg: &Value) -> bool {
        let Some(v) = crate::path::get(msg, &self.field) else { return false };
        match (v, &self.value) {
            (Value::Number(a), Value::Number(b)) => {
                let (Some(a), Some(b)) = (a.as_f64(), b.as_f64()) else { return false };
                match self.op {
                    Op::Eq => a == b,
                    Op::Ne => a != b,
                    Op::Lt => a < b,
                    Op::Le => a <= b,
                    Op::Gt => a > b,
                    Op::Ge => a >= b,
                }
            }
            (a, b) if std::mem::discriminant(a) == std::mem::discriminant(b) => match self.op {
                Op::Eq => a == b,
                Op::Ne => a != b,
                _ => false,
            },
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn field_values_constants_params_and_scaling() {
        let p = json!({"depth": 250, "way-point": {"x": 3.0}}).as_object().unwrap().clone();
        let s = Source::parse(&toml::Value::String("$depth * 0.01".into())).unwrap();
        assert_eq!(s.eval(&p).unwrap(), json!(2.5));
        let s = Source::parse(&toml::Value::String("$way-point.x".into())).unwrap();
        assert_eq!(s.eval(&p).unwrap(), json!(3.0));
        let q = json!({"way-point": [24, 12]}).as_object().unwrap().clone();
        let s = Source::parse(&toml::Value::String("$way-point[1] * 2".into())).unwrap();
        assert_eq!(s.eval(&q).unwrap(), json!(24.0));
        let s = Source::parse(&toml::Value::String("$depth - 50".into())).unwrap();
        assert_eq!(s.eval(&p).unwrap(), json!(200.0));
        assert_eq!(Source::parse(&toml::Value::String("$$5".into())).unwrap(), Source::Const(json!("$5")));
        assert!(Source::parse(&toml::Value::String("$depth / 2".into())).is_err());
        let s = Source::parse(&toml::Value::String("$speed".into())).unwrap();
        assert!(s.eval(&p).unwrap_err().contains("speed"));
    }

    #[test]
    fn conditions_compare_fields() {
        let c = Condition::parse("data == true").unwrap();
        assert!(c.holds(&json!({"data": true})) && !c.holds(&json!({"data": false})));
        assert_eq!(Condition::parse("data").unwrap(), c);
        let c = Condition::parse("range <= 2.5").unwrap();
        assert_eq!(c.op, Op::Le);
        assert!(c.holds(&json!({"range": 2})) && !c.holds(&json!({"range": 3.1})) && !c.holds(&json!({})));
        assert!(Condition::parse("message == \"done\"").unwrap().holds(&json!({"message": "done"})));
        assert!(Condition::parse("data < true").is_err());
        assert!(Condition::parse("a..b == 1").is_err());
        assert!(Condition::parse("x == maybe").is_err());
    }
}
