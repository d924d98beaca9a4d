//! The text of `.msg`, `.srv` and `.action` files (the ROS 2 interface
//! language): one field or constant per line, `#` comments, `---` between
//! the parts of a service or an action.

use super::{Action, Array, BaseType, Constant, Field, Message, Prim, Service};
use serde_json::Value;

/// Longest array bound or fixed size accepted (a bigger one is refused, not allocated).
pub const MAX_BOUND: usize = 1 << 24;

/// A definition that cannot be read, with its line (1-based).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    pub line: usize,
    pub message: String,
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

impl std::error::Error for ParseError {}

/// A message definition of package `package`.
pub fn parse_msg(package: &str, text: &str) -> Result<Message, ParseError> {
    let lines: Vec<(usize, &str)> = text.lines().enumerate().map(|(i, l)| (i + 1, l)).collect();
    parse_part(package, &lines)
}

/// A service definition: request `---` response.
pub fn parse_srv(package: &str, text: &str) -> Result<Service, ParseError> {
    let parts = split(text, 2)?;
    Ok(Service { request: parse_part(package, &parts[0])?, response: parse_part(package, &parts[1])? })
}

/// An action definition: goal `---` result `---` feedback.
pub fn parse_action(package: &str, text: &str) -> Result<Action, ParseError> {
    let parts = split(text, 3)?;
    Ok(Action {
        goal: parse_part(package, &parts[0])?,
        result: parse_part(package, &parts[1])?,
        feedback: parse_part(package, &parts[2])?,
    })
}

type Lines<'a> = Vec<(usize, &'a str)>;

fn split(text: &str, n: usize) -> Result<Vec<Lines<'_>>, ParseError> {
    let mut parts: Vec<Lines<'_>> = vec![Vec::new()];
    let mut last = 0;
    for (i, l) in text.lines().enumerate() {
        last = i + 1;
        if strip_comment(l).trim() == "---" {
            parts.push(Vec::new());
        } else if let Some(p) = parts.last_mut() {
            p.push((i + 1, l));
        }
    }
    if parts.len() != n {
        return Err(ParseError {
            line: last.max(1),
            message: format!(
                "expected {} `---` separator{}, found {}",
                n - 1,
                if n == 2 { "" } else { "s" },
                parts.len() - 1
            ),
        });
    }
    Ok(parts)
}

/// The line without its `#` comment (a `#` inside quotes is kept).
fn strip_comment(line: &str) -> &str {
    let mut quote: Option<char> = None;
    for (i, c) in line.char_indices() {
        match (quote, c) {
            (None, '#') => return &line[..i],
            (None, '"' | '\'') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            _ => {}
        }
    }
    line
}

fn parse_part(package: &str, lines: &[(usize, &str)]) -> Result<Message, ParseError> {
    let mut m = Message::default();
    for &(line, raw) in lines {
        let text = strip_comment(raw).trim();
        if text.is_empty() {
            continue;
        }
        let err = |message: String| ParseError { line, message };
        let (ty, rest) =
            text.split_once(char::is_whitespace).ok_or_else(|| err(format!("`{text}`: expected a type and a name")))?;
        let rest = rest.trim_start();
        let (base, array) = parse_type(package, ty).map_err(err)?;
        // A constant: `TYPE NAME=VALUE` (spaces around `=` allowed).
        let (name_part, value_part, is_constant) = match rest.split_once('=') {
            Some((n, v)) if !n.trim().contains(char::is_whitespace) => (n.trim(), Some(v.trim()), true),
            _ => match rest.split_once(char::is_whitespace) {
                Some((n, d)) => (n, Some(d.trim()).filter(|d| !d.is_empty()), false),
                None => (rest, None, false),
            },
        };
        if m.fields.iter().any(|f| f.name == name_part) || m.constants.iter().any(|c| c.name == name_part) {
            return Err(err(format!("`{name_part}` is defined twice")));
        }
        if is_constant {
            if !valid_name(name_part, true) {
                return Err(err(format!("`{name_part}`: a constant's name is upper case letters, digits and `_`")));
            }
            if array != Array::No || matches!(base, BaseType::Named { .. }) {
                return Err(err(format!("constant `{name_part}`: only scalars and strings can be constants")));
            }
            let value = parse_value(&base, Array::No, value_part.unwrap_or("")).map_err(err)?;
            m.constants.push(Constant { name: name_part.to_string(), base, value });
        } else {
            if !valid_name(name_part, false) {
                return Err(err(format!(
                    "`{name_part}`: a field's name is lower case letters, digits and `_`, starting with a letter"
                )));
            }
            let default = match value_part {
                Some(v) => {
                    if matches!(base, BaseType::Named { .. }) {
                        return Err(err(format!("field `{name_part}`: a nested message has no default value")));
                    }
                    Some(parse_value(&base, array, v).map_err(err)?)
                }
                None => None,
            };
            m.fields.push(Field { name: name_part.to_string(), base, array, default, line });
        }
    }
    Ok(m)
}

fn valid_name(name: &str, constant: bool) -> bool {
    let mut chars = name.chars();
    let first_ok = chars.next().is_some_and(|c| if constant { c.is_ascii_uppercase() } else { c.is_ascii_lowercase() });
    first_ok
        && name.chars().all(|c| {
            c == '_' || c.is_ascii_digit() || if constant { c.is_ascii_uppercase() } else { c.is_ascii_lowercase() }
        })
}

/// `T`, `T[N]`, `T[]`, `T[<=N]` with `T` a scalar, `string<=N`, `Name`,
/// `pkg/Name` or `pkg/msg/Name`.
pub fn parse_type(package: &str, ty: &str) -> Result<(BaseType, Array), String> {
    let (elem, array) = match ty.find('[') {
        Some(i) => {
            let inner = ty[i + 1..].strip_suffix(']').ok_or_else(|| format!("`{ty}`: expected `]`"))?;
            let array = if inner.is_empty() {
                Array::Unbounded
            } else if let Some(n) = inner.strip_prefix("<=") {
                Array::Bounded(bound(ty, n)?)
            } else {
                Array::Fixed(bound(ty, inner)?)
            };
            (&ty[..i], array)
        }
        None => (ty, Array::No),
    };
    let base = if let Some(n) = elem.strip_prefix("string<=") {
        BaseType::String(Some(bound(ty, n)?))
    } else if let Some(n) = elem.strip_prefix("wstring<=") {
        BaseType::WString(Some(bound(ty, n)?))
    } else if elem == "string" {
        BaseType::String(None)
    } else if elem == "wstring" {
        BaseType::WString(None)
    } else if let Some(p) = Prim::from_name(elem) {
        BaseType::Prim(p)
    } else if elem == "time" || elem == "duration" {
        // ROS 1 names, still accepted by ROS 2's parser.
        let name = if elem == "time" { "Time" } else { "Duration" };
        BaseType::Named { package: "builtin_interfaces".into(), name: name.into() }
    } else {
        let parts: Vec<&str> = elem.split('/').collect();
        let (pkg, name) = match parts.as_slice() {
            [name] if *name == "Header" => ("std_msgs", *name),
            [name] => (package, *name),
            [pkg, name] | [pkg, "msg", name] => (*pkg, *name),
            _ => return Err(format!("`{elem}` is not a type")),
        };
        let ok_ident = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !ok_ident(pkg) || !ok_ident(name) || !name.starts_with(|c: char| c.is_ascii_uppercase()) {
            return Err(format!("`{elem}` is not a type (a message type's name starts with a capital letter)"));
        }
        BaseType::Named { package: pkg.into(), name: name.into() }
    };
    Ok((base, array))
}

fn bound(ty: &str, n: &str) -> Result<usize, String> {
    match n.trim().parse::<usize>() {
        Ok(v) if v <= MAX_BOUND => Ok(v),
        Ok(_) => Err(format!("`{ty}`: bound over {MAX_BOUND}")),
        Err(_) => Err(format!("`{ty}`: `{n}` is not a size")),
    }
}

/// A default or constant value written in a definition, as JSON.
pub fn parse_value(base: &BaseType, array: Array, text: &str) -> Result<Value, String> {
    if array != Array::No {
        let inner = text
            .trim()
            .strip_prefix('[')
            .and_then(|t| t.strip_suffix(']'))
            .ok_or_else(|| format!("`{text}`: an array's value is written `[a, b, ...]`"))?;
        if inner.trim().is_empty() {
            return Ok(Value::Array(Vec::new()));
        }
        let items: Result<Vec<Value>, String> = inner.split(',').map(|t| parse_value(base, Array::No, t)).collect();
        let items = items?;
        let fits = match array {
            Array::Fixed(n) => items.len() == n,
            Array::Bounded(n) => items.len() <= n,
            _ => true,
        };
        if !fits {
            return Err(format!("`{text}`: {} elements do not fit the array", items.len()));
        }
        return Ok(Value::Array(items));
    }
    let t = text.trim();
    match base {
        BaseType::Prim(Prim::Bool) => match t {
            "true" | "True" | "1" => Ok(Value::Bool(true)),
            "false" | "False" | "0" => Ok(Value::Bool(false)),
            _ => Err(format!("`{t}` is not a bool")),
        },
        BaseType::Prim(p) if p.is_float() => t
            .parse::<f64>()
            .ok()
            .and_then(serde_json::Number::from_f64)
            .map(Value::Number)
            .ok_or_else(|| format!("`{t}` is not a number")),
        BaseType::Prim(p) => {
            let v: i128 = t.parse().map_err(|_| format!("`{t}` is not an integer"))?;
            let (lo, hi) = p.int_range().unwrap_or((0, 0));
            if v < lo || v > hi {
                return Err(format!("`{t}` is out of range"));
            }
            Ok(if v < 0 { Value::from(v as i64) } else { Value::from(v as u64) })
        }
        BaseType::String(bound) | BaseType::WString(bound) => {
            let s = if t.len() >= 2
                && (t.starts_with('"') && t.ends_with('"') || t.starts_with('\'') && t.ends_with('\''))
            {
                &t[1..t.len() - 1]
            } else {
                t
            };
            if bound.is_some_and(|b| s.chars().count() > b) {
                return Err(format!("`{t}` is longer than the string's bound"));
            }
            Ok(Value::String(s.to_string()))
        }
        BaseType::Named { .. } => Err("a nested message has no value".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_arrays_bounds_constants_defaults() {
        let m = parse_msg(
            "demo",
            "# a comment\nint8 LOW=-1 # low\nstring NAME = \"x#y\"\nbool flag true\nstring<=5 short\nfloat64[3] v [1.0, 2, 3]\nuint8[] data\nint32[<=4] few\nHeader header\ngeometry_msgs/Point p\nOther o\n",
        )
        .unwrap();
        assert_eq!(m.constants.len(), 2);
        assert_eq!(m.constants[0].value, Value::from(-1));
        assert_eq!(m.constants[1].value, Value::from("x#y"));
        let names: Vec<&str> = m.fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["flag", "short", "v", "data", "few", "header", "p", "o"]);
        assert_eq!(m.fields[0].default, Some(Value::Bool(true)));
        assert_eq!(m.fields[1].base, BaseType::String(Some(5)));
        assert_eq!(m.fields[2].array, Array::Fixed(3));
        assert_eq!(m.fields[3].array, Array::Unbounded);
        assert_eq!(m.fields[4].array, Array::Bounded(4));
        assert_eq!(m.fields[5].base.full_name().unwrap(), "std_msgs/msg/Header");
        assert_eq!(m.fields[6].base.full_name().unwrap(), "geometry_msgs/msg/Point");
        assert_eq!(m.fields[7].base.full_name().unwrap(), "demo/msg/Other");
        assert_eq!(m.fields[7].line, 11);
    }

    #[test]
    fn services_and_actions_split_at_dashes() {
        let s = parse_srv("std_srvs", "bool data\n---\nbool success\nstring message\n").unwrap();
        assert_eq!(s.request.fields.len(), 1);
        assert_eq!(s.response.fields.len(), 2);
        let a = parse_action("x", "float64 d\n---\n---\nfloat64 left\n").unwrap();
        assert!(a.result.fields.is_empty());
        assert_eq!(a.feedback.fields[0].name, "left");
        let e = parse_srv("x", "bool a\n").unwrap_err();
        assert!(e.message.contains("separator"), "{e}");
    }

    #[test]
    fn errors_have_their_line() {
        let e = parse_msg("x", "bool ok\nfloat65 bad\n").unwrap_err();
        assert_eq!(e.line, 2);
        let e = parse_msg("x", "bool ok\nbool ok\n").unwrap_err();
        assert!(e.message.contains("twice"));
        let e = parse_msg("x", "uint8 X=300\n").unwrap_err();
        assert!(e.message.contains("range"));
        let e = parse_msg("x", "int32[99999999999] a\n").unwrap_err();
        assert!(e.message.contains("bound") || e.message.contains("size"), "{e}");
        assert!(parse_msg("x", "bool Bad\n").is_err());
        assert!(parse_msg("x", "justone\n").is_err());
    }
}
