//! Dynamic CDR: a JSON value encoded and decoded against a message type of
//! a [`Registry`], the way ROS 2's middlewares put it on the wire: XCDR1
//! (plain CDR) with the 4-byte encapsulation header (`00 01 00 00`, little
//! endian; big endian `00 00` is read too), each scalar aligned to its size
//! counted from the end of the header, strings as a `u32` length that
//! counts a final NUL, sequences as a `u32` count, fixed arrays bare, and a
//! message without fields as one octet (rosidl's
//! `structure_needs_at_least_one_member`).
//!
//! Values: `bool` as JSON booleans, integers as JSON integers (also `byte`
//! and `char`, 0..=255), floats as numbers (a NaN or infinity decodes as
//! `null`, and `null` encodes as NaN), strings as strings, `wstring` as
//! UTF-16 code units of two octets, arrays as arrays, messages as objects.
//! Encoding fills a field the value lacks with its default (from the
//! definition, else zero, empty, or the nested message's defaults); a
//! field the type lacks, a wrong type, or a number out of range is an
//! error. Decoding never panics and never allocates more than the bytes
//! it was given can hold.

use crate::idl::{Array, BaseType, Field, Prim, Registry};
use serde_json::{Map, Number, Value};

/// Nesting deeper than this is refused (the registry also refuses cycles).
pub const MAX_DEPTH: usize = 64;

/// The encapsulation header of little-endian plain CDR.
pub const HEADER_LE: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Why a value cannot be encoded or bytes cannot be decoded; `path` is
/// the field (`pose.position.x`, `data[3]`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CdrError {
    pub path: String,
    pub message: String,
}

impl std::fmt::Display for CdrError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.path.is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "`{}`: {}", self.path, self.message)
        }
    }
}

impl std::error::Error for CdrError {}

fn error(path: &str, message: impl Into<String>) -> CdrError {
    CdrError { path: path.to_string(), message: message.into() }
}

fn join(path: &str, name: &str) -> String {
    if path.is_empty() {
        name.to_string()
    } else {
        format!("{path}.{name}")
    }
}

/// `value` as the message `full` (`pkg/msg/Name`), header included.
pub fn encode(reg: &Registry, full: &str, value: &Value) -> Result<Vec<u8>, CdrError> {
    let mut w = Writer { buf: HEADER_LE.to_vec(), base: 4, offset: 0 };
    w.message(reg, full, value, "", 0)?;
    Ok(w.buf)
}

/// The body of `value` as the message `full` (little endian, no header),
/// aligned as if it started `offset` octets into the stream: a message
/// nested in another one that is encoded elsewhere (an action's result
/// after its `int8 status` starts at offset 1).
pub fn encode_body(reg: &Registry, full: &str, value: &Value, offset: usize) -> Result<Vec<u8>, CdrError> {
    let mut w = Writer { buf: Vec::new(), base: 0, offset };
    w.message(reg, full, value, "", 0)?;
    Ok(w.buf)
}

/// The message `full` read from a little-endian body without header that
/// starts `offset` octets into its stream (see [`encode_body`]).
pub fn decode_body(reg: &Registry, full: &str, body: &[u8], offset: usize) -> Result<Value, CdrError> {
    let mut r = Reader { buf: body, pos: 0, little: true, offset };
    r.message(reg, full, "", 0)
}

/// The message `full` read from `bytes` (header included).
pub fn decode(reg: &Registry, full: &str, bytes: &[u8]) -> Result<Value, CdrError> {
    let (header, body) = bytes.split_at_checked(4).ok_or_else(|| error("", "shorter than the CDR header"))?;
    let little = match (header[0], header[1]) {
        (0x00, 0x01) => true,
        (0x00, 0x00) => false,
        (a, b) => return Err(error("", format!("encapsulation {a:02x} {b:02x} is not plain CDR"))),
    };
    let mut r = Reader { buf: body, pos: 0, little, offset: 0 };
    r.message(reg, full, "", 0)
}

/// The value a field takes when nothing gives it one.
pub fn default_of(reg: &Registry, owner: &str, f: &Field) -> Value {
    if let Some(d) = &f.default {
        return d.clone();
    }
    let one = || default_base(reg, owner, &f.base, 0);
    match f.array {
        Array::Fixed(n) => Value::Array((0..n.min(crate::idl::parse::MAX_BOUND)).map(|_| one()).collect()),
        Array::Unbounded | Array::Bounded(_) => Value::Array(Vec::new()),
        Array::No => one(),
    }
}

fn default_base(reg: &Registry, owner: &str, base: &BaseType, depth: usize) -> Value {
    match base {
        BaseType::Prim(Prim::Bool) => Value::Bool(false),
        BaseType::Prim(p) if p.is_float() => Value::from(0.0),
        BaseType::Prim(_) => Value::from(0),
        BaseType::String(_) | BaseType::WString(_) => Value::String(String::new()),
        BaseType::Named { .. } => {
            let Some(full) = reg.resolve(owner, base) else { return Value::Null };
            let Some(m) = reg.message(&full) else { return Value::Null };
            if depth > MAX_DEPTH {
                return Value::Null;
            }
            let mut map = Map::new();
            for f in &m.fields {
                let v = match (&f.default, f.array) {
                    (Some(d), _) => d.clone(),
                    (None, Array::No) => default_base(reg, &full, &f.base, depth + 1),
                    _ => default_of(reg, &full, f),
                };
                map.insert(f.name.clone(), v);
            }
            Value::Object(map)
        }
    }
}

struct Writer {
    buf: Vec<u8>,
    /// Octets of `buf` before the stream (the header).
    base: usize,
    /// Where `buf`'s stream starts in the whole stream.
    offset: usize,
}

impl Writer {
    fn align(&mut self, n: usize) {
        while !(self.buf.len() - self.base + self.offset).is_multiple_of(n) {
            self.buf.push(0);
        }
    }

    fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    fn message(&mut self, reg: &Registry, full: &str, value: &Value, path: &str, depth: usize) -> Result<(), CdrError> {
        if depth > MAX_DEPTH {
            return Err(error(path, "nested too deep"));
        }
        let m = reg.message(full).ok_or_else(|| error(path, format!("unknown type `{full}`")))?;
        let empty = Map::new();
        let obj = match value {
            Value::Object(o) => o,
            Value::Null => &empty,
            _ => return Err(error(path, format!("expected an object for `{full}`"))),
        };
        if let Some(k) = obj.keys().find(|k| m.field(k).is_none()) {
            return Err(error(&join(path, k), format!("`{full}` has no such field")));
        }
        if m.fields.is_empty() {
            self.buf.push(0);
            return Ok(());
        }
        for f in &m.fields {
            let p = join(path, &f.name);
            let v = match obj.get(&f.name) {
                Some(v) => v.clone(),
                None => default_of(reg, full, f),
            };
            self.field(reg, full, f, &v, &p, depth)?;
        }
        Ok(())
    }

    fn field(
        &mut self,
        reg: &Registry,
        owner: &str,
        f: &Field,
        v: &Value,
        path: &str,
        depth: usize,
    ) -> Result<(), CdrError> {
        if f.array == Array::No {
            return self.base(reg, owner, &f.base, v, path, depth);
        }
        let items = v.as_array().ok_or_else(|| error(path, "expected an array"))?;
        match f.array {
            Array::Fixed(n) if items.len() != n => {
                return Err(error(path, format!("expected {n} elements, found {}", items.len())))
            }
            Array::Bounded(n) if items.len() > n => {
                return Err(error(path, format!("at most {n} elements, found {}", items.len())))
            }
            Array::Fixed(_) => {}
            _ => self.u32(u32::try_from(items.len()).map_err(|_| error(path, "too many elements"))?),
        }
        for (i, item) in items.iter().enumerate() {
            self.base(reg, owner, &f.base, item, &format!("{path}[{i}]"), depth)?;
        }
        Ok(())
    }

    fn base(
        &mut self,
        reg: &Registry,
        owner: &str,
        base: &BaseType,
        v: &Value,
        path: &str,
        depth: usize,
    ) -> Result<(), CdrError> {
        match base {
            BaseType::Prim(p) => self.prim(*p, v, path),
            BaseType::String(bound) => {
                let s = v.as_str().ok_or_else(|| error(path, "expected a string"))?;
                if bound.is_some_and(|b| s.chars().count() > b) {
                    return Err(error(path, format!("longer than its bound {}", bound.unwrap_or(0))));
                }
                if s.contains('\0') {
                    return Err(error(path, "a string cannot hold NUL"));
                }
                self.u32(u32::try_from(s.len() + 1).map_err(|_| error(path, "string too long"))?);
                self.buf.extend_from_slice(s.as_bytes());
                self.buf.push(0);
                Ok(())
            }
            BaseType::WString(bound) => {
                let s = v.as_str().ok_or_else(|| error(path, "expected a string"))?;
                let units: Vec<u16> = s.encode_utf16().collect();
                if bound.is_some_and(|b| units.len() > b) {
                    return Err(error(path, format!("longer than its bound {}", bound.unwrap_or(0))));
                }
                self.u32(u32::try_from(units.len()).map_err(|_| error(path, "string too long"))?);
                for u in units {
                    self.buf.extend_from_slice(&u.to_le_bytes());
                }
                Ok(())
            }
            BaseType::Named { .. } => {
                let full = reg
                    .resolve(owner, base)
                    .ok_or_else(|| error(path, format!("unknown type `{}`", base.full_name().unwrap_or_default())))?;
                self.message(reg, &full, v, path, depth + 1)
            }
        }
    }

    fn prim(&mut self, p: Prim, v: &Value, path: &str) -> Result<(), CdrError> {
        self.align(p.size());
        if p.is_bool() {
            let b = v.as_bool().ok_or_else(|| error(path, "expected a boolean"))?;
            self.buf.push(u8::from(b));
            return Ok(());
        }
        if p.is_float() {
            let x = match v {
                Value::Null => f64::NAN,
                _ => v.as_f64().ok_or_else(|| error(path, "expected a number"))?,
            };
            match p {
                Prim::Float32 => self.buf.extend_from_slice(&(x as f32).to_le_bytes()),
                _ => self.buf.extend_from_slice(&x.to_le_bytes()),
            }
            return Ok(());
        }
        let n: i128 = match (v.as_i64(), v.as_u64()) {
            (Some(i), _) => i as i128,
            (None, Some(u)) => u as i128,
            _ => return Err(error(path, "expected an integer")),
        };
        let (lo, hi) = p.int_range().unwrap_or((0, 0));
        if n < lo || n > hi {
            return Err(error(path, format!("{n} is out of range")));
        }
        let bytes = (n as u64).to_le_bytes();
        self.buf.extend_from_slice(&bytes[..p.size()]);
        Ok(())
    }
}

struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    little: bool,
    /// Where `buf` starts in the whole stream.
    offset: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize, path: &str) -> Result<&[u8], CdrError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|e| *e <= self.buf.len())
            .ok_or_else(|| error(path, "message ends early"))?;
        let s = &self.buf[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn align(&mut self, n: usize, path: &str) -> Result<(), CdrError> {
        let pad = (n - (self.pos + self.offset) % n) % n;
        self.take(pad, path).map(|_| ())
    }

    fn scalar(&mut self, n: usize, path: &str) -> Result<u64, CdrError> {
        self.align(n, path)?;
        let little = self.little;
        let s = self.take(n, path)?;
        let mut b = [0u8; 8];
        if little {
            b[..n].copy_from_slice(s);
            Ok(u64::from_le_bytes(b))
        } else {
            b[8 - n..].copy_from_slice(s);
            Ok(u64::from_be_bytes(b))
        }
    }

    fn remaining(&self) -> usize {
        self.buf.len().saturating_sub(self.pos)
    }

    fn message(&mut self, reg: &Registry, full: &str, path: &str, depth: usize) -> Result<Value, CdrError> {
        if depth > MAX_DEPTH {
            return Err(error(path, "nested too deep"));
        }
        let m = reg.message(full).ok_or_else(|| error(path, format!("unknown type `{full}`")))?;
        if m.fields.is_empty() {
            self.take(1, path)?;
            return Ok(Value::Object(Map::new()));
        }
        let mut map = Map::new();
        for f in &m.fields {
            let p = join(path, &f.name);
            let v = self.field(reg, full, f, &p, depth)?;
            map.insert(f.name.clone(), v);
        }
        Ok(Value::Object(map))
    }

    fn field(&mut self, reg: &Registry, owner: &str, f: &Field, path: &str, depth: usize) -> Result<Value, CdrError> {
        let n = match f.array {
            Array::No => return self.base(reg, owner, &f.base, path, depth),
            Array::Fixed(n) => n,
            Array::Unbounded | Array::Bounded(_) => {
                let n = self.scalar(4, path)? as usize;
                if let Array::Bounded(b) = f.array {
                    if n > b {
                        return Err(error(path, format!("{n} elements over the bound {b}")));
                    }
                }
                n
            }
        };
        // Every element takes at least one octet: a count beyond what is
        // left is refused before anything is allocated.
        if n > self.remaining() {
            return Err(error(path, format!("{n} elements but {} octets left", self.remaining())));
        }
        let mut items = Vec::with_capacity(n);
        for i in 0..n {
            items.push(self.base(reg, owner, &f.base, &format!("{path}[{i}]"), depth)?);
        }
        Ok(Value::Array(items))
    }

    fn base(
        &mut self,
        reg: &Registry,
        owner: &str,
        base: &BaseType,
        path: &str,
        depth: usize,
    ) -> Result<Value, CdrError> {
        match base {
            BaseType::Prim(p) => self.prim(*p, path),
            BaseType::String(bound) => {
                let n = self.scalar(4, path)? as usize;
                let bytes = self.take(n, path)?;
                let bytes = bytes.strip_suffix(&[0]).unwrap_or(bytes);
                let s = std::str::from_utf8(bytes).map_err(|_| error(path, "a string that is not UTF-8"))?;
                if bound.is_some_and(|b| s.chars().count() > b) {
                    return Err(error(path, "a string over its bound"));
                }
                Ok(Value::String(s.to_string()))
            }
            BaseType::WString(bound) => {
                let n = self.scalar(4, path)? as usize;
                if n.saturating_mul(2) > self.remaining() {
                    return Err(error(path, "message ends early"));
                }
                let mut units = Vec::with_capacity(n);
                for _ in 0..n {
                    units.push(self.scalar(2, path)? as u16);
                }
                let s = String::from_utf16(&units).map_err(|_| error(path, "a wide string that is not UTF-16"))?;
                if bound.is_some_and(|b| n > b) {
                    return Err(error(path, "a string over its bound"));
                }
                Ok(Value::String(s))
            }
            BaseType::Named { .. } => {
                let full = reg
                    .resolve(owner, base)
                    .ok_or_else(|| error(path, format!("unknown type `{}`", base.full_name().unwrap_or_default())))?;
                self.message(reg, &full, path, depth + 1)
            }
        }
    }

    fn prim(&mut self, p: Prim, path: &str) -> Result<Value, CdrError> {
        let raw = self.scalar(p.size(), path)?;
        Ok(match p {
            Prim::Bool => match raw {
                0 => Value::Bool(false),
                1 => Value::Bool(true),
                _ => return Err(error(path, format!("{raw} is not a boolean"))),
            },
            Prim::Float32 => Number::from_f64(f32::from_bits(raw as u32) as f64).map_or(Value::Null, Value::Number),
            Prim::Float64 => Number::from_f64(f64::from_bits(raw)).map_or(Value::Null, Value::Number),
            Prim::Int8 => Value::from(raw as u8 as i8),
            Prim::Int16 => Value::from(raw as u16 as i16),
            Prim::Int32 => Value::from(raw as u32 as i32),
            Prim::Int64 => Value::from(raw as i64),
            _ => Value::from(raw),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn bool_and_string_match_the_bytes_ros2_sends() {
        let r = Registry::bundled();
        assert_eq!(encode(&r, "std_msgs/msg/Bool", &json!({"data": true})).unwrap(), [0, 1, 0, 0, 1]);
        assert_eq!(
            encode(&r, "std_msgs/msg/String", &json!({"data": "hi"})).unwrap(),
            [0, 1, 0, 0, 3, 0, 0, 0, b'h', b'i', 0]
        );
        // Empty message: one octet.
        assert_eq!(encode(&r, "std_msgs/msg/Empty", &json!({})).unwrap(), [0, 1, 0, 0, 0]);
        assert_eq!(decode(&r, "std_srvs/srv/Trigger_Request", &[0, 1, 0, 0, 0]).unwrap(), json!({}));
    }

    #[test]
    fn alignment_counts_from_the_end_of_the_header() {
        let r = Registry::bundled();
        // Header: Time{int32 sec, uint32 nanosec}, then a string.
        let v = json!({"stamp": {"sec": 1, "nanosec": 2}, "frame_id": "a"});
        let b = encode(&r, "std_msgs/msg/Header", &v).unwrap();
        assert_eq!(b, [0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, b'a', 0]);
        // SetBool response: bool, then the string length aligned to 4.
        let b = encode(&r, "std_srvs/srv/SetBool_Response", &json!({"success": true, "message": ""})).unwrap();
        assert_eq!(b, [0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0]);
        assert_eq!(decode(&r, "std_srvs/srv/SetBool_Response", &b).unwrap(), json!({"success": true, "message": ""}));
        // float64 after a bool is aligned to 8.
        let mut r2 = Registry::bundled();
        r2.add("t", crate::idl::bundled::Kind::Msg, "A", "bool b\nfloat64 x\n").unwrap();
        let b = encode(&r2, "t/msg/A", &json!({"b": true, "x": 1.5})).unwrap();
        assert_eq!(b.len(), 4 + 16);
        assert_eq!(&b[12..], &1.5f64.to_le_bytes());
    }

    #[test]
    fn defaults_fill_missing_fields_and_mistakes_are_errors() {
        let r = Registry::bundled();
        let b = encode(&r, "geometry_msgs/msg/Pose", &json!({"position": {"x": 2.0}})).unwrap();
        let v = decode(&r, "geometry_msgs/msg/Pose", &b).unwrap();
        assert_eq!(v["orientation"]["w"], json!(1.0));
        assert_eq!(v["position"], json!({"x": 2.0, "y": 0.0, "z": 0.0}));
        let e = encode(&r, "std_msgs/msg/Bool", &json!({"dat": true})).unwrap_err();
        assert_eq!(e.path, "dat");
        let e = encode(&r, "std_msgs/msg/UInt8", &json!({"data": 256})).unwrap_err();
        assert!(e.message.contains("range"));
        let e = encode(&r, "geometry_msgs/msg/PoseWithCovariance", &json!({"covariance": [1.0]})).unwrap_err();
        assert!(e.message.contains("36"), "{e}");
        assert!(encode(&r, "no/msg/Such", &json!({})).is_err());
    }

    #[test]
    fn big_endian_is_read_and_hostile_lengths_are_refused() {
        let r = Registry::bundled();
        let v = decode(&r, "std_msgs/msg/Int32", &[0, 0, 0, 0, 0, 0, 0, 7]).unwrap();
        assert_eq!(v, json!({"data": 7}));
        let e = decode(&r, "std_msgs/msg/Float64MultiArray", &[0, 1, 0, 0, 255, 255, 255, 255]).unwrap_err();
        assert!(e.message.contains("elements"), "{e}");
        assert!(decode(&r, "std_msgs/msg/String", &[0, 1, 0, 0, 9, 0, 0, 0, b'x']).is_err());
        assert!(decode(&r, "std_msgs/msg/Bool", &[0, 1, 0, 0, 2]).is_err());
        assert!(decode(&r, "std_msgs/msg/Bool", &[0, 1]).is_err());
        assert!(decode(&r, "std_msgs/msg/Bool", &[7, 7, 0, 0, 1]).is_err());
    }
}
