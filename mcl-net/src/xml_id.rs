//! Node ids as valid XML ids in PNML.
//!
//! PNML declares node ids as `xsd:ID`, an XML *NCName*: a letter or `_`
//! first, then letters, digits, `.`, `-` or `_`. MCL names may also hold `$`
//! and `/` (and a net read from another tool may hold anything), so the
//! writer encodes every other character as `_xHHHH_` (its code point in
//! hexadecimal: four digits, or six beyond U+FFFF), as .NET's
//! `XmlConvert.EncodeName` does, and the reader decodes them: ids are the
//! same after a round trip. A literal `_` followed by `x` is itself encoded
//! (`_x005F_`), so that every `_x` of the output starts an escape. Ids that
//! are already valid and hold no `_x` are written unchanged (all the
//! compiler's own ids, and every MCL name made of letters, digits, `_` and
//! `-` without `_x`).

use std::borrow::Cow;

/// The length of an escape `_xHHHH_` / `_xHHHHHH_` at the start of `s`, if any.
fn escape_len(s: &str) -> Option<(usize, u32)> {
    let b = s.as_bytes();
    if b.len() < 7 || b[0] != b'_' || b[1] != b'x' {
        return None;
    }
    for digits in [4usize, 6] {
        if b.len() >= digits + 3 && b[2..2 + digits].iter().all(u8::is_ascii_hexdigit) && b[2 + digits] == b'_' {
            let v = u32::from_str_radix(&s[2..2 + digits], 16).ok()?;
            return Some((digits + 3, v));
        }
    }
    None
}

fn valid_char(c: char, first: bool) -> bool {
    c.is_ascii_alphabetic() || c == '_' || (!first && (c.is_ascii_digit() || c == '.' || c == '-'))
}

/// `id` as a valid XML NCName (unchanged when it already is one).
pub fn encode(id: &str) -> Cow<'_, str> {
    // A literal `_` is kept only when no `x` follows it, so that the output
    // has no `_x` but the escapes' own.
    let keep = |i: usize, c: char| valid_char(c, i == 0) && !(c == '_' && id[i + 1..].starts_with('x'));
    if !id.is_empty() && id.char_indices().all(|(i, c)| keep(i, c)) {
        return Cow::Borrowed(id);
    }
    let mut out = String::with_capacity(id.len() + 8);
    for (i, c) in id.char_indices() {
        if keep(i, c) {
            out.push(c);
        } else if (c as u32) <= 0xFFFF {
            out.push_str(&format!("_x{:04X}_", c as u32));
        } else {
            out.push_str(&format!("_x{:06X}_", c as u32));
        }
    }
    Cow::Owned(out)
}

/// The id that [`encode`] wrote as `xml` (escapes that do not denote a
/// character are kept as they are).
pub fn decode(xml: &str) -> Cow<'_, str> {
    if !xml.contains("_x") {
        return Cow::Borrowed(xml);
    }
    let mut out = String::with_capacity(xml.len());
    let mut i = 0;
    while i < xml.len() {
        let rest = &xml[i..];
        if let Some((len, v)) = escape_len(rest) {
            if let Some(c) = char::from_u32(v) {
                out.push(c);
                i += len;
                continue;
            }
        }
        let c = rest.chars().next().expect("i is on a char boundary");
        out.push(c);
        i += c.len_utf8();
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_ncname(s: &str) -> bool {
        s.char_indices().all(|(i, c)| valid_char(c, i == 0)) && !s.is_empty()
    }

    #[test]
    fn plain_ids_are_unchanged() {
        for id in ["task.Goto.begin.1", "call12.start", "lock.Goto", "mission.ok", "way-point", "_a"] {
            assert_eq!(encode(id), id);
            assert_eq!(decode(id), id);
        }
    }

    #[test]
    fn round_trips_and_is_valid() {
        for id in [
            "task.Go$to.begin.1",
            "auv/mutex0",
            "1abc",
            "-x",
            ".x",
            "_x0041_",
            "a_x0024_b",
            "é",
            "space here",
            "🦀",
            "_x12",
            "_xFFFF_",
            "_x003C",
            "_x003C&",
            "&&x003C__&",
            "net\té&&x003C__&",
        ] {
            let e = encode(id);
            assert!(is_ncname(&e), "{id:?} encoded as {e:?}");
            assert_eq!(decode(&e), id, "{id:?} encoded as {e:?}");
        }
    }

    #[test]
    fn random_round_trip() {
        let alphabet: Vec<char> = "aZ09_x-./$: é🦀F&<".chars().collect();
        let mut seed = 0x2545F4914F6CDD1Du64;
        for _ in 0..5_000 {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            let n = 1 + (seed % 12) as usize;
            let id: String = (0..n).map(|k| alphabet[((seed >> (k * 4)) as usize + k) % alphabet.len()]).collect();
            let e = encode(&id);
            assert!(is_ncname(&e), "{id:?} encoded as {e:?}");
            assert_eq!(decode(&e), id);
        }
    }
}
