//! A small element tree over quick-xml, with byte offsets for error locations.

use quick_xml::escape::resolve_predefined_entity;
use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;
use quick_xml::XmlVersion;

use crate::pnml::PnmlError;

/// Deepest element nesting accepted (protects the stack and memory).
pub(crate) const MAX_DEPTH: usize = 256;

/// An XML element: local name, attributes, children and concatenated text.
#[derive(Debug, Default)]
pub(crate) struct Element {
    pub name: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<Element>,
    pub text: String,
    /// Byte offset of the `<` that opens the element.
    pub pos: usize,
}

impl Element {
    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

/// Line and column (1-based, column in characters) of a byte offset.
pub(crate) fn line_col(input: &str, pos: usize) -> (usize, usize) {
    let mut pos = pos.min(input.len());
    while !input.is_char_boundary(pos) {
        pos -= 1;
    }
    let before = &input[..pos];
    let line = before.bytes().filter(|&b| b == b'\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

fn local(name: &str) -> &str {
    match name.rfind(':') {
        Some(i) => &name[i + 1..],
        None => name,
    }
}

fn start_element(input: &str, e: &BytesStart<'_>, pos: usize) -> Result<Element, PnmlError> {
    let name = local(e.name().as_ref()).to_string();
    let mut attrs = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|err| PnmlError::at(input, pos, format!("bad attribute: {err}")))?;
        let key = local(a.key.as_ref()).to_string();
        let value = a
            .normalized_value(XmlVersion::Implicit1_0)
            .map_err(|err| PnmlError::at(input, pos, format!("bad attribute `{key}`: {err}")))?;
        attrs.push((key, value.into_owned()));
    }
    Ok(Element { name, attrs, children: Vec::new(), text: String::new(), pos })
}

/// Parses a whole document and returns its root element.
pub(crate) fn parse(input: &str) -> Result<Element, PnmlError> {
    let mut reader = Reader::from_str(input);
    reader.config_mut().check_end_names = true;
    let mut stack: Vec<Element> = Vec::new();
    let mut root: Option<Element> = None;
    loop {
        let pos = reader.buffer_position() as usize;
        let event = reader
            .read_event()
            .map_err(|err| PnmlError::at(input, reader.error_position() as usize, format!("malformed XML: {err}")))?;
        match event {
            Event::Start(e) | Event::Empty(e) if root.is_some() && stack.is_empty() => {
                let _ = e;
                return Err(PnmlError::at(input, pos, "more than one root element"));
            }
            Event::Start(e) => {
                if stack.len() >= MAX_DEPTH {
                    return Err(PnmlError::at(input, pos, format!("elements nested deeper than {MAX_DEPTH} levels")));
                }
                stack.push(start_element(input, &e, pos)?);
            }
            Event::Empty(e) => {
                let el = start_element(input, &e, pos)?;
                match stack.last_mut() {
                    Some(parent) => parent.children.push(el),
                    None => root = Some(el),
                }
            }
            Event::End(_) => {
                // check_end_names guarantees the end tag matches the open element.
                let Some(el) = stack.pop() else {
                    return Err(PnmlError::at(input, pos, "unexpected closing tag"));
                };
                match stack.last_mut() {
                    Some(parent) => parent.children.push(el),
                    None => root = Some(el),
                }
            }
            Event::Text(t) => {
                let content = t.xml10_content();
                match stack.last_mut() {
                    Some(el) => el.text.push_str(&content),
                    None if content.trim().is_empty() => {}
                    None => return Err(PnmlError::at(input, pos, "text outside the root element")),
                }
            }
            Event::CData(t) => match stack.last_mut() {
                Some(el) => el.text.push_str(&t.xml10_content()),
                None => return Err(PnmlError::at(input, pos, "CDATA outside the root element")),
            },
            Event::GeneralRef(r) => {
                let ch = r
                    .resolve_char_ref()
                    .map_err(|err| PnmlError::at(input, pos, format!("bad character reference: {err}")))?;
                let text: String = match ch {
                    Some(c) => c.to_string(),
                    None => match resolve_predefined_entity(&r) {
                        Some(s) => s.to_string(),
                        None => return Err(PnmlError::at(input, pos, format!("unknown entity `&{};`", &*r))),
                    },
                };
                match stack.last_mut() {
                    Some(el) => el.text.push_str(&text),
                    None => return Err(PnmlError::at(input, pos, "text outside the root element")),
                }
            }
            Event::Comment(_) | Event::Decl(_) | Event::PI(_) | Event::DocType(_) => {}
            Event::Eof => break,
        }
    }
    if let Some(open) = stack.last() {
        return Err(PnmlError::at(
            input,
            open.pos,
            format!("element `<{}>` is not closed before the end of the file", open.name),
        ));
    }
    root.ok_or_else(|| PnmlError::at(input, input.len(), "no root element"))
}

/// Escapes text content so that reading it back gives exactly `s`.
pub(crate) fn escape_text(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '\r' => out.push_str("&#13;"),
            _ => out.push(c),
        }
    }
    out
}

/// Escapes an attribute value so that reading it back (with attribute-value
/// normalization) gives exactly `s`.
pub(crate) fn escape_attr(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            _ => out.push(c),
        }
    }
    out
}

/// True for characters allowed in an XML 1.0 document.
pub(crate) fn is_xml_char(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r' | '\u{20}'..='\u{D7FF}' | '\u{E000}'..='\u{FFFD}' | '\u{10000}'..)
}
