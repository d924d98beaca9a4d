//! The bridge as a sans-IO state machine: commands of the player in, what
//! to put on ROS 2 out; messages, service responses and action results in,
//! events and perceptions for the player out. The transport (a ROS 2 node)
//! only moves bytes: it encodes and decodes with [`crate::cdr`] and feeds
//! the decoded values here.
//!
//! A topic event is raised only while its primitive is enabled (between
//! its `enable` and its `disable`): a message of a primitive the mission
//! does not run is not an answer to it. Perceptions are always passed on.

use super::check::Loaded;
use super::config::{Command, Raise};
use super::expr::{Condition, Source};
use serde_json::{Map, Value};
use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

/// What the bridge asks the transport, or tells the player.
#[derive(Clone, Debug, PartialEq)]
pub enum Out {
    /// Publish `value` (a message of type `ty`) on `topic`.
    Publish { topic: String, ty: String, value: Value },
    /// Call `service` (of type `ty`) with `request`; answer with
    /// [`Engine::on_response`] and the same `call`, an error once
    /// `timeout` has passed without a response.
    Call { call: u64, service: String, ty: String, request: Value, timeout: Duration },
    /// Send a goal to the action server `action` (of type `ty`) for `primitive`.
    SendGoal { primitive: String, action: String, ty: String, goal: Value },
    /// Cancel the goal of `primitive` at `action`.
    CancelGoal { primitive: String, action: String },
    /// Raise this event to the player.
    Event(String),
    /// Give this perception to the player.
    Perception { name: String, value: Value },
    /// Something the operator should read (a command the bridge could not map).
    Warning(String),
}

/// How an action's goal ended, from its `get_result` status.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GoalEnd {
    Succeeded,
    Aborted,
    /// Cancelled by the server (not after our own cancel).
    Canceled,
    /// The server did not accept the goal.
    Rejected,
}

impl GoalEnd {
    /// The end a `GoalStatus` number gives (4 succeeded, 5 canceled, 6 aborted).
    pub fn from_status(status: i64) -> Option<GoalEnd> {
        match status {
            4 => Some(GoalEnd::Succeeded),
            5 => Some(GoalEnd::Canceled),
            6 => Some(GoalEnd::Aborted),
            _ => None,
        }
    }
}

/// A service call waiting for its response.
struct PendingCall {
    primitive: String,
    /// The response's rules (condition, event).
    rules: Vec<(Option<Condition>, String)>,
    /// The event of no response (`on_failure`).
    failure: Option<String>,
    /// Made by `enable`: its answer counts only while the primitive is enabled.
    by_enable: bool,
}

struct TopicRule {
    primitive: String,
    when: Option<Condition>,
    event: String,
}

/// The bridge's mappings, ready to run.
pub struct Engine {
    loaded: Loaded,
    events: BTreeMap<String, Vec<TopicRule>>,
    perceptions: BTreeMap<String, Vec<(String, String)>>,
    subscriptions: BTreeMap<String, String>,
    enabled: BTreeSet<String>,
    calls: BTreeMap<u64, PendingCall>,
    next_call: u64,
    /// Primitives whose goal we cancelled: its end raises nothing.
    cancelled: BTreeSet<String>,
}

impl Engine {
    /// The engine of a checked bridge (conditions were checked by [`super::check`]).
    pub fn new(loaded: Loaded) -> Engine {
        let mut events: BTreeMap<String, Vec<TopicRule>> = BTreeMap::new();
        let mut perceptions: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
        let mut subscriptions = BTreeMap::new();
        for (name, p) in &loaded.bridge.primitives {
            for e in &p.events {
                let e = e.get_ref();
                subscriptions.insert(e.topic.get_ref().clone(), e.ty.get_ref().clone());
                events.entry(e.topic.get_ref().clone()).or_default().push(TopicRule {
                    primitive: name.get_ref().clone(),
                    when: e.when.as_ref().and_then(|w| Condition::parse(w.get_ref()).ok()),
                    event: e.event.get_ref().clone(),
                });
            }
            for q in &p.perceptions {
                let q = q.get_ref();
                subscriptions.insert(q.topic.get_ref().clone(), q.ty.get_ref().clone());
                perceptions
                    .entry(q.topic.get_ref().clone())
                    .or_default()
                    .push((q.field.get_ref().clone(), q.name.get_ref().clone()));
            }
        }
        Engine {
            loaded,
            events,
            perceptions,
            subscriptions,
            enabled: BTreeSet::new(),
            calls: BTreeMap::new(),
            next_call: 0,
            cancelled: BTreeSet::new(),
        }
    }

    /// The bridge file and the types it uses.
    pub fn loaded(&self) -> &Loaded {
        &self.loaded
    }

    /// The topics to subscribe to, with their message types.
    pub fn subscriptions(&self) -> &BTreeMap<String, String> {
        &self.subscriptions
    }

    /// The player's command `command` (`enable`, `disable`) of `primitive`
    /// with its parameters.
    pub fn on_command(&mut self, primitive: &str, command: &str, params: &Map<String, Value>) -> Vec<Out> {
        let Some(p) = self.loaded.bridge.primitives.get(primitive) else {
            return vec![Out::Warning(format!("the bridge file does not map primitive `{primitive}`"))];
        };
        match command {
            "enable" => {
                self.enabled.insert(primitive.to_string());
            }
            "disable" => {
                self.enabled.remove(primitive);
            }
            _ => {}
        }
        if let Some(a) = &p.action {
            let a = a.get_ref();
            match command {
                "enable" => {
                    self.cancelled.remove(primitive);
                    let ty = a.ty.get_ref();
                    return match build(&a.goal, params) {
                        Ok(goal) => vec![Out::SendGoal {
                            primitive: primitive.to_string(),
                            action: a.name.get_ref().clone(),
                            ty: ty.clone(),
                            goal,
                        }],
                        Err(e) => vec![
                            Out::Warning(format!("goal of `{primitive}`: {e}")),
                            Out::Event(a.aborted.get_ref().clone()),
                        ],
                    };
                }
                "disable" => {
                    self.cancelled.insert(primitive.to_string());
                    return vec![Out::CancelGoal {
                        primitive: primitive.to_string(),
                        action: a.name.get_ref().clone(),
                    }];
                }
                _ => {}
            }
        }
        let map = match command {
            "enable" => p.enable.as_ref(),
            "disable" => p.disable.as_ref(),
            _ => None,
        };
        match map.map(|c| c.get_ref().clone()) {
            Some(c) => self.command(primitive, command, &c, params),
            None => Vec::new(),
        }
    }

    fn command(&mut self, primitive: &str, command: &str, c: &Command, params: &Map<String, Value>) -> Vec<Out> {
        let value = match build(&c.fields, params) {
            Ok(v) => v,
            Err(e) => return vec![Out::Warning(format!("`{command}` of `{primitive}`: {e}"))],
        };
        let ty = c.ty.get_ref().clone();
        if let Some(topic) = &c.publish {
            return vec![Out::Publish { topic: topic.get_ref().clone(), ty, value }];
        }
        let Some(service) = &c.call else { return Vec::new() };
        let call = self.next_call;
        self.next_call += 1;
        let rules = c.on_response.iter().map(|r| raise_rule(r.get_ref())).collect();
        let failure = c.on_failure.as_ref().map(|f| f.get_ref().clone());
        let by_enable = command == "enable";
        self.calls.insert(call, PendingCall { primitive: primitive.to_string(), rules, failure, by_enable });
        let timeout = seconds(c.timeout.as_ref());
        vec![Out::Call { call, service: service.get_ref().clone(), ty, request: value, timeout }]
    }

    /// A message arrived on `topic` (decoded).
    pub fn on_message(&mut self, topic: &str, msg: &Value) -> Vec<Out> {
        let mut out = Vec::new();
        for (field, name) in self.perceptions.get(topic).into_iter().flatten() {
            if let Some(v) = crate::path::get(msg, field) {
                out.push(Out::Perception { name: name.clone(), value: v.clone() });
            }
        }
        for rule in self.events.get(topic).into_iter().flatten() {
            if self.enabled.contains(&rule.primitive) && rule.when.as_ref().is_none_or(|c| c.holds(msg)) {
                out.push(Out::Event(rule.event.clone()));
            }
        }
        out
    }

    /// The response to call `call`, or why there is none (a server that
    /// never answered, a response that does not decode): the error is a
    /// warning, and raises the command's `on_failure` event if it has one.
    /// The answer to an `enable` raises nothing once the primitive has been
    /// disabled (an abort, the losing branch of a parallel-or).
    pub fn on_response(&mut self, call: u64, response: Result<Value, String>) -> Vec<Out> {
        let Some(p) = self.calls.remove(&call) else { return Vec::new() };
        if p.by_enable && !self.enabled.contains(&p.primitive) {
            return Vec::new();
        }
        match response {
            Ok(v) => p
                .rules
                .iter()
                .filter(|(when, _)| when.as_ref().is_none_or(|c| c.holds(&v)))
                .map(|(_, e)| Out::Event(e.clone()))
                .collect(),
            Err(e) => std::iter::once(Out::Warning(format!("service call of `{}`: {e}", p.primitive)))
                .chain(p.failure.map(Out::Event))
                .collect(),
        }
    }

    /// How long the action server of `primitive` has to accept its goal or
    /// answer its cancel.
    pub fn goal_timeout(&self, primitive: &str) -> Duration {
        let a = self.loaded.bridge.primitives.get(primitive).and_then(|p| p.action.as_ref());
        seconds(a.and_then(|a| a.get_ref().timeout.as_ref()))
    }

    /// The goal of `primitive` ended.
    pub fn on_goal_end(&mut self, primitive: &str, end: GoalEnd) -> Vec<Out> {
        let Some(a) = self.loaded.bridge.primitives.get(primitive).and_then(|p| p.action.as_ref()) else {
            return Vec::new();
        };
        let a = a.get_ref();
        if self.cancelled.contains(primitive) {
            // Our own cancel (disable): the player no longer waits for it.
            return Vec::new();
        }
        let event = match end {
            GoalEnd::Succeeded => a.succeeded.get_ref(),
            GoalEnd::Aborted | GoalEnd::Rejected => a.aborted.get_ref(),
            GoalEnd::Canceled => a.canceled.as_ref().unwrap_or(&a.aborted).get_ref(),
        };
        vec![Out::Event(event.clone())]
    }

    /// Feedback of the goal of `primitive`.
    pub fn on_feedback(&mut self, primitive: &str, feedback: &Value) -> Vec<Out> {
        let Some(a) = self.loaded.bridge.primitives.get(primitive).and_then(|p| p.action.as_ref()) else {
            return Vec::new();
        };
        a.get_ref()
            .feedback
            .iter()
            .filter_map(|f| {
                let f = f.get_ref();
                crate::path::get(feedback, f.field.get_ref())
                    .map(|v| Out::Perception { name: f.name.get_ref().clone(), value: v.clone() })
            })
            .collect()
    }
}

/// A `timeout` of the bridge file (checked positive), or the default.
fn seconds(t: Option<&toml::Spanned<f64>>) -> Duration {
    let s = t.map_or(super::config::DEFAULT_TIMEOUT_S, |t| *t.get_ref());
    Duration::try_from_secs_f64(s).unwrap_or(Duration::from_secs_f64(super::config::DEFAULT_TIMEOUT_S))
}

fn raise_rule(r: &Raise) -> (Option<Condition>, String) {
    (r.when.as_ref().and_then(|w| Condition::parse(w.get_ref()).ok()), r.event.get_ref().clone())
}

/// The message a `fields`/`goal` table gives for `params`.
fn build(
    fields: &BTreeMap<toml::Spanned<String>, toml::Spanned<toml::Value>>,
    params: &Map<String, Value>,
) -> Result<Value, String> {
    let mut v = Value::Object(Map::new());
    for (path, source) in fields {
        let value = Source::parse(source.get_ref())?.eval(params)?;
        crate::path::set(&mut v, path.get_ref(), value)?;
    }
    Ok(v)
}
