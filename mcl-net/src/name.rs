//! [`Name`]: the immutable, cheaply cloned string of node ids and names.

use std::borrow::Borrow;
use std::fmt;
use std::ops::Deref;
use std::sync::{Arc, OnceLock};

use serde::{Serialize, Serializer};

/// An immutable string shared by reference counting: node ids and names.
///
/// A compiled mission has hundreds of thousands of nodes, each with an id and
/// a name that is usually the same text. A `Name` is a range of a shared,
/// reference-counted text: cloning it counts a reference, and a generator can
/// write the ids of many nodes into one [`SharedText`] and cut names from it,
/// one allocation for hundreds of nodes. It reads like a `&str` (it
/// dereferences to `str`, compares with `str`, `&str` and `String`,
/// displays, hashes, orders and borrows as `str`), and converts from and
/// into `String`.
#[derive(Clone)]
pub struct Name {
    /// A thin pointer (16 bytes in all): a net holds two names per node.
    text: Arc<OnceLock<Box<str>>>,
    start: u32,
    end: u32,
}

impl Name {
    /// The text.
    #[inline]
    pub fn as_str(&self) -> &str {
        match self.text.get() {
            Some(t) => t.get(self.start as usize..self.end as usize).unwrap_or(""),
            None => "",
        }
    }

    fn whole(text: Box<str>) -> Name {
        let end = u32::try_from(text.len()).expect("a name is shorter than 4 GiB");
        Name { text: Arc::new(OnceLock::from(text)), start: 0, end }
    }
}

/// A text that names are cut from before it is written: a generator hands
/// out names ([`SharedText::name`]) while it writes their text into a buffer,
/// then sets the text once ([`SharedText::set`]). Until then, and if a range
/// does not fall on the text's character boundaries, those names read as
/// the empty string.
#[derive(Clone, Debug, Default)]
pub struct SharedText(Arc<OnceLock<Box<str>>>);

impl SharedText {
    /// A text not written yet.
    pub fn new() -> Self {
        SharedText::default()
    }

    /// The name `text[range]` of the text to come. Panics if the range ends
    /// at 4 GiB or more.
    pub fn name(&self, range: std::ops::Range<usize>) -> Name {
        let (Ok(start), Ok(end)) = (u32::try_from(range.start), u32::try_from(range.end)) else {
            panic!("SharedText::name: text too long")
        };
        Name { text: self.0.clone(), start, end }
    }

    /// Writes the text; false if it was already written.
    pub fn set(&self, text: &str) -> bool {
        self.0.set(Box::from(text)).is_ok()
    }
}

impl Default for Name {
    /// The empty name (shared: no allocation).
    fn default() -> Self {
        static EMPTY: OnceLock<Arc<OnceLock<Box<str>>>> = OnceLock::new();
        Name { text: EMPTY.get_or_init(|| Arc::new(OnceLock::from(Box::from("")))).clone(), start: 0, end: 0 }
    }
}

impl PartialEq for Name {
    #[inline]
    fn eq(&self, other: &Name) -> bool {
        self.as_str() == other.as_str()
    }
}

impl Eq for Name {}

impl PartialOrd for Name {
    fn partial_cmp(&self, other: &Name) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Name {
    fn cmp(&self, other: &Name) -> std::cmp::Ordering {
        self.as_str().cmp(other.as_str())
    }
}

impl std::hash::Hash for Name {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.as_str().hash(state)
    }
}

impl Deref for Name {
    type Target = str;
    #[inline]
    fn deref(&self) -> &str {
        self.as_str()
    }
}

impl AsRef<str> for Name {
    #[inline]
    fn as_ref(&self) -> &str {
        self.as_str()
    }
}

impl Borrow<str> for Name {
    #[inline]
    fn borrow(&self) -> &str {
        self.as_str()
    }
}

impl fmt::Display for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self.as_str(), f)
    }
}

impl fmt::Debug for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl From<&str> for Name {
    #[inline]
    fn from(s: &str) -> Self {
        Name::whole(Box::from(s))
    }
}

impl From<&String> for Name {
    #[inline]
    fn from(s: &String) -> Self {
        Name::whole(Box::from(s.as_str()))
    }
}

impl From<String> for Name {
    #[inline]
    fn from(s: String) -> Self {
        Name::whole(Box::from(s))
    }
}

impl From<&Name> for Name {
    #[inline]
    fn from(s: &Name) -> Self {
        s.clone()
    }
}

impl From<Name> for String {
    fn from(n: Name) -> Self {
        n.as_str().to_string()
    }
}

impl From<&Name> for String {
    fn from(n: &Name) -> Self {
        n.as_str().to_string()
    }
}

impl PartialEq<str> for Name {
    #[inline]
    fn eq(&self, other: &str) -> bool {
        self.as_str() == other
    }
}

impl PartialEq<&str> for Name {
    #[inline]
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

impl PartialEq<String> for Name {
    #[inline]
    fn eq(&self, other: &String) -> bool {
        self.as_str() == other.as_str()
    }
}

impl PartialEq<Name> for str {
    #[inline]
    fn eq(&self, other: &Name) -> bool {
        self == other.as_str()
    }
}

impl PartialEq<Name> for &str {
    #[inline]
    fn eq(&self, other: &Name) -> bool {
        *self == other.as_str()
    }
}

impl PartialEq<Name> for String {
    #[inline]
    fn eq(&self, other: &Name) -> bool {
        self.as_str() == other.as_str()
    }
}

impl Serialize for Name {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::mutable_key_type)] // the text is written before the names are used as keys
    fn reads_like_a_str() {
        let n = Name::from("call1.start");
        let m = n.clone();
        assert_eq!(n, "call1.start");
        assert_eq!(n, m);
        assert_eq!("call1.start", n);
        assert_eq!(n, "call1.start".to_string());
        assert!(n.starts_with("call1."));
        assert_eq!(n.as_str(), "call1.start");
        assert_eq!(format!("{n}|{n:?}"), "call1.start|\"call1.start\"");
        assert_eq!(String::from(n.clone()), "call1.start");
        let mut set = std::collections::HashSet::new();
        set.insert(n);
        assert!(set.contains("call1.start"));
        assert_eq!(Name::default(), "");
        let text = SharedText::new();
        let a = text.name(0..8);
        let b = text.name(8..18);
        assert_eq!(a, "");
        assert!(text.set("m.0.p_runcall1.run"));
        assert!(!text.set("again"));
        assert_eq!((a.as_str(), b.as_str()), ("m.0.p_ru", "ncall1.run"));
        assert_eq!(b, Name::from("ncall1.run"));
        let c = SharedText::new();
        let d = c.name(1..12);
        c.set("xcall1.start");
        assert!(set.contains(&*d));
    }
}
