//! The ROS 2 node of `mcl run --ros2` (on `ros2-client`, a pure-Rust DDS):
//! it plays the AAC end of a [`mcl_runtime::link`] pair. The player's
//! commands go through the bridge's [`Engine`]; what it asks is published
//! as CDR bodies of the codec ([`RawCdr`]); messages on the subscribed
//! topics are decoded and given back to the engine, whose events and
//! perceptions go to the player.
//!
//! This first transport carries **topics** only: a service call or an
//! action goal of the bridge is reported as a warning and raises nothing
//! (the engine and the codec already handle them; `docs/ros2.md`).
//!
//! Topics are reliable and transient-local (the last 10 samples kept for
//! a reader that matches late), so that the first command of a mission is
//! not lost while DDS discovery is still under way.

use crate::bridge::engine::{Engine, Out};
use crate::cdr;
use crate::raw::RawCdr;
use mcl_runtime::link::{AacEnd, Inbound};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile, Subscription,
};
use std::collections::BTreeMap;
use std::time::Duration;
use tokio::sync::mpsc::error::TryRecvError;

/// How often the node looks for commands and messages.
const POLL: Duration = Duration::from_millis(5);
/// How long the node stays after the player left (`ros2-client`'s
/// publisher cannot wait for acknowledgments).
const LINGER: Duration = Duration::from_millis(500);

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
    publishers: BTreeMap<String, (Publisher<RawCdr>, String)>,
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
    let node = ctx.new_node(node_name, NodeOptions::new()).map_err(|e| format!("ROS 2 node: {e:?}"))?;
    let mut ros = Ros { node, publishers: BTreeMap::new() };
    let mut status =
        status.map(|l| crate::status::Outlet::open(&mut ros.node, &engine.loaded().bridge, l)).transpose()?;
    // Every topic the bridge publishes on, created before the mission starts.
    for p in engine.loaded().bridge.primitives.values() {
        for c in [&p.enable, &p.disable].into_iter().flatten() {
            if let Some(t) = &c.get_ref().publish {
                ros.publisher(t.get_ref(), c.get_ref().ty.get_ref())?;
            }
        }
    }
    let mut subs: Vec<(String, String, Subscription<RawCdr>)> = Vec::new();
    for (topic, ty) in engine.subscriptions() {
        let t = ros
            .node
            .create_topic(&topic_name(topic)?, type_name(ty)?, &qos())
            .map_err(|e| format!("topic `{topic}`: {e:?}"))?;
        let s = ros
            .node
            .create_subscription::<RawCdr>(&t, Some(qos()))
            .map_err(|e| format!("subscription `{topic}`: {e:?}"))?;
        subs.push((topic.clone(), ty.clone(), s));
    }
    loop {
        let mut outs = Vec::new();
        let mut closed = false;
        loop {
            match end.actions.try_recv() {
                Ok(a) => {
                    let _ = end.inbound.send(Inbound::Ack { seq: a.seq });
                    outs.extend(engine.on_command(&a.primitive, &a.command, &a.params.to_json_map()));
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    closed = true;
                    break;
                }
            }
        }
        for (topic, ty, s) in &subs {
            while let Ok(Some((m, _))) = s.take() {
                match cdr::decode_body(&engine.loaded().registry, ty, &m.0, 0) {
                    Ok(v) => outs.extend(engine.on_message(topic, &v)),
                    Err(e) => warn(&format!("a message on `{topic}` is not a `{ty}`: {e}")),
                }
            }
        }
        for o in outs {
            match o {
                Out::Publish { topic, ty, value } => {
                    let sent = cdr::encode_body(&engine.loaded().registry, &ty, &value, 0)
                        .map_err(|e| e.to_string())
                        .and_then(|body| {
                            ros.publisher(&topic, &ty)?.publish(RawCdr(body)).map_err(|e| format!("{e:?}"))
                        });
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
                Out::Call { service, .. } => {
                    warn(&format!("service `{service}`: services are not carried by this transport yet"))
                }
                Out::SendGoal { action, .. } | Out::CancelGoal { action, .. } => {
                    warn(&format!("action `{action}`: actions are not carried by this transport yet"))
                }
            }
        }
        if let Some(s) = &mut status {
            s.poll(&warn);
        }
        if closed {
            // The player has left: the node stays a moment so that its
            // reliable writers deliver the last commands (a disable sent
            // with the mission's end), then leaves the domain.
            std::thread::sleep(LINGER);
            return Ok(());
        }
        std::thread::sleep(POLL);
    }
}
