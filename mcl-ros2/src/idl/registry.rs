//! Resolved message types by full name (`pkg/msg/Name`). A service adds
//! its two parts (`pkg/srv/Name_Request`, `pkg/srv/Name_Response`) and an
//! action the messages ROS 2 sends for it (`pkg/action/Name_Goal`,
//! `_Result`, `_Feedback`, `_SendGoal_Request`, `_SendGoal_Response`,
//! `_GetResult_Request`, `_GetResult_Response`, `_FeedbackMessage`), so
//! that the CDR codec only knows messages.

use super::bundled::{Kind, DEFINITIONS};
use super::{parse_action, parse_msg, parse_srv, Array, BaseType, Field, Message, Prim};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A definition that cannot be read or resolved, with where it is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RegistryError {
    /// The definition (`pkg/msg/Name`) or the file.
    pub what: String,
    /// Line in its text, when known.
    pub line: Option<usize>,
    pub message: String,
}

impl std::fmt::Display for RegistryError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{l}: {}", self.what, self.message),
            None => write!(f, "{}: {}", self.what, self.message),
        }
    }
}

impl std::error::Error for RegistryError {}

/// Message types by full name, and which services and actions exist.
#[derive(Clone, Debug, Default)]
pub struct Registry {
    messages: BTreeMap<String, Message>,
    services: BTreeMap<String, ()>,
    actions: BTreeMap<String, ()>,
}

impl Registry {
    /// An empty registry.
    pub fn new() -> Registry {
        Registry::default()
    }

    /// The bundled packages ([`super::bundled`]).
    pub fn bundled() -> Registry {
        let mut r = Registry::new();
        for &(pkg, kind, name, text) in DEFINITIONS {
            // The bundled texts are tested to parse (`bundled_definitions_resolve`).
            let _ = r.add(pkg, kind, name, text);
        }
        r
    }

    /// Adds one definition; a later one with the same name replaces it.
    pub fn add(&mut self, package: &str, kind: Kind, name: &str, text: &str) -> Result<(), RegistryError> {
        let what = format!("{package}/{}/{name}", kind.as_str());
        let err = |e: super::ParseError| RegistryError { what: what.clone(), line: Some(e.line), message: e.message };
        match kind {
            Kind::Msg => {
                self.messages.insert(what.clone(), parse_msg(package, text).map_err(err)?);
            }
            Kind::Srv => {
                let s = parse_srv(package, text).map_err(err)?;
                self.messages.insert(format!("{what}_Request"), s.request);
                self.messages.insert(format!("{what}_Response"), s.response);
                self.services.insert(what, ());
            }
            Kind::Action => {
                let a = parse_action(package, text).map_err(err)?;
                let named = |suffix: &str| Field {
                    name: String::new(),
                    base: BaseType::Named { package: package.into(), name: format!("{name}_{suffix}") },
                    array: Array::No,
                    default: None,
                    line: 0,
                };
                let field =
                    |n: &str, base: BaseType| Field { name: n.into(), base, array: Array::No, default: None, line: 0 };
                let uuid = || BaseType::Named { package: "unique_identifier_msgs".into(), name: "UUID".into() };
                let time = BaseType::Named { package: "builtin_interfaces".into(), name: "Time".into() };
                let with = |fields: Vec<Field>| Message { fields, constants: Vec::new() };
                let goal = Field { name: "goal".into(), ..named("Goal") };
                let result = Field { name: "result".into(), ..named("Result") };
                let feedback = Field { name: "feedback".into(), ..named("Feedback") };
                // Nested action parts live under `pkg/action/`; see `resolve`.
                self.messages.insert(format!("{what}_Goal"), a.goal);
                self.messages.insert(format!("{what}_Result"), a.result);
                self.messages.insert(format!("{what}_Feedback"), a.feedback);
                self.messages.insert(format!("{what}_SendGoal_Request"), with(vec![field("goal_id", uuid()), goal]));
                self.messages.insert(
                    format!("{what}_SendGoal_Response"),
                    with(vec![field("accepted", BaseType::Prim(Prim::Bool)), field("stamp", time)]),
                );
                self.messages.insert(format!("{what}_GetResult_Request"), with(vec![field("goal_id", uuid())]));
                self.messages.insert(
                    format!("{what}_GetResult_Response"),
                    with(vec![field("status", BaseType::Prim(Prim::Int8)), result]),
                );
                self.messages.insert(format!("{what}_FeedbackMessage"), with(vec![field("goal_id", uuid()), feedback]));
                self.actions.insert(what, ());
            }
        }
        Ok(())
    }

    /// Adds every `.msg`, `.srv` and `.action` file under `dir` (a package
    /// folder `pkg/msg/Name.msg`, or a folder of packages); the package is
    /// the name of the folder above `msg`/`srv`/`action`.
    pub fn load_dir(&mut self, dir: &Path) -> Result<usize, RegistryError> {
        let mut files = Vec::new();
        walk(dir, &mut files, 0).map_err(|e| RegistryError {
            what: dir.display().to_string(),
            line: None,
            message: format!("cannot read the folder: {e}"),
        })?;
        let mut n = 0;
        for path in files {
            let kind = match path.extension().and_then(|e| e.to_str()) {
                Some("msg") => Kind::Msg,
                Some("srv") => Kind::Srv,
                Some("action") => Kind::Action,
                _ => continue,
            };
            let folder = path.parent().and_then(|p| p.file_name()).and_then(|s| s.to_str());
            let package = path.parent().and_then(|p| p.parent()).and_then(|p| p.file_name()).and_then(|s| s.to_str());
            let name = path.file_stem().and_then(|s| s.to_str());
            let (Some(package), Some(name), true) = (package, name, folder == Some(kind.as_str())) else {
                continue;
            };
            let text = std::fs::read_to_string(&path).map_err(|e| RegistryError {
                what: path.display().to_string(),
                line: None,
                message: format!("cannot read: {e}"),
            })?;
            self.add(package, kind, name, &text)
                .map_err(|e| RegistryError { what: path.display().to_string(), ..e })?;
            n += 1;
        }
        Ok(n)
    }

    /// The message `pkg/msg/Name` (or a service or action part).
    pub fn message(&self, full: &str) -> Option<&Message> {
        self.messages.get(full)
    }

    /// Whether the service `pkg/srv/Name` is known.
    pub fn has_service(&self, full: &str) -> bool {
        self.services.contains_key(full)
    }

    /// Whether the action `pkg/action/Name` is known.
    pub fn has_action(&self, full: &str) -> bool {
        self.actions.contains_key(full)
    }

    /// The full name of a field's nested type, seen from the message
    /// `owner` (an action's parts refer to each other under `pkg/action/`).
    pub fn resolve(&self, owner: &str, base: &BaseType) -> Option<String> {
        let BaseType::Named { package, name } = base else { return None };
        let as_msg = format!("{package}/msg/{name}");
        if self.messages.contains_key(&as_msg) {
            return Some(as_msg);
        }
        let kind = owner.split('/').nth(1).unwrap_or("msg");
        let local = format!("{package}/{kind}/{name}");
        self.messages.contains_key(&local).then_some(local)
    }

    /// Checks that every nested type of every message exists and that no
    /// message contains itself.
    pub fn check(&self) -> Result<(), RegistryError> {
        for (full, m) in &self.messages {
            for f in &m.fields {
                if matches!(f.base, BaseType::Named { .. }) && self.resolve(full, &f.base).is_none() {
                    return Err(RegistryError {
                        what: full.clone(),
                        line: Some(f.line).filter(|l| *l > 0),
                        message: format!(
                            "field `{}`: unknown type `{}`",
                            f.name,
                            f.base.full_name().unwrap_or_default()
                        ),
                    });
                }
            }
        }
        for full in self.messages.keys() {
            let mut stack = Vec::new();
            if self.cycle(full, &mut stack) {
                return Err(RegistryError {
                    what: full.clone(),
                    line: None,
                    message: format!("the type contains itself: {}", stack.join(" → ")),
                });
            }
        }
        Ok(())
    }

    fn cycle(&self, full: &str, stack: &mut Vec<String>) -> bool {
        if stack.iter().any(|s| s == full) {
            stack.push(full.to_string());
            return true;
        }
        stack.push(full.to_string());
        if let Some(m) = self.messages.get(full) {
            for f in &m.fields {
                if let Some(inner) = self.resolve(full, &f.base) {
                    if self.cycle(&inner, stack) {
                        return true;
                    }
                }
            }
        }
        stack.pop();
        false
    }
}

/// The DDS type name ROS 2 gives `pkg/msg/Name`: `pkg::msg::dds_::Name_`.
pub fn dds_type_name(full: &str) -> String {
    let parts: Vec<&str> = full.split('/').collect();
    match parts.as_slice() {
        [pkg, kind, name] => format!("{pkg}::{kind}::dds_::{name}_"),
        _ => full.to_string(),
    }
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>, depth: usize) -> std::io::Result<()> {
    if depth > 8 {
        return Ok(());
    }
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let p = e.path();
        if e.file_type()?.is_dir() {
            walk(&p, out, depth + 1)?;
        } else {
            out.push(p);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundled_definitions_resolve() {
        for &(pkg, kind, name, text) in DEFINITIONS {
            Registry::new().add(pkg, kind, name, text).unwrap();
        }
        let r = Registry::bundled();
        r.check().unwrap();
        assert!(r.message("geometry_msgs/msg/PoseStamped").is_some());
        assert!(r.has_service("std_srvs/srv/SetBool"));
        assert!(r.message("std_srvs/srv/Trigger_Request").unwrap().fields.is_empty());
        assert_eq!(dds_type_name("std_msgs/msg/Bool"), "std_msgs::msg::dds_::Bool_");
        assert_eq!(dds_type_name("std_srvs/srv/SetBool_Request"), "std_srvs::srv::dds_::SetBool_Request_");
    }

    #[test]
    fn actions_get_their_wire_messages_and_unknown_types_are_errors() {
        let mut r = Registry::bundled();
        r.add(
            "nav",
            Kind::Action,
            "GoTo",
            "geometry_msgs/Point target\nfloat64 speed 0.5\n---\nbool reached\n---\nfloat64 distance\n",
        )
        .unwrap();
        r.check().unwrap();
        assert!(r.has_action("nav/action/GoTo"));
        let send = r.message("nav/action/GoTo_SendGoal_Request").unwrap();
        assert_eq!(
            r.resolve("nav/action/GoTo_SendGoal_Request", &send.fields[1].base).unwrap(),
            "nav/action/GoTo_Goal"
        );
        r.add("nav", Kind::Msg, "Bad", "bool ok\nMissing m\n").unwrap();
        let e = r.check().unwrap_err();
        assert_eq!((e.what.as_str(), e.line), ("nav/msg/Bad", Some(2)));
        let mut r = Registry::new();
        r.add("a", Kind::Msg, "Loop", "Loop inner\n").unwrap();
        assert!(r.check().unwrap_err().message.contains("itself"));
    }
}
