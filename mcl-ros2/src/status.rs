//! The mission's state on the bridge's status topic (docs/ros2.md
//! *Status topic*): the calls running with their task, file and line, the
//! outcome once the mission ended, and the mission time of the last change,
//! as JSON in a `std_msgs/msg/String` on `status_topic` (default
//! `<namespace>/mcl/status`).
//!
//! The run's trace records reach the node through a [`Feed`] (the sink's
//! end, in the player's thread) and a [`Listener`] (the node's end); the
//! [`StatusTracker`] that rebuilds the state from them is mcl-runtime's
//! (sans-IO, shared with the Zenoh status key). Only
//! [`Outlet`], the publisher, needs the `node` feature.

use crate::bridge::config::Bridge;
use crate::idl::Registry;
pub use mcl_runtime::status::{RunningCall, Status, StatusTracker};
use mcl_runtime::trace::Record;
use std::sync::mpsc;

/// The ROS 2 type of the status messages.
pub const STATUS_TYPE: &str = "std_msgs/msg/String";

/// The status topic of `bridge`: its `status_topic`, else
/// `<namespace>/mcl/status`.
pub fn topic_of(bridge: &Bridge) -> String {
    if let Some(t) = &bridge.status_topic {
        return t.get_ref().clone();
    }
    let ns = bridge.namespace.as_ref().map_or("", |n| n.get_ref().trim_end_matches('/'));
    let ns = ns.trim_start_matches('/');
    if ns.is_empty() {
        "/mcl/status".to_string()
    } else {
        format!("/{ns}/mcl/status")
    }
}

/// The run's end of the status feed: gives the node the records that
/// change the state (a closed node is ignored).
#[derive(Clone, Debug)]
pub struct Feed(mpsc::Sender<Record>);

impl Feed {
    /// Passes `r` on when it can change the state.
    pub fn record(&self, r: &Record) {
        let relevant = StatusTracker::relevant(&r.kind);
        if relevant {
            let _ = self.0.send(r.clone());
        }
    }
}

/// The node's end of the status feed, with the state it makes.
#[derive(Debug)]
pub struct Listener {
    rx: mpsc::Receiver<Record>,
    tracker: StatusTracker,
}

impl Listener {
    /// Takes the records fed since the last call; the new state when it
    /// changed.
    pub fn poll(&mut self) -> Option<&Status> {
        let mut changed = false;
        while let Ok(r) = self.rx.try_recv() {
            changed |= self.tracker.record(&r);
        }
        changed.then(|| self.tracker.status())
    }
}

/// A status feed for `mission`: the sink's end and the node's end.
pub fn channel(mission: &str) -> (Feed, Listener) {
    let (tx, rx) = mpsc::channel();
    (Feed(tx), Listener { rx, tracker: StatusTracker::new(mission) })
}

/// The `std_msgs/msg/String` body (CDR, no header) of `status`; `reg`
/// holds the bundled `std_msgs`.
pub fn encode(reg: &Registry, status: &Status) -> Result<Vec<u8>, String> {
    let text = serde_json::to_string(status).map_err(|e| e.to_string())?;
    crate::cdr::encode_body(reg, STATUS_TYPE, &serde_json::json!({ "data": text }), 0).map_err(|e| e.to_string())
}

/// The publisher of the status topic, on the node of `mcl run --ros2`.
#[cfg(feature = "node")]
pub struct Outlet {
    listener: Listener,
    publisher: ros2_client::Publisher<crate::raw::RawCdr>,
    topic: String,
    registry: Registry,
}

#[cfg(feature = "node")]
impl Outlet {
    /// Creates the status topic of `bridge` on `node`.
    pub fn open(node: &mut ros2_client::Node, bridge: &Bridge, listener: Listener) -> Result<Outlet, String> {
        let topic = topic_of(bridge);
        let qos = crate::node::qos();
        let t = node
            .create_topic(&crate::node::topic_name(&topic)?, crate::node::type_name(STATUS_TYPE)?, &qos)
            .map_err(|e| format!("status topic `{topic}`: {e:?}"))?;
        let publisher = node
            .create_publisher::<crate::raw::RawCdr>(&t, Some(qos))
            .map_err(|e| format!("status publisher `{topic}`: {e:?}"))?;
        Ok(Outlet { listener, publisher, topic, registry: Registry::bundled() })
    }

    /// Publishes the state when the records fed since the last call
    /// changed it.
    pub fn poll(&mut self, warn: &impl Fn(&str)) {
        if let Some(s) = self.listener.poll() {
            let sent = encode(&self.registry, s)
                .and_then(|body| self.publisher.publish(crate::raw::RawCdr(body)).map_err(|e| format!("{e:?}")));
            if let Err(e) = sent {
                warn(&format!("cannot publish the status on `{}`: {e}", self.topic));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_runtime::trace::{Call, Ends, RecordKind};

    fn call(task: &str, site: u32, line: u32) -> Call {
        Call {
            task: Some(task.into()),
            call_site: Some(site),
            src: Some(format!("/m/mission.mcl:{line}")),
            ..Default::default()
        }
    }

    fn action(command: &str, c: Call) -> RecordKind {
        RecordKind::Action {
            seq: 1,
            action: "a".into(),
            primitive: "P".into(),
            command: command.into(),
            params: Default::default(),
            call: c,
            queued: false,
        }
    }

    #[test]
    fn calls_run_from_their_first_action_to_their_end_with_file_and_line() {
        let (feed, mut l) = channel("auv");
        feed.record(&Record::new(1.0, action("enable", call("Depth", 1, 4))));
        feed.record(&Record::new(1.5, RecordKind::Warning { message: "w".into() }));
        let s = l.poll().unwrap().clone();
        assert_eq!(s.running.len(), 1);
        let c = &s.running[0];
        assert_eq!(
            (c.task.as_str(), c.file.as_deref(), c.line, c.since),
            ("Depth", Some("/m/mission.mcl"), Some(4), 1.0)
        );
        assert!(l.poll().is_none(), "nothing new");
        let ev = RecordKind::Event {
            event: "ok".into(),
            transition: "t".into(),
            call: call("Depth", 1, 4),
            activation: None,
            ends: Some(Ends::Ok),
        };
        feed.record(&Record::new(2.0, ev));
        feed.record(&Record::new(2.0, action("enable", call("Surface", 2, 5))));
        let s = l.poll().unwrap().clone();
        assert_eq!(s.running.iter().map(|c| c.task.as_str()).collect::<Vec<_>>(), ["Surface"]);
        feed.record(&Record::new(3.0, RecordKind::Outcome { result: "ok".into(), reason: None, via: None }));
        let s = l.poll().unwrap().clone();
        assert_eq!((s.outcome.as_deref(), s.running.len(), s.actions, s.events, s.t), (Some("ok"), 0, 2, 1, 3.0));
        // The body is a `std_msgs/msg/String` holding the JSON.
        let reg = Registry::bundled();
        let msg = crate::cdr::decode_body(&reg, STATUS_TYPE, &encode(&reg, &s).unwrap(), 0).unwrap();
        let back: Status = serde_json::from_str(msg["data"].as_str().unwrap()).unwrap();
        assert_eq!(back, s);
    }

    #[test]
    fn the_default_topic_is_under_the_namespace() {
        let b = |t: &str| crate::bridge::config::parse(std::path::Path::new("b.toml"), t).unwrap();
        assert_eq!(topic_of(&b("node = \"n\"\n")), "/mcl/status");
        assert_eq!(topic_of(&b("node = \"n\"\nnamespace = \"/g500/\"\n")), "/g500/mcl/status");
        assert_eq!(topic_of(&b("node = \"n\"\nstatus_topic = \"/s\"\n")), "/s");
    }
}
