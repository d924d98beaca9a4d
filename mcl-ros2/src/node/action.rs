//! Action goals of the bridge on the wire: one `ros2-client` action client
//! per action, whose goal, result and feedback bodies are the dynamic
//! codec's ([`RawCdr`]; the goal and the feedback follow a 16-octet goal
//! id, the result an `int8` status, so they are encoded and decoded at
//! those offsets).
//!
//! A goal waits until DDS discovery has found the server's `send_goal`,
//! `get_result` and `cancel_goal` services, is sent, and asks for its
//! result as soon as it is accepted. Its end is the result's status; a
//! goal the server rejects, does not accept within the timeout, or whose
//! server leaves while it runs (its `get_result` reply writer is no longer
//! discovered) ends as aborted, with a warning that says why. Feedback of
//! the current goal of a primitive becomes [`Event::Feedback`].
//!
//! A cancelled goal is no longer the primitive's: its result raises
//! nothing. Its cancel is *in flight* until the server answers it (or the
//! timeout passes); the node holds the commands that follow until then
//! ([`Actions::cancelling`]), so that a server sees the losing branch of a
//! parallel-or cancelled before the next goal arrives.

use super::discovery::{Discovered, Endpoints};
use super::service::{endpoints, service_qos};
use super::{mapping, topic_name};
use crate::bridge::engine::GoalEnd;
use crate::cdr;
use crate::idl::Registry;
use crate::raw::RawCdr;
use ros2_client::action::{ActionClient, ActionClientQosPolicies, GoalId};
use ros2_client::service::{RmwRequestId, ServiceMapping};
use ros2_client::{ActionTypeName, Node, NodeName};
use serde_json::Value;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// What the goals of the bridge tell the node.
#[derive(Debug)]
pub(super) enum Event {
    /// The goal of `primitive` ended (with a warning saying why when the
    /// server did not give the end itself).
    End { primitive: String, end: GoalEnd, warning: Option<String> },
    /// Feedback of the goal of `primitive`.
    Feedback { primitive: String, feedback: Value },
    /// Something the operator should read.
    Warning(String),
}

pub(super) struct Server {
    ty: String,
    client: ActionClient<RawCdr, RawCdr, RawCdr>,
    /// The endpoints of send_goal, get_result, cancel_goal.
    services: [Endpoints; 3],
}

enum Phase {
    /// Waiting for the server to be discovered, with the encoded goal.
    Unmatched(Vec<u8>),
    /// Sent with this request; waiting for the server to accept it.
    Sending(RmwRequestId),
    /// Accepted; its result asked with this request.
    Running(RmwRequestId),
}

struct Goal {
    primitive: String,
    action: String,
    id: GoalId,
    phase: Phase,
    /// Until when the server may take to accept the goal.
    deadline: Instant,
    timeout: Duration,
    /// The primitive was disabled before the server accepted the goal:
    /// cancel it once accepted.
    cancel: bool,
}

/// A cancel sent, waiting for its answer.
struct Cancel {
    action: String,
    request: RmwRequestId,
    deadline: Instant,
    timeout: Duration,
}

/// The bridge's action clients and their goals.
pub(super) struct Actions {
    mapping: ServiceMapping,
    servers: BTreeMap<String, Server>,
    /// Goals by primitive (one at a time per primitive).
    goals: BTreeMap<String, Goal>,
    /// Goals disabled before their server accepted them.
    cancel_on_accept: Vec<Goal>,
    cancels: Vec<Cancel>,
}

/// The QoS of an action's services and topics: reliable and volatile
/// (a volatile reader matches any ROS 2 server's writers).
fn action_qos() -> ActionClientQosPolicies {
    ActionClientQosPolicies {
        goal_service: service_qos(),
        result_service: service_qos(),
        cancel_service: service_qos(),
        feedback_subscription: service_qos(),
        status_subscription: service_qos(),
    }
}

/// `ActionTypeName` of `pkg/action/Name`.
fn action_type(full: &str) -> Result<ActionTypeName, String> {
    match full.split('/').collect::<Vec<_>>().as_slice() {
        [pkg, "action", name] => Ok(ActionTypeName::new(pkg, name)),
        _ => Err(format!("`{full}` is not an action type `pkg/action/Name`")),
    }
}

impl Actions {
    pub(super) fn new(m: crate::bridge::config::Mapping) -> Actions {
        Actions {
            mapping: mapping(m),
            servers: BTreeMap::new(),
            goals: BTreeMap::new(),
            cancel_on_accept: Vec::new(),
            cancels: Vec::new(),
        }
    }

    /// The client of `action` (type `ty`), created on first use: the node
    /// creates them all at its start, so that servers discover them early.
    pub(super) fn server(
        &mut self,
        node: &mut Node,
        node_name: &NodeName,
        action: &str,
        ty: &str,
    ) -> Result<&Server, String> {
        if !self.servers.contains_key(action) {
            let client = node
                .create_action_client::<RawCdr, RawCdr, RawCdr>(
                    self.mapping,
                    &topic_name(action)?,
                    &action_type(ty)?,
                    action_qos(),
                )
                .map_err(|e| format!("action client of `{action}`: {e:?}"))?;
            let service = |s: &str, ty: &str| -> Result<Endpoints, String> {
                Ok(endpoints(&topic_name(&format!("{action}/_action/{s}"))?, node_name, ty))
            };
            let services = [
                service("send_goal", &format!("{ty}_SendGoal"))?,
                service("get_result", &format!("{ty}_GetResult"))?,
                service("cancel_goal", "action_msgs/srv/CancelGoal")?,
            ];
            self.servers.insert(action.to_string(), Server { ty: ty.to_string(), client, services });
        }
        match self.servers.get(action) {
            Some(s) if s.ty == ty => Ok(s),
            Some(s) => Err(format!("action `{action}` is used as `{}`, not `{ty}`", s.ty)),
            None => Err(format!("no client for action `{action}`")),
        }
    }

    /// Sends a goal for `primitive` (its previous goal, if any, is no
    /// longer its own). `Err`: the goal cannot be encoded or the client
    /// cannot be created (the goal is over).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn send_goal(
        &mut self,
        node: &mut Node,
        node_name: &NodeName,
        reg: &Registry,
        primitive: &str,
        action: &str,
        ty: &str,
        goal: &Value,
        timeout: Duration,
    ) -> Result<(), String> {
        // The goal follows its 16-octet id.
        let body = cdr::encode_body(reg, &format!("{ty}_Goal"), goal, 16).map_err(|e| e.to_string())?;
        self.server(node, node_name, action, ty)?;
        self.goals.insert(
            primitive.to_string(),
            Goal {
                primitive: primitive.to_string(),
                action: action.to_string(),
                id: GoalId::ZERO,
                phase: Phase::Unmatched(body),
                deadline: Instant::now() + timeout,
                timeout,
                cancel: false,
            },
        );
        Ok(())
    }

    /// Cancels the goal of `primitive` (none: nothing to do).
    pub(super) fn cancel(&mut self, primitive: &str, now: Instant) -> Vec<Event> {
        let Some(mut g) = self.goals.remove(primitive) else { return Vec::new() };
        match g.phase {
            // Never sent: nothing to cancel.
            Phase::Unmatched(_) => Vec::new(),
            Phase::Sending(_) => {
                g.cancel = true;
                self.cancel_on_accept.push(g);
                Vec::new()
            }
            Phase::Running(_) => self.send_cancel(&g, now).into_iter().collect(),
        }
    }

    /// Cancels every goal (the player has left).
    pub(super) fn cancel_all(&mut self, now: Instant) -> Vec<Event> {
        let primitives: Vec<String> = self.goals.keys().cloned().collect();
        primitives.iter().flat_map(|p| self.cancel(p, now)).collect()
    }

    fn send_cancel(&mut self, g: &Goal, now: Instant) -> Option<Event> {
        let s = self.servers.get(&g.action)?;
        match s.client.cancel_goal(g.id) {
            Ok(request) => {
                self.cancels.push(Cancel {
                    action: g.action.clone(),
                    request,
                    deadline: now + g.timeout,
                    timeout: g.timeout,
                });
                None
            }
            Err(e) => {
                Some(Event::Warning(format!("cannot cancel the goal of `{}` at `{}`: {e:?}", g.primitive, g.action)))
            }
        }
    }

    /// Whether a cancel waits for its answer (the node holds what follows).
    pub(super) fn cancelling(&self) -> bool {
        !self.cancels.is_empty() || !self.cancel_on_accept.is_empty()
    }

    /// Sends the goals whose server is now matched, and gives what the
    /// servers said: acceptances, results, feedback, cancels.
    pub(super) fn poll(&mut self, reg: &Registry, discovered: &mut Discovered, now: Instant) -> Vec<Event> {
        let mut out = Vec::new();
        let mut accepts = Vec::new();
        let mut results = Vec::new();
        let mut cancels = Vec::new();
        let mut feedback = Vec::new();
        for (action, s) in &self.servers {
            let warn = |what: &str, e: &dyn std::fmt::Debug| {
                Event::Warning(format!("{what} of `{action}` does not decode: {e:?}"))
            };
            for _ in 0..MAX_TAKE {
                match s.client.goal_client().receive_response() {
                    Ok(Some((req, resp))) => accepts.push((action.clone(), req, resp.accepted)),
                    Ok(None) => break,
                    Err(e) => out.push(warn("a goal response", &e)),
                }
            }
            for _ in 0..MAX_TAKE {
                match s.client.result_client().receive_response() {
                    Ok(Some((req, resp))) => results.push((action.clone(), req, resp.status as i64)),
                    Ok(None) => break,
                    Err(e) => out.push(warn("a result", &e)),
                }
            }
            for _ in 0..MAX_TAKE {
                match s.client.cancel_client().receive_response() {
                    Ok(Some((req, resp))) => cancels.push((action.clone(), req, resp.return_code as i64)),
                    Ok(None) => break,
                    Err(e) => out.push(warn("a cancel answer", &e)),
                }
            }
            for _ in 0..MAX_TAKE {
                match s.client.feedback_subscription().take() {
                    Ok(Some((m, _))) => feedback.push((action.clone(), s.ty.clone(), m.goal_id, m.feedback.0)),
                    Ok(None) => break,
                    Err(e) => out.push(warn("a feedback", &e)),
                }
            }
            // The status topic is read so that it does not pile up (the ends come from the results).
            for _ in 0..MAX_TAKE {
                if !matches!(s.client.status_subscription().take(), Ok(Some(_))) {
                    break;
                }
            }
        }
        for (action, req, accepted) in accepts {
            self.on_goal_response(&action, req, accepted, now, &mut out);
        }
        for (action, req, status) in results {
            let found =
                self.goals.iter().find(|(_, g)| g.action == action && matches!(g.phase, Phase::Running(r) if r == req));
            // The result of a goal no longer the primitive's (cancelled): nothing to raise.
            let Some(primitive) = found.map(|(p, _)| p.clone()) else { continue };
            self.goals.remove(&primitive);
            let (end, warning) = match GoalEnd::from_status(status) {
                Some(end) => (end, None),
                None => {
                    (GoalEnd::Aborted, Some(format!("the result of `{action}` has status {status}, not a goal's end")))
                }
            };
            out.push(Event::End { primitive, end, warning });
        }
        for (action, req, code) in cancels {
            let before = self.cancels.len();
            self.cancels.retain(|c| !(c.action == action && c.request == req));
            if self.cancels.len() < before && code != 0 {
                out.push(Event::Warning(format!(
                    "`{action}` did not cancel the goal (return code {code}: 1 rejected, 2 unknown goal, 3 already ended)"
                )));
            }
        }
        for (action, ty, id, body) in feedback {
            let Some(g) =
                self.goals.values().find(|g| g.action == action && g.id == id && matches!(g.phase, Phase::Running(_)))
            else {
                continue;
            };
            match cdr::decode_body(reg, &format!("{ty}_Feedback"), &body, 16) {
                Ok(feedback) => out.push(Event::Feedback { primitive: g.primitive.clone(), feedback }),
                Err(e) => out.push(Event::Warning(format!("a feedback of `{action}` is not a `{ty}_Feedback`: {e}"))),
            }
        }
        self.send_ready(discovered, now, &mut out);
        self.expire(discovered, now, &mut out);
        out
    }

    fn on_goal_response(
        &mut self,
        action: &str,
        req: RmwRequestId,
        accepted: bool,
        now: Instant,
        out: &mut Vec<Event>,
    ) {
        let is_it = |g: &Goal| g.action == action && matches!(g.phase, Phase::Sending(r) if r == req);
        // A goal disabled before it was accepted: cancel it now.
        if let Some(i) = self.cancel_on_accept.iter().position(is_it) {
            let g = self.cancel_on_accept.remove(i);
            if accepted {
                if let Some(w) = self.send_cancel(&g, now) {
                    out.push(w);
                }
            }
            return;
        }
        let Some(primitive) = self.goals.iter().find(|(_, g)| is_it(g)).map(|(p, _)| p.clone()) else { return };
        if !accepted {
            self.goals.remove(&primitive);
            out.push(Event::End {
                primitive,
                end: GoalEnd::Rejected,
                warning: Some(format!("the action server `{action}` rejected the goal")),
            });
            return;
        }
        let Some(s) = self.servers.get(action) else { return };
        let Some(g) = self.goals.get_mut(&primitive) else { return };
        match s.client.request_result(g.id) {
            Ok(r) => g.phase = Phase::Running(r),
            Err(e) => {
                self.goals.remove(&primitive);
                out.push(Event::End {
                    primitive,
                    end: GoalEnd::Aborted,
                    warning: Some(format!("cannot ask `{action}` for the result: {e:?}")),
                });
            }
        }
    }

    /// Sends the goals whose server is discovered.
    fn send_ready(&mut self, discovered: &mut Discovered, now: Instant, out: &mut Vec<Event>) {
        let mut failed = Vec::new();
        for (primitive, g) in self.goals.iter_mut() {
            let Phase::Unmatched(body) = &g.phase else { continue };
            let Some(s) = self.servers.get(&g.action) else { continue };
            if !s.services.iter().all(|e| discovered.ready(e, now)) {
                continue;
            }
            match s.client.send_goal(RawCdr(body.clone())) {
                Ok((req, id)) => {
                    g.id = id;
                    g.phase = Phase::Sending(req);
                }
                Err(e) => failed.push((primitive.clone(), format!("cannot send the goal to `{}`: {e:?}", g.action))),
            }
        }
        for (primitive, warning) in failed {
            self.goals.remove(&primitive);
            out.push(Event::End { primitive, end: GoalEnd::Aborted, warning: Some(warning) });
        }
    }

    /// Goals not accepted in time, goals whose server left, cancels not
    /// answered in time.
    fn expire(&mut self, discovered: &mut Discovered, now: Instant, out: &mut Vec<Event>) {
        let mut ended = Vec::new();
        for (primitive, g) in &self.goals {
            let why = match &g.phase {
                Phase::Unmatched(_) if now >= g.deadline => {
                    let Some(s) = self.servers.get(&g.action) else { continue };
                    let missing = s.services.iter().find(|e| !discovered.ready(e, now)).unwrap_or(&s.services[0]);
                    format!("action `{}`: {}", g.action, discovered.why_not(missing, g.timeout, now))
                }
                Phase::Sending(_) if now >= g.deadline => {
                    format!(
                        "the action server `{}` did not answer the goal within {:.1} s",
                        g.action,
                        g.timeout.as_secs_f64()
                    )
                }
                Phase::Running(_) => {
                    let Some(s) = self.servers.get(&g.action) else { continue };
                    let result = &s.services[1];
                    if discovered.has_writer(&result.reply, &result.reply_type, now) {
                        continue;
                    }
                    format!("the action server `{}` left while the goal ran", g.action)
                }
                _ => continue,
            };
            ended.push((primitive.clone(), why));
        }
        for (primitive, why) in ended {
            self.goals.remove(&primitive);
            out.push(Event::End { primitive, end: GoalEnd::Aborted, warning: Some(why) });
        }
        self.cancel_on_accept.retain(|g| now < g.deadline);
        self.cancels.retain(|c| {
            let live = now < c.deadline;
            if !live {
                out.push(Event::Warning(format!(
                    "the action server `{}` did not answer a cancel within {:.1} s",
                    c.action,
                    c.timeout.as_secs_f64()
                )));
            }
            live
        });
    }
}

/// At most this many samples are taken from one reader per poll.
const MAX_TAKE: usize = 256;
