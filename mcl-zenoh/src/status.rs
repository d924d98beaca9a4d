//! The mission state a vehicle publishes under `mcl/<vehicle>/status`
//! (docs/zenoh.md *Status*): running calls, outcome, pose when known,
//! rebuilt from the run's trace records (sans-IO: [`StatusTracker`]).

use std::collections::BTreeMap;
use std::sync::Arc;

use mcl_runtime::trace::{Ends, Record, RecordKind};
use serde::{Deserialize, Serialize};

use crate::keys;
use crate::node::Node;

/// A call whose primitive runs (it was sent an action and has not ended).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunningCall {
    /// The task called.
    pub task: String,
    /// The call site.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub call_site: Option<u32>,
    /// The call's label.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// Mission time of its first action.
    pub since: f64,
}

/// Where the vehicle is (from `pose` records: the simulator).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// East, metres.
    pub x: f64,
    /// North, metres.
    pub y: f64,
    /// Depth, metres.
    pub z: f64,
    /// Heading, radians.
    pub yaw: f64,
}

/// The payload of `mcl/<vehicle>/status`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Status {
    /// The mission.
    pub mission: String,
    /// Mission time of the last change (seconds).
    pub t: f64,
    /// The calls running, by call site.
    pub running: Vec<RunningCall>,
    /// `ok`, `fail`, `stuck`, `time_limit` once the mission ended.
    pub outcome: Option<String>,
    /// Why, when it did not end by itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The last pose, when the vehicle reports one.
    pub pose: Option<Pose>,
    /// Actions sent so far.
    pub actions: u64,
    /// Events taken so far.
    pub events: u64,
}

/// Rebuilds a [`Status`] from trace records.
#[derive(Clone, Debug, Default)]
pub struct StatusTracker {
    status: Status,
    running: BTreeMap<(String, Option<u32>), RunningCall>,
}

impl StatusTracker {
    /// The state of `mission` before it starts.
    pub fn new(mission: &str) -> StatusTracker {
        StatusTracker { status: Status { mission: mission.to_string(), ..Default::default() }, ..Default::default() }
    }

    /// Takes one record; returns whether the state changed.
    pub fn record(&mut self, r: &Record) -> bool {
        let end = |s: &mut Self, task: &Option<String>, site: Option<u32>| {
            task.as_ref().is_some_and(|t| s.running.remove(&(t.clone(), site)).is_some())
        };
        let changed = match &r.kind {
            RecordKind::Action { command, call, .. } => {
                self.status.actions += 1;
                if command == "disable" {
                    end(self, &call.task, call.call_site);
                } else if let Some(task) = &call.task {
                    self.running.entry((task.clone(), call.call_site)).or_insert_with(|| RunningCall {
                        task: task.clone(),
                        call_site: call.call_site,
                        label: call.label.clone(),
                        since: r.t,
                    });
                }
                true
            }
            RecordKind::Event { call, ends, .. } => {
                self.status.events += 1;
                if matches!(ends, Some(Ends::Ok | Ends::Fail)) {
                    end(self, &call.task, call.call_site);
                }
                true
            }
            RecordKind::Fire { call, ends: Some(Ends::Timeout), .. } => end(self, &call.task, call.call_site),
            RecordKind::Outcome { result, reason, .. } => {
                self.status.outcome = Some(result.clone());
                self.status.reason = reason.clone();
                self.running.clear();
                true
            }
            RecordKind::Pose { x, y, z, yaw } => {
                self.status.pose = Some(Pose { x: *x, y: *y, z: *z, yaw: *yaw });
                true
            }
            // A vehicle that reports its pose as a perception `pose`
            // (`{"x":…,"y":…,"z":…,"yaw":…}`).
            RecordKind::Perception { name, value } if name == "pose" => {
                match serde_json::from_value::<Pose>(value.clone()) {
                    Ok(p) => {
                        self.status.pose = Some(p);
                        true
                    }
                    Err(_) => false,
                }
            }
            _ => false,
        };
        if changed {
            self.status.t = r.t;
            self.status.running = self.running.values().cloned().collect();
        }
        changed
    }

    /// The state now.
    pub fn status(&self) -> &Status {
        &self.status
    }
}

/// Publishes the state of the missions of this process, each under
/// `mcl/<mission>/status` (or under one vehicle name for a single run).
pub struct StatusPublisher {
    node: Arc<Node>,
    /// The vehicle and mission names of a single run (whatever mission
    /// its records name).
    single: Option<(String, String)>,
    trackers: BTreeMap<String, StatusTracker>,
}

impl StatusPublisher {
    /// A publisher on `node`; `single`: the vehicle and the mission of a
    /// one-mission run.
    pub fn new(node: Arc<Node>, single: Option<(&str, &str)>) -> StatusPublisher {
        let single = single.map(|(v, m)| (v.to_string(), m.to_string()));
        StatusPublisher { node, single, trackers: BTreeMap::new() }
    }

    /// Takes one record of the run, and publishes the new state of its
    /// vehicle when it changed.
    pub fn record(&mut self, r: &Record) {
        let (vehicle, mission) = match (&self.single, &r.mission) {
            (Some((v, m)), _) => (v.clone(), m.clone()),
            (None, Some(m)) if m != "*" => (m.clone(), m.clone()),
            _ => return,
        };
        if keys::check_chunk("vehicle", &vehicle).is_err() {
            return;
        }
        let t = self.trackers.entry(vehicle.clone()).or_insert_with(|| StatusTracker::new(&mission));
        if t.record(r) {
            self.node.put(keys::status(&vehicle), serde_json::to_vec(t.status()).unwrap_or_default());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_runtime::trace::Call;

    fn call(task: &str, site: u32) -> Call {
        Call { task: Some(task.into()), call_site: Some(site), ..Default::default() }
    }

    #[test]
    fn calls_run_from_their_first_action_to_their_end() {
        let mut s = StatusTracker::new("auv");
        let action = |command: &str, c: Call| RecordKind::Action {
            seq: 1,
            action: "a".into(),
            primitive: "P".into(),
            command: command.into(),
            params: Default::default(),
            call: c,
            queued: false,
        };
        assert!(s.record(&Record::new(1.0, action("enable", call("Goto", 1)))));
        assert!(s.record(&Record::new(2.0, action("enable", call("Survey", 2)))));
        assert_eq!(s.status().running.iter().map(|c| c.task.as_str()).collect::<Vec<_>>(), ["Goto", "Survey"]);
        let ev = RecordKind::Event {
            event: "ok".into(),
            transition: "t".into(),
            call: call("Goto", 1),
            activation: None,
            ends: Some(Ends::Ok),
        };
        assert!(s.record(&Record::new(3.0, ev)));
        assert_eq!(s.status().running.len(), 1);
        assert_eq!(s.status().running[0].since, 2.0);
        assert!(s.record(&Record::new(4.0, RecordKind::Pose { x: 1.0, y: 2.0, z: 3.0, yaw: 0.0 })));
        assert!(!s.record(&Record::new(4.5, RecordKind::Warning { message: "w".into() })));
        let pose = serde_json::json!({"x": 5.0, "y": 6.0, "z": 7.0, "yaw": 1.0});
        assert!(s.record(&Record::new(4.6, RecordKind::Perception { name: "pose".into(), value: pose })));
        let bad = serde_json::json!({"x": "far"});
        assert!(!s.record(&Record::new(4.7, RecordKind::Perception { name: "pose".into(), value: bad })));
        assert!(s.record(&Record::new(5.0, RecordKind::Outcome { result: "ok".into(), reason: None, via: None })));
        let st = s.status();
        assert_eq!((st.outcome.as_deref(), st.running.len(), st.actions, st.events, st.t), (Some("ok"), 0, 2, 1, 5.0));
        assert_eq!(st.pose.map(|p| p.z), Some(7.0));
    }
}
