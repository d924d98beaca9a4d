//! PNML 2009 P/T nets, read and written with quick-xml.
//!
//! Reading accepts `http://www.pnml.org/version-2009/grammar/ptnet` nets with
//! one or more (possibly nested) pages, which are flattened. Names,
//! `initialMarking` and arc `inscription` are read from their `<text>`;
//! graphics and unknown labels are ignored, as are `<toolspecific>` blocks of
//! other tools (e.g. `tool="nupn"`). Reference nodes (`referencePlace`,
//! `referenceTransition`) are rejected.
//!
//! MCL data lives in `<toolspecific tool="mcl" version="1">` inside `net`,
//! `place` and `transition`. Provenance records are shared by many nodes
//! (the nodes of one structure or call have the same): the net holds each
//! record once with the indices of its places and transitions (0-based, in
//! document order, as ranges); a node may also hold a record itself, as
//! files written before the table do, or refer to a record by its `key`:
//!
//! ```xml
//! <toolspecific tool="mcl" version="1">          <!-- in a net -->
//!   <property key="mission" value="auv"/>
//!   <provenance task="Goto" callSite="3" structure="sequence" path="0.1"
//!               file="m.mcl" start="10" end="42" places="4-5" transitions="7-12"/>
//! </toolspecific>
//! <toolspecific tool="mcl" version="1">          <!-- in a place -->
//!   <interface id="1"/>
//! </toolspecific>
//! <toolspecific tool="mcl" version="1">          <!-- in a transition -->
//!   <kind type="event" event="ok"/>   <!-- or type="immediate", or
//!        type="timed" delay="2.5" (seconds), or type="timed" param="timeout" -->
//!   <priority value="2"/>
//!   <action action="Goto" primitive="goto" command="enable">
//!     <param name="x" value="24"/>
//!   </action>
//!   <binding task="Goto" callSite="3" label="first">   <!-- a call's start;
//!        optional role="monitor_condition", "while_condition" or "negated_while_condition" -->
//!     <arg name="way-point" value="[24, 12]"/>
//!   </binding>
//! </toolspecific>
//! ```
//!
//! A node's `<name>` is written only when it differs from its id (PNML
//! makes names optional; a node without one is named by its id). A net
//! without MCL data has only immediate transitions. [`write_pnml`] followed
//! by [`read_pnml`] gives back an equal [`Net`].
//!
//! Node and net ids are written as valid XML ids (`xsd:ID`): a character an
//! NCName cannot hold (`$`, `/` of MCL names, ...) is written `_xHHHH_` and
//! read back as itself ([`crate::xml_id`]).

use std::borrow::Cow;
use std::collections::HashSet;
use std::fmt;

use quick_xml::events::attributes::Attribute;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, BytesText, Event};
use quick_xml::name::QName;
use quick_xml::Writer;

use crate::model::{
    ActionRef, Arc, CallBinding, Delay, Net, NetBuilder, NodeId, Place, Provenance, SourceSpan, Transition,
    TransitionKind,
};
use crate::xml::{self, Element};
use crate::xml_id;

/// The provenance records of a net, by key.
type ProvenanceTable<'a> = std::collections::HashMap<&'a str, std::sync::Arc<Provenance>>;

/// The PNML 2009 P/T net type.
pub const PTNET_TYPE: &str = "http://www.pnml.org/version-2009/grammar/ptnet";
/// The PNML 2009 document namespace.
pub const PNML_NAMESPACE: &str = "http://www.pnml.org/version-2009/grammar/pnml";
/// `tool` attribute of MCL tool-specific blocks.
pub const MCL_TOOL: &str = "mcl";
/// `version` attribute of MCL tool-specific blocks written by this crate.
pub const MCL_TOOL_VERSION: &str = "1";

/// A PNML reading or writing error, with its location in the input.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PnmlError {
    /// 1-based line, or 0 when the error has no location.
    pub line: usize,
    /// 1-based column in characters, or 0 when the error has no location.
    pub column: usize,
    /// What went wrong.
    pub message: String,
}

impl PnmlError {
    pub(crate) fn at(input: &str, pos: usize, message: impl Into<String>) -> Self {
        let (line, column) = xml::line_col(input, pos);
        PnmlError { line, column, message: message.into() }
    }

    fn nowhere(message: impl Into<String>) -> Self {
        PnmlError { line: 0, column: 0, message: message.into() }
    }
}

impl fmt::Display for PnmlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}", self.message)
        } else {
            write!(f, "line {}, column {}: {}", self.line, self.column, self.message)
        }
    }
}

impl std::error::Error for PnmlError {}

/// Reads a document holding exactly one net.
pub fn read_pnml(input: &str) -> Result<Net, PnmlError> {
    let mut nets = read_pnml_nets(input)?;
    match nets.len() {
        1 => Ok(nets.remove(0)),
        0 => Err(PnmlError::at(input, 0, "the document holds no <net>")),
        n => Err(PnmlError::at(input, 0, format!("the document holds {n} nets; use read_pnml_nets"))),
    }
}

/// Reads every net of a document.
pub fn read_pnml_nets(input: &str) -> Result<Vec<Net>, PnmlError> {
    let root = xml::parse(input)?;
    if root.name != "pnml" {
        return Err(PnmlError::at(input, root.pos, format!("root element is <{}>, expected <pnml>", root.name)));
    }
    let r = Ctx { input };
    root.children_named("net").map(|n| r.net(n)).collect()
}

struct Ctx<'a> {
    input: &'a str,
}

/// Raw arc before node ids are resolved.
struct RawArc<'e> {
    el: &'e Element,
    source: &'e str,
    target: &'e str,
    weight: u32,
}

impl<'a> Ctx<'a> {
    fn err(&self, el: &Element, message: impl Into<String>) -> PnmlError {
        PnmlError::at(self.input, el.pos, message)
    }

    fn required<'e>(&self, el: &'e Element, key: &str) -> Result<&'e str, PnmlError> {
        el.attr(key).ok_or_else(|| self.err(el, format!("<{}> has no `{key}` attribute", el.name)))
    }

    /// The single child named `name`, if any (two are an error).
    fn single<'e>(&self, el: &'e Element, name: &'e str) -> Result<Option<&'e Element>, PnmlError> {
        let mut it = el.children_named(name);
        let first = it.next();
        if let Some(second) = it.next() {
            return Err(self.err(second, format!("<{}> has more than one <{name}>", el.name)));
        }
        Ok(first)
    }

    /// Text of `<label><text>…</text></label>`.
    fn label_text<'e>(&self, el: &'e Element, label: &'e str) -> Result<Option<&'e str>, PnmlError> {
        let Some(l) = self.single(el, label)? else {
            return Ok(None);
        };
        match self.single(l, "text")? {
            Some(t) => Ok(Some(t.text.as_str())),
            None => Err(self.err(l, format!("<{label}> has no <text>"))),
        }
    }

    fn label_number(&self, el: &Element, label: &str) -> Result<Option<u32>, PnmlError> {
        let Some(text) = self.label_text(el, label)? else {
            return Ok(None);
        };
        let at = self.single(el, label)?.unwrap_or(el);
        let t = text.trim();
        t.parse::<u32>()
            .map(Some)
            .map_err(|_| self.err(at, format!("<{label}> must be a whole number from 0 to {}, found `{t}`", u32::MAX)))
    }

    fn number<T: std::str::FromStr>(&self, el: &Element, key: &str) -> Result<Option<T>, PnmlError> {
        match el.attr(key) {
            None => Ok(None),
            Some(v) => {
                v.trim().parse::<T>().map(Some).map_err(|_| {
                    self.err(el, format!("attribute `{key}` of <{}> is not a valid number: `{v}`", el.name))
                })
            }
        }
    }

    /// The MCL tool-specific block of `el`, if any.
    fn mcl_block<'e>(&self, el: &'e Element) -> Result<Option<&'e Element>, PnmlError> {
        let mut found = None;
        for ts in el.children_named("toolspecific") {
            if ts.attr("tool") != Some(MCL_TOOL) {
                continue;
            }
            if found.is_some() {
                return Err(self.err(ts, format!("<{}> has more than one MCL <toolspecific>", el.name)));
            }
            let version = ts.attr("version").unwrap_or("");
            if version != MCL_TOOL_VERSION {
                return Err(self.err(
                    ts,
                    format!("unsupported MCL tool-specific version `{version}` (expected `{MCL_TOOL_VERSION}`)"),
                ));
            }
            found = Some(ts);
        }
        Ok(found)
    }

    fn net(&self, el: &Element) -> Result<Net, PnmlError> {
        let id = self.required(el, "id")?;
        let ty = self.required(el, "type")?.trim();
        if ty != PTNET_TYPE {
            return Err(
                self.err(el, format!("unsupported net type `{ty}`: only P/T nets ({PTNET_TYPE}) are supported"))
            );
        }
        let mut b = NetBuilder::new(&*xml_id::decode(id));
        if let Some(name) = self.label_text(el, "name")? {
            b.name(name);
        }
        let mut table: ProvenanceTable<'_> = Default::default();
        // (places?, first, last, record, element): the nodes of a record, by index.
        let mut ranges: Vec<(bool, u32, u32, std::sync::Arc<Provenance>, &Element)> = Vec::new();
        if let Some(ts) = self.mcl_block(el)? {
            for c in &ts.children {
                match c.name.as_str() {
                    "property" => {
                        b.property(self.required(c, "key")?, self.required(c, "value")?);
                    }
                    "provenance" => {
                        let prov = std::sync::Arc::new(self.provenance(c)?);
                        for (attr, places) in [("places", true), ("transitions", false)] {
                            if let Some(list) = c.attr(attr) {
                                for r in list.split_whitespace() {
                                    let (a, z) = r.split_once('-').unwrap_or((r, r));
                                    let (Ok(a), Ok(z)) = (a.parse::<u32>(), z.parse::<u32>()) else {
                                        return Err(self.err(c, format!("bad node range `{r}` in `{attr}`")));
                                    };
                                    ranges.push((places, a, z, prov.clone(), c));
                                }
                            }
                        }
                        if let Some(key) = c.attr("key") {
                            table.insert(key, prov);
                        }
                    }
                    other => return Err(self.err(c, format!("unknown MCL net data <{other}>"))),
                }
            }
        }
        let mut arcs = Vec::new();
        let mut place_els = Vec::new();
        let mut trans_els = Vec::new();
        let mut pages: Vec<&Element> = el.children_named("page").collect();
        if pages.is_empty() {
            return Err(self.err(el, "<net> has no <page>"));
        }
        // Depth-first, in document order.
        pages.reverse();
        while let Some(page) = pages.pop() {
            let mut nested = Vec::new();
            for c in &page.children {
                match c.name.as_str() {
                    "place" => {
                        b.add_place(self.place(c, &table)?);
                        place_els.push(c);
                    }
                    "transition" => {
                        b.add_transition(self.transition(c, &table)?);
                        trans_els.push(c);
                    }
                    "arc" => arcs.push(self.arc(c)?),
                    "page" => nested.push(c),
                    "referencePlace" | "referenceTransition" => {
                        return Err(self
                            .err(c, format!("<{}> is not supported: flatten reference nodes before loading", c.name)))
                    }
                    _ => {}
                }
            }
            pages.extend(nested.into_iter().rev());
        }
        for (places, a, z, prov, c) in ranges {
            if z < a {
                return Err(self.err(c, format!("empty node range `{a}-{z}`")));
            }
            for i in a..=z {
                let slot = if places {
                    b.place_mut(crate::PlaceId(i)).map(|p| &mut p.provenance)
                } else {
                    b.transition_mut(crate::TransitionId(i)).map(|t| &mut t.provenance)
                };
                match slot {
                    Some(slot) => *slot = prov.clone(),
                    None => {
                        let what = if places { "place" } else { "transition" };
                        return Err(self.err(c, format!("<provenance> names {what} #{i}, which the net does not have")));
                    }
                }
            }
        }
        self.resolve(b, arcs, &place_els, &trans_els)
    }

    fn resolve(
        &self,
        mut b: NetBuilder,
        arcs: Vec<RawArc<'_>>,
        places: &[&Element],
        transitions: &[&Element],
    ) -> Result<Net, PnmlError> {
        // Check ids here so that errors point at the offending element.
        let mut ids = std::collections::HashMap::new();
        let nodes = places.iter().enumerate().map(|(i, el)| (el, NodeId::Place(crate::PlaceId(i as u32)))).chain(
            transitions.iter().enumerate().map(|(i, el)| (el, NodeId::Transition(crate::TransitionId(i as u32)))),
        );
        for (el, node) in nodes {
            let id = self.required(el, "id")?;
            if id.is_empty() {
                return Err(self.err(el, "empty node id"));
            }
            if ids.insert(id, node).is_some() {
                return Err(self.err(el, format!("duplicate node id `{id}`")));
            }
        }
        for a in &arcs {
            let src = ids
                .get(a.source)
                .copied()
                .ok_or_else(|| self.err(a.el, format!("arc source `{}` is not a place or transition", a.source)))?;
            let dst = ids
                .get(a.target)
                .copied()
                .ok_or_else(|| self.err(a.el, format!("arc target `{}` is not a place or transition", a.target)))?;
            match (src, dst) {
                (NodeId::Place(p), NodeId::Transition(t)) => {
                    b.add_input(p, t, a.weight);
                }
                (NodeId::Transition(t), NodeId::Place(p)) => {
                    b.add_output(t, p, a.weight);
                }
                _ => {
                    return Err(self
                        .err(a.el, format!("arc `{}` -> `{}` must join a place and a transition", a.source, a.target)))
                }
            }
        }
        b.build().map_err(|e| PnmlError::nowhere(e.to_string()))
    }

    fn place(&self, el: &Element, table: &ProvenanceTable<'_>) -> Result<Place, PnmlError> {
        let id = self.required(el, "id")?;
        let mut p = Place::new(&*xml_id::decode(id));
        if let Some(name) = self.label_text(el, "name")? {
            p.name = name.into();
        }
        p.initial = self.label_number(el, "initialMarking")?.unwrap_or(0);
        if let Some(ts) = self.mcl_block(el)? {
            for c in &ts.children {
                match c.name.as_str() {
                    "interface" => {
                        p.interface =
                            self.number(c, "id")?.ok_or_else(|| self.err(c, "<interface> has no `id` attribute"))?
                    }
                    "provenance" => p.provenance = self.node_provenance(c, table)?,
                    other => return Err(self.err(c, format!("unknown MCL place data <{other}>"))),
                }
            }
        }
        Ok(p)
    }

    fn transition(&self, el: &Element, table: &ProvenanceTable<'_>) -> Result<Transition, PnmlError> {
        let id = self.required(el, "id")?;
        let mut t = Transition::new(&*xml_id::decode(id));
        if let Some(name) = self.label_text(el, "name")? {
            t.name = name.into();
        }
        if let Some(ts) = self.mcl_block(el)? {
            for c in &ts.children {
                match c.name.as_str() {
                    "kind" => t.kind = self.kind(c)?,
                    "priority" => {
                        t.priority = Some(
                            self.number(c, "value")?
                                .ok_or_else(|| self.err(c, "<priority> has no `value` attribute"))?,
                        )
                    }
                    "action" => t.actions.push(self.action(c)?),
                    "binding" => {
                        if t.binding.is_some() {
                            return Err(self.err(c, "a transition has at most one <binding>"));
                        }
                        t.binding = Some(self.binding(c)?.into());
                    }
                    "provenance" => t.provenance = self.node_provenance(c, table)?,
                    other => return Err(self.err(c, format!("unknown MCL transition data <{other}>"))),
                }
            }
        }
        Ok(t)
    }

    fn kind(&self, el: &Element) -> Result<TransitionKind, PnmlError> {
        match self.required(el, "type")? {
            "immediate" => Ok(TransitionKind::Immediate),
            "event" => Ok(TransitionKind::Event(self.required(el, "event")?.to_string())),
            "timed" => match (el.attr("delay"), el.attr("param")) {
                (Some(_), None) => {
                    let d: f64 = self.number(el, "delay")?.unwrap_or(f64::NAN);
                    if d.is_finite() && d >= 0.0 {
                        Ok(TransitionKind::Timed(Delay::Fixed(d)))
                    } else {
                        Err(self.err(el, "delay must be a finite number of seconds ≥ 0"))
                    }
                }
                (None, Some(p)) => Ok(TransitionKind::Timed(Delay::Param(p.to_string()))),
                _ => Err(self.err(el, "a timed <kind> needs exactly one of `delay` or `param`")),
            },
            other => {
                Err(self.err(el, format!("unknown transition kind `{other}` (expected immediate, event or timed)")))
            }
        }
    }

    fn action(&self, el: &Element) -> Result<ActionRef, PnmlError> {
        let mut a = ActionRef {
            action: self.required(el, "action")?.to_string(),
            primitive: el.attr("primitive").unwrap_or("").to_string(),
            command: el.attr("command").unwrap_or("").to_string(),
            params: Vec::new(),
        };
        for c in &el.children {
            if c.name != "param" {
                return Err(self.err(c, format!("unknown MCL action data <{}>", c.name)));
            }
            a.params.push((self.required(c, "name")?.to_string(), self.required(c, "value")?.to_string()));
        }
        Ok(a)
    }

    fn binding(&self, el: &Element) -> Result<CallBinding, PnmlError> {
        let mut b = CallBinding {
            task: self.required(el, "task")?.to_string(),
            call_site: self
                .number(el, "callSite")?
                .ok_or_else(|| self.err(el, "<binding> has no `callSite` attribute"))?,
            label: el.attr("label").map(str::to_string),
            args: Vec::new(),
            role: el.attr("role").map(str::to_string),
        };
        for c in &el.children {
            if c.name != "arg" {
                return Err(self.err(c, format!("unknown MCL binding data <{}>", c.name)));
            }
            b.args.push((self.required(c, "name")?.to_string(), self.required(c, "value")?.to_string()));
        }
        Ok(b)
    }

    /// A node's provenance: a reference into the net's table, or the record itself.
    fn node_provenance(
        &self,
        el: &Element,
        table: &ProvenanceTable<'_>,
    ) -> Result<std::sync::Arc<Provenance>, PnmlError> {
        match el.attr("ref") {
            Some(key) => table
                .get(key)
                .cloned()
                .ok_or_else(|| self.err(el, format!("<provenance ref=\"{key}\"> names no provenance of the net"))),
            None => Ok(self.provenance(el)?.into()),
        }
    }

    fn provenance(&self, el: &Element) -> Result<Provenance, PnmlError> {
        let span = match el.attr("file") {
            None => None,
            Some(file) => Some(SourceSpan {
                file: file.to_string(),
                start: self
                    .number(el, "start")?
                    .ok_or_else(|| self.err(el, "<provenance> with `file` needs `start`"))?,
                end: self.number(el, "end")?.ok_or_else(|| self.err(el, "<provenance> with `file` needs `end`"))?,
            }),
        };
        Ok(Provenance {
            task: el.attr("task").map(str::to_string),
            call_site: self.number(el, "callSite")?,
            structure: el.attr("structure").map(str::to_string),
            path: el.attr("path").map(str::to_string),
            span,
        })
    }

    fn arc<'e>(&self, el: &'e Element) -> Result<RawArc<'e>, PnmlError> {
        let source = self.required(el, "source")?;
        let target = self.required(el, "target")?;
        let weight = self.label_number(el, "inscription")?.unwrap_or(1);
        if weight == 0 {
            return Err(self.err(el, "arc inscription must be at least 1"));
        }
        Ok(RawArc { el, source, target, weight })
    }
}

// ---------------------------------------------------------------------------
// Writing

struct Out<W: std::io::Write> {
    w: Writer<W>,
}

fn io_err(e: std::io::Error) -> PnmlError {
    PnmlError::nowhere(format!("cannot write PNML: {e}"))
}

fn check_chars(what: &str, s: &str) -> Result<(), PnmlError> {
    match s.chars().find(|&c| !xml::is_xml_char(c)) {
        None => Ok(()),
        Some(c) => Err(PnmlError::nowhere(format!(
            "{what} `{}` contains character U+{:04X}, which XML 1.0 cannot represent",
            s.escape_debug(),
            c as u32
        ))),
    }
}

impl<W: std::io::Write> Out<W> {
    fn start(&mut self, name: &str, attrs: &[(&str, &str)]) -> Result<(), PnmlError> {
        let e = elem(name, attrs)?;
        self.w.write_event(Event::Start(e)).map_err(io_err)
    }

    fn empty(&mut self, name: &str, attrs: &[(&str, &str)]) -> Result<(), PnmlError> {
        let e = elem(name, attrs)?;
        self.w.write_event(Event::Empty(e)).map_err(io_err)
    }

    fn end(&mut self, name: &str) -> Result<(), PnmlError> {
        self.w.write_event(Event::End(BytesEnd::new(name))).map_err(io_err)
    }

    /// `<label><text>value</text></label>`
    fn label(&mut self, label: &str, value: &str) -> Result<(), PnmlError> {
        check_chars(label, value)?;
        self.start(label, &[])?;
        self.w
            .create_element("text")
            .write_text_content(BytesText::from_escaped(xml::escape_text(value)))
            .map_err(io_err)?;
        self.end(label)
    }

    fn toolspecific_start(&mut self) -> Result<(), PnmlError> {
        self.start("toolspecific", &[("tool", MCL_TOOL), ("version", MCL_TOOL_VERSION)])
    }

    fn provenance(&mut self, p: &Provenance, extra: &[(&str, &str)]) -> Result<(), PnmlError> {
        let call_site = p.call_site.map(|c| c.to_string());
        let (start, end) = match &p.span {
            Some(s) => (Some(s.start.to_string()), Some(s.end.to_string())),
            None => (None, None),
        };
        let mut attrs: Vec<(&str, &str)> = extra.to_vec();
        let pairs = [
            ("task", p.task.as_deref()),
            ("callSite", call_site.as_deref()),
            ("structure", p.structure.as_deref()),
            ("path", p.path.as_deref()),
            ("file", p.span.as_ref().map(|s| s.file.as_str())),
            ("start", start.as_deref()),
            ("end", end.as_deref()),
        ];
        for (k, v) in pairs {
            if let Some(v) = v {
                attrs.push((k, v));
            }
        }
        self.empty("provenance", &attrs)
    }
}

/// Adds node index `i` to a list of ranges `a-b c d-e` whose last range
/// started at `*open` (indices arrive in increasing order).
fn push_index(list: &mut String, open: &mut Option<(usize, usize)>, i: usize) {
    match open {
        Some((_, end)) if *end + 1 == i => *end = i,
        _ => {
            close_range(list, *open);
            *open = Some((i, i));
        }
    }
}

/// Writes the range `open` at the end of `list`.
fn close_range(list: &mut String, open: Option<(usize, usize)>) {
    use std::fmt::Write;
    if let Some((a, z)) = open {
        if !list.is_empty() {
            list.push(' ');
        }
        let _ = if a == z { write!(list, "{a}") } else { write!(list, "{a}-{z}") };
    }
}

fn elem<'a>(name: &'a str, attrs: &[(&str, &str)]) -> Result<BytesStart<'a>, PnmlError> {
    let mut e = BytesStart::new(name);
    for &(k, v) in attrs {
        check_chars(&format!("attribute `{k}`"), v)?;
        e.push_attribute(Attribute { key: QName(k), value: Cow::Owned(xml::escape_attr(v)) });
    }
    Ok(e)
}

/// An id that `used` says is free, built from `base`.
fn fresh_id(used: &impl Fn(&str) -> bool, base: &str, n: usize) -> String {
    let mut id = format!("{base}{n}");
    while used(id.as_str()) {
        id.push('_');
    }
    id
}

/// Writes `net` as a PNML 2009 document (2-space indentation).
///
/// Fails only if a string of the net contains a character XML 1.0 cannot
/// represent (such as U+0000). [`write_pnml_to`] writes the same bytes to
/// a writer without holding the document in memory.
pub fn write_pnml(net: &Net) -> Result<String, PnmlError> {
    let mut bytes = Vec::new();
    write_pnml_to(net, &mut bytes)?;
    String::from_utf8(bytes).map_err(|e| PnmlError::nowhere(format!("cannot write PNML: {e}")))
}

/// Writes `net` as a PNML 2009 document to `w`, as it goes (give it a
/// buffered writer): a large net's document (gigabytes for a million
/// calls) is never held in memory. The bytes are those of [`write_pnml`].
///
/// Fails if a string of the net contains a character XML 1.0 cannot
/// represent (such as U+0000), or if writing fails; what was written
/// before the error stays written.
pub fn write_pnml_to<W: std::io::Write>(net: &Net, w: W) -> Result<(), PnmlError> {
    let mut out = Out { w: Writer::new_with_indent(w, b' ', 2) };
    out.w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None))).map_err(io_err)?;
    out.start("pnml", &[("xmlns", PNML_NAMESPACE)])?;
    out.start("net", &[("id", &xml_id::encode(net.id())), ("type", PTNET_TYPE)])?;
    out.label("name", net.name())?;
    // Each provenance record once, with the nodes it belongs to as ranges of
    // node indices (places and transitions in document order). Records are
    // shared (`Arc`) by the nodes of one structure or call, which the
    // compiler creates one after the other, so the ranges are few; equal
    // records at different addresses are merged.
    let mut by_ptr: std::collections::HashMap<*const Provenance, usize> = Default::default();
    let mut by_value: std::collections::HashMap<&Provenance, usize> = Default::default();
    let mut records: Vec<(&Provenance, String, String)> = Vec::new();
    let nodes = net
        .places()
        .iter()
        .map(|p| (&p.provenance, true))
        .chain(net.transitions().iter().map(|t| (&t.provenance, false)));
    let (mut last_place, mut last_transition) = (Vec::new(), Vec::new());
    for (i, (prov, places)) in nodes.enumerate() {
        let i = if places { i } else { i - net.place_count() };
        if prov.is_empty() {
            continue;
        }
        let k = match by_ptr.get(&std::sync::Arc::as_ptr(prov)) {
            Some(&k) => k,
            None => {
                let k = *by_value.entry(&**prov).or_insert_with(|| {
                    records.push((&**prov, String::new(), String::new()));
                    records.len() - 1
                });
                by_ptr.insert(std::sync::Arc::as_ptr(prov), k);
                k
            }
        };
        let (list, last) =
            if places { (&mut records[k].1, &mut last_place) } else { (&mut records[k].2, &mut last_transition) };
        if last.len() <= k {
            last.resize(k + 1, None);
        }
        push_index(list, &mut last[k], i);
    }
    for (k, (_, places, transitions)) in records.iter_mut().enumerate() {
        close_range(places, last_place.get(k).copied().flatten());
        close_range(transitions, last_transition.get(k).copied().flatten());
    }
    if !net.properties().is_empty() || !records.is_empty() {
        out.toolspecific_start()?;
        for (k, v) in net.properties() {
            out.empty("property", &[("key", k), ("value", v)])?;
        }
        for (prov, places, transitions) in &records {
            let mut extra: Vec<(&str, &str)> = Vec::new();
            if !places.is_empty() {
                extra.push(("places", places));
            }
            if !transitions.is_empty() {
                extra.push(("transitions", transitions));
            }
            out.provenance(prov, &extra)?;
        }
        out.end("toolspecific")?;
    }
    // Ids taken that a fresh id (`page0`, `a17`, `a17_`...) could meet:
    // only those of that shape are kept, so a large net costs no set of
    // every id (a compiled mission has none of that shape).
    let fresh_shape = |id: &str| {
        let rest = id.strip_prefix("page").or_else(|| id.strip_prefix('a')).unwrap_or("");
        let digits = rest.trim_end_matches('_');
        !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())
    };
    let taken: HashSet<&str> = net
        .places()
        .iter()
        .map(|p| p.id.as_str())
        .chain(net.transitions().iter().map(|t| t.id.as_str()))
        .chain([net.id()])
        .filter(|id| fresh_shape(id))
        .collect();
    let used = |id: &str| taken.contains(id);
    let page_id = fresh_id(&used, "page", 0);
    out.start("page", &[("id", &page_id)])?;

    for p in net.places() {
        out.start("place", &[("id", &xml_id::encode(&p.id))])?;
        if p.name != p.id {
            out.label("name", &p.name)?;
        }
        if p.initial > 0 {
            out.label("initialMarking", &p.initial.to_string())?;
        }
        if p.interface != 0 {
            out.toolspecific_start()?;
            out.empty("interface", &[("id", &p.interface.to_string())])?;
            out.end("toolspecific")?;
        }
        out.end("place")?;
    }

    for t in net.transitions() {
        out.start("transition", &[("id", &xml_id::encode(&t.id))])?;
        if t.name != t.id {
            out.label("name", &t.name)?;
        }
        let has_data = !t.kind.is_immediate() || !t.actions.is_empty() || t.priority.is_some() || t.binding.is_some();
        if has_data {
            out.toolspecific_start()?;
            match &t.kind {
                TransitionKind::Immediate => {}
                TransitionKind::Event(e) => out.empty("kind", &[("type", "event"), ("event", e)])?,
                TransitionKind::Timed(Delay::Fixed(d)) => {
                    // `{}` prints the shortest string that parses back to the same f64.
                    out.empty("kind", &[("type", "timed"), ("delay", &format!("{d}"))])?
                }
                TransitionKind::Timed(Delay::Param(p)) => out.empty("kind", &[("type", "timed"), ("param", p)])?,
            }
            if let Some(prio) = t.priority {
                out.empty("priority", &[("value", &prio.to_string())])?;
            }
            for a in &t.actions {
                let attrs = [
                    ("action", a.action.as_str()),
                    ("primitive", a.primitive.as_str()),
                    ("command", a.command.as_str()),
                ];
                if a.params.is_empty() {
                    out.empty("action", &attrs)?;
                } else {
                    out.start("action", &attrs)?;
                    for (k, v) in &a.params {
                        out.empty("param", &[("name", k), ("value", v)])?;
                    }
                    out.end("action")?;
                }
            }
            if let Some(b) = &t.binding {
                let call_site = b.call_site.to_string();
                let mut attrs = vec![("task", b.task.as_str()), ("callSite", call_site.as_str())];
                if let Some(label) = &b.label {
                    attrs.push(("label", label));
                }
                if let Some(role) = &b.role {
                    attrs.push(("role", role));
                }
                if b.args.is_empty() {
                    out.empty("binding", &attrs)?;
                } else {
                    out.start("binding", &attrs)?;
                    for (k, v) in &b.args {
                        out.empty("arg", &[("name", k), ("value", v)])?;
                    }
                    out.end("binding")?;
                }
            }

            out.end("toolspecific")?;
        }
        out.end("transition")?;
    }

    let used = |id: &str| id == page_id || used(id);
    for (i, arc) in net.arcs().iter().enumerate() {
        let (src, dst, w) = match *arc {
            Arc::Input { place, transition, weight } => {
                (net.place(place).map(|p| p.id.as_str()), net.transition(transition).map(|t| t.id.as_str()), weight)
            }
            Arc::Output { transition, place, weight } => {
                (net.transition(transition).map(|t| t.id.as_str()), net.place(place).map(|p| p.id.as_str()), weight)
            }
        };
        let (Some(src), Some(dst)) = (src, dst) else {
            return Err(PnmlError::nowhere("arc refers to a missing node"));
        };
        let id = fresh_id(&used, "a", i);
        let (src, dst) = (xml_id::encode(src), xml_id::encode(dst));
        let attrs = [("id", id.as_str()), ("source", &*src), ("target", &*dst)];
        if w == 1 {
            out.empty("arc", &attrs)?;
        } else {
            out.start("arc", &attrs)?;
            out.label("inscription", &w.to_string())?;
            out.end("arc")?;
        }
    }
    out.end("page")?;
    out.end("net")?;
    out.end("pnml")?;
    let mut w = out.w.into_inner();
    w.write_all(b"\n").map_err(io_err)?;
    w.flush().map_err(io_err)
}
