//! A mission's state rebuilt from its trace records (sans-IO): the calls
//! running with their task, call site, label, file and line, the outcome
//! once the mission ended, the last pose, and counts of actions and events.
//! Published as JSON by the Zenoh status key (`mcl-zenoh`, docs/zenoh.md)
//! and the ROS 2 status topic (`mcl-ros2`, docs/ros2.md).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::trace::{Ends, Record, RecordKind};

/// A call whose primitive runs (it was sent an action and has not ended).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunningCall {
    /// The task called.
    pub task: String,
    /// The call site (numbered by the compiler).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub call_site: Option<u32>,
    /// The call's label.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// The file of the call.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// The line of the call (1-based).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line: Option<u32>,
    /// Mission time of its first action (seconds).
    pub since: f64,
}

/// Where the vehicle is (from `pose` records, or a perception `pose`).
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

/// A mission's state, as published.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Status {
    /// The mission (`plan:STEM` for a planned run).
    pub mission: String,
    /// Mission time of the last change (seconds).
    pub t: f64,
    /// The calls running, by task and call site.
    pub running: Vec<RunningCall>,
    /// `ok`, `fail`, `stuck`, `time_limit` once the mission ended (for a
    /// planned run: the last step's, until the next step starts).
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

/// `FILE:LINE` of a trace's `src` as its file and line.
fn file_line(src: &Option<String>) -> (Option<String>, Option<u32>) {
    match src.as_deref().and_then(|s| s.rsplit_once(':')) {
        Some((f, l)) => match l.parse() {
            Ok(n) => (Some(f.to_string()), Some(n)),
            Err(_) => (src.clone(), None),
        },
        None => (src.clone(), None),
    }
}

impl StatusTracker {
    /// The state of `mission` before it starts.
    pub fn new(mission: &str) -> StatusTracker {
        StatusTracker { status: Status { mission: mission.to_string(), ..Default::default() }, ..Default::default() }
    }

    /// Whether a record of this kind can change the state (the others
    /// need not be passed on).
    pub fn relevant(kind: &RecordKind) -> bool {
        match kind {
            RecordKind::Action { .. }
            | RecordKind::Event { .. }
            | RecordKind::Outcome { .. }
            | RecordKind::Pose { .. }
            | RecordKind::Fire { ends: Some(Ends::Timeout), .. } => true,
            RecordKind::Perception { name, .. } => name == "pose",
            _ => false,
        }
    }

    /// Takes one record; returns whether the state changed.
    pub fn record(&mut self, r: &Record) -> bool {
        let end = |s: &mut Self, task: &Option<String>, site: Option<u32>| {
            task.as_ref().is_some_and(|t| s.running.remove(&(t.clone(), site)).is_some())
        };
        let changed = match &r.kind {
            RecordKind::Action { command, call, .. } => {
                self.status.actions += 1;
                // A planned run's next step: a new mission begins.
                self.status.outcome = None;
                self.status.reason = None;
                if command == "disable" {
                    end(self, &call.task, call.call_site);
                } else if let Some(task) = &call.task {
                    let (file, line) = file_line(&call.src);
                    self.running.entry((task.clone(), call.call_site)).or_insert_with(|| RunningCall {
                        task: task.clone(),
                        call_site: call.call_site,
                        label: call.label.clone(),
                        file,
                        line,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::Call;

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
    fn calls_run_from_their_first_action_to_their_end() {
        let mut s = StatusTracker::new("auv");
        assert!(s.record(&Record::new(1.0, action("enable", call("Goto", 1, 4)))));
        assert!(s.record(&Record::new(2.0, action("enable", call("Survey", 2, 5)))));
        assert_eq!(s.status().running.iter().map(|c| c.task.as_str()).collect::<Vec<_>>(), ["Goto", "Survey"]);
        let c = &s.status().running[0];
        assert_eq!((c.file.as_deref(), c.line, c.since), (Some("/m/mission.mcl"), Some(4), 1.0));
        let ev = RecordKind::Event {
            event: "ok".into(),
            transition: "t".into(),
            call: call("Goto", 1, 4),
            activation: None,
            ends: Some(Ends::Ok),
        };
        assert!(s.record(&Record::new(3.0, ev)));
        assert_eq!(s.status().running.len(), 1);
        assert_eq!(s.status().running[0].since, 2.0);
        assert!(s.record(&Record::new(4.0, RecordKind::Pose { x: 1.0, y: 2.0, z: 3.0, yaw: 0.0 })));
        let warning = RecordKind::Warning { message: "w".into() };
        assert!(!StatusTracker::relevant(&warning));
        assert!(!s.record(&Record::new(4.5, warning)));
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
