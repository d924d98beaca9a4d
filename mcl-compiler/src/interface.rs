//! The vehicle file as a contract (`mcl interface`): per primitive, the
//! commands the player sends (each with its action name and its parameters
//! in declaration order) and the events the vehicle may send, each with the
//! role the compiled tasks give it (ends the task ok, ends it fail, or
//! neither, or raises a monitor's `do` block: `condition`) — taken from the
//! program and its compiled missions, never from names, the same roles as
//! the player's `hello.events`. An AAC written against this runs the
//! program's missions along their nominal path.

use crate::compile::task_outcome_events;
use crate::db::{Db, SourceFile};
use crate::scope::{self, DefKind};
use mcl_syntax::ast::{BindingKind, ValueKind};
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};

/// What a vehicle must offer the missions of a program.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct VehicleInterface {
    /// Primitives by name (the `Primitive` of `action = Primitive( c: ... )`).
    pub primitives: Vec<PrimitiveInterface>,
}

/// One primitive of the vehicle.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PrimitiveInterface {
    pub primitive: String,
    /// The commands the player sends it, in the order the actions are declared.
    pub commands: Vec<CommandInterface>,
    /// The events the vehicle sends for it.
    pub events: Vec<EventInterface>,
    /// The tasks that drive it.
    pub tasks: Vec<String>,
    /// A mission calls one of those tasks as a monitor's condition: the
    /// vehicle answers only when what it watches happens (never otherwise).
    pub monitor_condition: bool,
}

/// A command (`c: enable`) and the action that sends it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CommandInterface {
    pub command: String,
    pub action: String,
    /// The `v:` parameters, in order: task parameter names, or constants.
    pub params: Vec<String>,
}

/// An event and what it does to the tasks that wait for it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EventInterface {
    pub event: String,
    pub role: EventRole,
    /// The task whose transition it fires.
    pub task: String,
}

/// What an event does to its task.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EventRole {
    /// The primitive reached its goal: the task ends ok.
    EndsOk,
    /// The task's ok event, for a call that is a monitor's condition: it
    /// raises the monitor's `do` block, so the vehicle sends it only when
    /// what it watches happens (the player's `hello` role `condition`).
    Condition,
    /// The primitive failed: the task ends in fail.
    EndsFail,
    /// Neither (progress, or a step inside the task's pattern).
    Other,
}

impl EventRole {
    /// How the role reads in prose.
    pub fn describe(self) -> &'static str {
        match self {
            EventRole::EndsOk => "ends the task ok",
            EventRole::Condition => "a monitor's condition: sent only when what it watches happens",
            EventRole::EndsFail => "ends the task in fail",
            EventRole::Other => "neither ends the task ok nor in fail",
        }
    }
}

/// The interface of the program rooted at `root` (its imports included).
pub fn vehicle_interface(db: &dyn Db, root: SourceFile) -> VehicleInterface {
    let scope = scope::scope(db, root);
    let mut prims: BTreeMap<String, PrimitiveInterface> = BTreeMap::new();
    // Commands, in the order the actions are declared (by file, then text).
    let mut actions: Vec<_> = scope.names(DefKind::Action).filter_map(|n| scope.first(DefKind::Action, n)).collect();
    actions.sort_by_cached_key(|id| (id.file.path(db).to_path_buf(), scope::action(db, *id).map(|a| a.span.start)));
    for id in actions {
        let Some(a) = scope::action(db, id) else { continue };
        let p = prims.entry(a.primitive.text.clone()).or_default();
        p.primitive = a.primitive.text.clone();
        let params = a
            .params
            .iter()
            .map(|v| match &v.kind {
                ValueKind::Ident(n) => n.text.clone(),
                _ => crate::compile::value_json(v),
            })
            .collect();
        p.commands.push(CommandInterface {
            command: a.command.as_ref().map(|c| c.text.clone()).unwrap_or_default(),
            action: a.name.text.clone(),
            params,
        });
    }
    // How the compiled missions of the file call each task: as a monitor's
    // condition, or otherwise (the player's `hello.events` reads the same
    // bindings, `mcl_net::Net::task_calls`).
    let mut watched: BTreeSet<String> = BTreeSet::new();
    let mut plain: BTreeSet<String> = BTreeSet::new();
    for m in crate::compile::compile_file_unverified(db, root).unwrap_or_default() {
        for (task, calls) in m.net.task_calls() {
            if !calls.condition.is_empty() {
                watched.insert(task.to_string());
            }
            if !calls.other.is_empty() {
                plain.insert(task.to_string());
            }
        }
    }
    // Events, through the tasks that drive each primitive.
    let mut tasks: Vec<&str> = scope.names(DefKind::Task).collect();
    tasks.sort();
    for name in tasks {
        let Some(task) = scope.first(DefKind::Task, name).and_then(|id| scope::task(db, id)) else { continue };
        let primitives: BTreeSet<String> = task
            .bindings
            .iter()
            .filter(|b| b.kind == BindingKind::Action)
            .filter_map(|b| scope.first(DefKind::Action, &b.target.text).and_then(|id| scope::action(db, id)))
            .map(|a| a.primitive.text.clone())
            .collect();
        let (ok, fail) = task_outcome_events(db, scope, name);
        for prim in primitives {
            let p = prims.entry(prim.clone()).or_default();
            p.primitive = prim;
            p.tasks.push(name.to_string());
            p.monitor_condition |= watched.contains(name);
            // A task only watched has no plain ok end; one called both ways
            // has both roles (the action's `call_site` tells them apart).
            let is_watched = watched.contains(name);
            let is_plain = plain.contains(name) || !is_watched;
            for b in task.bindings.iter().filter(|b| b.kind == BindingKind::Event) {
                let event = b.target.text.clone();
                let roles: Vec<EventRole> = if ok.contains(&event) {
                    let mut r = Vec::new();
                    if is_plain {
                        r.push(EventRole::EndsOk);
                    }
                    if is_watched {
                        r.push(EventRole::Condition);
                    }
                    r
                } else if fail.contains(&event) {
                    vec![EventRole::EndsFail]
                } else {
                    vec![EventRole::Other]
                };
                for role in roles {
                    if !p.events.iter().any(|e| e.event == event && e.task == name && e.role == role) {
                        p.events.push(EventInterface { event: event.clone(), role, task: name.to_string() });
                    }
                }
            }
        }
    }
    VehicleInterface { primitives: prims.into_values().collect() }
}

/// The interface as Markdown: one section per primitive.
pub fn to_markdown(i: &VehicleInterface) -> String {
    use std::fmt::Write;
    let mut s = String::from("# Vehicle interface\n\n");
    s.push_str(
        "What the vehicle's AAC receives (`action` messages: `primitive`, `command`, and `params`, \
         an object whose keys are the parameters below, in declaration order) and sends (`event` \
         messages) for the missions of this program (docs/aac-protocol.md).\n",
    );
    for p in &i.primitives {
        let _ = writeln!(s, "\n## `{}`\n", p.primitive);
        if !p.tasks.is_empty() {
            let tasks: Vec<String> = p.tasks.iter().map(|t| format!("`{t}`")).collect();
            let _ = writeln!(s, "Driven by task{} {}.", if tasks.len() == 1 { "" } else { "s" }, tasks.join(", "));
        }
        if p.monitor_condition {
            s.push_str("\nWatched as a monitor's condition: send its ok event only when what it watches happens.\n");
        }
        s.push_str("\n| command | action | parameters |\n|---|---|---|\n");
        for c in &p.commands {
            let params: Vec<String> = c.params.iter().map(|x| format!("`{x}`")).collect();
            let _ = writeln!(s, "| `{}` | `{}` | {} |", c.command, c.action, params.join(", "));
        }
        if !p.events.is_empty() {
            s.push_str("\n| event | role | task |\n|---|---|---|\n");
            for e in &p.events {
                let _ = writeln!(s, "| `{}` | {} | `{}` |", e.event, e.role.describe(), e.task);
            }
        }
    }
    s
}
