//! A bridge file checked against the vehicle file and the message types:
//! a primitive the vehicle file lacks, a command or event the primitive
//! lacks, a type nobody defines, a field the message type lacks, a value
//! of the wrong kind, or a parameter the command does not have are errors
//! at their file and line.

use super::config::{parse, Bridge, BridgeError, Command, Locator};
use super::expr::{Condition, Source};
use crate::idl::Registry;
use crate::path::{kind_at, Kind};
use std::collections::BTreeMap;
use std::path::Path;
use toml::Spanned;

/// What the vehicle file offers, as the bridge sees it (the binary fills
/// it from `mcl_compiler::interface::vehicle_interface`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Vehicle {
    pub primitives: Vec<VehiclePrimitive>,
}

/// One primitive: its commands with their parameters, and its events.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VehiclePrimitive {
    pub name: String,
    /// (command, parameter names), `enable` and `disable` among them.
    pub commands: Vec<(String, Vec<String>)>,
    pub events: Vec<String>,
}

/// A bridge file read and checked, with the types it uses.
#[derive(Clone, Debug)]
pub struct Loaded {
    pub bridge: Bridge,
    pub registry: Registry,
}

/// Reads `file`, loads the interface folders it names (relative to it) on
/// top of the bundled ones, and checks it against `vehicle`.
pub fn load(file: &Path, vehicle: &Vehicle) -> Result<Loaded, Vec<BridgeError>> {
    let at_start = |message: String| BridgeError { file: file.to_path_buf(), line: 1, column: 1, message };
    // The bounded reader: a regular file only, never a FIFO that blocks.
    let text =
        mcl_net::input::read_source(file).map_err(|e| vec![at_start(format!("cannot read the bridge file: {e}"))])?;
    load_text(file, &text, vehicle)
}

/// [`load`] of the text of `file` (an editor's buffer): the interface
/// folders it names are read from disk, relative to `file`.
pub fn load_text(file: &Path, text: &str, vehicle: &Vehicle) -> Result<Loaded, Vec<BridgeError>> {
    let bridge = parse(file, text).map_err(|e| vec![e])?;
    let loc = Locator { file, text };
    let mut registry = Registry::bundled();
    let base = file.parent().unwrap_or(Path::new("."));
    for dir in &bridge.interfaces {
        if let Err(e) = registry.load_dir(&base.join(dir.get_ref())) {
            return Err(vec![registry_error(&loc, dir, e)]);
        }
    }
    if let Err(e) = registry.check() {
        let at = bridge.interfaces.first().map_or(0, |d| d.span().start);
        return Err(vec![loc.at(at, e.to_string())]);
    }
    let errors = check(&loc, &bridge, &registry, vehicle);
    if errors.is_empty() {
        Ok(Loaded { bridge, registry })
    } else {
        Err(errors)
    }
}

fn registry_error(loc: &Locator<'_>, dir: &Spanned<String>, e: crate::idl::RegistryError) -> BridgeError {
    match e.line {
        Some(line) => BridgeError { file: e.what.clone().into(), line, column: 1, message: e.message },
        None => loc.on(dir, e.to_string()),
    }
}

/// Every error of `bridge` against `registry` and `vehicle`.
pub fn check(loc: &Locator<'_>, bridge: &Bridge, registry: &Registry, vehicle: &Vehicle) -> Vec<BridgeError> {
    let mut c = Checker { loc, reg: registry, errors: Vec::new() };
    let node = bridge.node.get_ref();
    if !is_identifier(node) {
        c.err(
            &bridge.node,
            format!("`{node}` is not a ROS 2 node name (letters, digits and `_`, not starting with a digit)"),
        );
    }
    if let Some(ns) = &bridge.namespace {
        if !ns.get_ref().starts_with('/') || !(ns.get_ref() == "/" || is_ros_name(ns.get_ref())) {
            c.err(ns, format!("`{}` is not a namespace (it starts with `/`)", ns.get_ref()));
        }
    }
    if let Some(d) = &bridge.domain_id {
        if *d.get_ref() > 232 {
            c.err(d, format!("domain id {} is beyond 232, the last one ROS 2 can use", d.get_ref()));
        }
    }
    if let Some(t) = &bridge.status_topic {
        c.name(t, "topic");
    }
    if let Some(m) = &bridge.service_mapping {
        if super::config::Mapping::parse(m.get_ref()).is_none() {
            c.err(m, format!("`{}` is not a service mapping (`cyclone`, `enhanced` or `basic`)", m.get_ref()));
        }
    }
    for (pname, p) in &bridge.primitives {
        let Some(vp) = vehicle.primitives.iter().find(|v| v.name == *pname.get_ref()) else {
            let known: Vec<&str> = vehicle.primitives.iter().map(|v| v.name.as_str()).collect();
            c.err(
                pname,
                format!(
                    "the vehicle file has no primitive `{}` (its primitives: {})",
                    pname.get_ref(),
                    known.join(", ")
                ),
            );
            continue;
        };
        for (cmd, map) in [("enable", &p.enable), ("disable", &p.disable)] {
            let Some(map) = map else { continue };
            match vp.commands.iter().find(|(n, _)| n == cmd) {
                Some((_, params)) => c.command(cmd, map, params, vp),
                None => c.err(map, format!("primitive `{}` has no `{cmd}` command in the vehicle file", vp.name)),
            }
        }
        for e in &p.events {
            let e = e.get_ref();
            c.name(&e.topic, "topic");
            c.event(&e.event, vp, vehicle);
            if c.message(&e.ty) {
                if let Some(w) = &e.when {
                    c.condition(w, e.ty.get_ref());
                }
            }
        }
        for q in &p.perceptions {
            let q = q.get_ref();
            c.name(&q.topic, "topic");
            if c.message(&q.ty) {
                c.field(&q.field, q.ty.get_ref());
            }
        }
        if let Some(a) = &p.action {
            if let Some(e) = &p.enable {
                c.err(e, "an action's primitive is enabled by its goal: give `action` or `enable`, not both");
            }
            let a = a.get_ref();
            c.name(&a.name, "action");
            for ev in [Some(&a.succeeded), Some(&a.aborted), a.canceled.as_ref()].into_iter().flatten() {
                c.event(ev, vp, vehicle);
            }
            c.timeout(a.timeout.as_ref());
            let ty = a.ty.get_ref();
            if !c.reg.has_action(ty) {
                c.err(&a.ty, format!("no action type `{ty}` (bundled or in `interfaces`; written `pkg/action/Name`)"));
                continue;
            }
            let params = vp.commands.iter().find(|(n, _)| n == "enable").map(|(_, p)| p.as_slice()).unwrap_or(&[]);
            c.fields(&a.goal, &format!("{ty}_Goal"), params, &vp.name, "enable");
            for f in &a.feedback {
                c.field(&f.get_ref().field, &format!("{ty}_Feedback"));
            }
        }
    }
    c.errors
}

struct Checker<'a> {
    loc: &'a Locator<'a>,
    reg: &'a Registry,
    errors: Vec<BridgeError>,
}

impl Checker<'_> {
    fn err<T>(&mut self, at: &Spanned<T>, message: impl Into<String>) {
        self.errors.push(self.loc.on(at, message));
    }

    fn name(&mut self, n: &Spanned<String>, what: &str) {
        if !is_ros_name(n.get_ref()) {
            self.err(n, format!("`{}` is not a ROS 2 {what} name", n.get_ref()));
        }
    }

    /// Whether the message type exists (an error where it does not).
    fn message(&mut self, ty: &Spanned<String>) -> bool {
        let ok = self.reg.message(ty.get_ref()).is_some() && ty.get_ref().contains("/msg/");
        if !ok {
            self.err(
                ty,
                format!("no message type `{}` (bundled or in `interfaces`; written `pkg/msg/Name`)", ty.get_ref()),
            );
        }
        ok
    }

    fn event(&mut self, ev: &Spanned<String>, vp: &VehiclePrimitive, vehicle: &Vehicle) {
        let name = ev.get_ref();
        if vp.events.iter().any(|e| e == name) {
            return;
        }
        match vehicle.primitives.iter().find(|p| p.events.iter().any(|e| e == name)) {
            Some(other) => {
                self.err(ev, format!("event `{name}` belongs to primitive `{}`, not `{}`", other.name, vp.name))
            }
            None => self.err(
                ev,
                format!("primitive `{}` has no event `{name}` (its events: {})", vp.name, vp.events.join(", ")),
            ),
        }
    }

    fn timeout(&mut self, t: Option<&Spanned<f64>>) {
        if let Some(t) = t {
            let s = *t.get_ref();
            if !(s > 0.0 && s <= 86_400.0) {
                self.err(t, format!("timeout {s} is not a number of seconds in (0, 86400]"));
            }
        }
    }

    fn field(&mut self, f: &Spanned<String>, ty: &str) -> Option<Kind> {
        match kind_at(self.reg, ty, f.get_ref()) {
            Ok(k) => Some(k),
            Err(e) => {
                self.err(f, e);
                None
            }
        }
    }

    fn condition(&mut self, w: &Spanned<String>, ty: &str) {
        let cond = match Condition::parse(w.get_ref()) {
            Ok(c) => c,
            Err(e) => return self.err(w, e),
        };
        match kind_at(self.reg, ty, &cond.field) {
            Ok(k) => {
                if !fits(&k, &cond.value) {
                    self.err(w, format!("`{}` is {} but is compared with {}", cond.field, describe(&k), cond.value));
                }
            }
            Err(e) => self.err(w, e),
        }
    }

    fn fields(
        &mut self,
        fields: &BTreeMap<Spanned<String>, Spanned<toml::Value>>,
        ty: &str,
        params: &[String],
        prim: &str,
        cmd: &str,
    ) {
        for (path, value) in fields {
            let kind = self.field(path, ty);
            match Source::parse(value.get_ref()) {
                Err(e) => self.err(value, e),
                Ok(Source::Const(v)) => {
                    if let Some(k) = kind {
                        if !fits(&k, &v) {
                            self.err(value, format!("`{}` is {} but is given {v}", path.get_ref(), describe(&k)));
                        }
                    }
                }
                Ok(Source::Param { name, .. }) => {
                    if !params.contains(&name) {
                        self.err(
                            value,
                            format!(
                                "the `{cmd}` command of `{prim}` has no parameter `{name}` (its parameters: {})",
                                if params.is_empty() { "none".to_string() } else { params.join(", ") }
                            ),
                        );
                    }
                }
            }
        }
    }

    fn command(&mut self, command_name: &str, map: &Spanned<Command>, params: &[String], vp: &VehiclePrimitive) {
        let c = map.get_ref();
        let ty = c.ty.get_ref();
        match (&c.publish, &c.call) {
            (Some(topic), None) => {
                self.name(topic, "topic");
                if !c.on_response.is_empty() {
                    self.err(&c.on_response[0], "`on_response` goes with `call` (a service)");
                }
                if self.message(&c.ty) {
                    self.fields(&c.fields, ty, params, &vp.name, command_name);
                }
            }
            (None, Some(service)) => {
                self.name(service, "service");
                if !self.reg.has_service(ty) {
                    self.err(
                        &c.ty,
                        format!("no service type `{ty}` (bundled or in `interfaces`; written `pkg/srv/Name`)"),
                    );
                    return;
                }
                self.fields(&c.fields, &format!("{ty}_Request"), params, &vp.name, command_name);
                for r in &c.on_response {
                    let r = r.get_ref();
                    if let Some(w) = &r.when {
                        self.condition(w, &format!("{ty}_Response"));
                    }
                }
            }
            _ => self.err(map, "give one of `publish = \"/topic\"` and `call = \"/service\"`"),
        }
        if c.call.is_none() {
            if let Some(f) = &c.on_failure {
                self.err(f, "`on_failure` goes with `call` (a service)");
            }
            if let Some(t) = &c.timeout {
                self.err(t, "`timeout` goes with `call` (a service)");
            }
        }
        self.timeout(c.timeout.as_ref());
        // Events of responses are checked against the primitive.
        for ev in c.on_response.iter().map(|r| &r.get_ref().event).chain(&c.on_failure) {
            if !vp.events.iter().any(|e| e == ev.get_ref()) {
                self.err(
                    ev,
                    format!(
                        "primitive `{}` has no event `{}` (its events: {})",
                        vp.name,
                        ev.get_ref(),
                        vp.events.join(", ")
                    ),
                );
            }
        }
    }
}

fn fits(k: &Kind, v: &serde_json::Value) -> bool {
    matches!(
        (k, v),
        (Kind::Bool, serde_json::Value::Bool(_))
            | (Kind::Number, serde_json::Value::Number(_))
            | (Kind::String, serde_json::Value::String(_))
            | (Kind::Array, serde_json::Value::Array(_))
    )
}

fn describe(k: &Kind) -> String {
    match k {
        Kind::Bool => "a bool".into(),
        Kind::Number => "a number".into(),
        Kind::String => "a string".into(),
        Kind::Array => "an array".into(),
        Kind::Message(m) => format!("a message `{m}`"),
    }
}

fn is_identifier(s: &str) -> bool {
    s.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// A topic, service or action name: `/a/b`, `a/b`, `~/a` (relative names
/// are resolved in the node's namespace).
pub fn is_ros_name(s: &str) -> bool {
    let s = s.strip_prefix("~/").unwrap_or(s);
    let s = s.strip_prefix('/').unwrap_or(s);
    !s.is_empty() && s.split('/').all(|part| !part.starts_with(|c: char| c.is_ascii_digit()) && is_identifier(part))
}
