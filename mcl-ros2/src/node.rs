//! The ROS 2 node of `mcl run --ros2` (on `ros2-client`, a pure-Rust DDS):
//! it plays the AAC end of a [`mcl_runtime::link`] pair. The player's
//! commands go through the bridge's [`Engine`]; what it asks is published
//! as CDR bodies of the codec ([`RawCdr`]); messages on the subscribed
//! topics are decoded and given back to the engine, whose events and
//! perceptions go to the player.
//!
//! Topics are published and subscribed here; service calls go through
//! [`service`] and action goals through [`action`], whose answers (a
//! response, a goal's end, feedback) go back to the engine. What the engine
//! asks goes out in order, but nothing passes a goal's cancel until the
//! server has answered it ([`action::Actions::cancelling`]).
//!
//! Topics are reliable and transient-local (the last 10 samples kept for
//! a reader that matches late), so that the first command of a mission is
//! not lost while DDS discovery is still under way. Services and actions
//! are volatile, as ROS 2's: a request waits until discovery has found its
//! server ([`discovery`]).

mod action;
mod discovery;
mod service;

use discovery::Discovered;

use crate::bridge::config::Mapping;
use crate::bridge::engine::{Engine, Out};
use crate::cdr;
use crate::idl::registry::dds_type_name;
use crate::raw::RawCdr;
use mcl_runtime::link::{AacEnd, Inbound};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::service::ServiceMapping;
use ros2_client::{
    Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile, Subscription,
};
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::time::{Duration, Instant};
use tokio::sync::mpsc::error::TryRecvError;

/// How often the node looks for commands and messages.
const POLL: Duration = Duration::from_millis(5);
/// How long the node stays after the player left (`ros2-client`'s
/// publisher cannot wait for acknowledgments).
const LINGER: Duration = Duration::from_millis(500);
/// `ros2-client`'s mapping for the bridge's.
fn mapping(m: Mapping) -> ServiceMapping {
    match m {
        Mapping::Cyclone => ServiceMapping::Cyclone,
        Mapping::Enhanced => ServiceMapping::Enhanced,
        Mapping::Basic => ServiceMapping::Basic,
    }
}

/// The QoS of every topic of the bridge.
pub fn qos() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 10 })
}

/// `Name` of a topic as written in the bridge file (`/a/b`, `a/b`).
pub(crate) fn topic_name(topic: &str) -> Result<Name, String> {
    let t = topic.trim_start_matches('/');
    let (ns, base) = match t.rsplit_once('/') {
        Some((ns, base)) => (format!("/{ns}"), base),
        None => ("/".to_string(), t),
    };
    Name::new(&ns, base).map_err(|e| format!("topic `{topic}`: {e:?}"))
}

/// `MessageTypeName` of `pkg/msg/Name`.
pub(crate) fn type_name(full: &str) -> Result<MessageTypeName, String> {
    match full.split('/').collect::<Vec<_>>().as_slice() {
        [pkg, "msg", name] => Ok(MessageTypeName::new(pkg, name)),
        _ => Err(format!("`{full}` is not a message type `pkg/msg/Name`")),
    }
}

struct Ros {
    node: Node,
    node_name: NodeName,
    publishers: BTreeMap<String, (Publisher<RawCdr>, String)>,
    services: service::Services,
    actions: action::Actions,
    discovered: Discovered,
}

impl Ros {
    fn publisher(&mut self, topic: &str, ty: &str) -> Result<&Publisher<RawCdr>, String> {
        if !self.publishers.contains_key(topic) {
            let t = self
                .node
                .create_topic(&topic_name(topic)?, type_name(ty)?, &qos())
                .map_err(|e| format!("topic `{topic}`: {e:?}"))?;
            let p = self
                .node
                .create_publisher::<RawCdr>(&t, Some(qos()))
                .map_err(|e| format!("publisher `{topic}`: {e:?}"))?;
            self.publishers.insert(topic.to_string(), (p, ty.to_string()));
        }
        match self.publishers.get(topic) {
            Some((p, t)) if t == ty => Ok(p),
            Some((_, t)) => Err(format!("topic `{topic}` is published as `{t}`, not `{ty}`")),
            None => Err(format!("no publisher for `{topic}`")),
        }
    }
}

/// Runs the bridge as the ROS 2 node `node_name` in `namespace` on
/// `domain`, serving `end` until the player closes its side; with `status`,
/// publishes the mission's state on the status topic ([`crate::status`]).
/// `Err` when the node cannot be created.
pub fn serve(
    mut engine: Engine,
    mut end: AacEnd,
    status: Option<crate::status::Listener>,
    warn: impl Fn(&str),
) -> Result<(), String> {
    let b = &engine.loaded().bridge;
    let domain = b.domain_id.as_ref().map_or(0, |d| *d.get_ref());
    let ns = b.namespace.as_ref().map_or("/".to_string(), |n| n.get_ref().clone());
    let node_name = NodeName::new(&ns, b.node.get_ref()).map_err(|e| format!("node name: {e:?}"))?;
    let ctx =
        Context::with_options(ContextOptions::new().domain_id(domain)).map_err(|e| format!("ROS 2 context: {e:?}"))?;
    let node = ctx.new_node(node_name.clone(), NodeOptions::new()).map_err(|e| format!("ROS 2 node: {e:?}"))?;
    let m = b.mapping();
    let mut ros = Ros {
        node,
        node_name,
        publishers: BTreeMap::new(),
        services: service::Services::new(m),
        actions: action::Actions::new(m),
        discovered: Discovered::new(ctx.domain_participant()),
    };
    let mut status =
        status.map(|l| crate::status::Outlet::open(&mut ros.node, &engine.loaded().bridge, l)).transpose()?;
    // Every topic the bridge publishes on, created before the mission starts.
    for p in engine.loaded().bridge.primitives.values() {
        for c in [&p.enable, &p.disable].into_iter().flatten() {
            if let Some(t) = &c.get_ref().publish {
                ros.publisher(t.get_ref(), c.get_ref().ty.get_ref())?;
            }
            // Service and action clients too: a server must discover them
            // before their first request, or that request is lost.
            if let Some(s) = &c.get_ref().call {
                ros.services.client(&mut ros.node, &ros.node_name, s.get_ref(), c.get_ref().ty.get_ref())?;
            }
        }
        if let Some(a) = &p.action {
            let a = a.get_ref();
            ros.actions.server(&mut ros.node, &ros.node_name, a.name.get_ref(), a.ty.get_ref())?;
        }
    }
    let mut subs: Vec<(String, String, Subscription<RawCdr>)> = Vec::new();
    // (DDS topic, DDS type) of each subscription, to name the publishers of
    // another type, whose messages DDS never delivers.
    let mut expected: Vec<(String, String, String)> = Vec::new();
    for (topic, ty) in engine.subscriptions() {
        let name = topic_name(topic)?;
        expected.push((topic.clone(), name.to_dds_name("rt", &ros.node_name, ""), dds_type_name(ty)));
        let t = ros.node.create_topic(&name, type_name(ty)?, &qos()).map_err(|e| format!("topic `{topic}`: {e:?}"))?;
        let s = ros
            .node
            .create_subscription::<RawCdr>(&t, Some(qos()))
            .map_err(|e| format!("subscription `{topic}`: {e:?}"))?;
        subs.push((topic.clone(), ty.clone(), s));
    }
    let mut foreign: BTreeSet<(String, String)> = BTreeSet::new();
    // What the engine asked, in order, not yet carried out.
    let mut queue: VecDeque<Out> = VecDeque::new();
    let mut closed = false;
    let mut left = false;
    loop {
        while !closed {
            match end.actions.try_recv() {
                Ok(a) => {
                    let _ = end.inbound.send(Inbound::Ack { seq: a.seq });
                    queue.extend(engine.on_command(&a.primitive, &a.command, &a.params.to_json_map()));
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => closed = true,
            }
        }
        for (topic, ty, s) in &subs {
            while let Ok(Some((m, _))) = s.take() {
                match cdr::decode_body(&engine.loaded().registry, ty, &m.0, 0) {
                    Ok(v) => queue.extend(engine.on_message(topic, &v)),
                    Err(e) => warn(&format!("a message on `{topic}` is not a `{ty}`: {e}")),
                }
            }
        }
        let now = Instant::now();
        ros.discovered.refresh(now);
        for (topic, dds_topic, dds_type) in &expected {
            for other in ros.discovered.foreign_writers(dds_topic, dds_type, now) {
                if foreign.insert((topic.clone(), other.clone())) {
                    warn(&format!(
                        "a publisher on `{topic}` writes `{other}`, not `{dds_type}`: DDS does not deliver its messages"
                    ));
                }
            }
        }
        for (call, response) in ros.services.poll(&engine.loaded().registry, &mut ros.discovered, now) {
            queue.extend(engine.on_response(call, response));
        }
        for ev in ros.actions.poll(&engine.loaded().registry, &mut ros.discovered, now) {
            match ev {
                action::Event::End { primitive, end, warning } => {
                    if let Some(w) = warning {
                        warn(&w);
                    }
                    queue.extend(engine.on_goal_end(&primitive, end));
                }
                action::Event::Feedback { primitive, feedback } => {
                    queue.extend(engine.on_feedback(&primitive, &feedback))
                }
                action::Event::Warning(w) => warn(&w),
            }
        }
        // Nothing passes a cancel the server has not answered yet.
        while !ros.actions.cancelling() {
            let Some(o) = queue.pop_front() else { break };
            carry(&mut ros, &mut engine, &end, o, now, &warn);
        }
        if closed && queue.is_empty() && !left {
            // The player has left (the mission ended, or its time limit
            // passed): a goal still running is cancelled, not left to the vehicle.
            left = true;
            for ev in ros.actions.cancel_all(now) {
                if let action::Event::Warning(w) = ev {
                    warn(&w);
                }
            }
        }
        if let Some(s) = &mut status {
            s.poll(&warn);
        }
        if left && !ros.actions.cancelling() && !ros.services.busy() {
            // The player has left: the node stays a moment so that its
            // reliable writers deliver the last commands (a disable sent
            // with the mission's end), then leaves the domain.
            std::thread::sleep(LINGER);
            return Ok(());
        }
        std::thread::sleep(POLL);
    }
}

/// Carries out one thing the engine asked.
fn carry(ros: &mut Ros, engine: &mut Engine, end: &AacEnd, o: Out, now: Instant, warn: &impl Fn(&str)) {
    match o {
        Out::Publish { topic, ty, value } => {
            let sent = cdr::encode_body(&engine.loaded().registry, &ty, &value, 0)
                .map_err(|e| e.to_string())
                .and_then(|body| ros.publisher(&topic, &ty)?.publish(RawCdr(body)).map_err(|e| format!("{e:?}")));
            if let Err(e) = sent {
                warn(&format!("cannot publish on `{topic}`: {e}"));
            }
        }
        Out::Event(event) => {
            let _ = end.inbound.send(Inbound::Event { event, activation: None, n: None });
        }
        Out::Perception { name, value } => {
            let _ = end.inbound.send(Inbound::Perception { name, value, n: None });
        }
        Out::Warning(w) => warn(&w),
        Out::Call { call, service, ty, request, timeout } => {
            let reg = &engine.loaded().registry;
            if let Err(e) = ros.services.call(
                &mut ros.node,
                &ros.node_name,
                reg,
                &mut ros.discovered,
                call,
                &service,
                &ty,
                &request,
                timeout,
            ) {
                // The call is over: its failure goes back to the engine (and to the player).
                let outs = engine.on_response(call, Err(e));
                for o in outs {
                    carry(ros, engine, end, o, now, warn);
                }
            }
        }
        Out::SendGoal { primitive, action, ty, goal } => {
            let timeout = engine.goal_timeout(&primitive);
            let reg = &engine.loaded().registry;
            let sent =
                ros.actions.send_goal(&mut ros.node, &ros.node_name, reg, &primitive, &action, &ty, &goal, timeout);
            if let Err(e) = sent {
                warn(&format!("goal of `{primitive}` at `{action}`: {e}"));
                let outs = engine.on_goal_end(&primitive, crate::bridge::engine::GoalEnd::Aborted);
                for o in outs {
                    carry(ros, engine, end, o, now, warn);
                }
            }
        }
        Out::CancelGoal { primitive, .. } => {
            for ev in ros.actions.cancel(&primitive, now) {
                if let action::Event::Warning(w) = ev {
                    warn(&w);
                }
            }
        }
    }
}
