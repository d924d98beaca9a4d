//! Traces: one JSON object per line (JSONL), and the live log.
//!
//! Every record has `t` (seconds from the start of the mission) and `kind`;
//! `mission` is present when the mission is named (or when the file holds
//! several missions: then on every record, `"*"` on the `coord_summary`
//! that concerns them all). Kinds and their fields:
//!
//! | kind | fields |
//! |---|---|
//! | `action` | `seq`, `action`, `primitive`, `command`, `params`, `task`, `call_site`, `label`, `src`; `queued: true` when the link to the AAC was down (sent once it is up) |
//! | `event` | `event`, `task` (whose transition it fired), `transition`, `call_site`, `label`, `src`, `activation` (when the AAC named it) |
//! | `fire` | `transition`, `task`, `call_site`, `label` |
//! | `unexpected_event` | `event`, `reason` |
//! | `stale_event` | `event`, `activation`, `reason`: an answer of a primitive run that was disabled since (ignored) |
//! | `link` | `message`: the link to the AAC (connection attempts, errors the AAC reports, malformed messages, gaps in event numbers) |
//! | `timer` | `transition`, `task`, `deadline` (a timer of a positive delay started) |
//! | `perception` | `name`, `value` |
//! | `warning` | `message` |
//! | `outcome` | `result` (`ok`, `fail`, `stuck`, `time_limit`), `reason` |
//! | `coord_send` | `to`, `transition` (own, just fired), `seq`: a coordination message sent |
//! | `coord_receive` | `from`, `transition` (the sender's), `seq`, `event` (the event it becomes) |
//! | `coord_summary` | `messages` (sent), `result` (of the whole run), `mission: "*"`: the last record of a coordinated run |
//!
//! `src` is `file:line` of the call that sent the action or received the
//! event (from the net's provenance; the line is computed from the source
//! file when it is readable).

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};

use mcl_net::{Net, SourceSpan};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::player::Output;

/// One line of a trace.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Seconds from the start of the mission.
    pub t: f64,
    /// The mission's name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mission: Option<String>,
    /// `action`, `event`, `fire`, `unexpected_event`, `stale_event`, `timer`, `perception`,
    /// `warning`, `link`, `outcome`, `coord_send`, `coord_receive`, `coord_summary`.
    pub kind: String,
    /// Action sequence number.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seq: Option<u64>,
    /// Action name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub action: Option<String>,
    /// Primitive of the action.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub primitive: Option<String>,
    /// Command of the action.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub command: Option<String>,
    /// Parameters of the action.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub params: Option<Map<String, Value>>,
    /// Event name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub event: Option<String>,
    /// Transition id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transition: Option<String>,
    /// Task concerned.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<String>,
    /// Call site concerned.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub call_site: Option<u32>,
    /// Label of that call.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// Timer deadline.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deadline: Option<f64>,
    /// Perception name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Perception value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<Value>,
    /// Mission result.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub result: Option<String>,
    /// Why (outcome, unexpected event).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Warning text.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
    /// `file:line` of the call.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub src: Option<String>,
    /// Coordination: the mission a message is sent to.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub to: Option<String>,
    /// Coordination: the mission a message comes from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<String>,
    /// Coordination: number of messages sent in the run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub messages: Option<u64>,
    /// The activation an event named (the `seq` of the action that started
    /// the primitive run that raised it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub activation: Option<u64>,
    /// An action produced while the link to the AAC was down: queued, sent
    /// when the link is up again.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub queued: Option<bool>,
    /// What an event or a firing ends, from the compiled net (never from
    /// names): on an `event`, `ok` or `fail` when it is one of its task's ok
    /// or fail events (the net's `task_events` property), `none` when it is
    /// neither; on a `fire`,
    /// `timeout` when the transition is a task's timed transition (a
    /// time-out, shown in the live log without `-v`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ends: Option<String>,
    /// On an `outcome`: how the mission got there when it left its nominal
    /// path, the last handler it went through (`the catch at FILE:LINE`,
    /// `the condition of the monitor at FILE:LINE`). Absent when it
    /// completed its plan.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub via: Option<String>,
    /// On a `pose`: east, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<f64>,
    /// On a `pose`: north, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<f64>,
    /// On a `pose`: depth, metres (≥ 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z: Option<f64>,
    /// On a `pose`: heading, radians (0 towards +x, counter-clockwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yaw: Option<f64>,
}

impl Record {
    /// A record of this kind at time `t`.
    pub fn new(t: f64, kind: &str) -> Self {
        Record { t: round_time(t), kind: kind.to_string(), ..Default::default() }
    }
}

/// Times are written to the microsecond.
pub fn round_time(t: f64) -> f64 {
    (t * 1e6).round() / 1e6
}

/// Line numbers of source files, read on demand.
#[derive(Debug, Default)]
pub struct SourceMap {
    files: HashMap<String, Option<Vec<u32>>>,
    base: Option<PathBuf>,
}

impl SourceMap {
    /// Paths are shown relative to the current directory when they are under it.
    pub fn new() -> Self {
        SourceMap { files: HashMap::new(), base: std::env::current_dir().ok() }
    }

    /// `file:line` of the start of `span`, or `file` alone when the file cannot be read.
    pub fn locate(&mut self, span: &SourceSpan) -> String {
        let shown = match &self.base {
            Some(b) => {
                Path::new(&span.file).strip_prefix(b).map(|p| p.display().to_string()).unwrap_or(span.file.clone())
            }
            None => span.file.clone(),
        };
        let starts = self.files.entry(span.file.clone()).or_insert_with(|| {
            mcl_net::input::read_bytes(Path::new(&span.file), mcl_net::input::MAX_SOURCE_BYTES).ok().map(|bytes| {
                std::iter::once(0u32)
                    .chain(bytes.iter().enumerate().filter(|(_, &b)| b == b'\n').map(|(i, _)| i as u32 + 1))
                    .collect()
            })
        });
        match starts {
            Some(s) => {
                let line = s.partition_point(|&x| x <= span.start);
                format!("{shown}:{line}")
            }
            None => shown,
        }
    }
}

/// Turns player outputs into trace records and live-log lines.
#[derive(Clone, Debug)]
pub struct Tracer {
    mission: Option<String>,
    ids: Vec<String>,
    tasks: Vec<Option<String>>,
    /// Per transition: a timed transition of a task (a time-out).
    timeouts: Vec<bool>,
    /// Per task: its ok and fail events (the net's `task_events`).
    outcomes: HashMap<String, mcl_net::TaskEvents>,
    /// Handler transitions (the net's `handlers`): index, kind, and where
    /// their structure is written.
    handlers: HashMap<usize, (mcl_net::HandlerKind, Option<String>)>,
    /// The last handler fired (for the outcome's `via`).
    last_handler: std::cell::RefCell<Option<String>>,
    /// Per call site: (label, `file:line`).
    calls: HashMap<u32, (Option<String>, Option<String>)>,
}

impl Tracer {
    /// A tracer for `net`; `mission` goes on every record when given.
    pub fn new(net: &Net, mission: Option<String>, sources: &mut SourceMap) -> Self {
        let mut calls = HashMap::new();
        for t in net.transitions() {
            if let Some(b) = &t.binding {
                let src = t.provenance.span.as_ref().map(|s| sources.locate(s));
                calls.insert(b.call_site, (b.label.clone(), src));
            }
        }
        Tracer {
            mission,
            ids: net.transitions().iter().map(|t| t.id.to_string()).collect(),
            tasks: net
                .transitions()
                .iter()
                .map(|t| t.provenance.task.clone().or_else(|| t.binding.as_ref().map(|b| b.task.clone())))
                .collect(),
            timeouts: net
                .transitions()
                .iter()
                .map(|t| {
                    // A timed transition of a task's own net (not a call
                    // adapter's deferred release, not a zero delay).
                    let timed = match &t.kind {
                        mcl_net::TransitionKind::Timed(mcl_net::Delay::Fixed(d)) => *d > 0.0,
                        mcl_net::TransitionKind::Timed(mcl_net::Delay::Param(_)) => true,
                        _ => false,
                    };
                    timed && t.provenance.task.is_some() && t.provenance.call_site.is_none()
                })
                .collect(),
            outcomes: net.task_events().map(|(t, e)| (t.to_string(), e)).collect(),
            handlers: net
                .handlers()
                .into_iter()
                .filter_map(|h| {
                    let t = net.transition_by_id(&h.transition)?;
                    let src = net.transition(t)?.provenance.span.as_ref().map(|s| sources.locate(s));
                    Some((t.index(), (h.kind, src)))
                })
                .collect(),
            last_handler: Default::default(),
            calls,
        }
    }

    /// `ok` or `fail` when `event` is one of `task`'s ok or fail events,
    /// `none` when it is neither (a progress or condition event); `None`
    /// when the net does not say (a net without `task_events`).
    fn ends(&self, task: Option<&str>, event: &str) -> Option<String> {
        let e = self.outcomes.get(task?)?;
        Some(if e.ok.iter().any(|x| x == event) {
            "ok".into()
        } else if e.fail.iter().any(|x| x == event) {
            "fail".into()
        } else {
            "none".into()
        })
    }

    /// The mission name written on records.
    pub fn mission(&self) -> Option<&str> {
        self.mission.as_deref()
    }

    fn call(&self, r: &mut Record, call_site: Option<u32>) {
        r.call_site = call_site;
        if let Some((label, src)) = call_site.and_then(|c| self.calls.get(&c)) {
            r.label = label.clone();
            r.src = src.clone();
        }
    }

    /// The record of an output.
    pub fn record(&self, out: &Output) -> Record {
        let mut r = match out {
            Output::Send { t, action } => {
                let mut r = Record::new(*t, "action");
                r.seq = Some(action.seq);
                r.action = Some(action.action.clone());
                r.primitive = Some(action.primitive.clone());
                r.command = Some(action.command.clone());
                r.params = Some(action.params.clone());
                r.task = action.task.clone();
                self.call(&mut r, action.call_site);
                r
            }
            Output::Fired { t, transition, call_site } => {
                let mut r = Record::new(*t, "fire");
                r.transition = Some(self.ids[transition.index()].clone());
                r.task = self.tasks[transition.index()].clone();
                if self.timeouts[transition.index()] {
                    r.ends = Some("timeout".into());
                }
                if let Some((kind, src)) = self.handlers.get(&transition.index()) {
                    let (ends, what) = match kind {
                        mcl_net::HandlerKind::Catch => ("catch", "the catch"),
                        mcl_net::HandlerKind::Condition => ("condition", "the condition of the monitor"),
                    };
                    r.ends = Some(ends.into());
                    r.src = src.clone();
                    let via = match src {
                        Some(s) => format!("{what} at {s}"),
                        None => what.to_string(),
                    };
                    *self.last_handler.borrow_mut() = Some(via);
                }
                r.call_site = *call_site;
                r.label = call_site.and_then(|c| self.calls.get(&c)).and_then(|(l, _)| l.clone());
                r
            }
            Output::Event { t, event, transition, call_site, activation } => {
                let mut r = Record::new(*t, "event");
                r.event = Some(event.clone());
                r.task = self.tasks[transition.index()].clone();
                r.ends = self.ends(r.task.as_deref(), event);
                r.transition = Some(self.ids[transition.index()].clone());
                r.activation = *activation;
                self.call(&mut r, *call_site);
                r
            }
            Output::Stale { t, event, activation, reason } => {
                let mut r = Record::new(*t, "stale_event");
                r.event = Some(event.clone());
                r.activation = Some(*activation);
                r.reason = Some(reason.clone());
                r
            }
            Output::Unexpected { t, event, reason } => {
                let mut r = Record::new(*t, "unexpected_event");
                r.event = Some(event.clone());
                r.reason = Some(reason.to_string());
                r
            }
            Output::Timer { t, transition, deadline } => {
                let mut r = Record::new(*t, "timer");
                r.transition = Some(self.ids[transition.index()].clone());
                r.task = self.tasks[transition.index()].clone();
                r.deadline = Some(round_time(*deadline));
                r
            }
            Output::Perception { t, name, value } => {
                let mut r = Record::new(*t, "perception");
                r.name = Some(name.clone());
                r.value = Some(value.clone());
                r
            }
            Output::Warning { t, message } => {
                let mut r = Record::new(*t, "warning");
                r.message = Some(message.clone());
                r
            }
            Output::Outcome { t, outcome, reason } => {
                let mut r = Record::new(*t, "outcome");
                r.result = Some(outcome.as_str().to_string());
                r.reason = reason.clone();
                r.via = self.last_handler.borrow().clone();
                r
            }
        };
        r.mission = self.mission.clone();
        r
    }
}

/// The live-log line of a record (None for records not shown: fires and
/// timers unless `verbose`).
pub fn live_line(r: &Record, verbose: bool) -> Option<String> {
    let what = match r.kind.as_str() {
        "action" => {
            let params: Vec<String> = r.params.iter().flatten().map(|(k, v)| format!("{k}={v}")).collect();
            format!(
                "action   {} {}({}){}",
                r.primitive.as_deref().unwrap_or("?"),
                r.command.as_deref().unwrap_or("?"),
                params.join(", "),
                r.action.as_ref().map(|a| format!("  [{a}]")).unwrap_or_default()
            ) + if r.queued == Some(true) { "  (queued: the AAC is not connected)" } else { "" }
        }
        "event" => format!(
            "event    {}{}",
            r.event.as_deref().unwrap_or("?"),
            r.ends.as_deref().filter(|e| *e != "none").map(|e| format!("  (ends {e})")).unwrap_or_default()
        ),
        "unexpected_event" => {
            format!("UNEXPECTED event {} ({})", r.event.as_deref().unwrap_or("?"), r.reason.as_deref().unwrap_or(""))
        }
        "stale_event" => {
            format!("stale    {} ignored ({})", r.event.as_deref().unwrap_or("?"), r.reason.as_deref().unwrap_or(""))
        }
        "link" => format!("link     {}", r.message.as_deref().unwrap_or("")),
        "perception" => format!(
            "percept  {} = {}",
            r.name.as_deref().unwrap_or("?"),
            r.value.as_ref().map(|v| v.to_string()).unwrap_or_default()
        ),
        "warning" => format!("warning  {}", r.message.as_deref().unwrap_or("")),
        "coord_reject" => format!("REFUSED  coordination: {}", r.message.as_deref().unwrap_or("")),
        "outcome" => format!(
            "MISSION {}{}{}",
            r.result.as_deref().unwrap_or("?").to_uppercase(),
            r.reason.as_ref().map(|x| format!(": {x}")).unwrap_or_default(),
            r.via.as_ref().map(|v| format!(" (through {v})")).unwrap_or_default()
        ),
        "coord_send" => format!(
            "send     {} -> {}  (#{})",
            r.transition.as_deref().unwrap_or("?"),
            r.to.as_deref().unwrap_or("?"),
            r.seq.unwrap_or_default()
        ),
        "coord_receive" => format!(
            "receive  {}/{}  (#{})",
            r.from.as_deref().unwrap_or("?"),
            r.transition.as_deref().unwrap_or("?"),
            r.seq.unwrap_or_default()
        ),
        "coord_summary" => format!(
            "ALL MISSIONS {}: {} coordination messages sent",
            r.result.as_deref().unwrap_or("?").to_uppercase(),
            r.messages.unwrap_or_default()
        ),
        "fire" if r.ends.as_deref() == Some("catch") => "CATCH    the try block failed: its catch starts".to_string(),
        "fire" if r.ends.as_deref() == Some("condition") => {
            "CONDITION of a monitor ended: its watched block stops, its do block runs".to_string()
        }
        "fire" if r.ends.as_deref() == Some("timeout") => {
            format!("TIME-OUT {}", r.transition.as_deref().unwrap_or("?"))
        }
        "fire" if verbose => format!("fire     {}", r.transition.as_deref().unwrap_or("?")),
        "timer" if verbose => format!(
            "timer    {} until {}",
            r.transition.as_deref().unwrap_or("?"),
            r.deadline.map(|d| format!("{d:.3}")).unwrap_or_default()
        ),
        _ => return None,
    };
    let mut line = format!("[{:>10.3}] ", r.t);
    if let Some(m) = r.mission.as_deref().filter(|m| *m != "*") {
        line.push_str(&format!("{m}: "));
    }
    line.push_str(&what);
    if matches!(r.kind.as_str(), "action" | "event" | "fire" | "timer") {
        if let Some(task) = &r.task {
            line.push_str(&format!("  task={task}"));
        }
        if let Some(l) = &r.label {
            line.push_str(&format!(":{l}"));
        }
        if let Some(src) = &r.src {
            line.push_str(&format!("  at {src}"));
        }
    }
    Some(line)
}

/// Writes records as JSON lines that survive the end of the process.
///
/// Each record is serialized whole and appended to a buffer of complete
/// lines; the buffer goes to the file in one write, so the file only ever
/// grows by whole lines. Flush policy (documented in docs/running.md):
/// at every `outcome` and `coord_summary` record, whenever 64 KiB are
/// buffered, at least every second (a background thread flushes what is
/// buffered), on [`TraceWriter::flush`] and on drop, and through a
/// [`TraceFlusher`] (which `mcl run` calls on SIGINT and SIGTERM).
pub struct TraceWriter {
    shared: Arc<Mutex<Pending>>,
}

/// Lines not yet in the file.
struct Pending {
    file: std::fs::File,
    buf: Vec<u8>,
    /// The first write error, reported by the next `write` or `flush`.
    error: Option<std::io::Error>,
}

impl Pending {
    fn flush(&mut self) {
        if self.buf.is_empty() {
            return;
        }
        if let Err(e) = self.file.write_all(&self.buf) {
            self.error.get_or_insert(e);
        }
        self.buf.clear();
    }

    fn take_error(&mut self) -> std::io::Result<()> {
        self.error.take().map_or(Ok(()), Err)
    }
}

/// Buffered lines beyond this many bytes are written at once.
const FLUSH_BYTES: usize = 64 << 10;
/// Buffered lines are written at least this often.
const FLUSH_EVERY: std::time::Duration = std::time::Duration::from_secs(1);

/// Flushes a [`TraceWriter`] from elsewhere (a signal handler's thread);
/// does nothing once the writer is gone.
#[derive(Clone)]
pub struct TraceFlusher(Weak<Mutex<Pending>>);

impl TraceFlusher {
    /// Writes the buffered lines to the file.
    pub fn flush(&self) {
        if let Some(p) = self.0.upgrade() {
            p.lock().unwrap_or_else(|e| e.into_inner()).flush();
        }
    }
}

impl TraceWriter {
    /// Creates (truncates) the file, and starts the thread that flushes it
    /// every second.
    pub fn create(path: &Path) -> std::io::Result<Self> {
        if let Some(dir) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        let file = std::fs::File::create(path)?;
        let shared = Arc::new(Mutex::new(Pending { file, buf: Vec::new(), error: None }));
        let flusher = TraceFlusher(Arc::downgrade(&shared));
        std::thread::Builder::new().name("trace-flush".into()).spawn(move || {
            while flusher.0.strong_count() > 0 {
                std::thread::sleep(FLUSH_EVERY);
                flusher.flush();
            }
        })?;
        Ok(TraceWriter { shared })
    }

    fn pending(&self) -> std::sync::MutexGuard<'_, Pending> {
        self.shared.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Appends one record (a whole line).
    pub fn write(&mut self, r: &Record) -> std::io::Result<()> {
        self.write_line(&r.kind, r)
    }

    /// Appends one record given as JSON (`mcl plan --run`'s records).
    pub fn write_json(&mut self, r: &Value) -> std::io::Result<()> {
        self.write_line(r["kind"].as_str().unwrap_or(""), r)
    }

    fn write_line(&mut self, kind: &str, r: &impl Serialize) -> std::io::Result<()> {
        let mut line = serde_json::to_vec(r)?;
        line.push(b'\n');
        let mut p = self.pending();
        p.buf.extend_from_slice(&line);
        if p.buf.len() >= FLUSH_BYTES || matches!(kind, "outcome" | "coord_summary") {
            p.flush();
        }
        p.take_error()
    }

    /// Writes the buffered lines to the file.
    pub fn flush(&mut self) -> std::io::Result<()> {
        let mut p = self.pending();
        p.flush();
        p.take_error()
    }

    /// A handle that flushes this writer from another thread.
    pub fn flusher(&self) -> TraceFlusher {
        TraceFlusher(Arc::downgrade(&self.shared))
    }
}

impl Drop for TraceWriter {
    fn drop(&mut self) {
        self.pending().flush();
    }
}

/// Reads a JSONL trace. Errors name the line.
pub fn read_trace(path: &Path) -> Result<Vec<Record>, String> {
    let text = mcl_net::input::read_text(path, mcl_net::input::MAX_RECORDS_BYTES).map_err(|e| e.to_string())?;
    parse_trace(&text).map_err(|e| format!("{}:{e}", path.display()))
}

/// Parses JSONL trace text. Errors are `line: message`. A last line without
/// its newline that does not parse (a run killed while writing it) is
/// ignored.
pub fn parse_trace(text: &str) -> Result<Vec<Record>, String> {
    let mut out = Vec::new();
    let complete = text.ends_with('\n');
    let mut lines = text.lines().enumerate().peekable();
    while let Some((i, line)) = lines.next() {
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str(line) {
            Ok(r) => out.push(r),
            Err(_) if !complete && lines.peek().is_none() => {}
            Err(e) => return Err(format!("{}: {e}", i + 1)),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cut_last_line_is_ignored_and_others_are_errors() {
        let r = Record::new(1.0, "fire");
        let line = serde_json::to_string(&r).unwrap();
        let whole = format!("{line}\n{line}\n");
        assert_eq!(parse_trace(&whole).unwrap().len(), 2);
        let cut = format!("{whole}{}", &line[..10]);
        assert_eq!(parse_trace(&cut).unwrap().len(), 2);
        let bad = format!("{}\n{whole}", &line[..10]);
        assert!(parse_trace(&bad).unwrap_err().starts_with("1: "));
    }

    #[test]
    fn records_reach_the_file_at_outcomes_and_every_second() {
        let dir = std::env::temp_dir().join(format!("mcl-trace-writer-{}", std::process::id()));
        let path = dir.join("t.jsonl");
        let mut w = TraceWriter::create(&path).unwrap();
        w.write(&Record::new(0.0, "fire")).unwrap();
        w.write(&Record::new(0.5, "outcome")).unwrap();
        assert_eq!(read_trace(&path).unwrap().len(), 2, "flushed at the outcome");
        w.write(&Record::new(1.0, "fire")).unwrap();
        std::thread::sleep(FLUSH_EVERY * 2 + std::time::Duration::from_millis(200));
        assert_eq!(read_trace(&path).unwrap().len(), 3, "flushed by the timer");
        w.write(&Record::new(2.0, "fire")).unwrap();
        let f = w.flusher();
        f.flush();
        assert_eq!(read_trace(&path).unwrap().len(), 4, "flushed by a flusher");
        drop(w);
        f.flush();
        let _ = std::fs::remove_dir_all(dir);
    }
}
