//! The world modeler (seed 7.4): fact-provider scripts turn perceptions
//! received from the vehicle into facts of the knowledge database.
//!
//! Scripts are written in the seed's XML form (Extracts 7.6, 7.7):
//!
//! ```xml
//! <script id="low_battery">
//!   <condition value1="auv.battery" type1="perception" operator="<" value2="30" type2="literal"/>
//!   <del value1="ictineu" type1="vehicle" prop="batteryOk"/>
//!   <add value1="ictineu" type1="vehicle" prop="batteryLow"/>
//! </script>
//! ```
//!
//! A file holds any number of `<script>` elements, at top level or inside a
//! root element. `operator` may be written raw (`"<"`, as in the seed) or
//! escaped (`"&lt;"`). A fact `value1 prop value2` is the PDDL atom
//! `(prop value1 value2)` (`(prop value1)` without `value2`), in lower case;
//! `forall` stands for every object of the given type. When a perception
//! arrives, every script with a condition on it runs: if all its conditions
//! hold (a perception never received makes a condition false), its `del`
//! facts are removed, then its `add` facts added.

use crate::pddl::{CmpOp, Domain, Fact, Problem, OBJECT};
use std::collections::{BTreeSet, HashMap};

/// A perception's value.
#[derive(Clone, Debug, PartialEq)]
pub enum Percept {
    Num(f64),
    Text(String),
}

impl Percept {
    /// A number when the text is one.
    pub fn parse(s: &str) -> Percept {
        match s.trim().parse::<f64>() {
            Ok(n) if n.is_finite() => Percept::Num(n),
            _ => Percept::Text(s.to_string()),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Operand {
    Perception(String),
    Literal(Percept),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Condition {
    pub left: Operand,
    pub op: CmpOp,
    pub right: Operand,
}

/// `value1` / `value2` of an effect.
#[derive(Clone, Debug, PartialEq)]
pub enum Entity {
    Forall,
    Named(String),
}

#[derive(Clone, Debug, PartialEq)]
pub struct FactPattern {
    pub prop: String,
    pub args: Vec<(Entity, String)>,
}

/// A fact-provider script: fp = {id, conditions, effects} (7.7).
#[derive(Clone, Debug, PartialEq)]
pub struct Script {
    pub id: String,
    pub conditions: Vec<Condition>,
    pub del: Vec<FactPattern>,
    pub add: Vec<FactPattern>,
}

/// One change made to the knowledge database.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Change {
    pub script: String,
    pub fact: Fact,
    /// True for an addition, false for a removal.
    pub added: bool,
}

/// The seed writes `operator="<"`, which XML forbids inside attributes:
/// escape it before handing the text to the XML reader.
fn escape_raw_lt(xml: &str) -> String {
    let mut out = String::with_capacity(xml.len());
    let mut rest = xml;
    while let Some(i) = rest.find("operator=") {
        out.push_str(&rest[..i + "operator=".len()]);
        rest = &rest[i + "operator=".len()..];
        let q = match rest.chars().next() {
            Some(q @ ('"' | '\'')) => q,
            _ => continue,
        };
        let Some(end) = rest[1..].find(q) else { break };
        let val = &rest[1..1 + end];
        out.push(q);
        out.push_str(&val.replace('<', "&lt;"));
        out.push(q);
        rest = &rest[end + 2..];
    }
    out.push_str(rest);
    out
}

fn line_of(text: &str, pos: usize) -> usize {
    text[..pos.min(text.len())].matches('\n').count() + 1
}

/// Parses fact-provider scripts. `file` names the text in errors.
pub fn parse_scripts(file: &str, xml: &str) -> Result<Vec<Script>, String> {
    use quick_xml::events::Event;
    let text = escape_raw_lt(xml);
    let mut reader = quick_xml::Reader::from_str(&text);
    reader.config_mut().trim_text(true);
    let mut scripts: Vec<Script> = Vec::new();
    let mut current: Option<Script> = None;
    loop {
        let before = reader.buffer_position() as usize;
        let ev = reader.read_event().map_err(|e| format!("{file}:{}: XML error: {e}", line_of(&text, before)))?;
        // The line where the element just read starts.
        let end = (reader.buffer_position() as usize).min(text.len());
        let pos = text[..end].rfind('<').unwrap_or(before);
        let at = |msg: String| format!("{file}:{}: {msg}", line_of(&text, pos));
        let (e, empty) = match ev {
            Event::Eof => break,
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(e) => {
                if e.name().as_ref() == "script" {
                    match current.take() {
                        Some(s) => scripts.push(s),
                        None => return Err(at("`</script>` without `<script>`".into())),
                    }
                }
                continue;
            }
            _ => continue,
        };
        let name = e.name().as_ref().to_string();
        let mut attrs: HashMap<String, String> = HashMap::new();
        for a in e.attributes() {
            let a = a.map_err(|err| at(format!("bad attribute in `<{name}>`: {err}")))?;
            let k = a.key.as_ref().to_string();
            let v = a
                .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                .map_err(|err| at(format!("bad value of `{k}`: {err}")))?;
            attrs.insert(k, v.replace("\\_", "_"));
        }
        let get = |k: &str| attrs.get(k).cloned().ok_or_else(|| at(format!("`<{name}>` needs the attribute `{k}`")));
        match name.as_str() {
            "script" => {
                if current.is_some() {
                    return Err(at("`<script>` inside another `<script>`".into()));
                }
                let s = Script { id: get("id")?, conditions: Vec::new(), del: Vec::new(), add: Vec::new() };
                if empty {
                    scripts.push(s);
                } else {
                    current = Some(s);
                }
            }
            "condition" | "add" | "del" => {
                let Some(s) = current.as_mut() else {
                    return Err(at(format!("`<{name}>` outside a `<script>`")));
                };
                if name == "condition" {
                    let operand = |v: &str, t: &str| -> Result<Operand, String> {
                        let val = get(v)?;
                        match get(t)?.as_str() {
                            "perception" => Ok(Operand::Perception(val)),
                            "literal" => Ok(Operand::Literal(Percept::parse(&val))),
                            other => Err(at(format!("`{t}` must be \"perception\" or \"literal\", found \"{other}\""))),
                        }
                    };
                    let op = match get("operator")?.as_str() {
                        "=" | "==" => CmpOp::Eq,
                        "!=" => CmpOp::Ne,
                        "<" => CmpOp::Lt,
                        ">" => CmpOp::Gt,
                        "<=" => CmpOp::Le,
                        ">=" => CmpOp::Ge,
                        other => {
                            return Err(at(format!("unknown operator \"{other}\": expected =, !=, <, >, <= or >=")))
                        }
                    };
                    s.conditions.push(Condition {
                        left: operand("value1", "type1")?,
                        op,
                        right: operand("value2", "type2")?,
                    });
                } else {
                    let ent =
                        |v: String| if v == "forall" { Entity::Forall } else { Entity::Named(v.to_ascii_lowercase()) };
                    let mut args = vec![(ent(get("value1")?), get("type1")?.to_ascii_lowercase())];
                    if attrs.contains_key("value2") || attrs.contains_key("type2") {
                        args.push((ent(get("value2")?), get("type2")?.to_ascii_lowercase()));
                    }
                    let fp = FactPattern { prop: get("prop")?.to_ascii_lowercase(), args };
                    if name == "add" {
                        s.add.push(fp);
                    } else {
                        s.del.push(fp);
                    }
                }
            }
            _ => {} // a root element such as <scripts> or <world>
        }
    }
    if let Some(s) = current {
        return Err(format!("{file}: script `{}` is not closed (`</script>` missing)", s.id));
    }
    Ok(scripts)
}

/// The knowledge database and the scripts that keep it up to date.
#[derive(Clone, Debug)]
pub struct WorldModeler {
    scripts: Vec<Script>,
    perceptions: HashMap<String, Percept>,
    facts: BTreeSet<Fact>,
    /// Type -> objects of that type (subtypes included).
    objects: HashMap<String, Vec<String>>,
}

impl WorldModeler {
    /// A modeler over the objects of `domain` and `problem`, starting from the
    /// problem's initial facts. Errors: a script naming an unknown type or
    /// object, or an object that is not of the type given.
    pub fn new(scripts: Vec<Script>, domain: &Domain, problem: &Problem) -> Result<WorldModeler, String> {
        let parent: HashMap<&str, &str> = domain.types.iter().map(|(t, p)| (t.as_str(), p.as_str())).collect();
        let mut objects: HashMap<String, Vec<String>> = HashMap::new();
        for o in domain.constants.iter().chain(&problem.objects) {
            for t in &o.types {
                let mut t = t.as_str();
                for _ in 0..=parent.len() + 1 {
                    let v = objects.entry(t.to_string()).or_default();
                    if !v.contains(&o.name) {
                        v.push(o.name.clone());
                    }
                    if t == OBJECT {
                        break;
                    }
                    t = parent.get(t).copied().unwrap_or(OBJECT);
                }
            }
        }
        let known_type = |t: &str| t == OBJECT || parent.contains_key(t);
        for s in &scripts {
            for fp in s.del.iter().chain(&s.add) {
                for (e, t) in &fp.args {
                    if !known_type(t) {
                        return Err(format!("script `{}`: unknown type `{t}`", s.id));
                    }
                    if let Entity::Named(n) = e {
                        if !objects.get(t).is_some_and(|v| v.contains(n)) {
                            return Err(format!("script `{}`: `{n}` is not an object of type `{t}`", s.id));
                        }
                    }
                }
            }
        }
        Ok(WorldModeler {
            scripts,
            perceptions: HashMap::new(),
            facts: problem.init.iter().cloned().collect(),
            objects,
        })
    }

    pub fn facts(&self) -> &BTreeSet<Fact> {
        &self.facts
    }

    pub fn set_facts(&mut self, facts: impl IntoIterator<Item = Fact>) {
        self.facts = facts.into_iter().collect();
    }

    pub fn perception(&self, name: &str) -> Option<&Percept> {
        self.perceptions.get(name)
    }

    /// Records a perception and runs the scripts that have a condition on it.
    /// Returns the changes made, in order.
    pub fn perceive(&mut self, name: &str, value: Percept) -> Vec<Change> {
        self.perceptions.insert(name.to_string(), value);
        let mut changes = Vec::new();
        for i in 0..self.scripts.len() {
            let s = &self.scripts[i];
            let mentions = s
                .conditions
                .iter()
                .any(|c| c.left == Operand::Perception(name.into()) || c.right == Operand::Perception(name.into()));
            if !mentions || !s.conditions.iter().all(|c| self.holds(c)) {
                continue;
            }
            let del: Vec<Fact> = s.del.iter().flat_map(|p| self.expand(p)).collect();
            let add: Vec<Fact> = s.add.iter().flat_map(|p| self.expand(p)).collect();
            let id = s.id.clone();
            for f in del {
                if self.facts.remove(&f) {
                    changes.push(Change { script: id.clone(), fact: f, added: false });
                }
            }
            for f in add {
                if self.facts.insert(f.clone()) {
                    changes.push(Change { script: id.clone(), fact: f, added: true });
                }
            }
        }
        changes
    }

    fn value(&self, o: &Operand) -> Option<Percept> {
        match o {
            Operand::Perception(p) => self.perceptions.get(p).cloned(),
            Operand::Literal(v) => Some(v.clone()),
        }
    }

    fn holds(&self, c: &Condition) -> bool {
        match (self.value(&c.left), self.value(&c.right)) {
            (Some(Percept::Num(a)), Some(Percept::Num(b))) => c.op.holds(a, b),
            (Some(a), Some(b)) => {
                let s = |p: Percept| match p {
                    Percept::Num(n) => crate::pddl::fmt_num(n),
                    Percept::Text(t) => t,
                };
                let (a, b) = (s(a), s(b));
                match c.op {
                    CmpOp::Eq => a == b,
                    CmpOp::Ne => a != b,
                    CmpOp::Lt => a < b,
                    CmpOp::Le => a <= b,
                    CmpOp::Gt => a > b,
                    CmpOp::Ge => a >= b,
                }
            }
            _ => false,
        }
    }

    fn expand(&self, p: &FactPattern) -> Vec<Fact> {
        let mut out: Vec<Vec<String>> = vec![Vec::new()];
        for (e, t) in &p.args {
            let choices: Vec<String> = match e {
                Entity::Named(n) => vec![n.clone()],
                Entity::Forall => self.objects.get(t).cloned().unwrap_or_default(),
            };
            out = out
                .into_iter()
                .flat_map(|prefix| choices.iter().map(move |c| [prefix.clone(), vec![c.clone()]].concat()))
                .collect();
        }
        out.into_iter().map(|args| Fact { pred: p.prop.clone(), args }).collect()
    }
}
