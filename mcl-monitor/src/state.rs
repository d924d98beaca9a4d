//! What a sequence of trace records says about a run at its last record:
//! the state `GET /api/state` returns. The page derives the same from the
//! same records (`assets/app.js`, `derive`) with the rules of docs/monitor.md
//! (*Call states*):
//!
//! * a call (a mission and a call site) starts running at an action of its
//!   call whose command is not `disable`, when it is not running;
//! * it ends `ok` or `fail` at an event of its call that ends its task
//!   (`ends`), `fail` at a time-out of its task (a `fire` with `ends:
//!   timeout`), and `stopped` at a `disable` sent while it runs (its block
//!   aborted it);
//! * a mission's outcome is its `outcome` record; a coordinated run's is
//!   its `coord_summary` (`aborted` when the operator aborted every
//!   mission); the run is paused between an operator's `pause` and `resume`.

use std::collections::BTreeMap;

use mcl_runtime::operator::Command;
use mcl_runtime::trace::{Call, Ends, Record, RecordKind};
use serde::Serialize;

/// The name of a record's mission: its `mission`, else `mission` (the
/// name of an anonymous mission).
pub fn mission_of(r: &Record) -> &str {
    r.mission.as_deref().unwrap_or("mission")
}

/// `file` and 1-based `line` of a `src` (`file:line`; a file alone has no line).
pub fn split_src(src: &str) -> (String, Option<u32>) {
    match src.rsplit_once(':') {
        Some((f, l)) if !f.is_empty() => match l.parse() {
            Ok(n) => (f.to_string(), Some(n)),
            Err(_) => (src.to_string(), None),
        },
        _ => (src.to_string(), None),
    }
}

/// Where a call is in its life.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CallStatus {
    /// Started, not ended.
    Running,
    /// Ended by one of its task's ok events.
    Ok,
    /// Ended by one of its task's fail events or a time-out.
    Fail,
    /// Disabled while it ran (its block aborted it).
    Stopped,
}

/// One call of one mission.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CallState {
    /// The mission.
    pub mission: String,
    /// The task called.
    pub task: Option<String>,
    /// The call's label.
    pub label: Option<String>,
    /// The call site (numbered by the compiler).
    pub call_site: u32,
    /// The source file of the call.
    pub file: Option<String>,
    /// Its 1-based line.
    pub line: Option<u32>,
    /// Where it is.
    pub status: CallStatus,
    /// When it last started.
    pub since: f64,
    /// When it last ended.
    pub until: Option<f64>,
    /// How many times it started.
    pub runs: u32,
}

/// The state of a run after some records.
#[derive(Clone, Debug, Default)]
pub struct State {
    t: f64,
    records: usize,
    /// Per mission, per call site.
    calls: BTreeMap<String, BTreeMap<u32, CallState>>,
    outcomes: BTreeMap<String, String>,
    summary: Option<String>,
    paused: bool,
}

/// `GET /api/state`'s answer (docs/monitor.md).
#[derive(Clone, Debug, Serialize)]
pub struct StateJson {
    /// Mission time of the last record.
    pub t: f64,
    /// The run's outcome (null while running): a single mission's result,
    /// or a coordinated run's `coord_summary` result.
    pub outcome: Option<String>,
    /// Each mission's result, once it has one.
    pub outcomes: BTreeMap<String, String>,
    /// The calls running now, in mission and call-site order.
    pub running: Vec<CallState>,
    /// Every call seen, in mission and call-site order.
    pub calls: Vec<CallState>,
    /// Between an operator's `pause` and `resume`.
    pub paused: bool,
    /// How many records the run has produced.
    pub records: usize,
}

impl State {
    /// Takes one more record.
    pub fn apply(&mut self, r: &Record) {
        self.records += 1;
        self.t = self.t.max(r.t);
        let mission = mission_of(r);
        match &r.kind {
            RecordKind::Action { command, call, .. } => {
                if let Some(c) = self.call(mission, call) {
                    let running = c.status == CallStatus::Running;
                    if command == "disable" {
                        if running {
                            c.status = CallStatus::Stopped;
                            c.until = Some(r.t);
                        }
                    } else if !running {
                        c.status = CallStatus::Running;
                        c.since = r.t;
                        c.until = None;
                        c.runs += 1;
                    }
                }
            }
            RecordKind::Event { call, ends: Some(e @ (Ends::Ok | Ends::Fail)), .. } => {
                let status = if *e == Ends::Ok { CallStatus::Ok } else { CallStatus::Fail };
                self.end(mission, call, status, r.t);
            }
            RecordKind::Fire { call, ends: Some(Ends::Timeout), .. } => {
                self.end(mission, call, CallStatus::Fail, r.t);
            }
            RecordKind::Outcome { result, .. } => {
                self.outcomes.insert(mission.to_string(), result.clone());
            }
            RecordKind::CoordSummary { result, .. } => self.summary = Some(result.clone()),
            RecordKind::Operator { command: Command::Pause } => self.paused = true,
            RecordKind::Operator { command: Command::Resume } => self.paused = false,
            _ => {}
        }
    }

    /// Ends the running call of `call` with `status`.
    fn end(&mut self, mission: &str, call: &Call, status: CallStatus, t: f64) {
        if let Some(c) = self.call(mission, call) {
            if c.status == CallStatus::Running {
                c.status = status;
                c.until = Some(t);
            }
        }
    }

    /// The call a record concerns (created at its first record), when it
    /// names a call site.
    fn call(&mut self, mission: &str, call: &Call) -> Option<&mut CallState> {
        let site = call.call_site?;
        // No allocation for a mission already seen.
        if !self.calls.contains_key(mission) {
            self.calls.insert(mission.to_string(), BTreeMap::new());
        }
        let sites = self.calls.get_mut(mission)?;
        let c = sites.entry(site).or_insert_with(|| CallState {
            mission: mission.to_string(),
            task: None,
            label: None,
            call_site: site,
            file: None,
            line: None,
            status: CallStatus::Stopped,
            since: 0.0,
            until: None,
            runs: 0,
        });
        if c.task.is_none() {
            c.task.clone_from(&call.task);
        }
        if c.label.is_none() {
            c.label.clone_from(&call.label);
        }
        if let (None, Some(src)) = (&c.file, &call.src) {
            let (file, line) = split_src(src);
            c.file = Some(file);
            c.line = line;
        }
        Some(c)
    }

    /// Files named by the calls seen so far.
    pub fn files(&self) -> impl Iterator<Item = &str> {
        self.calls.values().flat_map(|m| m.values()).filter_map(|c| c.file.as_deref())
    }

    /// The answer of `GET /api/state`.
    pub fn json(&self) -> StateJson {
        let calls: Vec<CallState> =
            self.calls.values().flat_map(|m| m.values()).filter(|c| c.runs > 0).cloned().collect();
        // A coordinated run whose every mission the operator aborted is
        // `aborted` (its summary says `stuck`: the players had nothing left to fire).
        let all_aborted = !self.outcomes.is_empty() && self.outcomes.values().all(|r| r == "aborted");
        let outcome = match (&self.summary, self.outcomes.len()) {
            (Some(_), _) if all_aborted => Some("aborted".to_string()),
            (Some(s), _) => Some(s.clone()),
            (None, 1) if self.missions() <= 1 => self.outcomes.values().next().cloned(),
            _ => None,
        };
        StateJson {
            t: self.t,
            outcome,
            outcomes: self.outcomes.clone(),
            running: calls.iter().filter(|c| c.status == CallStatus::Running).cloned().collect(),
            calls,
            paused: self.paused,
            records: self.records,
        }
    }

    /// How many missions the calls belong to.
    fn missions(&self) -> usize {
        self.calls.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_runtime::trace::parse_trace;

    const TRACE: &str = r#"{"t":0.0,"kind":"fire","transition":"call1.start","task":"Init","call_site":1}
{"t":0.0,"kind":"action","seq":1,"action":"enableInit","primitive":"P","command":"enable","params":{},"task":"Init","call_site":1,"src":"m.mcl:15"}
{"t":0.0,"kind":"action","seq":2,"action":"enableAlarm","primitive":"A","command":"enable","params":{},"task":"Alarm","call_site":10,"src":"m.mcl:30"}
{"t":5.0,"kind":"event","event":"evInitOk","transition":"T2","task":"Init","call_site":1,"src":"m.mcl:15","ends":"ok"}
{"t":5.0,"kind":"action","seq":3,"action":"disableInit","primitive":"P","command":"disable","params":{},"task":"Init","call_site":1,"src":"m.mcl:15"}
{"t":5.0,"kind":"action","seq":4,"action":"enableAlt","primitive":"Q","command":"enable","params":{},"task":"Alt","call_site":2,"src":"m.mcl:16"}
"#;

    fn state(text: &str) -> State {
        let mut s = State::default();
        for r in parse_trace(text).unwrap() {
            s.apply(&r);
        }
        s
    }

    #[test]
    fn calls_run_from_their_first_action_to_their_ending_event() {
        let j = state(TRACE).json();
        assert_eq!(j.t, 5.0);
        assert_eq!(j.outcome, None);
        let running: Vec<(u32, Option<u32>)> = j.running.iter().map(|c| (c.call_site, c.line)).collect();
        assert_eq!(running, [(2, Some(16)), (10, Some(30))]);
        let init = j.calls.iter().find(|c| c.call_site == 1).unwrap();
        assert_eq!((init.status, init.until, init.file.as_deref()), (CallStatus::Ok, Some(5.0), Some("m.mcl")));
    }

    #[test]
    fn a_disable_while_running_stops_a_call_and_a_timeout_fails_it() {
        let more = r#"{"t":9.0,"kind":"fire","transition":"task.Alt.TO","task":"Alt","call_site":2,"ends":"timeout"}
{"t":9.0,"kind":"action","seq":5,"action":"disableAlarm","primitive":"A","command":"disable","params":{},"task":"Alarm","call_site":10,"src":"m.mcl:30"}
{"t":9.0,"kind":"operator","command":"pause"}
{"t":9.0,"kind":"outcome","result":"fail"}
"#;
        let j = state(&format!("{TRACE}{more}")).json();
        let status = |site| j.calls.iter().find(|c| c.call_site == site).unwrap().status;
        assert_eq!((status(2), status(10)), (CallStatus::Fail, CallStatus::Stopped));
        assert!(j.running.is_empty() && j.paused);
        assert_eq!(j.outcome.as_deref(), Some("fail"));
    }

    #[test]
    fn sources_split_at_their_last_colon() {
        assert_eq!(split_src("a/b.mcl:12"), ("a/b.mcl".to_string(), Some(12)));
        assert_eq!(split_src("C:/x.mcl:3"), ("C:/x.mcl".to_string(), Some(3)));
        assert_eq!(split_src("x.mcl"), ("x.mcl".to_string(), None));
    }
}
