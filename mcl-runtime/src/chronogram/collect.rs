//! From trace records to the chronogram's rows: one per primitive (per
//! mission), each with the bars of its activations and the marks of its
//! actions and events; the outcomes; the time span.

use std::collections::HashMap;

use serde_json::Value;

use super::fmt_time;
use crate::trace::{Call, Ends, Record, RecordKind};

/// How an activation ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Ending {
    /// Disabled without an outcome of its own (aborted), or still running.
    Aborted,
    Ok,
    Fail,
    Timeout,
}

/// One activation of a primitive: from its action to its `disable`.
#[derive(Debug)]
pub(super) struct Bar {
    pub start: f64,
    /// None: still enabled at the end.
    pub end: Option<f64>,
    pub ending: Ending,
    /// The parameters of the activating action.
    pub text: String,
}

/// A mark on a row.
#[derive(Debug)]
pub(super) struct Mark {
    pub t: f64,
    pub kind: MarkKind,
    /// Its name, written above the bars.
    pub name: String,
    /// Its tooltip.
    pub details: String,
}

/// One row of the chart.
#[derive(Debug, Default)]
pub(super) struct Row {
    pub label: String,
    pub bars: Vec<Bar>,
    /// In time order.
    pub marks: Vec<Mark>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum MarkKind {
    Ok,
    Fail,
    Other,
    Timeout,
    Unexpected,
    Stale,
    Action,
}

/// How one mission ended.
#[derive(Debug)]
pub(super) struct Outcome {
    pub t: f64,
    pub mission: Option<String>,
    pub result: String,
    pub reason: Option<String>,
    /// How it got there off its nominal path.
    pub via: Option<String>,
}

/// What the chronogram shows, before any coordinate.
#[derive(Debug)]
pub(super) struct Chart {
    pub rows: Vec<Row>,
    /// The missions of the trace, in order of first record.
    pub missions: Vec<Option<String>>,
    /// More than one mission: rows and outcomes name theirs.
    pub several: bool,
    pub outcomes: Vec<Outcome>,
    /// The time of the last record.
    pub end_time: f64,
}

/// Rows keyed by (mission, primitive), in order of first use, and what
/// the records seen so far leave open.
#[derive(Default)]
struct Collector {
    rows: Vec<Row>,
    row_of: HashMap<(Option<String>, String), usize>,
    several: bool,
    task_primitive: HashMap<(Option<String>, String), String>,
    /// Row -> index of its open bar.
    open: HashMap<usize, usize>,
    timers: HashMap<(Option<String>, String), f64>,
    unexpected: Vec<Mark>,
    outcomes: Vec<Outcome>,
    /// The row of each action, by (mission, seq).
    seq_row: HashMap<(Option<String>, u64), usize>,
}

/// ` (task T:label)` when the call names its task.
fn task_of(call: &Call) -> String {
    call.task
        .as_ref()
        .map(|t| format!(" (task {t}{})", call.label.as_ref().map(|l| format!(":{l}")).unwrap_or_default()))
        .unwrap_or_default()
}

/// ` at FILE:LINE` when the call says where it is written.
fn at(call: &Call) -> String {
    call.src.as_ref().map(|s| format!(" at {s}")).unwrap_or_default()
}

impl Collector {
    fn row(&mut self, m: &Option<String>, prim: &str) -> usize {
        let (rows, several) = (&mut self.rows, self.several);
        *self.row_of.entry((m.clone(), prim.to_string())).or_insert_with(|| {
            let label = match (several, m) {
                (true, Some(m)) => format!("{m}: {prim}"),
                _ => prim.to_string(),
            };
            rows.push(Row { label, ..Default::default() });
            rows.len() - 1
        })
    }

    /// The primitive that `call`'s task last activated.
    fn primitive_of(&self, m: &Option<String>, call_task: Option<&String>) -> Option<String> {
        call_task.and_then(|t| self.task_primitive.get(&(m.clone(), t.clone())).cloned())
    }

    fn mark(&mut self, i: usize, t: f64, kind: MarkKind, name: String, details: String) {
        self.rows[i].marks.push(Mark { t, kind, name, details });
    }

    #[allow(clippy::too_many_arguments)]
    fn action(
        &mut self,
        r: &Record,
        seq: u64,
        action: &str,
        prim: &str,
        cmd: &str,
        params: &crate::params::Params,
        call: &Call,
    ) {
        if let Some(task) = &call.task {
            self.task_primitive.insert((r.mission.clone(), task.clone()), prim.to_string());
        }
        let i = self.row(&r.mission, prim);
        let details = format!(
            "t={} action #{seq} {action} = {prim} {cmd}({}){}{}",
            fmt_time(r.t),
            params.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(", "),
            task_of(call),
            at(call)
        );
        self.seq_row.insert((r.mission.clone(), seq), i);
        self.mark(i, r.t, MarkKind::Action, action.to_string(), details);
        if cmd == "disable" {
            if let Some(b) = self.open.remove(&i) {
                self.rows[i].bars[b].end = Some(r.t);
            }
        } else if let std::collections::hash_map::Entry::Vacant(e) = self.open.entry(i) {
            let text = params
                .iter()
                .map(|(k, v)| match v {
                    Value::String(s) => format!("{k}: {s}"),
                    v => format!("{k}: {v}"),
                })
                .collect::<Vec<_>>()
                .join(", ");
            self.rows[i].bars.push(Bar { start: r.t, end: None, ending: Ending::Aborted, text });
            e.insert(self.rows[i].bars.len() - 1);
        }
    }

    fn event(&mut self, r: &Record, ev: &str, call: &Call, ends: Option<Ends>) {
        let prim = self
            .primitive_of(&r.mission, call.task.as_ref())
            .or_else(|| call.task.clone())
            .unwrap_or_else(|| "events".into());
        let i = self.row(&r.mission, &prim);
        // What the event ends comes from the net (`ends`); traces
        // written before it existed fall back to the event's name.
        let kind = match ends {
            Some(Ends::Ok) => MarkKind::Ok,
            Some(Ends::Fail) => MarkKind::Fail,
            Some(_) => MarkKind::Other,
            None if ev.ends_with("Ok") || ev.ends_with("_ok") => MarkKind::Ok,
            None if ev.ends_with("Fail") || ev.ends_with("_fail") => MarkKind::Fail,
            None => MarkKind::Other,
        };
        let details = format!("t={} event {ev}{}{}", fmt_time(r.t), task_of(call), at(call));
        if let Some(&b) = self.open.get(&i) {
            let bar = &mut self.rows[i].bars[b];
            if bar.ending == Ending::Aborted {
                bar.ending = match kind {
                    MarkKind::Ok => Ending::Ok,
                    MarkKind::Fail => Ending::Fail,
                    _ => Ending::Aborted,
                };
            }
        }
        self.mark(i, r.t, kind, ev.to_string(), details);
    }

    fn stale(&mut self, r: &Record, ev: &str, reason: &str, activation: u64) {
        let details = format!("t={} event {ev} of a disabled run, ignored: {reason}", fmt_time(r.t));
        let i = match self.seq_row.get(&(r.mission.clone(), activation)).copied() {
            Some(i) => i,
            None => self.row(&r.mission, "events"),
        };
        self.mark(i, r.t, MarkKind::Stale, format!("{ev} (stale)"), details);
    }

    /// A firing: a time-out when it is the timed transition of a timer due now.
    fn fire(&mut self, r: &Record, tr: &str, task: Option<&String>) {
        let Some(d) = self.timers.remove(&(r.mission.clone(), tr.to_string())) else { return };
        if (d - r.t).abs() >= 1e-6 {
            return;
        }
        let prim = self.primitive_of(&r.mission, task).unwrap_or_else(|| "timers".into());
        let i = self.row(&r.mission, &prim);
        let details = format!(
            "t={} time-out: {tr} fired{}",
            fmt_time(r.t),
            task.map(|t| format!(" (task {t})")).unwrap_or_default()
        );
        if let Some(&b) = self.open.get(&i) {
            self.rows[i].bars[b].ending = Ending::Timeout;
        }
        self.mark(i, r.t, MarkKind::Timeout, "time-out".into(), details);
    }

    fn record(&mut self, r: &Record) {
        match &r.kind {
            RecordKind::Action { seq, action, primitive, command, params, call, .. } => {
                self.action(r, *seq, action, primitive, command, params, call)
            }
            RecordKind::Event { event, call, ends, .. } => self.event(r, event, call, *ends),
            RecordKind::StaleEvent { event, reason, activation } => self.stale(r, event, reason, *activation),
            RecordKind::Timer { transition, deadline, .. } => {
                self.timers.insert((r.mission.clone(), transition.clone()), *deadline);
            }
            RecordKind::Fire { transition, call, .. } => self.fire(r, transition, call.task.as_ref()),
            RecordKind::UnexpectedEvent { event, reason } => {
                let details = format!("t={} unexpected event {event}: {reason}", fmt_time(r.t));
                self.unexpected.push(Mark { t: r.t, kind: MarkKind::Unexpected, name: event.clone(), details });
            }
            RecordKind::Outcome { result, reason, via } => self.outcomes.push(Outcome {
                t: r.t,
                mission: r.mission.clone(),
                result: result.clone(),
                reason: reason.clone(),
                via: via.clone(),
            }),
            _ => {}
        }
    }
}

/// The chart of `records`.
pub(super) fn collect(records: &[Record]) -> Chart {
    let mut missions: Vec<Option<String>> = Vec::new();
    // `"*"`: a record about every mission (coord_summary).
    for r in records.iter().filter(|r| r.mission.as_deref() != Some("*")) {
        if !missions.contains(&r.mission) {
            missions.push(r.mission.clone());
        }
    }
    let several = missions.len() > 1;
    let mut c = Collector { several, ..Default::default() };
    let mut end_time: f64 = 0.0;
    for r in records {
        end_time = end_time.max(r.t);
        c.record(r);
    }
    let mut rows = c.rows;
    if !c.unexpected.is_empty() {
        rows.push(Row { label: "unexpected events".into(), bars: Vec::new(), marks: c.unexpected });
    }
    for row in rows.iter_mut() {
        row.marks.sort_by(|a, b| a.t.total_cmp(&b.t));
    }
    Chart { rows, missions, several, outcomes: c.outcomes, end_time }
}
